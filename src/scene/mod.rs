//! Scene description: the JSON scene file, objects → parts → facets, built-in
//! primitives and the bundled town's generator.
//!
//! [`Scene::load`] reads a scene file ([`file`] documents the format), its
//! material databases and geometry, and gives:
//! - [`Scene::geometry`]: the [`SceneGeometry`] the tracer sees (each
//!   object's mesh stored once, placed by its instances);
//! - per facet (global facet numbering, see [`crate::geometry`]) its
//!   [`Part`]: [`Scene::facet_part`], or [`Scene::facet_parts`] for all at
//!   once; a part names its object, its material (index into
//!   [`Scene::materials`]) and per-part overrides, and
//!   [`Scene::part_material`] applies them;
//! - the site, image time, weather reference, and the `sensors`,
//!   `atmosphere` and `render` sections as JSON for later stages.
//!
//! [`Scene::check`] collects *every* problem (each naming the file and the
//! JSON path and line) rather than stopping at the first.
//!
//! It must not know ray tracing, the thermal model or rendering: it
//! describes the scene; later stages read it.

pub mod dirsig;
pub mod file;
pub mod gltf;
pub mod jsonloc;
pub mod obj;
pub mod primitives;
pub mod town;

use std::cell::OnceCell;
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use chrono::{DateTime, FixedOffset};
use glam::{Affine3A, Quat, Vec3};
use rayon::slice::ParallelSliceMut;
use serde::Serialize;
use serde_json::Value;

use crate::error::{Error, Location, Result};
use crate::geometry::{Instance, SceneGeometry, TriangleMesh};
use crate::material::{Material, MaterialDb};
use crate::sun::Site;
use crate::textio::{self, Comments};
use crate::weather::{LoadOptions, WeatherHistory};

pub use file::SceneFile;
pub use gltf::load_gltf;
pub use obj::{ObjGroup, load_obj};
use primitives::GroupedMesh;

/// A part: the faces of one object that share a material and overrides.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Part {
    /// Face group name.
    pub name: String,
    /// Index into [`Scene::objects`].
    pub object: usize,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Thickness override, m.
    pub thickness_m: Option<f64>,
    /// Self-generated power override, W/m².
    pub self_power_w_m2: Option<f64>,
    /// Exposed-area override.
    pub exposed_area: Option<f64>,
    /// Back-boundary override: the part's own, else its object's (None
    /// where the part gives `exposed_area`).
    pub back: Option<crate::material::BackSpec>,
    /// Fixed temperature, K (bypasses the thermal model).
    pub fixed_temperature_k: Option<f64>,
    /// Default sky-view shape factor, 0..=1.
    pub shape_factor: Option<f64>,
}

/// An object of the scene: one mesh, placed by a range of instances.
#[derive(Debug, Clone, Serialize)]
pub struct SceneObject {
    /// Name.
    pub name: String,
    /// Index into `geometry.meshes`.
    pub mesh: usize,
    /// Its instances: indices into `geometry.instances`.
    pub instances: Range<usize>,
}

/// The weather history of a scene, loaded with `irsig::weather`.
#[derive(Debug, Clone)]
pub struct WeatherRef {
    /// The file, resolved against the scene file's folder.
    pub path: PathBuf,
    /// The history (covers the image time).
    pub history: WeatherHistory,
}

/// A loaded scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// Free text.
    pub description: Option<String>,
    /// Site position.
    pub site: Site,
    /// Local time offset from UTC, hours.
    pub utc_offset_hours: f64,
    /// Image time.
    pub time: DateTime<FixedOffset>,
    /// Weather history reference.
    pub weather: Option<WeatherRef>,
    /// All materials of the scene's databases.
    pub materials: MaterialDb,
    /// Objects, in file order.
    pub objects: Vec<SceneObject>,
    /// Parts of all objects.
    pub parts: Vec<Part>,
    /// Meshes (one per object) and instances.
    pub geometry: SceneGeometry,
    /// Per mesh, per triangle: index into [`Scene::parts`].
    pub mesh_parts: Vec<Vec<u32>>,
    /// Per instance: index into [`Scene::objects`].
    pub instance_object: Vec<usize>,
    /// `geometry.facet_offsets()`, cached.
    pub facet_offsets: Vec<usize>,
    /// The `sensors` section, as written.
    pub sensors: Vec<Value>,
    /// The `atmosphere` section, as written.
    pub atmosphere: Option<Value>,
    /// The `render` section, as written.
    pub render: Option<Value>,
    /// Suspicious input that is not an error (each naming file, line and
    /// field): a site that looks like radians, a weather file for another
    /// place or time zone, a material's missing emissivity file. The
    /// command line prints them as `warning:` lines.
    pub warnings: Vec<String>,
}

/// How far (km) a weather file's own site may lie from the scene's before
/// the scene warns.
pub const WEATHER_SITE_TOLERANCE_KM: f64 = 50.0;

/// An OBJ shape larger than this (m, largest bounding-box side after
/// `unit`) is warned about: likely millimetres or centimetres read as metres.
pub const MESH_EXTENT_MAX_M: f64 = 5000.0;

/// An OBJ file smaller than this (m, largest bounding-box side after
/// `unit`) is warned about: likely metres read as millimetres, or a model in
/// kilometres.
pub const MESH_EXTENT_MIN_M: f64 = 0.05;

/// The signed volume (m³) a triangle mesh encloses, by the divergence
/// theorem (Σ p₀·(p₁×p₂)/6: positive when faces are counter-clockwise seen
/// from outside), or `None` if the mesh is not closed: every edge, with
/// vertices matched by position, must be shared by exactly two triangles.
pub fn closed_signed_volume(positions: &[Vec3], indices: &[[u32; 3]]) -> Option<f64> {
    if indices.is_empty() {
        return None;
    }
    // Weld by exact position (OBJ and glTF often repeat a vertex per face):
    // vertices sorted by their coordinates' bits, equal runs share an id.
    let key = |i: u32| positions[i as usize].to_array().map(f32::to_bits);
    let mut order: Vec<u32> = (0..positions.len() as u32).collect();
    order.par_sort_unstable_by_key(|&i| key(i));
    let mut weld = vec![0u32; positions.len()];
    let mut id = 0u32;
    for (k, &i) in order.iter().enumerate() {
        if k > 0 && key(i) != key(order[k - 1]) {
            id += 1;
        }
        weld[i as usize] = id;
    }
    drop(order);
    // Every edge (welded, unordered) of the non-degenerate triangles must
    // occur exactly twice: sorted, each run has length 2.
    let mut edges: Vec<u64> = Vec::with_capacity(3 * indices.len());
    for t in indices {
        let w = t.map(|i| weld[i as usize]);
        if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (w[k], w[(k + 1) % 3]);
            edges.push(u64::from(a.min(b)) << 32 | u64::from(a.max(b)));
        }
    }
    if edges.is_empty() {
        return None;
    }
    edges.par_sort_unstable();
    if edges.chunk_by(|a, b| a == b).any(|run| run.len() != 2) {
        return None;
    }
    let v: f64 = indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize].as_dvec3());
            a.dot(b.cross(c))
        })
        .sum();
    Some(v / 6.0)
}

/// The weather history before an image time that the thermal solve uses
/// (the render's default history window, 24 h).
pub const HISTORY_WINDOW: chrono::TimeDelta = chrono::TimeDelta::hours(24);

/// Gaps in `h` longer than [`WEATHER_GAP_STEPS`] of its typical (median)
/// step that overlap `from ..= to`, each described with its start and end
/// times: the weather across them is interpolated linearly, which hides
/// a missing afternoon's sun or a front.
pub fn weather_gaps(
    h: &WeatherHistory,
    from: DateTime<FixedOffset>,
    to: DateTime<FixedOffset>,
) -> Vec<String> {
    let r = h.records();
    let mut steps: Vec<chrono::TimeDelta> = r.windows(2).map(|w| w[1].time - w[0].time).collect();
    if steps.len() < 2 {
        return Vec::new();
    }
    steps.sort();
    let typical = steps[steps.len() / 2];
    r.windows(2)
        .filter(|w| {
            let d = w[1].time - w[0].time;
            d > typical * WEATHER_GAP_STEPS && w[0].time < to && w[1].time > from
        })
        .map(|w| {
            let d = w[1].time - w[0].time;
            format!(
                "no weather records from {} to {} ({:.1} h, the file's step being {:.2} h) \
                 inside the 24 h history before the image time; the gap is interpolated linearly",
                w[0].time.to_rfc3339(),
                w[1].time.to_rfc3339(),
                d.num_seconds() as f64 / 3600.0,
                typical.num_seconds() as f64 / 3600.0
            )
        })
        .collect()
}

/// A weather gap longer than this many typical steps is warned about.
pub const WEATHER_GAP_STEPS: i32 = 3;

/// Memory assumed available (bytes) where `/proc/meminfo` cannot be read:
/// 16 GiB.
pub const FALLBACK_MEMORY_BYTES: u64 = 16 << 30;

/// Memory available for new allocations, bytes: `MemAvailable` of
/// `/proc/meminfo` (Linux), else [`FALLBACK_MEMORY_BYTES`].
pub fn available_memory_bytes() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find_map(|l| l.strip_prefix("MemAvailable:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        })
        .map_or(FALLBACK_MEMORY_BYTES, |kb| kb * 1024)
}

/// Sensors whose image would not fit in `available` bytes, as errors naming
/// the sensor's width field (`sensors[i].width`, or `samples_per_line` for a
/// line scanner) and the estimate in GiB: width × height × oversample² ×
/// (bands + `extra_layers`, the renderer's truth layers) × 4 bytes (f32),
/// divided over `tiles` row bands
/// (`render --tile K/N` holds one band at a time). Sensors without those
/// keys are left to the sensor stage's own errors.
pub fn image_memory_errors(
    scene: &Scene,
    extra_layers: usize,
    tiles: usize,
    available: u64,
) -> Vec<Error> {
    let lines = std::fs::read_to_string(&scene.path)
        .ok()
        .map(|t| jsonloc::JsonLines::new(&t));
    let mut errors = Vec::new();
    for (i, s) in scene.sensors.iter().enumerate() {
        let num = |k: &str| s.get(k).and_then(Value::as_u64);
        let (field, w, h) = match (num("width"), num("height")) {
            (Some(w), Some(h)) => ("width", w, h),
            _ => match (num("samples_per_line"), num("lines")) {
                (Some(w), Some(h)) => ("samples_per_line", w, h),
                _ => continue,
            },
        };
        let os = num("oversample").unwrap_or(1) as f64;
        let bands = s.get("bands").and_then(Value::as_array).map_or(1, Vec::len);
        let layers = (bands + extra_layers) as f64;
        let bytes = w as f64 * h as f64 * os * os * layers * 4.0 / tiles.max(1) as f64;
        if bytes > available as f64 {
            let field = format!("sensors[{i}].{field}");
            let mut loc = Location::file(&scene.path);
            if let Some((l, c)) = lines.as_ref().and_then(|l| l.position(&field)) {
                loc = loc.at(l, c);
            }
            let per = if tiles > 1 { " per tile" } else { "" };
            errors.push(Error::parse(
                loc.with_field(field),
                format!(
                    "the image needs about {:.1} GiB{per} ({w} × {h} pixels × {os}² samples × \
                     {layers} layers × 4 bytes) but {:.1} GiB of memory is available: make it \
                     smaller, or render it in row bands with `--tile K/N`",
                    bytes / (1u64 << 30) as f64,
                    available as f64 / (1u64 << 30) as f64
                ),
            ));
        }
    }
    errors
}

/// What `irsig scene check` prints.
#[derive(Debug, Clone, Serialize)]
pub struct SceneSummary {
    /// The scene file.
    pub path: PathBuf,
    /// Site latitude, longitude (deg), altitude (m).
    pub site: [f64; 3],
    /// Image time, RFC 3339.
    pub time: String,
    /// Weather file, if any.
    pub weather: Option<PathBuf>,
    /// Weather records and the first and last record times (RFC 3339).
    pub weather_records: Option<(usize, String, String)>,
    /// Number of objects.
    pub objects: usize,
    /// Number of instances.
    pub instances: usize,
    /// Number of parts.
    pub parts: usize,
    /// Triangles stored (each mesh once).
    pub triangles_stored: usize,
    /// Triangles placed (facets: over all instances).
    pub triangles_placed: usize,
    /// Materials in the databases.
    pub materials_available: usize,
    /// Materials used, with their facet counts, in database order.
    pub materials_used: Vec<(String, usize)>,
    /// World bounding box min, m.
    pub bounds_min: [f32; 3],
    /// World bounding box max, m.
    pub bounds_max: [f32; 3],
    /// Number of sensors.
    pub sensors: usize,
    /// Per object: name, instances, triangles per instance.
    pub object_list: Vec<(String, usize, usize)>,
}

/// One error for a list of problems: the problem itself when there is one.
fn join_errors(errs: Vec<Error>) -> Error {
    if errs.len() == 1 {
        errs.into_iter().next().expect("one")
    } else {
        let n = errs.len();
        let list: Vec<String> = errs.iter().map(|e| format!("  {e}")).collect();
        Error::Other(format!("{n} problems in the scene:\n{}", list.join("\n")))
    }
}

impl Scene {
    /// Load a scene file; the error lists every problem found.
    pub fn load(path: &Path) -> Result<Scene> {
        Self::check(path).map_err(join_errors)
    }

    /// [`Scene::load`] for a DIRSIG scene or simulation imported with `options`.
    pub fn load_dirsig(path: &Path, options: &dirsig::ImportOptions) -> Result<Scene> {
        Self::check_dirsig(path, options).map_err(join_errors)
    }

    /// Load a scene file, collecting every problem found. A DIRSIG scene or
    /// simulation (`.scene`, `.jsim`, `.sim`; [`dirsig::is_dirsig_scene`]) is imported
    /// first ([`dirsig::import`], into a temporary folder); the import's warnings come
    /// first in [`Scene::warnings`].
    pub fn check(path: &Path) -> std::result::Result<Scene, Vec<Error>> {
        if dirsig::is_dirsig_scene(path) {
            return Self::check_dirsig(path, &dirsig::ImportOptions::default());
        }
        Loader::new(path)?.load()
    }

    /// Import a DIRSIG scene or simulation with `options` and load the result, collecting
    /// every problem found.
    pub fn check_dirsig(
        path: &Path,
        options: &dirsig::ImportOptions,
    ) -> std::result::Result<Scene, Vec<Error>> {
        let tmp = tempfile::Builder::new()
            .prefix("irsig-dirsig-")
            .tempdir()
            .map_err(|e| vec![Error::io(std::env::temp_dir(), e)])?;
        let out = tmp.path().join(format!(
            "{}.json",
            path.file_stem()
                .map_or("scene".into(), |s| s.to_string_lossy())
        ));
        let imported = dirsig::import(path, &out, options).map_err(|e| vec![e])?;
        imported.write(&out).map_err(|e| vec![e])?;
        let mut scene = Loader::new(&out)?.load()?;
        // Everything the scene needs was read while loading; the temporary files go.
        scene.path = path.to_path_buf();
        let mut warnings = imported.warnings;
        warnings.append(&mut scene.warnings);
        scene.warnings = warnings;
        Ok(scene)
    }

    /// Index into [`Scene::parts`] of primitive `prim` of instance `instance`.
    pub fn part_index(&self, instance: usize, prim: usize) -> usize {
        self.mesh_parts[self.geometry.instances[instance].mesh][prim] as usize
    }

    /// The part of global facet `facet`.
    pub fn facet_part(&self, facet: usize) -> &Part {
        let inst = self.facet_offsets.partition_point(|&o| o <= facet) - 1;
        &self.parts[self.part_index(inst, facet - self.facet_offsets[inst])]
    }

    /// Part index of every facet, in global facet order.
    pub fn facet_parts(&self) -> Vec<u32> {
        let mut v = Vec::with_capacity(self.geometry.facet_count());
        for inst in &self.geometry.instances {
            v.extend_from_slice(&self.mesh_parts[inst.mesh]);
        }
        v
    }

    /// The material of part `part` with the part's overrides applied
    /// (thickness, self power, exposed area, back boundary: a part's
    /// `back` or `exposed_area` over its object's `back` over the
    /// material's).
    pub fn part_material(&self, part: usize) -> Material {
        let p = &self.parts[part];
        let mut m = self.materials.materials()[p.material].clone();
        if let Some(t) = p.thickness_m {
            m.thickness_m = t;
        }
        if let Some(q) = p.self_power_w_m2 {
            m.self_power_w_m2 = q;
        }
        if let Some(e) = p.exposed_area {
            m.exposed_area = e;
            m.back = None;
        }
        if let Some(b) = &p.back {
            m.back = Some(b.clone());
            m.exposed_area = 0.0;
        }
        m
    }

    /// Summary for `irsig scene check`.
    pub fn summary(&self) -> SceneSummary {
        let mut used = vec![0usize; self.materials.len()];
        for inst in &self.geometry.instances {
            for &p in &self.mesh_parts[inst.mesh] {
                used[self.parts[p as usize].material] += 1;
            }
        }
        let (lo, hi) = self.geometry.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
        SceneSummary {
            path: self.path.clone(),
            site: [
                self.site.latitude_deg,
                self.site.longitude_deg,
                self.site.altitude_m,
            ],
            time: self.time.to_rfc3339(),
            weather: self.weather.as_ref().map(|w| w.path.clone()),
            weather_records: self.weather.as_ref().map(|w| {
                (
                    w.history.records().len(),
                    w.history.start().to_rfc3339(),
                    w.history.end().to_rfc3339(),
                )
            }),
            objects: self.objects.len(),
            instances: self.geometry.instances.len(),
            parts: self.parts.len(),
            triangles_stored: self.geometry.stored_triangle_count(),
            triangles_placed: self.geometry.facet_count(),
            materials_available: self.materials.len(),
            materials_used: used
                .iter()
                .enumerate()
                .filter(|(_, n)| **n > 0)
                .map(|(i, n)| (self.materials.materials()[i].name.clone(), *n))
                .collect(),
            bounds_min: lo.to_array(),
            bounds_max: hi.to_array(),
            sensors: self.sensors.len(),
            object_list: self
                .objects
                .iter()
                .map(|o| {
                    (
                        o.name.clone(),
                        o.instances.len(),
                        self.geometry.meshes[o.mesh].triangle_count(),
                    )
                })
                .collect(),
        }
    }
}

/// The JSON Schema of the scene file format, pretty-printed.
pub fn schema_json() -> String {
    let s = schemars::schema_for!(SceneFile);
    serde_json::to_string_pretty(&s).expect("schema serialises") + "\n"
}

/// Problems with a transform (as messages): a `matrix` that is not 16 finite numbers
/// with last row `0, 0, 0, 1`, or given together with `translate`, `rotate_deg` or
/// `scale`.
pub fn transform_problems(t: &file::TransformSpec) -> Vec<String> {
    let mut p = Vec::new();
    if let Some(m) = &t.matrix {
        if m.len() != 16 || m.iter().any(|v| !v.is_finite()) {
            p.push(format!(
                "`matrix` needs 16 finite numbers (4 rows of 4), found {}",
                m.len()
            ));
        } else if m[12..16] != [0.0, 0.0, 0.0, 1.0] {
            p.push(format!(
                "`matrix` last row is {:?}: expected [0, 0, 0, 1] (an affine transform; translation in the fourth column)",
                &m[12..16]
            ));
        }
        if t.translate.is_some() || t.rotate_deg.is_some() || t.scale.is_some() {
            p.push("`matrix` replaces `translate`, `rotate_deg` and `scale`: give one form".into());
        }
    }
    p
}

/// Object → parent transform: scale, then rotate x, y, z, then translate; or the
/// `matrix` (row by row, translation in the fourth column) when given and valid (see
/// [`transform_problems`]).
pub fn transform_affine(t: &file::TransformSpec) -> Affine3A {
    if let Some(m) = t.matrix.as_deref().filter(|m| m.len() == 16) {
        let c = |j: usize| Vec3::new(m[j] as f32, m[4 + j] as f32, m[8 + j] as f32);
        return Affine3A::from_cols(c(0).into(), c(1).into(), c(2).into(), c(3).into());
    }
    let s = match &t.scale {
        None => Vec3::ONE,
        Some(file::Scale::Uniform(s)) => Vec3::splat(*s as f32),
        Some(file::Scale::PerAxis(v)) => Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32),
    };
    let r = t.rotate_deg.unwrap_or([0.0; 3]);
    let q = Quat::from_rotation_z(r[2].to_radians() as f32)
        * Quat::from_rotation_y(r[1].to_radians() as f32)
        * Quat::from_rotation_x(r[0].to_radians() as f32);
    let tr = t.translate.unwrap_or([0.0; 3]);
    Affine3A::from_scale_rotation_translation(
        s,
        q,
        Vec3::new(tr[0] as f32, tr[1] as f32, tr[2] as f32),
    )
}

struct Loader {
    path: PathBuf,
    base: PathBuf,
    text: String,
    lines: OnceCell<jsonloc::JsonLines>,
    errors: Vec<Error>,
    warnings: Vec<String>,
}

impl Loader {
    fn new(path: &Path) -> std::result::Result<Self, Vec<Error>> {
        let text = std::fs::read_to_string(path).map_err(|e| vec![Error::io(path, e)])?;
        Ok(Loader {
            path: path.to_path_buf(),
            base: path.parent().unwrap_or(Path::new(".")).to_path_buf(),
            text,
            lines: OnceCell::new(),
            errors: Vec::new(),
            warnings: Vec::new(),
        })
    }

    fn loc(&self, field: &str) -> Location {
        let l = self
            .lines
            .get_or_init(|| jsonloc::JsonLines::new(&self.text));
        let mut loc = Location::file(&self.path);
        if let Some((n, c)) = l.position(field) {
            loc = loc.at(n, c);
        }
        loc.with_field(field)
    }

    fn err(&mut self, field: &str, msg: impl Into<String>) {
        let e = Error::parse(self.loc(field), msg);
        self.errors.push(e);
    }

    /// Something suspicious that is not an error: kept in
    /// [`Scene::warnings`], named like an error (file, line, field).
    fn warn(&mut self, field: &str, msg: impl Into<String>) {
        let w = Error::parse(self.loc(field), msg).to_string();
        self.warnings.push(w);
    }

    fn resolve(&self, p: &str) -> PathBuf {
        let p = Path::new(p);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base.join(p)
        }
    }

    fn load(mut self) -> std::result::Result<Scene, Vec<Error>> {
        let f: SceneFile = serde_json::from_str(&self.text)
            .map_err(|e| vec![jsonloc::serde_error(&self.path, &e)])?;
        // Site and time.
        let s = &f.site;
        if !(-90.0..=90.0).contains(&s.latitude_deg) {
            self.err(
                "site.latitude_deg",
                format!("{}°: expected −90..=90 (north positive)", s.latitude_deg),
            );
        }
        if !(-180.0..=180.0).contains(&s.longitude_deg) {
            self.err(
                "site.longitude_deg",
                format!("{}°: expected −180..=180 (east positive)", s.longitude_deg),
            );
        }
        if !(s.altitude_m.is_finite() && (-500.0..=9000.0).contains(&s.altitude_m)) {
            self.err(
                "site.altitude_m",
                format!("{} m: expected −500..=9000", s.altitude_m),
            );
        }
        if !(-12.0..=14.0).contains(&s.utc_offset_hours) {
            self.err(
                "site.utc_offset_hours",
                format!("{} h: expected −12..=14", s.utc_offset_hours),
            );
        }
        let site = Site {
            latitude_deg: s.latitude_deg,
            longitude_deg: s.longitude_deg,
            altitude_m: s.altitude_m,
        };
        if s.latitude_deg.abs() <= std::f64::consts::FRAC_PI_2
            && s.longitude_deg.abs() <= std::f64::consts::PI
            && (s.latitude_deg, s.longitude_deg) != (0.0, 0.0)
        {
            self.warn(
                "site",
                format!(
                    "latitude {} and longitude {} look like radians ({:.2}°, {:.2}°); irsig takes degrees",
                    s.latitude_deg,
                    s.longitude_deg,
                    s.latitude_deg.to_degrees(),
                    s.longitude_deg.to_degrees()
                ),
            );
        }
        let time = match crate::sun::parse_time(&f.time) {
            Ok(t) => {
                let offset_h = f64::from(t.offset().local_minus_utc()) / 3600.0;
                if s.utc_offset_hours.is_finite() && (offset_h - s.utc_offset_hours).abs() > 1e-6 {
                    self.err(
                        "site.utc_offset_hours",
                        format!(
                            "{} h, but the image time {} is at UTC{}: the two must agree \
                             (the site's offset is the one its times carry)",
                            s.utc_offset_hours,
                            f.time.trim(),
                            t.offset()
                        ),
                    );
                }
                Some(t)
            }
            Err(e) => {
                self.err("time", e.to_string());
                None
            }
        };
        // Weather.
        let mut weather = None;
        if let Some(w) = &f.weather {
            let p = self.resolve(&w.file);
            let mut opts = LoadOptions::default().with_site(site);
            if let Some(y) = w.year {
                opts = opts.with_year(y);
            }
            if let Some(t) = time {
                // A typical-year EPW/TMY3 file takes the image time's year.
                opts = opts.with_typical_year(chrono::Datelike::year(&t));
            }
            let mut ok = true;
            if let Some(st) = &w.start {
                match crate::sun::parse_time(st) {
                    Ok(t) => opts = opts.with_start(t),
                    Err(e) => {
                        self.err("weather.start", e.to_string());
                        ok = false;
                    }
                }
            }
            let site_ok = (-90.0..=90.0).contains(&site.latitude_deg)
                && (-180.0..=180.0).contains(&site.longitude_deg);
            if !p.is_file() {
                self.err(
                    "weather.file",
                    format!("weather file {} not found", p.display()),
                );
            } else if ok && site_ok {
                match crate::weather::load_with(&p, &opts) {
                    Ok(h) => {
                        if let Some(t) = time {
                            if t < h.start() || t > h.end() {
                                let hint = if matches!(
                                    h.format(),
                                    Some(
                                        crate::weather::Format::Epw | crate::weather::Format::Tmy3
                                    )
                                ) && w.year.is_none()
                                {
                                    " (for a typical-year file written with one year, set \
                                     `weather.year` to the image time's year)"
                                } else {
                                    ""
                                };
                                self.err(
                                    "weather.file",
                                    format!(
                                        "the weather history covers {} .. {}, not the image time {}{hint}",
                                        h.start().to_rfc3339(),
                                        h.end().to_rfc3339(),
                                        t.to_rfc3339()
                                    ),
                                );
                            }
                        }
                        self.check_weather_site(&site, time, &p, &h);
                        if let Some(t) = time {
                            for g in weather_gaps(&h, t - HISTORY_WINDOW, t) {
                                self.warn("weather.file", format!("{}: {g}", p.display()));
                            }
                        }
                        weather = Some(WeatherRef {
                            path: p,
                            history: h,
                        });
                    }
                    Err(e) => self.err("weather.file", format!("cannot read the weather: {e}")),
                }
            }
        }
        // Materials.
        let mut materials = MaterialDb::new();
        if f.materials.is_empty() {
            self.err("materials", "no material database given");
        }
        for (i, m) in f.materials.iter().enumerate() {
            let p = self.resolve(m);
            if !p.is_file() {
                self.err(
                    &format!("materials[{i}]"),
                    format!("material database {} not found", p.display()),
                );
                continue;
            }
            let db = if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("mat")) {
                crate::material::dirsig::load_mat(&p).map_err(|e| vec![e])
            } else {
                crate::material::db::load_json_all(&p)
            };
            match db {
                Ok(db) => {
                    if let Err(e) = materials.merge(db) {
                        self.errors.push(e);
                    }
                }
                Err(es) => self.errors.extend(es),
            }
        }
        // Objects.
        let mut geometry = SceneGeometry::default();
        let mut objects = Vec::new();
        let mut parts: Vec<Part> = Vec::new();
        let mut mesh_parts = Vec::new();
        let mut instance_object = Vec::new();
        let mut names: HashMap<String, usize> = HashMap::new();
        for (k, o) in f.objects.iter().enumerate() {
            let at = format!("objects[{k}]");
            if let Some(prev) = names.insert(o.name.clone(), k) {
                self.err(
                    &format!("{at}.name"),
                    format!("object name `{}` already used by objects[{prev}]", o.name),
                );
            }
            let Some(gm) = self.object_mesh(o, &at) else {
                continue;
            };
            let Some(group_part) =
                self.object_parts(o, &at, &gm, &materials, objects.len(), &mut parts)
            else {
                continue;
            };
            let mut bad_transform = false;
            let specs = o.transform.iter().map(|t| (format!("{at}.transform"), t));
            let inst = o.instances.iter().flatten().enumerate();
            let specs = specs.chain(inst.map(|(i, t)| (format!("{at}.instances[{i}]"), t)));
            let shape = o.shapes.iter().enumerate();
            let shape = shape.filter_map(|(j, s)| {
                s.transform
                    .as_ref()
                    .map(|t| (format!("{at}.shapes[{j}].transform"), t))
            });
            for (field, t) in specs.chain(shape).collect::<Vec<_>>() {
                for p in transform_problems(t) {
                    self.err(&field, p);
                    bad_transform = true;
                }
            }
            if bad_transform {
                continue;
            }
            let obj_t = o
                .transform
                .as_ref()
                .map(transform_affine)
                .unwrap_or(Affine3A::IDENTITY);
            let inst_specs: Vec<(String, Affine3A)> = match &o.instances {
                None => vec![(format!("{at}.transform"), obj_t)],
                Some(v) => v
                    .iter()
                    .enumerate()
                    .map(|(i, t)| (format!("{at}.instances[{i}]"), transform_affine(t) * obj_t))
                    .collect(),
            };
            if inst_specs.is_empty() {
                self.err(
                    &format!("{at}.instances"),
                    "empty instance list: the object would not appear",
                );
                continue;
            }
            let mesh_index = geometry.meshes.len();
            let first = geometry.instances.len();
            for (field, a) in inst_specs {
                let det = a.matrix3.determinant();
                if !(det.is_finite() && det > 0.0) {
                    self.err(
                        &field,
                        format!(
                            "transform has determinant {det}: expected > 0 (no zero or mirroring scale on placements)"
                        ),
                    );
                    continue;
                }
                geometry.instances.push(Instance {
                    mesh: mesh_index,
                    world_from_object: a,
                });
                instance_object.push(objects.len());
            }
            mesh_parts.push(
                gm.group_of
                    .iter()
                    .map(|g| group_part[*g as usize])
                    .collect(),
            );
            geometry.meshes.push(TriangleMesh {
                name: o.name.clone(),
                positions: gm.positions,
                indices: gm.indices,
            });
            objects.push(SceneObject {
                name: o.name.clone(),
                mesh: mesh_index,
                instances: first..geometry.instances.len(),
            });
        }
        if f.objects.is_empty() {
            self.err("objects", "the scene has no objects");
        }
        for (i, s) in f.sensors.iter().enumerate() {
            if !s.get("type").is_some_and(Value::is_string) {
                self.err(
                    &format!("sensors[{i}]"),
                    "a sensor needs a `type` string (`frame` or `line_scanner`)",
                );
            }
            // Response files read with changes (small negative values set to zero) warn
            // here; their errors are the sensor's, reported when it is built.
            let bands = s.get("bands").and_then(Value::as_array);
            for b in bands.into_iter().flatten() {
                if let Some(f) = b.get("response").and_then(Value::as_str) {
                    if let Ok(r) = crate::radiometry::read_response_csv(self.resolve(f)) {
                        self.warnings.extend(r.warnings().iter().cloned());
                    }
                }
            }
        }
        if !self.errors.is_empty() {
            return Err(self.errors);
        }
        let mut warnings = self.warnings;
        warnings.extend(materials.warnings.iter().cloned());
        let facet_offsets = geometry.facet_offsets();
        Ok(Scene {
            path: self.path,
            description: f.description,
            site,
            utc_offset_hours: f.site.utc_offset_hours,
            time: time.expect("no errors"),
            weather,
            materials,
            objects,
            parts,
            geometry,
            mesh_parts,
            instance_object,
            facet_offsets,
            sensors: f.sensors.into_iter().map(Value::Object).collect(),
            atmosphere: f.atmosphere,
            render: f.render.map(Value::Object),
            warnings,
        })
    }

    /// Warnings where the weather file's own site (EPW, TMY3 and irsig
    /// files carry one) is more than [`WEATHER_SITE_TOLERANCE_KM`] from the
    /// scene's, or its clock differs from the image time's by more than an
    /// hour (one hour is daylight saving: EPW and TMY3 are in standard time).
    fn check_weather_site(
        &mut self,
        site: &Site,
        time: Option<DateTime<FixedOffset>>,
        path: &Path,
        h: &WeatherHistory,
    ) {
        if let Some(w) = h.site() {
            let d = site.distance_km(w);
            if d > WEATHER_SITE_TOLERANCE_KM {
                self.warn(
                    "weather.file",
                    format!(
                        "{} is for a site {d:.0} km from the scene's ({:.3}°, {:.3}° against {:.3}°, {:.3}°): is it the right file, or the site's sign?",
                        path.display(),
                        w.latitude_deg,
                        w.longitude_deg,
                        site.latitude_deg,
                        site.longitude_deg
                    ),
                );
            }
        }
        if let (Some(t), Some(r)) = (time, h.records().first()) {
            let dt = (t.offset().local_minus_utc() - r.time.offset().local_minus_utc()).abs();
            if dt > 3600 {
                self.warn(
                    "weather.file",
                    format!(
                        "{} keeps time at UTC{} but the image time is at UTC{}: is it the right file?",
                        path.display(),
                        r.time.offset(),
                        t.offset()
                    ),
                );
            }
        }
    }

    /// The merged, grouped mesh of an object's shapes (object space).
    fn object_mesh(&mut self, o: &file::ObjectSpec, at: &str) -> Option<GroupedMesh> {
        let mut out = GroupedMesh::default();
        let mut ok = true;
        if o.shapes.is_empty() {
            self.err(
                &format!("{at}.shapes"),
                format!("object `{}` has no shapes", o.name),
            );
            return None;
        }
        for (j, s) in o.shapes.iter().enumerate() {
            let sat = format!("{at}.shapes[{j}]");
            match self.shape_mesh(s, &sat, &o.name) {
                Some(mut m) => {
                    if let Some(p) = &s.part {
                        m.groups = vec![p.clone()];
                        m.group_of.iter_mut().for_each(|g| *g = 0);
                    }
                    if let Some(t) = &s.transform {
                        let a = transform_affine(t);
                        let det = a.matrix3.determinant();
                        if !(det.is_finite() && det != 0.0) {
                            self.err(
                                &format!("{sat}.transform"),
                                "transform is singular (zero scale?)",
                            );
                            ok = false;
                            continue;
                        }
                        for p in &mut m.positions {
                            *p = a.transform_point3(*p);
                        }
                        if det < 0.0 {
                            // Mirrored: keep faces counter-clockwise from the front.
                            for t in &mut m.indices {
                                t.swap(1, 2);
                            }
                        }
                    }
                    out.append(&m);
                }
                None => ok = false,
            }
        }
        ok.then_some(out)
    }

    /// Warnings on a loaded `obj`/`gltf` shape (in metres, Z up, before
    /// the shape's transform): a closed mesh whose normals mostly face
    /// inward (negative enclosed volume), and an OBJ whose extent is
    /// implausible for its unit (over [`MESH_EXTENT_MAX_M`], or under
    /// [`MESH_EXTENT_MIN_M`] for a whole file).
    fn check_mesh_file(
        &mut self,
        m: &GroupedMesh,
        s: &file::ShapeSpec,
        at: &str,
        object: &str,
        kind: &str,
        path: &Path,
    ) {
        if let Some(v) = closed_signed_volume(&m.positions, &m.indices) {
            if v < 0.0 {
                let advice = if s.flip_normals {
                    "remove `\"flip_normals\": true`"
                } else {
                    "add `\"flip_normals\": true` to the shape"
                };
                self.warn(
                    at,
                    format!(
                        "object `{object}`: {} is a closed mesh whose normals face inward (enclosed \
                         volume {v:.3} m³): its outside would be treated as inside (no sun, wrong \
                         temperatures); {advice}",
                        path.display()
                    ),
                );
            }
        }
        if kind != "obj" || m.positions.is_empty() {
            return;
        }
        let (lo, hi) = m.positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let extent = f64::from((hi - lo).max_element());
        let unit = s
            .unit
            .and_then(|u| serde_json::to_string(&u).ok())
            .unwrap_or_else(|| "\"m\" (the default)".into());
        if extent > MESH_EXTENT_MAX_M {
            self.warn(
                at,
                format!(
                    "object `{object}`: {} spans {:.1} km in unit {unit}: is it in another unit \
                     (set the shape's `unit`: \"cm\", \"mm\", \"ft\", \"in\")?",
                    path.display(),
                    extent / 1000.0
                ),
            );
        } else if extent < MESH_EXTENT_MIN_M {
            self.warn(
                at,
                format!(
                    "object `{object}`: {} spans only {:.1} mm in unit {unit}: is it in another \
                     unit (set the shape's `unit`)?",
                    path.display(),
                    extent * 1000.0
                ),
            );
        }
    }

    fn shape_mesh(&mut self, s: &file::ShapeSpec, at: &str, object: &str) -> Option<GroupedMesh> {
        let kinds = [
            ("obj", s.obj.is_some()),
            ("gltf", s.gltf.is_some()),
            ("box", s.box_.is_some()),
            ("plane", s.plane.is_some()),
            ("heightmap", s.heightmap.is_some()),
            ("cylinder", s.cylinder.is_some()),
            ("cone", s.cone.is_some()),
            ("sphere", s.sphere.is_some()),
            ("gable_roof", s.gable_roof.is_some()),
        ];
        let given: Vec<&str> = kinds.iter().filter(|k| k.1).map(|k| k.0).collect();
        if given.len() != 1 {
            self.err(
                at,
                format!(
                    "a shape needs exactly one of obj, gltf, box, plane, heightmap, cylinder, cone, sphere, gable_roof; found {}",
                    if given.is_empty() { "none".to_string() } else { given.join(", ") }
                ),
            );
            return None;
        }
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let bad = |this: &mut Self, field: &str, msg: String| {
            this.err(&format!("{at}.{field}"), msg);
            None::<GroupedMesh>
        };
        let segs = |n: Option<usize>, d: usize| n.unwrap_or(d);
        if s.flip_normals && s.obj.is_none() && s.gltf.is_none() {
            return bad(
                self,
                "flip_normals",
                "`flip_normals` applies to `obj` and `gltf` shapes only (primitives face outward)"
                    .into(),
            );
        }
        if s.obj.is_none() && (s.up_axis.is_some() || s.unit.is_some()) {
            let field = if s.up_axis.is_some() {
                "up_axis"
            } else {
                "unit"
            };
            return bad(
                self,
                field,
                format!(
                    "`{field}` applies to `obj` shapes only (glTF is Y-up in metres by \
                     definition; primitives are in metres, Z up)"
                ),
            );
        }
        let mesh_file = match (&s.obj, &s.gltf) {
            (Some(p), _) => Some((p, "obj", load_obj as fn(&Path) -> Result<Vec<ObjGroup>>)),
            (None, Some(p)) => Some((p, "gltf", load_gltf as fn(&Path) -> Result<Vec<ObjGroup>>)),
            (None, None) => None,
        };
        if let Some((p, kind, load)) = mesh_file {
            let path = self.resolve(p);
            return match load(&path) {
                Ok(groups) => {
                    let mut m = GroupedMesh::default();
                    for g in groups {
                        let name = g.material_name.clone().unwrap_or(g.name.clone());
                        let gi = m.group(&name);
                        let base = m.positions.len() as u32;
                        m.positions.extend(g.mesh.positions);
                        for t in g.mesh.indices {
                            m.indices.push(t.map(|i| i + base));
                            m.group_of.push(gi);
                        }
                    }
                    let metres = s.unit.map_or(1.0, file::LengthUnit::metres) as f32;
                    let y_up = s.up_axis == Some(file::UpAxis::Y);
                    for p in &mut m.positions {
                        *p *= metres;
                        if y_up {
                            // A proper rotation (+90° about x): faces keep their winding.
                            *p = Vec3::new(p.x, -p.z, p.y);
                        }
                    }
                    if s.flip_normals {
                        for t in &mut m.indices {
                            t.swap(1, 2);
                        }
                    }
                    self.check_mesh_file(&m, s, at, object, kind, &path);
                    Some(m)
                }
                Err(e) => bad(
                    self,
                    kind,
                    format!("cannot load {}: {e}", kind.to_uppercase()),
                ),
            };
        }
        if let Some(b) = &s.box_ {
            if !b.size.iter().all(|v| pos(*v)) {
                return bad(
                    self,
                    "box.size",
                    format!("{:?}: expected three sizes > 0 m", b.size),
                );
            }
            if b.max_edge_m.is_some_and(|e| !pos(e)) {
                return bad(self, "box.max_edge_m", "expected > 0 m".into());
            }
            let sz = Vec3::new(b.size[0] as f32, b.size[1] as f32, b.size[2] as f32);
            return Some(primitives::box_mesh(sz, b.max_edge_m, b.bottom));
        }
        if let Some(p) = &s.plane {
            if !p.size.iter().all(|v| pos(*v)) {
                return bad(
                    self,
                    "plane.size",
                    format!("{:?}: expected two sizes > 0 m", p.size),
                );
            }
            if p.max_edge_m.is_some_and(|e| !pos(e)) {
                return bad(self, "plane.max_edge_m", "expected > 0 m".into());
            }
            return Some(primitives::plane_mesh(
                [p.size[0] as f32, p.size[1] as f32],
                p.max_edge_m,
            ));
        }
        if let Some(c) = &s.cylinder {
            if !pos(c.radius) || !pos(c.height) {
                return bad(self, "cylinder", "radius and height must be > 0 m".into());
            }
            return Some(primitives::cylinder_mesh(
                c.radius as f32,
                c.height as f32,
                segs(c.segments, 16),
                c.caps,
            ));
        }
        if let Some(c) = &s.cone {
            if !pos(c.radius) || !pos(c.height) {
                return bad(self, "cone", "radius and height must be > 0 m".into());
            }
            return Some(primitives::cone_mesh(
                c.radius as f32,
                c.height as f32,
                segs(c.segments, 16),
                c.cap,
            ));
        }
        if let Some(c) = &s.sphere {
            if !pos(c.radius) {
                return bad(self, "sphere.radius", "expected > 0 m".into());
            }
            return Some(primitives::sphere_mesh(
                c.radius as f32,
                segs(c.segments, 16),
                segs(c.rings, 8),
            ));
        }
        if let Some(g) = &s.gable_roof {
            if !(pos(g.width)
                && pos(g.depth)
                && pos(g.height)
                && g.overhang.is_finite()
                && g.overhang >= 0.0)
            {
                return bad(
                    self,
                    "gable_roof",
                    "width, depth, height must be > 0 m and overhang ≥ 0".into(),
                );
            }
            return Some(primitives::gable_roof_mesh(
                g.width as f32,
                g.depth as f32,
                g.height as f32,
                g.overhang as f32,
            ));
        }
        let h = s.heightmap.as_ref().expect("one kind given");
        self.heightmap(h, &format!("{at}.heightmap"))
    }

    fn heightmap(&mut self, h: &file::HeightmapSpec, at: &str) -> Option<GroupedMesh> {
        let [nx, ny] = h.cells;
        if !(h.size.iter().all(|v| v.is_finite() && *v > 0.0)) {
            self.err(&format!("{at}.size"), "expected two sizes > 0 m");
            return None;
        }
        if nx == 0 || ny == 0 || nx * ny > 4_000_000 {
            self.err(
                &format!("{at}.cells"),
                "expected 1..=4,000,000 cells in total, ≥ 1 each way",
            );
            return None;
        }
        let sources = [
            h.heights.is_some(),
            h.heights_csv.is_some(),
            h.function.is_some(),
        ];
        if sources.iter().filter(|x| **x).count() > 1 {
            self.err(at, "give at most one of heights, heights_csv, function");
            return None;
        }
        let (sx, sy) = (h.size[0], h.size[1]);
        let (dx, dy) = (sx / nx as f64, sy / ny as f64);
        // Vertex heights, row-major from the south (j = 0) edge.
        let mut z = vec![0.0f64; (nx + 1) * (ny + 1)];
        let rows: Option<(Vec<Vec<f64>>, String)> = if let Some(r) = &h.heights {
            Some((r.clone(), format!("{at}.heights")))
        } else if let Some(f) = &h.heights_csv {
            let p = self.resolve(f);
            match read_grid_csv(&p) {
                Ok(r) => Some((r, format!("{at}.heights_csv"))),
                Err(e) => {
                    self.err(&format!("{at}.heights_csv"), e.to_string());
                    return None;
                }
            }
        } else {
            None
        };
        if let Some((r, field)) = rows {
            if r.len() != ny + 1 || r.iter().any(|row| row.len() != nx + 1) {
                self.err(
                    &field,
                    format!(
                        "expected {} rows of {} heights (cells + 1 each way), found {} rows",
                        ny + 1,
                        nx + 1,
                        r.len()
                    ),
                );
                return None;
            }
            if r.iter().flatten().any(|v| !v.is_finite()) {
                self.err(&field, "heights must be finite numbers");
                return None;
            }
            for j in 0..=ny {
                for i in 0..=nx {
                    z[j * (nx + 1) + i] = r[ny - j][i];
                }
            }
        } else if let Some(f) = &h.function {
            for w in &f.waves {
                if !(w.wavelength_m.is_finite() && w.wavelength_m > 0.0) {
                    self.err(&format!("{at}.function.waves"), "wavelength_m must be > 0");
                    return None;
                }
            }
            for j in 0..=ny {
                for i in 0..=nx {
                    let x = -sx / 2.0 + i as f64 * dx;
                    let y = -sy / 2.0 + j as f64 * dy;
                    z[j * (nx + 1) + i] = height_function(f, x, y);
                }
            }
        }
        // Classes.
        let mut class_of: Vec<String> = vec!["surface".to_string(); nx * ny];
        if let Some(c) = &h.classes {
            let field = format!("{at}.classes.rows");
            if c.rows.len() != ny {
                self.err(
                    &field,
                    format!("expected {ny} rows (cells[1]), found {}", c.rows.len()),
                );
                return None;
            }
            for (r, row) in c.rows.iter().enumerate() {
                let chars: Vec<char> = row.chars().collect();
                if chars.len() != nx {
                    self.err(
                        &format!("{field}[{r}]"),
                        format!("expected {nx} characters (cells[0]), found {}", chars.len()),
                    );
                    return None;
                }
                let j = ny - 1 - r;
                for (i, ch) in chars.iter().enumerate() {
                    match c.legend.get(&ch.to_string()) {
                        Some(g) => class_of[j * nx + i] = g.clone(),
                        None => {
                            self.err(
                                &format!("{field}[{r}]"),
                                format!(
                                    "character `{ch}` at column {} is not in the legend",
                                    i + 1
                                ),
                            );
                            return None;
                        }
                    }
                }
            }
        }
        Some(primitives::heightmap_mesh(
            [sx as f32, sy as f32],
            nx,
            ny,
            |i, j| z[j * (nx + 1) + i] as f32,
            |i, j| class_of[j * nx + i].clone(),
        ))
    }

    /// Map each face group of `gm` to a part (created here); `None` after
    /// recording errors.
    fn object_parts(
        &mut self,
        o: &file::ObjectSpec,
        at: &str,
        gm: &GroupedMesh,
        db: &MaterialDb,
        object: usize,
        parts: &mut Vec<Part>,
    ) -> Option<Vec<u32>> {
        let mut ok = true;
        if let Some(b) = &o.back {
            for (field, msg) in b.problems() {
                self.err(&format!("{at}.back.{field}"), msg);
                ok = false;
            }
        }
        let mut spec_used = vec![false; o.parts.len()];
        let mut map = Vec::with_capacity(gm.groups.len());
        let material_index = |this: &mut Self, name: &str, field: &str| -> Option<usize> {
            match db.index_of(name) {
                Some(i) => Some(i),
                None => {
                    if !db.is_empty() {
                        let near = db.similar_names(name);
                        let names = db.materials().iter().map(|m| m.name.as_str());
                        let best = crate::suggest::closest(name, names);
                        let others: Vec<&str> =
                            near.into_iter().filter(|n| Some(*n) != best).collect();
                        let hint = match (best, others.is_empty()) {
                            (Some(c), true) => format!(" (did you mean `{c}`?)"),
                            (Some(c), false) => {
                                format!(" (did you mean `{c}`? similar: {})", others.join(", "))
                            }
                            (None, true) => String::new(),
                            (None, false) => format!(" (similar: {})", others.join(", ")),
                        };
                        this.err(field, format!("unknown material `{name}`{hint}"));
                    }
                    None
                }
            }
        };
        for g in &gm.groups {
            let spec = o.parts.iter().position(|p| &p.name == g);
            let part = if let Some(si) = spec {
                spec_used[si] = true;
                let p = &o.parts[si];
                let f = format!("{at}.parts[{si}]");
                let m = material_index(self, &p.material, &format!("{f}.material"));
                let mut good = m.is_some();
                let check = |this: &mut Self,
                             v: Option<f64>,
                             name: &str,
                             ok: &dyn Fn(f64) -> bool,
                             want: &str| {
                    if let Some(v) = v {
                        if !ok(v) {
                            this.err(&format!("{f}.{name}"), format!("{v}: expected {want}"));
                            return false;
                        }
                    }
                    true
                };
                good &= check(
                    self,
                    p.thickness_m,
                    "thickness_m",
                    &|v| v.is_finite() && v > 0.0,
                    "> 0 m",
                );
                good &= check(
                    self,
                    p.self_power_w_m2,
                    "self_power_w_m2",
                    &|v| v.is_finite(),
                    "a finite W/m²",
                );
                good &= check(
                    self,
                    p.exposed_area,
                    "exposed_area",
                    &|v| (-1.0..=1.0).contains(&v),
                    "−1..=1",
                );
                if let Some(b) = &p.back {
                    if p.exposed_area.is_some() {
                        self.err(
                            &format!("{f}.exposed_area"),
                            "give either `exposed_area` or `back`, not both",
                        );
                        good = false;
                    }
                    for (field, msg) in b.problems() {
                        self.err(&format!("{f}.back.{field}"), msg);
                        good = false;
                    }
                }
                if let (Some(t), Some(mi)) = (p.thickness_m, m)
                    && !db.materials()[mi].layers.is_empty()
                {
                    self.err(
                        &format!("{f}.thickness_m"),
                        format!(
                            "{t} m: material `{}` is a layered construction, whose thickness is its layers'; give another material instead",
                            p.material
                        ),
                    );
                    good = false;
                }
                good &= check(
                    self,
                    p.fixed_temperature_k,
                    "fixed_temperature_k",
                    &|v| v > 0.0 && v < 5000.0,
                    "0 < T < 5000 K",
                );
                good &= check(
                    self,
                    p.shape_factor,
                    "shape_factor",
                    &|v| (0.0..=1.0).contains(&v),
                    "0..=1",
                );
                good.then(|| Part {
                    name: g.clone(),
                    object,
                    material: m.expect("checked"),
                    thickness_m: p.thickness_m,
                    self_power_w_m2: p.self_power_w_m2,
                    exposed_area: p.exposed_area,
                    back: match (&p.back, p.exposed_area) {
                        (Some(b), _) => Some(b.clone()),
                        (None, Some(_)) => None,
                        (None, None) => o.back.clone(),
                    },
                    fixed_temperature_k: p.fixed_temperature_k,
                    shape_factor: p.shape_factor,
                })
            } else {
                let (name, field) = match &o.material {
                    Some(m) => (m.clone(), format!("{at}.material")),
                    None => (g.clone(), format!("{at}.shapes")),
                };
                // DIRSIG's OBJ convention: `usemtl <ID>` names a `.mat` ID (a number;
                // a label ID is usually also the NAME). Used when no material has the
                // group's name and exactly one has that ID.
                let by_id = || {
                    let id: u32 = g.trim().parse().ok()?;
                    let mut hits = db
                        .materials()
                        .iter()
                        .enumerate()
                        .filter(|(_, m)| m.id == id);
                    let (i, _) = hits.next()?;
                    hits.next().is_none().then_some(i)
                };
                let found = db
                    .index_of(&name)
                    .or_else(|| if o.material.is_none() { by_id() } else { None });
                match found {
                    Some(m) => Some(Part {
                        name: g.clone(),
                        object,
                        material: m,
                        thickness_m: None,
                        self_power_w_m2: None,
                        exposed_area: None,
                        back: o.back.clone(),
                        fixed_temperature_k: None,
                        shape_factor: None,
                    }),
                    None => {
                        if o.material.is_some() {
                            material_index(self, &name, &field);
                        } else if !db.is_empty() {
                            self.err(
                                &field,
                                format!(
                                    "object `{}`: face group `{g}` has no part, the object no `material`, and no material is named `{g}`",
                                    o.name
                                ),
                            );
                        }
                        None
                    }
                }
            };
            match part {
                Some(p) => {
                    map.push(parts.len() as u32);
                    parts.push(p);
                }
                None => ok = false,
            }
        }
        for (si, used) in spec_used.iter().enumerate() {
            if !used {
                let groups = gm.groups.join(", ");
                self.err(
                    &format!("{at}.parts[{si}].name"),
                    format!(
                        "part `{}` matches no face group of object `{}` (groups: {groups})",
                        o.parts[si].name, o.name
                    ),
                );
                ok = false;
            }
        }
        ok.then_some(map)
    }
}

/// Evaluate a terrain height function at (x, y), m.
pub fn height_function(f: &file::HeightFunction, x: f64, y: f64) -> f64 {
    let mut z = f.base_m;
    if let Some([a, b]) = f.slope {
        z += a * x + b * y;
    }
    for w in &f.waves {
        let d = w.direction_deg.to_radians();
        z += w.amplitude_m
            * (std::f64::consts::TAU * (x * d.cos() + y * d.sin()) / w.wavelength_m + w.phase_rad)
                .sin();
    }
    for b in &f.bowls {
        let r2 =
            ((x - b.center[0]).powi(2) + (y - b.center[1]).powi(2)) / (b.radius_m * b.radius_m);
        if r2 < 1.0 {
            z -= b.depth_m * (1.0 - r2).powi(2);
        }
    }
    for fl in &f.flats {
        // Distance outside the rectangle (0 inside).
        let ox = (fl.min[0] - x).max(x - fl.max[0]).max(0.0);
        let oy = (fl.min[1] - y).max(y - fl.max[1]).max(0.0);
        let d = ox.hypot(oy);
        let w = if d <= 0.0 {
            1.0
        } else if fl.blend_m > 0.0 && d < fl.blend_m {
            let t = d / fl.blend_m;
            1.0 - t * t * (3.0 - 2.0 * t)
        } else {
            0.0
        };
        z = w * fl.height_m + (1.0 - w) * z;
    }
    z
}

/// Read a CSV grid of numbers (comma, whitespace or `;` separated, quoted
/// cells allowed, `#` comments), through `crate::textio`.
fn read_grid_csv(path: &Path) -> Result<Vec<Vec<f64>>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut rows = Vec::new();
    for row in textio::rows(&text, Comments::Trailing) {
        let values: std::result::Result<Vec<f64>, _> = textio::tokens(&row.fields)
            .into_iter()
            .map(str::parse::<f64>)
            .collect();
        rows.push(values.map_err(|_| {
            Error::parse(
                Location::file(path).at_line(row.line),
                "expected numbers separated by commas",
            )
        })?);
    }
    Ok(rows)
}
