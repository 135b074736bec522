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
    if target == "gltf" {
        out.extend(gltf_seeds());
    }
    out
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
