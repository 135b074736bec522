//! Stage 3, sources: what arrives at a hit or leaves the scene — the sky
//! (isotropic-equivalent for diffuse reflection, directional for rays that
//! leave the scene, on [`SKY_NODES`] nodes), the ground beyond the scene,
//! the sun at the surface (its spectrum, and per hit its visibility by a
//! shadow ray, [`sun_ray_facets`]) and its glint lobe
//! ([`crate::render::glint`]).

use glam::Vec3;

use super::band::FastBand;
use super::conditions::{Conditions, SceneOptics, Sky, SunInput};
use super::surface::PlanckTable;
use super::{BandTables, Shader};
use crate::atmosphere::Atmosphere;
use crate::atmosphere::{ANGLE_NODES, angle_node, angle_node_cos};
use crate::radiometry::Planck;
use crate::trace::{Coherence, Hit, Ray};

/// Nodes of the directional sky table: cos θ from cos 89° (the horizon,
/// [`crate::atmosphere::MAX_SKY_ZENITH_DEG`]) to 1, quadratically spaced
/// (denser toward the horizon, where the sky radiance changes fastest).
pub(super) const SKY_NODES: usize = 24;

/// cos θ of sky node `k`.
pub(super) fn sky_node_cos(k: usize) -> f64 {
    let mu0 = crate::atmosphere::MAX_SKY_ZENITH_DEG.to_radians().cos();
    let s = k as f64 / (SKY_NODES - 1) as f64;
    mu0 + (1.0 - mu0) * s * s
}

/// The sky nodes bracketing a direction with vertical component `dz` of a
/// vector of length `len`: `(k, f)` with the direction at fraction `f` from
/// node `k` to node `k + 1`.
#[inline]
pub(super) fn sky_node(dz: f64, len: f64) -> (usize, f64) {
    let mu0 = crate::atmosphere::MAX_SKY_ZENITH_DEG.to_radians().cos();
    let mu = if len > 0.0 { dz / len } else { 1.0 };
    let s = ((mu - mu0).max(0.0) / (1.0 - mu0)).min(1.0).sqrt() * (SKY_NODES - 1) as f64;
    let k = (s as usize).min(SKY_NODES - 2);
    (k, s - k as f64)
}

/// The sky's single-scattered sunlight on `grid` for the directional sky
/// of a render: `[sky node][scattering-angle node]` spectra
/// ([`crate::atmosphere::Atmosphere::scattered_sky`] at the [`SKY_NODES`]
/// zeniths and the [`crate::atmosphere::ANGLE_NODES`] angles), the sun's
/// beam dimmed by the weather as the direct sun is ([`beam_attenuation`]).
/// `None` where the sky has none: a sky fixed by `sky_temperature_k`
/// ([`Sky::Blackbody`]), no sun or no beam, no scattering model (no
/// atmosphere, a tape7 table).
pub fn scattered_sky_nodes(
    conditions: &Conditions,
    grid: &crate::radiometry::SpectralGrid,
) -> crate::Result<Option<Vec<Vec<Vec<f64>>>>> {
    let (Sky::Atmosphere(_), Some(sun)) = (&conditions.sky, &conditions.sun) else {
        return Ok(None);
    };
    let zenith = sun_zenith_deg(sun);
    let c = beam_attenuation(sun);
    if !(zenith < 90.0 && c > 0.0) {
        return Ok(None);
    }
    let s = crate::atmosphere::Sun::new(zenith, 0.0, 1.0)?.with_attenuation(c)?;
    let cos: Vec<f64> = (0..ANGLE_NODES).map(angle_node_cos).collect();
    conditions
        .atmosphere
        .scattered_sky(&super::sky_node_zeniths_deg(), &s, &cos, grid)
}

/// Azimuth steps of [`scattered_sky_azimuth_mean`] over 0–180°.
const AZIMUTH_STEPS: usize = 90;

/// The azimuthal mean of the sky's scattered sunlight at each sky node,
/// from `table` (`[sky node][angle node]` spectra, [`scattered_sky_nodes`])
/// and the sun at `sun_zenith_deg`: at zenith θ the direction of azimuth φ
/// from the sun's has `cos Θ = cos θ_s·cos θ + sin θ_s·sin θ·cos φ`, and
/// the mean over φ is the midpoint rule on [`AZIMUTH_STEPS`] steps of
/// 0–180° (the sky is symmetric about the sun's vertical plane), each
/// angle interpolated as the rays' ([`angle_node`]). What a diffuse
/// surface reflects of it ([`super::reflected_sky`]) is taken from this
/// mean: its projected-cosine weight over a zenith ring is then the
/// ring's mean times the ring's weight, exact for a horizontal facet and
/// an approximation for a tilted one (whose weight favours one azimuth).
pub fn scattered_sky_azimuth_mean(table: &[Vec<Vec<f64>>], sun_zenith_deg: f64) -> Vec<Vec<f64>> {
    let (ss, cs) = sun_zenith_deg.to_radians().sin_cos();
    table
        .iter()
        .enumerate()
        .map(|(zn, angles)| {
            let n = angles.first().map_or(0, Vec::len);
            let mu = sky_node_cos(zn);
            let st = (1.0 - mu * mu).max(0.0).sqrt();
            let mut mean = vec![0.0; n];
            for j in 0..AZIMUTH_STEPS {
                let phi = std::f64::consts::PI * (j as f64 + 0.5) / AZIMUTH_STEPS as f64;
                let (k, f) = angle_node(cs * mu + ss * st * phi.cos());
                for ((m, &a), &b) in mean.iter_mut().zip(&angles[k]).zip(&angles[k + 1]) {
                    *m += a + f * (b - a);
                }
            }
            mean.iter_mut().for_each(|m| *m /= AZIMUTH_STEPS as f64);
            mean
        })
        .collect()
}

/// Solar spectral irradiance on a surface normal to the sun, W·m⁻²·µm⁻¹:
/// the broadband direct normal irradiance `dni_w_m2` distributed as a
/// 5772 K blackbody (IAU 2015 nominal effective temperature),
/// `E(λ) = DNI · π B(λ, 5772 K) / (σ · 5772⁴)`.
pub fn solar_spectrum(planck: &Planck, wavelengths_um: &[f64], dni_w_m2: f64) -> Vec<f64> {
    pub(super) const SUN_K: f64 = 5772.0;
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
    let c = beam_attenuation(sun);
    if c <= 0.0 {
        return Ok(vec![0.0; wl.len()]);
    }
    let tau = atmosphere.solar_transmittance(sun_zenith_deg(sun), grid)?;
    Ok(crate::radiometry::solar_irradiance_toa(grid, 1.0)
        .into_iter()
        .zip(tau)
        .map(|(e, t)| e * t * c)
        .collect())
}

/// Solar zenith angle of `sun`, degrees.
pub(super) fn sun_zenith_deg(sun: &SunInput) -> f64 {
    let d = sun.direction.normalize_or_zero();
    (d.z as f64).clamp(-1.0, 1.0).acos().to_degrees()
}

/// The weather's attenuation of the direct beam beyond the clear sky,
/// `c = min(1, DNI / DNI_clear)` (0 with the sun down or no measured beam):
/// the factor by which the clear-sky solar spectrum is dimmed
/// ([`surface_solar_spectrum`]), and with it the sunlight the atmosphere
/// scatters into a path ([`crate::render::path::PathSun::for_scene`]).
pub fn beam_attenuation(sun: &SunInput) -> f64 {
    let clear = clear_sky_dni_w_m2(sun_zenith_deg(sun));
    if clear <= 0.0 || sun.direct_normal_w_m2 <= 0.0 {
        return 0.0;
    }
    (sun.direct_normal_w_m2 / clear).min(1.0)
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
/// [`crate::render::per_hit`] traces its own rays for facets large against the
/// pixel footprint).
pub(super) fn sun_ray_facets(
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

/// A hit's sun visibility in [`SunRays::vis`]: its facet's sunlit fraction
/// (or its per-hit state's).
pub(super) const VIS_FACET: u8 = 2;

/// The shadow rays of a batch's hits ([`Shader::sun_visibility`]).
#[derive(Debug, Default)]
pub(super) struct SunRays {
    /// Per ray of the batch: 0 shaded, 1 lit, [`VIS_FACET`].
    pub(super) vis: Vec<u8>,
    pub(super) rays: Vec<Ray>,
    pub(super) idx: Vec<u32>,
    pub(super) occluded: Vec<bool>,
}

impl SunRays {
    /// The visibility of ray `i` as a sunlit fraction, if it traced one.
    #[inline]
    pub(super) fn of(&self, i: usize) -> Option<f32> {
        match self.vis.get(i) {
            Some(0) => Some(0.0),
            Some(1) => Some(1.0),
            _ => None,
        }
    }
}

impl Shader<'_> {
    /// Whether hits on facet `f` take their own sun visibility from a
    /// shadow ray ([`sun_ray_facets`]) instead of the facet's sunlit
    /// fraction.
    pub fn traces_sun_ray(&self, f: usize) -> bool {
        self.sun_ray[f]
    }

    /// Whether the face of facet material `mi` that a ray `d` sees (`ng`
    /// its geometric normal) is the face the sun falls on. A single-sided
    /// facet's sunlit face is its front (its `cos_sun` is 0 when the sun
    /// is behind it); a double-sided facet's `cos_sun` is `|n·s|`, lit on
    /// whichever side the sun is, so the face seen is lit only when the
    /// sun is on the viewer's side: in the thermal infrared a leaf layer
    /// or fence is opaque and its unlit face reflects no direct sun.
    #[inline]
    pub(super) fn seen_face_lit(&self, mi: usize, ng: Vec3, d: Vec3) -> bool {
        let dn = ng.dot(d);
        if !self.optics.materials[mi].double_sided {
            return dn < 0.0;
        }
        self.sun_dir.is_none_or(|s| dn * ng.dot(s) < 0.0)
    }

    /// The sun visibility of a batch's hits into `sr.vis`: one shadow ray
    /// toward the sun from each hit on a facet of [`sun_ray_facets`] whose
    /// seen face the sun lights (and which has no per-hit state, `has_state`:
    /// that state carries its own), traced together (parallel rays from
    /// neighbouring points: [`Coherence::Coherent`]); the origin is lifted
    /// off the surface by [`ShadeOptions::offset_m`] on the sun's side.
    pub(super) fn sun_visibility(
        &self,
        rays: &[Ray],
        hits: &[Option<Hit>],
        has_state: impl Fn(usize) -> bool,
        sr: &mut SunRays,
    ) {
        self.sun_visibility_of(rays, hits, 0..rays.len(), has_state, sr);
    }

    /// [`Shader::sun_visibility`] of the batch's rays `which` only (the
    /// others keep [`VIS_FACET`]).
    pub(super) fn sun_visibility_of(
        &self,
        rays: &[Ray],
        hits: &[Option<Hit>],
        which: impl IntoIterator<Item = usize>,
        has_state: impl Fn(usize) -> bool,
        sr: &mut SunRays,
    ) {
        sr.vis.clear();
        sr.rays.clear();
        sr.idx.clear();
        let Some(sun) = self.sun_dir else { return };
        sr.vis.resize(rays.len(), VIS_FACET);
        let s = &self.conditions.surface;
        for i in which {
            let (ray, Some(h)) = (&rays[i], &hits[i]) else {
                continue;
            };
            let f = self.facet_of(h);
            if !self.sun_ray[f] || has_state(i) {
                continue;
            }
            let mi = self.optics.facet_material[f] as usize;
            let dn = h.ng.dot(ray.dir);
            let diffuse_lit = s.cos_sun[f] > 0.0 && self.seen_face_lit(mi, h.ng, ray.dir);
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

    /// Band radiance (W·m⁻²·sr⁻¹, one per band into `out`) at the sensor of
    /// a primary ray that leaves the scene: the sky above the horizon, the
    /// ground beyond below it (no path, as [`Shader::shade_primary`]).
    pub fn fast_miss(&self, ray: &Ray, out: &mut [f32]) {
        let (k, f) = sky_node(ray.dir.z as f64, ray.dir.length() as f64);
        let ka = self.sky_angle(ray.dir);
        for (o, fb) in out.iter_mut().zip(&self.fast) {
            *o = if ray.dir.z >= 0.0 {
                fb.miss_sky_at(k, f, ka)
            } else {
                fb.miss_ground
            } as f32;
        }
    }

    /// The scattering-angle node and fraction of a ray of direction `dir`
    /// leaving the scene, for the sky's scattered sunlight (`(0, 0)` where
    /// the sky has none).
    #[inline]
    pub(super) fn sky_angle(&self, dir: Vec3) -> (usize, f64) {
        match self.sky_sun {
            Some(s) => angle_node((dir.dot(s) / dir.length()) as f64),
            None => (0, 0.0),
        }
    }

    /// Spectral radiance of a ray leaving the scene: the sky arriving from
    /// its direction (interpolated linearly in cos θ between the sky
    /// nodes) above the horizon, the ground beyond below it.
    pub fn miss_into(&self, dir: Vec3, out: &mut [f64]) {
        let (k, f) = sky_node(dir.z as f64, dir.length() as f64);
        // The scattering angle once for every band.
        let (ka, fa) = self.sky_angle(dir);
        for t in &self.bands {
            let o = &mut out[t.start..t.start + t.ground.len()];
            if dir.z >= 0.0 {
                let (a, b) = (&t.sky_dir[k], &t.sky_dir[k + 1]);
                for ((o, &a), &b) in o.iter_mut().zip(a).zip(b) {
                    *o = a + f * (b - a);
                }
                if self.sky_sun.is_some() && !t.sky_scatter.is_empty() {
                    // The scattered sunlight of the ray's own angle: linear
                    // in the angle, then in cos θ.
                    let (a, b) = (&t.sky_scatter[k], &t.sky_scatter[k + 1]);
                    for (j, o) in o.iter_mut().enumerate() {
                        let at = |r: &[Vec<f64>]| r[ka][j] + fa * (r[ka + 1][j] - r[ka][j]);
                        let (x, y) = (at(a), at(b));
                        *o += x + f * (y - x);
                    }
                }
            } else {
                o.copy_from_slice(&t.ground);
            }
        }
    }
}
