//! The render pipeline: scene → exposure and thermal state → primary rays →
//! radiance → sensor effects → image files.
//!
//! # How the parts fit
//! - [`shade`]: [`Shader`] evaluates the radiance of rays on each band's
//!   spectral grid — the "big equation" at every hit, with secondary rays
//!   for specular reflection and transmission — from the facets' thermal
//!   state ([`Conditions`], [`SurfaceState`]) and optics ([`SceneOptics`]).
//! - [`image`]: [`render_rows`] traces a sensor's primary rays row by row in
//!   packets ([`crate::trace::Coherence::Coherent`]), band-integrates and
//!   reduces the oversampling with the PSF into a [`RowBand`];
//!   [`finish`] applies the image-wide effects (MTF, NEdT noise,
//!   quantisation), computes apparent temperatures and builds the layers.
//! - [`tile`]: a render split into row bands (tile `K` of `N`), partial files
//!   and their assembly (`irsig merge`).
//! - [`session`]: the whole chain for a loaded scene file — the tracer built
//!   once, exposure and thermal state per image time, each sensor rendered
//!   and written ([`write_outputs`]: `NAME.exr`, `NAME.img`/`NAME.hdr`,
//!   `NAME.png`, all atomic).
//!
//! Results do not depend on the number of threads or on the tiling: rays
//! are traced in fixed rows, every value depends only on its own rays, and
//! noise streams are keyed by (seed, band, row).
//!
//! The one place that knows every stage: it takes a loaded scene and gives
//! image files. It must not know the command line (progress goes to a
//! [`crate::progress::Progress`] observer, errors name fields).

pub mod checks;
pub mod glint;
pub mod image;
pub mod path;
pub mod per_hit;
pub mod scene_thermal;
pub mod sections;
pub mod session;
pub mod shade;
pub mod state;
pub mod tile;

use std::path::{Path, PathBuf};

use serde::Deserialize;

pub use image::{
    Finished, MISS_TRUTH, POINT_LAYERS, RowBand, StageTimes, TRUTH_LAYERS, finish, finish_at,
    render_rows,
};
pub use shade::{
    Conditions, FastMiss, FastScratch, SceneOptics, ShadeOptions, Shader, Sky, SunInput,
    SurfaceState, TruthOut, clear_sky_dni_w_m2, surface_solar_spectrum,
};

use crate::output::{GeoOutputs, write_image_set_geo};
use crate::radiometry::Band;
use crate::sensor::Sensor;
use crate::{Error, Location, Result};

fn default_max_bounces() -> u32 {
    2
}
fn default_spectral_step_um() -> f64 {
    0.1
}
fn default_facet_samples() -> u32 {
    1
}
fn default_per_hit() -> bool {
    true
}
fn default_per_hit_size_px() -> f32 {
    per_hit::PerHitParams::default().size_px
}

/// The `render` section of a scene file (all fields optional).
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RenderConfig {
    /// Most secondary bounces (specular reflection, transmission) per
    /// primary ray (default 2).
    #[serde(default = "default_max_bounces")]
    pub max_bounces: u32,
    /// Spectral step of the band grids the radiance is evaluated on, µm
    /// (default 0.1: trapezoid error < 10⁻⁴ of the band radiance at 3–14 µm).
    #[serde(default = "default_spectral_step_um")]
    pub spectral_step_um: f64,
    /// Effective sky temperature, K (default: from the weather's downwelling
    /// longwave, `(E_sky/σ)^¼`).
    pub sky_temperature_k: Option<f64>,
    /// Sample points per facet edge for the solar and sky rays (default 1).
    #[serde(default = "default_facet_samples")]
    pub facet_samples: u32,
    /// Hemisphere sampling of the shape factor and background: text as
    /// [`crate::exposure::SkySampling`]'s `FromStr` (`stratified:N`,
    /// `dirsig`, `grid:DZxDA`); default `stratified:64`.
    #[serde(default)]
    #[schemars(schema_with = "sky_sampling_schema")]
    pub sky_sampling: crate::exposure::SkySampling,
    /// Also write each georeferenced image as a GeoTIFF, `STEM.tif`
    /// (default false; see [`write_outputs`]).
    #[serde(default)]
    pub geotiff: bool,
    /// Per-hit temperatures (default true): a hit on a facet whose
    /// exposure is not uniform, or that is large against the pixel
    /// footprint, gets the temperature of its own solar history
    /// ([`per_hit`]); false: every hit takes its facet's.
    #[serde(default = "default_per_hit")]
    pub per_hit: bool,
    /// The per-hit rule's "large": a facet whose sample spacing exceeds
    /// this many pixel footprints at the hit (default 16,
    /// [`per_hit::PerHitParams::size_px`]).
    #[serde(default = "default_per_hit_size_px")]
    pub per_hit_size_px: f32,
    /// Physics of the per-facet thermal inputs, each on by default; switch
    /// one off for side-by-side checks (`{"reflected_bounces": 0}`,
    /// `{"hemispherical_emissivity": false}`, …:
    /// [`scene_thermal::ThermalPhysics`]).
    #[serde(default)]
    pub thermal: scene_thermal::ThermalPhysics,
}

/// `render.sky_sampling` as written: `stratified:N`, `dirsig` or
/// `grid:DZxDA`.
fn sky_sampling_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
    schemars::json_schema!({
        "type": "string",
        "pattern": "^(dirsig|stratified:[0-9]+|grid:[0-9.]+x[0-9.]+)$",
        "default": "stratified:64",
        "description": "Hemisphere sampling of each facet's sky view: `stratified:N` (N jittered rays per face), `dirsig` (DIRSIG's 15°×30° grid) or `grid:DZxDA` (degrees)."
    })
}

impl Default for RenderConfig {
    fn default() -> Self {
        RenderConfig {
            max_bounces: default_max_bounces(),
            spectral_step_um: default_spectral_step_um(),
            sky_temperature_k: None,
            facet_samples: default_facet_samples(),
            sky_sampling: crate::exposure::SkySampling::default(),
            geotiff: false,
            per_hit: default_per_hit(),
            per_hit_size_px: default_per_hit_size_px(),
            thermal: scene_thermal::ThermalPhysics::default(),
        }
    }
}

impl RenderConfig {
    /// Parse the scene file's `render` section (`None`: defaults), naming
    /// `location` in errors.
    pub fn from_json(value: Option<&serde_json::Value>, location: &Location) -> Result<Self> {
        let Some(v) = value else {
            return Ok(RenderConfig::default());
        };
        let c: RenderConfig = sections::typed(
            v,
            location,
            "render",
            "an object with max_bounces, spectral_step_um, sky_temperature_k, facet_samples, \
             sky_sampling, geotiff, per_hit, per_hit_size_px, thermal",
        )?;
        let bad = |field: &str, msg: String| {
            Error::parse(location.clone().with_field(format!("render.{field}")), msg)
        };
        if c.max_bounces > 8 {
            return Err(bad(
                "max_bounces",
                format!("{}: expected 0 to 8", c.max_bounces),
            ));
        }
        if !(c.spectral_step_um.is_finite()
            && c.spectral_step_um > 0.0
            && c.spectral_step_um <= 1.0)
        {
            return Err(bad(
                "spectral_step_um",
                format!("{}: expected a step in (0, 1] µm", c.spectral_step_um),
            ));
        }
        if let Some(t) = c.sky_temperature_k {
            if !(t.is_finite() && t > 0.0 && t < 400.0) {
                return Err(bad(
                    "sky_temperature_k",
                    format!("{t}: expected a temperature in (0, 400) K"),
                ));
            }
        }
        if !(c.per_hit_size_px.is_finite() && c.per_hit_size_px > 0.0) {
            return Err(bad(
                "per_hit_size_px",
                format!(
                    "{}: expected a positive number of pixels",
                    c.per_hit_size_px
                ),
            ));
        }
        if !(1..=16).contains(&c.facet_samples) {
            return Err(bad(
                "facet_samples",
                format!("{}: expected 1 to 16", c.facet_samples),
            ));
        }
        c.thermal.validate().map_err(|e| match e {
            Error::Invalid { field, message } => bad(&format!("thermal.{field}"), message),
            other => other,
        })?;
        Ok(c)
    }
}

/// The spectral bands of `sensor` on grids of at most `step_um`; response
/// files are resolved against `base_dir` (the scene file's folder), errors
/// name `location` (the sensor in the scene file).
pub fn sensor_bands(
    sensor: &Sensor,
    base_dir: &Path,
    step_um: f64,
    location: &Location,
) -> Result<Vec<Band>> {
    sensor.resolve_bands(base_dir, step_um, location)
}

/// FNV-1a, 64 bit: a stable hash of the inputs, for tile consistency.
#[derive(Debug, Clone, Copy)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Feed bytes.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
    /// The hash.
    pub fn finish(&self) -> u64 {
        self.0
    }
    /// Continue from a previous [`Fnv::finish`].
    pub fn with_state(state: u64) -> Self {
        Fnv(state)
    }
}

/// The description written into the outputs (ENVI `description`): the
/// same for a render in one piece and its merged tiles.
pub fn description(scene: &Path, backend: &str, sensor: &str, time: &str) -> String {
    format!(
        "irsig render of {} ({backend}), sensor {sensor} at {time}",
        scene.display()
    )
}

/// The output files of image `stem` in `dir`.
pub fn output_paths(dir: &Path, stem: &str) -> [PathBuf; 4] {
    [
        dir.join(format!("{stem}.exr")),
        dir.join(format!("{stem}.img")),
        dir.join(format!("{stem}.hdr")),
        dir.join(format!("{stem}.png")),
    ]
}

/// Write a finished image into `dir`: `STEM.exr` (all layers), `STEM.img` +
/// `STEM.hdr` (ENVI, band radiances with centre wavelengths) and `STEM.png`
/// (quick-look of the apparent temperature), each atomically
/// ([`crate::output::write_image_set`]).
pub fn write_outputs(dir: &Path, stem: &str, f: &Finished, description: &str) -> Result<()> {
    write_outputs_geo(dir, stem, f, description, &GeoOutputs::default())
}

/// [`write_outputs`] with the image's georeference: in the ENVI header
/// (`map info`), and with `geo.geotiff` every layer also as `STEM.tif`
/// (a GeoTIFF; written only for a georeferenced image).
pub fn write_outputs_geo(
    dir: &Path,
    stem: &str,
    f: &Finished,
    description: &str,
    geo: &GeoOutputs,
) -> Result<()> {
    let spectral: Vec<(&str, f64)> = f
        .radiance_layers
        .iter()
        .map(String::as_str)
        .zip(f.wavelengths_um.iter().copied())
        .collect();
    let geo = GeoOutputs {
        georef: geo.georef.clone(),
        geotiff: geo.geotiff && geo.georef.is_some(),
    };
    write_image_set_geo(dir, stem, &f.stack, &spectral, description, &geo)?;
    Ok(())
}

/// What to write about where `sensor`'s image lies, for a scene at `site`:
/// its georeference where the geometry allows
/// ([`crate::sensor::georef::georeference`]) and, with `geotiff`, a GeoTIFF.
pub fn geo_outputs(sensor: &Sensor, site: &crate::sun::Site, geotiff: bool) -> GeoOutputs {
    GeoOutputs {
        georef: crate::sensor::georef::georeference(sensor, site),
        geotiff,
    }
}
