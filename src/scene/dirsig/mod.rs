//! DIRSIG scene import: a DIRSIG4 `.scene` (with its `.glist`/`.odb`/`.gdb` geometry and
//! `.mat`/`.ems` materials), or a simulation that names one (DIRSIG5 `.jsim`, DIRSIG4
//! `.sim`, with `.atm`, `.wth`, `.platform`, `.ppd`, `.tasks`), turned into an irsig
//! [`SceneFile`] and a material database ([`MaterialFile`]).
//!
//! [`import`] reads everything and gives an [`Imported`]: the scene, its materials,
//! the geometry files it generated (DIRSIG `.gdb` written as OBJ) and a `warning:` for
//! everything that could not be mapped, each naming the file, the line and what was
//! dropped. [`Imported::write`] writes them (`scene.json`, `scene.materials.json`,
//! `scene.geometry/`); [`crate::scene::Scene::load`] also takes a DIRSIG file directly
//! ([`is_dirsig_scene`]) by importing it into a temporary folder.
//!
//! One file per format: [`scene`] (`.scene`), [`glist`] (`.glist`), [`odb`] (`.odb`),
//! [`gdb`] (`.gdb` → OBJ), [`sim`] (`.jsim`, `.sim`, `.tasks`, `.atm`), [`platform`]
//! (`.platform`, `.ppd` → sensors); [`xml`] holds the XML helpers. The `.mat`/`.ems`
//! readers are [`crate::material::dirsig`]'s; `.wth` is [`crate::weather`]'s. The formats,
//! the conventions assumed and what maps are in `docs/tutorials/from-dirsig.md`.
//!
//! # Conventions
//! - DIRSIG's scene frame is east-north-up metres about the scene origin (the `.scene`
//!   `<sceneorigin>`), as irsig's world.
//! - Instance transforms (`.glist` `<staticinstance>`, `.odb` `INFO`): scale, then
//!   rotation about x, then y, then z (fixed scene axes, right-handed; degrees unless the
//!   element says `radians`), then translation (m) — irsig's own order
//!   ([`crate::scene::file::TransformSpec`]). DIRSIG's documentation calls the ODB order
//!   "fixed" and writes the angles x, y, z (its example turns a truck 90° about z); the
//!   x → y → z order itself is this importer's reading, honoured otherwise when a
//!   `rotationorder` is given. A 4×4 matrix is row by row with the translation in the
//!   fourth column (the ODB documentation's example ends `0 0 0 1`).
//! - Nested lists compose: world = parent instance ∘ child instance.
//!
//! Takes DIRSIG files; gives irsig scene and material files. Must not know ray tracing,
//! the thermal model or rendering.

pub mod gdb;
pub mod glist;
pub mod odb;
pub mod platform;
pub mod scene;
pub mod sim;
pub mod xml;

use std::cell::OnceCell;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use chrono::{DateTime, FixedOffset};
use glam::{DMat3, DMat4, DVec3};
use serde_json::{Map, Value};

use crate::error::{Error, Location, Result};
use crate::material::db::{EmissivityCurveSpec, EmissivityRows, MaterialEntry, MaterialFile};
use crate::material::dirsig::{MatEntry, TempSolver, read_mat_with};
use crate::material::{EmissivityCurve, MaterialSource};
use crate::scene::file::{
    LengthUnit, ObjectSpec, PartSpec, Scale, SceneFile, ShapeSpec, SiteSpec, TransformSpec,
    WeatherSpec,
};

/// Options of an import.
#[derive(Debug, Clone, Default)]
pub struct ImportOptions {
    /// Folders searched for a file not found where its DIRSIG file says (absolute
    /// paths from another machine, scenes split over folders): the file whose path ends
    /// with the most of the named path's trailing components is used, with a warning.
    pub search_dirs: Vec<PathBuf>,
    /// The image time (RFC 3339), replacing the `.tasks` time; required by a bare
    /// `.scene`, which has none (else a placeholder with a warning).
    pub time: Option<String>,
}

/// An imported scene: what [`Imported::write`] writes.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The irsig scene (its paths relative to the scene file it is written as).
    pub scene: SceneFile,
    /// The materials it uses (written beside the scene).
    pub materials: MaterialFile,
    /// Generated geometry files: path relative to the scene file, contents.
    pub files: Vec<(String, String)>,
    /// What could not be mapped, each naming file, line and what was dropped.
    pub warnings: Vec<String>,
}

/// Whether `path` is a DIRSIG scene or simulation file [`import`] takes: by extension
/// (`.scene`, `.jsim`, `.sim`), else by content (`<classicscene`, `<simulation`, a JSON
/// array with a `scene_list`).
pub fn is_dirsig_scene(path: &Path) -> bool {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if matches!(ext.as_deref(), Some("scene" | "jsim" | "sim")) {
        return true;
    }
    if matches!(ext.as_deref(), Some("json")) {
        return false;
    }
    let Ok(bytes) = std::fs::read(path) else {
        return false;
    };
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(4096)]).to_ascii_lowercase();
    head.contains("<classicscene") || head.contains("<simulation") || {
        head.trim_start().starts_with('[') && head.contains("\"scene_list\"")
    }
}

/// Import a DIRSIG `.scene`, `.jsim` or `.sim` file as the irsig scene to be written at
/// `out` (generated files are named relative to it). Errors name the file and line of
/// real corruption or of a missing file that is needed; everything else that cannot be
/// mapped is a warning in [`Imported::warnings`].
pub fn import(path: &Path, out: &Path, opts: &ImportOptions) -> Result<Imported> {
    let mut im = Importer::new(out, opts);
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let trimmed = text.trim_start();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if trimmed.starts_with('[') || trimmed.starts_with('{') || ext.as_deref() == Some("jsim") {
        im.jsim(path, &text)?;
    } else {
        let doc = xml::parse(&text, path)?;
        let root = doc.root_element();
        match root.tag_name().name().to_ascii_lowercase().as_str() {
            "classicscene" | "scene" => im.scene(path, root)?,
            "simulation" => im.sim(path, root)?,
            other => {
                return Err(Error::parse(
                    xml::loc(path, root),
                    format!(
                        "root element `<{other}>`: expected a DIRSIG scene (`<classicscene>`) or \
                         simulation (`<simulation>`, or a `.jsim` JSON array)"
                    ),
                ));
            }
        }
    }
    im.finish(path)
}

impl Imported {
    /// Write the scene to `out` (JSON), its materials beside it
    /// (`STEM.materials.json`) and the generated geometry (`STEM.geometry/`), each file
    /// atomically. Gives the files written.
    pub fn write(&self, out: &Path) -> Result<Vec<PathBuf>> {
        let dir = out.parent().unwrap_or(Path::new("."));
        let mut written = Vec::new();
        let mut put = |p: PathBuf, text: String| -> Result<()> {
            if let Some(d) = p.parent() {
                std::fs::create_dir_all(d).map_err(|e| Error::io(d, e))?;
            }
            // Atomically: an interrupted import leaves no half-written file.
            crate::output::atomic::write_atomic(&p, |w| {
                w.write_all(text.as_bytes()).map_err(|e| Error::io(&p, e))
            })?;
            written.push(p);
            Ok(())
        };
        for (rel, text) in &self.files {
            put(dir.join(rel), text.clone())?;
        }
        let mats = serde_json::to_string_pretty(&self.materials).expect("materials serialise");
        put(dir.join(materials_name(out)), mats + "\n")?;
        let scene = serde_json::to_string_pretty(&self.scene).expect("scene serialises");
        put(out.to_path_buf(), scene + "\n")?;
        Ok(written)
    }
}

/// The materials file written beside scene `out`.
fn materials_name(out: &Path) -> String {
    format!("{}.materials.json", stem(out))
}

fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into())
}

/// A placement: the transform, and its simple form when it has one.
#[derive(Debug, Clone)]
pub(crate) struct Placement {
    /// Parent ← object, 4×4 (column vectors).
    pub m: DMat4,
    /// The same as written in irsig's scale/rotate/translate form, when it is one.
    pub spec: Option<TransformSpec>,
}

impl Placement {
    pub(crate) fn identity() -> Self {
        Placement {
            m: DMat4::IDENTITY,
            spec: Some(TransformSpec::default()),
        }
    }

    /// From irsig's form: scale, rotate x then y then z (degrees), translate.
    pub(crate) fn from_spec(t: TransformSpec) -> Self {
        let s = match &t.scale {
            None => DVec3::ONE,
            Some(Scale::Uniform(s)) => DVec3::splat(*s),
            Some(Scale::PerAxis(v)) => DVec3::from(*v),
        };
        let r = t.rotate_deg.unwrap_or([0.0; 3]);
        let rot = DMat3::from_rotation_z(r[2].to_radians())
            * DMat3::from_rotation_y(r[1].to_radians())
            * DMat3::from_rotation_x(r[0].to_radians());
        let tr = DVec3::from(t.translate.unwrap_or([0.0; 3]));
        let m = DMat4::from_translation(tr) * DMat4::from_mat3(rot * DMat3::from_diagonal(s));
        Placement { m, spec: Some(t) }
    }

    /// From a general matrix.
    pub(crate) fn from_matrix(m: DMat4) -> Self {
        Placement { m, spec: None }
    }

    /// `self ∘ child` (the child placed inside `self`).
    pub(crate) fn then(&self, child: &Placement) -> Placement {
        let is_id = |p: &Placement| p.m.abs_diff_eq(DMat4::IDENTITY, 0.0);
        if is_id(self) {
            return child.clone();
        }
        if is_id(child) {
            return self.clone();
        }
        Placement::from_matrix(self.m * child.m)
    }

    /// As an irsig transform: the simple form, else `matrix` (row by row).
    pub(crate) fn to_spec(&self) -> TransformSpec {
        match &self.spec {
            Some(s) => s.clone(),
            None => {
                let r = self.m.transpose().to_cols_array();
                TransformSpec {
                    matrix: Some(r.to_vec()),
                    ..Default::default()
                }
            }
        }
    }
}

/// A rotation matrix from three angles (radians) applied in `order` (e.g. `"xyz"`: about
/// x first, then y, then z; fixed axes).
pub(crate) fn euler(order: &str, a: [f64; 3]) -> Option<DMat3> {
    let mut m = DMat3::IDENTITY;
    if order.len() != 3 {
        return None;
    }
    for c in order.chars() {
        let r = match c.to_ascii_lowercase() {
            'x' => DMat3::from_rotation_x(a[0]),
            'y' => DMat3::from_rotation_y(a[1]),
            'z' => DMat3::from_rotation_z(a[2]),
            _ => return None,
        };
        m = r * m;
    }
    Some(m)
}

/// A point given as a DIRSIG `<location>` (or `<point>`), in scene east-north-up metres.
/// The frame is the element's `type` (or `frame`) attribute: `scene` (default; `<x>`,
/// `<y>`, `<z>`, m), `geodetic` (`<latitude>`, `<longitude>` in degrees, east positive,
/// and `<altitude>`, m above the WGS84 ellipsoid) or `ecef` (`<x>`, `<y>`, `<z>`, m,
/// WGS84 Earth-centred, Earth-fixed), as DIRSIG's coordinates manual lists them
/// (dirsig.cis.rit.edu/docs/new/coordinates.html; the GeoLocation1 demo's glist places
/// an aircraft with `<location type="geodetic">`). Geographic points become scene
/// coordinates about `origin` (the `.scene` `<sceneorigin>`) through
/// [`crate::geodesy::enu_from_geodetic`]. UTM (which needs a zone) is an error naming
/// the element.
pub(crate) fn scene_point(
    path: &Path,
    n: roxmltree::Node,
    origin: Option<&SiteSpec>,
) -> Result<DVec3> {
    let frame = xml::attr(n, "type")
        .or_else(|| xml::attr(n, "frame"))
        .unwrap_or("scene")
        .to_ascii_lowercase();
    let site = || {
        origin
            .map(|o| crate::sun::Site {
                latitude_deg: o.latitude_deg,
                longitude_deg: o.longitude_deg,
                altitude_m: o.altitude_m,
            })
            .ok_or_else(|| {
                Error::parse(
                    xml::loc(path, n),
                    format!(
                        "a `{frame}` location needs the scene origin (`<sceneorigin>`), \
                         which is not known here"
                    ),
                )
            })
    };
    match frame.as_str() {
        "scene" | "sceneenu" | "local" => Ok(DVec3::from(xml::triple(path, n, 0.0)?)),
        "geodetic" | "geographic" | "lla" => {
            let lat = xml::req_number(path, n, "latitude")?;
            let lon = xml::req_number(path, n, "longitude")?;
            let alt = xml::opt_number(path, n, "altitude")?.unwrap_or(0.0);
            if lat.abs() > 90.0 || lon.abs() > 360.0 {
                return Err(Error::parse(
                    xml::loc(path, n),
                    format!(
                        "latitude {lat}°, longitude {lon}°: expected −90..=90 and \
                         −180..=360 (degrees, east positive)"
                    ),
                ));
            }
            Ok(crate::geodesy::enu_from_geodetic(&site()?, lat, lon, alt))
        }
        "ecef" => {
            let p = DVec3::from(xml::triple(path, n, 0.0)?);
            let (lat, lon, h) = crate::geodesy::geodetic_from_ecef(p);
            Ok(crate::geodesy::enu_from_geodetic(&site()?, lat, lon, h))
        }
        other => Err(Error::parse(
            xml::loc(path, n),
            format!(
                "location type `{other}`: irsig imports `scene`, `geodetic` and `ecef` \
                 locations (a UTM point can be given as geodetic)"
            ),
        )),
    }
}

/// The length unit of a DIRSIG `UNITS`/`units` value.
pub(crate) fn length_unit(s: &str) -> Option<LengthUnit> {
    Some(match s.trim().to_ascii_lowercase().as_str() {
        "meters" | "meter" | "metres" | "metre" | "m" => LengthUnit::Metre,
        "centimeters" | "centimeter" | "centimetres" | "cm" => LengthUnit::Centimetre,
        "millimeters" | "millimeter" | "millimetres" | "mm" => LengthUnit::Millimetre,
        "inches" | "inch" | "in" => LengthUnit::Inch,
        "feet" | "foot" | "ft" => LengthUnit::Foot,
        _ => return None,
    })
}

/// Which materials are in effect, and how OBJ material names are remapped.
#[derive(Debug, Clone, Default)]
pub(crate) struct MatCtx {
    /// Index into the importer's libraries (scene `.mat`, or a bundle's local one).
    pub lib: Option<usize>,
    /// `<assign id="ID">name</assign>`: OBJ material name → `.mat` ID.
    pub assign: BTreeMap<String, String>,
}

/// A geometry file to place.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) enum Geo {
    /// A Wavefront OBJ file (`usemtl` = `.mat` ID).
    Obj(PathBuf),
    /// A DIRSIG `.gdb` file.
    Gdb(PathBuf),
    /// A glist primitive (`<box>`) as generated OBJ text with one material ID; `src` is
    /// the list that names it (for names and messages).
    Prim {
        kind: String,
        obj: String,
        id: String,
        src: PathBuf,
    },
}

/// One `.mat` file read.
struct Library {
    path: PathBuf,
    entries: Vec<MatEntry>,
    /// Per entry: its name in the written database, when it has one.
    out: Vec<Option<String>>,
}

/// Thermal values given to a `DataDriven` material: unused by the thermal model (its
/// parts carry `fixed_temperature_k`), but a material must have valid ones.
const PLACEHOLDER_NOTE: &str = "DataDriven: surface temperature given (parts carry \
    fixed_temperature_k); the thermal values are placeholders the thermal model does not use";

pub(crate) struct Importer<'o> {
    opts: &'o ImportOptions,
    out: PathBuf,
    index: OnceCell<Vec<PathBuf>>,
    pub(crate) warnings: Vec<String>,
    libs: Vec<Library>,
    lib_by_path: HashMap<PathBuf, usize>,
    materials: Vec<MaterialEntry>,
    objects: Vec<ObjectSpec>,
    object_by_key: HashMap<String, usize>,
    files: Vec<(String, String)>,
    pub(crate) site: Option<SiteSpec>,
    pub(crate) description: Option<String>,
    pub(crate) time: Option<DateTime<FixedOffset>>,
    /// The task list's reference time: relative `.ppd` times count from it.
    pub(crate) time_reference: Option<DateTime<FixedOffset>>,
    pub(crate) weather: Option<PathBuf>,
    pub(crate) atmosphere: Option<Value>,
    pub(crate) render: Map<String, Value>,
    pub(crate) sensors: Vec<Map<String, Value>>,
    pub(crate) scene_seen: bool,
    /// The folder of the `.scene` read (`$SCENE_DIR`).
    pub(crate) scene_dir: Option<PathBuf>,
}

impl<'o> Importer<'o> {
    fn new(out: &Path, opts: &'o ImportOptions) -> Self {
        Importer {
            opts,
            out: out.to_path_buf(),
            index: OnceCell::new(),
            warnings: Vec::new(),
            libs: Vec::new(),
            lib_by_path: HashMap::new(),
            materials: Vec::new(),
            objects: Vec::new(),
            object_by_key: HashMap::new(),
            files: Vec::new(),
            site: None,
            description: None,
            time: None,
            time_reference: None,
            weather: None,
            atmosphere: None,
            render: Map::new(),
            sensors: Vec::new(),
            scene_seen: false,
            scene_dir: None,
        }
    }

    /// Record a warning at `loc`.
    pub(crate) fn warn(&mut self, loc: Location, msg: impl Into<String>) {
        self.warnings.push(Error::parse(loc, msg).to_string());
    }

    /// Expand `$SCENE_DIR`-style variables: `vars` first, then the environment.
    pub(crate) fn expand(s: &str, vars: &[(&str, &Path)]) -> String {
        let mut out = s.trim().to_string();
        for (k, v) in vars {
            for form in [format!("${{{k}}}"), format!("${k}")] {
                out = out.replace(&form, &v.to_string_lossy());
            }
        }
        if out.contains('$') {
            for var in ["DIRSIG_HOME", "HOME"] {
                if let Ok(v) = std::env::var(var) {
                    out = out.replace(&format!("${{{var}}}"), &v);
                    out = out.replace(&format!("${var}"), &v);
                }
            }
        }
        out
    }

    /// Find the file DIRSIG names `name` (after variable expansion): absolute as is,
    /// else relative to each of `bases`; failing that, in the search folders (see
    /// [`ImportOptions::search_dirs`]), with a warning. The error names `at` and where
    /// it looked.
    pub(crate) fn find(
        &mut self,
        name: &str,
        bases: &[PathBuf],
        what: &str,
        at: &Location,
    ) -> Result<PathBuf> {
        // Variables in any DIRSIG file name: `$SCENE_DIR` (the folder of the `.scene`
        // once read) and the environment's `$DIRSIG_HOME` (the jsim documentation's
        // ThermWeather example names `$DIRSIG_HOME/lib/data/weather/…`).
        let expanded = match &self.scene_dir {
            Some(d) => Self::expand(name, &[("SCENE_DIR", d.as_path())]),
            None => Self::expand(name, &[]),
        };
        let unset = if expanded.contains('$') {
            " (a `$` variable in the name is not set)"
        } else {
            ""
        };
        let name = expanded.as_str();
        let p = Path::new(name);
        let mut tried = Vec::new();
        if p.is_absolute() || name.chars().nth(1) == Some(':') {
            if p.is_file() {
                return Ok(p.to_path_buf());
            }
            tried.push(p.to_path_buf());
            // A path from another machine (`C:/DIRSIG/…/tasks/x.tasks`): its last one to
            // three components below each base.
            let comps: Vec<&str> = name.split(['/', '\\']).filter(|c| !c.is_empty()).collect();
            for k in (1..=comps.len().saturating_sub(1).min(3)).rev() {
                let tail: PathBuf = comps[comps.len() - k..].iter().collect();
                for b in bases {
                    let c = b.join(&tail);
                    if c.is_file() {
                        self.warn(
                            at.clone(),
                            format!(
                                "{what} `{name}` is not on this machine; using {}",
                                c.display()
                            ),
                        );
                        return Ok(c);
                    }
                }
            }
        } else {
            for b in bases {
                let c = b.join(p);
                if c.is_file() {
                    return Ok(c);
                }
                tried.push(c);
            }
        }
        if let Some(found) = self.search(name) {
            self.warn(
                at.clone(),
                format!(
                    "{what} `{name}` is not where the file says; using {} (found in the search folders)",
                    found.display()
                ),
            );
            return Ok(found);
        }
        let list: Vec<String> = tried.iter().map(|t| t.display().to_string()).collect();
        Err(Error::parse(
            at.clone(),
            format!(
                "{what} `{name}`{unset} not found (looked for {}{})",
                if list.is_empty() {
                    "it".into()
                } else {
                    list.join(", ")
                },
                if self.opts.search_dirs.is_empty() {
                    "; a search folder may help"
                } else {
                    " and in the search folders"
                }
            ),
        ))
    }

    /// The file in the search folders whose path ends with the most trailing components
    /// of `name` (at least its file name); ties go to the first folder, then the path.
    fn search(&self, name: &str) -> Option<PathBuf> {
        let want: Vec<String> = name
            .split(['/', '\\'])
            .filter(|c| !c.is_empty() && *c != "." && !c.ends_with(':'))
            .map(str::to_string)
            .collect();
        let index = self.index.get_or_init(|| {
            let mut files = Vec::new();
            for d in &self.opts.search_dirs {
                let mut stack = vec![(d.clone(), 0)];
                let mut mine = Vec::new();
                while let Some((dir, depth)) = stack.pop() {
                    let Ok(rd) = std::fs::read_dir(&dir) else {
                        continue;
                    };
                    for e in rd.flatten() {
                        let p = e.path();
                        if p.is_dir() && depth < 12 {
                            stack.push((p, depth + 1));
                        } else if p.is_file() && mine.len() < 50_000 {
                            mine.push(p);
                        }
                    }
                }
                mine.sort();
                files.extend(mine);
            }
            files
        });
        let score = |p: &Path| {
            let comps: Vec<String> = p
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            want.iter()
                .rev()
                .zip(comps.iter().rev())
                .take_while(|(a, b)| a == b)
                .count()
        };
        let mut best: Option<(usize, &PathBuf)> = None;
        for p in index {
            let s = score(p);
            if s > 0 && best.is_none_or(|(b, _)| s > b) {
                best = Some((s, p));
            }
        }
        best.map(|(_, p)| p.clone())
    }

    /// Read a `.mat` file once (emissivity files relative to `ems_dirs` first).
    pub(crate) fn library(
        &mut self,
        path: &Path,
        ems_dirs: &[PathBuf],
        at: &Location,
    ) -> Result<usize> {
        let key = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if let Some(&i) = self.lib_by_path.get(&key) {
            return Ok(i);
        }
        let mut found = Vec::new();
        let file = read_mat_with(path, ems_dirs, &mut |f| {
            let p = self.search(f)?;
            found.push((f.to_string(), p.clone()));
            Some(p)
        })
        .map_err(|e| Error::parse(at.clone(), format!("material database: {e}")))?;
        for (f, p) in found {
            self.warn(
                Location::file(path),
                format!(
                    "file `{f}` is not where the material database says; using {} (found in \
                     the search folders)",
                    p.display()
                ),
            );
        }
        let mut out = Vec::new();
        for e in &file.entries {
            self.warnings.extend(e.warnings.iter().cloned());
            if !matches!(e.solver, TempSolver::DataDriven { .. }) {
                self.warnings.extend(e.skipped.iter().cloned());
            }
            let entry = match (&e.material, &e.solver) {
                (Some(m), _) => Some(MaterialEntry {
                    id: m.id,
                    name: m.name.clone(),
                    description: None,
                    specific_heat_j_kg_k: Some(m.specific_heat_j_kg_k),
                    conductivity_w_m_k: Some(m.conductivity_w_m_k),
                    density_kg_m3: Some(m.density_kg_m3),
                    thickness_m: Some(m.thickness_m),
                    solar_absorptivity: m.solar_absorptivity,
                    thermal_emissivity: m.thermal_emissivity,
                    exposed_area: m.exposed_area,
                    self_power_w_m2: m.self_power_w_m2,
                    specular_fraction: m.specular_fraction,
                    specular_roughness: m.specular_roughness,
                    transmissivity: m.transmissivity,
                    double_sided: m.double_sided,
                    emissivity_curve: m.emissivity_curve.as_ref().map(curve_spec),
                    emissivity_file: None,
                    layers: Vec::new(),
                    back: None,
                    surface_energy: None,
                    convection: Default::default(),
                    source: Some(MaterialSource::Text(format!(
                        "DIRSIG {} line {} (ID {}), THERM units converted to SI",
                        path.display(),
                        e.line,
                        e.id
                    ))),
                }),
                (None, TempSolver::DataDriven { .. }) => {
                    let eps = e
                        .emissivity
                        .as_ref()
                        .map(|c| c.band_mean(8.0, 14.0).clamp(0.0, 1.0));
                    if eps.is_none() {
                        self.warn(
                            Location::file(path).at_line(e.line),
                            format!(
                                "material `{}` (ID {}): no emissivity or reflectance file; \
                                 imported as a blackbody (emissivity 1)",
                                e.name, e.id
                            ),
                        );
                    }
                    let eps = eps.unwrap_or(1.0);
                    Some(MaterialEntry {
                        id: e.numeric_id,
                        name: e.name.clone(),
                        description: Some(PLACEHOLDER_NOTE.into()),
                        specific_heat_j_kg_k: Some(1000.0),
                        conductivity_w_m_k: Some(1.0),
                        density_kg_m3: Some(1000.0),
                        thickness_m: Some(0.01),
                        solar_absorptivity: eps,
                        thermal_emissivity: eps,
                        exposed_area: 0.0,
                        self_power_w_m2: 0.0,
                        specular_fraction: e.specular_fraction,
                        specular_roughness: None,
                        transmissivity: 0.0,
                        double_sided: e.double_sided,
                        emissivity_curve: e.emissivity.as_ref().map(curve_spec),
                        emissivity_file: None,
                        layers: Vec::new(),
                        back: None,
                        surface_energy: None,
                        convection: Default::default(),
                        source: Some(MaterialSource::Text(format!(
                            "DIRSIG {} line {} (ID {}); {PLACEHOLDER_NOTE}",
                            path.display(),
                            e.line,
                            e.id
                        ))),
                    })
                }
                _ => None,
            };
            out.push(entry.map(|mut m| {
                // Names must be unique across the libraries of a scene.
                let base = m.name.clone();
                let mut k = 1;
                while self.materials.iter().any(|o| o.name == m.name) {
                    k += 1;
                    m.name = format!("{base} ({} {k})", stem(path));
                }
                let name = m.name.clone();
                self.materials.push(m);
                name
            }));
        }
        self.libs.push(Library {
            path: path.to_path_buf(),
            entries: file.entries,
            out,
        });
        self.lib_by_path.insert(key, self.libs.len() - 1);
        Ok(self.libs.len() - 1)
    }

    /// The written material and fixed temperature for `.mat` ID `id` of library `lib`;
    /// `used` says where (for the error).
    fn resolve(&self, lib: usize, id: &str, used: &str) -> Result<(String, Option<f64>)> {
        let l = &self.libs[lib];
        let same = |a: &str, b: &str| {
            a == b || matches!((a.parse::<u64>(), b.parse::<u64>()), (Ok(x), Ok(y)) if x == y)
        };
        let k = l
            .entries
            .iter()
            .position(|e| same(&e.id, id))
            .or_else(|| l.entries.iter().position(|e| e.name == id))
            .ok_or_else(|| {
                let ids: Vec<&str> = l.entries.iter().map(|e| e.id.as_str()).collect();
                Error::parse(
                    Location::file(&l.path),
                    format!(
                        "no material has ID `{id}` (used by {used}); IDs here: {}",
                        ids.join(", ")
                    ),
                )
            })?;
        let e = &l.entries[k];
        match &l.out[k] {
            Some(name) => Ok((
                name.clone(),
                match e.solver {
                    TempSolver::DataDriven { temperature_k } => Some(temperature_k),
                    _ => None,
                },
            )),
            None => Err(Error::parse(
                Location::file(&l.path).at_line(e.line),
                format!(
                    "material `{}` (ID {}) is used by {used} but cannot be imported: {}",
                    e.name,
                    e.id,
                    e.skipped.as_deref().unwrap_or("no thermal model")
                ),
            )),
        }
    }

    /// Place `geo` with materials `mats` (and `unit`) at `at`: one irsig object per
    /// distinct geometry and materials, one instance per placement.
    pub(crate) fn place(
        &mut self,
        geo: &Geo,
        mats: &MatCtx,
        unit: Option<LengthUnit>,
        at: &Placement,
        from: &Location,
    ) -> Result<()> {
        // Nested lists multiply their placements: huge (finite) values can overflow.
        let det = at.m.determinant();
        if !(at.m.is_finite() && det.is_finite() && det > 0.0) {
            return Err(Error::parse(
                from.clone(),
                format!(
                    "the placement (this instance within its lists) has determinant {det}: \
                     expected a finite transform with scales > 0 (no zero, mirroring or \
                     overflowing scale or translation)"
                ),
            ));
        }
        let key = format!("{geo:?}|{:?}|{:?}|{unit:?}", mats.lib, mats.assign);
        let k = match self.object_by_key.get(&key) {
            Some(&k) => k,
            None => {
                let o = self.make_object(geo, mats, unit, from)?;
                self.objects.push(o);
                self.object_by_key.insert(key, self.objects.len() - 1);
                self.objects.len() - 1
            }
        };
        let spec = at.to_spec();
        self.objects[k]
            .instances
            .get_or_insert_with(Vec::new)
            .push(spec);
        Ok(())
    }

    fn make_object(
        &mut self,
        geo: &Geo,
        mats: &MatCtx,
        unit: Option<LengthUnit>,
        from: &Location,
    ) -> Result<ObjectSpec> {
        let Some(lib) = mats.lib else {
            return Err(Error::parse(
                from.clone(),
                "geometry without a material database (the scene has no `<matfilename>` and \
                 the object no `<localmaterials>`)",
            ));
        };
        let (file, path, groups): (String, &Path, gdb::Groups) = match geo {
            Geo::Obj(p) => {
                let gs = crate::scene::load_obj(p)?;
                let mut names: Vec<String> = Vec::new();
                for g in &gs {
                    let Some(m) = &g.material_name else {
                        return Err(Error::parse(
                            Location::file(p),
                            format!(
                                "group `{}` has faces without `usemtl`: DIRSIG OBJ files name \
                                 each face's material ID with `usemtl <ID>`",
                                g.name
                            ),
                        ));
                    };
                    if !names.contains(m) {
                        names.push(m.clone());
                    }
                }
                let groups = names
                    .into_iter()
                    .map(|n| {
                        let id = mats.assign.get(&n).cloned().unwrap_or_else(|| n.clone());
                        (n, id, None)
                    })
                    .collect();
                (self.relative(p), p.as_path(), groups)
            }
            Geo::Prim { kind, obj, id, src } => {
                let name = format!(
                    "{}.geometry/{}_{kind}.obj",
                    stem(&self.out),
                    self.files.len()
                );
                self.files.push((name.clone(), obj.clone()));
                (name, src.as_path(), vec![(id.clone(), id.clone(), None)])
            }
            Geo::Gdb(p) => {
                let g = gdb::to_obj(p)?;
                self.warnings.extend(g.warnings);
                let name = format!(
                    "{}.geometry/{}_{}.obj",
                    stem(&self.out),
                    self.files.len(),
                    stem(p)
                );
                self.files.push((name.clone(), g.obj));
                (name, p.as_path(), g.groups)
            }
        };
        let mut parts = Vec::new();
        for (group, id, fixed_k) in groups {
            let used = format!("`usemtl {group}` in {}", path.display());
            let (material, fixed) = self.resolve(lib, &id, &used)?;
            parts.push(PartSpec {
                name: group,
                material,
                thickness_m: None,
                self_power_w_m2: None,
                exposed_area: None,
                fixed_temperature_k: fixed_k.or(fixed),
                shape_factor: None,
                back: None,
            });
        }
        let mut name = match geo {
            Geo::Prim { kind, .. } => kind.clone(),
            _ => stem(path),
        };
        let base = name.clone();
        let mut k = 1;
        while self.objects.iter().any(|o| o.name == name) {
            k += 1;
            name = format!("{base}_{k}");
        }
        Ok(ObjectSpec {
            name,
            description: Some(format!("from {}", path.display())),
            shapes: vec![ShapeSpec {
                obj: Some(file),
                unit: unit.filter(|u| *u != LengthUnit::Metre),
                ..Default::default()
            }],
            parts,
            material: None,
            back: None,
            transform: None,
            instances: None,
        })
    }

    /// `p` as written in the scene: relative to the output folder when below it, else
    /// absolute.
    fn relative(&self, p: &Path) -> String {
        let abs = |p: &Path| {
            std::path::absolute(p)
                .unwrap_or_else(|_| p.to_path_buf())
                .canonicalize()
                .unwrap_or_else(|_| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf()))
        };
        let out_dir = abs(self.out.parent().unwrap_or(Path::new(".")));
        let a = abs(p);
        match a.strip_prefix(&out_dir) {
            Ok(r) => r.to_string_lossy().into_owned(),
            Err(_) => a.to_string_lossy().into_owned(),
        }
    }

    fn finish(mut self, input: &Path) -> Result<Imported> {
        let Some(site) = self.site.clone() else {
            return Err(Error::parse(
                Location::file(input),
                "no DIRSIG scene (`.scene` with a `<sceneorigin>`) found in this file",
            ));
        };
        if self.objects.is_empty() {
            return Err(Error::parse(
                Location::file(input),
                "the DIRSIG scene places no geometry irsig can import (see the warnings)",
            ));
        }
        let time = match (&self.opts.time, self.time) {
            (Some(t), _) => crate::sun::parse_time(t)
                .map_err(|e| Error::parse(Location::field("time"), e.to_string()))?,
            (None, Some(t)) => t,
            (None, None) => {
                // A placeholder: noon, 21 June 2020, in the site's nominal time zone.
                let h = (site.longitude_deg / 15.0).round() as i32;
                let off = FixedOffset::east_opt(h * 3600).expect("|h| ≤ 12");
                let t = chrono::NaiveDate::from_ymd_opt(2020, 6, 21)
                    .and_then(|d| d.and_hms_opt(12, 0, 0))
                    .and_then(|d| d.and_local_timezone(off).single())
                    .expect("valid date");
                self.warn(
                    Location::file(input),
                    format!(
                        "no image time (a `.scene` has none; a `.jsim`/`.sim` gives it through \
                         its `.tasks`): using {} — give the time to replace it",
                        t.to_rfc3339()
                    ),
                );
                t
            }
        };
        let site = SiteSpec {
            utc_offset_hours: f64::from(time.offset().local_minus_utc()) / 3600.0,
            ..site
        };
        let weather = match self.weather.clone() {
            Some(w) => Some(self.weather_spec(&w, time)?),
            None => {
                self.warn(
                    Location::file(input),
                    "no weather file (`.wth`) named: the scene has no weather; the thermal \
                     model needs one (add `weather` to the scene)",
                );
                None
            }
        };
        let mats_name = materials_name(&self.out);
        let scene = SceneFile {
            schema: None,
            description: Some(format!(
                "{}imported from DIRSIG {} by `irsig import dirsig`",
                self.description
                    .as_deref()
                    .filter(|d| !d.is_empty())
                    .map(|d| format!("{d}: "))
                    .unwrap_or_default(),
                input.display()
            )),
            site,
            time: time.to_rfc3339(),
            weather,
            materials: vec![mats_name],
            objects: self.objects,
            sensors: self.sensors,
            atmosphere: self.atmosphere,
            render: (!self.render.is_empty()).then_some(self.render),
        };
        Ok(Imported {
            scene,
            materials: MaterialFile {
                schema: None,
                description: Some(format!(
                    "Materials of DIRSIG scene {} (THERM units converted to SI)",
                    input.display()
                )),
                notes: None,
                materials: self.materials,
            },
            files: self.files,
            warnings: self.warnings,
        })
    }

    /// The weather reference for `.wth` (or other) file `w` at image time `time`. A
    /// `.wth` carries no date, in local time: its first row is taken at local midnight,
    /// so that the image falls in the file's last day that reaches it — DIRSIG's files
    /// hold 48 hours "so that DIRSIG can simulate any time during the current day and
    /// have at least 24-hours of previous weather history" (dirsig.org/docs/new/wth.html):
    /// a 48-hour file starts the day before the image, at midnight too.
    fn weather_spec(&mut self, w: &Path, time: DateTime<FixedOffset>) -> Result<WeatherSpec> {
        let file = self.relative(w);
        let is_wth = w.extension().is_some_and(|e| e.eq_ignore_ascii_case("wth"));
        if !is_wth {
            return Ok(WeatherSpec {
                file,
                start: None,
                year: None,
            });
        }
        let text = std::fs::read_to_string(w).map_err(|e| Error::io(w, e))?;
        let head = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("");
        let v: Vec<f64> = head
            .split_whitespace()
            .filter_map(|s| s.parse().ok())
            .collect();
        let span_h = match v.as_slice() {
            [n, dt, ..] if *n >= 1.0 && *dt > 0.0 => (n - 1.0) * dt,
            _ => {
                return Err(Error::parse(
                    Location::file(w).at_line(1),
                    format!("`.wth` header: expected `RECORDS STEP_HOURS`, found `{head}`"),
                ));
            }
        };
        let midnight = time
            .date_naive()
            .and_hms_opt(0, 0, 0)
            .and_then(|d| d.and_local_timezone(*time.offset()).single())
            .expect("valid midnight");
        let hour = (time - midnight).num_seconds() as f64 / 3600.0;
        // Whole days before the image date: ⌈(span − hour)/24⌉ − 1, so an image at
        // midnight is at the start of the last day, not at the file's last row.
        let days = ((span_h - hour) / 24.0).ceil() as i64 - 1;
        let days = days.max(0);
        let start = chrono::TimeDelta::try_days(days)
            .and_then(|d| midnight.checked_sub_signed(d))
            .ok_or_else(|| {
                Error::parse(
                    Location::file(w).at_line(1),
                    format!("`.wth` header `{head}`: {span_h} hours reach beyond the calendar"),
                )
            })?;
        Ok(WeatherSpec {
            file,
            start: Some(start.to_rfc3339()),
            year: None,
        })
    }
}

/// An emissivity curve as the JSON database writes it.
fn curve_spec(c: &EmissivityCurve) -> EmissivityCurveSpec {
    EmissivityCurveSpec {
        wavelengths_um: c.wavelengths_um.clone(),
        emissivity: if c.angles_deg.is_empty() {
            EmissivityRows::Single(c.emissivity[0].clone())
        } else {
            EmissivityRows::PerAngle(c.emissivity.clone())
        },
        angles_deg: c.angles_deg.clone(),
    }
}
