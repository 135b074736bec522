//! Per-hit radiance: the "big equation" on each band's spectral grid, with
//! secondary rays for specular reflection and transmission.
//!
//! For a hit on a facet at temperature `T`, seen at view zenith `θ` from the
//! normal facing the ray, with spectral emissivity `ε(λ, θ)`, grey
//! transmissivity `t` and specular fraction `s` (Kirchhoff: reflectance
//! `r = 1 − ε − t`, diffuse `r_d = (1 − s)·r`, specular `r_s = s·r`), the
//! radiance leaving toward the sensor is (Schott, *Remote Sensing: The Image
//! Chain Approach*, 2nd ed., eq. 4.59, as DIRSIG evaluates it):
//!
//! ```text
//! L(λ) = ε·B(λ, T)                                 self-emission
//!      + r_d·E_s(λ)·cos σ·f_sun / π                direct sun (diffuse part)
//!      + r_d·[F·L_sky(λ) + (1 − F)·B(λ, T_bg)]     sky and background
//!      + r_s·L_spec(λ)                             radiance along the mirror ray
//!      + r_s·E_s(λ)·v·D(h)/(4 cos θ)               the sun through the glint lobe
//!      + t·L_behind(λ)                             radiance along the continuing ray
//! ```
//!
//! `F` is the facet's sky shape factor, `f_sun` the hit's sunlit fraction
//! (its own shadow ray where that matters, [`sun_ray_facets`]; `v` that
//! ray's answer, 0 or 1, and `D(h)/(4 cos θ)` the lobe of [`super::glint`]),
//! `cos σ` the cosine of the solar incidence, `T_bg` the radiative mean
//! temperature of what it sees below the sky. `L_spec` and `L_behind` are
//! traced (the same equation at the next hit) while the bounce budget lasts;
//! past it, both take the diffuse environment `F·L_sky + (1 − F)·B(T_bg)`.
//! Misses see the sky only, so the mirror ray and the glint lobe do not
//! count the sun twice.
//!
//! Rays that leave the scene see the sky radiance arriving from their own
//! direction when they point above the horizon (`dir.z ≥ 0`;
//! [`crate::atmosphere::Atmosphere::sky_radiance_toward`] on [`SKY_NODES`]
//! values of cos θ, linear between them) and the ground beyond the scene (a
//! blackbody at [`Conditions::ground_temperature_k`]) when they point below
//! it. `L_sky` in the diffuse term above is the isotropic-equivalent sky
//! ([`crate::atmosphere::Atmosphere::sky_radiance`]).
//!
//! Units: wavelength µm, spectral radiance W·m⁻²·sr⁻¹·µm⁻¹, spectral
//! irradiance W·m⁻²·µm⁻¹, band radiance ∫ R L dλ in W·m⁻²·sr⁻¹.
//!
//! Speed: Planck's function is tabulated per band on a temperature grid of
//! [`PLANCK_TABLE_STEP_K`] covering the scene's temperatures and
//! interpolated linearly (relative error ≤ 2·10⁻⁶, i.e. < 10⁻⁴ K in
//! brightness temperature, at 3–14 µm; temperatures off the table are
//! evaluated exactly), and emissivity per material on a 1° angle grid.
//!
//! Primary rays take [`Shader::fast_primary`] where no secondary ray is
//! needed: the band radiance at the sensor in one fused pass per band over
//! single-precision tables with the band weights (response × trapezoid,
//! times τ₂ per range node of the path table) folded in; for a material
//! whose emissivity is flat within a band (grey, at each angle row) ε and
//! r leave the sums and the band radiance is a handful of lookups in
//! per-band integrals over the Planck table (`Σ w·τ₂·B(T_k)`, `Σ w·τ₂·L_sky`,
//! `Σ w·τ₂·E_s`). Both use the same interpolations as the spectral
//! reference ([`Shader::shade`] + [`Shader::band_radiance`]), so they agree
//! with it to rounding (≤ 6·10⁻⁷ relative measured in `tests/render.rs`).

use glam::Vec3;

use super::path::PathTables;
use super::per_hit::{HitState, PerHit};
use crate::atmosphere::{Atmosphere, SkyConditions};
use crate::geometry::SceneGeometry;
use crate::material::Material;
use crate::radiometry::{Band, Emissivity, Planck};
use crate::trace::{Coherence, Hit, Ray, Tracer};

/// Temperature step of the tabulated Planck function, K.
pub const PLANCK_TABLE_STEP_K: f64 = 0.05;
/// Most nodes of the Planck table (beyond: exact evaluation).
const PLANCK_TABLE_MAX_NODES: usize = 16384;
/// Angle rows of the emissivity tables (0°, 1°, …, 90°).
const ANGLE_ROWS: usize = 91;
/// Nodes of the directional sky table: cos θ from cos 89° (the horizon,
/// [`crate::atmosphere::MAX_SKY_ZENITH_DEG`]) to 1, quadratically spaced
/// (denser toward the horizon, where the sky radiance changes fastest).
const SKY_NODES: usize = 24;

/// cos θ of sky node `k`.
fn sky_node_cos(k: usize) -> f64 {
    let mu0 = crate::atmosphere::MAX_SKY_ZENITH_DEG.to_radians().cos();
    let s = k as f64 / (SKY_NODES - 1) as f64;
    mu0 + (1.0 - mu0) * s * s
}

/// The sky nodes bracketing a direction with vertical component `dz` of a
/// vector of length `len`: `(k, f)` with the direction at fraction `f` from
/// node `k` to node `k + 1`.
#[inline]
fn sky_node(dz: f64, len: f64) -> (usize, f64) {
    let mu0 = crate::atmosphere::MAX_SKY_ZENITH_DEG.to_radians().cos();
    let mu = if len > 0.0 { dz / len } else { 1.0 };
    let s = ((mu - mu0).max(0.0) / (1.0 - mu0)).min(1.0).sqrt() * (SKY_NODES - 1) as f64;
    let k = (s as usize).min(SKY_NODES - 2);
    (k, s - k as f64)
}

/// Sky radiance model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sky {
    /// An isotropic sky: a blackbody at this temperature, K.
    Blackbody {
        /// Effective sky temperature, K.
        temperature_k: f64,
    },
    /// The atmosphere's sky radiance ([`Atmosphere::sky_radiance`]) for
    /// these surface conditions.
    Atmosphere(SkyConditions),
}

/// The sun as the renderer sees it at the image time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SunInput {
    /// Unit east-north-up vector toward the sun.
    pub direction: Vec3,
    /// Direct normal irradiance at the surface, W/m² (broadband; distributed
    /// over wavelength by [`surface_solar_spectrum`]).
    pub direct_normal_w_m2: f64,
}

/// Per-facet thermal state at the image time (global facet order).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SurfaceState {
    /// Surface temperature, K.
    pub temperature_k: Vec<f32>,
    /// Sky shape factor F, 0–1.
    pub shape_factor: Vec<f32>,
    /// Sunlit fraction, 0–1.
    pub sun_fraction: Vec<f32>,
    /// Cosine of the solar incidence on the front face (0 when the sun is
    /// behind the face or below the horizon).
    pub cos_sun: Vec<f32>,
    /// Radiative mean temperature of the background (non-sky) seen, K.
    pub background_k: Vec<f32>,
}

impl SurfaceState {
    /// Every facet at `temperature_k`, seeing only sky (F = 1), in shade.
    pub fn uniform(facets: usize, temperature_k: f32) -> Self {
        SurfaceState {
            temperature_k: vec![temperature_k; facets],
            shape_factor: vec![1.0; facets],
            sun_fraction: vec![0.0; facets],
            cos_sun: vec![0.0; facets],
            background_k: vec![temperature_k; facets],
        }
    }

    /// Number of facets.
    pub fn len(&self) -> usize {
        self.temperature_k.len()
    }

    /// Whether there are no facets.
    pub fn is_empty(&self) -> bool {
        self.temperature_k.is_empty()
    }

    /// Check the lengths agree and the values are finite and in range.
    pub fn validate(&self, facets: usize) -> crate::Result<()> {
        let lens = [
            ("temperature_k", self.temperature_k.len()),
            ("shape_factor", self.shape_factor.len()),
            ("sun_fraction", self.sun_fraction.len()),
            ("cos_sun", self.cos_sun.len()),
            ("background_k", self.background_k.len()),
        ];
        for (name, n) in lens {
            if n != facets {
                return Err(crate::Error::invalid(
                    format!("surface state `{name}`"),
                    format!("{n} values: expected one per facet ({facets})"),
                ));
            }
        }
        if let Some((i, t)) = self
            .temperature_k
            .iter()
            .chain(&self.background_k)
            .enumerate()
            .find(|(_, t)| !(t.is_finite() && **t > 0.0))
        {
            return Err(crate::Error::invalid(
                "surface temperature",
                format!("value {i} is {t} K: expected a finite positive temperature"),
            ));
        }
        Ok(())
    }
}

/// Everything about the image time the shading needs.
#[derive(Debug, Clone, PartialEq)]
pub struct Conditions {
    /// Per-facet thermal state.
    pub surface: SurfaceState,
    /// Sky radiance.
    pub sky: Sky,
    /// The sun, `None` at night.
    pub sun: Option<SunInput>,
    /// Temperature of the ground beyond the scene (rays leaving the scene
    /// downward), K; a blackbody.
    pub ground_temperature_k: f64,
    /// The atmosphere: sky radiance for [`Sky::Atmosphere`]; the sensor
    /// path is applied through [`Shader::with_path`].
    pub atmosphere: Atmosphere,
    /// Per-hit temperatures ([`super::per_hit`]); `None`: every hit takes
    /// its facet's state.
    pub per_hit: Option<std::sync::Arc<PerHit>>,
    /// Wind speed, m/s: the roughness of water's glint lobe
    /// ([`super::glint::cox_munk_slope_variance`]).
    pub wind_speed_m_s: f64,
}

/// What the renderer knows about each facet of the scene.
#[derive(Debug, Clone)]
pub struct SceneOptics {
    /// Materials; facets index into this.
    pub materials: Vec<Material>,
    /// Per facet: index into `materials`.
    pub facet_material: Vec<u32>,
    /// Per facet: object id (written to the `object_id` layer).
    pub facet_object: Vec<u32>,
}

/// Shading options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadeOptions {
    /// Most secondary bounces (specular reflection / transmission) per
    /// primary ray.
    pub max_bounces: u32,
    /// Secondary-ray origin offset along the normal, m.
    pub offset_m: f32,
}

/// Solar spectral irradiance on a surface normal to the sun, W·m⁻²·µm⁻¹:
/// the broadband direct normal irradiance `dni_w_m2` distributed as a
/// 5772 K blackbody (IAU 2015 nominal effective temperature),
/// `E(λ) = DNI · π B(λ, 5772 K) / (σ · 5772⁴)`.
pub fn solar_spectrum(planck: &Planck, wavelengths_um: &[f64], dni_w_m2: f64) -> Vec<f64> {
    const SUN_K: f64 = 5772.0;
    let sigma = crate::radiometry::Constants::CODATA_2018.stefan_boltzmann_w_m2_k4();
    let scale = dni_w_m2.max(0.0) * std::f64::consts::PI / (sigma * SUN_K.powi(4));
    wavelengths_um
        .iter()
        .map(|&l| scale * planck.radiance(l, SUN_K))
        .collect()
}

/// Clear-sky direct normal irradiance at the ground for the sun at
/// `zenith_deg`, W/m²: Meinel & Meinel (1976), *Applied Solar Energy*,
/// I_D = S₀·0.7^(AM^0.678), AM = 1/cos z (S₀ the solar constant of
/// [`crate::radiometry::equation::SOLAR_CONSTANT_W_M2`]); 0 at or below the horizon.
pub fn clear_sky_dni_w_m2(zenith_deg: f64) -> f64 {
    if !(zenith_deg.is_finite() && zenith_deg < 90.0) {
        return 0.0;
    }
    let am = 1.0 / zenith_deg.max(0.0).to_radians().cos();
    crate::radiometry::equation::SOLAR_CONSTANT_W_M2 * 0.7f64.powf(am.powf(0.678))
}

/// Solar spectral irradiance at the ground on a surface normal to the sun,
/// W·m⁻²·µm⁻¹, on `grid`. With no atmosphere, the weather's broadband DNI
/// spread as a 5772 K blackbody ([`solar_spectrum`]). With one, the
/// top-of-atmosphere spectrum ([`crate::radiometry::solar_irradiance_toa`],
/// 1 AU) times the atmosphere's τ₁(λ) along the sun's path
/// ([`Atmosphere::solar_transmittance`]: no energy inside the absorption
/// bands) times the weather's attenuation beyond a clear sky,
/// c = min(1, DNI / DNI_clear) ([`clear_sky_dni_w_m2`]: clouds and haze,
/// taken as grey; at most the clear sky, since near the horizon a measured
/// DNI over a small modelled clear-sky DNI would otherwise multiply the
/// spectrum without bound).
pub fn surface_solar_spectrum(
    atmosphere: &Atmosphere,
    planck: &Planck,
    sun: &SunInput,
    grid: &crate::radiometry::SpectralGrid,
) -> crate::Result<Vec<f64>> {
    let wl = grid.wavelengths_um();
    if matches!(atmosphere, Atmosphere::None) {
        return Ok(solar_spectrum(planck, wl, sun.direct_normal_w_m2));
    }
    let d = sun.direction.normalize_or_zero();
    let zenith = (d.z as f64).clamp(-1.0, 1.0).acos().to_degrees();
    let clear = clear_sky_dni_w_m2(zenith);
    if clear <= 0.0 || sun.direct_normal_w_m2 <= 0.0 {
        return Ok(vec![0.0; wl.len()]);
    }
    let c = (sun.direct_normal_w_m2 / clear).min(1.0);
    let tau = atmosphere.solar_transmittance(zenith, grid)?;
    Ok(crate::radiometry::solar_irradiance_toa(grid, 1.0)
        .into_iter()
        .zip(tau)
        .map(|(e, t)| e * t * c)
        .collect())
}

/// One band's precomputed tables.
#[derive(Debug, Clone)]
struct BandTables {
    band: Band,
    /// Offset of this band's wavelengths in the concatenated spectrum.
    start: usize,
    /// Sky spectral radiance of the isotropic-equivalent sky (the reflected
    /// sky of a diffuse surface).
    sky: Vec<f64>,
    /// Sky spectral radiance arriving from each of the [`SKY_NODES`]
    /// directions ([`sky_node_cos`]): what a ray leaving the scene sees.
    sky_dir: Vec<Vec<f64>>,
    /// Ground-beyond-the-scene spectral radiance.
    ground: Vec<f64>,
    /// Solar spectral irradiance at the surface, normal to the sun.
    sun: Vec<f64>,
    /// Per material: `ANGLE_ROWS × n` emissivities.
    eps: Vec<Vec<f64>>,
}

/// Planck's function on a temperature grid, all bands' wavelengths
/// concatenated.
#[derive(Debug, Clone)]
struct PlanckTable {
    t0: f64,
    nodes: usize,
    /// `nodes × total` values.
    values: Vec<f64>,
}

/// One band's tables for [`Shader::fast_primary`], single precision, the
/// quadrature weights (response × trapezoid) folded in where they multiply.
#[derive(Debug, Clone)]
struct FastBand {
    /// Number of wavelengths, rounded up to a multiple of [`LANES`]; every
    /// row below is padded with zeros to it (zero weight: the padding adds
    /// nothing).
    len: usize,
    /// Planck's function on [`Shader`]'s temperature table, `nodes × len`.
    planck: Vec<f32>,
    /// Quadrature weights × response, µm.
    w: Vec<f32>,
    /// Sky spectral radiance.
    sky: Vec<f32>,
    /// Solar spectral irradiance normal to the sun.
    sun: Vec<f32>,
    /// Per material: `ANGLE_ROWS × len` emissivities.
    eps: Vec<Vec<f32>>,
    /// Band radiance of a ray leaving the scene upward, per sky node
    /// ([`sky_node_cos`]), and downward (ground beyond), W·m⁻²·sr⁻¹.
    miss_sky: Vec<f64>,
    miss_ground: f64,
    /// Per material: when its emissivity is the same at every wavelength
    /// of the band (at each angle row), the `ANGLE_ROWS` values.
    grey: Vec<Option<Vec<f64>>>,
    /// Band integrals with the plain weights (no path).
    plain: Integrals,
}

impl FastBand {
    /// The band radiance of the sky at fraction `f` from node `k` to node
    /// `k + 1` (see [`sky_node`]).
    #[inline]
    fn miss_sky_at(&self, k: usize, f: f64) -> f64 {
        let (a, b) = (self.miss_sky[k], self.miss_sky[k + 1]);
        a + f * (b - a)
    }
}

/// Band integrals `Σ_λ q(λ)·X(λ)` of one band for one weighting `q`
/// (`w`, or `w·τ₂` at one range node): what a hit on a material that is
/// grey within the band needs, since ε and r then leave the sums.
#[derive(Debug, Clone)]
struct Integrals {
    /// Per node of the Planck table: `Σ q·B(λ, T_k)`.
    planck: Vec<f64>,
    /// `Σ q·L_sky`.
    sky: f64,
    /// `Σ q·E_s`.
    sun: f64,
}

impl Integrals {
    fn new(q: &[f64], t: &BandTables, table: &PlanckTable, total: usize) -> Self {
        let dot = |v: &[f64]| q.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
        let nl = t.band.len();
        Integrals {
            planck: table
                .values
                .chunks(total)
                .map(|node| dot(&node[t.start..t.start + nl]))
                .collect(),
            sky: dot(&t.sky),
            sun: dot(&t.sun),
        }
    }

    /// `Σ q·B(T)` at table node `k` + fraction `f`.
    #[inline]
    fn planck_at(&self, k: usize, f: f64) -> f64 {
        let p = &self.planck;
        p[k] + f * (p[k + 1] - p[k])
    }
}

/// The sensor path folded into the band weights, per range node of the
/// [`PathTables`]: `w·τ₂(λ)` per band and the band path radiance `Σ w·L_u`.
#[derive(Debug, Clone)]
struct FastPath {
    /// Per band, per node: `w·τ₂` on the band's grid.
    weighted_tau: Vec<Vec<Vec<f32>>>,
    /// Per band, per node: `Σ w·L_u`, W·m⁻²·sr⁻¹.
    path_radiance: Vec<Vec<f64>>,
    /// Per band, per node: the band integrals weighted by `w·τ₂`.
    integrals: Vec<Vec<Integrals>>,
}

/// Which primary hits [`Shader::fast_primary`] leaves to the spectral
/// reference ([`Shader::shade_primary`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FastMiss {
    /// The material is specular or transmissive and the bounce budget
    /// allows secondary rays.
    Secondary,
    /// A temperature lies off the tabulated Planck function.
    OffTable,
    /// The material reflects the sun through a glint lobe
    /// ([`super::glint`]).
    Glint,
}

impl PlanckTable {
    /// Node `k` and fraction of temperature `t` (K), when it lies on the
    /// table.
    fn position(&self, t: f64) -> Option<(usize, f64)> {
        let x = (t - self.t0) / PLANCK_TABLE_STEP_K;
        if self.nodes >= 2 && x >= 0.0 && x < (self.nodes - 1) as f64 {
            let k = x as usize;
            Some((k, x - k as f64))
        } else {
            None
        }
    }
}

/// Row `a0` of the 1° emissivity tables and the fraction toward `a0 + 1`
/// for the cosine of the view zenith `cos_view` (clamped to [0, 1]).
#[inline]
fn angle_row(cos_view: f32) -> (usize, f64) {
    let theta = acos_unit(cos_view.clamp(0.0, 1.0) as f64).to_degrees();
    // θ ≥ 0: truncation is the floor.
    let a0 = (theta as usize).min(ANGLE_ROWS - 2);
    (a0, theta - a0 as f64)
}

/// arccos x for 0 ≤ x ≤ 1, radians, to 3·10⁻⁸ (Abramowitz & Stegun,
/// *Handbook of Mathematical Functions*, eq. 4.4.46: 2·10⁻⁸ with its
/// ten-digit coefficients; 2·10⁻⁶° is far inside
/// the 1° emissivity rows).
#[inline]
fn acos_unit(x: f64) -> f64 {
    const A: [f64; 8] = [
        1.570_796_305_0,
        -0.214_598_801_6,
        0.088_978_987_4,
        -0.050_174_304_6,
        0.030_891_881_0,
        -0.017_088_125_6,
        0.006_670_090_1,
        -0.001_262_491_1,
    ];
    let p = A.iter().rev().fold(0.0, |acc, &a| acc * x + a);
    (1.0 - x).max(0.0).sqrt() * p
}

/// arccos x in degrees for 0 ≤ x ≤ 1, single precision: the polynomial of
/// [`acos_unit`] (Abramowitz & Stegun eq. 4.4.46) in f32, written so a loop
/// over many cosines vectorises. Error ≤ 2·10⁻⁵° (f32 rounding; tested),
/// far inside the 1° emissivity rows.
#[inline]
fn acos_deg(x: f32) -> f32 {
    const A: [f32; 8] = [
        // 1.570 796 305 0: in f32, π/2.
        std::f32::consts::FRAC_PI_2,
        -0.214_598_8,
        0.088_978_99,
        -0.050_174_303,
        0.030_891_88,
        -0.017_088_126,
        0.006_670_09,
        -0.001_262_491_1,
    ];
    // Estrin's scheme: a shorter dependency chain than Horner's.
    let x2 = x * x;
    let x4 = x2 * x2;
    let p01 = A[0] + A[1] * x;
    let p23 = A[2] + A[3] * x;
    let p45 = A[4] + A[5] * x;
    let p67 = A[6] + A[7] * x;
    let p = (p01 + p23 * x2) + (p45 + p67 * x2) * x4;
    (1.0 - x).max(0.0).sqrt() * p * (180.0 / std::f32::consts::PI)
}

/// What a hit on a facet needs in [`Shader::shade_fast`]'s grey path (its
/// material is grey in every band, so ε and r leave the band sums; it
/// spawns no secondary ray; its temperatures lie on the Planck table) and
/// the truth values of the pixel it is seen in: one cache line's half, the
/// one random access of a hit.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(32))]
struct GreyFacet {
    /// Material index; `u32::MAX`: the facet is not on the grey path.
    mi: u32,
    /// Object id.
    object: u32,
    /// Planck table nodes of the surface and background temperatures.
    kt: u16,
    kg: u16,
    /// Their fractions toward the next node.
    ft: f32,
    fg: f32,
    /// Sky shape factor F.
    big_f: f32,
    /// Diffuse-reflected sun on the lit face: `(1 − s)·cos σ·f_sun/π`
    /// (`f_sun = 1` for a facet whose hits trace a shadow ray).
    sd: f32,
    /// Sunlit fraction f_sun.
    sun_fraction: f32,
}

impl GreyFacet {
    const NONE: GreyFacet = GreyFacet {
        mi: u32::MAX,
        object: 0,
        kt: 0,
        kg: 0,
        ft: 0.0,
        fg: 0.0,
        big_f: 0.0,
        sd: 0.0,
        sun_fraction: 0.0,
    };
}

/// Relative size below which a hit's reflected sun is left to its facet's
/// sunlit fraction: where the diffusely reflected sun at full sun,
/// `(1 − s)·r_max·cos σ·Σw·E_s/π`, is below this fraction of the facet's
/// least emitted band radiance `ε_min·Σw·B(T)` in every band, a wrong
/// sunlit fraction changes the pixel by less than 10⁻³ of its radiance
/// (≈ 0.06 K at 300 K in 8–12 µm, ≈ 0.025 K in 3–5 µm: below a typical
/// NEdT), and no shadow ray is traced.
pub const SUN_RAY_THRESHOLD: f64 = 1e-3;

/// Per facet: whether a hit on it takes its own sun visibility (a shadow
/// ray from the hit point toward the sun) instead of the facet's sunlit
/// fraction. Facets of materials with a glint lobe (`glint_m2[mi] > 0`)
/// always do while the sun faces them; others when their sample points
/// disagree at the image time (`0 < f_sun < 1`: the facet's fraction is
/// right for no point of it) and the reflected sun matters
/// ([`SUN_RAY_THRESHOLD`]). A facet whose sample points agree keeps their
/// answer (a shadow edge between its sample points is taken as absent;
/// [`super::per_hit`] traces its own rays for facets large against the
/// pixel footprint).
fn sun_ray_facets(
    optics: &SceneOptics,
    conditions: &Conditions,
    bands: &[BandTables],
    fast: &[FastBand],
    table: &PlanckTable,
    glint_m2: &[f64],
) -> Vec<bool> {
    use rayon::prelude::*;
    let s = &conditions.surface;
    let sun_up = bands.iter().any(|t| t.sun.iter().any(|&e| e > 0.0));
    if !sun_up {
        return vec![false; s.len()];
    }
    // Per material, per band: (1 − s)·max r and min ε over angles and
    // wavelengths, and Σw·E_s/π.
    let bounds: Vec<Vec<(f64, f64, f64)>> = optics
        .materials
        .iter()
        .enumerate()
        .map(|(mi, m)| {
            let tr = m.transmissivity.clamp(0.0, 1.0);
            let sd = 1.0 - m.specular_fraction.clamp(0.0, 1.0);
            bands
                .iter()
                .map(|t| {
                    let lo = t.eps[mi].iter().fold(f64::INFINITY, |a, &e| a.min(e));
                    let r_max = (1.0 - lo - tr).max(0.0);
                    let sun = t.band.integrate(&t.sun) / std::f64::consts::PI;
                    (sd * r_max, lo, sun)
                })
                .collect()
        })
        .collect();
    (0..s.len())
        .into_par_iter()
        .map(|f| {
            let mi = optics.facet_material[f] as usize;
            if glint_m2[mi] > 0.0 {
                return true;
            }
            let (fs, cos) = (s.sun_fraction[f], s.cos_sun[f] as f64);
            if !(fs > 0.0 && fs < 1.0 && cos > 0.0) {
                return false;
            }
            let Some((k, x)) = table.position(s.temperature_k[f] as f64) else {
                return true;
            };
            bounds[mi].iter().zip(fast).any(|(&(r, eps, sun), fb)| {
                r * cos * sun >= SUN_RAY_THRESHOLD * eps * fb.plain.planck_at(k, x)
            })
        })
        .collect()
}

/// The per-facet records of the grey path and, for renders without a
/// sensor path, each grey facet's view-independent terms per band (built
/// once per image, in parallel): `[Σw·B(T), env, sd·Σw·E_s, t·env]` with
/// `env = F·Σw·L_sky + (1 − F)·Σw·B(T_bg)`, so that a hit needs only
/// `ε(θ)·x + r·(env + lit·w) + z`.
fn grey_facets(
    optics: &SceneOptics,
    conditions: &Conditions,
    options: &ShadeOptions,
    fast: &[FastBand],
    table: &PlanckTable,
    sun_ray: &[bool],
    glint_m2: &[f64],
) -> (Vec<GreyFacet>, Vec<[f32; 4]>) {
    use rayon::prelude::*;
    let s = &conditions.surface;
    let nb = fast.len();
    // Per material: on the grey path at all.
    let eligible: Vec<bool> = optics
        .materials
        .iter()
        .enumerate()
        .map(|(mi, m)| {
            let secondary =
                options.max_bounces > 0 && (m.specular_fraction > 0.0 || m.transmissivity > 0.0);
            nb > 0
                && !secondary
                && glint_m2[mi] <= 0.0
                && fast.iter().all(|fb| fb.grey[mi].is_some())
        })
        .collect();
    // Node indices are stored in 16 bits.
    let nodes_fit = table.nodes <= u16::MAX as usize;
    let mut grey = vec![GreyFacet::NONE; s.len()];
    let mut terms = vec![[0f32; 4]; s.len() * nb];
    grey.par_iter_mut()
        .zip(terms.par_chunks_mut(nb.max(1)))
        .enumerate()
        .for_each(|(f, (g, terms))| {
            let mi = optics.facet_material[f] as usize;
            // (A shape factor outside [0, 1] takes the general path, which
            // clamps it, so the truth layer keeps the value as given.)
            if !(eligible[mi] && nodes_fit && (0.0..=1.0).contains(&s.shape_factor[f])) {
                return;
            }
            let (Some((kt, ft)), Some((kg, fg))) = (
                table.position(s.temperature_k[f] as f64),
                table.position(s.background_k[f] as f64),
            ) else {
                return;
            };
            let m = &optics.materials[mi];
            // A facet whose hits trace their own shadow ray: the sun at full
            // strength, the hit's visibility applied per hit.
            let fs = if sun_ray[f] {
                1.0
            } else {
                (s.sun_fraction[f] as f64).clamp(0.0, 1.0)
            };
            let sun_front = (s.cos_sun[f] as f64).max(0.0) * fs / std::f64::consts::PI;
            let sd = (1.0 - m.specular_fraction.clamp(0.0, 1.0)) * sun_front;
            let big_f = s.shape_factor[f] as f64;
            let tr = m.transmissivity.clamp(0.0, 1.0);
            for (t, fb) in terms.iter_mut().zip(fast) {
                let p = &fb.plain;
                let env = big_f * p.sky + (1.0 - big_f) * p.planck_at(kg, fg);
                *t = [
                    p.planck_at(kt, ft) as f32,
                    env as f32,
                    (sd * p.sun) as f32,
                    (tr * env) as f32,
                ];
            }
            *g = GreyFacet {
                mi: mi as u32,
                object: optics.facet_object[f],
                kt: kt as u16,
                kg: kg as u16,
                ft: ft as f32,
                fg: fg as f32,
                big_f: s.shape_factor[f],
                sd: sd as f32,
                sun_fraction: s.sun_fraction[f],
            };
        });
    (grey, terms)
}

/// The band integrals of the grey path, single precision, flat: per band
/// the Planck integrals `Σ q_i·B(T_k)` of every temperature node `k` and
/// range node `i` (weights `q_i = w·τ₂(R_i)`; without a path two equal
/// nodes of the plain weights `w`), per range node the sky, sun and path
/// terms, and the grey emissivities of every material. Every table is
/// band-interleaved (the bands of one entry are adjacent), so one hit reads
/// each entry of all its bands from one place.
#[derive(Debug, Clone, Default)]
struct GreyTables {
    /// Bands.
    bands: usize,
    /// Path nodes (at least 2): height nodes × range nodes, node
    /// `a · range_nodes + i` ([`PathTables::node`]).
    nodes: usize,
    /// Range nodes per height node.
    range_nodes: usize,
    /// Heights of the height nodes above the ground datum, m (one node:
    /// no height interpolation).
    heights: Vec<f32>,
    /// `1 / (heights[a + 1] − heights[a])`.
    inv_height_spacing: Vec<f32>,
    /// Ranges of the nodes, m (empty without a path: every hit is at
    /// node 1, fraction 0).
    ranges: Vec<f32>,
    /// `1 / (ranges[i] − ranges[i − 1])`.
    inv_spacing: Vec<f32>,
    /// First guess of the node of range `r`: `√r · sqrt_scale` (exact for
    /// the quadratic spacing of [`PathTables`], refined for any spacing).
    sqrt_scale: f32,
    /// `Σ q_i·B(T_k)` of band `b` at `[(k · nodes + i) · bands + b]`.
    planck: Vec<f32>,
    /// Per range node `i`: `Σ q_i·L_sky`, `Σ q_i·E_s` and `Σ w·L_u` of band
    /// `b` at `[(3·i + 0, 1, 2) · bands + b]`.
    node: Vec<f32>,
    /// Grey emissivity at `[(material · ANGLE_ROWS + angle row) · bands + b]`
    /// (0 for materials not grey in every band: never read).
    eps: Vec<f32>,
    /// Per material: double-sided.
    double_sided: Vec<bool>,
    /// Per material: transmissivity t.
    tr: Vec<f32>,
}

impl GreyTables {
    /// Tables from each band's integrals and path radiance per range node
    /// (`nodes[b][i]`), at `ranges` (empty: no path).
    fn new(
        fast: &[FastBand],
        nodes: &[Vec<(&Integrals, f64)>],
        ranges: &[f64],
        heights: &[f64],
        materials: &[Material],
    ) -> Self {
        let nb = nodes.len();
        let r = nodes.first().map_or(2, Vec::len);
        let nt = nodes
            .first()
            .and_then(|b| b.first())
            .map_or(0, |(i, _)| i.planck.len());
        let mut planck = vec![0f32; nt * r * nb];
        let mut node = vec![0f32; 3 * r * nb];
        for (b, band) in nodes.iter().enumerate() {
            for (i, (ig, lu)) in band.iter().enumerate() {
                for (k, &x) in ig.planck.iter().enumerate() {
                    planck[(k * r + i) * nb + b] = x as f32;
                }
                node[3 * i * nb + b] = ig.sky as f32;
                node[(3 * i + 1) * nb + b] = ig.sun as f32;
                node[(3 * i + 2) * nb + b] = *lu as f32;
            }
        }
        let grey_everywhere = |mi: usize| fast.iter().all(|fb| fb.grey[mi].is_some());
        let mut eps = vec![0f32; materials.len() * ANGLE_ROWS * nb];
        for mi in (0..materials.len()).filter(|&mi| grey_everywhere(mi)) {
            for (b, fb) in fast.iter().enumerate() {
                let rows = fb.grey[mi].as_ref().expect("grey in every band");
                for (a, &e) in rows.iter().enumerate() {
                    eps[(mi * ANGLE_ROWS + a) * nb + b] = e as f32;
                }
            }
        }
        let ranges: Vec<f32> = ranges.iter().map(|&x| x as f32).collect();
        let inv_spacing = (0..ranges.len())
            .map(|i| {
                if i == 0 {
                    0.0
                } else {
                    1.0 / (ranges[i] - ranges[i - 1])
                }
            })
            .collect();
        let sqrt_scale = match ranges.last() {
            Some(&last) if last > 0.0 => (ranges.len() - 1) as f32 / last.sqrt(),
            _ => 0.0,
        };
        let heights: Vec<f32> = heights.iter().map(|&x| x as f32).collect();
        let inv_height_spacing = heights.windows(2).map(|w| 1.0 / (w[1] - w[0])).collect();
        GreyTables {
            bands: nb,
            nodes: r,
            range_nodes: if ranges.is_empty() { r } else { ranges.len() },
            heights,
            inv_height_spacing,
            ranges,
            inv_spacing,
            sqrt_scale,
            planck,
            node,
            eps,
            double_sided: materials.iter().map(|m| m.double_sided).collect(),
            tr: materials
                .iter()
                .map(|m| m.transmissivity.clamp(0.0, 1.0) as f32)
                .collect(),
        }
    }

    /// The range nodes bracketing range `r` (m): `(i, x)` with `r` at
    /// fraction `x` (clamped to [0, 1]) from node `i − 1` to node `i`, as
    /// [`PathTables::locate`]; `(1, 0)` without a path.
    #[inline(always)]
    fn locate(&self, r: f32) -> (usize, f32) {
        let x = &self.ranges;
        if x.len() < 2 {
            return (1, 0.0);
        }
        let last = x.len() - 1;
        let mut i = ((r.max(0.0).sqrt() * self.sqrt_scale) as usize + 1).min(last);
        while i < last && x[i] <= r {
            i += 1;
        }
        while i > 1 && x[i - 1] > r {
            i -= 1;
        }
        (i, ((r - x[i - 1]) * self.inv_spacing[i]).clamp(0.0, 1.0))
    }

    /// The height nodes bracketing height `z` (m): `(a, u)` with `z` at
    /// fraction `u` (clamped to [0, 1]) from node `a` to `a + 1`, as
    /// [`PathTables::locate_height`]; `(0, 0)` with one node.
    #[inline(always)]
    fn locate_height(&self, z: f32) -> (usize, f32) {
        let x = &self.heights;
        if x.len() < 2 {
            return (0, 0.0);
        }
        let mut a = 0;
        while a + 2 < x.len() && x[a + 1] <= z {
            a += 1;
        }
        (a, ((z - x[a]) * self.inv_height_spacing[a]).clamp(0.0, 1.0))
    }
}

/// Where [`Shader::shade_fast`] writes the truth values
/// ([`super::TRUTH_LAYERS`] order) of a batch's pixel-centre rays: rays
/// `first`, `first + stride`, … (one per value of each layer slice).
pub struct TruthOut<'a, 'b> {
    /// Index of the first pixel-centre ray in the batch.
    pub first: usize,
    /// Rays from one pixel-centre ray to the next (≥ 1).
    pub stride: usize,
    /// One slice per truth layer, a value per pixel-centre ray.
    pub layers: &'a mut [&'b mut [f32]],
}

impl TruthOut<'_, '_> {
    /// The ray index and column after column `col` (`usize::MAX` past
    /// the last column).
    #[inline]
    fn advance(&self, col: usize) -> (usize, usize) {
        let col = col + 1;
        if col < self.layers[0].len() {
            (self.first + col * self.stride.max(1), col)
        } else {
            (usize::MAX, col)
        }
    }
}

/// The truth values of up to [`TruthBlock::LEN`] consecutive pixels, per
/// layer, on their way to a [`TruthOut`]: written to the layers a block at
/// a time (one bounds check and one copy per layer and block instead of
/// one per value). Columns come in order from 0; column `c` is held at
/// `c % LEN`.
struct TruthBlock {
    /// Per layer, the block's values.
    values: [[f32; TruthBlock::LEN]; 6],
}

impl TruthBlock {
    const LEN: usize = 8;

    fn new() -> Self {
        TruthBlock {
            values: [[0.0; Self::LEN]; 6],
        }
    }

    /// Hold column `col`'s values; a full block goes to `t`.
    #[inline]
    fn push(&mut self, t: &mut TruthOut<'_, '_>, col: usize, v: [f32; 6]) {
        let j = col % Self::LEN;
        for (layer, v) in self.values.iter_mut().zip(v) {
            layer[j] = v;
        }
        if j == Self::LEN - 1 {
            let s = col + 1 - Self::LEN;
            for (layer, v) in t.layers.iter_mut().zip(&self.values) {
                layer[s..s + Self::LEN].copy_from_slice(v);
            }
        }
    }

    /// Write the values of a partial last block to `t`, `cols` columns
    /// having been pushed.
    fn flush(&self, t: &mut TruthOut<'_, '_>, cols: usize) {
        let n = cols % Self::LEN;
        let s = cols - n;
        for (layer, v) in t.layers.iter_mut().zip(&self.values) {
            layer[s..s + n].copy_from_slice(&v[..n]);
        }
    }
}

/// One band of [`Shader::grey_terms_pass`]: with `ε` interpolated between
/// the angle rows' `e0` and `e1` at fraction `ta`, and `r = max(1 − ε − t,
/// 0)`, the radiance `ε·x + r·(env + lit·w) + z` from the facet's terms
/// `[x, env, w, z]` ([`grey_facets`]).
#[inline(always)]
fn grey_terms_band(e0: f32, e1: f32, ta: f32, tr: f32, lit: bool, [x, env, w, z]: [f32; 4]) -> f32 {
    let eps = e0 + ta * (e1 - e0);
    let r = (1.0 - eps - tr).max(0.0);
    eps * x + r * (env + if lit { w } else { 0.0 }) + z
}

/// A hit on the grey path, as [`Shader::shade_fast`] gathers it.
#[derive(Debug, Clone, Copy)]
struct GreyHit {
    /// Ray index in the batch.
    ray: u32,
    /// Facet.
    facet: u32,
    /// `d·n_g` (its sign: which face is seen).
    dn: f32,
    /// `|d|²·|n_g|²`, then (second pass) the view zenith θ, degrees.
    theta: f32,
    /// Slant range, m.
    range: f32,
    /// Height of the hit above the ground datum (scene z), m.
    z: f32,
    /// The hit's own shadow ray found the sun blocked.
    shaded: bool,
}

/// A hit's sun visibility in [`SunRays::vis`]: its facet's sunlit fraction
/// (or its per-hit state's).
const VIS_FACET: u8 = 2;

/// The shadow rays of a batch's hits ([`Shader::sun_visibility`]).
#[derive(Debug, Default)]
struct SunRays {
    /// Per ray of the batch: 0 shaded, 1 lit, [`VIS_FACET`].
    vis: Vec<u8>,
    rays: Vec<Ray>,
    idx: Vec<u32>,
    occluded: Vec<bool>,
}

impl SunRays {
    /// The visibility of ray `i` as a sunlit fraction, if it traced one.
    #[inline]
    fn of(&self, i: usize) -> Option<f32> {
        match self.vis.get(i) {
            Some(0) => Some(0.0),
            Some(1) => Some(1.0),
            _ => None,
        }
    }
}

/// Working memory of [`Shader::shade_fast`], reused from call to call.
#[derive(Debug, Default)]
pub struct FastScratch {
    grey: Vec<GreyHit>,
    sun: SunRays,
    bands: Vec<f32>,
    /// Per ray of the batch: index into `states` (`u32::MAX`: the facet's
    /// state).
    state_of: Vec<u32>,
    /// Per-hit states of the batch's hits that have one.
    states: Vec<HitState>,
    /// `(facet, point)` of those hits.
    points: Vec<(u32, Vec3)>,
}

/// The radiance of rays: per ray, the spectral radiance on every band's
/// grid, bands concatenated.
pub struct Shader<'a> {
    tracer: &'a dyn Tracer,
    offsets: Vec<usize>,
    optics: &'a SceneOptics,
    conditions: &'a Conditions,
    options: ShadeOptions,
    bands: Vec<BandTables>,
    total: usize,
    wavelengths: Vec<f64>,
    planck: Planck,
    table: PlanckTable,
    path: Option<PathTables>,
    fast: Vec<FastBand>,
    fast_path: Option<FastPath>,
    /// Per facet: its record for the grey path of [`Shader::shade_fast`].
    grey: Vec<GreyFacet>,
    /// The grey path's band integrals (of the path once one is set).
    grey_tables: GreyTables,
    /// Without a sensor path: per grey facet, per band, the
    /// view-independent terms of [`grey_facets`] (empty once a path is
    /// set).
    grey_terms: Vec<[f32; 4]>,
    /// Angular size of a pixel, rad (0: unknown), for the per-hit rule.
    pixel_angle_rad: f32,
    /// Unit vector toward the sun while it lights the bands (`None`: no
    /// reflected sun).
    sun_dir: Option<Vec3>,
    /// Per facet: hits trace their own shadow ray ([`sun_ray_facets`]).
    sun_ray: Vec<bool>,
    /// Per material: the Beckmann `m²` of its glint lobe (0: no glint;
    /// [`super::glint`]).
    glint_m2: Vec<f64>,
}

impl std::fmt::Debug for Shader<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Shader")
            .field("tracer", &self.tracer.name())
            .field("bands", &self.bands.len())
            .field("spectrum_len", &self.total)
            .finish()
    }
}

impl<'a> Shader<'a> {
    /// Precompute the tables for `bands` under `conditions`.
    pub fn new(
        tracer: &'a dyn Tracer,
        geometry: &'a SceneGeometry,
        optics: &'a SceneOptics,
        conditions: &'a Conditions,
        bands: &[Band],
        options: ShadeOptions,
    ) -> crate::Result<Self> {
        let facets = geometry.facet_count();
        conditions.surface.validate(facets)?;
        if optics.facet_material.len() != facets || optics.facet_object.len() != facets {
            return Err(crate::Error::invalid(
                "scene optics",
                format!(
                    "{} materials / {} objects per facet: expected {facets}",
                    optics.facet_material.len(),
                    optics.facet_object.len()
                ),
            ));
        }
        if let Some(m) = optics
            .facet_material
            .iter()
            .find(|&&m| m as usize >= optics.materials.len())
        {
            return Err(crate::Error::invalid(
                "scene optics",
                format!("material index {m}: expected < {}", optics.materials.len()),
            ));
        }
        let planck = bands.first().map(|b| *b.planck()).unwrap_or_default();
        let emissivities = optics
            .materials
            .iter()
            .map(Emissivity::from_material)
            .collect::<crate::Result<Vec<_>>>()?;
        let mut tables = Vec::new();
        let mut wavelengths = Vec::new();
        for band in bands {
            let wl = band.wavelengths_um();
            let (sky, sky_dir) = match &conditions.sky {
                Sky::Blackbody { temperature_k } => {
                    let sky: Vec<f64> = wl
                        .iter()
                        .map(|&l| planck.radiance(l, *temperature_k))
                        .collect();
                    (sky.clone(), vec![sky; SKY_NODES])
                }
                Sky::Atmosphere(c) => {
                    let zeniths: Vec<f64> = (0..SKY_NODES)
                        .map(|k| sky_node_cos(k).clamp(-1.0, 1.0).acos().to_degrees())
                        .collect();
                    (
                        conditions.atmosphere.sky_radiance(c, band.grid())?,
                        conditions
                            .atmosphere
                            .sky_radiances_toward(c, &zeniths, band.grid())?,
                    )
                }
            };
            let ground = wl
                .iter()
                .map(|&l| planck.radiance(l, conditions.ground_temperature_k))
                .collect();
            let sun = match conditions.sun {
                Some(s) if s.direction.z > 0.0 => {
                    surface_solar_spectrum(&conditions.atmosphere, &planck, &s, band.grid())?
                }
                _ => vec![0.0; wl.len()],
            };
            let eps = emissivities
                .iter()
                .map(|e| {
                    let mut rows = Vec::with_capacity(ANGLE_ROWS * wl.len());
                    for a in 0..ANGLE_ROWS {
                        rows.extend(wl.iter().map(|&l| e.eval(l, a as f64)));
                    }
                    rows
                })
                .collect();
            tables.push(BandTables {
                band: band.clone(),
                start: wavelengths.len(),
                sky,
                sky_dir,
                ground,
                sun,
                eps,
            });
            wavelengths.extend_from_slice(wl);
        }
        let total = wavelengths.len();
        // Planck table over the scene's temperature range.
        let s = &conditions.surface;
        let (lo, hi) = s
            .temperature_k
            .iter()
            .chain(&s.background_k)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| {
                (lo.min(t as f64), hi.max(t as f64))
            });
        // Per-hit temperatures may lie beyond the facets'.
        let (lo, hi) = match &conditions.per_hit {
            Some(ph) => {
                let (a, b) = ph.temperature_bounds(&s.temperature_k);
                (lo.min(a as f64), hi.max(b as f64))
            }
            None => (lo, hi),
        };
        let table = if lo.is_finite() && total > 0 {
            let t0 = (lo / PLANCK_TABLE_STEP_K).floor() * PLANCK_TABLE_STEP_K;
            let nodes =
                (((hi - t0) / PLANCK_TABLE_STEP_K).ceil() as usize + 2).min(PLANCK_TABLE_MAX_NODES);
            let mut values = Vec::with_capacity(nodes * total);
            for k in 0..nodes {
                let t = t0 + k as f64 * PLANCK_TABLE_STEP_K;
                values.extend(wavelengths.iter().map(|&l| planck.radiance(l, t)));
            }
            PlanckTable { t0, nodes, values }
        } else {
            PlanckTable {
                t0: 0.0,
                nodes: 0,
                values: Vec::new(),
            }
        };
        let fast: Vec<FastBand> = tables
            .iter()
            .map(|t| {
                let nl = t.band.len();
                let len = nl.div_ceil(LANES) * LANES;
                // Rows of `nl` values, each padded with zeros to `len`.
                let pad = |v: &[f64]| -> Vec<f32> {
                    v.chunks(nl)
                        .flat_map(|r| {
                            r.iter()
                                .map(|&x| x as f32)
                                .chain(std::iter::repeat_n(0.0, len - nl))
                        })
                        .collect()
                };
                let planck: Vec<f64> = table
                    .values
                    .chunks(total)
                    .flat_map(|node| &node[t.start..t.start + nl])
                    .copied()
                    .collect();
                let grey = t
                    .eps
                    .iter()
                    .map(|e| {
                        let rows: Vec<&[f64]> = e.chunks(nl).collect();
                        rows.iter()
                            .all(|r| r.iter().all(|&x| x == r[0]))
                            .then(|| rows.iter().map(|r| r[0]).collect())
                    })
                    .collect();
                FastBand {
                    len,
                    grey,
                    plain: Integrals::new(t.band.weights_um(), t, &table, total),
                    planck: pad(&planck),
                    w: pad(t.band.weights_um()),
                    sky: pad(&t.sky),
                    sun: pad(&t.sun),
                    eps: t.eps.iter().map(|e| pad(e)).collect(),
                    miss_sky: t.sky_dir.iter().map(|v| t.band.integrate(v)).collect(),
                    miss_ground: t.band.integrate(&t.ground),
                }
            })
            .collect();
        let sun_dir = conditions
            .sun
            .map(|s| s.direction.normalize_or_zero())
            .filter(|_| tables.iter().any(|t| t.sun.iter().any(|&e| e > 0.0)));
        let glint_m2: Vec<f64> = optics
            .materials
            .iter()
            .map(|m| {
                if sun_dir.is_some() && m.specular_fraction > 0.0 {
                    super::glint::lobe_slope_variance(m, conditions.wind_speed_m_s)
                } else {
                    0.0
                }
            })
            .collect();
        let sun_ray = sun_ray_facets(optics, conditions, &tables, &fast, &table, &glint_m2);
        let (grey, grey_terms) = grey_facets(
            optics, conditions, &options, &fast, &table, &sun_ray, &glint_m2,
        );
        let plain: Vec<Vec<(&Integrals, f64)>> = fast
            .iter()
            .map(|fb| vec![(&fb.plain, 0.0), (&fb.plain, 0.0)])
            .collect();
        let grey_tables = GreyTables::new(&fast, &plain, &[], &[], &optics.materials);
        Ok(Shader {
            grey,
            grey_tables,
            grey_terms,
            tracer,
            offsets: geometry.facet_offsets(),
            optics,
            conditions,
            options,
            bands: tables,
            total,
            wavelengths,
            planck,
            table,
            path: None,
            fast,
            fast_path: None,
            pixel_angle_rad: 0.0,
            sun_dir,
            sun_ray,
            glint_m2,
        })
    }

    /// The same shader applying the sensor path's τ₂ and L_u to primary
    /// hits ([`Shader::shade_primary`], [`Shader::fast_primary`]); `None`:
    /// no atmosphere.
    pub fn with_path(mut self, path: Option<PathTables>) -> Self {
        self.fast_path = path.as_ref().map(|p| FastPath {
            weighted_tau: self
                .bands
                .iter()
                .enumerate()
                .map(|(b, t)| {
                    p.bands[b]
                        .iter()
                        .map(|(tau, _)| {
                            let len = t.band.len().div_ceil(LANES) * LANES;
                            let mut v: Vec<f32> = t
                                .band
                                .weights_um()
                                .iter()
                                .zip(tau)
                                .map(|(w, x)| (w * x) as f32)
                                .collect();
                            v.resize(len, 0.0);
                            v
                        })
                        .collect()
                })
                .collect(),
            path_radiance: self
                .bands
                .iter()
                .enumerate()
                .map(|(b, t)| {
                    p.bands[b]
                        .iter()
                        .map(|(_, lu)| t.band.integrate(lu))
                        .collect()
                })
                .collect(),
            integrals: self
                .bands
                .iter()
                .enumerate()
                .map(|(b, t)| {
                    p.bands[b]
                        .iter()
                        .map(|(tau, _)| {
                            let q: Vec<f64> = t
                                .band
                                .weights_um()
                                .iter()
                                .zip(tau)
                                .map(|(w, x)| w * x)
                                .collect();
                            Integrals::new(&q, t, &self.table, self.total)
                        })
                        .collect()
                })
                .collect(),
        });
        if let (Some(p), Some(fp)) = (&path, &self.fast_path) {
            let nodes: Vec<Vec<(&Integrals, f64)>> = fp
                .integrals
                .iter()
                .zip(&fp.path_radiance)
                .map(|(ig, lu)| ig.iter().zip(lu.iter().copied()).collect())
                .collect();
            self.grey_tables = GreyTables::new(
                &self.fast,
                &nodes,
                &p.ranges_m,
                &p.heights_m,
                &self.optics.materials,
            );
            // The per-facet terms hold for the plain weights only.
            self.grey_terms = Vec::new();
        }
        self.path = path;
        self
    }

    /// The same shader with the angular size of a pixel (rad), for the
    /// per-hit rule's pixel footprint ([`super::per_hit`]).
    pub fn with_pixel_angle(mut self, rad: f64) -> Self {
        self.pixel_angle_rad = rad as f32;
        self
    }

    /// The per-hit states of the hits of a batch whose facets want one
    /// into `sc` (`state_of`, `states`).
    fn per_hit_states(&self, rays: &[Ray], hits: &[Option<Hit>], sc: &mut FastScratch) {
        sc.state_of.clear();
        sc.states.clear();
        let Some(ph) = &self.conditions.per_hit else {
            return;
        };
        sc.state_of.resize(rays.len(), u32::MAX);
        sc.points.clear();
        for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
            let Some(h) = hit else { continue };
            let f = self.facet_of(h);
            if ph.wants(f, h.t * ray.dir.length(), self.pixel_angle_rad) {
                sc.state_of[i] = sc.points.len() as u32;
                sc.points.push((f as u32, ray.origin + ray.dir * h.t));
            }
        }
        ph.states(self.tracer, &sc.points, &mut sc.states);
    }

    /// The per-hit state of one hit, if its facet wants one.
    fn hit_state(&self, ray: &Ray, h: &Hit) -> Option<HitState> {
        let ph = self.conditions.per_hit.as_ref()?;
        let f = self.facet_of(h);
        if !ph.wants(f, h.t * ray.dir.length(), self.pixel_angle_rad) {
            return None;
        }
        let mut out = Vec::with_capacity(1);
        ph.states(
            self.tracer,
            &[(f as u32, ray.origin + ray.dir * h.t)],
            &mut out,
        );
        out.pop()
    }

    /// The sun visibility of a batch's hits into `sr.vis`: one shadow ray
    /// toward the sun from each hit on a facet of [`sun_ray_facets`] whose
    /// seen face the sun lights (and which has no per-hit state, `has_state`:
    /// that state carries its own), traced together (parallel rays from
    /// neighbouring points: [`Coherence::Coherent`]); the origin is lifted
    /// off the surface by [`ShadeOptions::offset_m`] on the sun's side.
    fn sun_visibility(
        &self,
        rays: &[Ray],
        hits: &[Option<Hit>],
        has_state: impl Fn(usize) -> bool,
        sr: &mut SunRays,
    ) {
        sr.vis.clear();
        sr.rays.clear();
        sr.idx.clear();
        let Some(sun) = self.sun_dir else { return };
        sr.vis.resize(rays.len(), VIS_FACET);
        let s = &self.conditions.surface;
        for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
            let Some(h) = hit else { continue };
            let f = self.facet_of(h);
            if !self.sun_ray[f] || has_state(i) {
                continue;
            }
            let mi = self.optics.facet_material[f] as usize;
            let dn = h.ng.dot(ray.dir);
            let diffuse_lit =
                s.cos_sun[f] > 0.0 && (dn < 0.0 || self.optics.materials[mi].double_sided);
            let sn = h.ng.dot(sun);
            // The glint lobe of the seen face needs the sun on its side.
            let glint_lit = self.glint_m2[mi] > 0.0 && dn * sn < 0.0;
            if !(diffuse_lit || glint_lit) {
                continue;
            }
            let n = h.ng.normalize_or(Vec3::Z);
            let side = if sn >= 0.0 { 1.0 } else { -1.0 };
            let p = ray.origin + ray.dir * h.t;
            sr.rays
                .push(Ray::new(p + n * (side * self.options.offset_m), sun));
            sr.idx.push(i as u32);
        }
        if sr.rays.is_empty() {
            return;
        }
        sr.occluded.clear();
        sr.occluded.resize(sr.rays.len(), false);
        self.tracer
            .occluded(&sr.rays, Coherence::Coherent, &mut sr.occluded);
        for (&i, &o) in sr.idx.iter().zip(&sr.occluded) {
            sr.vis[i as usize] = u8::from(!o);
        }
    }

    /// Whether a hit on facet `f` spawns secondary rays (specular or
    /// transmissive material, bounce budget left).
    pub fn spawns_secondary(&self, f: usize) -> bool {
        let m = &self.optics.materials[self.optics.facet_material[f] as usize];
        self.options.max_bounces > 0 && (m.specular_fraction > 0.0 || m.transmissivity > 0.0)
    }

    /// Band radiance (W·m⁻²·sr⁻¹, one per band into `out`) at the sensor of
    /// a primary ray that leaves the scene: the sky above the horizon, the
    /// ground beyond below it (no path, as [`Shader::shade_primary`]).
    pub fn fast_miss(&self, ray: &Ray, out: &mut [f32]) {
        let (k, f) = sky_node(ray.dir.z as f64, ray.dir.length() as f64);
        for (o, fb) in out.iter_mut().zip(&self.fast) {
            *o = if ray.dir.z >= 0.0 {
                fb.miss_sky_at(k, f)
            } else {
                fb.miss_ground
            } as f32;
        }
    }

    /// Band radiances at the sensor (W·m⁻²·sr⁻¹, one per band into `out`)
    /// of the primary ray `ray` (unit direction) hitting `h`, without the
    /// spectral intermediate of [`Shader::shade_primary`]: per band one
    /// fused pass over the grid of
    ///
    /// ```text
    /// Σ_λ w·τ₂(λ, R) · [ε·B(T) + r·(env + (1 − s)·E_s·cos σ·f_sun/π) + t·env]
    ///   + Σ_λ w·L_u(λ, R),      r = max(1 − ε − t, 0),
    ///   env = F·L_sky + (1 − F)·B(T_bg)
    /// ```
    ///
    /// (the big equation of the module docs with `L_spec = L_behind = env`,
    /// which is what the reference evaluates for a hit without secondary
    /// rays), with the same interpolations as the reference — ε linear in
    /// the 1° angle rows, B linear on the Planck table, τ₂ and L_u linear
    /// in range — so the two agree to single-precision rounding
    /// (~10⁻⁶ relative; `tests/render.rs` checks ≤ 10⁻⁵). The band weights
    /// `w` (response × trapezoid) are folded into `w·τ₂` and `Σ w·L_u`
    /// per range node, which is exact because both are linear in the range
    /// interpolation. Returns `Err` (and leaves `out` alone) for hits that
    /// need the reference: secondary rays, or temperatures off the table.
    pub fn fast_primary(&self, ray: &Ray, h: &Hit, out: &mut [f32]) -> Result<(), FastMiss> {
        let mut slow = Vec::new();
        let mut o = vec![0f32; self.fast.len()];
        self.shade_fast(
            std::slice::from_ref(ray),
            &[Some(*h)],
            &mut o,
            &mut slow,
            &mut FastScratch::default(),
            None,
        );
        if slow.is_empty() {
            out.copy_from_slice(&o);
            Ok(())
        } else if self.spawns_secondary(self.facet_of(h)) {
            Err(FastMiss::Secondary)
        } else if self.glint_m2[self.optics.facet_material[self.facet_of(h)] as usize] > 0.0 {
            Err(FastMiss::Glint)
        } else {
            Err(FastMiss::OffTable)
        }
    }

    /// [`Shader::fast_primary`] and [`Shader::fast_miss`] for a batch of
    /// primary rays (unit directions) and their hits: band radiances into
    /// `out` band-major (`out[b · n + i]` for ray `i` of `n`), the indices
    /// of the hits left to the spectral reference appended to `slow`
    /// (their `out` values untouched).
    ///
    /// Hits on materials grey in every band (without secondary rays, on
    /// the Planck table) take the grey path in three passes over the batch
    /// — per hit the facet's record, `d·n_g` and the range; the view
    /// zeniths of all of them at once (a loop that vectorises); then per
    /// band `ε(θ)·ΣqB(T) + r·(env + sd·Σq·E_s) + t·env + Σw·L_u` from
    /// [`GreyTables`], with `q` the range-interpolated path weights — so
    /// that no per-hit latency chain stalls the others. Other hits take
    /// the per-hit fused spectral sums.
    ///
    /// With `truth`, the truth values of the pixel-centre rays it names are
    /// written as the batch is read ([`Shader::truth_of`]).
    pub fn shade_fast(
        &self,
        rays: &[Ray],
        hits: &[Option<Hit>],
        out: &mut [f32],
        slow: &mut Vec<usize>,
        sc: &mut FastScratch,
        mut truth: Option<TruthOut<'_, '_>>,
    ) {
        let n = rays.len();
        let nb = self.fast.len();
        debug_assert!(hits.len() == n && out.len() >= nb * n);
        sc.grey.clear();
        sc.bands.resize(nb, 0.0);
        self.per_hit_states(rays, hits, sc);
        {
            let state_of = &sc.state_of;
            let has_state = |i: usize| state_of.get(i).is_some_and(|&k| k != u32::MAX);
            self.sun_visibility(rays, hits, has_state, &mut sc.sun);
        }
        // The next pixel-centre ray and its column.
        let (mut next, mut col) = match &truth {
            Some(t) if !t.layers.is_empty() && !t.layers[0].is_empty() => (t.first, 0usize),
            _ => (usize::MAX, 0),
        };
        let mut block = TruthBlock::new();
        for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
            let centre = i == next;
            let Some(h) = hit else {
                let up = ray.dir.z >= 0.0;
                let (k, f) = sky_node(ray.dir.z as f64, ray.dir.length() as f64);
                for (b, fb) in self.fast.iter().enumerate() {
                    out[b * n + i] = if up {
                        fb.miss_sky_at(k, f)
                    } else {
                        fb.miss_ground
                    } as f32;
                }
                if let (true, Some(t)) = (centre, &mut truth) {
                    block.push(t, col, super::MISS_TRUTH);
                    (next, col) = t.advance(col);
                }
                continue;
            };
            let f = self.facet_of(h);
            let range = h.t * ray.dir.length();
            let state = sc
                .state_of
                .get(i)
                .filter(|&&k| k != u32::MAX)
                .map(|&k| sc.states[k as usize]);
            let vis = sc.sun.of(i);
            if let (true, Some(t)) = (centre, &mut truth) {
                let mut v = self.truth_of_hit(f, range, state);
                if let Some(x) = vis {
                    v[4] = x;
                }
                block.push(t, col, v);
                (next, col) = t.advance(col);
            }
            if let Some(st) = state {
                if self
                    .fast_general(ray, h, Some(st), None, &mut sc.bands)
                    .is_err()
                {
                    slow.push(i);
                    continue;
                }
                for (b, &v) in sc.bands.iter().enumerate() {
                    out[b * n + i] = v;
                }
                continue;
            }
            let n2 = ray.dir.length_squared() * h.ng.length_squared();
            if self.grey[f].mi != u32::MAX && n2 > 0.0 && n2.is_finite() {
                sc.grey.push(GreyHit {
                    ray: i as u32,
                    facet: f as u32,
                    dn: ray.dir.dot(h.ng),
                    theta: n2,
                    range,
                    z: ray.origin.z + ray.dir.z * h.t,
                    shaded: vis == Some(0.0),
                });
                continue;
            }
            if self.fast_general(ray, h, None, vis, &mut sc.bands).is_err() {
                slow.push(i);
                continue;
            }
            for (b, &v) in sc.bands.iter().enumerate() {
                out[b * n + i] = v;
            }
        }
        if let Some(t) = &mut truth {
            // `col`: the columns written.
            block.flush(t, col);
        }
        // View zeniths, degrees: cos θ = |d·n_g| / (|d|·|n_g|).
        for g in &mut sc.grey {
            g.theta = acos_deg((g.dn.abs() / g.theta.sqrt()).min(1.0));
        }
        if self.grey_terms.is_empty() {
            self.grey_pass(sc, n, out);
        } else {
            self.grey_terms_pass(sc, n, out);
        }
    }

    /// The grey path's last pass without a sensor path: per band
    /// `ε(θ)·x + r·(env + lit·w) + z` from the facet's precomputed terms
    /// ([`grey_facets`]), `r = max(1 − ε − t, 0)`. One and two bands (the
    /// common cases) have their own loops with the band count known.
    fn grey_terms_pass(&self, sc: &FastScratch, n: usize, out: &mut [f32]) {
        match self.grey_tables.bands {
            1 => self.grey_terms_pass_n::<1>(sc, n, out),
            2 => self.grey_terms_pass_n::<2>(sc, n, out),
            _ => self.grey_terms_pass_any(sc, n, out),
        }
    }

    /// A gathered hit's place in the grey tables: its facet's material
    /// `mi`, the emissivity angle row `a0` and the fraction `ta` toward
    /// `a0 + 1`, and whether its sunlit face is seen.
    #[inline(always)]
    fn grey_hit_rows(&self, hit: &GreyHit) -> (usize, usize, f32, bool) {
        let mi = self.grey[hit.facet as usize].mi as usize;
        let th = hit.theta;
        // θ ≥ 0: truncation is the floor.
        let a0 = (th as usize).min(ANGLE_ROWS - 2);
        let lit = (hit.dn < 0.0 || self.grey_tables.double_sided[mi]) && !hit.shaded;
        (mi, a0, th - a0 as f32, lit)
    }

    /// [`Shader::grey_terms_pass`] with `NB` bands.
    fn grey_terms_pass_n<const NB: usize>(&self, sc: &FastScratch, n: usize, out: &mut [f32]) {
        let gt = &self.grey_tables;
        debug_assert_eq!(gt.bands, NB);
        let (out, _) = out.split_at_mut(NB * n);
        for hit in &sc.grey {
            let (i, f) = (hit.ray as usize, hit.facet as usize);
            let (mi, a0, ta, lit) = self.grey_hit_rows(hit);
            let tr = gt.tr[mi];
            // Angle rows a0 and a0 + 1, and the terms: one bounds check
            // each (the lengths are constants).
            let row = (mi * ANGLE_ROWS + a0) * NB;
            let e0: &[f32; NB] = (&gt.eps[row..][..NB]).try_into().expect("angle row");
            let e1: &[f32; NB] = (&gt.eps[row + NB..][..NB])
                .try_into()
                .expect("next angle row");
            let t: &[[f32; 4]; NB] = (&self.grey_terms[f * NB..][..NB])
                .try_into()
                .expect("one facet's terms");
            for b in 0..NB {
                out[b * n + i] = grey_terms_band(e0[b], e1[b], ta, tr, lit, t[b]);
            }
        }
    }

    /// [`Shader::grey_terms_pass`] with any number of bands.
    fn grey_terms_pass_any(&self, sc: &FastScratch, n: usize, out: &mut [f32]) {
        let gt = &self.grey_tables;
        let nb = gt.bands;
        for hit in &sc.grey {
            let (i, f) = (hit.ray as usize, hit.facet as usize);
            let (mi, a0, ta, lit) = self.grey_hit_rows(hit);
            let tr = gt.tr[mi];
            let e = &gt.eps[(mi * ANGLE_ROWS + a0) * nb..][..2 * nb];
            let terms = &self.grey_terms[f * nb..][..nb];
            for (b, &t) in terms.iter().enumerate() {
                out[b * n + i] = grey_terms_band(e[b], e[nb + b], ta, tr, lit, t);
            }
        }
    }

    /// The grey path's last pass over every hit gathered in `sc` (see
    /// [`Shader::shade_fast`]): per band
    /// `ε(θ)·ΣqB(T) + r·(env + sd·Σq·E_s) + t·env + Σw·L_u`, with
    /// `env = F·Σq·L_sky + (1 − F)·ΣqB(T_bg)`, `r = max(1 − ε − t, 0)`, the
    /// integrals bilinear in temperature then range as in the reference.
    /// The bands of one entry are adjacent in [`GreyTables`]: the offsets
    /// are computed once per hit, then each band is a few loads.
    fn grey_pass(&self, sc: &FastScratch, n: usize, out: &mut [f32]) {
        let gt = &self.grey_tables;
        let (nb, nodes) = (gt.bands, gt.nodes);
        let (pl, nd, ep) = (&gt.planck[..], &gt.node[..], &gt.eps[..]);
        // Next height node: `range_nodes` nodes on (none with one height).
        let two = gt.heights.len() >= 2;
        let hstep = if two { gt.range_nodes } else { 0 };
        for hit in &sc.grey {
            let i = hit.ray as usize;
            let g = &self.grey[hit.facet as usize];
            let mi = g.mi as usize;
            let th = hit.theta;
            // θ ≥ 0: truncation is the floor.
            let a0 = (th as usize).min(ANGLE_ROWS - 2);
            let ta = th - a0 as f32;
            let (ri, rx) = gt.locate(hit.range);
            let (ai, ax) = gt.locate_height(hit.z);
            let sd = if (hit.dn < 0.0 || gt.double_sided[mi]) && !hit.shaded {
                g.sd
            } else {
                0.0
            };
            let tr = gt.tr[mi];
            let (big_f, one_f) = (g.big_f, 1.0 - g.big_f);
            let (ft, fg) = (g.ft, g.fg);
            // Entry offsets: emissivity at angle rows a0, a0 + 1 (+nb);
            // Planck rows k, k + 1 (+nodes·nb) at range nodes ri − 1, ri
            // (+nb) of height node ai (+hstep·nb: ai + 1); sky, sun, path
            // at node ri − 1 (+0, +nb, +2nb) and ri (+3nb).
            let e = (mi * ANGLE_ROWS + a0) * nb;
            let (kt, kg) = (g.kt as usize, g.kg as usize);
            let n0 = ai * gt.range_nodes + ri - 1;
            let t0 = (kt * nodes + n0) * nb;
            let g0 = (kg * nodes + n0) * nb;
            let up = nodes * nb;
            let q = 3 * n0 * nb;
            let (hp, hq) = (hstep * nb, 3 * hstep * nb);
            for b in 0..nb {
                let eps = ep[e + b] + ta * (ep[e + nb + b] - ep[e + b]);
                // Temperature first, then range, then height, as the
                // reference.
                let at = |h: usize, hq: usize| {
                    grey_node(pl, nd, [up, nb, b], [t0 + h, g0 + h, q + hq], [ft, fg, rx])
                };
                let [mut bt, mut bg, mut sky, mut sun, mut lu] = at(0, 0);
                if two {
                    let [bt1, bg1, sky1, sun1, lu1] = at(hp, hq);
                    bt += ax * (bt1 - bt);
                    bg += ax * (bg1 - bg);
                    sky += ax * (sky1 - sky);
                    sun += ax * (sun1 - sun);
                    lu += ax * (lu1 - lu);
                }
                let r = (1.0 - eps - tr).max(0.0);
                let env = big_f * sky + one_f * bg;
                out[b * n + i] = eps * bt + r * (env + sd * sun) + tr * env + lu;
            }
        }
    }

    /// The truth values ([`super::TRUTH_LAYERS`] order) of the pixel whose
    /// centre ray `ray` hits `h`: surface temperature, material id, object
    /// id, shape factor, sun fraction, depth (m). Read from the facet's
    /// grey-path record where it has one (the temperature recovered from
    /// its Planck table node and fraction: within 2·10⁻⁹ K in f64, so the
    /// same f32), from the per-facet arrays otherwise.
    /// The sun fraction is the hit's own where it has a per-hit state or
    /// traces a shadow ray ([`sun_ray_facets`]).
    pub fn truth_of(&self, ray: &Ray, h: &Hit) -> [f32; 6] {
        let state = self.hit_state(ray, h);
        let mut v = self.truth_of_hit(self.facet_of(h), h.t * ray.dir.length(), state);
        let mut sun = SunRays::default();
        let hit = [Some(*h)];
        self.sun_visibility(
            std::slice::from_ref(ray),
            &hit,
            |_| state.is_some(),
            &mut sun,
        );
        if let Some(x) = sun.of(0) {
            v[4] = x;
        }
        v
    }

    /// [`Shader::truth_of`] of a hit on facet `f` at range `d` (m) with
    /// its own `state` (per-hit temperatures) or its facet's.
    #[inline]
    fn truth_of_hit(&self, f: usize, d: f32, state: Option<HitState>) -> [f32; 6] {
        let mut v = self.truth_of_facet(f, d);
        if let Some(st) = state {
            v[0] = self.conditions.surface.temperature_k[f] + st.dt_k;
            v[4] = st.sun_fraction;
        }
        v
    }

    /// [`Shader::truth_of`] of a hit on facet `f` at range `d` (m).
    #[inline]
    fn truth_of_facet(&self, f: usize, d: f32) -> [f32; 6] {
        let depth = if d.is_finite() { d } else { 0.0 };
        let g = &self.grey[f];
        if g.mi != u32::MAX {
            let t = self.table.t0 + (g.kt as f64 + g.ft as f64) * PLANCK_TABLE_STEP_K;
            return [
                t as f32,
                self.optics.materials[g.mi as usize].id as f32,
                g.object as f32,
                g.big_f,
                g.sun_fraction,
                depth,
            ];
        }
        let s = &self.conditions.surface;
        [
            s.temperature_k[f],
            self.material_id_of(f),
            self.optics.facet_object[f] as f32,
            s.shape_factor[f],
            s.sun_fraction[f],
            depth,
        ]
    }

    /// [`Shader::fast_primary`] of a hit off the grey path: per band the
    /// grey integrals or the fused spectral sum.
    /// `vis`: the hit's own sun visibility (its shadow ray), if traced.
    fn fast_general(
        &self,
        ray: &Ray,
        h: &Hit,
        state: Option<HitState>,
        vis: Option<f32>,
        out: &mut [f32],
    ) -> Result<(), FastMiss> {
        let f = self.facet_of(h);
        if self.spawns_secondary(f) {
            return Err(FastMiss::Secondary);
        }
        let mi = self.optics.facet_material[f] as usize;
        if self.glint_m2[mi] > 0.0 {
            return Err(FastMiss::Glint);
        }
        let s = &self.conditions.surface;
        let (t_hit, sun_fraction) = hit_temperature(s, f, state);
        let sun_fraction = vis.unwrap_or(sun_fraction);
        let (kt, ft) = self.table_position(t_hit).ok_or(FastMiss::OffTable)?;
        let (kg, fg) = self
            .table_position(s.background_k[f] as f64)
            .ok_or(FastMiss::OffTable)?;
        let m = &self.optics.materials[mi];
        let (_, nrm, d) = self.hit_frame(ray, h);
        let (a0, ta) = angle_row(-d.dot(nrm));
        let big_f = (s.shape_factor[f] as f64).clamp(0.0, 1.0);
        let front = h.ng.dot(d) < 0.0;
        let sun_w = if front || m.double_sided {
            (s.cos_sun[f] as f64).max(0.0) * (sun_fraction as f64).clamp(0.0, 1.0)
                / std::f64::consts::PI
        } else {
            0.0
        };
        let sd = (1.0 - m.specular_fraction.clamp(0.0, 1.0)) * sun_w;
        let tr = m.transmissivity.clamp(0.0, 1.0);
        // The path nodes: range node i − 1 → i at fraction x, of height
        // node a (and a + 1 at fraction u when the table has two or more).
        let node = match (&self.path, &self.fast_path) {
            (Some(p), Some(_)) => {
                let (i, x) = p.locate((h.t * ray.dir.length()) as f64);
                let (a, u) = p.locate_height((ray.origin.z + ray.dir.z * h.t) as f64);
                let next = (p.heights_m.len() >= 2).then(|| p.node(a + 1, i - 1));
                Some((p.node(a, i - 1), x, next, u))
            }
            _ => None,
        };
        for (b, fb) in self.fast.iter().enumerate() {
            if let Some(g) = &fb.grey[mi] {
                // ε and r leave the sums: Σ q·ε·B(T) = ε·Σ q·B(T), …
                let eps = g[a0] + ta * (g[a0 + 1] - g[a0]);
                let r = (1.0 - eps - tr).max(0.0);
                let (bt, bg, sky, sun, lu) = match (node, &self.fast_path) {
                    (Some((n0, x, next, u)), Some(fp)) => {
                        let lerp = |a: f64, b: f64, x: f64| a + x * (b - a);
                        // Linear in range at the height node of `n0`.
                        let at = |n0: usize| {
                            let (p, q) = (&fp.integrals[b][n0], &fp.integrals[b][n0 + 1]);
                            let w = &fp.path_radiance[b];
                            [
                                lerp(p.planck_at(kt, ft), q.planck_at(kt, ft), x),
                                lerp(p.planck_at(kg, fg), q.planck_at(kg, fg), x),
                                lerp(p.sky, q.sky, x),
                                lerp(p.sun, q.sun, x),
                                lerp(w[n0], w[n0 + 1], x),
                            ]
                        };
                        let mut v = at(n0);
                        if let Some(n1) = next {
                            let v1 = at(n1);
                            for (a, b) in v.iter_mut().zip(v1) {
                                *a = lerp(*a, b, u);
                            }
                        }
                        (v[0], v[1], v[2], v[3], v[4])
                    }
                    _ => {
                        let p = &fb.plain;
                        (p.planck_at(kt, ft), p.planck_at(kg, fg), p.sky, p.sun, 0.0)
                    }
                };
                let env = big_f * sky + (1.0 - big_f) * bg;
                let v = eps * bt + r * (env + sd * sun) + tr * env;
                out[b] = (v + lu) as f32;
                continue;
            }
            let nl = fb.len;
            let e = &fb.eps[mi];
            let row = |k: usize| &fb.planck[k * nl..(k + 1) * nl];
            // The fused sum with path weights `w·τ₂` linear in range
            // between `q0` and `q1`, plus the band path radiance.
            let sum_with = |q0: &[f32], q1: &[f32], fr: f32| {
                band_sum(
                    &BandStreams {
                        e0: &e[a0 * nl..(a0 + 1) * nl],
                        e1: &e[(a0 + 1) * nl..(a0 + 2) * nl],
                        t0: row(kt),
                        t1: row(kt + 1),
                        g0: row(kg),
                        g1: row(kg + 1),
                        q0,
                        q1,
                        sky: &fb.sky,
                        sun: &fb.sun,
                    },
                    [ta as f32, ft as f32, fg as f32, fr],
                    big_f as f32,
                    sd as f32,
                    tr as f32,
                ) as f64
            };
            out[b] = match (node, &self.fast_path) {
                (Some((n0, x, next, u)), Some(fp)) => {
                    let at = |n0: usize| {
                        let (q, w) = (&fp.weighted_tau[b], &fp.path_radiance[b]);
                        sum_with(&q[n0], &q[n0 + 1], x as f32) + w[n0] + x * (w[n0 + 1] - w[n0])
                    };
                    let v = at(n0);
                    match next {
                        Some(n1) => v + u * (at(n1) - v),
                        None => v,
                    }
                }
                _ => sum_with(&fb.w, &fb.w, 0.0),
            } as f32;
        }
        Ok(())
    }

    /// Node `k` and fraction of temperature `t` on the Planck table, when
    /// it lies on it.
    fn table_position(&self, t: f64) -> Option<(usize, f64)> {
        self.table.position(t)
    }

    /// [`Shader::shade`] for primary rays (unit directions, from the
    /// sensor): the radiance at the sensor, `L·τ₂ + L_u` over the slant
    /// range of each hit.
    pub fn shade_primary(&self, rays: &[Ray], hits: &[Option<Hit>], out: &mut [f64]) {
        self.shade(rays, hits, 0, out);
        let Some(p) = &self.path else { return };
        let n = self.total;
        for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
            let Some(h) = hit else { continue };
            let range = (h.t * ray.dir.length()) as f64;
            let z = (ray.origin.z + ray.dir.z * h.t) as f64;
            for (b, t) in self.bands.iter().enumerate() {
                let s = &mut out[i * n + t.start..i * n + t.start + t.band.len()];
                p.apply(b, range, z, s);
            }
        }
    }

    /// Number of spectral values per ray (all bands).
    pub fn spectrum_len(&self) -> usize {
        self.total
    }

    /// Number of bands.
    pub fn band_count(&self) -> usize {
        self.bands.len()
    }

    /// The band `b`.
    pub fn band(&self, b: usize) -> &Band {
        &self.bands[b].band
    }

    /// Band radiance ∫ R L dλ (W·m⁻²·sr⁻¹) of band `b` from a concatenated
    /// spectrum.
    pub fn band_radiance(&self, b: usize, spectrum: &[f64]) -> f64 {
        let t = &self.bands[b];
        t.band.integrate(&spectrum[t.start..t.start + t.band.len()])
    }

    /// Global facet index of a hit.
    pub fn facet_of(&self, hit: &Hit) -> usize {
        SceneGeometry::facet_id(&self.offsets, hit.instance, hit.prim)
    }

    /// The `material_id` truth value of facet `f`: its material's id.
    #[inline]
    pub fn material_id_of(&self, f: usize) -> f32 {
        self.optics.materials[self.optics.facet_material[f] as usize].id as f32
    }

    /// The tracer.
    pub fn tracer(&self) -> &'a dyn Tracer {
        self.tracer
    }

    /// The scene optics.
    pub fn optics(&self) -> &SceneOptics {
        self.optics
    }

    /// The conditions.
    pub fn conditions(&self) -> &Conditions {
        self.conditions
    }

    /// B(λ, T) for all wavelengths into `out`: tabulated, or exact off the
    /// table.
    fn planck_into(&self, t: f64, out: &mut [f64]) {
        let tab = &self.table;
        let x = (t - tab.t0) / PLANCK_TABLE_STEP_K;
        if tab.nodes >= 2 && x >= 0.0 && x < (tab.nodes - 1) as f64 {
            let k = x as usize;
            let f = x - k as f64;
            let a = &tab.values[k * self.total..(k + 1) * self.total];
            let b = &tab.values[(k + 1) * self.total..(k + 2) * self.total];
            for ((o, &va), &vb) in out.iter_mut().zip(a).zip(b) {
                *o = va + f * (vb - va);
            }
        } else {
            for (o, &l) in out.iter_mut().zip(&self.wavelengths) {
                *o = self.planck.radiance(l, t);
            }
        }
    }

    /// Spectral radiance arriving along each ray (misses see the sky or the
    /// ground beyond), written to `out` (`rays.len() × spectrum_len()`).
    /// `depth` is the number of bounces already taken.
    pub fn shade(&self, rays: &[Ray], hits: &[Option<Hit>], depth: u32, out: &mut [f64]) {
        let n = self.total;
        debug_assert_eq!(out.len(), rays.len() * n);
        // Secondary rays: (parent, is_transmission).
        let mut sec_rays = Vec::new();
        let mut sec_parent = Vec::new();
        if depth < self.options.max_bounces {
            for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
                let Some(h) = hit else { continue };
                let m =
                    &self.optics.materials[self.optics.facet_material[self.facet_of(h)] as usize];
                if m.specular_fraction <= 0.0 && m.transmissivity <= 0.0 {
                    continue;
                }
                let (p, nrm, d) = self.hit_frame(ray, h);
                if m.specular_fraction > 0.0 {
                    let r = d - 2.0 * d.dot(nrm) * nrm;
                    sec_rays.push(Ray::new(p + nrm * self.options.offset_m, r));
                    sec_parent.push((i, false));
                }
                if m.transmissivity > 0.0 {
                    sec_rays.push(Ray::new(p - nrm * self.options.offset_m, d));
                    sec_parent.push((i, true));
                }
            }
        }
        let mut sec_spec = Vec::new();
        if !sec_rays.is_empty() {
            let mut sec_hits = vec![None; sec_rays.len()];
            self.tracer
                .intersect(&sec_rays, Coherence::Incoherent, &mut sec_hits);
            sec_spec = vec![0.0; sec_rays.len() * n];
            self.shade(&sec_rays, &sec_hits, depth + 1, &mut sec_spec);
        }
        // Index of each ray's reflected / transmitted spectrum.
        let mut refl = vec![usize::MAX; rays.len()];
        let mut trans = vec![usize::MAX; rays.len()];
        for (k, &(i, is_t)) in sec_parent.iter().enumerate() {
            if is_t {
                trans[i] = k;
            } else {
                refl[i] = k;
            }
        }
        let mut sun = SunRays::default();
        let has_state = |i: usize| {
            let (Some(ph), Some(h)) = (&self.conditions.per_hit, &hits[i]) else {
                return false;
            };
            ph.wants(
                self.facet_of(h),
                h.t * rays[i].dir.length(),
                self.pixel_angle_rad,
            )
        };
        self.sun_visibility(rays, hits, has_state, &mut sun);
        let mut b_t = vec![0.0; n];
        let mut b_bg = vec![0.0; n];
        for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
            let o = &mut out[i * n..(i + 1) * n];
            let Some(h) = hit else {
                self.miss_into(ray.dir, o);
                continue;
            };
            let spec_in =
                (refl[i] != usize::MAX).then(|| &sec_spec[refl[i] * n..(refl[i] + 1) * n]);
            let behind =
                (trans[i] != usize::MAX).then(|| &sec_spec[trans[i] * n..(trans[i] + 1) * n]);
            let lit = sun.of(i);
            self.leaving_into(ray, h, lit, spec_in, behind, &mut b_t, &mut b_bg, o);
        }
    }

    /// Spectral radiance of a ray leaving the scene: the sky arriving from
    /// its direction (interpolated linearly in cos θ between the sky
    /// nodes) above the horizon, the ground beyond below it.
    pub fn miss_into(&self, dir: Vec3, out: &mut [f64]) {
        let (k, f) = sky_node(dir.z as f64, dir.length() as f64);
        for t in &self.bands {
            let o = &mut out[t.start..t.start + t.ground.len()];
            if dir.z >= 0.0 {
                let (a, b) = (&t.sky_dir[k], &t.sky_dir[k + 1]);
                for ((o, &a), &b) in o.iter_mut().zip(a).zip(b) {
                    *o = a + f * (b - a);
                }
            } else {
                o.copy_from_slice(&t.ground);
            }
        }
    }

    /// Hit point, normal facing the ray's origin, and unit ray direction.
    fn hit_frame(&self, ray: &Ray, h: &Hit) -> (Vec3, Vec3, Vec3) {
        let d = ray.dir.normalize_or_zero();
        let p = ray.origin + ray.dir * h.t;
        let mut nrm = h.ng.normalize_or(Vec3::Z);
        if nrm.dot(d) > 0.0 {
            nrm = -nrm;
        }
        (p, nrm, d)
    }

    /// The spectral radiance leaving hit `h` toward the origin of `ray`
    /// (the module docs' equation, with the glint of [`super::glint`]);
    /// `vis` the hit's own sun visibility where it traced a shadow ray.
    #[allow(clippy::too_many_arguments)]
    fn leaving_into(
        &self,
        ray: &Ray,
        h: &Hit,
        vis: Option<f32>,
        spec_in: Option<&[f64]>,
        behind: Option<&[f64]>,
        b_t: &mut [f64],
        b_bg: &mut [f64],
        out: &mut [f64],
    ) {
        let f = self.facet_of(h);
        let s = &self.conditions.surface;
        let mi = self.optics.facet_material[f] as usize;
        let m = &self.optics.materials[mi];
        let (_, nrm, d) = self.hit_frame(ray, h);
        let cos_view = (-d.dot(nrm)).clamp(0.0, 1.0) as f64;
        let theta = cos_view.acos().to_degrees();
        let a0 = (theta.floor() as usize).min(ANGLE_ROWS - 2);
        let ta = theta - a0 as f64;
        let (t_hit, sun_fraction) = hit_temperature(s, f, self.hit_state(ray, h));
        let sun_fraction = vis.unwrap_or(sun_fraction);
        // The glint lobe toward the viewer: the hit's own visibility (a
        // specular facet always traces it while the sun faces it).
        let glint = match (self.sun_dir, vis) {
            (Some(sd), Some(v)) if self.glint_m2[mi] > 0.0 && v > 0.0 => {
                super::glint::glint_lobe_sr(self.glint_m2[mi], nrm, -d, sd)
            }
            _ => 0.0,
        };
        self.planck_into(t_hit, b_t);
        self.planck_into(s.background_k[f] as f64, b_bg);
        let big_f = (s.shape_factor[f] as f64).clamp(0.0, 1.0);
        // The sun only lights the face it falls on: for a single-sided facet
        // seen from behind, cos σ of the front face does not apply.
        let front = h.ng.dot(d) < 0.0;
        let sun_w = if front || m.double_sided {
            (s.cos_sun[f] as f64).max(0.0) * (sun_fraction as f64).clamp(0.0, 1.0)
                / std::f64::consts::PI
        } else {
            0.0
        };
        let spec_frac = m.specular_fraction.clamp(0.0, 1.0);
        let tr = m.transmissivity.clamp(0.0, 1.0);
        for t in &self.bands {
            let nl = t.band.len();
            let e = &t.eps[mi];
            let e0 = &e[a0 * nl..(a0 + 1) * nl];
            let e1 = &e[(a0 + 1) * nl..(a0 + 2) * nl];
            for j in 0..nl {
                let k = t.start + j;
                let eps = e0[j] + ta * (e1[j] - e0[j]);
                let r = (1.0 - eps - tr).max(0.0);
                let rd = (1.0 - spec_frac) * r;
                let rs = spec_frac * r;
                let env = big_f * t.sky[j] + (1.0 - big_f) * b_bg[k];
                let sun = t.sun[j] * sun_w;
                let spec = spec_in.map_or(env, |v| v[k]) + t.sun[j] * glint;
                let beh = behind.map_or(env, |v| v[k]);
                out[k] = eps * b_t[k] + rd * (sun + env) + rs * spec + tr * beh;
            }
        }
    }
}

/// The temperature (K) and sunlit fraction of a hit on facet `f`: its own
/// (per-hit `state`) or its facet's.
#[inline]
fn hit_temperature(s: &SurfaceState, f: usize, state: Option<HitState>) -> (f64, f32) {
    match state {
        Some(st) => ((s.temperature_k[f] + st.dt_k) as f64, st.sun_fraction),
        None => (s.temperature_k[f] as f64, s.sun_fraction[f]),
    }
}

/// One height node's grey-path terms of band `b` ([`Shader::grey_pass`]):
/// `[Σq·B(T), Σq·B(T_bg), Σq·L_sky, Σq·E_s, Σw·L_u]`, the Planck
/// integrals linear in temperature (fractions `ft`, `fg` from the entries
/// at `t0`, `g0`; the next temperature node `up` on) and all linear in
/// range (fraction `rx`; the next range node `nb` on, the node terms at
/// `q`, `3·nb` on).
#[inline(always)]
fn grey_node(
    pl: &[f32],
    nd: &[f32],
    [up, nb, b]: [usize; 3],
    [t0, g0, q]: [usize; 3],
    [ft, fg, rx]: [f32; 3],
) -> [f32; 5] {
    let bilerp = |o: usize, f: f32| {
        let v0 = pl[o + b] + f * (pl[o + up + b] - pl[o + b]);
        let v1 = pl[o + nb + b] + f * (pl[o + up + nb + b] - pl[o + nb + b]);
        v0 + rx * (v1 - v0)
    };
    let node = |o: usize| nd[q + o + b] + rx * (nd[q + o + 3 * nb + b] - nd[q + o + b]);
    [
        bilerp(t0, ft),
        bilerp(g0, fg),
        node(0),
        node(nb),
        node(2 * nb),
    ]
}

/// The spectral rows one band of [`Shader::fast_primary`] reads (all of
/// the band's length): emissivity at the two angle rows, Planck at the two
/// table nodes of the surface and of the background temperature, `w·τ₂` at
/// the two range nodes, sky radiance and solar irradiance.
struct BandStreams<'s> {
    e0: &'s [f32],
    e1: &'s [f32],
    t0: &'s [f32],
    t1: &'s [f32],
    g0: &'s [f32],
    g1: &'s [f32],
    q0: &'s [f32],
    q1: &'s [f32],
    sky: &'s [f32],
    sun: &'s [f32],
}

/// Lanes of the partial sums of [`band_sum`] (a fixed order: the result
/// does not depend on the machine), and the padding of its rows.
const LANES: usize = 8;

/// `Σ_λ w·τ₂ · [ε·B(T) + r·(env + sd·E_s) + tr·env]` over one band (see
/// [`Shader::fast_primary`]); `frac` = the interpolation fractions of
/// angle, temperature, background temperature and range. All rows are
/// [`FastBand::len`] long, a multiple of [`LANES`].
#[inline]
fn band_sum(s: &BandStreams, frac: [f32; 4], big_f: f32, sd: f32, tr: f32) -> f32 {
    let [ta, ft, fg, fr] = frac;
    let one_f = 1.0 - big_f;
    let one_t = 1.0 - tr;
    let lane = |v: &[f32], c: usize| -> [f32; LANES] {
        v[c..c + LANES].try_into().expect("rows are whole lanes")
    };
    let mut acc = [0f32; LANES];
    for c in (0..s.e0.len()).step_by(LANES) {
        let (e0, e1, t0, t1) = (lane(s.e0, c), lane(s.e1, c), lane(s.t0, c), lane(s.t1, c));
        let (g0, g1, q0, q1) = (lane(s.g0, c), lane(s.g1, c), lane(s.q0, c), lane(s.q1, c));
        let (sky, sun) = (lane(s.sky, c), lane(s.sun, c));
        for l in 0..LANES {
            let eps = e0[l] + ta * (e1[l] - e0[l]);
            let bt = t0[l] + ft * (t1[l] - t0[l]);
            let bg = g0[l] + fg * (g1[l] - g0[l]);
            let wt = q0[l] + fr * (q1[l] - q0[l]);
            let env = big_f * sky[l] + one_f * bg;
            let r = one_t - eps;
            let r = if r > 0.0 { r } else { 0.0 };
            acc[l] += wt * (eps * bt + r * (env + sd * sun[l]) + tr * env);
        }
    }
    acc.iter().sum()
}

#[cfg(test)]
mod tests {
    #[test]
    fn acos_deg_is_within_its_stated_bound() {
        for i in 0..=100_000 {
            let x = i as f64 / 100_000.0;
            // The cosine as the renderer has it: in f32.
            let x = x as f32;
            let err = (super::acos_deg(x) as f64 - (x as f64).acos().to_degrees()).abs();
            assert!(err <= 2e-5, "acos({x}): error {err}°");
        }
    }

    #[test]
    fn acos_unit_is_within_its_published_bound() {
        for i in 0..=100_000 {
            let x = i as f64 / 100_000.0;
            let err = (super::acos_unit(x) - x.acos()).abs();
            assert!(err <= 3e-8, "acos({x}): error {err}");
        }
    }
}
