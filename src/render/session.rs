//! The whole chain for a scene file: the library's front, re-exported at
//! the crate root.
//!
//! [`Session::open`] loads the scene (geometry, materials, weather), types
//! its `sensors`, `atmosphere` and `render` sections, and builds the tracer
//! once. [`Session::thermal`] computes every facet's thermal state at the
//! image times in one go (one spin-up for the whole series).
//! [`Session::render_rows`] renders rows of one sensor under one time's
//! conditions, [`Session::finish`] applies the image-wide sensor effects
//! and [`Session::write_image`] writes the files; [`Session::run`] loops
//! over times and sensors (whole images, or one tile of row bands each),
//! reporting to a [`Progress`] observer.
//!
//! Owns the session state and its [`Timings`]; takes a scene file and
//! [`RunOptions`], gives image files (or row bands and thermal states to a
//! caller that goes step by step). Knows nothing of the command line: no
//! argument parsing, no terminal output; errors name fields.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use chrono::{DateTime, FixedOffset};
use serde::Deserialize;

use super::image::{Finished, RowBand, StageTimes, finish_at, render_rows};
use super::path::PathTables;
use super::shade::{Conditions, SceneOptics, ShadeOptions, Shader, Sky, SunInput, SurfaceState};
use super::state::{FacetStates, FacetTimeState};
use super::tile::{TileInfo, tile_is_complete, tile_path, tile_rows, write_tile};
use super::{Fnv, RenderConfig, write_outputs_geo};
use crate::atmosphere::{
    Aerosol, AerosolModel, Atmosphere, BuiltinAtmosphere, Profile, SurfaceMet, Tape7Lut,
};
use crate::progress::{NoProgress, Progress, Stage};
use crate::radiometry::Band;
use crate::scene::Scene;
use crate::sensor::Sensor;
use crate::trace::{self, Backend, Tracer, Watertight};
use crate::weather::{WeatherHistory, WeatherRecord};
use crate::{Error, Location, Result};

/// The scene file's `atmosphere` section: a name (`"none"`, `"builtin"`,
/// `"standard"`, or an AFGL profile name such as `"tropical"`) or an object
/// with a `model` tag. Absent: [`AtmosphereConfig::Standard`] with the
/// profile chosen by the site and month ([`AtmosphereConfig::default`]).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(try_from = "serde_json::Value")]
pub enum AtmosphereConfig {
    /// No atmosphere between scene and sensor; a grey sky at the air
    /// temperature with the weather's downwelling longwave (`"none"`).
    None,
    /// The built-in layered model on its analytic profile (US 1976
    /// temperatures, exponential water vapour, no ozone), driven by the
    /// weather at the image time (`{"model": "builtin"}`).
    Builtin {
        /// CO₂ volume mixing ratio, ppmv (default 420).
        co2_ppmv: Option<f64>,
        /// Water-vapour scale height, m (default 2000).
        water_scale_height_m: Option<f64>,
        /// LOWTRAN 7's aerosol (`"aerosol"`, `"visibility_km"`); `None`:
        /// clear air (`"aerosol": "none"`). Default: rural, 23 km.
        aerosol: Option<Aerosol>,
        /// The scene names no `visibility_km`: the weather's visibility at
        /// the image time, where it has one, replaces the aerosol's
        /// ([`AtmosphereConfig::aerosol_at`]).
        weather_visibility: bool,
    },
    /// The built-in layered model on an AFGL model atmosphere, the weather
    /// at the image time blended into its lowest layers
    /// (`{"model": "standard", "profile": NAME}`; the default).
    Standard {
        /// The profile; `None`: chosen by the site's latitude and the month
        /// ([`Profile::for_site`]).
        profile: Option<Profile>,
        /// CO₂ volume mixing ratio, ppmv (default 420).
        co2_ppmv: Option<f64>,
        /// As for [`AtmosphereConfig::Builtin`].
        aerosol: Option<Aerosol>,
        /// As for [`AtmosphereConfig::Builtin`].
        weather_visibility: bool,
    },
    /// A table of MODTRAN tape7 runs, listed in an index JSON file (relative
    /// to the scene file).
    Tape7 {
        /// The index file.
        index: PathBuf,
    },
}

impl schemars::JsonSchema for AtmosphereConfig {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "AtmosphereConfig".into()
    }
    /// As [`AtmosphereConfig`]'s `TryFrom<Value>` reads it: a name, or an
    /// object tagged by `model`.
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let names: Vec<&str> = ["none", "builtin", "standard"]
            .into_iter()
            .chain(Profile::ALL.map(Profile::name))
            .collect();
        let profiles: Vec<&str> = Profile::ALL.map(Profile::name).to_vec();
        let aerosols: Vec<&str> = std::iter::once("none")
            .chain(AerosolModel::ALL.map(AerosolModel::name))
            .collect();
        let aerosol = serde_json::json!({ "type": "string", "enum": aerosols,
            "description": "LOWTRAN 7's boundary-layer aerosol (default rural); none: clear air" });
        let visibility = serde_json::json!({ "type": "number", "exclusiveMinimum": 0,
            "description": "visibility at the ground, km (default: the weather's at the image time where it has one, else 23; urban 5)" });
        schemars::json_schema!({
            "description": "The atmosphere between scene and sensor, and the sky. Absent: the built-in layered model on the AFGL profile of the site's latitude and the month.",
            "oneOf": [
                { "type": "string", "enum": names,
                  "description": "`none`, `builtin`, `standard` (profile by site and month) or an AFGL profile name" },
                { "type": "object", "additionalProperties": false, "required": ["model"],
                  "properties": { "model": { "const": "none" } } },
                { "type": "object", "additionalProperties": false, "required": ["model"],
                  "properties": {
                      "model": { "const": "builtin" },
                      "co2_ppmv": { "type": "number", "description": "CO₂ volume mixing ratio, ppmv (default 420)" },
                      "water_scale_height_m": { "type": "number", "description": "water-vapour scale height, m (default 2000)" },
                      "aerosol": aerosol, "visibility_km": visibility
                  } },
                { "type": "object", "additionalProperties": false, "required": ["model"],
                  "properties": {
                      "model": { "const": "standard" },
                      "profile": { "type": "string", "enum": profiles },
                      "co2_ppmv": { "type": "number", "description": "CO₂ volume mixing ratio, ppmv (default 420)" },
                      "aerosol": aerosol, "visibility_km": visibility
                  } },
                { "type": "object", "additionalProperties": false, "required": ["model", "index"],
                  "properties": {
                      "model": { "const": "tape7" },
                      "index": { "type": "string", "description": "index JSON of MODTRAN tape7 runs, relative to the scene file" }
                  } }
            ]
        })
    }
}

impl Default for AtmosphereConfig {
    /// The built-in model on the AFGL profile of the site and month.
    fn default() -> Self {
        AtmosphereConfig::Standard {
            profile: None,
            co2_ppmv: None,
            aerosol: Some(Aerosol::default()),
            weather_visibility: true,
        }
    }
}

/// The aerosol of a built-in atmosphere object from its `aerosol` and
/// `visibility_km`: absent, LOWTRAN's rural 23 km (a visibility alone sets
/// the rural aerosol's); `"none"`, clear air; a model without a visibility,
/// the model's default (LOWTRAN's: 23 km, urban 5 km).
fn aerosol_config(
    name: Option<&str>,
    visibility_km: Option<f64>,
) -> std::result::Result<Option<Aerosol>, String> {
    let model = match name {
        None => Some(AerosolModel::Rural),
        Some(n) => AerosolModel::from_name(n).map_err(|e| e.to_string())?,
    };
    match (model, visibility_km) {
        (None, Some(_)) => {
            Err("visibility_km: a visibility needs an aerosol, not \"aerosol\": \"none\"".into())
        }
        (None, None) => Ok(None),
        (Some(m), v) => Aerosol::new(m, v.unwrap_or(m.default_visibility_km()))
            .map(Some)
            .map_err(|e| e.to_string()),
    }
}

/// The object form of [`AtmosphereConfig`] as written.
#[derive(Deserialize)]
#[serde(tag = "model", rename_all = "snake_case", deny_unknown_fields)]
enum AtmosphereObject {
    None,
    Builtin {
        co2_ppmv: Option<f64>,
        water_scale_height_m: Option<f64>,
        aerosol: Option<String>,
        visibility_km: Option<f64>,
    },
    Standard {
        profile: Option<String>,
        co2_ppmv: Option<f64>,
        aerosol: Option<String>,
        visibility_km: Option<f64>,
    },
    Tape7 {
        index: PathBuf,
    },
}

impl TryFrom<serde_json::Value> for AtmosphereConfig {
    type Error = String;
    fn try_from(v: serde_json::Value) -> std::result::Result<Self, String> {
        let profile = |name: &str| Profile::from_name(name).map_err(|e| e.to_string());
        if let serde_json::Value::String(name) = &v {
            return Ok(match name.as_str() {
                "none" => AtmosphereConfig::None,
                "builtin" => AtmosphereConfig::Builtin {
                    co2_ppmv: None,
                    water_scale_height_m: None,
                    aerosol: Some(Aerosol::default()),
                    weather_visibility: true,
                },
                "standard" => AtmosphereConfig::default(),
                other => AtmosphereConfig::Standard {
                    profile: Some(profile(other).map_err(|_| {
                        let names = ["none", "builtin", "standard"]
                            .into_iter()
                            .chain(Profile::ALL.map(Profile::name));
                        format!(
                            "unknown atmosphere `{other}`: expected \"none\", \"builtin\", \
                             \"standard\" or a profile ({}){}",
                            Profile::ALL.map(Profile::name).join(", "),
                            crate::suggest::hint(other, names)
                        )
                    })?),
                    co2_ppmv: None,
                    aerosol: Some(Aerosol::default()),
                    weather_visibility: true,
                },
            });
        }
        Ok(
            match serde_json::from_value::<AtmosphereObject>(v)
                .map_err(|e| crate::suggest::with_suggestion(&e.to_string()))?
            {
                AtmosphereObject::None => AtmosphereConfig::None,
                AtmosphereObject::Builtin {
                    co2_ppmv,
                    water_scale_height_m,
                    aerosol,
                    visibility_km,
                } => AtmosphereConfig::Builtin {
                    co2_ppmv,
                    water_scale_height_m,
                    aerosol: aerosol_config(aerosol.as_deref(), visibility_km)?,
                    weather_visibility: visibility_km.is_none(),
                },
                AtmosphereObject::Standard {
                    profile: p,
                    co2_ppmv,
                    aerosol,
                    visibility_km,
                } => AtmosphereConfig::Standard {
                    profile: p.as_deref().map(profile).transpose()?,
                    co2_ppmv,
                    aerosol: aerosol_config(aerosol.as_deref(), visibility_km)?,
                    weather_visibility: visibility_km.is_none(),
                },
                AtmosphereObject::Tape7 { index } => AtmosphereConfig::Tape7 { index },
            },
        )
    }
}

impl AtmosphereConfig {
    /// The built-in model's aerosol at the time of the weather `record`
    /// (`None`: clear air, or no built-in model), and the record's
    /// visibility where it lay outside LOWTRAN's table and was clamped.
    ///
    /// Where the scene names no `visibility_km`, the record's visibility
    /// (the weather's at the image time, [`WeatherRecord::visibility_km`])
    /// replaces the model's default, clamped to
    /// [`crate::atmosphere::aerosol::VISIBILITY_TABLE_KM`]; a record without
    /// one keeps the default (23 km; urban 5 km). A scene's
    /// `visibility_km` always wins.
    pub fn aerosol_at(&self, record: &WeatherRecord) -> (Option<Aerosol>, Option<f64>) {
        match self {
            AtmosphereConfig::Builtin {
                aerosol: Some(a),
                weather_visibility,
                ..
            }
            | AtmosphereConfig::Standard {
                aerosol: Some(a),
                weather_visibility,
                ..
            } => {
                if *weather_visibility {
                    let (a, clamped) = a.with_observed_visibility(record.visibility_km);
                    (Some(a), clamped)
                } else {
                    (Some(*a), None)
                }
            }
            _ => (None, None),
        }
    }
}

/// `warning:` text for image times whose weather visibility lies outside
/// LOWTRAN 7's table and is clamped for the aerosol
/// ([`AtmosphereConfig::aerosol_at`]): one line naming the weather file,
/// the first such time and how many there are. `times` empty: the scene's.
pub fn visibility_warnings(session: &Session, times: &[DateTime<FixedOffset>]) -> Vec<String> {
    visibility_warnings_of(&session.scene, &session.atmosphere, &session.weather, times)
}

/// [`visibility_warnings`] for a scene not yet opened as a [`Session`]
/// (`irsig scene check`): its `atmosphere` section and weather history;
/// nothing where the section does not parse or there is no weather (those
/// are errors of [`super::checks::render_problems`]).
pub fn scene_visibility_warnings(scene: &Scene, times: &[DateTime<FixedOffset>]) -> Vec<String> {
    let (Ok(sections), Some(weather)) = (super::sections::parse(scene), scene.weather.as_ref())
    else {
        return Vec::new();
    };
    visibility_warnings_of(scene, &sections.atmosphere, &weather.history, times)
}

fn visibility_warnings_of(
    scene: &Scene,
    atmosphere: &AtmosphereConfig,
    weather: &WeatherHistory,
    times: &[DateTime<FixedOffset>],
) -> Vec<String> {
    let scene_time = [scene.time];
    let times = if times.is_empty() {
        &scene_time[..]
    } else {
        times
    };
    let clamped: Vec<(DateTime<FixedOffset>, f64, f64)> = times
        .iter()
        .filter_map(|t| {
            let rec = weather.at(*t).ok()?;
            let (a, c) = atmosphere.aerosol_at(&rec);
            Some((*t, c?, a?.visibility_km))
        })
        .collect();
    let Some(&(t, v, used)) = clamped.first() else {
        return Vec::new();
    };
    let file = scene.weather.as_ref().map_or_else(
        || "the weather".to_string(),
        |w| w.path.display().to_string(),
    );
    let (lo, hi) = crate::atmosphere::aerosol::VISIBILITY_TABLE_KM;
    vec![format!(
        "{file}: visibility {v} km at {} is outside LOWTRAN 7's aerosol table \
         ({lo}–{hi} km): the aerosol takes {used} km{}",
        t.to_rfc3339(),
        if clamped.len() > 1 {
            format!(" (and at {} more image times)", clamped.len() - 1)
        } else {
            String::new()
        }
    )]
}

/// The atmosphere of `scene` under `config` at one image time, driven by
/// the weather `record` (a tape7 table is read from its index file).
pub(crate) fn atmosphere_at(
    config: &AtmosphereConfig,
    scene: &Scene,
    record: &WeatherRecord,
) -> Result<Atmosphere> {
    Ok(match config {
        AtmosphereConfig::None => Atmosphere::None,
        AtmosphereConfig::Builtin {
            co2_ppmv,
            water_scale_height_m,
            ..
        } => {
            let mut p = crate::atmosphere::BuiltinParams {
                aerosol: config.aerosol_at(record).0,
                ..Default::default()
            };
            if let Some(c) = co2_ppmv {
                p.co2_ppmv = *c;
            }
            if let Some(w) = water_scale_height_m {
                p.water_scale_height_m = *w;
            }
            Atmosphere::Builtin(BuiltinAtmosphere::with_params(
                SurfaceMet::from_weather(record, scene.site.altitude_m),
                p,
            )?)
        }
        AtmosphereConfig::Standard {
            profile, co2_ppmv, ..
        } => {
            let profile = profile.unwrap_or_else(|| {
                use chrono::Datelike;
                Profile::for_site(scene.site.latitude_deg, record.time.month())
            });
            let mut p = crate::atmosphere::BuiltinParams {
                profile: Some(profile),
                aerosol: config.aerosol_at(record).0,
                ..Default::default()
            };
            if let Some(c) = co2_ppmv {
                p.co2_ppmv = *c;
            }
            Atmosphere::Builtin(BuiltinAtmosphere::with_params(
                SurfaceMet::from_weather(record, scene.site.altitude_m),
                p,
            )?)
        }
        AtmosphereConfig::Tape7 { index } => {
            let base = scene.path.parent().unwrap_or(Path::new("."));
            Atmosphere::Tape7Lut(Tape7Lut::read_index(base.join(index))?)
        }
    })
}

/// Options of a render run.
#[derive(Clone)]
pub struct RunOptions {
    /// Tracing backend.
    pub backend: Backend,
    /// Image times; empty: the scene's time.
    pub times: Vec<DateTime<FixedOffset>>,
    /// Render only tile `K` of `N` (1-based) into a partial file.
    pub tile: Option<(usize, usize)>,
    /// Noise seed overriding the sensors' own.
    pub seed: Option<u64>,
    /// Told how the run progresses ([`Stage::Exposure`],
    /// [`Stage::Thermal`], then [`Stage::Rows`]); `None`: nobody is told.
    pub progress: Option<Arc<dyn Progress>>,
    /// Only these sensors (by name); empty: all.
    pub sensors: Vec<String>,
    /// Read every facet's state from this state folder
    /// ([`super::state::read_states`]) instead of solving it; the folder
    /// must hold this scene's state at the run's times.
    pub state: Option<PathBuf>,
}

impl std::fmt::Debug for RunOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RunOptions")
            .field("backend", &self.backend)
            .field("times", &self.times)
            .field("tile", &self.tile)
            .field("seed", &self.seed)
            .field("progress", &self.progress.is_some())
            .field("sensors", &self.sensors)
            .field("state", &self.state)
            .finish()
    }
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            backend: Backend::Embree,
            times: Vec::new(),
            tile: None,
            seed: None,
            progress: None,
            sensors: Vec::new(),
            state: None,
        }
    }
}

/// Where the time of a run went (wall clock; the per-stage split of the
/// row loop is summed over threads and scaled to its wall time).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Timings {
    /// Loading the scene, materials and weather.
    pub load: Duration,
    /// Building the BVH.
    pub bvh_build: Duration,
    /// Per-facet rays and thermal solve (setup, rays, thermal passes).
    pub thermal: Duration,
    /// Of [`Timings::thermal`]: the thermal passes alone (the slab model
    /// over every facet, without the per-facet rays).
    pub thermal_solve: Duration,
    /// Of [`Timings::thermal_solve`]: sunlight reflected between facets.
    pub reflected_shortwave: Duration,
    /// Per image time and sensor: the shading tables (spectra, emissivity
    /// and Planck tables, band integrals, per-facet terms, path table).
    pub radiometry_setup: Duration,
    /// Primary-ray generation.
    pub ray_generation: Duration,
    /// Primary-ray tracing (packets).
    pub primary_trace: Duration,
    /// Radiometry of the primary rays that spawn no secondary rays: the
    /// big equation band-integrated, truth values.
    pub radiometry: Duration,
    /// Primary hits on specular or transmissive materials: secondary-ray
    /// tracing and the spectral radiometry of those hits.
    pub secondary: Duration,
    /// Sensor: PSF reduction, MTF, noise, quantisation, apparent temperature.
    pub sensor: Duration,
    /// Writing files.
    pub output: Duration,
    /// Primary rays traced.
    pub primary_rays: u64,
    /// Primary hits that spawned secondary rays.
    pub secondary_hits: u64,
}

impl Timings {
    /// Total.
    pub fn total(&self) -> Duration {
        self.load
            + self.bvh_build
            + self.thermal
            + self.radiometry_setup
            + self.ray_generation
            + self.primary_trace
            + self.radiometry
            + self.secondary
            + self.sensor
            + self.output
    }
}

/// A scene ready to render.
pub struct Session {
    /// The loaded scene.
    pub scene: Scene,
    /// The `render` section.
    pub config: RenderConfig,
    /// The sensors, in scene order.
    pub sensors: Vec<Sensor>,
    /// Each sensor's bands on the render's spectral grids.
    pub bands: Vec<Vec<Band>>,
    /// The weather history.
    pub weather: WeatherHistory,
    /// The tracer.
    pub tracer: Box<dyn Tracer>,
    /// Backend used.
    pub backend: Backend,
    /// Per-facet optics.
    pub optics: SceneOptics,
    atmosphere: AtmosphereConfig,
    hash: u64,
    file_hash: u64,
    /// Timings so far.
    pub timings: Timings,
    /// Warnings of the thermal solves so far, each once (for a
    /// `warning:` line): the materials whose exchange with the air did
    /// not settle ([`super::scene_thermal::unsettled_exchange_warnings`]).
    pub warnings: Vec<String>,
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("scene", &self.scene.path)
            .field("sensors", &self.sensors.len())
            .field("backend", &self.backend)
            .finish()
    }
}

/// The per-facet thermal state at each image time.
#[derive(Debug, Clone)]
pub struct ThermalStates {
    /// The image times.
    pub times: Vec<DateTime<FixedOffset>>,
    /// Per time: the conditions the shading needs.
    pub conditions: Vec<Conditions>,
    /// Per time: the weather record.
    pub records: Vec<WeatherRecord>,
    /// Where the scene-wide solve's time went (history setup, per-facet
    /// rays, thermal passes).
    pub timings: super::scene_thermal::SceneThermalTimings,
}

impl Session {
    /// Load `scene_path` and build the tracer with `backend`.
    pub fn open(scene_path: &Path, backend: Backend) -> Result<Session> {
        let t0 = Instant::now();
        let scene = Scene::load(scene_path)?;
        Self::from_scene(scene, backend, t0)
    }

    /// [`Session::open`] for a scene already loaded (so that its
    /// [`Scene::warnings`] can be shown before the render sections are
    /// checked). `t0` is when loading began (the load time in [`Timings`]).
    ///
    /// # Errors
    /// As [`Session::open`], for everything after reading the scene file.
    pub fn from_scene(scene: Scene, backend: Backend, t0: Instant) -> Result<Session> {
        Self::from_scene_observed(scene, backend, t0, &NoProgress)
    }

    /// [`Session::open`], reporting [`Stage::Load`] and [`Stage::Bvh`] to
    /// `progress`.
    ///
    /// # Errors
    /// As [`Session::open`].
    pub fn open_observed(
        scene_path: &Path,
        backend: Backend,
        progress: &dyn Progress,
    ) -> Result<Session> {
        let t0 = Instant::now();
        let scene = Self::load_scene_observed(scene_path, progress)?;
        Self::from_scene_observed(scene, backend, t0, progress)
    }

    /// [`Scene::load`], reporting [`Stage::Load`] to `progress` (for a
    /// caller that looks at the scene before [`Session::from_scene_observed`]).
    ///
    /// # Errors
    /// As [`Scene::load`].
    pub fn load_scene_observed(scene_path: &Path, progress: &dyn Progress) -> Result<Scene> {
        progress.start(Stage::Load, 0);
        let scene = Scene::load(scene_path);
        progress.finish();
        scene
    }

    /// [`Session::from_scene`], reporting [`Stage::Bvh`] to `progress`.
    ///
    /// # Errors
    /// As [`Session::from_scene`].
    pub fn from_scene_observed(
        scene: Scene,
        backend: Backend,
        t0: Instant,
        progress: &dyn Progress,
    ) -> Result<Session> {
        let scene_path = scene.path.clone();
        let scene_path = scene_path.as_path();
        let file = Location::file(scene_path);
        let super::sections::Sections {
            config,
            atmosphere,
            sensors,
            bands,
        } = super::sections::parse(&scene)?;
        let weather_ref = scene.weather.as_ref().ok_or_else(|| {
            Error::parse(
                file.clone().with_field("weather"),
                "missing: a render needs a weather history (`\"weather\": {\"file\": …}`)",
            )
        })?;
        let weather = weather_ref.history.clone();
        // Optics: one material per part (overrides applied).
        let parts = scene.facet_parts();
        let materials = (0..scene.parts.len())
            .map(|p| scene.part_material(p))
            .collect();
        let facet_object = parts
            .iter()
            .map(|&p| scene.parts[p as usize].object as u32)
            .collect();
        let optics = SceneOptics {
            materials,
            facet_material: parts,
            facet_object,
        };
        // Hash of everything the images depend on.
        let mut h = Fnv::default();
        let text = std::fs::read(scene_path).map_err(|e| Error::io(scene_path, e))?;
        h.write(&text);
        let mut fh = Fnv::default();
        fh.write(&text);
        h.write(&std::fs::read(&weather_ref.path).map_err(|e| Error::io(&weather_ref.path, e))?);
        h.write(format!("{:?}", optics.materials).as_bytes());
        h.write(format!("{:?}", scene.geometry.bounds()).as_bytes());
        h.write(&scene.geometry.facet_count().to_le_bytes());
        h.write(env!("CARGO_PKG_VERSION").as_bytes());
        let load = t0.elapsed();
        let t1 = Instant::now();
        progress.start(Stage::Bvh, 0);
        let tracer = trace::build(&scene.geometry, backend);
        progress.finish();
        let tracer = tracer?;
        let bvh_build = t1.elapsed();
        Ok(Session {
            scene,
            config,
            sensors,
            bands,
            weather,
            tracer,
            backend,
            optics,
            atmosphere,
            hash: h.finish(),
            file_hash: fh.finish(),
            timings: Timings {
                load,
                bvh_build,
                ..Timings::default()
            },
            warnings: Vec::new(),
        })
    }

    /// The atmosphere at one image time (the scene's configuration driven
    /// by the weather `record`).
    pub(crate) fn atmosphere_at(&self, record: &WeatherRecord) -> Result<Atmosphere> {
        atmosphere_at(&self.atmosphere, &self.scene, record)
    }

    /// The thermal state of every facet at each of `times` (one exposure
    /// computation and one thermal spin-up for the whole series).
    pub fn thermal(&mut self, times: &[DateTime<FixedOffset>]) -> Result<ThermalStates> {
        self.thermal_observed(times, &NoProgress)
    }

    /// [`Session::thermal`], reporting to `progress` the stages
    /// [`Stage::Exposure`] (the rays, advanced per batch of facets, and
    /// the ground test) and [`Stage::Thermal`] (the thermal passes).
    ///
    /// # Errors
    /// As [`Session::thermal`].
    pub fn thermal_observed(
        &mut self,
        times: &[DateTime<FixedOffset>],
        progress: &dyn Progress,
    ) -> Result<ThermalStates> {
        let own = self.exposure_tracer()?;
        let t0 = Instant::now();
        let (states, warnings) = scene_thermal(self, own, times, progress)?;
        self.note_warnings(warnings);
        self.timings.thermal += t0.elapsed();
        self.timings.thermal_solve += states.timings.thermal;
        self.timings.reflected_shortwave += states.timings.reflected;
        Ok(states)
    }

    /// Every facet's state at `times` (the scene's time when empty), solved
    /// in one go as [`Session::thermal_observed`] does: what a state folder
    /// holds ([`super::state`]).
    ///
    /// # Errors
    /// As [`Session::thermal`].
    pub fn facet_states(
        &mut self,
        times: &[DateTime<FixedOffset>],
        progress: &dyn Progress,
    ) -> Result<FacetStates> {
        let times = if times.is_empty() {
            vec![self.scene.time]
        } else {
            times.to_vec()
        };
        let own = self.exposure_tracer()?;
        let t0 = Instant::now();
        let params = solve_params(self);
        let solved = super::scene_thermal::solve_scene_handing_over(
            own,
            self.tracer.as_ref(),
            &self.scene,
            &times,
            &params,
            progress,
        )?;
        let states = self.facet_states_of(&solved, &times)?;
        self.note_warnings(super::scene_thermal::unsettled_exchange_warnings(
            &self.scene,
            &solved.temperatures,
        ));
        self.timings.thermal += t0.elapsed();
        self.timings.thermal_solve += solved.timings.thermal;
        self.timings.reflected_shortwave += solved.timings.reflected;
        Ok(states)
    }

    /// Adds the warnings not yet noted to [`Session::warnings`].
    pub(crate) fn note_warnings(&mut self, warnings: Vec<String>) {
        for w in warnings {
            if !self.warnings.contains(&w) {
                self.warnings.push(w);
            }
        }
    }

    /// The tracer for the exposure's rays (solar history, sky view): rays
    /// from interior sample points in generic directions, which need no
    /// watertight tests ([`Watertight::No`]; the ground test stays on
    /// [`Session::tracer`], see [`super::scene_thermal::FacetTracers`]). A second Embree scene
    /// over the same geometry (built in about the time of the first, and
    /// dropped by the caller), whose shadow rays are ≈ 1.4× faster; `None`
    /// with obvhs, whose tests are the same either way. Its build time
    /// counts as BVH build.
    pub fn exposure_tracer(&mut self) -> Result<Option<Box<dyn Tracer>>> {
        if self.backend == Backend::Obvhs {
            return Ok(None);
        }
        let t0 = Instant::now();
        let tracer = trace::build_with(&self.scene.geometry, self.backend, Watertight::No)?;
        self.timings.bvh_build += t0.elapsed();
        Ok(Some(tracer))
    }

    /// Output file stem of `sensor` at time `time` (`series`: more than one
    /// time in the run).
    pub fn stem(sensor: &Sensor, time: &DateTime<FixedOffset>, series: bool) -> String {
        if series {
            format!("{}_{}", sensor.name, time.format("%Y%m%dT%H%M%S"))
        } else {
            sensor.name.clone()
        }
    }

    /// Tile metadata of `sensor` (index) at `time`.
    fn tile_info(
        &self,
        s: usize,
        stem: &str,
        time: &DateTime<FixedOffset>,
        (k, n): (usize, usize),
        seed: u64,
    ) -> TileInfo {
        let sensor = &self.sensors[s];
        let rows = tile_rows(k, n, sensor.height());
        let mut h = Fnv::with_state(self.hash);
        h.write(sensor.name.as_bytes());
        h.write(time.to_rfc3339().as_bytes());
        h.write(&seed.to_le_bytes());
        h.write(self.backend.as_str().as_bytes());
        // The render settings as used (the command line may override the
        // scene file's).
        h.write(format!("{:?}", self.config).as_bytes());
        TileInfo {
            version: 1,
            scene_hash: format!("{:016x}", h.finish()),
            scene_file_hash: format!("{:016x}", self.file_hash),
            scene: std::path::absolute(&self.scene.path).unwrap_or(self.scene.path.clone()),
            sensor: sensor.name.clone(),
            stem: stem.to_string(),
            time: time.to_rfc3339(),
            tile: k,
            tiles: n,
            width: sensor.width(),
            height: sensor.height(),
            row_start: rows.start,
            row_end: rows.end,
            bands: sensor.bands.iter().map(|b| b.name.clone()).collect(),
            seed,
            backend: self.backend.as_str().to_string(),
        }
    }

    /// Render rows `rows` of sensor `s` under `cond`.
    pub fn render_rows(
        &mut self,
        s: usize,
        cond: &Conditions,
        rows: std::ops::Range<usize>,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<RowBand> {
        let sensor = &self.sensors[s];
        let bands = &self.bands[s];
        let size = self
            .scene
            .geometry
            .bounds()
            .map(|(lo, hi)| (hi - lo).length())
            .unwrap_or(1.0);
        let opts = ShadeOptions {
            max_bounces: self.config.max_bounces,
            offset_m: (1e-5 * size).max(1e-4),
        };
        let t_setup = Instant::now();
        let paths = PathTables::new(
            &cond.atmosphere,
            sensor,
            bands,
            self.scene.site.altitude_m,
            size as f64,
            super::path::scene_heights(&self.scene.geometry),
            super::path::PathSun::for_scene(cond.sun.as_ref()).as_ref(),
        )?;
        let shader = Shader::new(
            self.tracer.as_ref(),
            &self.scene.geometry,
            &self.optics,
            cond,
            bands,
            opts,
        )?
        .with_path(paths)
        .with_pixel_angle(sensor.pixel_angle_rad());
        self.timings.radiometry_setup += t_setup.elapsed();
        let times = StageTimes::default();
        let t0 = Instant::now();
        let band = render_rows(&shader, sensor, rows, &times, progress)?;
        let wall = t0.elapsed();
        // Split the loop's wall time by the threads' shares.
        let parts = [
            times.ray_generation(),
            times.primary_trace(),
            times.shading(),
            times.secondary(),
            times.reduction(),
        ];
        let sum: f64 = parts
            .iter()
            .map(|d| d.as_secs_f64())
            .sum::<f64>()
            .max(1e-12);
        let loop_wall = wall.saturating_sub(times.psf()).as_secs_f64();
        let share = |d: Duration| Duration::from_secs_f64(loop_wall * d.as_secs_f64() / sum);
        self.timings.ray_generation += share(parts[0]);
        self.timings.primary_trace += share(parts[1]);
        self.timings.radiometry += share(parts[2]);
        self.timings.secondary += share(parts[3]);
        // The PSF: the box reduction in the row loop, other PSFs after it.
        self.timings.sensor += share(parts[4]) + times.psf();
        let load = |c: &std::sync::atomic::AtomicU64| c.load(std::sync::atomic::Ordering::Relaxed);
        self.timings.primary_rays += load(&times.primary_rays);
        self.timings.secondary_hits += load(&times.secondary_hits);
        Ok(band)
    }

    /// Apply the image-wide effects to a full row band of sensor `s`.
    pub fn finish(&mut self, s: usize, band: RowBand, seed: u64) -> Result<Finished> {
        let t0 = Instant::now();
        let f = finish_at(
            band,
            &self.sensors[s],
            &self.bands[s],
            seed,
            Some(&self.scene.site),
        )?;
        self.timings.sensor += t0.elapsed();
        Ok(f)
    }

    /// The index of the sensor called `name`.
    ///
    /// # Errors
    /// [`Error::Invalid`] for field `sensor`, listing the scene's sensors.
    pub fn sensor_index(&self, name: &str) -> Result<usize> {
        self.sensors
            .iter()
            .position(|s| s.name == name)
            .ok_or_else(|| {
                Error::invalid(
                    "sensor",
                    format!(
                        "`{name}`: no such sensor{} (the scene has {})",
                        crate::suggest::hint(name, self.sensors.iter().map(|s| s.name.as_str())),
                        self.sensors
                            .iter()
                            .map(|s| s.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })
    }

    /// Write the finished image of sensor `s` at `time` into `out_dir` as
    /// `STEM.exr`, `STEM.img` + `STEM.hdr` (ENVI) and `STEM.png`, described
    /// by the scene file's absolute path, the backend, sensor and time.
    /// Counts as output time.
    pub fn write_image(
        &mut self,
        out_dir: &Path,
        stem: &str,
        s: usize,
        time: &DateTime<FixedOffset>,
        image: &Finished,
    ) -> Result<()> {
        let t0 = Instant::now();
        let scene = std::path::absolute(&self.scene.path).unwrap_or(self.scene.path.clone());
        let desc = super::description(
            &scene,
            self.backend.as_str(),
            &self.sensors[s].name,
            &time.to_rfc3339(),
        );
        let geo = super::geo_outputs(&self.sensors[s], &self.scene.site, self.config.geotiff);
        write_outputs_geo(out_dir, stem, image, &desc, &geo)?;
        self.timings.output += t0.elapsed();
        Ok(())
    }

    /// Render every (selected) sensor at every time into `out_dir`: whole
    /// images (`STEM.exr`, `.img`/`.hdr`, `.png`), or with `options.tile`
    /// one tile file each (skipped when already complete). Returns the
    /// stems written or skipped.
    pub fn run(&mut self, out_dir: &Path, options: &RunOptions) -> Result<Vec<String>> {
        std::fs::create_dir_all(out_dir).map_err(|e| Error::io(out_dir, e))?;
        for name in &options.sensors {
            self.sensor_index(name)?;
        }
        let times = if options.times.is_empty() {
            vec![self.scene.time]
        } else {
            options.times.clone()
        };
        let series = times.len() > 1;
        let chosen: Vec<usize> = (0..self.sensors.len())
            .filter(|&i| {
                options.sensors.is_empty() || options.sensors.contains(&self.sensors[i].name)
            })
            .collect();
        // Which images still need work (tiles already complete are skipped).
        let mut jobs = Vec::new();
        let mut done = Vec::new();
        for (ti, time) in times.iter().enumerate() {
            for &s in &chosen {
                let sensor = &self.sensors[s];
                let stem = Self::stem(sensor, time, series);
                let seed = options.seed.unwrap_or(sensor.effects.seed);
                if let Some(tile) = options.tile {
                    let info = self.tile_info(s, &stem, time, tile, seed);
                    let path = tile_path(out_dir, &stem, tile.0, tile.1);
                    if tile_is_complete(&path, &info) {
                        done.push(stem);
                        continue;
                    }
                }
                jobs.push((ti, s, stem, seed));
            }
        }
        if jobs.is_empty() {
            return Ok(done);
        }
        let progress: &dyn Progress = options.progress.as_deref().unwrap_or(&NoProgress);
        let states = match &options.state {
            Some(dir) => {
                let t0 = Instant::now();
                let read = super::state::read_states(self, dir, &times)?;
                let states = self.conditions(&read)?;
                self.timings.thermal += t0.elapsed();
                states
            }
            None => self.thermal_observed(&times, progress)?,
        };
        let total_rows: u64 = jobs
            .iter()
            .map(|(_, s, _, _)| match options.tile {
                Some((k, n)) => tile_rows(k, n, self.sensors[*s].height()).len() as u64,
                None => self.sensors[*s].height() as u64,
            })
            .sum();
        progress.start(Stage::Rows, total_rows);
        for (ti, s, stem, seed) in jobs {
            let time = times[ti];
            progress.item(&stem);
            let height = self.sensors[s].height();
            let rows = match options.tile {
                Some((k, n)) => tile_rows(k, n, height),
                None => 0..height,
            };
            let cond = &states.conditions[ti];
            let band = self.render_rows(s, cond, rows, &|n| progress.advance(n))?;
            match options.tile {
                Some(tile) => {
                    let info = self.tile_info(s, &stem, &time, tile, seed);
                    let t0 = Instant::now();
                    write_tile(&tile_path(out_dir, &stem, tile.0, tile.1), &info, &band)?;
                    self.timings.output += t0.elapsed();
                }
                None => {
                    let f = self.finish(s, band, seed)?;
                    self.write_image(out_dir, &stem, s, &time, &f)?;
                }
            }
            done.push(stem);
        }
        progress.finish();
        Ok(done)
    }
}

/// The scene-wide solve's parameters under the render settings.
pub(crate) fn solve_params(session: &Session) -> super::scene_thermal::SceneThermalParams {
    let mut params = super::scene_thermal::SceneThermalParams::default();
    params.exposure.samples_per_edge = session.config.facet_samples;
    params.exposure.sky = session.config.sky_sampling;
    params.physics = session.config.thermal;
    params
}

/// The thermal state at each image time from the scene-wide solve
/// ([`super::scene_thermal::solve_scene`]: per-facet solar history and sky view
/// traced once, the two-pass slab model spun up over the history window
/// covering all times), plus what the shading needs at each time: the
/// sun's incidence, the background temperatures, the sky and the sun.
fn scene_thermal(
    session: &Session,
    exposure: Option<Box<dyn Tracer>>,
    times: &[DateTime<FixedOffset>],
    progress: &dyn Progress,
) -> Result<(ThermalStates, Vec<String>)> {
    use super::scene_thermal::solve_scene_handing_over;
    let params = solve_params(session);
    let mut solved = solve_scene_handing_over(
        exposure,
        session.tracer.as_ref(),
        &session.scene,
        times,
        &params,
        progress,
    )?;
    let states = session.facet_states_of(&solved, times)?;
    let mut out = session.conditions(&states)?;
    out.timings = solved.timings;
    let warnings =
        super::scene_thermal::unsettled_exchange_warnings(&session.scene, &solved.temperatures);
    // Per-hit temperatures need what only the solve has (each point's own
    // solar history is traced at render time against the solve's Green's
    // functions); a state folder holds per-facet values only.
    if session.config.per_hit {
        let solar = std::sync::Arc::new(std::mem::take(&mut solved.exposure.solar));
        let sky_view = std::sync::Arc::new(std::mem::take(&mut solved.exposure.sky));
        let reflected = std::sync::Arc::new(std::mem::take(&mut solved.exposure.reflected));
        let sky = super::per_hit::SkyInputs::new(
            &solved.exposure.facets,
            sky_view.clone(),
            params.exposure.sky,
            params.exposure.seed,
            &solved.setup.shape_factor_override,
        )
        .with_reflected(reflected, &solved, params.physics.ground_albedo)
        .with_exposed_back(solved.exposed_back_shape_factor.clone());
        for (i, (c, image)) in out
            .conditions
            .iter_mut()
            .zip(&solved.point_response)
            .enumerate()
        {
            if let Some(image) = image {
                let ph = super::per_hit::PerHit::new(
                    solar.clone(),
                    &solved.exposure.facets,
                    &sky_view,
                    image,
                    &solved.sun_directions,
                    super::per_hit::PerHitParams {
                        size_px: session.config.per_hit_size_px,
                        ..super::per_hit::PerHitParams::default()
                    },
                )
                .with_sky(sky.clone(), solved.surface_temperature_k(i));
                c.per_hit = Some(std::sync::Arc::new(ph));
            }
        }
    }
    Ok((out, warnings))
}

impl Session {
    /// Per facet, the shape factor of its back face where it is
    /// double-sided (`None` elsewhere), with the parts' overrides, from a
    /// scene-wide solve.
    fn back_shape_factors(&self, solved: &super::scene_thermal::SceneThermal) -> Vec<Option<f32>> {
        let sky = &solved.exposure.sky;
        (0..sky.facet_count())
            .map(|f| {
                let part = self.scene.parts[self.optics.facet_material[f] as usize].shape_factor;
                sky.back_shape_factor(f)
                    .map(|b| part.map_or(b, |v| v as f32))
            })
            .collect()
    }

    /// What the render reads of a scene-wide solve at `times` (the solve's
    /// image times): per facet, its temperature, sun fraction, incidence
    /// and background at each time, and its shape factor with the parts'
    /// overrides.
    ///
    /// # Errors
    /// The weather not covering a time.
    pub fn facet_states_of(
        &self,
        solved: &super::scene_thermal::SceneThermal,
        times: &[DateTime<FixedOffset>],
    ) -> Result<FacetStates> {
        let scene = &self.scene;
        let n = scene.geometry.facet_count();
        let mut shape_factor = solved.shape_factor().to_vec();
        for (f, sf) in shape_factor.iter_mut().enumerate() {
            if let Some(v) = scene.parts[self.optics.facet_material[f] as usize].shape_factor {
                *sf = v as f32;
            }
        }
        let mut at = Vec::with_capacity(times.len());
        for (ti, time) in times.iter().enumerate() {
            let rec = self.weather.at(*time)?;
            let t_air = rec.air_temperature_k;
            let record = solved.temperatures.image_records[ti];
            let temps = solved.surface_temperature_k(ti).to_vec();
            let sun_fraction = solved.sun_fraction(ti);
            let solar = &solved.exposure.solar;
            let cos_sun: Vec<f32> = (0..n)
                .map(|f| solar.cos_incidence(f)[record].max(0.0))
                .collect();
            let background_k: Vec<f32> = (0..n)
                .map(|f| {
                    solved
                        .exposure
                        .sky
                        .background_temperature(f, &temps, t_air as f32)
                })
                .collect();
            at.push(FacetTimeState {
                temperature_k: temps,
                sun_fraction,
                cos_sun,
                background_k,
            });
        }
        Ok(FacetStates {
            times: times.to_vec(),
            first: 0,
            shape_factor,
            back_shape_factor: self.back_shape_factors(solved),
            at,
        })
    }

    /// The conditions of each time of `states` (every facet of the scene):
    /// its per-facet state, and the sky, sun and atmosphere from the
    /// weather at that time. The same whether `states` was solved or read
    /// from a state folder.
    ///
    /// # Errors
    /// States of another facet count; the weather not covering a time; the
    /// atmosphere's errors.
    pub fn conditions(&self, states: &FacetStates) -> Result<ThermalStates> {
        let n = self.scene.geometry.facet_count();
        if states.first != 0 || states.len() != n {
            return Err(Error::invalid(
                "facet state",
                format!(
                    "holds facets {}..{}, the scene has {n}",
                    states.first,
                    states.first + states.len()
                ),
            ));
        }
        let mut conditions = Vec::new();
        let mut records = Vec::new();
        for (time, at) in states.times.iter().zip(&states.at) {
            let rec = self.weather.at(*time)?;
            let t_air = rec.air_temperature_k;
            let surface = SurfaceState {
                temperature_k: at.temperature_k.clone(),
                shape_factor: states.shape_factor.clone(),
                back_shape_factor: states.back_shape_factor.clone(),
                sun_fraction: at.sun_fraction.clone(),
                cos_sun: at.cos_sun.clone(),
                background_k: at.background_k.clone(),
            };
            let sp = self.weather.sun_position(*time)?;
            let d = sp.direction_enu().as_vec3().normalize_or_zero();
            let sun = (d.z > 0.0).then_some(SunInput {
                direction: d,
                direct_normal_w_m2: rec.direct_normal_w_m2,
            });
            let sky = match self.config.sky_temperature_k {
                Some(t) => Sky::Blackbody { temperature_k: t },
                None => Sky::Atmosphere(crate::atmosphere::SkyConditions {
                    air_temperature_k: t_air,
                    sky_longwave_w_m2: rec.sky_longwave_w_m2,
                }),
            };
            conditions.push(Conditions {
                surface,
                sky,
                sun,
                ground_temperature_k: t_air,
                atmosphere: self.atmosphere_at(&rec)?,
                per_hit: None,
                wind_speed_m_s: rec.wind_speed_m_s,
            });
            records.push(rec);
        }
        Ok(ThermalStates {
            times: states.times.clone(),
            conditions,
            records,
            timings: Default::default(),
        })
    }
}
