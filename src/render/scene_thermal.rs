//! The per-facet pipeline of a render: history window → sun directions →
//! rays ([`compute_exposure`]) → thermal passes
//! ([`solve_facet_temperatures`]) → temperatures at the image times.
//!
//! # What it owns, takes and gives
//! - Owns the order of the stages and the thermal side of a scene
//!   ([`FacetThermalSetup`]: which facets are solved with which property
//!   set, which are fixed, which lie on the ground).
//! - Takes a scene (or its geometry, weather, site and setup), the tracers
//!   ([`FacetTracers`]) and the image times; gives [`SceneThermal`]: every
//!   facet's temperature at the image times with the ray-traced inputs the
//!   shading reuses (sun fraction, incidence, shape factor, background).
//! - It is the one place that knows both [`crate::exposure`] (what the
//!   rays find) and [`crate::thermal::scene`] (what the slab model makes of
//!   it): neither of those knows the other. The [`Exposure`] reaches the
//!   thermal solve as plain arrays ([`SceneInputs`], `From<&Exposure>`).
//!   It knows nothing of sensors, shading or images.

use std::ops::Range;
use std::time::{Duration, Instant};

use chrono::{DateTime, FixedOffset, TimeDelta};
use rayon::prelude::*;

use crate::exposure::{
    Exposure, ExposureParams, ExposureStats, FacetSamples, HistoryWindow, SkyView, SolarHistory,
    exposed_back_shape_factors, exposure_of, history_step, history_times, image_window,
    sun_directions,
};
use crate::geometry::SceneGeometry;
use crate::progress::{NoProgress, Progress, Stage};
use crate::scene::Scene;
use crate::sun::Site;
use crate::thermal::scene::{
    FacetThermal, PassStats, PointResponse, SceneInputs, SceneTemperatures, SolarSource,
    ThermalParams, solve_facet_temperatures,
};
use crate::thermal::wind::{FacetWind, WindProfile};
use crate::thermal::{BackBoundary, Forcing, SlabProperties};
use crate::trace::{Coherence, Ray, Tracer};
use crate::weather::{WeatherHistory, WeatherRecord};
use crate::{Error, Location, Result};

// The exposure's night records are the thermal inputs' records without a
// reflected-shortwave slot.
const _: () = assert!(crate::exposure::reflected::NIGHT == crate::thermal::scene::NO_SLOT);

impl<'a> From<&'a Exposure> for SceneInputs<'a> {
    /// The exposure's per-facet results as the thermal solve's inputs
    /// (borrowed, no copies).
    fn from(e: &'a Exposure) -> Self {
        SceneInputs {
            records: e.solar.steps,
            solar: &e.solar,
            normal: &e.facets.normal,
            double_sided: &e.facets.double_sided,
            shape_factor: &e.sky.shape_factor,
            back_shape_factor: &e.sky.back_shape_factor,
            exposed_back_shape_factor: &[],
            ground_weight: &e.sky.ground_weight,
            background_offsets: &e.sky.offsets,
            background: &e.sky.entries,
            reflected_direct: &e.reflected.direct,
            reflected_slot: &e.reflected.slot,
            reflected_diffuse: &e.reflected.diffuse,
            wind: &[],
        }
    }
}

impl SolarSource for SolarHistory {
    fn records(&self) -> usize {
        self.steps
    }
    fn facets(&self) -> usize {
        self.facet_count()
    }
    fn sun_fraction_into(&self, facet: usize, out: &mut [f32]) {
        SolarHistory::sun_fraction_into(self, facet, out);
    }
    fn cos_incidence_into(&self, facet: usize, out: &mut [f32]) {
        SolarHistory::cos_incidence_into(self, facet, out);
    }
    /// Only the day records with lit sample points: elsewhere the product
    /// is zero (the sunlit fraction is), so the cosine is not needed.
    ///
    /// When the day records are one run and a count is one byte (fewer
    /// than 256 sample points: every render), the run is decoded without
    /// branches (a zero count gives `+0`, as the fill), so that it
    /// vectorises: the same operations as [`crate::geometry::sun_cosine`]
    /// and the general loop below, bit for bit.
    fn sunlit_cos_into(&self, facet: usize, out: &mut [f32]) {
        out.fill(0.0);
        let (normal, double_sided) = (self.normal[facet], self.double_sided[facet]);
        let m = self.points as f32;
        let nd = self.day.len();
        if let (Some(&first), Some(&last)) = (self.day.first(), self.day.last())
            && self.width() == 1
            && last as usize + 1 == first as usize + nd
        {
            // `day` ascends, so its records are `first..=last`.
            let r0 = first as usize;
            let lit = &self.lit[facet * nd..(facet + 1) * nd];
            let sun = &self.sun[r0..r0 + nd];
            for ((o, &k), v) in out[r0..r0 + nd].iter_mut().zip(lit).zip(sun) {
                let s = (k as f32 / m).clamp(0.0, 1.0);
                let c = (normal.x * v.x) + (normal.y * v.y) + (normal.z * v.z);
                let c = if v.z <= 0.0 {
                    0.0
                } else if double_sided || c > 0.0 {
                    c.abs().min(1.0)
                } else {
                    0.0
                };
                *o = s * c.max(0.0);
            }
            return;
        }
        for (d, &r) in self.day.iter().enumerate() {
            let lit = self.lit_points(facet, d);
            if lit != 0 {
                let s = (lit as f32 / m).clamp(0.0, 1.0);
                let c = crate::geometry::sun_cosine(normal, double_sided, self.sun[r as usize]);
                out[r as usize] = s * c.max(0.0);
            }
        }
    }
}

/// The records `window` (indices into the history, in order) of a solar
/// history: one image time's own window, read without copying the
/// history.
#[derive(Debug)]
struct SolarWindow<'a> {
    solar: &'a SolarHistory,
    window: &'a [usize],
}

impl SolarSource for SolarWindow<'_> {
    fn records(&self) -> usize {
        self.window.len()
    }
    fn facets(&self) -> usize {
        self.solar.facet_count()
    }
    fn sun_fraction_into(&self, facet: usize, out: &mut [f32]) {
        for (o, &r) in out.iter_mut().zip(self.window) {
            *o = self.solar.sun_fraction_at(facet, r);
        }
    }
    fn cos_incidence_into(&self, facet: usize, out: &mut [f32]) {
        for (o, &r) in out.iter_mut().zip(self.window) {
            *o = self.solar.cos_incidence_at(facet, r);
        }
    }
}

/// How each facet's temperature is obtained: the thermal side of a scene.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FacetThermalSetup {
    /// Per facet (global facet order): solved with a property set, or fixed.
    pub kinds: Vec<FacetThermal>,
    /// The property sets [`FacetThermal::Solve`] indexes.
    pub props: Vec<SlabProperties>,
    /// Per facet: both faces are front faces (thin objects); may be empty.
    pub double_sided: Vec<bool>,
    /// Per facet: a shape factor that replaces the traced one in the
    /// thermal solve (a part's `shape_factor` override); may be empty.
    pub shape_factor_override: Vec<Option<f32>>,
    /// Per facet: the shortwave albedo its neighbours receive reflected
    /// sunlight from, `1 − α − τ` of its material (solar absorptivity α,
    /// transmissivity τ; `1 − α` for opaque materials); may be empty
    /// (then `1 − α` of the property set, 0 for fixed facets).
    pub albedo: Vec<f32>,
}

impl FacetThermalSetup {
    /// The thermal side of a loaded scene: per part, its material with the
    /// part's overrides ([`Scene::part_material`]) as slab properties, or
    /// its fixed temperature; double-sided from the material; the part's
    /// shape-factor override.
    ///
    /// # Errors
    /// A material outside the slab model's domain, naming the scene file,
    /// the object and the part.
    pub fn from_scene(scene: &Scene) -> Result<Self> {
        FacetThermalSetup::from_scene_with(scene, &ThermalPhysics::default())
    }

    /// [`FacetThermalSetup::from_scene`] with the switches of `physics`
    /// (without [`ThermalPhysics::hemispherical_emissivity`], the property
    /// sets keep the materials' normal emissivity, for comparisons).
    ///
    /// # Errors
    /// As [`FacetThermalSetup::from_scene`].
    pub fn from_scene_with(scene: &Scene, physics: &ThermalPhysics) -> Result<Self> {
        let mut props = Vec::new();
        let mut part_kind = Vec::with_capacity(scene.parts.len());
        let mut part_ds = Vec::with_capacity(scene.parts.len());
        let mut part_albedo = Vec::with_capacity(scene.parts.len());
        for (i, p) in scene.parts.iter().enumerate() {
            let m = scene.part_material(i);
            part_ds.push(m.double_sided);
            part_albedo
                .push((1.0 - m.solar_absorptivity - m.transmissivity).clamp(0.0, 1.0) as f32);
            part_kind.push(match p.fixed_temperature_k {
                Some(t) => FacetThermal::Fixed(t as f32),
                None => {
                    let sp = SlabProperties::from_material(&m).map_err(|e| {
                        Error::parse(
                            Location::file(&scene.path).with_field(format!(
                                "object `{}`, part `{}`",
                                scene.objects[p.object].name, p.name
                            )),
                            e.to_string(),
                        )
                    })?;
                    let sp = if physics.hemispherical_emissivity {
                        sp
                    } else {
                        SlabProperties {
                            thermal_emissivity: m.thermal_emissivity,
                            ..sp
                        }
                    };
                    props.push(sp);
                    FacetThermal::Solve(props.len() as u32 - 1)
                }
            });
        }
        let parts = scene.facet_parts();
        let any_override = scene.parts.iter().any(|p| p.shape_factor.is_some());
        Ok(FacetThermalSetup {
            kinds: parts.iter().map(|&p| part_kind[p as usize]).collect(),
            props,
            double_sided: parts.iter().map(|&p| part_ds[p as usize]).collect(),
            albedo: parts.iter().map(|&p| part_albedo[p as usize]).collect(),
            shape_factor_override: if any_override {
                parts
                    .iter()
                    .map(|&p| scene.parts[p as usize].shape_factor.map(|f| f as f32))
                    .collect()
            } else {
                Vec::new()
            },
        })
    }
}

impl FacetThermalSetup {
    /// The facets that lie on the ground: solved with an insulated back
    /// (a material with `exposed_area` 0: pavements, soil, grass, sand —
    /// but also insulated roofs), facing up (normal `z ≥ 0.5`, slopes up to
    /// 60°), with nothing of the scene below them (a ray from the facet's
    /// centre straight down, started just under its plane, hits nothing).
    /// Roofs, decks and bridges have the terrain below them; the terrain and
    /// what lies on it do not.
    pub fn ground_facets<T: Tracer + ?Sized>(
        &self,
        tracer: &T,
        facets: &FacetSamples,
    ) -> Vec<bool> {
        self.ground_facets_of(tracer, facets, 0..facets.len())
    }

    /// [`FacetThermalSetup::ground_facets`] of the facets `range` only: one
    /// flag per facet of the range. Each facet's test is one ray of its
    /// own, so a range's flags are the whole scene's.
    pub fn ground_facets_of<T: Tracer + ?Sized>(
        &self,
        tracer: &T,
        facets: &FacetSamples,
        range: Range<usize>,
    ) -> Vec<bool> {
        let (start, n) = (range.start, range.end.min(facets.len()));
        let candidate: Vec<usize> = (start..n)
            .filter(|&f| match self.kinds.get(f) {
                Some(FacetThermal::Solve(pi)) => {
                    self.props[*pi as usize].back == BackBoundary::Insulated
                        && facets.normal[f].z >= 0.5
                }
                _ => false,
            })
            .collect();
        let rays: Vec<Ray> = candidate
            .iter()
            .map(|&f| {
                let pts = facets.facet_points(f);
                let c = pts.iter().copied().sum::<glam::Vec3>() / pts.len() as f32;
                // Just under the plane, so the facet itself is not hit.
                let origin = c - facets.normal[f] * facets.offset_m;
                Ray::new(origin, glam::Vec3::NEG_Z)
            })
            .collect();
        let mut hit = vec![false; rays.len()];
        rays.par_chunks(4096)
            .zip(hit.par_chunks_mut(4096))
            .for_each(|(r, o)| tracer.occluded(r, Coherence::Coherent, o));
        let mut ground = vec![false; n.saturating_sub(start)];
        for (&f, h) in candidate.iter().zip(hit) {
            ground[f - start] = !h;
        }
        ground
    }

    /// Per facet of `range`: whether its back face takes its own traced
    /// shape factor ([`FacetThermalSetup::exposed_back_shape_factor`]): a
    /// solved facet whose property set has an exposed back
    /// ([`BackBoundary::Exposed`]) and no shape-factor override (an
    /// override states the front's sky view, and the back keeps `1 − F` of
    /// it). One flag per facet of the scene, false outside `range`.
    pub fn exposed_backs(&self, n: usize, range: Range<usize>) -> Vec<bool> {
        let mut out = vec![false; n];
        let end = range.end.min(n);
        for (f, o) in out
            .iter_mut()
            .enumerate()
            .take(end)
            .skip(range.start.min(end))
        {
            *o = match self.kinds.get(f) {
                Some(FacetThermal::Solve(pi)) => {
                    matches!(self.props[*pi as usize].back, BackBoundary::Exposed { .. })
                        && self
                            .shape_factor_override
                            .get(f)
                            .is_none_or(|o| o.is_none())
                }
                _ => false,
            };
        }
        out
    }

    /// The back faces' own shape factors of the facets `range` whose back
    /// is exposed ([`FacetThermalSetup::exposed_backs`]; single-sided
    /// facets only, a double-sided facet's back face is in the sky view)
    /// ([`exposed_back_shape_factors`]: one more hemisphere of occlusion
    /// rays per such facet, the same rays for any split of the facets):
    /// one value per facet of `range` (`None`: the slab model's `1 − F`),
    /// and the rays traced.
    pub fn exposed_back_shape_factor<T: Tracer + ?Sized>(
        &self,
        tracer: &T,
        facets: &FacetSamples,
        params: &ExposureParams,
        range: Range<usize>,
    ) -> (Vec<Option<f32>>, u64) {
        let flags = self.exposed_backs(facets.len(), range.clone());
        if !flags.iter().any(|&b| b) {
            return (vec![None; range.len()], 0);
        }
        let (mut fb, rays) = exposed_back_shape_factors(
            tracer,
            facets,
            &flags,
            params.sky,
            params.seed,
            params.batch_facets,
        );
        (fb.drain(range).collect(), rays)
    }

    /// Per facet: its albedo ([`FacetThermalSetup::albedo`], or `1 − α`
    /// of its property set, 0 for a fixed facet).
    pub fn facet_albedo(&self) -> Vec<f32> {
        if !self.albedo.is_empty() {
            return self.albedo.clone();
        }
        self.kinds
            .iter()
            .map(|k| match k {
                FacetThermal::Solve(pi) => {
                    (1.0 - self.props[*pi as usize].solar_absorptivity).clamp(0.0, 1.0) as f32
                }
                FacetThermal::Fixed(_) => 0.0,
            })
            .collect()
    }

    /// This setup with the deep-ground back boundary
    /// ([`BackBoundary::GROUND`]) for the facets flagged in `ground` (the
    /// insulated property sets they use get a ground twin).
    pub fn with_ground(&self, ground: &[bool]) -> FacetThermalSetup {
        let mut out = self.clone();
        let mut twin: Vec<Option<u32>> = vec![None; self.props.len()];
        for (f, k) in out.kinds.iter_mut().enumerate() {
            if let FacetThermal::Solve(pi) = k
                && ground.get(f).copied().unwrap_or(false)
                && self.props[*pi as usize].back == BackBoundary::Insulated
            {
                let t = *twin[*pi as usize].get_or_insert_with(|| {
                    out.props
                        .push(self.props[*pi as usize].with_back(BackBoundary::GROUND));
                    out.props.len() as u32 - 1
                });
                *pi = t;
            }
        }
        out
    }
}

/// Parameters of [`solve_scene_temperatures`].
#[derive(Debug, Clone, PartialEq)]
pub struct SceneThermalParams {
    /// The history window.
    pub window: HistoryWindow,
    /// Ray tracing of the per-facet inputs.
    pub exposure: ExposureParams,
    /// The thermal passes.
    pub thermal: ThermalParams,
    /// Give the facets that lie on the ground the deep-ground back boundary
    /// ([`FacetThermalSetup::ground_facets`]). Default true; the scene
    /// study of `irsig::analysis` applies the same rule when it re-solves
    /// facets.
    pub ground: bool,
    /// Which physics of the per-facet inputs are on (all by default).
    pub physics: ThermalPhysics,
}

impl Default for SceneThermalParams {
    fn default() -> Self {
        SceneThermalParams {
            window: HistoryWindow::default(),
            exposure: ExposureParams::default(),
            thermal: ThermalParams::default(),
            ground: true,
            physics: ThermalPhysics::default(),
        }
    }
}

/// Physics of the per-facet thermal inputs that a scene may switch off for
/// side-by-side comparisons (the `render.thermal` section of a scene file;
/// `docs/physics/reflected-and-wind.md`). Reflected shortwave and the
/// hemispherical emissivity are on by default; the wind at each facet is
/// off until it is smooth between neighbours (see [`ThermalPhysics::facet_wind`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ThermalPhysics {
    /// Bounces of shortwave reflected between facets
    /// ([`crate::exposure::reflected`]; default
    /// [`crate::exposure::reflected::BOUNCES`]); 0 switches it off.
    pub reflected_bounces: u32,
    /// Albedo of the ground beyond the scene (default
    /// [`crate::exposure::reflected::GROUND_ALBEDO`]).
    pub ground_albedo: f32,
    /// Emit and absorb with the hemispherical emissivity of the renderer's
    /// angular model (default true); false keeps the materials' normal
    /// emissivity.
    pub hemispherical_emissivity: bool,
    /// Reduce the weather's wind to each facet's height and canyon
    /// ([`crate::thermal::wind`]); false (the default): the weather's wind
    /// at every facet. Off by default because the canyon factor comes from
    /// each facet's sampled sky view and the solve groups facets in wind
    /// classes of 0.02: on the town the roof and walls then speckle from
    /// facet to facet (steps of ≈ 0.2 K), a sampling artefact, not physics.
    pub facet_wind: bool,
    /// Roughness length of the site for the wind profile, m (default
    /// [`crate::thermal::wind::ROUGHNESS_M`]).
    pub roughness_m: f64,
}

impl Default for ThermalPhysics {
    fn default() -> Self {
        ThermalPhysics {
            reflected_bounces: crate::exposure::reflected::BOUNCES,
            ground_albedo: crate::exposure::reflected::GROUND_ALBEDO,
            hemispherical_emissivity: true,
            facet_wind: false,
            roughness_m: crate::thermal::wind::ROUGHNESS_M,
        }
    }
}

impl ThermalPhysics {
    /// All three off: the model before issue 19 (no reflected shortwave,
    /// normal emissivity, the weather's wind at every facet).
    pub const OFF: ThermalPhysics = ThermalPhysics {
        reflected_bounces: 0,
        ground_albedo: crate::exposure::reflected::GROUND_ALBEDO,
        hemispherical_emissivity: false,
        facet_wind: false,
        roughness_m: crate::thermal::wind::ROUGHNESS_M,
    };

    /// Checks the values, naming the field.
    ///
    /// # Errors
    /// [`Error::Invalid`] for more than 16 bounces, an albedo outside
    /// `[0, 1]` or a roughness length outside (0, 2 m).
    pub fn validate(&self) -> Result<()> {
        crate::thermal::wind::WindProfile {
            roughness_m: self.roughness_m,
        }
        .validate(crate::thermal::WIND_HEIGHT_M, crate::thermal::AIR_HEIGHT_M)?;
        if self.reflected_bounces > 16 {
            return Err(Error::invalid(
                "reflected_bounces",
                format!("{}: expected 0 to 16", self.reflected_bounces),
            ));
        }
        if !(0.0..=1.0).contains(&self.ground_albedo) {
            return Err(Error::invalid(
                "ground_albedo",
                format!("{}: expected a fraction in [0, 1]", self.ground_albedo),
            ));
        }
        Ok(())
    }
}

/// Timings of [`solve_scene_temperatures`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SceneThermalTimings {
    /// History grid, weather interpolation and sun positions.
    pub setup: Duration,
    /// Ray tracing (solar history and sky view).
    pub rays: Duration,
    /// Thermal stage: sunlight reflected between facets and the thermal
    /// passes.
    pub thermal: Duration,
    /// Of [`SceneThermalTimings::thermal`]: sunlight reflected between
    /// facets ([`crate::exposure::ReflectedShortwave`]).
    pub reflected: Duration,
}

impl SceneThermalTimings {
    /// Total.
    pub fn total(&self) -> Duration {
        self.setup + self.rays + self.thermal
    }
}

/// Temperatures and ray-traced inputs of every facet of a scene.
#[derive(Debug, Clone)]
pub struct SceneThermal {
    /// Record times of the history.
    pub times: Vec<DateTime<FixedOffset>>,
    /// The weather at each record time (interpolated).
    pub records: Vec<WeatherRecord>,
    /// Unit east-north-up vector toward the sun at each record time.
    pub sun_directions: Vec<glam::Vec3>,
    /// The image times, as given.
    pub image_times: Vec<DateTime<FixedOffset>>,
    /// Solar history, shape factors and background per facet.
    pub exposure: Exposure,
    /// Surface temperatures at the image times, with per-pass statistics.
    pub temperatures: SceneTemperatures,
    /// The thermal setup actually solved (with the ground facets' back
    /// boundary when [`SceneThermalParams::ground`]).
    pub setup: FacetThermalSetup,
    /// Facets solved with the deep-ground back boundary.
    pub ground_facets: usize,
    /// Per facet: the traced shape factor of its exposed back
    /// ([`FacetThermalSetup::exposed_back_shape_factor`]; `None`: not
    /// exposed, double-sided, or `1 − F`).
    pub exposed_back_shape_factor: Vec<Option<f32>>,
    /// Per image time: how its facets' temperatures respond to a point's
    /// own sunlit history (the linearised method only; per-hit
    /// temperatures, [`crate::render::per_hit`]).
    pub point_response: Vec<Option<ImageResponse>>,
    /// Where the time went.
    pub timings: SceneThermalTimings,
}

/// One image time's [`PointResponse`] over its own window.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageResponse {
    /// The window's records (indices into [`SceneThermal::times`]), the
    /// image time last: record `k` of a row is history record
    /// `records[k]`.
    pub records: Vec<usize>,
    /// The facets' responses at the image time (one image row each).
    pub response: PointResponse,
}

impl SceneThermal {
    /// Surface temperature of every facet at image time `image`, K.
    pub fn surface_temperature_k(&self, image: usize) -> &[f32] {
        &self.temperatures.surface_temperature_k[image]
    }
    /// Shape factor (sky view factor, front face) of every facet.
    pub fn shape_factor(&self) -> &[f32] {
        &self.exposure.sky.shape_factor
    }
    /// Sunlit fraction of every facet at image time `image`.
    pub fn sun_fraction(&self, image: usize) -> Vec<f32> {
        let r = self.temperatures.image_records[image];
        let s = &self.exposure.solar;
        (0..s.facet_count())
            .map(|f| s.sun_fraction_at(f, r))
            .collect()
    }
    /// Cosine of the solar incidence angle of every facet at image time
    /// `image` (0 at night or behind a single-sided facet).
    pub fn cos_incidence(&self, image: usize) -> Vec<f32> {
        let r = self.temperatures.image_records[image];
        let s = &self.exposure.solar;
        (0..s.facet_count())
            .map(|f| s.cos_incidence_at(f, r))
            .collect()
    }
    /// Background temperature of every facet at image time `image`, K: the
    /// radiative mean of the final temperatures of what its blocked
    /// hemisphere rays hit, with the ground beyond the scene at the air
    /// temperature ([`crate::exposure::SkyView::background_temperature`]).
    pub fn background_temperature_k(&self, image: usize) -> Vec<f32> {
        let r = self.temperatures.image_records[image];
        let air = self.records[r].air_temperature_k as f32;
        let t = self.surface_temperature_k(image);
        (0..t.len())
            .map(|f| self.exposure.sky.background_temperature(f, t, air))
            .collect()
    }
    /// Facets per second through the whole pipeline (rays + thermal).
    pub fn facets_per_second(&self) -> f64 {
        self.exposure.facets.len() as f64 / self.timings.total().as_secs_f64().max(1e-9)
    }
}

/// The tracers of the per-facet pipeline. A single tracer converts into
/// both (`solve_scene(&tracer, …)`).
#[derive(Clone, Copy)]
pub struct FacetTracers<'a> {
    /// The shadow and sky-view rays: from interior sample points in generic
    /// directions, so a non-watertight scene serves
    /// ([`crate::trace::Watertight::No`]).
    pub exposure: &'a dyn Tracer,
    /// The ground test's vertical rays through facet centres, which on a
    /// gridded scene (a roof's centre above a terrain grid line) can run
    /// exactly through a shared edge: a watertight scene, since one lost ray
    /// flips a facet's back boundary.
    pub exact: &'a dyn Tracer,
}

impl<'a> From<&'a dyn Tracer> for FacetTracers<'a> {
    fn from(t: &'a dyn Tracer) -> Self {
        FacetTracers {
            exposure: t,
            exact: t,
        }
    }
}

impl<'a, T: Tracer> From<&'a T> for FacetTracers<'a> {
    fn from(t: &'a T) -> Self {
        (t as &dyn Tracer).into()
    }
}

/// Every facet's surface temperature at `image_times`. This is what a
/// render calls. Stages:
/// 1. the history window: record times, weather and sun at each, the
///    records of the image times;
/// 2. the rays: solar history and sky view of every facet
///    ([`compute_exposure`]), with the setup's shape-factor overrides;
/// 3. the ground test ([`FacetThermalSetup::ground_facets`], when
///    [`SceneThermalParams::ground`]);
/// 4. the thermal passes ([`solve_facet_temperatures`]).
///
/// # Errors
/// Bad window, weather not covering it, bad site, mismatched setup lengths,
/// and the thermal solver's errors (naming the facet).
pub fn solve_scene_temperatures<'a>(
    tracers: impl Into<FacetTracers<'a>>,
    geometry: &SceneGeometry,
    setup: &FacetThermalSetup,
    weather: &WeatherHistory,
    site: &Site,
    image_times: &[DateTime<FixedOffset>],
    params: &SceneThermalParams,
) -> Result<SceneThermal> {
    solve_scene_temperatures_observed(
        tracers,
        geometry,
        setup,
        weather,
        site,
        image_times,
        params,
        &NoProgress,
    )
}

/// [`solve_scene_temperatures`], telling `progress` which stage runs
/// ([`Progress::item`]: the rays, the ground test, the thermal passes) and
/// advancing it by the facet count when done. The caller starts and
/// finishes the [`crate::progress::Stage::Thermal`] stage.
///
/// # Errors
/// As [`solve_scene_temperatures`].
#[allow(clippy::too_many_arguments)]
pub fn solve_scene_temperatures_observed<'a>(
    tracers: impl Into<FacetTracers<'a>>,
    geometry: &SceneGeometry,
    setup: &FacetThermalSetup,
    weather: &WeatherHistory,
    site: &Site,
    image_times: &[DateTime<FixedOffset>],
    params: &SceneThermalParams,
    progress: &dyn Progress,
) -> Result<SceneThermal> {
    solve_scene_inner(
        None,
        tracers.into(),
        geometry,
        setup,
        weather,
        site,
        image_times,
        params,
        progress,
    )
}

/// [`solve_scene_temperatures_observed`], where `owned`, when given, is
/// the exposure's tracer (it replaces `tracers.exposure`) and is dropped
/// once the rays are traced: the thermal passes, the stage's peak memory,
/// run without its BVH.
#[allow(clippy::too_many_arguments)]
fn solve_scene_inner(
    owned: Option<Box<dyn Tracer + '_>>,
    tracers: FacetTracers<'_>,
    geometry: &SceneGeometry,
    setup: &FacetThermalSetup,
    weather: &WeatherHistory,
    site: &Site,
    image_times: &[DateTime<FixedOffset>],
    params: &SceneThermalParams,
    progress: &dyn Progress,
) -> Result<SceneThermal> {
    let t0 = Instant::now();
    let history = History::new(weather, site, image_times, &params.window)?;
    let facets = facet_samples(geometry, setup, &params.exposure)?;
    let t1 = Instant::now();
    params.physics.validate()?;
    let n = facets.len();
    let rays = {
        let tracers = match owned.as_deref() {
            Some(exposure) => FacetTracers {
                exposure,
                exact: tracers.exact,
            },
            None => tracers,
        };
        trace_range(tracers, &facets, setup, &history, params, 0..n, progress)?
    };
    drop(owned);
    let t2 = Instant::now();
    let mut out = solve_traced(
        facets,
        setup,
        history,
        image_times,
        params,
        vec![rays],
        progress,
    )?;
    out.timings.setup = t1 - t0;
    out.timings.rays = t2 - t1;
    Ok(out)
}

/// The ray-traced inputs of the facets `range` of a scene: what one shard
/// of the split per-facet stage traces (rays and ground test) before the
/// thermal passes, which need every facet's.
#[derive(Debug, Clone, PartialEq)]
pub struct FacetRays {
    /// The facets, in global facet order.
    pub range: Range<usize>,
    /// Their solar history (every record of the history window).
    pub solar: SolarHistory,
    /// Their sky view (with the setup's shape-factor overrides); the
    /// background entries name facets by global id.
    pub sky: SkyView,
    /// Per facet of the range: it lies on the ground
    /// ([`FacetThermalSetup::ground_facets`]; all false when
    /// [`SceneThermalParams::ground`] is off).
    pub ground: Vec<bool>,
    /// Per facet of the range: the traced shape factor of its exposed
    /// back ([`FacetThermalSetup::exposed_back_shape_factor`]; `None`:
    /// `1 − F`).
    pub exposed_back_shape_factor: Vec<Option<f32>>,
    /// Ray counts and times.
    pub stats: ExposureStats,
}

/// The facet frames and sample points of the rays, checked against the
/// setup.
fn facet_samples(
    geometry: &SceneGeometry,
    setup: &FacetThermalSetup,
    params: &ExposureParams,
) -> Result<FacetSamples> {
    let n = geometry.facet_count();
    if !setup.double_sided.is_empty() && setup.double_sided.len() != n {
        return Err(Error::invalid(
            "double_sided",
            format!(
                "expected one flag per facet ({n}) or none, got {}",
                setup.double_sided.len()
            ),
        ));
    }
    if !setup.shape_factor_override.is_empty() && setup.shape_factor_override.len() != n {
        return Err(Error::invalid(
            "shape_factor_override",
            format!(
                "expected one entry per facet ({n}) or none, got {}",
                setup.shape_factor_override.len()
            ),
        ));
    }
    crate::exposure::validate_params(params)?;
    Ok(FacetSamples::new(
        geometry,
        &setup.double_sided,
        params.samples_per_edge,
        params.offset_rel,
    ))
}

/// Stages 2 and 3 for the facets `range`: their rays (solar history and
/// sky view, with the setup's shape-factor overrides) and their ground
/// test. Reports the items "solar history and sky view" (advancing by
/// each batch of facets, twice the range in all) and "ground test".
fn trace_range(
    tracers: FacetTracers<'_>,
    facets: &FacetSamples,
    setup: &FacetThermalSetup,
    history: &History,
    params: &SceneThermalParams,
    range: Range<usize>,
    progress: &dyn Progress,
) -> Result<FacetRays> {
    progress.start(Stage::Exposure, 2 * range.len() as u64);
    progress.item("solar history and sky view");
    let (solar, mut sky, mut stats) = exposure_of(
        tracers.exposure,
        facets,
        &history.sun,
        &params.exposure,
        range.clone(),
        &|n| progress.advance(n),
    )?;
    let t_back = Instant::now();
    let (exposed_back_shape_factor, back_rays) =
        setup.exposed_back_shape_factor(tracers.exposure, facets, &params.exposure, range.clone());
    stats.sky_rays += back_rays;
    stats.sky += t_back.elapsed();
    if !setup.shape_factor_override.is_empty() {
        for (i, o) in setup.shape_factor_override[range.clone()]
            .iter()
            .enumerate()
        {
            if let Some(v) = *o {
                sky.shape_factor[i] = v;
            }
        }
    }
    let ground = if params.ground {
        progress.item("ground test");
        setup.ground_facets_of(tracers.exact, facets, range.clone())
    } else {
        vec![false; range.len()]
    };
    progress.finish();
    Ok(FacetRays {
        range,
        solar,
        sky,
        ground,
        exposed_back_shape_factor,
        stats,
    })
}

/// Stage 4 on the traced inputs of every facet (`parts`: consecutive
/// ranges from facet 0 to the last), reporting the item "thermal solve".
/// The timings' `setup` and `rays` are left zero.
///
/// # Errors
/// Parts that do not cover the facets in order; as
/// [`solve_facet_temperatures`].
fn solve_traced(
    facets: FacetSamples,
    setup: &FacetThermalSetup,
    history: History,
    image_times: &[DateTime<FixedOffset>],
    params: &SceneThermalParams,
    parts: Vec<FacetRays>,
    progress: &dyn Progress,
) -> Result<SceneThermal> {
    let n = facets.len();
    let mut solar = SolarHistory::empty(&history.sun, facets.per_facet as u32);
    let mut sky = SkyView::default();
    let mut ground = Vec::with_capacity(n);
    let mut exposed_back = Vec::with_capacity(n);
    let mut stats = ExposureStats::default();
    let mut next = 0;
    for p in parts {
        if p.range.start != next
            || p.ground.len() != p.range.len()
            || p.exposed_back_shape_factor.len() != p.range.len()
            || p.sky.facet_count() != p.range.len()
            || p.solar.steps != solar.steps
            || p.solar.day != solar.day
            || p.solar.points != solar.points
            || p.solar.facet_count() != p.range.len()
            || p.solar.lit.len() != p.range.len() * solar.day.len() * solar.width()
        {
            return Err(Error::invalid(
                "facet rays",
                format!(
                    "the part of facets {}..{} ({} steps, {} with the sun up, {} sample points) \
                     does not follow facet {next} of a history of {} steps ({} with the sun up, \
                     {} sample points)",
                    p.range.start,
                    p.range.end,
                    p.solar.steps,
                    p.solar.day.len(),
                    p.solar.points,
                    solar.steps,
                    solar.day.len(),
                    solar.points
                ),
            ));
        }
        // The first part is moved, not copied: a scene traced in one piece
        // would otherwise hold its solar history and sky view twice here.
        if next == 0 {
            solar = p.solar;
            sky = p.sky;
            ground = p.ground;
            exposed_back = p.exposed_back_shape_factor;
        } else {
            solar.append(p.solar);
            sky.append(p.sky);
            ground.extend(p.ground);
            exposed_back.extend(p.exposed_back_shape_factor);
        }
        next = p.range.end;
        stats.solar_rays += p.stats.solar_rays;
        stats.sky_rays += p.stats.sky_rays;
        stats.solar += p.stats.solar;
        stats.sky += p.stats.sky;
    }
    if next != n {
        return Err(Error::invalid(
            "facet rays",
            format!("the parts cover facets 0..{next} of {n}"),
        ));
    }
    stats.facets = n;
    // Parts read from files carry no geometry: the cosine of incidence is
    // recomputed from the facets' normals and the sun.
    if solar.normal.len() != n {
        solar.normal = facets.normal.clone();
        solar.double_sided = facets.double_sided.clone();
    }
    solar.sun = history.sun.clone();
    let exposure = Exposure {
        facets,
        solar,
        sky,
        reflected: crate::exposure::ReflectedShortwave::default(),
        stats,
    };
    // Sunlight reflected between facets: from every facet's traced inputs,
    // so after all parts are in (no rays of its own); part of the thermal
    // stage.
    let t2 = Instant::now();
    progress.start(Stage::Thermal, n as u64);
    let exposure = if params.physics.reflected_bounces > 0 {
        progress.item("reflected shortwave");
        let albedo = setup.facet_albedo();
        exposure.with_reflected(
            &albedo,
            params.physics.ground_albedo,
            &history.sun,
            params.physics.reflected_bounces,
        )?
    } else {
        exposure
    };
    let reflected = t2.elapsed();
    let (setup, ground_facets) = if params.ground {
        let count = ground.iter().filter(|&&g| g).count();
        (setup.with_ground(&ground), count)
    } else {
        (setup.clone(), 0)
    };
    progress.item("thermal solve");
    let wind = if params.physics.facet_wind {
        facet_wind(&exposure, &history.forcing, params.physics.roughness_m)
    } else {
        Vec::new()
    };
    let (temperatures, point_response) = solve_windows(
        &exposure,
        &exposed_back,
        &wind,
        &setup,
        &history,
        &params.thermal,
    )?;
    progress.advance(n as u64);
    progress.finish();
    let t3 = Instant::now();
    Ok(SceneThermal {
        times: history.times,
        records: history.records,
        sun_directions: history.sun,
        image_times: image_times.to_vec(),
        exposure,
        temperatures,
        setup,
        ground_facets,
        exposed_back_shape_factor: exposed_back,
        point_response,
        timings: SceneThermalTimings {
            setup: Duration::ZERO,
            rays: Duration::ZERO,
            thermal: t3 - t2,
            reflected,
        },
    })
}

/// Stage 1: the history window's record times, the weather and the sun at
/// each, and the records of the image times.
struct History {
    /// Record times.
    times: Vec<DateTime<FixedOffset>>,
    /// The weather at each record (interpolated).
    records: Vec<WeatherRecord>,
    /// The same as the slab model's forcing.
    forcing: Forcing,
    /// Unit east-north-up vector toward the sun at each record.
    sun: Vec<glam::Vec3>,
    /// Record of each image time.
    image_records: Vec<usize>,
    /// Each image time's own window: its records, itself last.
    windows: Vec<Vec<usize>>,
}

impl History {
    /// # Errors
    /// Bad window, weather not covering it, bad site.
    fn new(
        weather: &WeatherHistory,
        site: &Site,
        image_times: &[DateTime<FixedOffset>],
        window: &HistoryWindow,
    ) -> Result<History> {
        let times = history_times(weather, image_times, window)?;
        let records = times
            .iter()
            .map(|&t| weather.at(t))
            .collect::<Result<Vec<_>>>()?;
        let forcing = Forcing::from_records(&records)?;
        let sun = sun_directions(site, &times)?;
        let image_records: Vec<usize> = image_times
            .iter()
            .map(|t| {
                times
                    .iter()
                    .position(|x| (*x - *t).abs() < TimeDelta::seconds(1))
                    .expect("image times are on the grid")
            })
            .collect();
        let step = history_step(weather, window);
        let windows = image_times
            .iter()
            .map(|&t| image_window(&times, t, image_times, window.length, step))
            .collect();
        Ok(History {
            times,
            records,
            forcing,
            sun,
            image_records,
            windows,
        })
    }
}

/// Stage 4: the thermal passes, over each image time's own window
/// ([`image_window`]), so that the temperatures at an image time do not
/// depend on the other times of a series (the slab model spins up on the
/// window's first day, and the linearised solve's references are taken over
/// the window). Image times with the same window share one solve; a single
/// image time whose window is the whole history solves on the exposure as
/// it is. Returns the temperatures with `image_records` indexing the whole
/// history, and the passes' statistics summed over the windows; and each
/// image time's point response over its window.
///
/// # Errors
/// As [`solve_facet_temperatures`].
fn solve_windows(
    exposure: &Exposure,
    exposed_back: &[Option<f32>],
    wind: &[FacetWind],
    setup: &FacetThermalSetup,
    history: &History,
    params: &ThermalParams,
) -> Result<(SceneTemperatures, Vec<Option<ImageResponse>>)> {
    let all = history.times.len();
    let mut out = SceneTemperatures {
        image_records: history.image_records.clone(),
        surface_temperature_k: vec![Vec::new(); history.windows.len()],
        passes: Vec::new(),
        point_response: None,
        unsettled_exchanges: Vec::new(),
    };
    let mut responses: Vec<Option<ImageResponse>> = vec![None; history.windows.len()];
    // The image time whose solve serves each image time (itself, or the
    // first with the same window): copied to the others after the loop,
    // so that a single window is never copied.
    let first_of: Vec<usize> = history
        .windows
        .iter()
        .map(|w| {
            history
                .windows
                .iter()
                .position(|v| v == w)
                .expect("a window is its own")
        })
        .collect();
    for (i, w) in history.windows.iter().enumerate() {
        if first_of[i] != i {
            continue;
        }
        let last = w.len() - 1;
        let r = if w.len() == all {
            let mut inputs = SceneInputs::from(exposure);
            inputs.wind = wind;
            inputs.exposed_back_shape_factor = exposed_back;
            solve_facet_temperatures(
                inputs,
                &setup.kinds,
                &setup.props,
                &history.forcing,
                &[last],
                params,
            )?
        } else {
            let solar = SolarWindow {
                solar: &exposure.solar,
                window: w,
            };
            // The window's records read the reflected coefficients where
            // the whole history holds them (no copy).
            let slot: Vec<u32> = if exposure.reflected.slot.is_empty() {
                Vec::new()
            } else {
                w.iter().map(|&r| exposure.reflected.slot[r]).collect()
            };
            let mut inputs = SceneInputs::from(exposure);
            inputs.records = w.len();
            inputs.solar = &solar;
            inputs.reflected_slot = &slot;
            inputs.wind = wind;
            inputs.exposed_back_shape_factor = exposed_back;
            let records: Vec<WeatherRecord> = w.iter().map(|&r| history.records[r]).collect();
            let forcing = Forcing::from_records(&records)?;
            solve_facet_temperatures(
                inputs,
                &setup.kinds,
                &setup.props,
                &forcing,
                &[last],
                params,
            )?
        };
        let pr = r.point_response.map(|response| ImageResponse {
            records: w.clone(),
            response,
        });
        let t = r
            .surface_temperature_k
            .into_iter()
            .next()
            .unwrap_or_default();
        add_passes(&mut out.passes, &r.passes);
        for (set, passes) in r.unsettled_exchanges {
            crate::thermal::scene::note_unsettled(&mut out.unsettled_exchanges, set, passes);
        }
        out.surface_temperature_k[i] = t;
        responses[i] = pr;
    }
    for (i, &j) in first_of.iter().enumerate() {
        if j != i {
            out.surface_temperature_k[i] = out.surface_temperature_k[j].clone();
            responses[i] = responses[j].clone();
        }
    }
    Ok((out, responses))
}

/// `warning:` texts for the property sets of `scene`'s thermal setup
/// ([`FacetThermalSetup::from_scene`]: one per part without a fixed
/// temperature, in part order) whose exchange's reference passes stopped on
/// their cap without settling (`temperatures`'
/// [`SceneTemperatures::unsettled_exchanges`]), each naming the material,
/// object and part, the residual and the passes.
pub fn unsettled_exchange_warnings(scene: &Scene, temperatures: &SceneTemperatures) -> Vec<String> {
    let solved: Vec<usize> = (0..scene.parts.len())
        .filter(|&i| scene.parts[i].fixed_temperature_k.is_none())
        .collect();
    temperatures
        .unsettled_exchanges
        .iter()
        .filter_map(|(set, passes)| {
            let name = match solved.get(*set) {
                Some(&i) => {
                    let part = &scene.parts[i];
                    format!(
                        "`{}` (object `{}`, part `{}`)",
                        scene.part_material(i).name,
                        scene.objects[part.object].name,
                        part.name
                    )
                }
                None => format!("of property set {set}"),
            };
            passes.warning(&name)
        })
        .collect()
}

/// The wind reduction of every facet ([`crate::thermal::wind`]): its
/// centre's height above the scene's lowest sample point, its tilt and its
/// mean sky view, under the site roughness `roughness_m`, the forcing's
/// measurement height and its air height as the lowest height.
pub fn facet_wind(exposure: &Exposure, forcing: &Forcing, roughness_m: f64) -> Vec<FacetWind> {
    let facets = &exposure.facets;
    let n = facets.len();
    let centre = |f: usize| {
        let p = facets.facet_points(f);
        p.iter().copied().sum::<glam::Vec3>() / p.len().max(1) as f32
    };
    let ground = (0..n)
        .flat_map(|f| facets.facet_points(f).iter().map(|p| p.z))
        .fold(f32::INFINITY, f32::min);
    let profile = WindProfile { roughness_m };
    (0..n)
        .into_par_iter()
        .map(|f| {
            FacetWind::new(
                &profile,
                (centre(f).z - ground) as f64,
                facets.normal[f].z as f64,
                exposure.sky.mean_shape_factor(f) as f64,
                forcing.wind_height_m,
                forcing.air_height_m,
            )
        })
        .collect()
}

/// Adds one window's pass statistics to the run's (work and time summed,
/// the worst convergence kept).
fn add_passes(total: &mut Vec<PassStats>, passes: &[PassStats]) {
    if total.is_empty() {
        total.extend_from_slice(passes);
        return;
    }
    for (t, p) in total.iter_mut().zip(passes) {
        t.solved_facets += p.solved_facets;
        t.classes += p.classes;
        t.reused_facets += p.reused_facets;
        t.setup += p.setup;
        t.solve += p.solve;
        t.max_spinup_change_k = t.max_spinup_change_k.max(p.max_spinup_change_k);
        t.max_change_from_previous_pass_k = match (
            t.max_change_from_previous_pass_k,
            p.max_change_from_previous_pass_k,
        ) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
    }
}

/// [`solve_scene_temperatures`] for a loaded scene at its image time: the
/// scene's geometry, parts, weather and site.
///
/// # Errors
/// A scene without a weather history (naming the scene file), and as
/// [`solve_scene_temperatures`].
pub fn solve_scene<'a>(
    tracers: impl Into<FacetTracers<'a>>,
    scene: &Scene,
    image_times: &[DateTime<FixedOffset>],
    params: &SceneThermalParams,
) -> Result<SceneThermal> {
    solve_scene_observed(tracers, scene, image_times, params, &NoProgress)
}

/// [`solve_scene`], reporting its stages to `progress` as
/// [`solve_scene_temperatures_observed`] does.
///
/// # Errors
/// As [`solve_scene`].
pub fn solve_scene_observed<'a>(
    tracers: impl Into<FacetTracers<'a>>,
    scene: &Scene,
    image_times: &[DateTime<FixedOffset>],
    params: &SceneThermalParams,
    progress: &dyn Progress,
) -> Result<SceneThermal> {
    let (weather, setup, times) = scene_parts(scene, image_times, params)?;
    solve_scene_temperatures_observed(
        tracers,
        &scene.geometry,
        &setup,
        weather,
        &scene.site,
        &times,
        params,
        progress,
    )
}

/// [`solve_scene_observed`] with the exposure's own tracer handed over
/// (`exposure`; `None`: `exact` traces every ray): it is dropped as soon
/// as the rays are traced, so that the thermal passes run without its BVH.
///
/// # Errors
/// As [`solve_scene`].
pub fn solve_scene_handing_over(
    exposure: Option<Box<dyn Tracer + '_>>,
    exact: &dyn Tracer,
    scene: &Scene,
    image_times: &[DateTime<FixedOffset>],
    params: &SceneThermalParams,
    progress: &dyn Progress,
) -> Result<SceneThermal> {
    let (weather, setup, times) = scene_parts(scene, image_times, params)?;
    solve_scene_inner(
        exposure,
        exact.into(),
        &scene.geometry,
        &setup,
        weather,
        &scene.site,
        &times,
        params,
        progress,
    )
}

/// The first half of [`solve_scene`] for the facets `range` only: their
/// rays and ground test, as the whole scene's solve traces them when the
/// range starts on a multiple of [`ExposureParams::batch_facets`]
/// (`crate::render::state` splits a scene so). Reports as
/// [`solve_scene_observed`] does, without the thermal solve.
///
/// # Errors
/// As [`solve_scene`], for the history and the rays.
pub fn trace_scene_facets<'a>(
    tracers: impl Into<FacetTracers<'a>>,
    scene: &Scene,
    image_times: &[DateTime<FixedOffset>],
    params: &SceneThermalParams,
    range: Range<usize>,
    progress: &dyn Progress,
) -> Result<FacetRays> {
    let (weather, setup, times) = scene_parts(scene, image_times, params)?;
    let history = History::new(weather, &scene.site, &times, &params.window)?;
    let facets = facet_samples(&scene.geometry, &setup, &params.exposure)?;
    let n = facets.len();
    if range.start > range.end || range.end > n {
        return Err(Error::invalid(
            "facet range",
            format!(
                "{}..{} is not within the scene's {n} facets",
                range.start, range.end
            ),
        ));
    }
    trace_range(
        tracers.into(),
        &facets,
        &setup,
        &history,
        params,
        range,
        progress,
    )
}

/// The second half of [`solve_scene`]: the thermal passes on the rays of
/// every facet, traced in parts ([`trace_scene_facets`]; consecutive
/// ranges from facet 0 to the last). With the parts of one scene, times
/// and parameters, the result is [`solve_scene`]'s bit for bit.
///
/// # Errors
/// Parts that do not cover the facets in order or hold another history
/// length; as [`solve_scene`].
pub fn solve_scene_traced(
    scene: &Scene,
    image_times: &[DateTime<FixedOffset>],
    params: &SceneThermalParams,
    parts: Vec<FacetRays>,
    progress: &dyn Progress,
) -> Result<SceneThermal> {
    let (weather, setup, times) = scene_parts(scene, image_times, params)?;
    let history = History::new(weather, &scene.site, &times, &params.window)?;
    let facets = facet_samples(&scene.geometry, &setup, &params.exposure)?;
    solve_traced(facets, &setup, history, &times, params, parts, progress)
}

/// A scene's weather history, thermal setup and image times (the scene's
/// time when `image_times` is empty).
fn scene_parts<'s>(
    scene: &'s Scene,
    image_times: &[DateTime<FixedOffset>],
    params: &SceneThermalParams,
) -> Result<(
    &'s WeatherHistory,
    FacetThermalSetup,
    Vec<DateTime<FixedOffset>>,
)> {
    let weather = scene.weather.as_ref().ok_or_else(|| {
        Error::parse(
            Location::file(&scene.path).with_field("weather"),
            "the thermal model needs a weather history; add `\"weather\": \"FILE\"`",
        )
    })?;
    let setup = FacetThermalSetup::from_scene_with(scene, &params.physics)?;
    let times: Vec<DateTime<FixedOffset>> = if image_times.is_empty() {
        vec![scene.time]
    } else {
        image_times.to_vec()
    };
    Ok((&weather.history, setup, times))
}
