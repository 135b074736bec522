//! Sensors: where primary rays come from, and what the sensor does to the
//! radiance image.
//!
//! - [`SensorConfig`] is one entry of a scene file's `sensors` array
//!   (serde, `"type": "frame"` or `"line_scanner"`); [`Sensor::from_config`]
//!   validates it into a [`Sensor`]: a [`Geometry`] ([`FrameCamera`] or
//!   [`LineScanner`]), its spectral [`BandConfig`]s and its [`Effects`].
//! - [`Sensor::rays_for_row`] gives the primary rays of one image row (a
//!   camera row or a scanner line), `N×N` per pixel, laid out as rows of the
//!   oversampled image; the render loop traces them, turns hits into
//!   radiance, and the [`effects`] chain turns the oversampled radiance image
//!   into the sensor's image: [`effects::reduce_oversampled`] (PSF) →
//!   [`effects::apply_mtf`] → [`effects::add_noise`] (NEdT) →
//!   [`effects::quantise`] (digital counts).
//! - [`Sensor::project`] maps a world point to continuous image coordinates
//!   (tests, ground-truth overlays).
//!
//! - [`georef`]: where the image lies on the map ([`georef::georeference`]:
//!   an affine pixel → UTM transform where the geometry allows), the
//!   output orientation ([`Orientation`]: line scanners north-up on request)
//!   and the opt-in geolocation truth layers ([`GeoLayer`]).
//!
//! Transforms are named `<to>_from_<from>`; world space is ENU metres.
//!
//! Takes a sensor description; gives rays and, from radiances, the sensor's
//! image. It must not know the scene, materials or the thermal model.

pub mod camera;
pub mod effects;
pub mod georef;
pub mod scanner;

use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};
use serde::Deserialize;

pub use camera::FrameCamera;
pub use effects::{BandImage, Effects, Mtf, MtfModel, Psf};
pub use scanner::{LineScanner, LineScannerParams};

use crate::radiometry::{Band, read_response_csv};
use crate::trace::Ray;
use crate::{Error, Location, Result};

/// A table derived from some of a sensor's public fields, kept with the key
/// of the fields it was made from: a sensor whose fields were changed after
/// it was built makes the table afresh instead of reading a stale one.
#[derive(Clone, PartialEq, Default)]
pub(crate) struct Derived<K, T> {
    key: K,
    table: T,
}

impl<K: PartialEq, T> Derived<K, T> {
    /// `table`, made from the fields whose key is `key`.
    pub(crate) fn new(key: K, table: T) -> Self {
        Derived { key, table }
    }

    /// The table for the fields whose key is `key`: this one if it was made
    /// from them, else `make()`'s.
    pub(crate) fn get(&self, key: K, make: impl FnOnce() -> T) -> std::borrow::Cow<'_, T>
    where
        T: Clone,
    {
        if self.key == key {
            std::borrow::Cow::Borrowed(&self.table)
        } else {
            std::borrow::Cow::Owned(make())
        }
    }
}

impl<K, T: std::fmt::Debug> std::fmt::Debug for Derived<K, T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.table.fmt(f)
    }
}

/// A spectral band as given in the scene file. The response is resolved by
/// the radiometry module (CSV reader, band integration).
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BandConfig {
    /// Band name (used in layer names).
    pub name: String,
    /// Relative spectral response: a CSV file (µm, response; relative to the
    /// scene file) or a rectangular band `[lo_um, hi_um]`.
    pub response: ResponseSpec,
}

/// A band's spectral response as written in the scene file.
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum ResponseSpec {
    /// A rectangular response from `lo` to `hi`, µm.
    Range([f64; 2]),
    /// A CSV file of wavelength (µm) and relative response.
    File(PathBuf),
}

impl BandConfig {
    /// Resolve the response into a radiometry [`Band`] sampled every
    /// ≤ `step_um`: a rectangular band, or the CSV file (relative paths are
    /// taken from `base_dir`, the scene file's folder) read by
    /// [`crate::radiometry::read_response_csv`].
    pub fn resolve(&self, base_dir: &Path, step_um: f64) -> Result<Band> {
        match &self.response {
            ResponseSpec::Range([lo, hi]) => Band::flat(*lo, *hi, step_um),
            ResponseSpec::File(f) => {
                let resp = read_response_csv(base_dir.join(f))?;
                Band::from_response(&resp, step_um)
            }
        }
    }

    /// The band centre for a rectangular band, µm (`None` for a file, whose
    /// centre the radiometry module computes).
    pub fn range_centre_um(&self) -> Option<f64> {
        match self.response {
            ResponseSpec::Range([lo, hi]) => Some(0.5 * (lo + hi)),
            ResponseSpec::File(_) => None,
        }
    }
}

fn one() -> usize {
    1
}
fn unit_gain() -> f64 {
    1.0
}
fn default_up() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}
fn default_reference_temperature() -> f64 {
    300.0
}

/// One sensor of the scene file.
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum SensorConfig {
    /// A frame camera.
    Frame(FrameCameraConfig),
    /// An airborne whiskbroom line scanner.
    LineScanner(LineScannerConfig),
}

/// Sensor-effects settings shared by both sensor types (see [`Effects`]).
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MtfConfig {
    /// Entrance-pupil (aperture) diameter for the diffraction-limited optics
    /// MTF, m (omit for no optics MTF).
    pub aperture_diameter_m: Option<f64>,
    /// Wavelength for the optics MTF, µm (default: the first band's centre).
    pub wavelength_um: Option<f64>,
    /// Detector fill factor (active width / pitch, 0–1) for the detector
    /// sinc MTF (omit for none).
    pub fill_factor: Option<f64>,
}

/// `{"type": "frame", ...}`: a frame camera. Give `focal_length_m` with
/// `pixel_pitch_m`, or `fov_deg` (full horizontal field of view); point it
/// with `look_at` (+ `up`), or with `yaw_deg`/`pitch_deg`/`roll_deg`
/// (azimuth clockwise from north, elevation, roll; see
/// [`camera::yaw_pitch_roll_axes`]).
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FrameCameraConfig {
    /// Sensor name (output file stem).
    pub name: String,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Pixel pitch, m.
    pub pixel_pitch_m: Option<f64>,
    /// Focal length, m.
    pub focal_length_m: Option<f64>,
    /// Full horizontal field of view, degrees.
    pub fov_deg: Option<f64>,
    /// Position, world metres.
    pub position: [f64; 3],
    /// Point looked at, world metres.
    pub look_at: Option<[f64; 3]>,
    /// Up direction for `look_at`.
    #[serde(default = "default_up")]
    pub up: [f64; 3],
    /// Pointing azimuth, degrees clockwise from north (without `look_at`).
    pub yaw_deg: Option<f64>,
    /// Pointing elevation, degrees (−90 = nadir).
    pub pitch_deg: Option<f64>,
    /// Roll about the viewing axis, degrees.
    pub roll_deg: Option<f64>,
    /// Spectral bands.
    pub bands: Vec<BandConfig>,
    /// Sub-pixel rays per side.
    #[serde(default = "one")]
    pub oversample: usize,
    /// Point-spread function for the oversampling reduction.
    #[serde(default)]
    pub psf: Psf,
    /// Optics/detector MTF.
    pub mtf: Option<MtfConfig>,
    /// Noise-equivalent temperature difference, K.
    pub nedt_k: Option<f64>,
    /// Scene temperature at which the NEdT is quoted, K.
    #[serde(default = "default_reference_temperature")]
    pub nedt_reference_k: f64,
    /// Quantisation bits (omit for no digital-count layer).
    pub bits: Option<u32>,
    /// Counts per radiance unit (W·m⁻²·sr⁻¹·µm⁻¹).
    #[serde(default = "unit_gain")]
    pub gain: f64,
    /// Counts offset.
    #[serde(default)]
    pub offset: f64,
    /// Noise seed.
    #[serde(default)]
    pub seed: u64,
    /// Extra truth layers, besides the six always written: any of
    /// `latitude`, `longitude` (degrees, WGS-84) and `x`, `y`, `z` (scene
    /// metres) of each pixel's centre-ray hit, NaN where the ray misses.
    #[serde(default)]
    pub truth_layers: Vec<String>,
}

/// `{"type": "line_scanner", ...}`: an airborne whiskbroom scanner (see
/// [`scanner`] for the geometry and conventions).
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LineScannerConfig {
    /// Sensor name.
    pub name: String,
    /// Instantaneous field of view, rad.
    pub ifov_rad: f64,
    /// Total scan angle, degrees.
    pub scan_angle_deg: f64,
    /// Samples per line.
    pub samples_per_line: usize,
    /// Lines.
    pub lines: usize,
    /// Lines per second.
    pub scan_rate_hz: f64,
    /// Altitude above `z = 0`, m.
    pub altitude_m: f64,
    /// Ground speed, m/s.
    pub ground_speed_m_s: f64,
    /// Ground track, degrees clockwise from north.
    pub heading_deg: f64,
    /// Roll (right wing down +), degrees.
    #[serde(default)]
    pub roll_deg: f64,
    /// Pitch (nose up +), degrees.
    #[serde(default)]
    pub pitch_deg: f64,
    /// Yaw / crab (nose right +), degrees.
    #[serde(default)]
    pub yaw_deg: f64,
    /// Ground position (east, north) of line 0, m.
    pub start: [f64; 2],
    /// Time of line 0 after the scene time, s.
    #[serde(default)]
    pub start_time: f64,
    /// Model the mirror sweep time within each line.
    #[serde(default)]
    pub mirror_sweep: bool,
    /// Spectral bands.
    pub bands: Vec<BandConfig>,
    /// Sub-sample rays per side.
    #[serde(default = "one")]
    pub oversample: usize,
    /// Point-spread function.
    #[serde(default)]
    pub psf: Psf,
    /// Optics/detector MTF.
    pub mtf: Option<MtfConfig>,
    /// NEdT, K.
    pub nedt_k: Option<f64>,
    /// Scene temperature at which the NEdT is quoted, K.
    #[serde(default = "default_reference_temperature")]
    pub nedt_reference_k: f64,
    /// Quantisation bits.
    pub bits: Option<u32>,
    /// Counts per radiance unit.
    #[serde(default = "unit_gain")]
    pub gain: f64,
    /// Counts offset.
    #[serde(default)]
    pub offset: f64,
    /// Noise seed.
    #[serde(default)]
    pub seed: u64,
    /// Extra truth layers (see [`FrameCameraConfig::truth_layers`]).
    #[serde(default)]
    pub truth_layers: Vec<String>,
    /// Orientation of the written image: `north_up` (default: the first row
    /// is the northernmost line and the image is not mirrored, see
    /// [`Orientation::north_up`]) or `as_flown` (row 0 is the first line,
    /// column 0 the port end of each line: the ground mirrored).
    #[serde(default)]
    pub orientation: ScanOrientation,
}

/// How a line scanner's image is laid out in its files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ScanOrientation {
    /// Row 0 is the first line flown, column 0 the port end of each line
    /// (seen from above, the ground mirrored).
    AsFlown,
    /// The first row is the northernmost line, and the image is not
    /// mirrored ([`Orientation::north_up`]). The default.
    #[default]
    NorthUp,
}

/// A flip of the sensor's image into the written image: written pixel
/// `(col, row)` is sensor pixel `(W − 1 − col, row)` with `flip_columns`,
/// `(col, H − 1 − row)` with `flip_rows`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Orientation {
    /// Reverse the order of the columns.
    pub flip_columns: bool,
    /// Reverse the order of the rows.
    pub flip_rows: bool,
}

impl Orientation {
    /// The north-up layout of a line scanner flying on `heading_rad`
    /// (clockwise from north). As flown, rows follow the track and columns
    /// run from port to starboard, which is a mirror image of the ground
    /// (seen from above) on every heading. One flip undoes it: with a
    /// northward track (`cos heading > 0`) the rows are reversed, so the
    /// first row is the northernmost line; otherwise (southward, or exactly
    /// east or west) the columns are reversed, and the first row already is
    /// the northernmost (east/west: the westernmost / easternmost). The
    /// image is then the ground as seen from above, turned by the heading
    /// off north-up at most ±90° (the ENVI `rotation=`).
    pub fn north_up(heading_rad: f64) -> Orientation {
        if heading_rad.cos() > 1e-12 {
            Orientation {
                flip_columns: false,
                flip_rows: true,
            }
        } else {
            Orientation {
                flip_columns: true,
                flip_rows: false,
            }
        }
    }

    /// Whether anything is flipped.
    pub fn is_identity(&self) -> bool {
        !self.flip_columns && !self.flip_rows
    }

    /// Continuous sensor coordinates of continuous written-image point
    /// `(u, v)` of a `w × h` image (the flip is its own inverse).
    pub fn apply(&self, u: f64, v: f64, w: f64, h: f64) -> (f64, f64) {
        (
            if self.flip_columns { w - u } else { u },
            if self.flip_rows { h - v } else { v },
        )
    }

    /// Flip a row-major `w`-wide layer in place.
    pub fn flip_layer(&self, data: &mut [f32], w: usize) {
        if self.flip_columns {
            for row in data.chunks_exact_mut(w.max(1)) {
                row.reverse();
            }
        }
        if self.flip_rows {
            let h = data.len() / w.max(1);
            for r in 0..h / 2 {
                let (top, bottom) = data.split_at_mut((h - 1 - r) * w);
                top[r * w..(r + 1) * w].swap_with_slice(&mut bottom[..w]);
            }
        }
    }
}

/// A geolocation truth layer (opt-in: a sensor's `truth_layers`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GeoLayer {
    /// Geodetic latitude of the hit, degrees (WGS-84).
    Latitude,
    /// Longitude of the hit, degrees east.
    Longitude,
    /// Scene x (east) of the hit, m.
    X,
    /// Scene y (north), m.
    Y,
    /// Scene z (up), m.
    Z,
}

impl GeoLayer {
    /// Every geolocation layer, in output order.
    pub const ALL: [GeoLayer; 5] = [
        GeoLayer::Latitude,
        GeoLayer::Longitude,
        GeoLayer::X,
        GeoLayer::Y,
        GeoLayer::Z,
    ];

    /// The layer name.
    pub fn name(&self) -> &'static str {
        match self {
            GeoLayer::Latitude => "latitude",
            GeoLayer::Longitude => "longitude",
            GeoLayer::X => "x",
            GeoLayer::Y => "y",
            GeoLayer::Z => "z",
        }
    }

    /// Parse a sensor's `truth_layers` list (names as [`GeoLayer::name`]),
    /// in output order, without repeats.
    pub fn parse_list(names: &[String]) -> Result<Vec<GeoLayer>> {
        let mut out = Vec::new();
        for n in names {
            let Some(l) = GeoLayer::ALL.iter().find(|l| l.name() == n) else {
                return Err(Error::invalid(
                    "truth_layers",
                    format!(
                        "unknown layer `{n}`: expected any of latitude, longitude, x, y, z \
                         (the standard truth layers are always written)"
                    ),
                ));
            };
            if out.contains(l) {
                return Err(Error::invalid(
                    "truth_layers",
                    format!("`{n}` is listed twice"),
                ));
            }
            out.push(*l);
        }
        out.sort_by_key(|l| GeoLayer::ALL.iter().position(|a| a == l));
        Ok(out)
    }
}

/// The imaging geometry of a sensor.
#[derive(Debug, Clone, PartialEq)]
pub enum Geometry {
    /// Frame camera.
    Frame(FrameCamera),
    /// Line scanner.
    LineScanner(LineScanner),
}

/// A validated sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensor {
    /// Name (output file stem).
    pub name: String,
    /// Imaging geometry.
    pub geometry: Geometry,
    /// Spectral bands (responses still to be resolved by radiometry).
    pub bands: Vec<BandConfig>,
    /// Sensor effects applied to each band's radiance image.
    pub effects: Effects,
    /// Geolocation truth layers to write, in output order.
    pub geo_layers: Vec<GeoLayer>,
    /// How the sensor's image is laid out in the written image.
    pub orientation: Orientation,
}

fn vec3(a: [f64; 3]) -> DVec3 {
    DVec3::from_array(a)
}

impl Sensor {
    /// Validate a scene-file sensor. `location` names the sensor in the
    /// scene file (e.g. `scene.json`, field `sensors[0]`); errors name the
    /// offending field below it.
    pub fn from_config(config: &SensorConfig, location: &Location) -> Result<Self> {
        let at = |field: &str, e: Error| -> Error {
            let msg = match e {
                Error::Invalid { message, .. } => message,
                other => other.to_string(),
            };
            let base = location.field.clone().unwrap_or_else(|| "sensor".into());
            Error::parse(location.clone().with_field(format!("{base}.{field}")), msg)
        };
        let bad = |field: &str, msg: String| at(field, Error::invalid(field, msg));
        match config {
            SensorConfig::Frame(c) => {
                let focal_px = match (c.focal_length_m, c.pixel_pitch_m, c.fov_deg) {
                    (Some(f), Some(p), None) => {
                        if !(f > 0.0 && p > 0.0 && f.is_finite() && p.is_finite()) {
                            return Err(bad(
                                "focal_length_m",
                                format!("{f} m with pitch {p} m: expected positive lengths"),
                            ));
                        }
                        f / p
                    }
                    (None, _, Some(fov)) => {
                        if !(fov > 0.0 && fov < 180.0) {
                            return Err(bad(
                                "fov_deg",
                                format!("{fov}: expected a field of view between 0 and 180°"),
                            ));
                        }
                        0.5 * c.width as f64 / (0.5 * fov.to_radians()).tan()
                    }
                    _ => {
                        return Err(bad(
                            "focal_length_m",
                            "expected either `focal_length_m` with `pixel_pitch_m`, or `fov_deg`"
                                .into(),
                        ));
                    }
                };
                let position = vec3(c.position);
                let axes = match (c.look_at, c.yaw_deg, c.pitch_deg) {
                    (Some(l), None, None) => camera::look_at_axes(position, vec3(l), vec3(c.up))
                        .map_err(|e| at("look_at", e))?,
                    (None, Some(y), Some(p)) => camera::yaw_pitch_roll_axes(
                        y.to_radians(),
                        p.to_radians(),
                        c.roll_deg.unwrap_or(0.0).to_radians(),
                    ),
                    _ => {
                        return Err(bad(
                            "look_at",
                            "expected either `look_at` (with optional `up`), or `yaw_deg` and \
                             `pitch_deg`"
                                .into(),
                        ));
                    }
                };
                let geometry =
                    FrameCamera::new(c.width, c.height, focal_px, axes, position, c.oversample)
                        .map_err(|e| at("width", e))?;
                let effects = Effects::from_parts(
                    c.psf,
                    c.mtf.as_ref(),
                    c.pixel_pitch_m
                        .zip(c.focal_length_m)
                        .map(|(p, f)| p / f)
                        .unwrap_or(1.0 / focal_px),
                    (
                        c.nedt_k,
                        c.nedt_reference_k,
                        c.bits,
                        c.gain,
                        c.offset,
                        c.seed,
                    ),
                )
                .map_err(|e| {
                    let field = match &e {
                        Error::Invalid { field, .. } => field.clone(),
                        _ => "mtf".into(),
                    };
                    at(&field, e)
                })?;
                check_bands(&c.bands).map_err(|e| at("bands", e))?;
                Ok(Sensor {
                    name: c.name.clone(),
                    geometry: Geometry::Frame(geometry),
                    bands: c.bands.clone(),
                    effects,
                    geo_layers: GeoLayer::parse_list(&c.truth_layers)
                        .map_err(|e| at("truth_layers", e))?,
                    orientation: Orientation::default(),
                })
            }
            SensorConfig::LineScanner(c) => {
                let p = LineScannerParams {
                    ifov_rad: c.ifov_rad,
                    scan_angle_rad: c.scan_angle_deg.to_radians(),
                    samples_per_line: c.samples_per_line,
                    lines: c.lines,
                    scan_rate_hz: c.scan_rate_hz,
                    altitude_m: c.altitude_m,
                    ground_speed_m_s: c.ground_speed_m_s,
                    heading_rad: c.heading_deg.to_radians(),
                    roll_pitch_yaw_rad: [
                        c.roll_deg.to_radians(),
                        c.pitch_deg.to_radians(),
                        c.yaw_deg.to_radians(),
                    ],
                    start: DVec2::from_array(c.start),
                    start_time_s: c.start_time,
                    mirror_sweep: c.mirror_sweep,
                    oversample: c.oversample,
                };
                let geometry = LineScanner::new(&p).map_err(|e| {
                    let field = match &e {
                        Error::Invalid { field, .. } => field.clone(),
                        _ => "ifov_rad".into(),
                    };
                    at(&field, e)
                })?;
                let effects = Effects::from_parts(
                    c.psf,
                    c.mtf.as_ref(),
                    geometry.sample_step_rad(),
                    (
                        c.nedt_k,
                        c.nedt_reference_k,
                        c.bits,
                        c.gain,
                        c.offset,
                        c.seed,
                    ),
                )
                .map_err(|e| {
                    let field = match &e {
                        Error::Invalid { field, .. } => field.clone(),
                        _ => "mtf".into(),
                    };
                    at(&field, e)
                })?;
                check_bands(&c.bands).map_err(|e| at("bands", e))?;
                let orientation = match c.orientation {
                    ScanOrientation::AsFlown => Orientation::default(),
                    ScanOrientation::NorthUp => Orientation::north_up(geometry.heading_rad),
                };
                Ok(Sensor {
                    name: c.name.clone(),
                    geometry: Geometry::LineScanner(geometry),
                    bands: c.bands.clone(),
                    effects,
                    geo_layers: GeoLayer::parse_list(&c.truth_layers)
                        .map_err(|e| at("truth_layers", e))?,
                    orientation,
                })
            }
        }
    }

    /// Resolve every band's response (see [`BandConfig::resolve`]); errors
    /// name the band (`<location>.bands[i].response`).
    pub fn resolve_bands(
        &self,
        base_dir: &Path,
        step_um: f64,
        location: &Location,
    ) -> Result<Vec<Band>> {
        self.bands
            .iter()
            .enumerate()
            .map(|(i, b)| {
                b.resolve(base_dir, step_um).map_err(|e| match e {
                    Error::Invalid { message, .. } => {
                        let base = location.field.clone().unwrap_or_else(|| "sensor".into());
                        Error::parse(
                            location
                                .clone()
                                .with_field(format!("{base}.bands[{i}].response")),
                            message,
                        )
                    }
                    other => other,
                })
            })
            .collect()
    }

    /// Image width: columns / samples per line.
    pub fn width(&self) -> usize {
        match &self.geometry {
            Geometry::Frame(c) => c.width,
            Geometry::LineScanner(s) => s.samples_per_line,
        }
    }

    /// Image height: rows / lines.
    pub fn height(&self) -> usize {
        match &self.geometry {
            Geometry::Frame(c) => c.height,
            Geometry::LineScanner(s) => s.lines,
        }
    }

    /// Oversampling factor `N` (`N×N` rays per pixel).
    pub fn oversample(&self) -> usize {
        match &self.geometry {
            Geometry::Frame(c) => c.oversample,
            Geometry::LineScanner(s) => s.oversample,
        }
    }

    /// Angular size of a pixel, rad: `pitch / focal length` at the centre
    /// of a frame camera, the IFOV of a line scanner.
    pub fn pixel_angle_rad(&self) -> f64 {
        match &self.geometry {
            Geometry::Frame(c) => 1.0 / c.focal_px,
            Geometry::LineScanner(s) => s.ifov_rad,
        }
    }

    /// Rays per image row: `width · N²`.
    pub fn rays_per_row(&self) -> usize {
        self.width() * self.oversample() * self.oversample()
    }

    /// Append the primary rays of image row `row` to `out` (see
    /// [`FrameCamera::rays_for_row`], [`LineScanner::rays_for_line`]).
    pub fn rays_for_row(&self, row: usize, out: &mut Vec<Ray>) {
        match &self.geometry {
            Geometry::Frame(c) => c.rays_for_row(row, out),
            Geometry::LineScanner(s) => s.rays_for_line(row, out),
        }
    }

    /// Time offset (s, after the scene time) at which row `row` is imaged:
    /// 0 for a frame camera, the line start for a scanner.
    pub fn row_time(&self, row: usize) -> f64 {
        match &self.geometry {
            Geometry::Frame(_) => 0.0,
            Geometry::LineScanner(s) => s.line_time(row),
        }
    }

    /// Continuous image coordinates `(column, row)` — for a scanner
    /// `(sample, line)` — of world point `p`, or `None` where it is not seen.
    /// These are the sensor's coordinates; the written image may be flipped
    /// ([`Sensor::project_written`]).
    pub fn project(&self, p: DVec3) -> Option<DVec2> {
        match &self.geometry {
            Geometry::Frame(c) => c.project(p),
            Geometry::LineScanner(s) => s.project(p).map(|ls| DVec2::new(ls.y, ls.x)),
        }
    }

    /// [`Sensor::project`] in the written image's coordinates (after the
    /// [`Orientation`] flip).
    pub fn project_written(&self, p: DVec3) -> Option<DVec2> {
        let uv = self.project(p)?;
        let (u, v) = self
            .orientation
            .apply(uv.x, uv.y, self.width() as f64, self.height() as f64);
        Some(DVec2::new(u, v))
    }

    /// The point where the line of sight through continuous sensor image
    /// point `(u, v)` (`(sample, line)` for a scanner, whose aircraft
    /// position is taken at that point's time) meets the horizontal plane
    /// `z = z_m`, or `None` if it never does (looking up or level).
    pub fn ground_point(&self, u: f64, v: f64, z_m: f64) -> Option<DVec3> {
        let (o, d) = match &self.geometry {
            Geometry::Frame(c) => (c.position(), c.direction(u, v)),
            Geometry::LineScanner(s) => {
                let theta = s.scan_angle(u);
                let t = s.start_time_s + (v - 0.5) / s.scan_rate_hz + s.sweep_delay(theta);
                (s.position(t), s.direction(theta, 0.0))
            }
        };
        if d.z.is_nan() || d.z >= -1e-12 {
            return None;
        }
        let k = (z_m - o.z) / d.z;
        (k > 0.0).then(|| o + d * k)
    }
}

fn check_bands(bands: &[BandConfig]) -> Result<()> {
    if bands.is_empty() {
        return Err(Error::invalid("bands", "empty: expected at least one band"));
    }
    for (i, b) in bands.iter().enumerate() {
        if bands[..i].iter().any(|o| o.name == b.name) {
            return Err(Error::invalid(
                "bands",
                format!(
                    "band name `{}` is used twice: expected unique names",
                    b.name
                ),
            ));
        }
        if let ResponseSpec::Range([lo, hi]) = b.response {
            if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
                return Err(Error::invalid(
                    "bands",
                    format!(
                        "band `{}`: response [{lo}, {hi}] µm: expected 0 < lo < hi",
                        b.name
                    ),
                ));
            }
            if lo < crate::radiometry::band::BAND_LIMITS_UM.0
                || hi > crate::radiometry::band::BAND_LIMITS_UM.1
            {
                let hint = if lo >= 200.0 {
                    format!(
                        "; in nanometres that would be [{}, {}] µm",
                        lo / 1000.0,
                        hi / 1000.0
                    )
                } else {
                    String::new()
                };
                return Err(Error::invalid(
                    "bands",
                    format!(
                        "band `{}`: response [{lo}, {hi}] µm is outside {}–{} µm{hint}",
                        b.name,
                        crate::radiometry::band::BAND_LIMITS_UM.0,
                        crate::radiometry::band::BAND_LIMITS_UM.1
                    ),
                ));
            }
        }
    }
    Ok(())
}
