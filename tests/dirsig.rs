//! DIRSIG scene import (issue 20 item 1): `.scene`, `.glist`, `.odb`, `.gdb`, `.mat`,
//! `.jsim`, `.sim`, `.tasks`, `.atm`, `.platform`, `.ppd` → an irsig scene. Hand-written
//! files cover each format and convention; the ignored tests import the real files in
//! `../shared/data/dirsig` (and render the complete scene set).

use std::path::{Path, PathBuf};

use glam::Vec3;
use irsig::scene::Scene;
use irsig::scene::dirsig::{ImportOptions, import, is_dirsig_scene};

use crate::util::shared_data;

fn put(dir: &Path, rel: &str, text: &str) -> PathBuf {
    let p = dir.join(rel);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    std::fs::write(&p, text).unwrap();
    p
}

/// A THERM entry in classic units (cal, g, cm, h).
fn therm_entry(id: &str, name: &str) -> String {
    format!(
        "MATERIAL_ENTRY {{\n    ID = {id}\n    NAME = {name}\n    TEMP_SOLVER_NAME = Therm\n    TEMP_SOLVER {{\n        SPECIFIC_HEAT = 0.22\n        MASS_DENSITY = 2.3\n        THERMAL_CONDUCTIVITY = 8\n        SOLAR_ABSORPTION = 0.7\n        THERMAL_EMISSIVITY = 0.9\n        EXPOSED_AREA = 0\n        THICKNESS = 10\n    }}\n}}\n"
    )
}

const NULL_ENTRY: &str = "MATERIAL_ENTRY {\n    ID = 100\n    NAME = Nothing\n    TEMP_SOLVER_NAME = Null\n    TEMP_SOLVER {\n    }\n}\n";

/// A `.scene` at the origin of Rochester, geometry in `geometry/`, materials in
/// `materials/scene.mat`, one geometry list.
fn scene_xml(glist: &str) -> String {
    format!(
        r#"<classicscene>
  <metadata><entry><name>Name</name><value><![CDATA[Test]]></value></entry></metadata>
  <sceneorigin>
    <location frame="geodetic">
      <latitude>43.16</latitude><longitude>-77.61</longitude><altitude>160</altitude>
    </location>
  </sceneorigin>
  <gdbdirectory>$SCENE_DIR/geometry</gdbdirectory>
  <geometrylist enabled="true">
    <geometrylistinclude name="g" enabled="true">{glist}</geometrylistinclude>
  </geometrylist>
  <matfilename>$SCENE_DIR/materials/scene.mat</matfilename>
  <emsdirectory>$SCENE_DIR/materials/</emsdirectory>
</classicscene>
"#
    )
}

/// One triangle (1,0,0), (0,1,0), (0,0,0), front face up, material ID `id`.
fn tri_obj(id: &str) -> String {
    format!("v 1 0 0\nv 0 1 0\nv 0 0 0\nusemtl {id}\nf 3 1 2\n")
}

fn load(path: &Path) -> Scene {
    Scene::check_dirsig(
        path,
        &ImportOptions {
            time: Some("2025-06-21T14:00:00-04:00".into()),
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e:#?}"))
}

/// Where instance `i` of the scene puts object-space point `p`.
fn placed(s: &Scene, i: usize, p: [f32; 3]) -> Vec3 {
    s.geometry.instances[i]
        .world_from_object
        .transform_point3(Vec3::from(p))
}

fn near(a: Vec3, b: [f32; 3]) -> bool {
    (a - Vec3::from(b)).length() < 1e-4
}

/// DIRSIG's instance convention: scale, then rotation about x, then y, then z (fixed
/// axes, degrees), then translation; a 4×4 matrix row by row with the translation in
/// the fourth column; radians when the rotation says so; another rotation order when
/// given; nested lists compose (parent ∘ child).
#[test]
fn glist_instances_place_objects_where_dirsig_convention_says() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    put(dir, "materials/scene.mat", &therm_entry("7", "concrete"));
    put(dir, "geometry/objects/tri.obj", &tri_obj("7"));
    put(
        dir,
        "geometry/lists/main.glist",
        r#"<geometrylist enabled="true">
  <object>
    <basegeometry><obj><filename>objects/tri.obj</filename></obj></basegeometry>
    <staticinstance>
      <translation><point><x>10</x><y>20</y><z>0</z></point></translation>
      <scale><cartesiantriple><x>2</x><y>2</y><z>2</z></cartesiantriple></scale>
      <rotation><cartesiantriple><x>0</x><y>0</y><z>90</z></cartesiantriple></rotation>
    </staticinstance>
    <staticinstance>
      <matrix>1, 0, 0, 5,  0, 1, 0, 6,  0, 0, 1, 7,  0, 0, 0, 1</matrix>
    </staticinstance>
    <staticinstance>
      <rotation angularunits="radians"><cartesiantriple><x>1.5707963267948966</x><y>0</y><z>1.5707963267948966</z></cartesiantriple></rotation>
    </staticinstance>
    <staticinstance>
      <rotation rotationorder="zyx"><cartesiantriple><x>90</x><y>0</y><z>90</z></cartesiantriple></rotation>
    </staticinstance>
    <staticinstance/>
  </object>
  <object>
    <basegeometry><glist><filename>lists/child.glist</filename></glist></basegeometry>
    <staticinstance>
      <translation><point><x>100</x><y>0</y><z>0</z></point></translation>
    </staticinstance>
  </object>
</geometrylist>
"#,
    );
    put(
        dir,
        "geometry/lists/child.glist",
        r#"<geometrylist>
  <object>
    <basegeometry><obj><filename>objects/tri.obj</filename></obj></basegeometry>
    <staticinstance>
      <rotation><cartesiantriple><x>0</x><y>0</y><z>90</z></cartesiantriple></rotation>
    </staticinstance>
  </object>
</geometrylist>
"#,
    );
    let scene = put(dir, "test.scene", &scene_xml("lists/main.glist"));
    assert!(is_dirsig_scene(&scene));
    let s = load(&scene);
    assert_eq!(s.objects.len(), 1, "one mesh, instanced");
    assert_eq!(s.geometry.instances.len(), 6);
    // Scale 2 → (2, 0, 0); +90° about z → (0, 2, 0); + (10, 20, 0).
    assert!(near(placed(&s, 0, [1.0, 0.0, 0.0]), [10.0, 22.0, 0.0]));
    // Matrix: translation (5, 6, 7).
    assert!(near(placed(&s, 1, [1.0, 0.0, 0.0]), [6.0, 6.0, 7.0]));
    // x first: (0, 1, 0) → Rx(90°) → (0, 0, 1) → Rz(90°) → (0, 0, 1).
    assert!(near(placed(&s, 2, [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]));
    // z first: (0, 1, 0) → Rz(90°) → (−1, 0, 0) → Rx(90°) → (−1, 0, 0).
    assert!(near(placed(&s, 3, [0.0, 1.0, 0.0]), [-1.0, 0.0, 0.0]));
    assert!(near(placed(&s, 4, [1.0, 0.0, 0.0]), [1.0, 0.0, 0.0]));
    // Nested: the child's rotation, then the parent's translation.
    assert!(near(placed(&s, 5, [1.0, 0.0, 0.0]), [100.0, 1.0, 0.0]));
    // The material is the .mat entry of the `usemtl` ID.
    let m = &s.materials.materials()[s.parts[0].material];
    assert_eq!(m.name, "concrete");
}

/// The `.mat` values reach the scene in SI, converted by hand here: 0.22 cal/(g·°C) =
/// 921.096 J/(kg·K); 2.3 g/cm³ = 2300 kg/m³; 8 cal/(cm·h·°C) = 8 × 4.1868/36 = 0.930400
/// W/(m·K); 10 cm = 0.1 m.
#[test]
fn imported_materials_carry_si_values() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    put(dir, "materials/scene.mat", &therm_entry("7", "concrete"));
    put(dir, "geometry/objects/tri.obj", &tri_obj("7"));
    put(
        dir,
        "geometry/l.glist",
        "<geometrylist><object><basegeometry><obj><filename>objects/tri.obj</filename></obj></basegeometry><staticinstance/></object></geometrylist>",
    );
    let scene = put(dir, "t.scene", &scene_xml("l.glist"));
    let out = dir.join("out/t.json");
    let im = import(&scene, &out, &ImportOptions::default()).unwrap();
    let m = &im.materials.materials[0];
    assert!((m.specific_heat_j_kg_k.unwrap() - 921.096).abs() < 1e-9);
    assert!((m.density_kg_m3.unwrap() - 2300.0).abs() < 1e-9);
    assert!((m.conductivity_w_m_k.unwrap() - 0.930_4).abs() < 1e-9);
    assert!((m.thickness_m.unwrap() - 0.1).abs() < 1e-12);
    // No time in a bare .scene: a placeholder with a warning.
    assert!(im.warnings.iter().any(|w| w.contains("no image time")));
    // Written and loadable as an ordinary irsig scene.
    let files = im.write(&out).unwrap();
    assert!(files.iter().any(|f| f.ends_with("t.materials.json")));
    let s = Scene::check(&out).unwrap_or_else(|e| panic!("{e:#?}"));
    assert_eq!(s.site.latitude_deg, 43.16);
    assert_eq!(s.site.altitude_m, 160.0);
}

/// `.odb` (9-value and 16-value INFO lines, UNITS, nested) and `.gdb` (facets with
/// material IDs and a fixed temperature in °C).
#[test]
fn odb_and_gdb_import() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    put(
        dir,
        "materials/scene.mat",
        &(therm_entry("7", "concrete") + &therm_entry("8", "steel")),
    );
    put(
        dir,
        "geometry/box.gdb",
        "OBJECT\nBOX\n1-0-0\nPART\nTOP\n1-1-0\n\
         FACE\nF1\n1-1-1\nconcrete\n7\nf1\n-1.0\n0.0\n0.0\n0.0\nnull\nnull\nnull\n4\n\
         0 0 0\n100 0 0\n100 100 0\n0 100 0\n0 0 1\n0.0\n0.0\n0.0\n\
         FACE\nF2\n1-1-2\nsteel\n8\n50.0\n0.0\n0.0\n0.0\nnull\nnull\nnull\n3\n\
         0 0 1\n100 0 1\n0 100 1\n0 0 1\n0.0\n0.0\n0.0\nEND\n",
    );
    put(dir, "geometry/tri.obj", &tri_obj("8"));
    put(
        dir,
        "geometry/inner.odb",
        "DIRSIG_ODB = 1.0\nOBJECT {\n    OBJ_FILENAME = tri.obj\n    UNITS = METERS\n    INSTANCES {\n        INFO = 0, 0, 0, 1, 1, 1, 0, 0, 90\n    }\n}\n",
    );
    put(
        dir,
        "geometry/scene.odb",
        "DIRSIG_ODB = 1.0\n\nOBJECT {\n    GDB_FILENAME = box.gdb\n    UNITS = CENTIMETERS\n    INSTANCES {\n        INFO = 10.0, 20.0, 0.0, 1.00, 1.00, 1.00, 0.00, 0.00, 90.0\n        INFO = 1 0 0 -5 0 1 0 0 0 0 1 0 0 0 0 1\n        INFO = car_path.mov\n    }\n}\n\nOBJECT {\n    ODB_FILENAME = inner.odb\n    INSTANCES {\n        INFO = 0, 0, 3, 1, 1, 1, 0, 0, 0\n    }\n}\n",
    );
    put(
        dir,
        "geometry/l.glist",
        "<geometrylist><object><basegeometry><odb><filename>scene.odb</filename></odb></basegeometry><staticinstance/></object></geometrylist>",
    );
    let scene = put(dir, "t.scene", &scene_xml("l.glist"));
    let out = dir.join("t.json");
    let im = import(&scene, &out, &ImportOptions::default()).unwrap();
    assert!(
        im.warnings
            .iter()
            .any(|w| w.contains("scene.odb:line 9") && w.contains("car_path.mov")),
        "{:#?}",
        im.warnings
    );
    let gdb = &im.scene.objects[0];
    assert_eq!(gdb.instances.as_ref().unwrap().len(), 2);
    let parts: Vec<(&str, &str, Option<f64>)> = gdb
        .parts
        .iter()
        .map(|p| (p.name.as_str(), p.material.as_str(), p.fixed_temperature_k))
        .collect();
    assert_eq!(
        parts,
        vec![("7", "concrete", None), ("8_at_50C", "steel", Some(323.15))]
    );
    let s = load(&scene);
    // The GDB in centimetres: (100, 0, 0) cm → 1 m, rotated 90° about z → (0, 1, 0),
    // moved by (10, 20, 0) m.
    assert!(near(
        placed(&s, 0, [100.0 * 0.01, 0.0, 0.0]),
        [10.0, 21.0, 0.0]
    ));
    // The matrix row by row: translation −5 m in x.
    assert!(near(placed(&s, 1, [0.0, 0.0, 0.0]), [-5.0, 0.0, 0.0]));
    // Nested: inner rotation 90° about z, then the outer lift of 3 m.
    assert!(near(placed(&s, 2, [1.0, 0.0, 0.0]), [0.0, 1.0, 3.0]));
    // The gdb mesh is 3 triangles: a quad and a triangle.
    assert_eq!(s.geometry.meshes[s.objects[0].mesh].indices.len(), 3);
}

/// Bundles: `<localmaterials>`, `search_paths="local"`, `<assign>`; `DataDriven` →
/// fixed-temperature parts with the emissivity of `SimpleReflectance` (1 − ρ); a `Null`
/// entry is a warning while unused and an error naming the file and line when used.
#[test]
fn bundles_data_driven_and_null_materials() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    put(
        dir,
        "materials/scene.mat",
        &(therm_entry("7", "concrete") + NULL_ENTRY),
    );
    put(dir, "geometry/tri.obj", &tri_obj("7"));
    put(
        dir,
        "geometry/bundles/jet/jet.mat",
        "MATERIAL_ENTRY {\n    ID = Hot_mat\n    NAME = Hot_mat\n    DOUBLE_SIDED = TRUE\n    TEMP_SOLVER_NAME = DataDriven\n    TEMP_SOLVER {\n        TEMPERATURE = 1500\n    }\n    SURFACE_PROPERTIES {\n        REFLECTANCE_PROP_NAME = SimpleReflectance\n        REFLECTANCE_PROP {\n            TXT_FILENAME = ref.txt\n        }\n    }\n}\n",
    );
    put(
        dir,
        "geometry/bundles/jet/ref.txt",
        "0.4 0.30\r\n14.0 0.30\r\n",
    );
    put(dir, "geometry/bundles/jet/jet.obj", &tri_obj("Body"));
    put(
        dir,
        "geometry/bundles/jet/jet.glist",
        r#"<geometrylist>
  <object search_paths="local">
    <localmaterials>jet.mat</localmaterials>
    <basegeometry><obj><filename>jet.obj</filename><assign id="Hot_mat">Body</assign></obj></basegeometry>
    <staticinstance/>
  </object>
</geometrylist>"#,
    );
    put(
        dir,
        "geometry/l.glist",
        r#"<geometrylist>
  <object><basegeometry><obj><filename>tri.obj</filename></obj></basegeometry><staticinstance/></object>
  <object><basegeometry><glist><filename>bundles/jet/jet.glist</filename></glist></basegeometry>
    <staticinstance><translation><point><x>0</x><y>0</y><z>50</z></point></translation></staticinstance>
  </object>
  <object><basesource><pointsource matid="lamp"/></basesource><staticinstance/></object>
</geometrylist>"#,
    );
    let scene = put(dir, "t.scene", &scene_xml("l.glist"));
    let im = import(&scene, &dir.join("t.json"), &ImportOptions::default()).unwrap();
    assert!(
        im.warnings
            .iter()
            .any(|w| w.contains("scene.mat:line 18") && w.contains("`Null`")),
        "{:#?}",
        im.warnings
    );
    assert!(
        im.warnings
            .iter()
            .any(|w| w.contains("l.glist:line 6") && w.contains("point sources"))
    );
    let s = load(&scene);
    let jet = s.objects.iter().position(|o| o.name == "jet").unwrap();
    let part = s.parts.iter().find(|p| p.object == jet).unwrap();
    assert_eq!(part.name, "Body");
    assert_eq!(part.fixed_temperature_k, Some(1500.0));
    let m = &s.materials.materials()[part.material];
    assert!((m.emissivity_at(10.0, 0.0) - 0.7).abs() < 1e-12);
    assert!(m.double_sided);

    // Used, the Null entry is an error naming where it is defined and who uses it.
    put(dir, "geometry/tri.obj", &tri_obj("100"));
    let e = import(&scene, &dir.join("t.json"), &ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("scene.mat:line 15") && e.contains("`usemtl 100`"),
        "{e}"
    );
}

/// A 48-hour `.wth` of hourly rows (format of `irsig::weather`'s `.wth` reader).
fn wth() -> String {
    let mut s = String::from("49 1.000000\n");
    for h in 0..49 {
        let t = 15.0 + 8.0 * ((h as f64 - 8.0) / 24.0 * std::f64::consts::TAU).sin();
        s += &format!(
            "{:.2}{:6.2}{:8.2}{:6.2}{:6.2}{:7.2}{:9.2}{:9.2}{:5.2}{:3}{:3}{:7.2}{:6.2}\n",
            h as f64, t, 1000.0, 0.6, 5.0, 2.0, 0.0, 0.0, 1.0, 0, 0, 0.0, 0.0
        );
    }
    s
}

/// A DIRSIG5 `.jsim` with a platform, motion, tasks, weather and atmosphere plugin; and a
/// DIRSIG4 `.sim` with a `.atm` (sky temperature) — times, sensors and weather.
#[test]
fn simulations_give_time_sensor_weather_and_atmosphere() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    put(
        dir,
        "scene/materials/scene.mat",
        &therm_entry("7", "concrete"),
    );
    put(
        dir,
        "scene/geometry/plane.obj",
        "v -50 -50 0\nv 50 -50 0\nv 50 50 0\nv -50 50 0\nusemtl 7\nf 1 2 3 4\n",
    );
    put(
        dir,
        "scene/geometry/l.glist",
        "<geometrylist><object><basegeometry><obj><filename>plane.obj</filename></obj></basegeometry><staticinstance/></object></geometrylist>",
    );
    put(dir, "scene/t.scene", &scene_xml("l.glist"));
    put(dir, "weather/w.wth", &wth());
    put(
        dir,
        "tasks/t.tasks",
        r#"<tasklist><reference><datetime type="absolute">2025-06-21T10:00:00.0000-04:00</datetime></reference>
<task><start><datetime type="relative">3600</datetime></start><stop><datetime type="relative">3600</datetime></stop></task></tasklist>"#,
    );
    put(
        dir,
        "motion/m.ppd",
        r#"<platformmotion type="generic"><method type="raw"/>
<data rotationframe="sceneenu" rotationorder="xyz" angletype="absolute" angularunits="degrees" spatialunits="meters">
<entry><datetime type="relative">0</datetime>
<position><location type="scene"><point><x>0</x><y>0</y><z>1000</z></point></location></position>
<orientation><eulerangles><cartesiantriple><x>0</x><y>0</y><z>0</z></cartesiantriple></eulerangles></orientation></entry>
</data></platformmotion>"#,
    );
    put(
        dir,
        "platforms/p.platform",
        r#"<platform><attachment><mount name="m" type="static"><data angularunits="radians" rotationorder="xyz"><xrotation>0</xrotation><yrotation>0</yrotation><zrotation>0</zrotation></data>
<attachment><instrument name="cam" type="generic"><properties><focallength>50</focallength><aperturediameter>0.03</aperturediameter></properties>
<focalplane enabled="true" name="LWIR cam"><capturemethod><spectralresponse><bandpass spectralunits="microns"><minimum>7</minimum><maximum>13</maximum><delta>0.1</delta></bandpass>
<channellist><channel name="lw" shape="rectangle"><center>10</center><width>4</width></channel></channellist></spectralresponse></capturemethod>
<detectorarray spatialunits="microns"><xelementcount>64</xelementcount><yelementcount>48</yelementcount><xelementspacing>17</xelementspacing><yelementspacing>17</yelementspacing></detectorarray>
</focalplane></instrument></attachment></mount></attachment></platform>"#,
    );
    let jsim = put(
        dir,
        "jsims/s.jsim",
        r#"[{"scene_list": [{"inputs": "D:/elsewhere/scene/t.scene"}],
  "plugin_list": [
    {"name": "BasicPlatform", "inputs": {"platform_filename": "platforms/p.platform",
      "motion_filename": "motion/m.ppd", "tasks_filename": "tasks/t.tasks"}},
    {"name": "NewAtmosphere", "inputs": {"backend": {"name": "modtran_tape",
      "tape5_parameters": {"atmospheric_model": "MidLatitudeSummer"}}}},
    {"name": "ThermWeather", "inputs": {"filename": "weather/w.wth"}},
    {"name": "Clouds", "inputs": {}}
  ]}]"#,
    );
    let im = import(&jsim, &dir.join("out.json"), &ImportOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let s = &im.scene;
    assert_eq!(s.time, "2025-06-21T11:00:00-04:00");
    assert_eq!(s.site.utc_offset_hours, -4.0);
    // A 48-hour .wth starts at midnight the day before (it covers the image time).
    assert_eq!(
        s.weather.as_ref().unwrap().start.as_deref(),
        Some("2025-06-20T00:00:00-04:00")
    );
    // At midnight the image is at the start of the file's second day (DIRSIG's current
    // day), not at its last row: the file still starts the day before.
    let midnight = import(
        &jsim,
        &dir.join("out0.json"),
        &ImportOptions {
            time: Some("2025-06-21T00:00:00-04:00".into()),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(
        midnight.scene.weather.as_ref().unwrap().start.as_deref(),
        Some("2025-06-20T00:00:00-04:00")
    );
    assert_eq!(s.atmosphere, Some(serde_json::json!("mid-latitude-summer")));
    assert!(
        im.warnings
            .iter()
            .any(|w| w.contains("s.jsim:line 8") && w.contains("`Clouds`")),
        "{:#?}",
        im.warnings
    );
    assert!(
        im.warnings
            .iter()
            .any(|w| w.contains("not on this machine"))
    );
    let cam = &s.sensors[0];
    assert_eq!(cam["name"], "LWIR_cam");
    assert_eq!(cam["width"], 64);
    assert_eq!(cam["height"], 48);
    assert!((cam["pixel_pitch_m"].as_f64().unwrap() - 17e-6).abs() < 1e-15);
    assert!((cam["focal_length_m"].as_f64().unwrap() - 0.05).abs() < 1e-15);
    assert_eq!(cam["position"], serde_json::json!([0.0, 0.0, 1000.0]));
    assert_eq!(cam["look_at"], serde_json::json!([0.0, 0.0, 0.0]));
    assert_eq!(cam["bands"][0]["response"], serde_json::json!([8.0, 12.0]));
    // Loads and renders as it stands.
    let out = dir.join("out.json");
    im.write(&out).unwrap();
    let mut session =
        irsig::render::session::Session::open(&out, irsig::trace::Backend::Embree).unwrap();
    let files = session
        .run(
            &dir.join("img"),
            &irsig::render::session::RunOptions::default(),
        )
        .unwrap();
    assert!(!files.is_empty());

    // DIRSIG4 .sim with a .atm: no atmosphere, the apparent sky temperature.
    put(
        dir,
        "a.atm",
        "<atmosphericconditions><uniformweather><classicdata><filename>weather/w.wth</filename></classicdata></uniformweather>\n<simpleradiativetransfer><apparentskytemperature>250</apparentskytemperature></simpleradiativetransfer></atmosphericconditions>",
    );
    let sim = put(
        dir,
        "x.sim",
        r#"<simulation><scene externalfile="scene/t.scene"/><atmosphericconditions externalfile="a.atm"/>
<tasklist externalfile="tasks/t.tasks"/></simulation>"#,
    );
    let im = import(&sim, &dir.join("out2.json"), &ImportOptions::default()).unwrap();
    assert_eq!(im.scene.atmosphere, Some(serde_json::json!("none")));
    assert_eq!(
        im.scene.render.as_ref().unwrap()["sky_temperature_k"],
        serde_json::json!(250.0)
    );
    assert!(im.scene.weather.is_some());
    // A .atm is never taken for weather.
    let e = irsig::weather::load(&dir.join("a.atm"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("DIRSIG atmosphere file"), "{e}");
}

/// WGS84 semi-major axis (m) and first eccentricity squared (NIMA TR8350.2).
const WGS84_A: f64 = 6_378_137.0;
const WGS84_E2: f64 = 6.694_379_990_14e-3;

/// Where a geodetic point `dlat_deg` due north of the origin and `dh` m above it lies in
/// the origin's east-north-up frame, by the meridian's radius of curvature at the mean
/// latitude (second order in the arc: the chord and the drop below the origin's
/// horizon). Independent of the importer's ECEF path.
fn north_up(lat0_deg: f64, h0: f64, dlat_deg: f64, dh: f64) -> (f64, f64) {
    let phi = (lat0_deg + dlat_deg / 2.0).to_radians();
    let m = WGS84_A * (1.0 - WGS84_E2) / (1.0 - WGS84_E2 * phi.sin().powi(2)).powf(1.5);
    let d = dlat_deg.to_radians();
    let r = m + h0 + dh;
    (r * d.sin(), r * d.cos() - (m + h0))
}

/// Geographic placements (DIRSIG coordinates manual, dirsig.cis.rit.edu/docs/new/
/// coordinates.html; the construct is the GeoLocation1 demo's glist,
/// dirsig.cis.rit.edu/demos/zips/GeoLocation1.zip): a `<staticinstance>` translated to a
/// `<location type="geodetic">` lands at the scene ENU point of that latitude, longitude
/// and altitude (rotation still applied about z first); a `<box>` primitive (the same
/// demo's ground, `<matid>` with lower and upper extents) is a closed box facing
/// outward; a `.ppd` entry at a geodetic `<location>` puts the camera there. The
/// material is the DIRSIG manual's NEF example (materials: nefmaterial-howto.html), a
/// Therm block with no THICKNESS and no SOLAR_ABSORPTION.
#[test]
fn geographic_locations_and_box_primitive() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    // The manual's NEF example as printed (no THICKNESS: left out, unused) as ID 8001,
    // and with a thickness as ID 8000 (its VISIBLE_EMISSIVITY is the solar absorptance).
    let nef = "MATERIAL_ENTRY {\n    NAME = asphalt\n    ID = 8001\n    SURFACE_PROPERTIES {\n        REFLECTANCE_PROP_NAME = NEFBeardMaxwell\n        REFLECTANCE_PROP {\n            NEF_MAT_FILE = /home/NEFDS/0693UUUASP.nmf\n        }\n    }\n    RAD_SOLVER_NAME = Generic\n    RAD_SOLVER {\n        INITIAL_SAMPLE_COUNT = 25\n    }\n    TEMP_SOLVER_NAME = Therm\n    TEMP_SOLVER {\n        SPECIFIC_HEAT = 0.4650\n        THERMAL_CONDUCTIVITY = 20.9300\n        MASS_DENSITY = 1.0000\n        SPECULARITY = 0.10\n        VISIBLE_EMISSIVITY = 0.95\n        THERMAL_EMISSIVITY = 0.65\n        EXPOSED_AREA = 0.40\n    }\n}\n";
    let thick = nef
        .replace("ID = 8001", "ID = 8000")
        .replace("NAME = asphalt", "NAME = thick asphalt")
        .replace(
            "EXPOSED_AREA = 0.40\n",
            "EXPOSED_AREA = 0.40\n        THICKNESS = 5\n",
        );
    put(
        dir,
        "materials/scene.mat",
        &(therm_entry("5", "paint")
            + &thick
            + nef
            // A material-map proxy: no NAME, no solver, a LUT of bare `DC:ID` lines.
            + "MATERIAL_ENTRY {\n    ID = proxy\n    MATERIAL_MAP {\n        IMAGE_FILENAME = m.png\n        LUT {\n            0:5\n            255:8000\n        }\n    }\n}\n"),
    );
    put(dir, "geometry/tri.obj", &tri_obj("5"));
    put(
        dir,
        "geometry/geo.glist",
        r#"<geometrylist enabled="true">
  <object>
    <basegeometry>
      <box>
        <matid>8000</matid>
        <lowerextent><point><x>-1000</x><y>-1000</y><z>-1</z></point></lowerextent>
        <upperextent><point><x> 1000</x><y> 1000</y><z> 0</z></point></upperextent>
      </box>
    </basegeometry>
    <staticinstance>
      <translation><point><x>0</x><y>0</y><z>0</z></point></translation>
    </staticinstance>
  </object>
  <object>
    <basegeometry><obj><filename>tri.obj</filename></obj></basegeometry>
    <staticinstance>
      <translation>
        <location type="geodetic">
          <latitude>43.18</latitude><longitude>-77.61</longitude><altitude>210</altitude>
        </location>
      </translation>
      <rotation><cartesiantriple><x>0</x><y>0</y><z>45</z></cartesiantriple></rotation>
    </staticinstance>
  </object>
</geometrylist>
"#,
    );
    let scene = put(dir, "t.scene", &scene_xml("geo.glist"));
    let s = load(&scene);
    // The scene origin is 43.16 N, 160 m (scene_xml): 0.02° north and 50 m up.
    let (n, u) = north_up(43.16, 160.0, 0.02, 50.0);
    let p = placed(&s, 1, [0.0, 0.0, 0.0]);
    assert!(p.x.abs() < 0.01, "{p}");
    assert!((f64::from(p.y) - n).abs() < 0.02, "{p} vs north {n}");
    assert!((f64::from(p.z) - u).abs() < 0.02, "{p} vs up {u}");
    // Rotated 45° about z before the move.
    let q = placed(&s, 1, [1.0, 0.0, 0.0]) - p;
    let h = std::f32::consts::FRAC_1_SQRT_2;
    assert!((q - Vec3::new(h, h, 0.0)).length() < 1e-3, "{q}");
    // The box: 12 triangles enclosing 2000 × 2000 × 1 m³ with outward normals (a
    // positive signed volume), its material the ID 8000 entry.
    let b = &s.objects[0];
    let m = &s.geometry.meshes[b.mesh];
    assert_eq!(m.indices.len(), 12);
    let vol: f64 = m
        .indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    assert!((vol - 4.0e6).abs() < 1.0, "{vol}");
    let (lo, hi) = m.positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    assert_eq!(
        (lo, hi),
        (
            Vec3::new(-1000.0, -1000.0, -1.0),
            Vec3::new(1000.0, 1000.0, 0.0)
        )
    );
    let im = import(&scene, &dir.join("o.json"), &ImportOptions::default()).unwrap();
    assert_eq!(im.scene.objects[0].parts[0].material, "thick asphalt");
    let asphalt = im
        .materials
        .materials
        .iter()
        .find(|m| m.name == "thick asphalt")
        .unwrap();
    // 20.93 cal/(cm·h·°C) × 4.1868/36 = 2.434 W/(m·K); 0.465 cal/(g·°C) × 4186.8;
    // 5 cm.
    assert!((asphalt.conductivity_w_m_k.unwrap() - 20.93 * 4.1868 / 36.0).abs() < 1e-9);
    assert!((asphalt.specific_heat_j_kg_k.unwrap() - 0.465 * 4186.8).abs() < 1e-9);
    assert!((asphalt.thickness_m.unwrap() - 0.05).abs() < 1e-12);
    assert!((asphalt.solar_absorptivity - 0.95).abs() < 1e-12);
    assert!((asphalt.thermal_emissivity - 0.65).abs() < 1e-12);
    assert!(
        im.warnings.iter().any(|w| w.contains("scene.mat:line 54")
            && w.contains("ID 8001")
            && w.contains("THICKNESS")),
        "{:#?}",
        im.warnings
    );
    assert!(
        im.warnings
            .iter()
            .any(|w| w.contains("ID proxy has no NAME")),
        "{:#?}",
        im.warnings
    );
    // Used, the entry without a thickness is an error naming it.
    put(
        dir,
        "geometry/b2.glist",
        "<geometrylist><object><basegeometry><box><matid>8001</matid><lowerextent>0 0 0</lowerextent><upperextent>1 1 1</upperextent></box></basegeometry><staticinstance/></object></geometrylist>",
    );
    let s2 = put(dir, "t2.scene", &scene_xml("b2.glist"));
    let e = import(&s2, &dir.join("o3.json"), &ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("ID 8001") && e.contains("THICKNESS"), "{e}");

    // A platform at a geodetic location, 1 km above the triangle's point.
    put(
        dir,
        "m.ppd",
        r#"<platformmotion type="generic"><method type="raw"/>
<data rotationframe="sceneenu" rotationorder="xyz" angularunits="degrees" spatialunits="meters">
<entry><datetime type="relative">0</datetime>
<position><location type="geodetic"><latitude>43.18</latitude><longitude>-77.61</longitude><altitude>1210</altitude></location></position>
<orientation><eulerangles><cartesiantriple><x>0</x><y>0</y><z>0</z></cartesiantriple></eulerangles></orientation></entry>
</data></platformmotion>"#,
    );
    put(
        dir,
        "p.platform",
        r#"<platform><attachment><mount name="m" type="static"><attachment><instrument name="cam" type="generic"><properties><focallength>50</focallength></properties>
<focalplane enabled="true" name="cam"><capturemethod><spectralresponse><bandpass spectralunits="microns"><minimum>8</minimum><maximum>12</maximum><delta>0.1</delta></bandpass></spectralresponse></capturemethod>
<detectorarray spatialunits="microns"><xelementcount>8</xelementcount><yelementcount>8</yelementcount><xelementspacing>17</xelementspacing><yelementspacing>17</yelementspacing></detectorarray>
</focalplane></instrument></attachment></mount></attachment></platform>"#,
    );
    let sim = put(
        dir,
        "x.sim",
        r#"<simulation><scene externalfile="t.scene"/><platform externalfile="p.platform"/><platformmotion externalfile="m.ppd"/></simulation>"#,
    );
    let im = import(&sim, &dir.join("o2.json"), &ImportOptions::default()).unwrap();
    let pos: Vec<f64> = im.scene.sensors[0]["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let (n, u) = north_up(43.16, 160.0, 0.02, 1050.0);
    assert!(pos[0].abs() < 0.01, "{pos:?}");
    assert!(
        (pos[1] - n).abs() < 0.02 && (pos[2] - u).abs() < 0.02,
        "{pos:?} vs {n}, {u}"
    );

    // A flight line: entries at 0 s and 100 s from the task reference; the task starts at
    // 25 s, so the platform is a quarter of the way along (DIRSIG interpolates between
    // entries); the orientation is the nearest entry's (the first: looking down).
    put(
        dir,
        "line.ppd",
        r#"<platformmotion type="generic"><method type="raw"/>
<data rotationframe="sceneenu" rotationorder="xyz" angularunits="degrees" spatialunits="meters">
<entry><datetime type="relative">100</datetime>
<position><location type="scene"><point><x>1000</x><y>0</y><z>800</z></point></location></position>
<orientation><eulerangles><cartesiantriple><x>0</x><y>0</y><z>90</z></cartesiantriple></eulerangles></orientation></entry>
<entry><datetime type="relative">0</datetime>
<position><location type="scene"><point><x>0</x><y>0</y><z>800</z></point></location></position>
<orientation><eulerangles><cartesiantriple><x>0</x><y>0</y><z>0</z></cartesiantriple></eulerangles></orientation></entry>
</data></platformmotion>"#,
    );
    put(
        dir,
        "t.tasks",
        r#"<tasklist><reference><datetime type="absolute">2025-06-21T10:00:00-04:00</datetime></reference>
<task><start><datetime type="relative">25</datetime></start><stop><datetime type="relative">25</datetime></stop></task></tasklist>"#,
    );
    let sim = put(
        dir,
        "line.sim",
        r#"<simulation><scene externalfile="t.scene"/><platform externalfile="p.platform"/><platformmotion externalfile="line.ppd"/><tasklist externalfile="t.tasks"/></simulation>"#,
    );
    let im = import(&sim, &dir.join("o4.json"), &ImportOptions::default()).unwrap();
    assert_eq!(im.scene.time, "2025-06-21T10:00:25-04:00");
    let cam = &im.scene.sensors[0];
    assert_eq!(cam["position"], serde_json::json!([250.0, 0.0, 800.0]));
    assert_eq!(cam["up"], serde_json::json!([0.0, 1.0, 0.0]));
    // A flexible `.motion` (BasicPlatform takes one too) is not imported: the sensor is
    // dropped with a warning, the scene still imports.
    put(
        dir,
        "f.motion",
        r#"<motion type="flexible"><locationengine type="straight"><start frame="scene"><x>0</x><y>0</y><z>500</z></start></locationengine><orientationengine type="velocity"/></motion>"#,
    );
    let sim = put(
        dir,
        "flex.sim",
        r#"<simulation><scene externalfile="t.scene"/><platform externalfile="p.platform"/><platformmotion externalfile="f.motion"/><tasklist externalfile="t.tasks"/></simulation>"#,
    );
    let im = import(&sim, &dir.join("o5.json"), &ImportOptions::default()).unwrap();
    assert!(im.scene.sensors.is_empty());
    assert!(
        im.warnings
            .iter()
            .any(|w| w.contains("f.motion:line 1") && w.contains("flexible motion")),
        "{:#?}",
        im.warnings
    );
}

/// A scene's `<geometrylistinclude>` may name an `.odb` or a `.gdb` as well as a `.glist`
/// (RIT's Tacoma scene includes `terrain.odb`, `tacoma.odb` and `targets.glist`, as listed
/// in github.com/KevinKearney/protoDIRSIG notebooks/dirfm_tutorials/
/// tutorial_tacoma_scene.ipynb); an `.odb` without its extension is known by its
/// `DIRSIG_ODB` line; `$SCENE_DIR` is expanded in any file name.
#[test]
fn geometry_list_includes_odb_and_gdb() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    put(dir, "materials/scene.mat", &therm_entry("7", "concrete"));
    put(
        dir,
        "geometry/pad.gdb",
        "OBJECT\nPAD\n1-0-0\nPART\nTOP\n1-1-0\n\
         FACE\nF1\n1-1-1\nconcrete\n7\nf1\n-1.0\n0.0\n0.0\n0.0\nnull\nnull\nnull\n4\n\
         0 0 0\n2 0 0\n2 2 0\n0 2 0\n0 0 1\n0.0\n0.0\n0.0\nEND\n",
    );
    put(dir, "geometry/tri.obj", &tri_obj("7"));
    put(
        dir,
        "geometry/terrain",
        "DIRSIG_ODB = 1.0\nOBJECT {\n    OBJ_FILENAME = tri.obj\n    UNITS = METERS\n    INSTANCES {\n        INFO = 5, 0, 0, 1, 1, 1, 0, 0, 0\n    }\n}\n",
    );
    let scene = put(
        dir,
        "t.scene",
        &scene_xml(
            "terrain</geometrylistinclude>\n    <geometrylistinclude>$SCENE_DIR/geometry/pad.gdb",
        ),
    );
    let s = load(&scene);
    assert_eq!(s.objects.len(), 2);
    // The ODB's instance moves the triangle 5 m east; the GDB stays where it is.
    assert!(near(placed(&s, 0, [0.0, 0.0, 0.0]), [5.0, 0.0, 0.0]));
    assert!(near(placed(&s, 1, [2.0, 2.0, 0.0]), [2.0, 2.0, 0.0]));
}

/// Surface properties of real libraries beyond `ClassicEmissivity`: a `ShellTarget`
/// property names its emissivity `EMISSIVITY_FILE` (RIT's Tacoma `tacoma.mat`, as
/// protoDIRSIG's src/protodirsig/scene_coverage.py reads it, with a `BRDF_FIT_FILE`), in
/// the emissivity or the reflectance block; the curve is read from it.
#[test]
fn shell_target_emissivity_file_is_read() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    put(
        dir,
        "emissivity/panel.ems",
        &format!(
            "1\n{}CURVE_BEGIN\n7.0 0.80\n14.0 0.80\n",
            "1.0\n".repeat(91)
        ),
    );
    let shell = |id: &str, block: &str| {
        format!(
            "MATERIAL_ENTRY {{\n    ID = {id}\n    NAME = panel {id}\n    SURFACE_PROPERTIES {{\n        {block}_PROP_NAME = ShellTarget\n        {block}_PROP {{\n            BRDF_FIT_FILE = matte.fit\n            EMISSIVITY_FILE = emissivity/panel.ems\n        }}\n    }}\n    TEMP_SOLVER_NAME = Therm\n    TEMP_SOLVER {{\n        SPECIFIC_HEAT = 0.22\n        MASS_DENSITY = 2.3\n        THERMAL_CONDUCTIVITY = 8\n        SOLAR_ABSORPTION = 0.7\n        THERMAL_EMISSIVITY = 0.9\n        EXPOSED_AREA = 0\n        THICKNESS = 10\n    }}\n}}\n"
        )
    };
    let mat = put(
        dir,
        "shell.mat",
        &(shell("1", "EMISSIVITY") + &shell("2", "REFLECTANCE")),
    );
    let f = irsig::material::dirsig::read_mat(&mat, &[]).unwrap();
    assert_eq!(f.entries.len(), 2);
    for e in &f.entries {
        let c = e
            .emissivity
            .as_ref()
            .unwrap_or_else(|| panic!("{} has no curve", e.name));
        assert!((c.band_mean(8.0, 12.0) - 0.80).abs() < 1e-12, "{}", e.name);
        assert!(e.warnings.is_empty(), "{:?}", e.warnings);
    }
}

/// Corrupt input: errors name the file and line.
#[test]
fn bad_dirsig_input_names_file_and_line() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    put(dir, "materials/scene.mat", &therm_entry("7", "concrete"));
    put(dir, "geometry/tri.obj", &tri_obj("7"));
    let scene = put(dir, "t.scene", &scene_xml("l.glist"));
    let err = |glist: &str| {
        put(dir, "geometry/l.glist", glist);
        import(&scene, &dir.join("t.json"), &ImportOptions::default())
            .unwrap_err()
            .to_string()
    };
    let e = err("<geometrylist>\n<object>\n</geometrylist>");
    assert!(e.contains("l.glist:line 3") && e.contains("XML"), "{e}");
    let e = err(
        "<geometrylist>\n<object><basegeometry><obj><filename>tri.obj</filename></obj></basegeometry>\n<staticinstance><matrix>1 0 0</matrix></staticinstance></object></geometrylist>",
    );
    assert!(e.contains("l.glist:line 3") && e.contains("16"), "{e}");
    let e = err(
        "<geometrylist>\n<object><basegeometry><obj><filename>missing.obj</filename></obj></basegeometry><staticinstance/></object></geometrylist>",
    );
    assert!(
        e.contains("l.glist:line 2") && e.contains("missing.obj") && e.contains("not found"),
        "{e}"
    );
    let e = err(
        "<geometrylist>\n<object><basegeometry><obj><filename>tri.obj</filename></obj></basegeometry>\n<staticinstance><translation><point><x>ten</x></point></translation></staticinstance></object></geometrylist>",
    );
    assert!(e.contains("l.glist:line 3") && e.contains("`ten`"), "{e}");
    put(
        dir,
        "geometry/bad.odb",
        "DIRSIG_ODB = 1.0\nOBJECT {\n  OBJ_FILENAME = tri.obj\n  INSTANCES {\n    INFO = 1, 2, 3\n  }\n}\n",
    );
    let e = err(
        "<geometrylist><object><basegeometry><odb><filename>bad.odb</filename></odb></basegeometry><staticinstance/></object></geometrylist>",
    );
    assert!(
        e.contains("bad.odb:line 5") && e.contains("9 numbers"),
        "{e}"
    );
    put(
        dir,
        "geometry/bad.gdb",
        "OBJECT\nA\n1-0-0\nPART\nP\n1-1-0\nFACE\nF\n1-1-1\nm\n7\n-1\n0\n0\n0\nnull\nnull\nnull\n5\n",
    );
    let e = err(
        "<geometrylist><object><basegeometry><gdb><filename>bad.gdb</filename></gdb></basegeometry><staticinstance/></object></geometrylist>",
    );
    assert!(e.contains("bad.gdb:line 19") && e.contains("3 or 4"), "{e}");
    // A scene without an origin.
    let e = import(
        &put(
            dir,
            "n.scene",
            "<classicscene>\n<geometrylist/>\n</classicscene>",
        ),
        &dir.join("t.json"),
        &ImportOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("n.scene:line 1") && e.contains("sceneorigin"),
        "{e}"
    );
}

// ------------------------------------------------------------------ real files

/// Substitute geometry for the two OBJ files the real Tahoe set names but does not hold
/// (`geometry/objects/small.obj`, `geometry/bundles/hypersonic/hypersonic.obj`; see
/// `protoDIRSIG/PROVENANCE.md`): a 2 km terrain in patches of the scene's material IDs
/// and a 2 m box of `Gidder_mat`. Also `jun2392.wth`, which `simple.atm` names from the
/// DIRSIG installation, as a copy of the set's `saw.wth`.
fn substitutes(dir: &Path) {
    let ids = [11, 14, 15, 16, 19, 1, 13, 17, 18, 12];
    let mut t = String::new();
    for j in 0..5 {
        for i in 0..5 {
            t += &format!("v {} {} 0\n", -1000 + 500 * i, -1000 + 500 * j);
        }
    }
    for k in 0..16 {
        let (i, j) = (k % 4, k / 4);
        let a = j * 5 + i + 1;
        t += &format!(
            "usemtl {}\nf {} {} {} {}\n",
            ids[k % 10],
            a,
            a + 1,
            a + 6,
            a + 5
        );
    }
    put(dir, "geometry/objects/small.obj", &t);
    let b = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv -1 -1 2\nv 1 -1 2\nv 1 1 2\nv -1 1 2\n\
             usemtl Gidder_mat\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    put(dir, "geometry/bundles/hypersonic/hypersonic.obj", b);
    let saw = std::fs::read_to_string(shared_data("dirsig").join("saw.wth")).unwrap();
    put(dir, "weather/jun2392.wth", &saw);
}

/// The complete real set (the AUROR `.jsim` naming the Tahoe scene, its platform,
/// motion, tasks and weather by `C:/` paths) imports with the set and the substitutes
/// as search folders, and renders.
#[test]
#[ignore = "needs ../shared/data"]
fn real_auror_simulation_imports_and_renders() {
    let set = shared_data("dirsig/protoDIRSIG");
    let d = tempfile::tempdir().unwrap();
    substitutes(d.path());
    let opts = ImportOptions {
        search_dirs: vec![d.path().to_path_buf(), set.clone()],
        time: None,
    };
    let out = d.path().join("out/tahoe.json");
    let jsim = set.join("AUROR_ref/jsims/AurorSimulation.jsim");
    let im = import(&jsim, &out, &opts).unwrap_or_else(|e| panic!("{e}"));
    let s = &im.scene;
    assert_eq!(s.time, "2009-07-27T11:29:32-08:00");
    assert_eq!((s.site.latitude_deg, s.site.longitude_deg), (39.0, -120.0));
    assert_eq!(s.objects.len(), 2);
    // The vehicle at the start of its straight-line motion.
    let jet = s.objects.iter().find(|o| o.name == "hypersonic").unwrap();
    assert_eq!(
        jet.instances.as_ref().unwrap()[0].translate,
        Some([-400.0, 400.0, 50000.0])
    );
    assert_eq!(jet.parts[0].fixed_temperature_k, Some(1500.0));
    // Every tahoe.mat entry and the bundle's: 10 + 1, with every emissivity file found.
    assert_eq!(im.materials.materials.len(), 11);
    assert!(
        im.materials
            .materials
            .iter()
            .all(|m| m.emissivity_curve.is_some())
    );
    // The camera: 500 × 500, 10 µm, 306 mm, 550 km up, looking down, image up = south
    // (the .ppd's 180° about z).
    let cam = &s.sensors[0];
    assert_eq!(
        (cam["width"].as_u64(), cam["height"].as_u64()),
        (Some(500), Some(500))
    );
    assert!((cam["focal_length_m"].as_f64().unwrap() - 0.306).abs() < 1e-12);
    assert_eq!(
        cam["position"],
        serde_json::json!([-400.0, 400.0, 550000.0])
    );
    let up = cam["up"].as_array().unwrap();
    assert!((up[1].as_f64().unwrap() + 1.0).abs() < 1e-9);
    for needle in [
        "NewAtmosphere",
        "dynamic instance",
        "gaussian",
        "truthcollection",
    ] {
        assert!(
            im.warnings.iter().any(|w| w.contains(needle)),
            "{needle}: {:#?}",
            im.warnings
        );
    }
    // Renders (a smaller image of the same camera, to keep the test fast).
    let mut im = im;
    im.scene.sensors[0]["width"] = 64.into();
    im.scene.sensors[0]["height"] = 64.into();
    im.scene.sensors[0]["pixel_pitch_m"] = (10e-6 * 500.0 / 64.0).into();
    im.write(&out).unwrap();
    // Its 0.82–0.88 µm NIR channel lies below the built-in atmosphere's 3–16 µm: refused,
    // naming the sensor, not rendered as a near-black image.
    let e = match irsig::render::session::Session::open(&out, irsig::trace::Backend::Embree) {
        Ok(_) => panic!("a NIR band under the built-in atmosphere is refused"),
        Err(e) => e.to_string(),
    };
    assert!(
        e.contains("sensors[0]") && e.contains("outside the built-in atmosphere"),
        "{e}"
    );
    // A thermal band renders.
    im.scene.sensors[0]["bands"] = serde_json::json!([{"name": "lwir", "response": [8.0, 12.0]}]);
    im.write(&out).unwrap();
    let mut session =
        irsig::render::session::Session::open(&out, irsig::trace::Backend::Embree).unwrap();
    let files = session
        .run(
            &d.path().join("img"),
            &irsig::render::session::RunOptions::default(),
        )
        .unwrap();
    assert_eq!(files, vec!["CIS120".to_string()]);
    assert!(d.path().join("img/CIS120.exr").is_file());
    // `scene check`/`render` take the simulation directly.
    let direct = Scene::check_dirsig(&jsim, &opts).unwrap_or_else(|e| panic!("{e:#?}"));
    assert_eq!(direct.objects.len(), 2);
    assert_eq!(direct.path, jsim);
}

/// Every real DIRSIG file in the shared set is read: `.mat` (every entry), `.ems`, the
/// scene-level XML (`.scene`, `.glist`, `.platform`, `.ppd`, `.tasks`, `.atm`, `.jsim`)
/// through imports that use them. Skipped, with the reason: `vehicle.int` and
/// `ref_reflective.txt`/`ref.txt` are read through the materials that name them; the
/// `.wth` files by `tests/weather.rs`.
#[test]
#[ignore = "needs ../shared/data"]
fn every_real_dirsig_file_is_read() {
    let root = shared_data("dirsig");
    let mut files = Vec::new();
    let mut stack = vec![root.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                files.push(p);
            }
        }
    }
    let ext = |p: &Path| {
        p.extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_string()
    };
    for p in files.iter().filter(|p| ext(p) == "mat") {
        let m = irsig::material::dirsig::read_mat(p, &[]).unwrap_or_else(|e| panic!("{e}"));
        assert!(!m.entries.is_empty(), "{}", p.display());
    }
    for p in files.iter().filter(|p| ext(p) == "ems") {
        irsig::material::dirsig::read_ems(p).unwrap_or_else(|e| panic!("{e}"));
    }
    // The Tahoe .mat by hand (entry ID 11, Water): 1 cal/(g·°C) = 4186.8 J/(kg·K),
    // 1 g/cm³ = 1000 kg/m³, 5.13 cal/(cm·h·°C) × 4.1868/36 = 0.596619 W/(m·K), 1 cm.
    let tahoe = irsig::material::dirsig::read_mat(&root.join("tahoe.mat"), &[]).unwrap();
    let water = tahoe.entries.iter().find(|e| e.id == "11").unwrap();
    let w = water.material.as_ref().unwrap();
    assert_eq!(w.name, "Water");
    assert!((w.specific_heat_j_kg_k - 4186.8).abs() < 1e-9);
    assert!((w.density_kg_m3 - 1000.0).abs() < 1e-9);
    assert!((w.conductivity_w_m_k - 5.13 * 4.1868 / 36.0).abs() < 1e-12);
    assert!((w.conductivity_w_m_k - 0.596_619).abs() < 1e-6);
    assert!((w.thickness_m - 0.01).abs() < 1e-15);
    assert_eq!(
        (w.solar_absorptivity, w.thermal_emissivity, w.exposed_area),
        (0.45, 0.98, 0.5)
    );
    // Terrain (proxy), ID 1: steel's values, 464.4 → 54.0 W/(m·K), 0.089 → 372.6 J/(kg·K),
    // 7.833 g/cm³ → 7833 kg/m³, exposed area −0.5 kept as read.
    let t = tahoe
        .entries
        .iter()
        .find(|e| e.id == "1")
        .unwrap()
        .material
        .clone()
        .unwrap();
    assert!((t.conductivity_w_m_k - 54.0097).abs() < 1e-4);
    assert!((t.specific_heat_j_kg_k - 372.6252).abs() < 1e-9);
    assert!((t.density_kg_m3 - 7833.0).abs() < 1e-9);
    assert_eq!(t.exposed_area, -0.5);
    // The DataDriven bundle material and the label IDs.
    let pd = root.join("protoDIRSIG");
    let hyp = irsig::material::dirsig::read_mat(
        &pd.join("manifold_config_repo/scenes/tahoe/geometry/bundles/hypersonic/hypersonic.mat"),
        &[],
    )
    .unwrap();
    assert_eq!(hyp.entries[0].id, "Gidder_mat");
    assert_eq!(
        hyp.entries[0].solver,
        irsig::material::dirsig::TempSolver::DataDriven {
            temperature_k: 1500.0
        }
    );
    // ref.txt: reflectance 0 → emissivity 1.
    assert_eq!(
        hyp.entries[0].emissivity.as_ref().unwrap().at(1.0, 0.0),
        1.0
    );

    // The sidebar glists (assign, point source) and simple.atm, through a hand-made
    // scene and simulation that include them.
    let d = tempfile::tempdir().unwrap();
    substitutes(d.path());
    let side = pd.join("notebooks/sidebars/vehicle_point_source");
    let dir = d.path();
    put(dir, "materials/scene.mat", &therm_entry("7", "concrete"));
    put(
        dir,
        "geometry/l.glist",
        &format!(
            "<geometrylist>\n<geometrylistinclude>{}</geometrylistinclude>\n<geometrylistinclude>{}</geometrylistinclude>\n</geometrylist>",
            side.join("hypersonic_reflective/hypersonic_reflective.glist")
                .display(),
            side.join("vehicle_pointsource/vehicle_pointsource.glist")
                .display(),
        ),
    );
    // The reflective bundle's OBJ (not in the set) is the substitute model.
    put(dir, "t.scene", &scene_xml("l.glist"));
    let sim = put(
        dir,
        "t.sim",
        &format!(
            "<simulation><scene externalfile=\"t.scene\"/><atmosphericconditions externalfile=\"{}\"/><tasklist externalfile=\"{}\"/></simulation>",
            root.join("rendered-ai/packages/dirsig_pkg/dirsig_pkg/simple.atm")
                .display(),
            pd.join("AUROR_ref/tasks/AurorTask.tasks").display()
        ),
    );
    let opts = ImportOptions {
        search_dirs: vec![dir.to_path_buf()],
        time: None,
    };
    let im = import(&sim, &dir.join("o.json"), &opts).unwrap_or_else(|e| panic!("{e}"));
    let jet = &im.scene.objects[0];
    assert_eq!(jet.parts[0].name, "Gidder_mat");
    assert_eq!(jet.parts[0].material, "Gidder_mat_reflective");
    assert_eq!(jet.parts[0].fixed_temperature_k, Some(1500.0));
    // ref_reflective.txt: reflectance 0.30 → emissivity 0.70.
    let m = im
        .materials
        .materials
        .iter()
        .find(|m| m.name == "Gidder_mat_reflective")
        .unwrap();
    assert!((m.thermal_emissivity - 0.7).abs() < 1e-12);
    assert!(im.warnings.iter().any(|w| w.contains("point sources")));
    let sky = im
        .scene
        .render
        .as_ref()
        .and_then(|r| r.get("sky_temperature_k"));
    assert_eq!(sky.and_then(|v| v.as_f64()), Some(250.0));
    assert_eq!(im.scene.atmosphere, Some(serde_json::json!("none")));
    assert_eq!(im.scene.time, "2009-07-27T11:29:32-08:00");
}
