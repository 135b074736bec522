//! The sun reflected by specular and glossy surfaces (glint): the solar
//! disc seen through a surface's roughness lobe.
//!
//! A surface whose reflectance has a specular part `r_s(λ) = s·r(λ)` (the
//! material's specular fraction `s`, `r = 1 − ε − t`) reflects the direct
//! solar irradiance `E_s(λ)` (normal to the sun, W·m⁻²·µm⁻¹) toward the
//! viewer with the microfacet BRDF of an isotropic Beckmann slope
//! distribution (Beckmann & Spizzichino 1963, *The Scattering of
//! Electromagnetic Waves from Rough Surfaces*; Walter et al. 2007, EGSR,
//! eq. 25), the Fresnel term being `r_s` itself and shadowing–masking left
//! out (grazing geometry only):
//!
//! ```text
//! f_s = r_s · D(h) / (4 cos θ_i cos θ_o),
//! D(h) = exp(−tan²θ_h / m²) / (π m² cos⁴θ_h)        sr⁻¹
//! L_glint(λ) = f_s · E_s(λ) · cos θ_i = r_s(λ) · E_s(λ) · D(h) / (4 cos θ_o)
//! ```
//!
//! with `h` the half vector of the directions to the sun and to the viewer,
//! `θ_h` its angle from the normal, `θ_o` the view zenith (from the normal).
//! `D` is normalised, `∫ D(h) cos θ_h dω_h = 1`, so the lobe carries the
//! specular reflectance: `∫ f_s cos θ_i dω_i = r_s` (exact at normal view;
//! within 2·10⁻³ at 40° by quadrature, [`glint_lobe_sr`]); a smooth surface (`m → 0`) is the
//! mirror of the module `shade`'s specular ray.
//!
//! For water `m²` is the slope variance of the sea surface of Cox & Munk
//! (1954), *J. Opt. Soc. Am.* 44, 838, eq. for the clean surface:
//! `σ² = 0.003 + 5.12·10⁻³·U` (U the wind speed in m/s at 12.5 m; here
//! the weather's wind speed, whose measurement height is not corrected for)
//! — the Cox–Munk slope distribution is the Beckmann `D` with `m² = σ²`.
//! Other specular materials (glass, glossy paint, metal) take their
//! `specular_roughness` (the RMS facet slope m, `m²` its square), else
//! [`GLOSSY_RMS_SLOPE`]. The solar disc's own extent widens every
//! lobe: a uniform disc of angular radius `α` moves the mirror normal over
//! a disc of radius `α/2`, per-axis variance `α²/16`, i.e. a Beckmann
//! `m²` of `α²/8`, added to the surface's ([`SUN_ANGULAR_RADIUS_RAD`]).

use glam::Vec3;

use crate::material::Material;
use crate::material::surface::SurfaceKind;

/// Mean angular radius of the solar disc, rad: 959.63″ (IAU; the solar
/// radius 695 700 km at 1 AU).
pub const SUN_ANGULAR_RADIUS_RAD: f64 = 4.652e-3;

/// RMS facet slope of specular materials other than water that give no
/// `specular_roughness`: 0.05 (2.9°), between float glass (< 1°) and
/// glossy paint (Walter et al. 2007 fit GGX widths of 0.05–0.2 to glossy
/// measured surfaces). irsig choice.
pub const GLOSSY_RMS_SLOPE: f64 = 0.05;

/// Beckmann slope variance `m²` of [`GLOSSY_RMS_SLOPE`].
pub const GLOSSY_SLOPE_VARIANCE: f64 = GLOSSY_RMS_SLOPE * GLOSSY_RMS_SLOPE;

/// Cox & Munk (1954) slope variance of a clean sea surface at wind speed
/// `wind_m_s` (m/s; negative or non-finite taken as calm).
pub fn cox_munk_slope_variance(wind_m_s: f64) -> f64 {
    let u = if wind_m_s.is_finite() {
        wind_m_s.max(0.0)
    } else {
        0.0
    };
    0.003 + 5.12e-3 * u
}

/// The Beckmann `m²` of a material's glint lobe under wind `wind_m_s`
/// (m/s), the sun's disc included: water after Cox & Munk, others the
/// square of their `specular_roughness` (RMS slope), else
/// [`GLOSSY_SLOPE_VARIANCE`].
pub fn lobe_slope_variance(m: &Material, wind_m_s: f64) -> f64 {
    let water = m
        .surface_energy
        .is_some_and(|s| s.kind == SurfaceKind::Water);
    let surface = if water {
        cox_munk_slope_variance(wind_m_s)
    } else {
        m.specular_roughness
            .filter(|r| r.is_finite() && *r >= 0.0)
            .map_or(GLOSSY_SLOPE_VARIANCE, |r| r * r)
    };
    surface + SUN_ANGULAR_RADIUS_RAD * SUN_ANGULAR_RADIUS_RAD / 8.0
}

/// The glint lobe `D(h) / (4 cos θ_o)`, sr⁻¹, for unit normal `n`, unit
/// direction to the viewer `v` and to the sun `s` (module docs); 0 when
/// either lies behind the surface. `L_glint = r_s · E_s · lobe`.
pub fn glint_lobe_sr(m2: f64, n: Vec3, v: Vec3, s: Vec3) -> f64 {
    let (n, v, s) = (n.as_dvec3(), v.as_dvec3(), s.as_dvec3());
    let (cos_o, cos_i) = (n.dot(v), n.dot(s));
    if cos_o <= 0.0 || cos_i <= 0.0 || m2 <= 0.0 {
        return 0.0;
    }
    let h = (v + s).normalize_or_zero();
    let c = n.dot(h);
    if c <= 0.0 {
        return 0.0;
    }
    let c2 = c * c;
    let tan2 = (1.0 - c2) / c2;
    let d = (-tan2 / m2).exp() / (std::f64::consts::PI * m2 * c2 * c2);
    d / (4.0 * cos_o)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hemispherical–directional reflectance of the lobe over `r_s`,
    /// `∫ f cos θ_i dω_i / r_s = ∫ lobe dω_i` over the hemisphere of sun
    /// directions, by quadrature in (θ_i, φ).
    fn albedo(m2: f64, view_zenith_deg: f64) -> f64 {
        let n = Vec3::Z;
        let t = view_zenith_deg.to_radians();
        let v = Vec3::new(t.sin() as f32, 0.0, t.cos() as f32);
        let (nt, np) = (4000, 720);
        let mut sum = 0.0;
        let dt = std::f64::consts::FRAC_PI_2 / nt as f64;
        let dp = 2.0 * std::f64::consts::PI / np as f64;
        for i in 0..nt {
            let th = (i as f64 + 0.5) * dt;
            for j in 0..np {
                let ph = (j as f64 + 0.5) * dp;
                let s = Vec3::new(
                    (th.sin() * ph.cos()) as f32,
                    (th.sin() * ph.sin()) as f32,
                    th.cos() as f32,
                );
                sum += glint_lobe_sr(m2, n, v, s) * th.sin() * dt * dp;
            }
        }
        sum
    }

    #[test]
    fn the_lobe_carries_the_specular_reflectance() {
        // Normalised Beckmann D: the lobe's reflectance is r_s (to the
        // quadrature's accuracy) at normal and 40° view, for a glossy and a
        // windy-water lobe.
        for m2 in [GLOSSY_SLOPE_VARIANCE, cox_munk_slope_variance(5.0)] {
            for view in [0.0, 40.0] {
                let a = albedo(m2, view);
                assert!((a - 1.0).abs() < 2e-3, "m² {m2} at {view}°: ∫ = {a}");
            }
        }
    }

    #[test]
    fn the_lobe_peaks_in_the_mirror_direction() {
        let m2 = cox_munk_slope_variance(3.0);
        let s = Vec3::new(0.5, 0.0, 0.75f32.sqrt());
        let mirror = Vec3::new(-0.5, 0.0, 0.75f32.sqrt());
        let peak = glint_lobe_sr(m2, Vec3::Z, mirror, s);
        // D(h = n) = 1/(π m²), over 4 cos θ_o.
        let expect = 1.0 / (std::f64::consts::PI * m2 * 4.0 * 0.75f64.sqrt());
        assert!((peak / expect - 1.0).abs() < 1e-5, "{peak} vs {expect}");
        for off in [0.05f32, 0.1, 0.2] {
            let v = (mirror + Vec3::new(off, 0.0, 0.0)).normalize();
            assert!(glint_lobe_sr(m2, Vec3::Z, v, s) < peak);
        }
        // Behind the surface: nothing.
        assert_eq!(glint_lobe_sr(m2, Vec3::Z, -mirror, s), 0.0);
        assert_eq!(glint_lobe_sr(m2, Vec3::Z, mirror, -s), 0.0);
    }

    /// A material's `specular_roughness` sets its lobe (`m²` = its square,
    /// plus the sun's disc); without it the glossy default; water keeps
    /// Cox–Munk from the wind whatever the field says.
    #[test]
    fn the_lobe_takes_the_materials_roughness_and_water_the_wind() {
        let db = crate::material::stock::stock().expect("stock materials");
        let disc = SUN_ANGULAR_RADIUS_RAD * SUN_ANGULAR_RADIUS_RAD / 8.0;
        let mut glass = db.get("glass").expect("stock glass").clone();
        glass.specular_roughness = None;
        assert!((lobe_slope_variance(&glass, 3.0) - (GLOSSY_SLOPE_VARIANCE + disc)).abs() < 1e-15);
        glass.specular_roughness = Some(0.2);
        assert!((lobe_slope_variance(&glass, 3.0) - (0.04 + disc)).abs() < 1e-15);
        // A rougher lobe is lower at its peak by the ratio of the m².
        let s = Vec3::new(0.5, 0.0, 0.75f32.sqrt());
        let mirror = Vec3::new(-0.5, 0.0, 0.75f32.sqrt());
        let m_rough = lobe_slope_variance(&glass, 0.0);
        glass.specular_roughness = Some(0.05);
        let m_smooth = lobe_slope_variance(&glass, 0.0);
        let ratio = glint_lobe_sr(m_smooth, Vec3::Z, mirror, s)
            / glint_lobe_sr(m_rough, Vec3::Z, mirror, s);
        assert!((ratio - m_rough / m_smooth).abs() < 1e-6 * ratio, "{ratio}");
        let water = db.get("water").expect("stock water").clone();
        assert!(
            (lobe_slope_variance(&water, 7.0) - (cox_munk_slope_variance(7.0) + disc)).abs()
                < 1e-15
        );
    }

    #[test]
    fn cox_munk_variance_follows_the_published_fit() {
        // Cox & Munk (1954): σ² = 0.003 + 5.12e-3 U; at 10 m/s 0.0542.
        assert!((cox_munk_slope_variance(10.0) - 0.0542).abs() < 1e-12);
        assert_eq!(cox_munk_slope_variance(-1.0), 0.003);
        assert_eq!(cox_munk_slope_variance(f64::NAN), 0.003);
    }
}
