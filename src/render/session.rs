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

use super::image::{Finished, RowBand, StageTimes, finish, render_rows};
use super::path::PathTables;
use super::scene_thermal::FacetTracers;
use super::shade::{Conditions, SceneOptics, ShadeOptions, Shader, Sky, SunInput, SurfaceState};
use super::tile::{TileInfo, tile_is_complete, tile_path, tile_rows, write_tile};
use super::{Fnv, RenderConfig, sensor_bands, write_outputs};
use crate::atmosphere::{Atmosphere, BuiltinAtmosphere, Profile, SurfaceMet, Tape7Lut};
use crate::progress::{NoProgress, Progress, Stage};
use crate::radiometry::Band;
use crate::scene::Scene;
use crate::sensor::{Sensor, SensorConfig};
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
    },
    /// A table of MODTRAN tape7 runs, listed in an index JSON file (relative
    /// to the scene file).
    Tape7 {
        /// The index file.
        index: PathBuf,
    },
}

impl Default for AtmosphereConfig {
    /// The built-in model on the AFGL profile of the site and month.
    fn default() -> Self {
        AtmosphereConfig::Standard {
            profile: None,
            co2_ppmv: None,
        }
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
    },
    Standard {
        profile: Option<String>,
        co2_ppmv: Option<f64>,
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
                },
                "standard" => AtmosphereConfig::default(),
                other => AtmosphereConfig::Standard {
                    profile: Some(profile(other).map_err(|_| {
                        format!(
                            "unknown atmosphere `{other}`: expected \"none\", \"builtin\", \
                             \"standard\" or a profile ({})",
                            Profile::ALL.map(Profile::name).join(", ")
                        )
                    })?),
                    co2_ppmv: None,
                },
            });
        }
        Ok(
            match serde_json::from_value::<AtmosphereObject>(v).map_err(|e| e.to_string())? {
                AtmosphereObject::None => AtmosphereConfig::None,
                AtmosphereObject::Builtin {
                    co2_ppmv,
                    water_scale_height_m,
                } => AtmosphereConfig::Builtin {
                    co2_ppmv,
                    water_scale_height_m,
                },
                AtmosphereObject::Standard {
                    profile: p,
                    co2_ppmv,
                } => AtmosphereConfig::Standard {
                    profile: p.as_deref().map(profile).transpose()?,
                    co2_ppmv,
                },
                AtmosphereObject::Tape7 { index } => AtmosphereConfig::Tape7 { index },
            },
        )
    }
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
    /// Told how the run progresses ([`Stage::Thermal`], then
    /// [`Stage::Rows`]); `None`: nobody is told.
    pub progress: Option<Arc<dyn Progress>>,
    /// Only these sensors (by name); empty: all.
    pub sensors: Vec<String>,
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

fn parse_at<T: for<'de> Deserialize<'de>>(
    v: &serde_json::Value,
    loc: &Location,
    expected: &str,
) -> Result<T> {
    serde_json::from_value(v.clone())
        .map_err(|e| Error::parse(loc.clone(), format!("{e}: expected {expected}")))
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
        let scene_path = scene.path.clone();
        let scene_path = scene_path.as_path();
        let file = Location::file(scene_path);
        let config = RenderConfig::from_json(scene.render.as_ref(), &file)?;
        let atmosphere = match &scene.atmosphere {
            None => AtmosphereConfig::default(),
            Some(v) => parse_at(
                v,
                &file.clone().with_field("atmosphere"),
                "\"none\", a profile name, {\"model\": \"none\"}, {\"model\": \"builtin\"}, \
                 {\"model\": \"standard\", \"profile\": NAME} or {\"model\": \"tape7\", \"index\": FILE}",
            )?,
        };
        let base = scene_path.parent().unwrap_or(Path::new(".")).to_path_buf();
        let mut sensors = Vec::new();
        let mut bands = Vec::new();
        for (i, v) in scene.sensors.iter().enumerate() {
            let loc = file.clone().with_field(format!("sensors[{i}]"));
            let c: SensorConfig = parse_at(
                v,
                &loc,
                "a sensor with \"type\": \"frame\" or \"line_scanner\"",
            )?;
            let s = Sensor::from_config(&c, &loc)?;
            if sensors.iter().any(|o: &Sensor| o.name == s.name) {
                return Err(Error::parse(
                    loc.with_field(format!("sensors[{i}].name")),
                    format!("`{}` is used twice: expected unique sensor names", s.name),
                ));
            }
            bands.push(sensor_bands(&s, &base, config.spectral_step_um, &loc)?);
            sensors.push(s);
        }
        if sensors.is_empty() {
            return Err(Error::parse(
                file.clone().with_field("sensors"),
                "no sensors: expected at least one frame camera or line scanner",
            ));
        }
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
        let tracer = trace::build(&scene.geometry, backend)?;
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
        })
    }

    /// The atmosphere at one image time (the scene's configuration driven
    /// by the weather `record`).
    pub(crate) fn atmosphere_at(&self, record: &WeatherRecord) -> Result<Atmosphere> {
        Ok(match &self.atmosphere {
            AtmosphereConfig::None => Atmosphere::None,
            AtmosphereConfig::Builtin {
                co2_ppmv,
                water_scale_height_m,
            } => {
                let mut p = crate::atmosphere::BuiltinParams::default();
                if let Some(c) = co2_ppmv {
                    p.co2_ppmv = *c;
                }
                if let Some(w) = water_scale_height_m {
                    p.water_scale_height_m = *w;
                }
                Atmosphere::Builtin(BuiltinAtmosphere::with_params(
                    SurfaceMet::from_weather(record, self.scene.site.altitude_m),
                    p,
                )?)
            }
            AtmosphereConfig::Standard { profile, co2_ppmv } => {
                let profile = profile.unwrap_or_else(|| {
                    use chrono::Datelike;
                    Profile::for_site(self.scene.site.latitude_deg, record.time.month())
                });
                let mut p = crate::atmosphere::BuiltinParams {
                    profile: Some(profile),
                    ..Default::default()
                };
                if let Some(c) = co2_ppmv {
                    p.co2_ppmv = *c;
                }
                Atmosphere::Builtin(BuiltinAtmosphere::with_params(
                    SurfaceMet::from_weather(record, self.scene.site.altitude_m),
                    p,
                )?)
            }
            AtmosphereConfig::Tape7 { index } => {
                let base = self.scene.path.parent().unwrap_or(Path::new("."));
                Atmosphere::Tape7Lut(Tape7Lut::read_index(base.join(index))?)
            }
        })
    }

    /// The thermal state of every facet at each of `times` (one exposure
    /// computation and one thermal spin-up for the whole series).
    pub fn thermal(&mut self, times: &[DateTime<FixedOffset>]) -> Result<ThermalStates> {
        self.thermal_observed(times, &NoProgress)
    }

    /// [`Session::thermal`], telling `progress` which of its stages runs
    /// (the rays, the ground test, the thermal passes) and advancing it by
    /// the facet count when done; the caller starts and finishes the
    /// [`Stage::Thermal`] stage.
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
        let tracers = FacetTracers {
            exposure: own.as_deref().unwrap_or(self.tracer.as_ref()),
            exact: self.tracer.as_ref(),
        };
        let states = scene_thermal(self, tracers, times, progress)?;
        self.timings.thermal += t0.elapsed();
        self.timings.thermal_solve += states.timings.thermal;
        Ok(states)
    }

    /// The tracer for the exposure's rays (solar history, sky view): rays
    /// from interior sample points in generic directions, which need no
    /// watertight tests ([`Watertight::No`]; the ground test stays on
    /// [`Session::tracer`], see [`FacetTracers`]). A second Embree scene
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
        )?;
        let shader = Shader::new(
            self.tracer.as_ref(),
            &self.scene.geometry,
            &self.optics,
            cond,
            bands,
            opts,
        )?
        .with_path(paths);
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
        let f = finish(band, &self.sensors[s], &self.bands[s], seed)?;
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
                        "`{name}`: no such sensor (the scene has {})",
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
        write_outputs(out_dir, stem, image, &desc)?;
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
        let facets = self.scene.geometry.facet_count() as u64;
        progress.start(Stage::Thermal, facets);
        let states = self.thermal_observed(&times, progress)?;
        progress.finish();
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

/// The thermal state at each image time from the scene-wide solve
/// ([`super::scene_thermal::solve_scene`]: per-facet solar history and sky view
/// traced once, the two-pass slab model spun up over the history window
/// covering all times), plus what the shading needs at each time: the
/// sun's incidence, the background temperatures, the sky and the sun.
fn scene_thermal(
    session: &Session,
    tracers: FacetTracers<'_>,
    times: &[DateTime<FixedOffset>],
    progress: &dyn Progress,
) -> Result<ThermalStates> {
    use super::scene_thermal::{SceneThermalParams, solve_scene_observed};
    let scene = &session.scene;
    let mut params = SceneThermalParams::default();
    params.exposure.samples_per_edge = session.config.facet_samples;
    params.exposure.sky = session.config.sky_sampling;
    params.physics = session.config.thermal;
    let solved = solve_scene_observed(tracers, scene, times, &params, progress)?;
    let n = scene.geometry.facet_count();
    let shape = solved.shape_factor().to_vec();
    let mut conditions = Vec::new();
    let mut records = Vec::new();
    for (ti, time) in times.iter().enumerate() {
        let rec = session.weather.at(*time)?;
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
        let mut shape_factor = shape.clone();
        for (f, sf) in shape_factor.iter_mut().enumerate() {
            if let Some(v) = scene.parts[session.optics.facet_material[f] as usize].shape_factor {
                *sf = v as f32;
            }
        }
        let surface = SurfaceState {
            temperature_k: temps,
            shape_factor,
            sun_fraction,
            cos_sun,
            background_k,
        };
        let sp = session.weather.sun_position(*time)?;
        let d = sp.direction_enu().as_vec3().normalize_or_zero();
        let sun = (d.z > 0.0).then_some(SunInput {
            direction: d,
            direct_normal_w_m2: rec.direct_normal_w_m2,
        });
        let sky = match session.config.sky_temperature_k {
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
            atmosphere: session.atmosphere_at(&rec)?,
        });
        records.push(rec);
    }
    Ok(ThermalStates {
        times: times.to_vec(),
        conditions,
        records,
        timings: solved.timings,
    })
}
