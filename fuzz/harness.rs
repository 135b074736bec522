//! Fuzz harness shared by the cargo-fuzz targets (`fuzz/fuzz_targets/*.rs`)
//! and the stable-Rust smoke test (`tests/fuzz_smoke.rs`), which include this
//! file with `#[path]`.
//!
//! Each target feeds arbitrary bytes to one of irsig's readers. A reader may
//! return an error (that is the point), but must never panic, and what it
//! accepts must be sane: no NaN/infinite values in the parsed records, and
//! every error must say where (the file name appears in its message).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// A target: bytes in, whether the reader accepted them.
pub type Target = fn(&[u8]) -> bool;

/// The targets, by name (each is a file in `fuzz/fuzz_targets/`).
pub const TARGETS: &[(&str, Target)] = &[
    ("scene_json", scene_json),
    ("obj", obj),
    ("gltf", gltf),
    ("material_json", material_json),
    ("dirsig_mat", dirsig_mat),
    ("dirsig_ems", dirsig_ems),
    ("weather", weather),
    ("tape7", tape7),
    ("response_csv", response_csv),
    ("params", params),
    ("points", points),
    ("dirsig_xml", dirsig_xml),
    ("dirsig_text", dirsig_text),
    ("state", state),
];

const MATERIALS_JSON: &str = include_str!("../scenes/materials.json");

/// A per-process scratch directory holding the shared material library
/// (`materials.json`) and `s/geo/two.obj`, for scene inputs to refer to.
fn scratch() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("irsig-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(d.join("s/geo")).expect("scratch dir");
        std::fs::write(d.join("materials.json"), MATERIALS_JSON).expect("materials");
        std::fs::write(d.join("s/geo/two.obj"), SEED_OBJ).expect("obj");
        d
    })
}

/// Write `data` to `name` in this thread's scratch subfolder; returns the path.
fn input_file(name: &str, data: &[u8]) -> PathBuf {
    let p = scratch()
        .join("s")
        .join(format!("{:?}-{name}", std::thread::current().id()).replace(['(', ')'], ""));
    std::fs::write(&p, data).expect("write fuzz input");
    p
}

/// An error must name the file it came from.
fn check_error(e: &irsig::Error, path: &Path) -> bool {
    let msg = e.to_string();
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(
        msg.contains(&*name),
        "error does not name the file {name}: {msg}"
    );
    false
}

fn text(data: &[u8]) -> std::borrow::Cow<'_, str> {
    String::from_utf8_lossy(data)
}

fn finite(xs: &[f64], what: &str) {
    for (i, x) in xs.iter().enumerate() {
        assert!(x.is_finite(), "{what}[{i}] = {x} accepted");
    }
}

/// Scene JSON (`Scene::check`), with the materials and an OBJ at hand.
pub fn scene_json(data: &[u8]) -> bool {
    // Bound the work: the scene format can ask for huge heightmaps; the
    // fuzzer's own memory/time limits catch that, but keep inputs small.
    if data.len() > 4096 {
        return false;
    }
    let p = input_file("scene.json", data);
    match irsig::scene::Scene::check(&p) {
        Ok(s) => {
            for m in &s.geometry.meshes {
                for v in &m.positions {
                    assert!(v.is_finite(), "non-finite vertex {v} accepted");
                }
            }
            true
        }
        Err(errs) => {
            assert!(!errs.is_empty(), "failure without an error");
            for e in &errs {
                let msg = e.to_string();
                assert!(!msg.is_empty());
            }
            false
        }
    }
}

/// Wavefront OBJ (`load_obj_str`).
pub fn obj(data: &[u8]) -> bool {
    let p = Path::new("fuzz.obj");
    match irsig::scene::obj::load_obj_str(&text(data), p) {
        Ok(groups) => {
            for g in &groups {
                let n = g.mesh.positions.len() as u32;
                for v in &g.mesh.positions {
                    assert!(v.is_finite(), "non-finite vertex {v} accepted");
                }
                for t in &g.mesh.indices {
                    for &i in t {
                        assert!(i < n, "index {i} out of {n} vertices");
                    }
                }
            }
            true
        }
        Err(e) => check_error(&e, p),
    }
}

/// glTF 2.0, JSON or binary (`load_gltf_slice`, external buffers refused).
pub fn gltf(data: &[u8]) -> bool {
    let p = Path::new("fuzz.glb");
    match irsig::scene::gltf::load_gltf_slice(data, p, None) {
        Ok(groups) => {
            for g in &groups {
                let n = g.mesh.positions.len() as u32;
                for v in &g.mesh.positions {
                    assert!(v.is_finite(), "non-finite vertex {v} accepted");
                }
                for t in &g.mesh.indices {
                    for &i in t {
                        assert!(i < n, "index {i} out of {n} vertices");
                    }
                }
            }
            true
        }
        Err(e) => check_error(&e, p),
    }
}

/// irsig material JSON (`db::load_json_all`).
pub fn material_json(data: &[u8]) -> bool {
    let p = input_file("materials.json", data);
    match irsig::material::db::load_json_all(&p) {
        Ok(db) => {
            for m in db.materials() {
                assert!(
                    m.problems().is_empty(),
                    "invalid material {} accepted",
                    m.name
                );
            }
            true
        }
        Err(errs) => {
            assert!(!errs.is_empty());
            for e in &errs {
                check_error(e, &p);
            }
            false
        }
    }
}

/// DIRSIG4 `.mat` (`dirsig::load_mat`).
pub fn dirsig_mat(data: &[u8]) -> bool {
    let p = input_file("fuzz.mat", data);
    match irsig::material::dirsig::load_mat(&p) {
        Ok(db) => {
            for m in db.materials() {
                assert!(
                    m.problems().is_empty(),
                    "invalid material {} accepted",
                    m.name
                );
            }
            true
        }
        Err(e) => check_error(&e, &p),
    }
}

/// DIRSIG classic emissivity file (`dirsig::read_ems`).
pub fn dirsig_ems(data: &[u8]) -> bool {
    let p = input_file("fuzz.ems", data);
    match irsig::material::dirsig::read_ems(&p) {
        Ok(c) => {
            assert!(c.problems().is_empty(), "invalid curve accepted: {c:?}");
            true
        }
        Err(e) => check_error(&e, &p),
    }
}

/// Weather: every format (detected from content), with a `.wth` start time
/// and a site given.
pub fn weather(data: &[u8]) -> bool {
    use irsig::weather::{LoadOptions, detect_format, load_str};
    let p = Path::new("fuzzweather");
    let t = text(data);
    let format = match detect_format(p, &t) {
        Ok(f) => f,
        Err(e) => return check_error(&e, p),
    };
    let start = chrono::DateTime::parse_from_rfc3339("2025-06-20T00:00:00-04:00").unwrap();
    let site = irsig::sun::Site {
        latitude_deg: 43.16,
        longitude_deg: -77.61,
        altitude_m: 160.0,
    };
    let options = LoadOptions::default().with_start(start).with_site(site);
    match load_str(&t, p, format, &options) {
        Ok(h) => {
            assert!(h.records().len() >= 2);
            for w in h.records().windows(2) {
                assert!(w[0].time < w[1].time, "times not increasing");
            }
            for r in h.records() {
                finite(
                    &[
                        r.air_temperature_k,
                        r.dew_point_k,
                        r.relative_humidity,
                        r.pressure_pa,
                        r.wind_speed_m_s,
                        r.wind_direction_deg,
                        r.direct_normal_w_m2,
                        r.diffuse_horizontal_w_m2,
                        r.global_horizontal_w_m2,
                        r.sky_longwave_w_m2,
                        r.total_sky_cover,
                        r.opaque_sky_cover,
                    ],
                    "weather record",
                );
            }
            true
        }
        Err(e) => check_error(&e, p),
    }
}

/// MODTRAN tape7 (`Tape7::parse`).
pub fn tape7(data: &[u8]) -> bool {
    let p = Path::new("fuzz.tape7");
    match irsig::atmosphere::Tape7::parse(&text(data), p) {
        Ok(t) => {
            let (w, tr) = t.transmittance_um();
            finite(&w, "wavelength");
            finite(&tr, "transmittance");
            let _ = t.range_um();
            true
        }
        Err(e) => check_error(&e, p),
    }
}

/// Relative spectral response CSV (`parse_response_csv`).
pub fn response_csv(data: &[u8]) -> bool {
    let p = Path::new("fuzz-response.csv");
    match irsig::radiometry::response::parse_response_csv(&text(data), p) {
        Ok(r) => {
            finite(r.wavelengths_um(), "wavelength");
            finite(r.response(), "response");
            let x = r.at(10.0);
            assert!(x.is_finite());
            true
        }
        Err(e) => check_error(&e, p),
    }
}

/// PARAMS JSON (`ParamSet::parse`) against the bundled material library.
pub fn params(data: &[u8]) -> bool {
    static MATS: OnceLock<Vec<irsig::material::Material>> = OnceLock::new();
    let mats = MATS.get_or_init(|| {
        irsig::material::MaterialDb::load_json(&scratch().join("materials.json"))
            .expect("bundled materials")
            .materials()
            .to_vec()
    });
    let p = Path::new("fuzz-params.json");
    match irsig::analysis::params::ParamSet::parse(&text(data), p, mats) {
        Ok(ps) => {
            finite(&ps.nominal(), "nominal");
            true
        }
        Err(e) => check_error(&e, p),
    }
}

/// POINTS files: truth points, control points, temperature series (all
/// three readers on the same bytes).
pub fn points(data: &[u8]) -> bool {
    use irsig::analysis::csv::{read_control_points, read_temperature_series, read_truth_points};
    let p = input_file("points.csv", data);
    let truth = match read_truth_points(&p) {
        Ok(pts) => {
            for pt in &pts {
                if let Some(v) = pt.value {
                    assert!(v.is_finite(), "value {v} accepted");
                }
            }
            true
        }
        Err(e) => check_error(&e, &p),
    };
    let control = match read_control_points(&p) {
        Ok(_) => true,
        Err(e) => check_error(&e, &p),
    };
    let series = match read_temperature_series(&p) {
        Ok(s) => {
            for (_, t) in s {
                assert!(t.is_finite(), "temperature {t} accepted");
            }
            true
        }
        Err(e) => check_error(&e, &p),
    };
    truth || control || series
}

// ---------------------------------------------------------------- DIRSIG scene import

/// The hand-written DIRSIG simulation every DIRSIG target imports: a `.sim` and a
/// `.jsim` naming a `.scene` (origin, folders, a geometry list, a `.mat` with an
/// `.ems`), a `.glist` (OBJ with a translate/scale/rotate instance, a 4×4 matrix
/// instance, a nested list, an `.odb`), the `.odb` (9- and 16-value INFO lines, a
/// `.gdb`), the `.gdb`, a `.tasks`, a `.ppd`, a `.platform`, a `.atm` and a `.wth`.
/// Paths relative to the set's folder.
pub const DIRSIG_SET: &[(&str, &str)] = &[
    (
        "x.sim",
        r#"<simulation>
  <scene externalfile="scene/t.scene"/>
  <atmosphericconditions externalfile="a.atm"/>
  <platform externalfile="platforms/p.platform"/>
  <platformmotion externalfile="motion/m.ppd"/>
  <tasklist externalfile="tasks/t.tasks"/>
</simulation>
"#,
    ),
    (
        "s.jsim",
        r#"[{"scene_list": [{"inputs": "scene/t.scene"}],
  "plugin_list": [
    {"name": "BasicPlatform", "inputs": {"platform_filename": "platforms/p.platform",
      "motion_filename": "motion/m.ppd", "tasks_filename": "tasks/t.tasks"}},
    {"name": "NewAtmosphere", "inputs": {"backend": {"name": "modtran_tape",
      "tape5_parameters": {"atmospheric_model": "MidLatitudeSummer"}}}},
    {"name": "ThermWeather", "inputs": {"filename": "weather/w.wth"}},
    {"name": "SpiceEphemeris", "inputs": {}}
  ]}]
"#,
    ),
    (
        "a.atm",
        r#"<atmosphericconditions>
  <uniformweather><classicdata><filename>weather/w.wth</filename></classicdata></uniformweather>
  <simpleradiativetransfer><apparentskytemperature>250</apparentskytemperature></simpleradiativetransfer>
</atmosphericconditions>
"#,
    ),
    (
        "scene/t.scene",
        r#"<classicscene>
  <metadata><entry><name>Name</name><value><![CDATA[Fuzz]]></value></entry></metadata>
  <sceneorigin>
    <location frame="geodetic">
      <latitude>43.16</latitude><longitude>-77.61</longitude><altitude>160</altitude>
    </location>
  </sceneorigin>
  <gdbdirectory>$SCENE_DIR/geometry</gdbdirectory>
  <geometrylist enabled="true">
    <geometrylistinclude name="g" enabled="true">l.glist</geometrylistinclude>
  </geometrylist>
  <matfilename>$SCENE_DIR/materials/scene.mat</matfilename>
  <emsdirectory>$SCENE_DIR/materials/</emsdirectory>
</classicscene>
"#,
    ),
    (
        "scene/materials/scene.mat",
        "MATERIAL_ENTRY {
    ID = 7
    NAME = concrete
    TEMP_SOLVER_NAME = Therm
    TEMP_SOLVER {
        SPECIFIC_HEAT = 0.22
        MASS_DENSITY = 2.3
        THERMAL_CONDUCTIVITY = 8
        SOLAR_ABSORPTION = 0.7
        THERMAL_EMISSIVITY = 0.9
        EXPOSED_AREA = 0
        THICKNESS = 10
    }
    SURFACE_PROPERTIES {
        EMISSIVITY_PROP_NAME = ClassicEmissivity
        EMISSIVITY_PROP {
            FILENAME = e.ems
        }
    }
}
MATERIAL_ENTRY {
    ID = steel_mat
    NAME = steel
    TEMP_SOLVER_NAME = Therm
    TEMP_SOLVER {
        SPECIFIC_HEAT = 0.11
        MASS_DENSITY = 7.8
        THERMAL_CONDUCTIVITY = 400
        SOLAR_ABSORPTION = 0.5
        THERMAL_EMISSIVITY = 0.3
        EXPOSED_AREA = 1
        THICKNESS = 0.5
    }
}
MATERIAL_ENTRY {
    ID = 100
    NAME = Nothing
    TEMP_SOLVER_NAME = Null
    TEMP_SOLVER {
    }
}
",
    ),
    // One curve: 91 angular weights (0..=90°, falling off near grazing), then the
    // new-format spectrum (µm, TAB-separated as in Rendered.ai's files).
    (
        "scene/materials/e.ems",
        "1\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n1.0\n0.99\n0.98\n0.96\n0.93\n0.89\n0.83\n0.74\n0.61\n0.42\n0.2\n0.0\nCURVE_BEGIN\n3.0\t0.90\n8.0\t0.93\n14.0\t0.95\n",
    ),
    (
        "scene/geometry/l.glist",
        r#"<geometrylist enabled="true">
  <object>
    <basegeometry><obj><filename>tri.obj</filename></obj></basegeometry>
    <staticinstance/>
    <staticinstance>
      <translation><point><x>10</x><y>0</y><z>0</z></point></translation>
      <scale><cartesiantriple><x>2</x><y>2</y><z>1</z></cartesiantriple></scale>
      <rotation><cartesiantriple><x>0</x><y>0</y><z>90</z></cartesiantriple></rotation>
    </staticinstance>
    <staticinstance><matrix>1,0,0,-5, 0,1,0,0, 0,0,1,0, 0,0,0,1</matrix></staticinstance>
  </object>
  <object>
    <basegeometry><glist><filename>inner.glist</filename></glist></basegeometry>
    <staticinstance><translation><point><x>0</x><y>0</y><z>3</z></point></translation></staticinstance>
  </object>
  <object>
    <basegeometry><odb><filename>scene.odb</filename></odb></basegeometry>
    <staticinstance/>
  </object>
</geometrylist>
"#,
    ),
    (
        "scene/geometry/inner.glist",
        r#"<geometrylist>
  <object><basegeometry><obj><filename>quad.obj</filename><assign id="steel_mat">roof</assign></obj></basegeometry>
    <staticinstance/></object>
</geometrylist>
"#,
    ),
    (
        "scene/geometry/tri.obj",
        "v 1 0 0\nv 0 1 0\nv 0 0 0\nusemtl 7\nf 3 1 2\n",
    ),
    (
        "scene/geometry/quad.obj",
        "v -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\nusemtl roof\nf 1 2 3 4\n",
    ),
    (
        "scene/geometry/scene.odb",
        "DIRSIG_ODB = 1.0

OBJECT {
    GDB_FILENAME = box.gdb
    UNITS = CENTIMETERS
    INSTANCES {
        INFO = 10.0, 20.0, 0.0, 1.00, 1.00, 1.00, 0.00, 0.00, 90.0
        INFO = 1 0 0 -5 0 1 0 0 0 0 1 0 0 0 0 1
    }
}

OBJECT {
    OBJ_FILENAME = tri.obj
    UNITS = METERS
    INSTANCES {
        INFO = 0, 0, 3, 1, 1, 1, 0, 0, 0
    }
}
",
    ),
    (
        "scene/geometry/box.gdb",
        "OBJECT\nBOX\n1-0-0\nPART\nTOP\n1-1-0\n\
FACE\nF1\n1-1-1\nconcrete\n7\nf1\n-1.0\n0.0\n0.0\n0.0\nnull\nnull\nnull\n4\n\
0 0 0\n100 0 0\n100 100 0\n0 100 0\n0 0 1\n0.0\n0.0\n0.0\n\
FACE\nF2\n1-1-2\nsteel\nsteel_mat\n50.0\n0.0\n0.0\n0.0\nnull\nnull\nnull\n3\n\
0 0 1\n100 0 1\n0 100 1\n0 0 1\n0.0\n0.0\n0.0\nEND\n",
    ),
    (
        "tasks/t.tasks",
        r#"<tasklist>
  <reference><datetime type="absolute">2025-06-21T10:00:00.0000-04:00</datetime></reference>
  <task><start><datetime type="relative">3600</datetime></start><stop><datetime type="relative">3600</datetime></stop></task>
</tasklist>
"#,
    ),
    (
        "motion/m.ppd",
        r#"<platformmotion type="generic"><method type="raw"/>
<data rotationframe="sceneenu" rotationorder="xyz" angletype="absolute" angularunits="degrees" spatialunits="meters">
<entry><datetime type="relative">0</datetime>
<position><location type="scene"><point><x>0</x><y>0</y><z>1000</z></point></location></position>
<orientation><eulerangles><cartesiantriple><x>0</x><y>0</y><z>0</z></cartesiantriple></eulerangles></orientation></entry>
</data></platformmotion>
"#,
    ),
    (
        "platforms/p.platform",
        r#"<platform><attachment><mount name="m" type="static"><data angularunits="radians" rotationorder="xyz"><xrotation>0</xrotation><yrotation>0</yrotation><zrotation>0</zrotation></data>
<attachment><instrument name="cam" type="generic"><properties><focallength>50</focallength><aperturediameter>0.03</aperturediameter></properties>
<focalplane enabled="true" name="LWIR cam"><capturemethod><spectralresponse><bandpass spectralunits="microns"><minimum>7</minimum><maximum>13</maximum><delta>0.1</delta></bandpass>
<channellist><channel name="lw" shape="rectangle"><center>10</center><width>4</width></channel></channellist></spectralresponse></capturemethod>
<detectorarray spatialunits="microns"><xelementcount>64</xelementcount><yelementcount>48</yelementcount><xelementspacing>17</xelementspacing><yelementspacing>17</yelementspacing></detectorarray>
</focalplane></instrument></attachment></mount></attachment></platform>
"#,
    ),
    (
        "weather/w.wth",
        "3 1.000000\n0.0015.00 1000.00  0.60  5.00   2.00     0.00     0.00 1.00  0  0   0.00  0.00\n\
1.0014.00 1000.00  0.60  5.00   2.00     0.00     0.00 1.00  0  0   0.00  0.00\n\
2.0013.00 1000.00  0.60  5.00   2.00     0.00     0.00 1.00  0  0   0.00  0.00\n",
    ),
];

/// This thread's copy of [`DIRSIG_SET`] (written on first use).
fn dirsig_dir() -> PathBuf {
    thread_local! {
        static DIR: PathBuf = {
            let d = scratch().join(
                format!("dirsig-{:?}", std::thread::current().id()).replace(['(', ')'], ""),
            );
            for (rel, text) in DIRSIG_SET {
                let p = d.join(rel);
                std::fs::create_dir_all(p.parent().unwrap()).expect("dirsig set folder");
                std::fs::write(&p, text).expect("dirsig set file");
            }
            d
        };
    }
    DIR.with(Clone::clone)
}

/// The root element's name of XML `data` (lower case; the first `<name` after any
/// declarations, comments and DTD), if any.
fn xml_root(data: &[u8]) -> Option<String> {
    let mut i = 0;
    while let Some(k) = data[i..].iter().position(|&c| c == b'<') {
        let s = i + k + 1;
        let name: Vec<u8> = data[s..]
            .iter()
            .take_while(|c| c.is_ascii_alphanumeric() || matches!(c, b'_' | b'-' | b':'))
            .copied()
            .collect();
        if name.first().is_some_and(u8::is_ascii_alphabetic) {
            return Some(String::from_utf8_lossy(&name).to_ascii_lowercase());
        }
        i = s;
    }
    None
}

/// Import the set's `entry` with `data` in place of its file `role`; check what is
/// accepted, restore the file.
fn dirsig_import(role: &str, entry: &str, data: &[u8]) -> bool {
    use irsig::scene::dirsig::{ImportOptions, import};
    let dir = dirsig_dir();
    let target = dir.join(role);
    std::fs::write(&target, data).expect("write fuzz input");
    let opts = ImportOptions {
        search_dirs: Vec::new(),
        time: None,
    };
    let result = import(&dir.join(entry), &dir.join("out.json"), &opts);
    let original = DIRSIG_SET.iter().find(|(r, _)| *r == role).unwrap().1;
    std::fs::write(&target, original).expect("restore fixture");
    match result {
        Ok(im) => {
            check_imported(&im, &dir);
            true
        }
        Err(e) => {
            // Every error names a file: the one at fault or the one naming it.
            match &e {
                irsig::Error::Io { .. } => {}
                irsig::Error::Parse { location, .. } => {
                    assert!(location.path.is_some(), "error names no file: {e}")
                }
                other => panic!("error names no file: {other}"),
            }
            false
        }
    }
}

/// What an import accepts: finite numbers everywhere (a NaN serialises as `null`),
/// a site on the globe, a valid time, materials that load as a database, every
/// object's and part's material among them, generated OBJ files with finite vertices
/// and indices in range.
fn check_imported(im: &irsig::scene::dirsig::Imported, dir: &Path) {
    fn no_null(v: &serde_json::Value, at: &str) {
        match v {
            serde_json::Value::Null => panic!("non-finite number accepted at {at}"),
            serde_json::Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    no_null(x, &format!("{at}[{i}]"));
                }
            }
            serde_json::Value::Object(m) => {
                for (k, x) in m {
                    no_null(x, &format!("{at}.{k}"));
                }
            }
            _ => {}
        }
    }
    let scene = serde_json::to_value(&im.scene).expect("scene serialises");
    no_null(&scene, "scene");
    let mats = serde_json::to_value(&im.materials).expect("materials serialise");
    no_null(&mats, "materials");
    let site = &im.scene.site;
    assert!(
        (-90.0..=90.0).contains(&site.latitude_deg)
            && (-180.0..=360.0).contains(&site.longitude_deg),
        "site {site:?} accepted"
    );
    assert!(
        chrono::DateTime::parse_from_rfc3339(&im.scene.time).is_ok(),
        "time {} accepted",
        im.scene.time
    );
    let names: Vec<&str> = im
        .materials
        .materials
        .iter()
        .map(|m| m.name.as_str())
        .collect();
    for o in &im.scene.objects {
        let used = o.material.iter().map(String::as_str);
        for m in used.chain(o.parts.iter().map(|p| p.material.as_str())) {
            assert!(
                names.contains(&m),
                "object {} uses unknown material {m}",
                o.name
            );
        }
    }
    let p = dir.join("out.materials.json");
    std::fs::write(&p, serde_json::to_string(&im.materials).unwrap()).expect("write");
    if let Err(errs) = irsig::material::db::load_json_all(&p) {
        panic!("imported materials invalid: {errs:?}");
    }
    for (rel, text) in &im.files {
        if rel.ends_with(".obj") {
            let groups = irsig::scene::obj::load_obj_str(text, Path::new(rel))
                .unwrap_or_else(|e| panic!("generated {rel} does not load: {e}"));
            for g in &groups {
                let n = g.mesh.positions.len() as u32;
                for v in &g.mesh.positions {
                    assert!(v.is_finite(), "non-finite vertex {v} in {rel}");
                }
                for t in &g.mesh.indices {
                    for &i in t {
                        assert!(i < n, "index {i} out of {n} vertices in {rel}");
                    }
                }
            }
        }
    }
}

/// DIRSIG XML files (`.scene`, `.glist`, `.sim`, `.tasks`, `.ppd`, `.platform`,
/// `.atm`), by root element, imported through the set's `.sim` (a `.scene` or
/// `.glist` through the set's `.scene`); any other root is the simulation itself.
pub fn dirsig_xml(data: &[u8]) -> bool {
    if data.len() > 65536 {
        return false;
    }
    let (role, entry) = match xml_root(data).as_deref() {
        Some("classicscene") => ("scene/t.scene", "scene/t.scene"),
        Some("geometrylist") => ("scene/geometry/l.glist", "scene/t.scene"),
        Some("tasklist") => ("tasks/t.tasks", "x.sim"),
        Some("platformmotion") => ("motion/m.ppd", "x.sim"),
        Some("platform") => ("platforms/p.platform", "x.sim"),
        Some("atmosphericconditions") => ("a.atm", "x.sim"),
        _ => ("x.sim", "x.sim"),
    };
    dirsig_import(role, entry, data)
}

/// DIRSIG text files: `.jsim` (JSON: starts with `[` or `{`), `.odb` (holds
/// `DIRSIG_ODB`), else `.gdb`; a `.jsim` is imported itself, the others through the
/// set's `.scene`.
pub fn dirsig_text(data: &[u8]) -> bool {
    if data.len() > 65536 {
        return false;
    }
    let head = data.iter().find(|c| !c.is_ascii_whitespace());
    let (role, entry) = if matches!(head, Some(b'[' | b'{')) {
        ("s.jsim", "s.jsim")
    } else if data
        .windows(10)
        .any(|w| w.eq_ignore_ascii_case(b"DIRSIG_ODB"))
    {
        ("scene/geometry/scene.odb", "scene/t.scene")
    } else {
        ("scene/geometry/box.gdb", "scene/t.scene")
    };
    dirsig_import(role, entry, data)
}

// ---------------------------------------------------------------- state folders

/// The scene a fuzzed state folder belongs to: 5 facets, two image times, one shard.
fn state_key() -> irsig::render::state::StateKey {
    irsig::render::state::StateKey {
        scene_hash: "0123456789abcdef".into(),
        times: vec![
            "2025-06-21T12:00:00-04:00".into(),
            "2025-06-21T14:00:00-04:00".into(),
        ],
        facets: 5,
    }
}

/// This thread's state folder.
fn state_dir() -> PathBuf {
    thread_local! {
        static DIR: PathBuf = {
            let d = scratch().join(
                format!("state-{:?}", std::thread::current().id()).replace(['(', ')'], ""),
            );
            std::fs::create_dir_all(&d).expect("state folder");
            d
        };
    }
    DIR.with(Clone::clone)
}

/// A state folder's files (`render::state`): `manifest.json` (JSON input) or a
/// shard file (anything else), read both as a state file (`state-1-of-1.arrow`) and
/// as a pass-1 rays file (`rays-1-of-1.arrow`) of [`state_key`]'s scene.
pub fn state(data: &[u8]) -> bool {
    use irsig::render::state::{read_manifest, read_rays, read_state_file};
    let dir = state_dir();
    let head = data.iter().find(|c| !c.is_ascii_whitespace());
    if head == Some(&b'{') {
        let p = dir.join("manifest.json");
        std::fs::write(&p, data).expect("write fuzz input");
        return match read_manifest(&dir) {
            Ok(Some(m)) => {
                assert_eq!(m.format, irsig::render::state::FORMAT);
                assert!(m.version <= irsig::render::state::VERSION);
                true
            }
            Ok(None) => panic!("manifest present but not read"),
            Err(e) => check_error(&e, &p),
        };
    }
    let key = state_key();
    let p = dir.join("state-1-of-1.arrow");
    std::fs::write(&p, data).expect("write fuzz input");
    let states = match read_state_file(&p, &key, (1, 1), 0..5) {
        Ok(s) => {
            assert_eq!(s.len(), 5);
            assert_eq!(s.at.len(), 2);
            finite32(&s.shape_factor, "shape_factor");
            for t in &s.at {
                for (v, what) in [
                    (&t.temperature_k, "temperature"),
                    (&t.sun_fraction, "sun_fraction"),
                    (&t.cos_sun, "cos_sun"),
                    (&t.background_k, "background"),
                ] {
                    assert_eq!(v.len(), 5, "{what}");
                    finite32(v, what);
                }
            }
            true
        }
        Err(e) => check_error(&e, &p),
    };
    let p = dir.join("rays-1-of-1.arrow");
    std::fs::write(&p, data).expect("write fuzz input");
    let rays = match read_rays(&p, &key, (1, 1), 0..5) {
        Ok(r) => {
            let sky = &r.sky;
            assert_eq!(sky.shape_factor.len(), 5);
            assert_eq!(sky.back_shape_factor.len(), 5);
            assert_eq!(sky.std_error.len(), 5);
            assert_eq!(sky.ground_weight.len(), 5);
            assert_eq!(r.ground.len(), 5);
            assert_eq!(sky.offsets.len(), 6);
            assert!(sky.offsets.windows(2).all(|w| w[0] <= w[1]), "offsets");
            assert_eq!(*sky.offsets.last().unwrap() as usize, sky.entries.len());
            for e in &sky.entries {
                assert!((e.facet as usize) < key.facets, "facet {}", e.facet);
                assert!(e.weight.is_finite(), "weight {}", e.weight);
            }
            finite32(&sky.shape_factor, "shape_factor");
            finite32(&sky.std_error, "std_error");
            finite32(&sky.ground_weight, "ground_weight");
            let backs: Vec<f32> = sky.back_shape_factor.iter().flatten().copied().collect();
            finite32(&backs, "back_shape_factor");
            let h = &r.solar;
            assert_eq!(h.facet_count(), 5);
            assert_eq!(h.lit.len(), 5 * h.day.len() * h.width());
            for f in 0..5 {
                for d in 0..h.day.len() {
                    assert!(
                        h.lit_points(f, d) <= h.points,
                        "lit points above the points"
                    );
                }
            }
            true
        }
        Err(e) => check_error(&e, &p),
    };
    states || rays
}

fn finite32(xs: &[f32], what: &str) {
    for (i, x) in xs.iter().enumerate() {
        assert!(x.is_finite(), "{what}[{i}] = {x} accepted");
    }
}

/// Seeds of `state`: a manifest, and a state file and a rays file written by
/// `render::state`'s own writers for [`state_key`]'s scene.
fn state_seeds() -> Vec<Vec<u8>> {
    use irsig::exposure::{BackgroundEntry, ExposureStats, SkyView, SolarHistory};
    use irsig::render::scene_thermal::FacetRays;
    use irsig::render::state::{FacetStates, FacetTimeState, write_rays, write_states};
    let key = state_key();
    let dir = scratch().join("state-seeds");
    std::fs::create_dir_all(&dir).expect("seed folder");
    let manifest = serde_json::json!({
        "format": irsig::render::state::FORMAT,
        "version": irsig::render::state::VERSION,
        "scene": "/data/town/scene.json",
        "scene_hash": key.scene_hash,
        "facets": key.facets,
        "times": key.times,
        "rays_shards": 1,
        "state_shards": 1,
    });
    let at = |t: f32| FacetTimeState {
        temperature_k: vec![t, t + 1.0, t + 2.5, t - 3.0, t + 10.0],
        sun_fraction: vec![1.0, 0.5, 0.0, 1.0, 0.25],
        cos_sun: vec![0.9, 0.8, 0.0, 0.7, 0.6],
        background_k: vec![300.0; 5],
    };
    let states = FacetStates {
        times: Vec::new(),
        first: 0,
        shape_factor: vec![1.0, 0.8, 0.5, 0.9, 0.2],
        back_shape_factor: vec![None, Some(0.4), None, None, None],
        at: vec![at(300.0), at(310.0)],
    };
    let p = dir.join("state-1-of-1.arrow");
    write_states(&p, &key, (1, 1), &states).expect("state seed");
    let state_file = std::fs::read(&p).expect("state seed");
    let rays = FacetRays {
        range: 0..5,
        solar: SolarHistory {
            steps: 3,
            facets: 5,
            day: vec![1, 2],
            points: 2,
            lit: (0..10).map(|i| (i % 3) as u8).collect(),
            ..SolarHistory::default()
        },
        sky: SkyView {
            shape_factor: vec![1.0, 0.8, 0.5, 0.9, 0.2],
            back_shape_factor: vec![None, Some(0.4), None, None, Some(0.1)],
            std_error: vec![0.0, 0.01, 0.02, 0.01, 0.03],
            ground_weight: vec![0.0, 0.1, 0.2, 0.05, 0.3],
            offsets: vec![0, 0, 1, 3, 3, 5],
            entries: [(0, 0.1), (0, 0.2), (1, 0.1), (2, 0.3), (3, 0.2)]
                .map(|(facet, weight)| BackgroundEntry { facet, weight })
                .to_vec(),
        },
        ground: vec![true, false, false, true, false],
        exposed_back_shape_factor: vec![Some(0.5), None, None, Some(0.3), None],
        stats: ExposureStats::default(),
    };
    let p = dir.join("rays-1-of-1.arrow");
    write_rays(&p, &key, (1, 1), &rays).expect("rays seed");
    let rays_file = std::fs::read(&p).expect("rays seed");
    vec![
        serde_json::to_vec_pretty(&manifest).unwrap(),
        state_file,
        rays_file,
    ]
}

// ---------------------------------------------------------------- seeds

/// A small scene using the shared material library, a heightmap, a box
/// with instances and the OBJ file.
pub const SEED_SCENE: &str = r#"{
  "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160, "utc_offset_hours": -4},
  "time": "2025-06-21T14:00:00-04:00",
  "materials": ["../materials.json"],
  "objects": [
    {"name": "ground",
     "shapes": [{"heightmap": {"size": [20, 10], "cells": [2, 1],
                  "heights": [[0, 1, 2], [0, 0, 0]],
                  "classes": {"legend": {"a": "asphalt", "g": "lawn"}, "rows": ["ag"]}}}],
     "parts": [{"name": "lawn", "material": "grass", "shape_factor": 0.9}]},
    {"name": "shed",
     "shapes": [{"box": {"size": [2, 3, 4], "bottom": false}}],
     "material": "painted_steel",
     "parts": [{"name": "top", "material": "painted_steel", "thickness_m": 0.01, "self_power_w_m2": 50}],
     "instances": [{"translate": [100, 0, 0]},
                   {"translate": [0, 100, 0], "rotate_deg": [0, 0, 90], "scale": 2}]},
    {"name": "thing", "shapes": [{"obj": "geo/two.obj"}],
     "parts": [{"name": "glass", "material": "glass", "fixed_temperature_k": 300}],
     "material": "concrete"}
  ],
  "sensors": [{"type": "frame", "name": "cam", "width": 4}]
}"#;

/// Two OBJ groups, quads, texture indices and negative indices.
pub const SEED_OBJ: &str = "# two groups, the MTL file is absent
mtllib missing.mtl
o ground
v 0 0 0
v 10 0 0
v 10 10 0
v 0 10 0
usemtl asphalt
f 1 2 3 4
o shed
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
vt 0 0
usemtl painted_steel
f 5 6 7
f 5/1 6/1 8/1
usemtl glass
f -4 -2 -1
";

const SEED_RESPONSE: &str = "wavelength_um,response\n8,0\n9,1\n13,1\n14,0\n";
const SEED_RESPONSE2: &str = "# comment\n8 0\n9\t1\n\n13;1 # x\n14,0\n";
const SEED_PARAMS: &str = r#"{"params": [
  {"kind": "weather", "property": "air_temperature_offset_k", "low": -2, "high": 2, "uncertainty": 0.5},
  {"kind": "weather", "property": "relative_humidity_offset", "low": -0.2, "high": 0.2},
  {"kind": "material", "material": "asphalt", "property": "thermal_emissivity", "low": 0.85, "high": 0.98}
]}"#;
const SEED_TRUTH: &str = "id,x,y,value,material\np1,10,10,300.5,asphalt\np2,20,5,290,grass\n";
const SEED_CONTROL: &str =
    "synth_x,synth_y,truth_x,truth_y\n10,10,11,10\n20,5,19,7\n0,0,3,1\n7,7,8,8\n";
const SEED_SERIES: &str =
    "time,surface_temperature_k\n2025-06-21T10:00:00-04:00,300\n2025-06-21T11:00:00-04:00,305.5\n";
const SEED_MATERIALS: &str = r#"{"materials": [
  {"name": "slab", "id": 7, "density_kg_m3": 2300, "specific_heat_j_kg_k": 880,
   "conductivity_w_m_k": 1.4, "thickness_m": 0.2, "solar_absorptivity": 0.7,
   "thermal_emissivity": 0.92, "exposed_area": 1.0,
   "emissivity_curve": {"wavelengths_um": [3, 14], "emissivity": [[0.9, 0.95]]}}
]}"#;
const SEED_WEATHER_CSV: &str = "time,air_temperature_k,dew_point_k,pressure_pa,wind_speed_m_s,global_horizontal_w_m2\n\
2025-06-20T00:00:00-04:00,290,280,101325,2,0\n2025-06-20T01:00:00-04:00,289,280,101325,2.5,0\n";

/// Seed inputs for `target`: the repository's fixtures and, where present,
/// the real DIRSIG/MODTRAN files in `../shared/data`, plus inline examples.
pub fn seeds(target: &str, repo: &Path) -> Vec<Vec<u8>> {
    let shared = repo.join("../shared/data");
    let files: Vec<PathBuf> = match target {
        "material_json" => vec![repo.join("scenes/materials.json")],
        "dirsig_mat" => vec![shared.join("dirsig/tahoe.mat")],
        "dirsig_ems" => vec![shared.join("dirsig/gray.ems")],
        "weather" => vec![
            shared.join("dirsig/saw.wth"),
            repo.join("tests/data/weather/723170TYA_jun21.csv"),
            repo.join("tests/data/weather/rochester_sample_tmy3.csv"),
            repo.join("tests/data/weather/rochester_sample.epw"),
            repo.join("scenes/town/weather.csv"),
        ],
        "tape7" => [
            "tape7-01b",
            "tape7-02c",
            "tape7-05",
            "tape7.LWIRSun",
            "tape7.MWIRSun",
        ]
        .iter()
        .map(|f| shared.join("modtran").join(f))
        .collect(),
        _ => vec![],
    };
    let inline: &[&str] = match target {
        "scene_json" => &[SEED_SCENE],
        "obj" => &[SEED_OBJ],
        "material_json" => &[SEED_MATERIALS],
        "response_csv" => &[SEED_RESPONSE, SEED_RESPONSE2],
        "params" => &[SEED_PARAMS],
        "points" => &[SEED_TRUTH, SEED_CONTROL, SEED_SERIES],
        "weather" => &[SEED_WEATHER_CSV],
        _ => &[],
    };
    let mut out: Vec<Vec<u8>> = files.iter().filter_map(|f| std::fs::read(f).ok()).collect();
    out.extend(inline.iter().map(|s| s.as_bytes().to_vec()));
    let set = |roles: &[&str]| -> Vec<Vec<u8>> {
        roles
            .iter()
            .map(|r| {
                DIRSIG_SET
                    .iter()
                    .find(|(n, _)| n == r)
                    .unwrap()
                    .1
                    .as_bytes()
                    .to_vec()
            })
            .collect()
    };
    match target {
        "gltf" => out.extend(gltf_seeds()),
        "dirsig_xml" => out.extend(set(&[
            "x.sim",
            "a.atm",
            "scene/t.scene",
            "scene/geometry/l.glist",
            "scene/geometry/inner.glist",
            "tasks/t.tasks",
            "motion/m.ppd",
            "platforms/p.platform",
        ])),
        "dirsig_text" => out.extend(set(&[
            "s.jsim",
            "scene/geometry/scene.odb",
            "scene/geometry/box.gdb",
        ])),
        "state" => out.extend(state_seeds()),
        _ => {}
    }
    out
}

/// More starting inputs for `target` that its reader need not accept: real DIRSIG
/// files from `../shared/data/dirsig` (where present) whose references lie outside
/// the hand-written set (geometry, materials and weather of their own scenes), so
/// their import stops at a missing file; mutated all the same.
pub fn extra_seeds(target: &str, repo: &Path) -> Vec<Vec<u8>> {
    let d = repo.join("../shared/data/dirsig/protoDIRSIG");
    let files: Vec<PathBuf> = match target {
        "dirsig_xml" => vec![
            d.join("config_repo/scenes/tahoe/tahoe.scene"),
            d.join("manifold_config_repo/scenes/tahoe/geometry/lists/terrain.glist"),
            d.join("manifold_config_repo/scenes/tahoe/geometry/bundles/hypersonic/hypersonic.glist"),
            d.join("AUROR_ref/geometry/lists/hypersonic.glist"),
            d.join("notebooks/sidebars/vehicle_point_source/vehicle_pointsource/vehicle_pointsource.glist"),
            d.join("AUROR_ref/tasks/AurorTask.tasks"),
            d.join("tests/fixtures/auror_ref/motion/AurorMotion.ppd"),
            d.join("manifold_config_repo/platforms/AurorNIRDetector/AurorNIRDetector.platform"),
            repo.join("../shared/data/dirsig/rendered-ai/packages/dirsig_pkg/dirsig_pkg/simple.atm"),
        ],
        "dirsig_text" => vec![d.join("AUROR_ref/jsims/AurorSimulation.jsim")],
        _ => vec![],
    };
    files.iter().filter_map(|f| std::fs::read(f).ok()).collect()
}

/// Two glTF seeds, the same document as `.gltf` (base64 data URI) and as
/// GLB: a cube (8 vertices, `u8` indices) under a rotated, translated node
/// with a scaled child, a triangle strip with `u16` indices, and an
/// unindexed triangle fan.
fn gltf_seeds() -> Vec<Vec<u8>> {
    use base64::Engine;
    let mut bin: Vec<u8> = Vec::new();
    let f32s = |bin: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| bin.extend(x.to_le_bytes()));
    let cube: Vec<f32> = (0..8)
        .flat_map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
        .collect();
    f32s(&mut bin, &cube); // 0..96
    let idx: [u8; 36] = [
        0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5, 0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3, 0, 2, 3, 0, 3, 1,
        4, 5, 7, 4, 7, 6,
    ];
    bin.extend(idx); // 96..132
    f32s(&mut bin, &[0., 0., 0., 0., 0., 1., 1., 0., 0., 1., 0., 1.]); // 132..180
    for i in [0u16, 1, 2, 3] {
        bin.extend(i.to_le_bytes()); // 180..188
    }
    f32s(
        &mut bin,
        &[0., 0., 0., 1., 0., 0., 1., 0., -1., 0., 0., -1.],
    ); // 188..236
    let doc = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,2]}],
"nodes":[{"name":"root","translation":[5,0,1],"rotation":[0,0.7071068,0,0.7071068],"children":[1]},
{"mesh":0,"scale":[2,3,4]},{"mesh":1,"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,2,0,1]}],
"meshes":[{"name":"cube","primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]},
{"name":"flat","primitives":[{"attributes":{"POSITION":2},"indices":3,"mode":5,"material":1},
{"attributes":{"POSITION":4},"mode":6}]}],
"materials":[{"name":"brick"},{"name":"glass"}],
"accessors":[{"bufferView":0,"componentType":5126,"count":8,"type":"VEC3","min":[0,0,0],"max":[1,1,1]},
{"bufferView":1,"componentType":5121,"count":36,"type":"SCALAR"},
{"bufferView":2,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,0,1]},
{"bufferView":3,"componentType":5123,"count":4,"type":"SCALAR"},
{"bufferView":4,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,-1],"max":[1,0,0]}],
"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":96},{"buffer":0,"byteOffset":96,"byteLength":36},
{"buffer":0,"byteOffset":132,"byteLength":48},{"buffer":0,"byteOffset":180,"byteLength":8},
{"buffer":0,"byteOffset":188,"byteLength":48}],
"buffers":[{"byteLength":236URI}]}"#;
    let uri = format!(
        r#","uri":"data:application/octet-stream;base64,{}""#,
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    let text = doc.replace("URI", &uri).into_bytes();
    // GLB (glTF 2.0 §4.4): header, JSON chunk (space-padded), BIN chunk.
    let mut json = doc.replace("URI", "").into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::new();
    glb.extend(b"glTF");
    glb.extend(2u32.to_le_bytes());
    glb.extend((total as u32).to_le_bytes());
    glb.extend((json.len() as u32).to_le_bytes());
    glb.extend(0x4E4F_534Au32.to_le_bytes());
    glb.extend(json);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(0x004E_4942u32.to_le_bytes());
    glb.extend(bin);
    vec![text, glb]
}
