//! The per-hit radiance ("big equation"), spectral on a band grid: the one
//! reference implementation. The renderer's spectral path
//! ([`crate::render::Shader::shade`]) evaluates every hit through
//! [`leaving_radiance`]; its fast paths (grey band integrals, the fused
//! single-precision band sums) are tested against it on random inputs
//! (`tests/render.rs`, `docs/physics/radiometry.md`). The solar spectrum at
//! the top of the atmosphere is in [`super::solar`].
//!
//! For a facet at temperature T seen at view zenith θ (from its normal), with
//! spectral emissivity ε(λ, θ), transmissivity t (grey) and reflectance
//! r(λ) = max(1 − ε(λ, θ) − t, 0) (Kirchhoff; r = 1 − ε for opaque facets)
//! split into a specular part r_s = s·r and a diffuse part r_d = (1 − s)·r
//! (s the material's specular fraction), the radiance leaving toward the
//! sensor is (after DIRSIG; Schott, *Remote Sensing: The Image Chain
//! Approach*, 2nd ed., eq. 4.59):
//!
//! ```text
//! L(λ) = ε·B(λ,T)                                  self-emission
//!      + r_d·E_s(λ)·cos σ·f_sun / π                direct sun (diffuse part)
//!      + r_d·F·L_sky(λ)                            sky, L_sky = (E_ds + E_de)/π
//!      + r_d·(1 − F)·L_bg(λ)                       background, L_bg = L_bs + L_be
//!      + r_s·L_spec(λ)                             specular: radiance arriving
//!                                                  along the mirror direction
//!      + r_s·E_s(λ)·v·D(h)/(4 cos θ)               the sun through the glint lobe
//!      + t·L_behind(λ)                             radiance along the continuing ray
//! ```
//!
//! E_s is the solar spectral irradiance at the surface on a plane normal to
//! the sun (E_toa·τ₁), `v·D(h)/(4 cos θ)` the glint lobe of
//! [`crate::render::glint`] times the hit's sun visibility. When no
//! specular or continuing ray was traced (bounce budget spent) L_spec and
//! L_behind default to the diffuse environment F·L_sky + (1 − F)·L_bg.
//! The sensor sees L·τ₂ + L_u, integrated over the band response
//! ([`at_sensor`]). Units: spectral radiance W·m⁻²·sr⁻¹·µm⁻¹, irradiance
//! W·m⁻²·µm⁻¹, band radiance W·m⁻²·sr⁻¹.

use super::band::Band;

/// Solar constant (total solar irradiance at 1 AU), W/m²: Kopp & Lean 2011,
/// Geophys. Res. Lett. 38, L01706 (1360.8 ± 0.5).
pub const SOLAR_CONSTANT_W_M2: f64 = 1360.8;
/// Effective temperature of the solar photosphere, K (blackbody of the same
/// total flux; IAU 2015 nominal value 5772 K). The top-of-atmosphere
/// spectrum is the measured one ([`super::solar`]); this is for the grey
/// spreading of a broadband irradiance where no spectrum applies.
pub const SUN_TEMPERATURE_K: f64 = 5772.0;

pub use super::solar::solar_irradiance_toa;

/// The reflectance split of a facet at one wavelength.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReflectanceSplit {
    /// Diffuse reflectance r_d = (1 − s)(1 − ε − t).
    pub diffuse: f64,
    /// Specular reflectance r_s = s(1 − ε − t).
    pub specular: f64,
    /// Transmittance t: the weight of the continuing ray's radiance.
    pub transmitted: f64,
}

/// Split 1 − ε into specular, diffuse and transmitted parts (Kirchhoff:
/// ε + r + t = 1, clamped so r ≥ 0).
#[inline]
pub fn reflectance_split(
    emissivity: f64,
    specular_fraction: f64,
    transmissivity: f64,
) -> ReflectanceSplit {
    let t = transmissivity.clamp(0.0, 1.0);
    let r = (1.0 - emissivity - t).max(0.0);
    let s = specular_fraction.clamp(0.0, 1.0);
    ReflectanceSplit {
        diffuse: (1.0 - s) * r,
        specular: s * r,
        transmitted: t,
    }
}

/// Everything the equation needs for one hit; spectra are on the band grid.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceInputs<'a> {
    /// Blackbody spectral radiance at the surface temperature, B(λ, T),
    /// W·m⁻²·sr⁻¹·µm⁻¹ (exact: [`super::SpectralGrid::blackbody`]; the
    /// renderer passes its tabulated values, see its module docs).
    pub blackbody: &'a [f64],
    /// ε(λ, θ_view) on the grid (see [`super::Emissivity::eval_into`]).
    pub emissivity: &'a [f64],
    /// Fraction s of the reflectance that is specular, 0–1.
    pub specular_fraction: f64,
    /// Grey transmissivity t, 0–1 (0 for opaque facets).
    pub transmissivity: f64,
    /// Sky view (shape) factor F, 0–1.
    pub shape_factor: f64,
    /// Sky radiance (E_ds + E_de)/π, W·m⁻²·sr⁻¹·µm⁻¹.
    pub sky_radiance: &'a [f64],
    /// Background radiance L_bs + L_be, W·m⁻²·sr⁻¹·µm⁻¹.
    pub background_radiance: &'a [f64],
    /// Direct solar irradiance at the surface on a plane normal to the sun,
    /// E_s·τ₁, W·m⁻²·µm⁻¹ (`None` at night).
    pub solar_irradiance: Option<&'a [f64]>,
    /// cos σ · f_sun: cosine of the sun's incidence angle on the facet times
    /// the sunlit fraction (≤ 0: no direct sun, e.g. the sun behind the face).
    pub cos_sun: f64,
    /// The glint lobe toward the viewer times the hit's sun visibility,
    /// v·D(h)/(4 cos θ_v), sr⁻¹ ([`crate::render::glint::glint_lobe_sr`];
    /// 0: no glint).
    pub glint_sr: f64,
    /// Radiance arriving along the specular direction, traced by the caller;
    /// `None`: use the diffuse environment F·L_sky + (1 − F)·L_bg.
    pub specular_radiance: Option<&'a [f64]>,
    /// Radiance arriving along the continuing (transmitted) ray, traced by
    /// the caller; `None`: use the diffuse environment.
    pub transmitted_radiance: Option<&'a [f64]>,
}

/// Spectral radiance leaving the facet toward the sensor, written into `out`
/// (W·m⁻²·sr⁻¹·µm⁻¹, one value per grid wavelength of the inputs): the
/// module docs' equation, every term.
pub fn leaving_radiance(inputs: &SurfaceInputs, out: &mut [f64]) {
    let n = out.len();
    debug_assert_eq!(inputs.blackbody.len(), n);
    debug_assert_eq!(inputs.emissivity.len(), n);
    debug_assert_eq!(inputs.sky_radiance.len(), n);
    debug_assert_eq!(inputs.background_radiance.len(), n);
    let f = inputs.shape_factor.clamp(0.0, 1.0);
    // E_s·cos σ·f_sun/π = E_s · sun_w.
    let sun_w = inputs.cos_sun.max(0.0) / std::f64::consts::PI;
    for i in 0..n {
        let eps = inputs.emissivity[i];
        let split = reflectance_split(eps, inputs.specular_fraction, inputs.transmissivity);
        let env = f * inputs.sky_radiance[i] + (1.0 - f) * inputs.background_radiance[i];
        let e_s = inputs.solar_irradiance.map_or(0.0, |e| e[i]);
        let sun = e_s * sun_w;
        let spec = inputs.specular_radiance.map_or(env, |s| s[i]) + e_s * inputs.glint_sr;
        let behind = inputs.transmitted_radiance.map_or(env, |s| s[i]);
        out[i] = eps * inputs.blackbody[i]
            + split.diffuse * (sun + env)
            + split.specular * spec
            + split.transmitted * behind;
    }
}

/// Band radiance at the sensor, ∫ R (L·τ₂ + L_u) dλ in W·m⁻²·sr⁻¹, for a
/// leaving spectral radiance `leaving` and the path's transmittance τ₂ and
/// path radiance L_u, all on `band`'s grid.
pub fn at_sensor(
    leaving: &[f64],
    transmittance: &[f64],
    path_radiance: &[f64],
    band: &Band,
) -> f64 {
    let w = band.weights_um();
    debug_assert!(leaving.len() == w.len() && transmittance.len() == w.len());
    debug_assert_eq!(path_radiance.len(), w.len());
    (0..w.len())
        .map(|i| w[i] * (leaving[i] * transmittance[i] + path_radiance[i]))
        .sum()
}
