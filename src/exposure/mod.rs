//! Ray-traced per-facet inputs of the thermal model: solar history, shape
//! factor and background, for every facet of a scene.
//!
//! # What it owns, takes and gives
//! - Takes a [`SceneGeometry`], any [`Tracer`], per-facet double-sided
//!   flags and the sun's direction at each history step.
//! - Gives an [`Exposure`]: per facet, the sunlit fraction and cos-incidence
//!   history, the shape factor and the background (which facets its
//!   blocked hemisphere rays hit). Plus the time grid of the history
//!   ([`history_times`]) and the sun along it ([`sun_directions`]).
//! - It knows no thermal model: materials, temperatures and the scene
//!   solve live in `irsig::thermal::scene`, which reads these results as
//!   plain arrays; `irsig::render::scene_thermal` runs the two in turn.
//!
//! # How the parts fit
//! - [`FacetSamples`]: per-facet frame and `n²` stratified sample points
//!   (the ray origins), built once from the [`SceneGeometry`].
//! - [`solar_history`]: for each time step of the history window, one
//!   occlusion ray per sample point toward the sun → [`SolarHistory`]
//!   (`sun_fraction`, `cos_incidence` per facet and step).
//! - [`sky_view`]: hemisphere rays (DIRSIG's fixed 15°×30° grid or
//!   stratified cosine-weighted sampling, [`SkySampling`]) → [`SkyView`]:
//!   the shape factor F (view factor to the sky dome), its standard error,
//!   and the background — which facets the blocked rays hit, with weights
//!   ([`BackgroundEntry`]) — plus the weight of the ground beyond the scene.
//! - [`solar_rays`] / [`sky_rays`]: the rays those two trace for a batch
//!   of facets, in their order, and the coherence they declare
//!   ([`SOLAR_RAY_COHERENCE`], [`SKY_RAY_COHERENCE`]) — for benchmarks of
//!   the tracers on the exposure stage's own rays (`irsig bench trace`).
//! - [`reflected_shortwave`]: the sunlight reflected onto each facet by the
//!   facets and ground its hemisphere rays hit (radiosity over the
//!   background lists, per unit of the weather's irradiances) →
//!   [`ReflectedShortwave`]; it needs the facets' albedos, so the caller
//!   adds it ([`Exposure::with_reflected`]).
//! - [`compute_exposure`] runs all of it and times it ([`Exposure`]).
//! - [`history_times`] / [`sun_directions`]: the record times of the
//!   history window ([`HistoryWindow`], default 24 h at ≤ 15 min, on a grid
//!   anchored to the epoch; [`image_window`]: one image time's own records)
//!   and the
//!   sun's direction at each, computed once for the scene (NREL SPA).
//!
//! Rays go through any [`Tracer`] (Embree or obvhs) in batches of
//! [`ExposureParams::batch_facets`] facets, batches in parallel (rayon).
//! Every ray depends only on its facet, step and sample index (jitter is
//! seeded per facet), so results are identical for any thread count.
//!
//! # Example
//! ```no_run
//! # fn demo(tracer: &dyn irsig::trace::Tracer, geometry: &irsig::geometry::SceneGeometry) -> irsig::Result<()> {
//! use irsig::exposure::{ExposureParams, compute_exposure};
//! let sun = [glam::Vec3::new(0.0, -0.5, 0.866)]; // one step, sun 60° up in the south
//! let exp = compute_exposure(tracer, geometry, &[], &sun, &ExposureParams::default())?;
//! println!("F of facet 0 = {} ± {}", exp.sky.shape_factor[0], exp.sky.std_error[0]);
//! println!("sunlit fraction = {}", exp.solar.sun_fraction(0)[0]);
//! # Ok(()) }
//! ```

mod facets;
mod history;
pub mod reflected;
pub mod sampling;
mod sky;
mod solar;

use std::time::{Duration, Instant};

use glam::Vec3;

pub use crate::geometry::BackgroundEntry;
pub use facets::FacetSamples;
pub use history::{HistoryWindow, history_step, history_times, image_window, sun_directions};
pub use reflected::{ReflectedShortwave, reflected_shortwave};
pub use sky::{
    FacePatterns, RAY_COHERENCE as SKY_RAY_COHERENCE, SkySampling, SkyView,
    exposed_back_shape_factors, sky_rays, sky_view, sky_view_of,
};
pub use solar::{
    RAY_COHERENCE as SOLAR_RAY_COHERENCE, SolarHistory, solar_history, solar_history_of, solar_rays,
};

use crate::geometry::SceneGeometry;
use crate::trace::Tracer;
use crate::{Error, Result};

/// Parameters of the exposure computation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExposureParams {
    /// Sample points per facet edge `n`: `n²` points per facet (default 2).
    pub samples_per_edge: u32,
    /// Hemisphere sampling for the shape factor (default stratified, 64
    /// rays per face: [`SkySampling::default`]).
    pub sky: SkySampling,
    /// Ray-origin lift off the facet plane, relative to the scene's
    /// coordinate scale (default 1e-5: 1 cm for a 1 km scene).
    pub offset_rel: f32,
    /// Facets per tracer batch (default 512).
    pub batch_facets: usize,
    /// Seed of the stratified jitter.
    pub seed: u64,
    /// Solar history traced at every `solar_stride`-th step and refined
    /// where a sample point's visibility changes ([`solar_history`]);
    /// 1 traces every step (default 1).
    pub solar_stride: u32,
}

impl Default for ExposureParams {
    fn default() -> Self {
        ExposureParams {
            samples_per_edge: 2,
            sky: SkySampling::default(),
            offset_rel: 1e-5,
            batch_facets: 512,
            seed: 0x1A5E_5EED,
            solar_stride: 1,
        }
    }
}

/// Counts and timings of an exposure computation.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ExposureStats {
    /// Facets.
    pub facets: usize,
    /// Occlusion rays toward the sun.
    pub solar_rays: u64,
    /// Hemisphere rays.
    pub sky_rays: u64,
    /// Time to build sample points.
    pub setup: Duration,
    /// Time tracing the solar history.
    pub solar: Duration,
    /// Time tracing the sky view.
    pub sky: Duration,
    /// Time computing the reflected shortwave.
    pub reflected: Duration,
}

impl ExposureStats {
    /// Total time.
    pub fn total(&self) -> Duration {
        self.setup + self.solar + self.sky + self.reflected
    }
}

/// All ray-traced thermal inputs of a scene.
#[derive(Debug, Clone)]
pub struct Exposure {
    /// Facet frames and sample points.
    pub facets: FacetSamples,
    /// Sunlit fraction and cosine of incidence per facet and step.
    pub solar: SolarHistory,
    /// Shape factor and background per facet.
    pub sky: SkyView,
    /// Shortwave reflected onto each facet by what it sees
    /// ([`reflected_shortwave`]); empty until the caller, who knows the
    /// facets' albedos, computes it ([`Exposure::with_reflected`]).
    pub reflected: ReflectedShortwave,
    /// Counts and timings.
    pub stats: ExposureStats,
}

impl Exposure {
    /// Adds the reflected shortwave ([`reflected_shortwave`]) for the
    /// facets' `albedo`, the ground beyond the scene's `ground_albedo`, the
    /// sun directions the solar history was traced with and `bounces`
    /// bounces (0: none).
    ///
    /// # Errors
    /// As [`reflected_shortwave`].
    pub fn with_reflected(
        mut self,
        albedo: &[f32],
        ground_albedo: f32,
        sun_dirs: &[Vec3],
        bounces: u32,
    ) -> Result<Exposure> {
        let t0 = Instant::now();
        self.reflected = reflected_shortwave(
            &self.sky,
            &self.solar,
            albedo,
            ground_albedo,
            sun_dirs,
            bounces,
        )?;
        self.stats.reflected = t0.elapsed();
        Ok(self)
    }
}

/// Traces the solar history and sky view of every facet of `geometry`.
///
/// `double_sided` has one flag per facet (global facet order) or is empty
/// (all single-sided). `sun_dirs` are unit east-north-up vectors toward the
/// sun, one per time step of the history window, computed once for the
/// scene (e.g. from [`crate::sun`]); steps with `z ≤ 0` are night.
///
/// # Errors
/// [`Error::Invalid`] when `double_sided` has the wrong length, a sun
/// direction is not finite and unit-length, or a parameter is out of range.
pub fn compute_exposure<T: Tracer + ?Sized>(
    tracer: &T,
    geometry: &SceneGeometry,
    double_sided: &[bool],
    sun_dirs: &[Vec3],
    params: &ExposureParams,
) -> Result<Exposure> {
    let n = geometry.facet_count();
    if !double_sided.is_empty() && double_sided.len() != n {
        return Err(Error::invalid(
            "double_sided",
            format!(
                "expected one flag per facet ({n}) or none, got {}",
                double_sided.len()
            ),
        ));
    }
    if let Some((i, d)) = sun_dirs
        .iter()
        .enumerate()
        .find(|(_, d)| !d.is_finite() || (d.length() - 1.0).abs() > 1e-3)
    {
        return Err(Error::invalid(
            format!("sun_dirs[{i}]"),
            format!("expected a finite unit vector, got {d}"),
        ));
    }
    validate_params(params)?;
    let t0 = Instant::now();
    let facets = FacetSamples::new(
        geometry,
        double_sided,
        params.samples_per_edge,
        params.offset_rel,
    );
    let setup = t0.elapsed();
    let (solar, sky, mut stats) = exposure_of(tracer, &facets, sun_dirs, params, 0..n, &|_| {})?;
    stats.setup = setup;
    Ok(Exposure {
        facets,
        solar,
        sky,
        reflected: ReflectedShortwave::default(),
        stats,
    })
}

/// The solar history and sky view of the facets `range` of `facets` (one
/// shard of a scene), as [`compute_exposure`] traces them: a range that
/// starts on a multiple of [`ExposureParams::batch_facets`] gets the whole
/// scene's answers bit for bit. `done(n)` is called as each batch of `n`
/// facets is traced (solar history, then sky view: twice the range's
/// facets in all). The stats' `setup` is zero.
///
/// # Errors
/// As [`compute_exposure`] for the sun directions and parameters.
pub fn exposure_of<T: Tracer + ?Sized>(
    tracer: &T,
    facets: &FacetSamples,
    sun_dirs: &[Vec3],
    params: &ExposureParams,
    range: std::ops::Range<usize>,
    done: &(dyn Fn(u64) + Sync),
) -> Result<(SolarHistory, SkyView, ExposureStats)> {
    if let Some((i, d)) = sun_dirs
        .iter()
        .enumerate()
        .find(|(_, d)| !d.is_finite() || (d.length() - 1.0).abs() > 1e-3)
    {
        return Err(Error::invalid(
            format!("sun_dirs[{i}]"),
            format!("expected a finite unit vector, got {d}"),
        ));
    }
    validate_params(params)?;
    let t1 = Instant::now();
    let (solar, solar_rays) = solar_history_of(
        tracer,
        facets,
        sun_dirs,
        params.batch_facets,
        params.solar_stride,
        range.clone(),
        done,
    );
    let t2 = Instant::now();
    let (sky, sky_rays) = sky_view_of(
        tracer,
        facets,
        params.sky,
        params.seed,
        params.batch_facets,
        range.clone(),
        done,
    );
    let t3 = Instant::now();
    Ok((
        solar,
        sky,
        ExposureStats {
            facets: range.len(),
            solar_rays,
            sky_rays,
            setup: Duration::ZERO,
            solar: t2 - t1,
            sky: t3 - t2,
            reflected: Duration::ZERO,
        },
    ))
}

pub(crate) fn validate_params(p: &ExposureParams) -> Result<()> {
    if !(1..=16).contains(&p.samples_per_edge) {
        return Err(Error::invalid(
            "samples_per_edge",
            format!("expected 1 to 16, got {}", p.samples_per_edge),
        ));
    }
    if !(p.offset_rel.is_finite() && p.offset_rel > 0.0 && p.offset_rel < 1e-2) {
        return Err(Error::invalid(
            "offset_rel",
            format!(
                "expected a small positive number (e.g. 1e-5), got {}",
                p.offset_rel
            ),
        ));
    }
    if !(1..=96).contains(&p.solar_stride) {
        return Err(Error::invalid(
            "solar_stride",
            format!("expected 1 to 96 steps, got {}", p.solar_stride),
        ));
    }
    match p.sky {
        SkySampling::Grid {
            zenith_step_deg: z,
            azimuth_step_deg: a,
        } => {
            if !(z.is_finite()
                && (0.5..=90.0).contains(&z)
                && a.is_finite()
                && (0.5..=360.0).contains(&a))
            {
                return Err(Error::invalid(
                    "sky.grid",
                    format!(
                        "expected zenith step 0.5–90° and azimuth step 0.5–360°, got {z}° × {a}°"
                    ),
                ));
            }
        }
        SkySampling::Stratified { samples } => {
            if !(1..=1 << 20).contains(&samples) {
                return Err(Error::invalid(
                    "sky.samples",
                    format!("expected 1 to 1048576 rays per facet, got {samples}"),
                ));
            }
        }
    }
    Ok(())
}
