//! Per-hit radiance: the "big equation" on each band's spectral grid, with
//! secondary rays for specular reflection and transmission.
//!
//! Stages, data flowing one way (one file each): `hit` (frame, view
//! zenith, per-hit state) → `surface` (temperature and B(λ, T),
//! emissivity, the grey path's facet records) → `sources` (sky, ground
//! beyond, sun and its per-hit visibility, glint) → `path` (τ₂ and L_u
//! folded into the band weights) → `band` (the band radiance at the
//! sensor). `spectral` drives them for the reference — each hit's inputs
//! handed to [`crate::radiometry::leaving_radiance`], the one
//! implementation of the equation below — and `fast` for the fast
//! primary paths tested against it; `truth` writes the truth layers.
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
//!      + r_d·[F·L_eq(λ, β) + (1 − F)·B(λ, T_bg)]   sky and background
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
//! past it, both take the diffuse environment `F·L_eq + (1 − F)·B(T_bg)`.
//! Misses see the sky only, so the mirror ray and the glint lobe do not
//! count the sun twice.
//!
//! Rays that leave the scene see the sky radiance arriving from their own
//! direction when they point above the horizon (`dir.z ≥ 0`;
//! [`crate::atmosphere::Atmosphere::sky_radiance_toward`] on [`SKY_NODES`]
//! values of cos θ, linear between them) and the ground beyond the scene (a
//! blackbody at [`Conditions::ground_temperature_k`]) when they point below
//! it. `L_eq` in the diffuse term above is that directional sky integrated
//! over the sky a facet of tilt β faces ([`reflected_sky`]), tabulated on
//! [`TILT_NODES`] tilts and linear between them. A hit on the back face of
//! a double-sided facet takes that face's own `F` and tilt 180° − β where
//! its view is known ([`SurfaceState::back_shape_factor`],
//! [`Shader::seen_sky`]), else the front face's.
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
//! per-band integrals over the Planck table (`Σ w·τ₂·B(T_k)`, `Σ w·τ₂·L_eq`
//! per tilt node, `Σ w·τ₂·E_s`). Both use the same interpolations as the spectral
//! reference ([`Shader::shade`] + [`Shader::band_radiance`]), so they agree
//! with it to rounding; `tests/render.rs` checks ≤ 10⁻⁵ relative against
//! the reference equation with exact Planck radiances on random inputs
//! (`docs/physics/radiometry.md`, the tolerance table).

mod band;
mod conditions;
mod fast;
mod hit;
mod path;
mod reflected_sky;
mod sources;
mod spectral;
mod surface;
mod truth;

pub use conditions::{Conditions, SceneOptics, ShadeOptions, Sky, SunInput, SurfaceState};
pub use fast::{FastMiss, FastScratch};
pub use reflected_sky::{
    TILT_NODES, reflected_sky, ring_weight, sky_node_zeniths_deg, sky_tilt_weights, tilt_at,
    tilt_position,
};
pub use sources::{
    SUN_RAY_THRESHOLD, beam_attenuation, clear_sky_dni_w_m2, scattered_sky_azimuth_mean,
    scattered_sky_nodes, solar_spectrum, surface_solar_spectrum,
};
pub use surface::PLANCK_TABLE_STEP_K;
pub use truth::TruthOut;

use glam::Vec3;
use rayon::prelude::*;

use super::path::PathTables;
use crate::geometry::SceneGeometry;
use crate::radiometry::{Band, Emissivity, Planck};
use crate::trace::Tracer;

use band::{FastBand, GreyTables, Integrals, LANES};
use hit::ANGLE_ROWS;
use path::FastPath;
use sources::{SKY_NODES, sun_ray_facets};
use surface::{GreyFacet, PLANCK_TABLE_MAX_NODES, PlanckTable, grey_facets};

/// One band's precomputed tables.
#[derive(Debug, Clone)]
struct BandTables {
    band: Band,
    /// Offset of this band's wavelengths in the concatenated spectrum.
    start: usize,
    /// The diffusely reflected sky: `L_eq(λ)` per tilt node
    /// ([`reflected_sky`], [`TILT_NODES`]).
    sky_tilt: Vec<Vec<f64>>,
    /// Sky spectral radiance arriving from each of the [`SKY_NODES`]
    /// directions ([`sky_node_cos`]): what a ray leaving the scene sees.
    sky_dir: Vec<Vec<f64>>,
    /// By day: the sky's scattered sunlight per sky node and
    /// scattering-angle node, `sky_scatter[k][a]` spectra
    /// ([`scattered_sky_nodes`]; empty: none). Rays leaving the scene add
    /// it at their own angle; the reflected sky `sky_tilt` holds its
    /// azimuthal mean ([`scattered_sky_azimuth_mean`]).
    sky_scatter: Vec<Vec<Vec<f64>>>,
    /// Ground-beyond-the-scene spectral radiance.
    ground: Vec<f64>,
    /// Solar spectral irradiance at the surface, normal to the sun.
    sun: Vec<f64>,
    /// Per material: `ANGLE_ROWS × n` emissivities.
    eps: Vec<Vec<f64>>,
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
    /// Per facet: the position of its front face's tilt on the tilt table
    /// of the reflected sky ([`tilt_position`]).
    tilt: Vec<f32>,
    /// Per facet: the same for its back face (tilt 180° − β), which a hit
    /// on the back face of a double-sided facet reflects
    /// ([`Shader::seen_sky`]).
    back_tilt: Vec<f32>,
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
    /// Per facet: what [`Shader::shade_fast`] does with a hit on it, one
    /// byte of `RULE_*` flags ([`Shader::facet_rules`]).
    rule: Vec<u8>,
    /// Unit vector toward the sun while the sky holds scattered sunlight
    /// ([`BandTables::sky_scatter`]).
    sky_sun: Option<Vec3>,
}

/// [`Shader::rule`]: the facet is on the grey path ([`grey_facets`]).
pub(super) const RULE_GREY: u8 = 1;
/// Its hits trace their own shadow ray ([`sun_ray_facets`]).
pub(super) const RULE_SUN_RAY: u8 = 2;
/// Its hits all take a per-hit state
/// ([`crate::render::per_hit::PerHitRule::Always`]).
pub(super) const RULE_PER_HIT: u8 = 4;
/// Its hits take a per-hit state at ranges where it is large against the
/// pixel footprint ([`crate::render::per_hit::PerHitRule::ByRange`]).
pub(super) const RULE_PER_HIT_BY_RANGE: u8 = 8;
/// Its back face has a sky view of its own (a double-sided facet with a
/// back shape factor, [`SurfaceState::back_shape_factor`]): hits on the
/// back face leave the grey path's front-face record for
/// [`Shader::fast_general`].
pub(super) const RULE_BACK_SKY: u8 = 16;

/// Per facet (global order): the positions of its front and back faces'
/// tilts on the tilt table of the reflected sky, from the vertical
/// component of its world-space front normal
/// ([`crate::geometry::triangle_normal_area`]; the back face's tilt is
/// 180° − β).
fn facet_tilts(geometry: &SceneGeometry) -> (Vec<f32>, Vec<f32>) {
    geometry
        .instances
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, inst)| {
            (0..geometry.meshes[inst.mesh].triangle_count()).map(move |p| {
                let (n, _) = crate::geometry::triangle_normal_area(&geometry.world_triangle(i, p));
                (tilt_position(n.z as f64), tilt_position(-n.z as f64))
            })
        })
        .unzip()
}

/// The thermal sky arriving from each of the [`SKY_NODES`] directions on
/// `band`'s grid: a blackbody for [`Sky::Blackbody`], else the
/// atmosphere's directional sky.
fn sky_directions(
    conditions: &Conditions,
    planck: &Planck,
    band: &Band,
) -> crate::Result<Vec<Vec<f64>>> {
    match &conditions.sky {
        Sky::Blackbody { temperature_k } => {
            let sky: Vec<f64> = band
                .wavelengths_um()
                .iter()
                .map(|&l| planck.radiance(l, *temperature_k))
                .collect();
            Ok(vec![sky; SKY_NODES])
        }
        // (One call for all directions: each call computes the broadband
        // scale, which costs more than several directions.)
        Sky::Atmosphere(c) => {
            conditions
                .atmosphere
                .sky_radiances_toward(c, &sky_node_zeniths_deg(), band.grid())
        }
    }
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
        // Each band's sources, in parallel (bands, and within a band the
        // sky, its directions and the sun: the same values as in turn).
        let sources = bands
            .par_iter()
            .map(|band| -> crate::Result<_> {
                let wl = band.wavelengths_um();
                let ((sky_dir, sky_scatter), sun) = rayon::join(
                    || {
                        rayon::join(
                            || sky_directions(conditions, &planck, band),
                            || scattered_sky_nodes(conditions, band.grid()),
                        )
                    },
                    || match conditions.sun {
                        Some(s) if s.direction.z > 0.0 => {
                            surface_solar_spectrum(&conditions.atmosphere, &planck, &s, band.grid())
                        }
                        _ => Ok(vec![0.0; wl.len()]),
                    },
                );
                let sky_dir = sky_dir?;
                let sky_scatter = sky_scatter?.unwrap_or_default();
                // The reflected sky: the thermal sky with the azimuthal
                // mean of the scattered sunlight.
                let sky_tilt = if sky_scatter.is_empty() {
                    reflected_sky::tilt_table(&sky_dir)
                } else {
                    let zenith = conditions
                        .sun
                        .as_ref()
                        .map_or(90.0, sources::sun_zenith_deg);
                    let mean = scattered_sky_azimuth_mean(&sky_scatter, zenith);
                    let total: Vec<Vec<f64>> = sky_dir
                        .iter()
                        .zip(&mean)
                        .map(|(a, b)| a.iter().zip(b).map(|(x, y)| x + y).collect())
                        .collect();
                    reflected_sky::tilt_table(&total)
                };
                let ground = wl
                    .iter()
                    .map(|&l| planck.radiance(l, conditions.ground_temperature_k))
                    .collect();
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
                Ok((sky_tilt, sky_dir, sky_scatter, ground, sun?, eps))
            })
            .collect::<crate::Result<Vec<_>>>()?;
        let mut tables = Vec::with_capacity(bands.len());
        let mut wavelengths = Vec::new();
        for (band, (sky_tilt, sky_dir, sky_scatter, ground, sun, eps)) in bands.iter().zip(sources)
        {
            tables.push(BandTables {
                band: band.clone(),
                start: wavelengths.len(),
                sky_tilt,
                sky_dir,
                sky_scatter,
                ground,
                sun,
                eps,
            });
            wavelengths.extend_from_slice(band.wavelengths_um());
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
            let mut values = vec![0.0; nodes * total];
            values
                .par_chunks_mut(total)
                .enumerate()
                .for_each(|(k, row)| {
                    let t = t0 + k as f64 * PLANCK_TABLE_STEP_K;
                    for (v, &l) in row.iter_mut().zip(&wavelengths) {
                        *v = planck.radiance(l, t);
                    }
                });
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
                    sky: t.sky_tilt.iter().map(|v| pad(v)).collect(),
                    sun: pad(&t.sun),
                    eps: t.eps.iter().map(|e| pad(e)).collect(),
                    miss_sky: t.sky_dir.iter().map(|v| t.band.integrate(v)).collect(),
                    miss_ground: t.band.integrate(&t.ground),
                    miss_scatter: t
                        .sky_scatter
                        .iter()
                        .flat_map(|angles| angles.iter().map(|l| t.band.integrate(l)))
                        .collect(),
                }
            })
            .collect();
        let sun_dir = conditions
            .sun
            .map(|s| s.direction.normalize_or_zero())
            .filter(|_| tables.iter().any(|t| t.sun.iter().any(|&e| e > 0.0)));
        let sky_sun = conditions
            .sun
            .map(|s| s.direction.normalize_or_zero())
            .filter(|_| tables.iter().any(|t| !t.sky_scatter.is_empty()));
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
        let (tilt, back_tilt) = facet_tilts(geometry);
        let (grey, grey_terms) = grey_facets(
            optics, conditions, &options, &fast, &table, &sun_ray, &glint_m2, &tilt,
        );
        let plain: Vec<Vec<(&Integrals, f64)>> = fast
            .iter()
            .map(|fb| vec![(&fb.plain, 0.0), (&fb.plain, 0.0)])
            .collect();
        let grey_tables = GreyTables::new(&fast, &plain, &[], &[], &optics.materials);
        Ok(Shader {
            grey,
            tilt,
            back_tilt,
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
            rule: Vec::new(),
            sky_sun,
        }
        .with_rules())
    }

    /// The same shader with the angular size of a pixel (rad), for the
    /// per-hit rule's pixel footprint ([`super::per_hit`]).
    pub fn with_pixel_angle(mut self, rad: f64) -> Self {
        self.pixel_angle_rad = rad as f32;
        self.with_rules()
    }

    /// The shader with its per-facet rules ([`Shader::facet_rules`]).
    fn with_rules(mut self) -> Self {
        self.rule = self.facet_rules();
        self
    }

    /// Per facet, the `RULE_*` flags of a hit on it: on the grey path
    /// ([`RULE_GREY`]), tracing its own shadow ray ([`RULE_SUN_RAY`]),
    /// taking a per-hit state always ([`RULE_PER_HIT`]) or by range
    /// ([`RULE_PER_HIT_BY_RANGE`]) — so that [`Shader::shade_fast`] reads
    /// one byte per hit to find the hits that need none of the per-hit
    /// work.
    fn facet_rules(&self) -> Vec<u8> {
        use crate::render::per_hit::PerHitRule;
        let ph = self.conditions.per_hit.as_deref();
        (0..self.grey.len())
            .into_par_iter()
            .map(|f| {
                let mut r = 0;
                if self.grey[f].mi != u32::MAX {
                    r |= RULE_GREY;
                }
                if self.sun_ray[f] {
                    r |= RULE_SUN_RAY;
                }
                let mi = self.optics.facet_material[f] as usize;
                if self.optics.materials[mi].double_sided
                    && self.conditions.surface.back_shape_factor(f).is_some()
                {
                    r |= RULE_BACK_SKY;
                }
                match ph.map(|p| p.rule(f, self.pixel_angle_rad)) {
                    Some(PerHitRule::Always) => r |= RULE_PER_HIT,
                    Some(PerHitRule::ByRange) => r |= RULE_PER_HIT_BY_RANGE,
                    Some(PerHitRule::Never) | None => {}
                }
                r
            })
            .collect()
    }

    /// The position of facet `f`'s front face on the tilt table of the
    /// reflected sky ([`tilt_position`]).
    pub fn facet_tilt(&self, f: usize) -> f32 {
        self.tilt[f]
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
}
