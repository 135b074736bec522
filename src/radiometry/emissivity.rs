//! Spectral, directional emissivity ε(λ, θ).
//!
//! A material gives either a grey value, a spectral curve at normal view, or
//! a spectral curve per view zenith angle (DIRSIG `.ems` angular data). The
//! evaluator interpolates linearly in λ and in θ, holding the end values
//! beyond the tabulated range.
//!
//! **Default angular fall-off** (materials with no angular data): the
//! emissivity of a smooth dielectric from the Fresnel equations (Born & Wolf,
//! *Principles of Optics*, §1.5.2), ε(θ) = 1 − ½(r_s² + r_p²), with a real
//! refractive index n chosen so the normal value is reproduced exactly:
//! 1 − ε(0) = ((n − 1)/(n + 1))², i.e. n = (1 + √(1 − ε₀))/(1 − √(1 − ε₀)).
//! ε(θ) is then nearly flat to ~50° and falls to 0 at grazing, as measured
//! for water (Masuda, Takashima & Takayama 1988, Remote Sens. Environ. 24,
//! 313) and for asphalt, soils and paints (Labed & Stoll 1991; Sobrino &
//! Cuenca 1999, Appl. Opt. 38, 3931). ε₀ = 1 stays 1 at every angle (n = 1).
//! [`AngularFalloff::None`] switches this off (ε independent of θ).
//!
//! Owns the evaluation of ε(λ, θ) (table lookups by [`crate::math`]). Takes
//! a [`Material`] or an [`EmissivityCurve`]; gives an [`Emissivity`]
//! evaluator. Must not know file formats ([`crate::material`]) or bands.

use crate::material::{EmissivityCurve, Material};
use crate::math::{bracket, interp1d, lerp};
use crate::{Error, Result};

/// What to do with view angle when the material has no angular data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AngularFalloff {
    /// Fresnel fall-off of a dielectric matching the normal emissivity.
    #[default]
    Fresnel,
    /// ε independent of view angle.
    None,
}

/// Unpolarised Fresnel reflectance of a smooth interface from air into a
/// medium of real refractive index `n` ≥ 1, at incidence `theta_rad`.
pub fn fresnel_reflectance(n: f64, theta_rad: f64) -> f64 {
    let c = theta_rad.cos().clamp(0.0, 1.0);
    let s2 = 1.0 - c * c;
    let ct = (1.0 - s2 / (n * n)).max(0.0).sqrt();
    let rs = (c - n * ct) / (c + n * ct);
    let rp = (ct - n * c) / (ct + n * c);
    if !(rs.is_finite() && rp.is_finite()) {
        return 1.0; // c = 0 and ct·n = 0 cannot both hold for n ≥ 1; guard anyway
    }
    0.5 * (rs * rs + rp * rp)
}

/// ε(θ) of a smooth dielectric whose normal emissivity is `normal` (see the
/// module docs). `theta_deg` is the view zenith from the surface normal.
pub fn fresnel_emissivity(normal: f64, theta_deg: f64) -> f64 {
    let normal = normal.clamp(0.0, 1.0);
    if normal >= 1.0 {
        return 1.0;
    }
    if normal <= 0.0 {
        return 0.0;
    }
    let r0 = (1.0 - normal).sqrt();
    let n = (1.0 + r0) / (1.0 - r0);
    let theta = theta_deg.clamp(0.0, 90.0).to_radians();
    (1.0 - fresnel_reflectance(n, theta)).clamp(0.0, 1.0)
}

/// An emissivity evaluator for one material.
#[derive(Debug, Clone, PartialEq)]
pub struct Emissivity {
    /// Wavelengths, µm (empty for grey).
    wavelengths_um: Vec<f64>,
    /// One row per angle (or one row); for grey, one row of one value.
    rows: Vec<Vec<f64>>,
    /// Angles of the rows, degrees; empty or one = no angular data.
    angles_deg: Vec<f64>,
    falloff: AngularFalloff,
}

impl Emissivity {
    /// A grey emissivity (0–1), with the default angular fall-off.
    pub fn grey(emissivity: f64) -> Result<Self> {
        if !(0.0..=1.0).contains(&emissivity) {
            return Err(Error::invalid(
                "emissivity",
                format!("expected a value in 0–1, got {emissivity}"),
            ));
        }
        Ok(Emissivity {
            wavelengths_um: vec![1.0],
            rows: vec![vec![emissivity]],
            angles_deg: vec![],
            falloff: AngularFalloff::default(),
        })
    }

    /// From a spectral (optionally angular) curve; validates it.
    pub fn from_curve(curve: &EmissivityCurve) -> Result<Self> {
        let wl = &curve.wavelengths_um;
        if wl.is_empty() {
            return Err(Error::invalid(
                "emissivity_curve.wavelengths_um",
                "is empty",
            ));
        }
        for i in 0..wl.len() {
            if !(wl[i].is_finite() && wl[i] > 0.0) || (i > 0 && wl[i] <= wl[i - 1]) {
                return Err(Error::invalid(
                    format!("emissivity_curve.wavelengths_um[{i}]"),
                    format!("expected positive, strictly increasing µm, got {}", wl[i]),
                ));
            }
        }
        let nrows = curve.angles_deg.len().max(1);
        if curve.emissivity.len() != nrows {
            return Err(Error::invalid(
                "emissivity_curve.emissivity",
                format!(
                    "expected {nrows} row(s) (one per angle), got {}",
                    curve.emissivity.len()
                ),
            ));
        }
        for (r, row) in curve.emissivity.iter().enumerate() {
            if row.len() != wl.len() {
                return Err(Error::invalid(
                    format!("emissivity_curve.emissivity[{r}]"),
                    format!("expected {} values, got {}", wl.len(), row.len()),
                ));
            }
            if let Some((c, v)) = row
                .iter()
                .enumerate()
                .find(|(_, v)| !(0.0..=1.0).contains(*v))
            {
                return Err(Error::invalid(
                    format!("emissivity_curve.emissivity[{r}][{c}]"),
                    format!("expected an emissivity in 0–1, got {v}"),
                ));
            }
        }
        let a = &curve.angles_deg;
        for i in 0..a.len() {
            if !(0.0..=90.0).contains(&a[i]) || (i > 0 && a[i] <= a[i - 1]) {
                return Err(Error::invalid(
                    format!("emissivity_curve.angles_deg[{i}]"),
                    format!("expected increasing angles in 0–90°, got {}", a[i]),
                ));
            }
        }
        Ok(Emissivity {
            wavelengths_um: wl.clone(),
            rows: curve.emissivity.clone(),
            angles_deg: a.clone(),
            falloff: AngularFalloff::default(),
        })
    }

    /// The material's emissivity: its curve, else its grey `thermal_emissivity`.
    pub fn from_material(m: &Material) -> Result<Self> {
        let r = match &m.emissivity_curve {
            Some(c) => Emissivity::from_curve(c),
            None => Emissivity::grey(m.thermal_emissivity),
        };
        r.map_err(|e| Error::invalid(format!("material `{}`", m.name), e.to_string()))
    }

    /// The same with another angular fall-off for data without angles.
    pub fn with_falloff(mut self, falloff: AngularFalloff) -> Self {
        self.falloff = falloff;
        self
    }

    /// Whether the data carry their own angular dependence.
    pub fn has_angular_data(&self) -> bool {
        self.angles_deg.len() >= 2
    }

    /// ε(λ) at normal view (or the first tabulated angle).
    pub fn normal(&self, wavelength_um: f64) -> f64 {
        interp1d(&self.wavelengths_um, &self.rows[0], wavelength_um)
    }

    /// ε(λ, θ) for λ in µm and view zenith θ in degrees from the normal.
    pub fn eval(&self, wavelength_um: f64, view_zenith_deg: f64) -> f64 {
        let theta = view_zenith_deg.abs().min(90.0);
        if self.has_angular_data() {
            let (i0, i1, t) = bracket(&self.angles_deg, theta);
            let e0 = interp1d(&self.wavelengths_um, &self.rows[i0], wavelength_um);
            let e1 = interp1d(&self.wavelengths_um, &self.rows[i1], wavelength_um);
            return lerp(e0, e1, t);
        }
        let e0 = self.normal(wavelength_um);
        match self.falloff {
            AngularFalloff::Fresnel => fresnel_emissivity(e0, theta),
            AngularFalloff::None => e0,
        }
    }

    /// ε(λ, θ) on the given wavelengths, into `out`.
    pub fn eval_into(&self, wavelengths_um: &[f64], view_zenith_deg: f64, out: &mut [f64]) {
        debug_assert_eq!(wavelengths_um.len(), out.len());
        for (o, &l) in out.iter_mut().zip(wavelengths_um) {
            *o = self.eval(l, view_zenith_deg);
        }
    }
}
