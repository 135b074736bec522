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
//! **Hemispherical emissivity** (what the thermal model emits and absorbs
//! with): `ε_h = 2∫₀^{π/2} ε(θ) cos θ sin θ dθ` of the same angular model
//! ([`Emissivity::hemispherical`], [`hemispherical_ratio`],
//! [`thermal_hemispherical_emissivity`]), by composite Simpson quadrature in
//! θ ([`HEMISPHERE_INTERVALS`] intervals; error < 10⁻⁶ against the closed
//! form of a dielectric, [`dielectric_hemispherical_emissivity`]). For the
//! Fresnel fall-off ε_h/ε_n is 0.953 at n = 1.33 (water), 0.946 at n = 1.5
//! (glass), 0.944 at n = 2 — the 0.94–0.95 of Modest, *Radiative Heat
//! Transfer*, 3rd ed., 2013, ch. 3, and Siegel & Howell, *Thermal Radiation
//! Heat Transfer*, for non-metals.
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

/// Intervals of the composite Simpson rule in θ of the hemispherical
/// integrals (even).
pub const HEMISPHERE_INTERVALS: usize = 180;

/// `2∫₀^{π/2} e(θ) cos θ sin θ dθ` of `e` (θ in degrees), composite Simpson
/// with [`HEMISPHERE_INTERVALS`] intervals.
pub fn hemispherical_integral(e: impl Fn(f64) -> f64) -> f64 {
    let n = HEMISPHERE_INTERVALS;
    let h = std::f64::consts::FRAC_PI_2 / n as f64;
    let g = |i: usize| {
        let t = i as f64 * h;
        e(t.to_degrees()) * (2.0 * t).sin() // 2 cos θ sin θ
    };
    let mut s = g(0) + g(n);
    for i in 1..n {
        s += if i % 2 == 1 { 4.0 } else { 2.0 } * g(i);
    }
    s * h / 3.0
}

/// Hemispherical emissivity of a smooth dielectric of real refractive index
/// `n > 1` in air, in closed form: `1 − ρ_h` with Dunkle's hemispherical
/// reflectance of the Fresnel equations,
/// `ρ_h = ½ + (3n+1)(n−1)/(6(n+1)²) + n²(n²−1)²/(n²+1)³·ln((n−1)/(n+1))
///  − 2n³(n²+2n−1)/((n²+1)(n⁴−1)) + 8n⁴(n⁴+1)/((n²+1)(n⁴−1)²)·ln n`
/// (Siegel & Howell, *Thermal Radiation Heat Transfer*, ch. 3; Modest,
/// *Radiative Heat Transfer*, 3rd ed., 2013, ch. 3). The check of the
/// quadrature ([`hemispherical_integral`]).
pub fn dielectric_hemispherical_emissivity(n: f64) -> f64 {
    let (n2, n4) = (n * n, n.powi(4));
    let rho = 0.5
        + (3.0 * n + 1.0) * (n - 1.0) / (6.0 * (n + 1.0).powi(2))
        + n2 * (n2 - 1.0).powi(2) / (n2 + 1.0).powi(3) * ((n - 1.0) / (n + 1.0)).ln()
        - 2.0 * n.powi(3) * (n2 + 2.0 * n - 1.0) / ((n2 + 1.0) * (n4 - 1.0))
        + 8.0 * n4 * (n4 + 1.0) / ((n2 + 1.0) * (n4 - 1.0).powi(2)) * n.ln();
    1.0 - rho
}

/// `ε_h/ε_n` of an angular model given as ε(θ) (θ in degrees): the
/// hemispherical over the normal value (1 when ε(0) = 0).
pub fn hemispherical_ratio(e: impl Fn(f64) -> f64) -> f64 {
    let normal = e(0.0);
    if normal <= 0.0 {
        return 1.0;
    }
    hemispherical_integral(e) / normal
}

/// The hemispherical broadband emissivity of a material for the thermal
/// model: its `thermal_emissivity` — a **normal** emissivity, as DIRSIG's
/// `THERMAL_EMISSIVITY` — times `ε_h/ε_n` of the angular model the renderer
/// applies to it ([`Emissivity::from_material`]: the material's angular
/// curve, else the Fresnel fall-off matching the normal value). For a
/// spectral curve the ratio is that of the curve's mean over its
/// wavelengths.
///
/// # Errors
/// As [`Emissivity::from_material`] (a bad curve), naming the material.
pub fn thermal_hemispherical_emissivity(m: &Material) -> Result<f64> {
    let eps = m.thermal_emissivity.clamp(0.0, 1.0);
    let ratio = match &m.emissivity_curve {
        None => hemispherical_ratio(|t| fresnel_emissivity(eps, t)),
        Some(_) => {
            let e = Emissivity::from_material(m)?;
            let wl = e.wavelengths_um.clone();
            let mean = |t: f64| wl.iter().map(|&l| e.eval(l, t)).sum::<f64>() / wl.len() as f64;
            hemispherical_ratio(mean)
        }
    };
    Ok((eps * ratio).clamp(0.0, 1.0))
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

    /// Hemispherical emissivity at `wavelength_um`, `2∫ε(λ, θ) cos θ sin θ dθ`
    /// ([`hemispherical_integral`]).
    pub fn hemispherical(&self, wavelength_um: f64) -> f64 {
        hemispherical_integral(|t| self.eval(wavelength_um, t))
    }

    /// ε(λ, θ) on the given wavelengths, into `out`.
    pub fn eval_into(&self, wavelengths_um: &[f64], view_zenith_deg: f64, out: &mut [f64]) {
        debug_assert_eq!(wavelengths_um.len(), out.len());
        for (o, &l) in out.iter_mut().zip(wavelengths_um) {
            *o = self.eval(l, view_zenith_deg);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::EmissivityCurve;

    /// The Simpson quadrature of the Fresnel model against Dunkle's closed
    /// form, and the published ratio ε_h/ε_n of 0.94–0.95 for n ≈ 1.5.
    #[test]
    fn hemispherical_fresnel_matches_closed_form_and_published_ratio() {
        for n in [1.2f64, 1.33, 1.5, 2.0, 3.0, 5.0] {
            let r0 = ((n - 1.0) / (n + 1.0)).powi(2);
            let normal = 1.0 - r0;
            let quad = hemispherical_integral(|t| fresnel_emissivity(normal, t));
            let exact = dielectric_hemispherical_emissivity(n);
            assert!((quad - exact).abs() < 1e-6, "n = {n}: {quad} vs {exact}");
        }
        let ratio = hemispherical_ratio(|t| fresnel_emissivity(0.96, t));
        assert!((0.94..=0.95).contains(&ratio), "n = 1.5: ε_h/ε_n = {ratio}");
        // Lambertian (no fall-off) and black: ε_h = ε_n.
        assert!((hemispherical_ratio(|_| 0.9) - 1.0).abs() < 1e-9);
        assert!((hemispherical_ratio(|t| fresnel_emissivity(1.0, t)) - 1.0).abs() < 1e-8);
    }

    /// A material's thermal emissivity: grey → the Fresnel ratio; an angular
    /// curve → its own ratio.
    #[test]
    fn thermal_hemispherical_emissivity_of_materials() {
        let db = crate::material::stock::stock().unwrap();
        let mut m = db.get("asphalt").unwrap().clone();
        m.emissivity_curve = None;
        m.thermal_emissivity = 0.96;
        let e = thermal_hemispherical_emissivity(&m).unwrap();
        assert!(
            (e - dielectric_hemispherical_emissivity(1.5)).abs() < 1e-6,
            "{e}"
        );
        // ε(θ) = 0.9 cos θ-like table: ε_h = 2∫0.9 cos²θ sinθ = 0.6 (to the
        // linear interpolation of the table).
        let angles: Vec<f64> = (0..=90).map(f64::from).collect();
        m.emissivity_curve = Some(EmissivityCurve {
            wavelengths_um: vec![8.0, 12.0],
            emissivity: angles
                .iter()
                .map(|a| vec![0.9 * a.to_radians().cos(); 2])
                .collect(),
            angles_deg: angles.clone(),
        });
        m.thermal_emissivity = 0.9;
        let e = thermal_hemispherical_emissivity(&m).unwrap();
        assert!((e - 0.6).abs() < 1e-3, "{e}");
    }
}
