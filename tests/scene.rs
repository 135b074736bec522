//! Tests: scene files, OBJ loading, primitives, the bundled town.

use std::path::Path;

use irsig::scene::load_obj;

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const TWO_GROUPS: &str = "# two groups, the MTL file is absent
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
usemtl painted_steel
f 5 6 7
f 5/1 6/1 8/1
usemtl glass
f -4 -2 -1
";

#[test]
fn obj_groups_materials_triangulation() {
    let d = tempfile::tempdir().unwrap();
    let p = write(d.path(), "g.obj", TWO_GROUPS);
    let groups = load_obj(&p).unwrap();
    let summary: Vec<(&str, Option<&str>, usize)> = groups
        .iter()
        .map(|g| {
            (
                g.name.as_str(),
                g.material_name.as_deref(),
                g.mesh.triangle_count(),
            )
        })
        .collect();
    assert_eq!(
        summary,
        vec![
            ("ground", Some("asphalt"), 2),
            ("shed", Some("painted_steel"), 2),
            ("shed", Some("glass"), 1),
        ]
    );
    // The quad's two triangles cover its 100 m², normals +z.
    let g = &groups[0].mesh;
    let mut area = 0.0;
    for t in 0..g.triangle_count() {
        let (n, a) = irsig::geometry::triangle_normal_area(&g.triangle(t));
        assert!((n.z - 1.0).abs() < 1e-6);
        area += a;
    }
    assert!((area - 100.0).abs() < 1e-4);
    // Negative (relative) indices: -4 -2 -1 = vertices 5, 7, 8.
    let t = groups[2].mesh.triangle(0);
    assert_eq!(t[0], glam::Vec3::ZERO);
    assert_eq!(t[1], glam::Vec3::Y);
    assert_eq!(t[2], glam::Vec3::Z);
}

#[test]
fn obj_errors_name_line() {
    let d = tempfile::tempdir().unwrap();
    let p = write(d.path(), "v.obj", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n");
    let e = load_obj(&p).unwrap_err().to_string();
    assert!(
        e.contains("v.obj:line 2") && e.contains("3 finite numbers"),
        "{e}"
    );
    let p = write(d.path(), "f.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    let e = load_obj(&p).unwrap_err().to_string();
    assert!(e.contains("f.obj:line 4") && e.contains("index 4"), "{e}");
    let p = write(d.path(), "empty.obj", "v 0 0 0\n");
    let e = load_obj(&p).unwrap_err().to_string();
    assert!(e.contains("no faces"), "{e}");
    let e = load_obj(&d.path().join("absent.obj"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("absent.obj"), "{e}");
}

use glam::Vec3;
use irsig::geometry::{TriangleMesh, triangle_normal_area};
use irsig::render::sections::schema_json;
use irsig::scene::{Scene, primitives, town};

use crate::util::{glb, gltf_doc, gltf_embedded, irsig_bin, repo_path};

/// Signed volume enclosed by a triangle mesh (divergence theorem): positive
/// when every face is counter-clockwise seen from outside.
fn signed_volume(positions: &[Vec3], indices: &[[u32; 3]]) -> f64 {
    indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

#[test]
fn primitives_are_closed_and_outward() {
    let b = primitives::box_mesh(Vec3::new(2.0, 3.0, 4.0), Some(0.7), true);
    let v = signed_volume(&b.positions, &b.indices);
    assert!((v - 24.0).abs() < 1e-4, "{v}");
    let n = 24;
    let c = primitives::cylinder_mesh(1.5, 2.0, n, true);
    let exact = 0.5 * n as f64 * 1.5f64.powi(2) * (std::f64::consts::TAU / n as f64).sin() * 2.0;
    assert!((signed_volume(&c.positions, &c.indices) - exact).abs() < 1e-4);
    let k = primitives::cone_mesh(1.0, 3.0, n, true);
    assert!((signed_volume(&k.positions, &k.indices) - exact / 1.5f64.powi(2) / 2.0).abs() < 1e-4);
    // A fine UV sphere approaches 4/3 π r³ from below.
    let s = primitives::sphere_mesh(2.0, 64, 32);
    let vs = signed_volume(&s.positions, &s.indices);
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 8.0;
    assert!(vs < exact && vs > 0.99 * exact, "{vs} vs {exact}");
    // Gable roof + the box below it close a house: volume = box + prism.
    let mut h = primitives::box_mesh(Vec3::new(8.0, 10.0, 3.0), None, true);
    let mut r = primitives::gable_roof_mesh(8.0, 10.0, 2.0, 0.0);
    r.positions.iter_mut().for_each(|p| p.z += 3.0);
    h.append(&r);
    // The box's top is inside; remove it to close the shape.
    let top = h.group("top");
    let keep: Vec<[u32; 3]> = h
        .indices
        .iter()
        .zip(&h.group_of)
        .filter(|(_, g)| **g != top)
        .map(|(t, _)| *t)
        .collect();
    let v = signed_volume(&h.positions, &keep);
    assert!((v - (240.0 + 0.5 * 8.0 * 2.0 * 10.0)).abs() < 1e-3, "{v}");
}

fn area(m: &TriangleMesh) -> f64 {
    (0..m.triangle_count())
        .map(|t| triangle_normal_area(&m.triangle(t)).1 as f64)
        .sum()
}

const SMALL: &str = r#"{
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

/// A scene in `dir/scenes_x/` whose material library is the repo's.
fn small_scene(dir: &Path, text: &str) -> std::path::PathBuf {
    let sd = dir.join("s");
    std::fs::create_dir_all(sd.join("geo")).unwrap();
    std::fs::copy(
        repo_path("scenes/materials.json"),
        dir.join("materials.json"),
    )
    .unwrap();
    write(&sd.join("geo"), "two.obj", TWO_GROUPS);
    write(&sd, "scene.json", text)
}

/// Issue 20: a Y-up OBJ (a 1 × 2 × 1 ft post, tall along y, as modelling tools export)
/// stands upright with `up_axis: "y"`, in metres with `unit: "ft"`; the front-facing
/// winding survives (the volume stays positive). `up_axis`/`unit` on a non-OBJ shape and
/// unknown values are errors naming the field.
#[test]
fn obj_up_axis_and_unit_per_shape() {
    // A closed box 1 × 2 × 1 (x, y, z), faces counter-clockwise from outside.
    const POST: &str = "v 0 0 0\nv 1 0 0\nv 1 2 0\nv 0 2 0\nv 0 0 1\nv 1 0 1\nv 1 2 1\nv 0 2 1\n\
f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    let d = tempfile::tempdir().unwrap();
    let scene = |shape: &str| {
        SMALL.replace(
            r#"{"name": "thing", "shapes": [{"obj": "geo/two.obj"}],"#,
            &format!(
                r#"{{"name": "thing", "shapes": [{{"part": "glass", {}],"#,
                &shape[1..]
            ),
        )
    };
    let p = small_scene(d.path(), SMALL);
    write(&d.path().join("s/geo"), "post.obj", POST);
    let extent = |shape: &str| {
        write(&d.path().join("s"), "scene.json", &scene(shape));
        let s = Scene::load(&p).unwrap();
        let m = &s.geometry.meshes[s.objects[2].mesh];
        let (lo, hi) = m.positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        (lo, hi, signed_volume(&m.positions, &m.indices))
    };
    let (lo, hi, v) = extent(r#"{"obj": "geo/post.obj"}"#);
    assert_eq!((lo, hi), (Vec3::ZERO, Vec3::new(1.0, 2.0, 1.0)));
    assert!((v - 2.0).abs() < 1e-5, "{v}");
    // Y up: the post's 2 ft length is now height (z), its depth runs to −y.
    let (lo, hi, v) = extent(r#"{"obj": "geo/post.obj", "up_axis": "y", "unit": "ft"}"#);
    let ft = 0.3048f32;
    assert!(
        (lo - Vec3::new(0.0, -ft, 0.0)).abs().max_element() < 1e-6,
        "{lo}"
    );
    assert!(
        (hi - Vec3::new(ft, 0.0, 2.0 * ft)).abs().max_element() < 1e-6,
        "{hi}"
    );
    assert!((v - 2.0 * 0.3048f64.powi(3)).abs() < 1e-6, "{v}");
    // Every unit, Z up stated.
    for (unit, m) in [("m", 1.0), ("cm", 0.01), ("mm", 0.001), ("in", 0.0254)] {
        let (_, hi, _) = extent(&format!(
            r#"{{"obj": "geo/post.obj", "up_axis": "z", "unit": "{unit}"}}"#
        ));
        assert!((hi.y - 2.0 * m as f32).abs() < 1e-7, "{unit}: {hi}");
    }
    // Errors.
    write(
        &d.path().join("s"),
        "scene.json",
        &scene(r#"{"box": {"size": [1, 1, 1]}, "up_axis": "y"}"#),
    );
    let e = Scene::load(&p).unwrap_err().to_string();
    assert!(e.contains("shapes[0].up_axis") && e.contains("obj"), "{e}");
    write(
        &d.path().join("s"),
        "scene.json",
        &scene(r#"{"obj": "geo/post.obj", "unit": "yd"}"#),
    );
    let e = Scene::load(&p).unwrap_err().to_string();
    assert!(e.contains("scene.json") && e.contains("yd"), "{e}");
}

/// Issue 20: DIRSIG's OBJ convention `usemtl <ID>` maps a face group to the `.mat` entry
/// with that ID when no material has the group's name.
#[test]
fn obj_usemtl_dirsig_id_maps_to_mat_entry() {
    let d = tempfile::tempdir().unwrap();
    let p = small_scene(d.path(), SMALL);
    let sd = d.path().join("s");
    write(
        &sd,
        "lib.mat",
        "MATERIAL_ENTRY {\n  ID = 19\n  NAME = Steel plate\n  TEMP_SOLVER_NAME = Therm\n  TEMP_SOLVER {\n    SPECIFIC_HEAT = 0.1\n    MASS_DENSITY = 7.8\n    THERMAL_CONDUCTIVITY = 430\n    SOLAR_ABSORPTION = 0.5\n    THERMAL_EMISSIVITY = 0.8\n    EXPOSED_AREA = 1\n    THICKNESS = 0.5\n  }\n}\n",
    );
    write(
        &sd.join("geo"),
        "ids.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl 19\nf 1 2 3\n",
    );
    let scene = SMALL
        .replace(
            r#""materials": ["../materials.json"],"#,
            r#""materials": ["../materials.json", "lib.mat"],"#,
        )
        .replace(
            r#"{"name": "thing", "shapes": [{"obj": "geo/two.obj"}],
     "parts": [{"name": "glass", "material": "glass", "fixed_temperature_k": 300}],
     "material": "concrete"}"#,
            r#"{"name": "thing", "shapes": [{"obj": "geo/ids.obj"}]}"#,
        );
    assert!(scene.contains("ids.obj") && scene.contains("lib.mat"));
    write(&sd, "scene.json", &scene);
    let s = Scene::load(&p).unwrap();
    let parts = s.facet_parts();
    let last = *parts.last().unwrap() as usize;
    assert_eq!(s.part_material(last).name, "Steel plate");
    // An ID nothing has stays an error naming the group.
    write(
        &sd.join("geo"),
        "ids.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl 77\nf 1 2 3\n",
    );
    let e = Scene::load(&p).unwrap_err().to_string();
    assert!(e.contains("`77`"), "{e}");
}

/// `heights_csv` gives the same terrain as inline `heights`: comments,
/// blank lines, whitespace or comma separators, quoted cells; a bad cell
/// names the file and line.
#[test]
fn heightmap_heights_csv_matches_inline_heights() {
    let d = tempfile::tempdir().unwrap();
    let p = small_scene(d.path(), SMALL);
    let inline = Scene::load(&p).unwrap();
    write(
        &d.path().join("s"),
        "h.csv",
        "# north row first\r\n0, 1, \"2\"  # peak at NE\r\n\r\n0 0\t0\r\n",
    );
    let csv_scene = SMALL.replace(
        r#""heights": [[0, 1, 2], [0, 0, 0]],"#,
        r#""heights_csv": "h.csv","#,
    );
    assert_ne!(csv_scene, SMALL);
    write(&d.path().join("s"), "scene.json", &csv_scene);
    let from_csv = Scene::load(&p).unwrap();
    assert_eq!(
        from_csv.geometry.meshes[0].positions,
        inline.geometry.meshes[0].positions
    );
    write(&d.path().join("s"), "h.csv", "0,1,2\n# c\n0,x,0\n");
    let e = Scene::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("h.csv:line 3") && e.contains("heights_csv"),
        "{e}"
    );
}

#[test]
fn small_scene_instancing_parts_and_bounds() {
    let d = tempfile::tempdir().unwrap();
    let p = small_scene(d.path(), SMALL);
    let s = Scene::load(&p).unwrap();
    assert_eq!(s.objects.len(), 3);
    assert_eq!(s.geometry.meshes.len(), 3);
    assert_eq!(s.geometry.instances.len(), 4);
    // Heightmap 2×1 cells = 4; box without bottom = 10; OBJ = 5.
    assert_eq!(s.geometry.stored_triangle_count(), 4 + 10 + 5);
    assert_eq!(s.geometry.facet_count(), 4 + 2 * 10 + 5);
    assert_eq!(s.facet_parts().len(), s.geometry.facet_count());
    // Box areas: 2·3 + 2·(2·4) + 2·(3·4) = 46 m²; the second instance is
    // scaled by 2 (area × 4).
    let sh = &s.objects[1];
    assert_eq!(sh.instances, 1..3);
    assert!((area(&s.geometry.meshes[sh.mesh]) - 46.0).abs() < 1e-4);
    let w = s.geometry.flatten();
    let off = &s.facet_offsets;
    let world_area: f64 = (off[2]..off[3])
        .map(|f| triangle_normal_area(&w.triangle(f)).1 as f64)
        .sum();
    assert!((world_area - 4.0 * 46.0).abs() < 1e-3);
    // Bounds: the shed scaled ×2 (4 × 6 × 8 m) and turned 90° spans
    // x ∈ [−3, 3], y ∈ [98, 102], z ≤ 8.
    let (lo, hi) = s.geometry.bounds().unwrap();
    assert!(
        (hi.y - 102.0).abs() < 1e-4 && (hi.z - 8.0).abs() < 1e-4,
        "{hi}"
    );
    assert!(
        (lo.x + 10.0).abs() < 1e-4 && (hi.x - 101.0).abs() < 1e-4,
        "{lo} {hi}"
    );
    // Heightmap: first row is the north edge; the NE vertex is at z = 2.
    let g = &s.geometry.meshes[0];
    let ne = g
        .positions
        .iter()
        .find(|p| p.x == 10.0 && p.y == 5.0)
        .unwrap();
    assert_eq!(ne.z, 2.0);
    // West cell is asphalt (implicit part from the material name), east
    // cell the `lawn` part with its grass material and shape factor.
    let mat = |f: usize| {
        s.materials.materials()[s.facet_part(f).material]
            .name
            .clone()
    };
    for f in 0..4 {
        let c = irsig::geometry::triangle_normal_area(&w.triangle(f));
        let cx: f32 = w.triangle(f).iter().map(|p| p.x).sum::<f32>() / 3.0;
        assert!(c.1 > 0.0);
        if cx < 0.0 {
            assert_eq!(mat(f), "asphalt");
        } else {
            assert_eq!(mat(f), "grass");
            assert_eq!(s.facet_part(f).shape_factor, Some(0.9));
            assert_eq!(s.facet_part(f).name, "lawn");
        }
    }
    // Shed: the `top` part overrides thickness and power; walls use the
    // object's material as is.
    let tops: Vec<usize> = (off[1]..off[3])
        .filter(|&f| s.facet_part(f).name == "top")
        .collect();
    assert_eq!(tops.len(), 4);
    for &f in &tops {
        let n = triangle_normal_area(&w.triangle(f)).0;
        assert!(n.z > 0.999);
        let pi = s.part_index(
            s.facet_offsets.partition_point(|&o| o <= f) - 1,
            (f - off[1]) % 10,
        );
        let m = s.part_material(pi);
        assert_eq!((m.thickness_m, m.self_power_w_m2), (0.01, 50.0));
    }
    let wall = (off[1]..off[2])
        .find(|&f| s.facet_part(f).name == "sides")
        .unwrap();
    let wm = s.part_material(
        s.parts
            .iter()
            .position(|p| p == s.facet_part(wall))
            .unwrap(),
    );
    assert_eq!(wm, s.materials.get("painted_steel").unwrap().clone());
    // OBJ groups by usemtl: asphalt (implicit from the object's material
    // `concrete`), painted_steel, glass (explicit part).
    let obj_parts: Vec<(String, String)> = (off[3]..off[4])
        .map(|f| (s.facet_part(f).name.clone(), mat(f)))
        .collect();
    assert_eq!(obj_parts[0], ("asphalt".into(), "concrete".into()));
    assert_eq!(obj_parts[2], ("painted_steel".into(), "concrete".into()));
    assert_eq!(obj_parts[4], ("glass".into(), "glass".into()));
    assert_eq!(s.facet_part(off[3] + 4).fixed_temperature_k, Some(300.0));
    assert_eq!(s.instance_object, vec![0, 1, 1, 2]);
    assert_eq!(s.sensors.len(), 1);
    assert_eq!(s.sensors[0]["type"], "frame");
}

/// Every problem is reported, each with file, line and JSON path.
#[test]
fn scene_errors_collected_with_lines() {
    let bad = r#"{
  "site": {"latitude_deg": 95, "longitude_deg": -77.61, "utc_offset_hours": -4},
  "time": "2025-06-21 14:00",
  "weather": {"file": "nowhere.csv"},
  "materials": ["../materials.json"],
  "objects": [
    {"name": "a",
     "shapes": [{"box": {"size": [1, 1, 1]}, "plane": {"size": [1, 1]}}]},
    {"name": "b",
     "shapes": [{"obj": "geo/missing.obj"}]},
    {"name": "c",
     "shapes": [{"box": {"size": [1, 1, 1]}}],
     "parts": [{"name": "top", "material": "asphalt_roof"},
               {"name": "sides", "material": "brick",
                "thickness_m": -0.2},
               {"name": "roof", "material": "brick"}],
     "material": "brick"}
  ]
}"#;
    let d = tempfile::tempdir().unwrap();
    let p = small_scene(d.path(), bad);
    let errs: Vec<String> = Scene::check(&p)
        .unwrap_err()
        .iter()
        .map(|e| e.to_string())
        .collect();
    let has = |line: usize, field: &str, what: &str| {
        assert!(
            errs.iter()
                .any(|e| e.contains(&format!("scene.json:line {line}: column "))
                    && e.contains(&format!(": field `{field}`"))
                    && e.contains(what)),
            "no error at line {line} `{field}` about {what}: {errs:#?}"
        )
    };
    has(2, "site.latitude_deg", "−90..=90");
    has(3, "time", "RFC 3339");
    has(4, "weather.file", "not found");
    has(8, "objects[0].shapes[0]", "exactly one");
    has(10, "objects[1].shapes[0].obj", "missing.obj");
    has(
        13,
        "objects[2].parts[0].material",
        "unknown material `asphalt_roof`",
    );
    assert!(
        errs.iter()
            .any(|e| e.contains("similar: asphalt_shingle_roof")),
        "{errs:#?}"
    );
    has(15, "objects[2].parts[1].thickness_m", "> 0 m");
    has(16, "objects[2].parts[2].name", "matches no face group");
    assert_eq!(errs.len(), 8, "{errs:#?}");
    // `load` reports them all in one error.
    let one = Scene::load(&p).unwrap_err().to_string();
    assert!(one.contains("8 problems"), "{one}");

    // Syntax and unknown keys: serde's line.
    let p = small_scene(d.path(), &SMALL.replace("\"cells\"", "\"celss\""));
    let e = Scene::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("scene.json:line 7") && e.contains("celss"),
        "{e}"
    );
    let p = small_scene(d.path(), &SMALL.replace("\"ag\"", "\"ax\""));
    let e = Scene::load(&p).unwrap_err().to_string();
    assert!(e.contains("line 9") && e.contains("`x`"), "{e}");
}

#[test]
fn town_loads_with_expected_content() {
    let p = repo_path("scenes/town/scene.json");
    let s = Scene::load(&p).unwrap();
    let sum = s.summary();
    assert_eq!(sum.time, "2025-06-21T14:00:00-04:00");
    assert_eq!((s.site.latitude_deg, s.site.longitude_deg), (43.16, -77.61));
    // 300 × 300 terrain cells, 2 triangles each.
    let terrain = &s.objects[0];
    assert_eq!(s.geometry.meshes[terrain.mesh].triangle_count(), 180_000);
    assert!(
        (200_000..=400_000).contains(&sum.triangles_placed),
        "{} placed",
        sum.triangles_placed
    );
    assert!(sum.triangles_placed > sum.triangles_stored);
    // Trees and cars are instanced: one mesh, many placements.
    for name in [
        "deciduous_tree",
        "coniferous_tree",
        "car_parked",
        "car_running",
        "house_clapboard",
    ] {
        let o = s.objects.iter().find(|o| o.name == name).unwrap();
        assert!(o.instances.len() >= 5, "{name}: {}", o.instances.len());
    }
    // Every material of the library is used by a part or as a layer of a
    // used construction, but `crop` (the town has no farmland),
    // `tar_gravel_roof` (the plant roof is `flat_roof_insulated`, whose
    // outer face has its optics) and the glazing (the town has no
    // windows); and running engines exist.
    let mut used: std::collections::BTreeSet<&str> =
        sum.materials_used.iter().map(|(n, _)| n.as_str()).collect();
    for (n, _) in &sum.materials_used {
        for l in &s.materials.get(n).unwrap().layers {
            used.insert(l.material.as_deref().unwrap());
        }
    }
    let unused: Vec<&str> = s
        .materials
        .materials()
        .iter()
        .map(|m| m.name.as_str())
        .filter(|n| !used.contains(n))
        .collect();
    assert_eq!(
        unused,
        ["tar_gravel_roof", "crop", "float_glass", "double_glazing"]
    );
    // Streets are layered, and walls have the interior behind them.
    assert!(used.contains("asphalt_road") && used.contains("brick_cavity_wall"));
    assert!(
        s.parts
            .iter()
            .any(|p| matches!(p.back, Some(irsig::material::BackSpec::Interior(_))))
    );
    assert!(
        s.parts
            .iter()
            .any(|p| p.self_power_w_m2.is_some_and(|q| q > 0.0)
                && s.objects[p.object].name == "car_running")
    );
    let av = s
        .objects
        .iter()
        .position(|o| o.name == "armoured_vehicle")
        .unwrap();
    assert!(
        s.parts
            .iter()
            .any(|p| p.object == av && p.thickness_m == Some(0.025))
    );
    // Bounds: the 600 m square, heights of a few metres, the stack on top.
    assert!(sum.bounds_min[0] >= -302.0 && sum.bounds_max[0] <= 302.0);
    assert!(sum.bounds_min[2] > -5.0 && sum.bounds_max[2] < 60.0 && sum.bounds_max[2] > 40.0);
    // Sensors: a frame camera and a line scanner.
    let types: Vec<&str> = s
        .sensors
        .iter()
        .map(|v| v["type"].as_str().unwrap())
        .collect();
    assert_eq!(types, vec!["frame", "line_scanner"]);
    assert_eq!(s.sensors[0]["width"], 640);
    assert_eq!(s.sensors[1]["altitude_m"], 600.0);
    // The sensor stage accepts both as written.
    for (i, v) in s.sensors.iter().enumerate() {
        let cfg: irsig::sensor::SensorConfig = serde_json::from_value(v.clone()).unwrap();
        let loc = irsig::Location::file(&p).with_field(format!("sensors[{i}]"));
        irsig::sensor::Sensor::from_config(&cfg, &loc).unwrap();
    }
}

#[test]
fn town_file_matches_generator_and_schema_is_current() {
    let file: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(repo_path("scenes/town/scene.json")).unwrap(),
    )
    .unwrap();
    assert!(
        file == town::town_scene(),
        "scenes/town/scene.json is stale: run `irsig scene town --out scenes/town/scene.json`"
    );
    let schema = std::fs::read_to_string(repo_path("scenes/scene.schema.json")).unwrap();
    assert_eq!(
        schema,
        schema_json(),
        "scenes/scene.schema.json is stale: run `irsig scene schema --out scenes/scene.schema.json`"
    );
    let v: serde_json::Value = serde_json::from_str(&schema).unwrap();
    for key in [
        "site",
        "time",
        "objects",
        "materials",
        "sensors",
        "atmosphere",
        "render",
    ] {
        assert!(v["properties"].get(key).is_some(), "schema lacks {key}");
    }
}

/// The schema describes every section: an editor using it accepts the
/// bundled town and the documented section forms, and flags a misspelt key
/// in `sensors`, `render` or `atmosphere` (draft 2020-12, checked with the
/// `boon` validator).
#[test]
fn schema_describes_sensors_render_and_atmosphere() {
    let schema: serde_json::Value = serde_json::from_str(&schema_json()).unwrap();
    let mut compiler = boon::Compiler::new();
    compiler.add_resource("urn:irsig-scene", schema).unwrap();
    let mut schemas = boon::Schemas::new();
    let id = compiler.compile("urn:irsig-scene", &mut schemas).unwrap();
    let town = town::town_scene();
    assert!(
        schemas.validate(&town, id).is_ok(),
        "the town must validate"
    );
    let with = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut v = town.clone();
        edit(&mut v);
        schemas.validate(&v, id).is_ok()
    };
    // Valid forms.
    assert!(with(&|v| v["atmosphere"] = "tropical".into()));
    assert!(with(
        &|v| v["atmosphere"] =
            serde_json::json!({"model": "standard", "profile": "sub-arctic-winter"})
    ));
    assert!(with(
        &|v| v["atmosphere"] = serde_json::json!({"model": "tape7", "index": "t7/index.json"})
    ));
    assert!(with(
        &|v| v["render"] = serde_json::json!({"max_bounces": 1, "sky_sampling": "dirsig"})
    ));
    // Misspelt keys and names.
    assert!(!with(&|v| {
        let s = v["sensors"][0].as_object_mut().unwrap();
        let f = s.remove("focal_length_m").unwrap();
        s.insert("focal_lenght_m".into(), f);
    }));
    assert!(!with(&|v| v["sensors"][0]["type"] = "fram".into()));
    assert!(!with(
        &|v| v["render"] = serde_json::json!({"max_bounce": 1})
    ));
    assert!(!with(
        &|v| v["render"] = serde_json::json!({"sky_sampling": "stratified"})
    ));
    assert!(!with(&|v| v["atmosphere"] = "midlatitude_sumer".into()));
    assert!(!with(
        &|v| v["atmosphere"] = serde_json::json!({"model": "standard", "profile": "arctic"})
    ));
}

#[test]
fn cli_scene_check() {
    let d = tempfile::tempdir().unwrap();
    let p = small_scene(d.path(), SMALL);
    let out = std::process::Command::new(irsig_bin())
        .args(["scene", "check", "--load-only", "--json"])
        .arg(&p)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["triangles_placed"], 29);
    assert_eq!(v["instances"], 4);
    let p = small_scene(
        d.path(),
        &SMALL
            .replace("43.16", "95")
            .replace("\"grass\"", "\"gras\""),
    );
    let out = std::process::Command::new(irsig_bin())
        .args(["scene", "check"])
        .arg(&p)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("latitude_deg")
            && err.contains("unknown material `gras`")
            && err.contains("2 problem"),
        "{err}"
    );
}

#[test]
fn scene_weather_is_loaded_and_must_cover_the_image_time() {
    let d = tempfile::tempdir().unwrap();
    let town_weather = repo_path("scenes/town/weather.csv");
    let p = small_scene(d.path(), SMALL);
    std::fs::copy(&town_weather, p.parent().unwrap().join("w.csv")).unwrap();
    let with = SMALL.replace(
        "\"materials\": [",
        "\"weather\": {\"file\": \"w.csv\"},\n  \"materials\": [",
    );
    let p = small_scene(d.path(), &with);
    let s = Scene::load(&p).unwrap();
    let w = s.weather.as_ref().unwrap();
    assert!(w.history.start() <= s.time && s.time <= w.history.end());
    assert!(w.history.records().len() > 2);

    let late = with.replace("2025-06-21T14:00:00-04:00", "2025-07-01T14:00:00-04:00");
    let p = small_scene(d.path(), &late);
    let e = Scene::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("line 4: column 15: field `weather.file`") && e.contains("not the image time"),
        "{e}"
    );
}

/// A DIRSIG .wth carries no date: the scene gives its start.
#[test]
#[ignore = "needs ../shared/data"]
fn scene_dirsig_wth_weather_starts_at_the_scene_start() {
    let dir = crate::util::shared_data("dirsig");
    let d = tempfile::tempdir().unwrap();
    let p = small_scene(d.path(), SMALL);
    std::fs::copy(dir.join("saw.wth"), p.parent().unwrap().join("saw.wth")).unwrap();
    let wth = SMALL.replace(
        "\"materials\": [",
        "\"weather\": {\"file\": \"saw.wth\", \"start\": \"2025-06-20T00:00:00-04:00\"},\n  \"materials\": [",
    );
    let p = small_scene(d.path(), &wth);
    let s = Scene::load(&p).unwrap();
    let h = &s.weather.as_ref().unwrap().history;
    assert_eq!(h.end() - h.start(), chrono::TimeDelta::hours(48));
}

// ---------------------------------------------------------------- glTF

/// Issue 3/8: glTF import — node transforms (translation, scale, a
/// mirroring scale), Y-up to Z-up, strips, grouping by material name; the
/// Issue 20: a Draco- or meshopt-compressed glTF names the extension it requires
/// (it used to fail validation with "Missing data (and 3 more problems)").
#[test]
fn gltf_unsupported_required_extensions_are_named() {
    use irsig::scene::load_gltf;
    let d = tempfile::tempdir().unwrap();
    let (doc, bin) = gltf_doc();
    let mut draco = doc.clone();
    draco["extensionsUsed"] = serde_json::json!([
        "KHR_draco_mesh_compression",
        "KHR_materials_emissive_strength"
    ]);
    draco["extensionsRequired"] = serde_json::json!(["KHR_draco_mesh_compression"]);
    // As a Draco exporter writes it: the accessors lose their buffer views.
    draco["accessors"][0]
        .as_object_mut()
        .unwrap()
        .remove("bufferView");
    draco["meshes"][0]["primitives"][0]["extensions"] = serde_json::json!({
        "KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}
    });
    let f = write(d.path(), "draco.gltf", &gltf_embedded(draco, &bin));
    let e = load_gltf(&f).unwrap_err().to_string();
    assert!(
        e.contains("draco.gltf")
            && e.contains("extensionsRequired")
            && e.contains("`KHR_draco_mesh_compression` (Draco-compressed geometry)")
            && e.contains("KHR_materials_emissive_strength")
            && !e.contains("Missing data"),
        "{e}"
    );
    let mut meshopt = doc.clone();
    meshopt["extensionsUsed"] = serde_json::json!(["EXT_meshopt_compression"]);
    meshopt["extensionsRequired"] = serde_json::json!(["EXT_meshopt_compression"]);
    let f = d.path().join("meshopt.glb");
    std::fs::write(&f, glb(&meshopt, &bin)).unwrap();
    let e = load_gltf(&f).unwrap_err().to_string();
    assert!(
        e.contains("meshopt.glb") && e.contains("`EXT_meshopt_compression` (meshoptimizer"),
        "{e}"
    );
    // Extensions used but not required leave the file readable.
    let mut used = doc.clone();
    used["extensionsUsed"] = serde_json::json!(["KHR_materials_emissive_strength"]);
    let f = write(d.path(), "used.gltf", &gltf_embedded(used, &bin));
    assert!(load_gltf(&f).is_ok());
}

/// `.gltf` (data URI), `.glb` and external-buffer forms give the same
/// triangles.
#[test]
fn gltf_meshes_nodes_axes_and_groups() {
    use irsig::scene::load_gltf;
    let d = tempfile::tempdir().unwrap();
    let (doc, bin) = gltf_doc();
    let embedded = write(d.path(), "m.gltf", &gltf_embedded(doc.clone(), &bin));
    let binary = d.path().join("m.glb");
    std::fs::write(&binary, glb(&doc, &bin)).unwrap();
    let mut ext = doc.clone();
    ext["buffers"][0]["uri"] = serde_json::json!("m.bin");
    std::fs::write(d.path().join("m.bin"), &bin).unwrap();
    let external = write(d.path(), "ext.gltf", &ext.to_string());
    let groups = load_gltf(&embedded).unwrap();
    for other in [&binary, &external] {
        let g = load_gltf(other).unwrap();
        assert_eq!(g.len(), groups.len());
        for (a, b) in g.iter().zip(&groups) {
            assert_eq!(a.mesh.positions, b.mesh.positions);
            assert_eq!(a.mesh.indices, b.mesh.indices);
        }
    }
    let names: Vec<(&str, Option<&str>)> = groups
        .iter()
        .map(|g| (g.name.as_str(), g.material_name.as_deref()))
        .collect();
    assert_eq!(
        names,
        [("crate", Some("painted_steel")), ("panel", Some("glass"))]
    );
    let crate_ = &groups[0].mesh;
    assert_eq!(crate_.indices.len(), 24, "two cubes of 12 triangles");
    // Both cubes closed and outward: volume 2³ + 1 (the mirrored one keeps
    // its faces outward).
    let v = signed_volume(&crate_.positions, &crate_.indices);
    assert!((v - 9.0).abs() < 1e-4, "{v}");
    // Placement, Y-up → Z-up (x, y, z) → (x, −z, y): the scaled cube spans
    // x 10..12, y −2..0, z 0..2; the mirrored one x −1..0, y 5..4 → 4..5.
    let bounds = |pts: &[Vec3]| {
        pts.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        })
    };
    let (lo, hi) = bounds(&crate_.positions[..8]);
    assert!(lo.abs_diff_eq(Vec3::new(10.0, -2.0, 0.0), 1e-6), "{lo}");
    assert!(hi.abs_diff_eq(Vec3::new(12.0, 0.0, 2.0), 1e-6), "{hi}");
    let (lo, hi) = bounds(&crate_.positions[8..]);
    assert!(lo.abs_diff_eq(Vec3::new(-1.0, 4.0, 0.0), 1e-6), "{lo}");
    assert!(hi.abs_diff_eq(Vec3::new(0.0, 5.0, 1.0), 1e-6), "{hi}");
    // The strip: two triangles, both facing up (+Z) at height 3.
    let panel = &groups[1].mesh;
    assert_eq!(panel.indices.len(), 2);
    for t in 0..2 {
        let (n, a) = triangle_normal_area(&panel.triangle(t));
        assert!(
            n.abs_diff_eq(Vec3::Z, 1e-6) && (a - 0.5).abs() < 1e-6,
            "{n} {a}"
        );
    }
    assert!(panel.positions.iter().all(|p| p.z == 3.0));
}

/// A scene object made of a glTF file: its material names map to parts and
/// the database; errors name the file and the glTF field.
#[test]
fn gltf_in_a_scene_and_errors_name_file_and_field() {
    use irsig::scene::load_gltf;
    let d = tempfile::tempdir().unwrap();
    let (doc, bin) = gltf_doc();
    let p = small_scene(
        d.path(),
        r#"{
  "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160, "utc_offset_hours": -4},
  "time": "2025-06-21T14:00:00-04:00",
  "materials": ["../materials.json"],
  "objects": [{"name": "yard", "shapes": [{"gltf": "geo/m.glb"}],
               "parts": [{"name": "glass", "material": "glass", "fixed_temperature_k": 300}]}]
}"#,
    );
    std::fs::write(p.parent().unwrap().join("geo/m.glb"), glb(&doc, &bin)).unwrap();
    let s = Scene::load(&p).unwrap();
    assert_eq!(s.geometry.facet_count(), 26);
    let parts = s.facet_parts();
    let names: Vec<String> = parts
        .iter()
        .map(|&q| s.part_material(q as usize).name.clone())
        .collect();
    assert_eq!(names.iter().filter(|n| **n == "painted_steel").count(), 24);
    assert_eq!(names.iter().filter(|n| **n == "glass").count(), 2);

    // Errors.
    let case = |name: &str, doc: &serde_json::Value, bin: &[u8]| {
        let f = write(d.path(), name, &gltf_embedded(doc.clone(), bin));
        load_gltf(&f).unwrap_err().to_string()
    };
    let mut bad = doc.clone();
    bad["accessors"][1]["count"] = serde_json::json!(40);
    let e = case("long.gltf", &bad, &bin);
    assert!(
        e.contains("long.gltf")
            && e.contains("meshes[0].primitives[0].indices")
            && e.contains("does not fit"),
        "{e}"
    );
    let mut bin9 = bin.clone();
    bin9[96..98].copy_from_slice(&9u16.to_le_bytes());
    let e = case("idx.gltf", &doc, &bin9);
    assert!(
        e.contains("idx.gltf") && e.contains("is 9, beyond the 8 vertices"),
        "{e}"
    );
    let mut nan = bin.clone();
    nan[0..4].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = case("nan.gltf", &doc, &nan);
    assert!(
        e.contains("attributes.POSITION") && e.contains("finite"),
        "{e}"
    );
    let mut bad = doc.clone();
    bad["meshes"][1]["primitives"][0]["attributes"]["POSITION"] = serde_json::json!(9);
    let e = case("pos.gltf", &bad, &bin);
    assert!(
        e.contains("pos.gltf")
            && e.contains("meshes[1].primitives[0].attributes.POSITION")
            && e.contains("accessor 9 does not exist"),
        "{e}"
    );
    let mut bad = doc.clone();
    bad["nodes"][1]["children"] = serde_json::json!([0]);
    let e = case("cycle.gltf", &bad, &bin);
    assert!(
        e.contains("cycle.gltf") && e.contains("expected a tree"),
        "{e}"
    );
    let e = case("short.gltf", &doc, &bin[..100]);
    assert!(e.contains("buffers[0]") && e.contains("byteLength"), "{e}");
    let f = d.path().join("cut.glb");
    std::fs::write(&f, &glb(&doc, &bin)[..60]).unwrap();
    let e = load_gltf(&f).unwrap_err().to_string();
    assert!(e.contains("cut.glb") && e.contains("glTF"), "{e}");
    // A GLB header declaring fewer bytes than itself (an unchecked
    // subtraction inside the gltf crate).
    let mut tiny = glb(&doc, &bin);
    tiny[8..12].copy_from_slice(&5u32.to_le_bytes());
    std::fs::write(&f, &tiny).unwrap();
    let e = load_gltf(&f).unwrap_err().to_string();
    assert!(e.contains("cut.glb") && e.contains("12-byte header"), "{e}");
    let e = load_gltf(&d.path().join("absent.glb"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("absent.glb"), "{e}");
    // In a scene: the shape's field and the glTF's.
    std::fs::write(
        p.parent().unwrap().join("geo/m.glb"),
        &glb(&doc, &bin)[..60],
    )
    .unwrap();
    let e = Scene::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("objects[0].shapes[0].gltf") && e.contains("m.glb"),
        "{e}"
    );
}

/// Issue 21: suspicious input is a warning, never silent — a site that
/// looks like radians, a weather file for a place more than 50 km away
/// (a wrong-sign longitude puts Rochester in Kyrgyzstan) or in another
/// time zone; the real site and its own weather give none.
#[test]
fn suspicious_sites_and_weather_are_warned_about() {
    let d = tempfile::tempdir().unwrap();
    let town_weather = repo_path("scenes/town/weather.csv");
    let with = SMALL.replace(
        "\"materials\": [",
        "\"weather\": {\"file\": \"w.csv\"},\n  \"materials\": [",
    );
    let p = small_scene(d.path(), &with);
    std::fs::copy(&town_weather, p.parent().unwrap().join("w.csv")).unwrap();
    let s = Scene::load(&p).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);

    let sign = small_scene(
        d.path(),
        &with.replace("\"longitude_deg\": -77.61", "\"longitude_deg\": 77.61"),
    );
    let w = Scene::load(&sign).unwrap().warnings;
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("line 4: column 15: field `weather.file`") && w[0].contains("10104 km"),
        "{w:?}"
    );

    let rad = small_scene(
        d.path(),
        &SMALL.replace(
            "\"latitude_deg\": 43.16, \"longitude_deg\": -77.61",
            "\"latitude_deg\": 0.7533, \"longitude_deg\": -1.3545",
        ),
    );
    let w = Scene::load(&rad).unwrap().warnings;
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("field `site`") && w[0].contains("look like radians (43.16°, -77.61°)"),
        "{w:?}"
    );

    // The town's weather kept in UTC−4; an image time in UTC+9 (Tokyo).
    let tokyo = small_scene(
        d.path(),
        &with
            .replace("2025-06-21T14:00:00-04:00", "2025-06-22T03:00:00+09:00")
            .replace("\"utc_offset_hours\": -4", "\"utc_offset_hours\": 9"),
    );
    let w = Scene::load(&tokyo).unwrap().warnings;
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("UTC-04:00") && w[0].contains("UTC+09:00"),
        "{w:?}"
    );
}

/// Great-circle distances against published values: Rochester NY to
/// Bondville IL (the flux site), and a quarter meridian.
#[test]
fn site_distance_is_the_great_circle() {
    let roc = irsig::sun::Site::new(43.16, -77.61, 0.0).unwrap();
    let same = roc.distance_km(&roc);
    assert_eq!(same, 0.0);
    let pole = irsig::sun::Site::new(90.0, 0.0, 0.0).unwrap();
    let equator = irsig::sun::Site::new(0.0, 0.0, 0.0).unwrap();
    // A quarter of a great circle of the 6371.0088 km mean radius.
    assert!((pole.distance_km(&equator) - 6371.0088 * std::f64::consts::FRAC_PI_2).abs() < 1e-6);
    // Antipodes: half a circumference, without NaN from rounding.
    let anti = irsig::sun::Site::new(-43.16, 102.39, 0.0).unwrap();
    assert!((roc.distance_km(&anti) - 6371.0088 * std::f64::consts::PI).abs() < 1e-6);
}

/// The scene's warnings reach the user on stderr as `warning:` lines from
/// both `scene check` (also with `--json`, whose stdout stays JSON) and
/// `render` (before any work).
#[test]
fn cli_prints_scene_warnings_on_stderr() {
    let d = tempfile::tempdir().unwrap();
    let rad = small_scene(
        d.path(),
        &SMALL.replace(
            "\"latitude_deg\": 43.16, \"longitude_deg\": -77.61",
            "\"latitude_deg\": 0.7533, \"longitude_deg\": -1.3545",
        ),
    );
    for args in [
        &["scene", "check", "--load-only"][..],
        &["scene", "check", "--load-only", "--json"][..],
    ] {
        let out = std::process::Command::new(irsig_bin())
            .args(args)
            .arg(&rad)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{err}");
        assert!(
            err.starts_with("warning: ") && err.contains("look like radians"),
            "{args:?}: {err}"
        );
    }
    // `render` says it before failing on the scene's missing weather.
    let rad = small_scene(
        d.path(),
        &SMALL
            .replace(
                "\"latitude_deg\": 43.16, \"longitude_deg\": -77.61",
                "\"latitude_deg\": 0.7533, \"longitude_deg\": -1.3545",
            )
            .replace(
                r#""sensors": [{"type": "frame", "name": "cam", "width": 4}]"#,
                r#""sensors": [{"type": "frame", "name": "cam", "width": 4, "height": 4,
                    "fov_deg": 30, "position": [0, -50, 20], "look_at": [0, 0, 0],
                    "bands": [{"name": "lwir", "response": [8, 12]}]}]"#,
            ),
    );
    let out = std::process::Command::new(irsig_bin())
        .args(["render", "--quiet", "-o"])
        .arg(d.path().join("out"))
        .arg(&rad)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.starts_with("warning: ")
            && err.contains("look like radians")
            && err.contains("weather"),
        "{err}"
    );
}

/// Issue 21: `site.utc_offset_hours` must agree with the offset the image
/// time carries (it used to be required but unused): a mismatch is an error
/// naming the field and its line.
#[test]
fn utc_offset_must_agree_with_the_image_time() {
    let d = tempfile::tempdir().unwrap();
    let p = small_scene(
        d.path(),
        &SMALL.replace("\"utc_offset_hours\": -4", "\"utc_offset_hours\": -5"),
    );
    let e = Scene::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("line 2: column ")
            && e.contains("field `site.utc_offset_hours`")
            && e.contains("UTC-04:00"),
        "{e}"
    );
}

/// Issue 21: a closed OBJ mesh whose faces wind clockwise from outside (normals inward)
/// is a warning naming the object and the shape, from `Scene::load` and on stderr from
/// `scene check` and `render`; `"flip_normals": true` turns it outward (positive volume,
/// no warning); the key on a primitive is an error naming the field. An open mesh (the
/// two-group OBJ) is not judged.
#[test]
fn inward_closed_mesh_is_warned_and_flip_normals_fixes_it() {
    // The 1 × 2 × 1 box of `obj_up_axis_and_unit_per_shape` with every face reversed.
    const INWARD: &str = "v 0 0 0\nv 1 0 0\nv 1 2 0\nv 0 2 0\nv 0 0 1\nv 1 0 1\nv 1 2 1\nv 0 2 1\n\
f 1 2 3 4\nf 8 7 6 5\nf 5 6 2 1\nf 6 7 3 2\nf 7 8 4 3\nf 8 5 1 4\n";
    let d = tempfile::tempdir().unwrap();
    let scene = |shape: &str| {
        SMALL.replace(
            r#"{"name": "thing", "shapes": [{"obj": "geo/two.obj"}],"#,
            &format!(r#"{{"name": "thing", "shapes": [{shape}],"#),
        )
    };
    let p = small_scene(d.path(), SMALL);
    assert!(Scene::load(&p).unwrap().warnings.is_empty());
    write(&d.path().join("s/geo"), "inward.obj", INWARD);
    write(
        &d.path().join("s"),
        "scene.json",
        &scene(r#"{"part": "glass", "obj": "geo/inward.obj"}"#),
    );
    let s = Scene::load(&p).unwrap();
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    let w = &s.warnings[0];
    assert!(
        w.contains("objects[2].shapes[0]")
            && w.contains("object `thing`")
            && w.contains("inward.obj")
            && w.contains("volume -2.000 m³")
            && w.contains("flip_normals"),
        "{w}"
    );
    let m = &s.geometry.meshes[s.objects[2].mesh];
    assert!((signed_volume(&m.positions, &m.indices) + 2.0).abs() < 1e-5);
    // Both commands print it.
    for args in [&["scene", "check"][..], &["render", "--quiet", "-o"][..]] {
        let mut c = std::process::Command::new(irsig_bin());
        c.args(args);
        if args[0] == "render" {
            c.arg(d.path().join("out"));
        }
        let out = c.arg(&p).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.starts_with("warning: ") && err.contains("normals face inward"),
            "{args:?}: {err}"
        );
    }
    // Flipped: outward, silent.
    write(
        &d.path().join("s"),
        "scene.json",
        &scene(r#"{"part": "glass", "obj": "geo/inward.obj", "flip_normals": true}"#),
    );
    let s = Scene::load(&p).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let m = &s.geometry.meshes[s.objects[2].mesh];
    assert!((signed_volume(&m.positions, &m.indices) - 2.0).abs() < 1e-5);
    // Not on primitives.
    write(
        &d.path().join("s"),
        "scene.json",
        &scene(r#"{"part": "glass", "box": {"size": [1, 1, 1]}, "flip_normals": true}"#),
    );
    let e = Scene::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("shapes[0].flip_normals") && e.contains("obj"),
        "{e}"
    );
}

/// Issue 21: an OBJ whose size is implausible for its `unit` — a 20 m tower written in
/// millimetres read as metres (20 km), or a 3 m shed written in metres declared as
/// millimetres (3 mm) — is a warning naming the object, the shape and `unit`; the same
/// files with the right unit are silent.
#[test]
fn obj_extent_implausible_for_its_unit_is_warned() {
    let d = tempfile::tempdir().unwrap();
    let p = small_scene(d.path(), SMALL);
    let boxed = |x: f64, y: f64, z: f64| {
        format!(
            "v 0 0 0\nv {x} 0 0\nv {x} {y} 0\nv 0 {y} 0\nv 0 0 {z}\nv {x} 0 {z}\nv {x} {y} {z}\nv 0 {y} {z}\n\
f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n"
        )
    };
    write(
        &d.path().join("s/geo"),
        "tower.obj",
        &boxed(5000.0, 5000.0, 20000.0),
    );
    write(&d.path().join("s/geo"), "shed.obj", &boxed(3.0, 2.0, 2.5));
    let warnings = |shape: &str| {
        let text = SMALL.replace(
            r#"{"name": "thing", "shapes": [{"obj": "geo/two.obj"}],"#,
            &format!(r#"{{"name": "thing", "shapes": [{shape}],"#),
        );
        write(&d.path().join("s"), "scene.json", &text);
        Scene::load(&p).unwrap().warnings
    };
    let w = warnings(r#"{"part": "glass", "obj": "geo/tower.obj"}"#);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("objects[2].shapes[0]")
            && w[0].contains("object `thing`")
            && w[0].contains("spans 20.0 km")
            && w[0].contains("`unit`"),
        "{w:?}"
    );
    assert!(warnings(r#"{"part": "glass", "obj": "geo/tower.obj", "unit": "mm"}"#).is_empty());
    let w = warnings(r#"{"part": "glass", "obj": "geo/shed.obj", "unit": "mm"}"#);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("spans only 3.0 mm") && w[0].contains("\"mm\""),
        "{w:?}"
    );
    assert!(warnings(r#"{"part": "glass", "obj": "geo/shed.obj"}"#).is_empty());
    // And on stderr from `scene check`.
    warnings(r#"{"part": "glass", "obj": "geo/tower.obj"}"#);
    let out = std::process::Command::new(irsig_bin())
        .args(["scene", "check", "--load-only"])
        .arg(&p)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && err.starts_with("warning: ") && err.contains("spans 20.0 km"),
        "{err}"
    );
}

/// Issue 21: a weather gap longer than 3 of the file's steps inside the 24 h history
/// before the image time is a warning with the gap's start and end (the town's 15-min
/// weather with 02:00–10:00 on the image day removed); a gap of exactly 3 steps inside
/// the window, or a long one before it, is silent. `render` prints it too.
#[test]
fn weather_gaps_in_the_history_window_are_warned() {
    let d = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(repo_path("scenes/town/weather.csv")).unwrap();
    let without = |cut: &[(&str, &str)]| -> String {
        text.lines()
            .filter(|l| {
                !cut.iter()
                    .any(|(a, b)| l.starts_with("20") && *a < &l[..19] && &l[..19] < *b)
            })
            .map(|l| format!("{l}\n"))
            .collect()
    };
    let with = SMALL.replace(
        "\"materials\": [",
        "\"weather\": {\"file\": \"w.csv\"},\n  \"materials\": [",
    );
    let p = small_scene(d.path(), &with);
    let w_csv = p.parent().unwrap().join("w.csv");
    // 45 min inside the window (12:00 → 12:45), 3 h before it: silent.
    std::fs::write(
        &w_csv,
        without(&[
            ("2025-06-21T12:00:00", "2025-06-21T12:45:00"),
            ("2025-06-19T04:00:00", "2025-06-19T07:00:00"),
        ]),
    )
    .unwrap();
    let w = Scene::load(&p).unwrap().warnings;
    assert!(w.is_empty(), "{w:?}");
    // 8 h inside it.
    std::fs::write(
        &w_csv,
        without(&[("2025-06-21T02:00:00", "2025-06-21T10:00:00")]),
    )
    .unwrap();
    let w = Scene::load(&p).unwrap().warnings;
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("field `weather.file`")
            && w[0].contains("from 2025-06-21T02:00:00-04:00 to 2025-06-21T10:00:00-04:00")
            && w[0].contains("8.0 h")
            && w[0].contains("0.25 h"),
        "{w:?}"
    );
    let out = std::process::Command::new(irsig_bin())
        .args(["render", "--quiet", "-o"])
        .arg(d.path().join("out"))
        .arg(&p)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with("warning: ") && err.contains("no weather records from"),
        "{err}"
    );
}

/// Issue 21: an image larger than the available memory is an error before anything is
/// allocated, naming `sensors[i].width` and the estimate in GiB (a 200000 × 200000 image
/// used to abort with a backtrace); the estimate is width × height × oversample² ×
/// (bands + truth layers) × 4 bytes, spread over `--tile` row bands.
#[test]
fn image_larger_than_memory_is_an_error_before_allocating() {
    let d = tempfile::tempdir().unwrap();
    let sensor = |w: u64| {
        SMALL.replace(
            r#""sensors": [{"type": "frame", "name": "cam", "width": 4}]"#,
            &format!(
                r#""sensors": [{{"type": "frame", "name": "cam", "width": {w}, "height": {w},
                    "oversample": 2, "fov_deg": 30, "position": [0, -50, 20], "look_at": [0, 0, 0],
                    "bands": [{{"name": "lwir", "response": [8, 12]}}]}}]"#
            ),
        )
    };
    let p = small_scene(d.path(), &sensor(1000));
    let s = Scene::load(&p).unwrap();
    // 1000² × 2² × (1 + 6) × 4 B = 112 MB.
    let mb = 1_000_000u64;
    assert!(irsig::scene::image_memory_errors(&s, 6, 1, 113 * mb).is_empty());
    let e = irsig::scene::image_memory_errors(&s, 6, 1, 111 * mb);
    assert_eq!(e.len(), 1);
    let e = e[0].to_string();
    assert!(
        e.contains("field `sensors[0].width`") && e.contains("0.1 GiB") && e.contains("--tile"),
        "{e}"
    );
    assert!(irsig::scene::image_memory_errors(&s, 6, 2, 57 * mb).is_empty());

    let p = small_scene(d.path(), &sensor(200_000));
    for args in [&["scene", "check"][..], &["render", "--quiet", "-o"][..]] {
        let mut c = std::process::Command::new(irsig_bin());
        c.args(args);
        if args[0] == "render" {
            c.arg(d.path().join("out"));
        }
        let out = c.arg(&p).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("field `sensors[0].width`")
                && err.contains("about 4172.3 GiB")
                && !err.contains("panicked")
                && !err.contains("memory allocation"),
            "{args:?}: {err}"
        );
    }
}

/// Issue 21: a DIRSIG material whose emissivity file is missing is the same `warning:`
/// from `render` as from `scene check` (it used to be shown by `scene check` only).
#[test]
fn missing_emissivity_file_is_warned_by_render_too() {
    let d = tempfile::tempdir().unwrap();
    let p = small_scene(d.path(), SMALL);
    write(
        &d.path().join("s"),
        "lib.mat",
        "MATERIAL_ENTRY {\n  ID = 19\n  NAME = Steel plate\n  TEMP_SOLVER_NAME = Therm\n  TEMP_SOLVER {\n    SPECIFIC_HEAT = 0.1\n    MASS_DENSITY = 7.8\n    THERMAL_CONDUCTIVITY = 430\n    SOLAR_ABSORPTION = 0.5\n    THERMAL_EMISSIVITY = 0.8\n    EXPOSED_AREA = 1\n    THICKNESS = 0.5\n  }\n  SURFACE_PROPERTIES {\n    EMISSIVITY_PROP_NAME = ClassicEmissivity\n    EMISSIVITY_PROP {\n      FILENAME = gone.ems\n    }\n  }\n}\n",
    );
    write(
        &d.path().join("s"),
        "scene.json",
        &SMALL.replace(
            r#""materials": ["../materials.json"],"#,
            r#""materials": ["../materials.json", "lib.mat"],"#,
        ),
    );
    let mut seen = Vec::new();
    for args in [&["scene", "check"][..], &["render", "--quiet", "-o"][..]] {
        let mut c = std::process::Command::new(irsig_bin());
        c.args(args);
        if args[0] == "render" {
            c.arg(d.path().join("out"));
        }
        let out = c.arg(&p).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        let w: Vec<String> = err
            .lines()
            .filter(|l| l.starts_with("warning: "))
            .map(str::to_string)
            .collect();
        assert!(
            w.len() == 1 && w[0].contains("lib.mat") && w[0].contains("`gone.ems` not found"),
            "{args:?}: {err}"
        );
        seen.push(w);
    }
    assert_eq!(seen[0], seen[1]);
}

/// Issue 21: a camera that sees no scene geometry (looking up at the sky), or that sits
/// inside a closed object (every ray meets the back of a face), is a `warning:` naming
/// the sensor from `scene check` and `render`; the same camera looking at the scene
/// from outside is silent.
#[test]
fn camera_seeing_nothing_or_inside_an_object_is_warned() {
    const POST: &str = "v 0 0 0\nv 1 0 0\nv 1 2 0\nv 0 2 0\nv 0 0 1\nv 1 0 1\nv 1 2 1\nv 0 2 1\n\
f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    let d = tempfile::tempdir().unwrap();
    let scene = |position: &str, look_at: &str| {
        SMALL
            .replace(
                "\"materials\": [",
                "\"weather\": {\"file\": \"w.csv\"},\n  \"materials\": [",
            )
            .replace(
                r#"{"name": "thing", "shapes": [{"obj": "geo/two.obj"}],"#,
                r#"{"name": "post", "shapes": [{"part": "glass", "obj": "geo/post.obj", "transform": {"scale": 10}}],"#,
            )
            .replace(
                r#""sensors": [{"type": "frame", "name": "cam", "width": 4}]"#,
                &format!(
                    r#""sensors": [{{"type": "frame", "name": "cam", "width": 4, "height": 4,
                    "fov_deg": 30, "position": {position}, "look_at": {look_at},
                    "bands": [{{"name": "lwir", "response": [8, 12]}}]}}]"#
                ),
            )
    };
    let p = small_scene(d.path(), SMALL);
    std::fs::copy(
        repo_path("scenes/town/weather.csv"),
        p.parent().unwrap().join("w.csv"),
    )
    .unwrap();
    write(&d.path().join("s/geo"), "post.obj", POST);
    let run = |text: &str| -> Vec<String> {
        write(&d.path().join("s"), "scene.json", text);
        let mut all = Vec::new();
        for args in [&["scene", "check"][..], &["render", "--quiet", "-o"][..]] {
            let mut c = std::process::Command::new(irsig_bin());
            c.args(args);
            if args[0] == "render" {
                c.arg(d.path().join("out"));
            }
            let out = c.arg(&p).output().unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(out.status.success(), "{args:?}: {err}");
            let w: Vec<String> = err
                .lines()
                .filter(|l| l.starts_with("warning: "))
                .map(str::to_string)
                .collect();
            all.push(w.join("\n"));
        }
        assert_eq!(all[0], all[1]);
        all.swap_remove(0).lines().map(str::to_string).collect()
    };
    assert!(run(&scene("[0, -50, 20]", "[0, 0, 0]")).is_empty());
    let w = run(&scene("[0, -50, 20]", "[0, -60, 100]"));
    assert!(
        w.len() == 1 && w[0].contains("sensor `cam` sees no scene geometry"),
        "{w:?}"
    );
    let w = run(&scene("[5, 10, 5]", "[5, 30, 5]"));
    assert!(
        w.len() == 1 && w[0].contains("sensor `cam`") && w[0].contains("inside object `post`"),
        "{w:?}"
    );
}

/// The one-pass reader of plain-geometry OBJ text equals the reference
/// reader (pre-scan + tobj) group for group, vertex for vertex, bit for bit:
/// groups by `o`/`g` (an empty name, faces before the first), triangles,
/// quads and polygons fanned, negative indices, vertices shared between
/// groups (each group gets its own copies, in first-use order), comments.
#[test]
fn obj_plain_fast_path_equals_the_reference_reader() {
    let p = Path::new("plain.obj");
    let texts = [
        // Faces before any group; a vertex reused by the next group.
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.5\nf 1 2 3\n# comment\n\no second\nf 2 4 3\n",
        // Quads, a pentagon, negative indices, repeated vertices, `g` and
        // an empty `o`, exponents and signs.
        "o a\nv -1.5e1 0 +2\nv 10 0 0\nv 10 10 0\nv 0 10 0.125\nv 5 15 1\n\
         f 1 2 3 4\nf -5 -4 -3 -2 -1\ng b\nf 4 3 5\nf 5 4 3\no\nf 1 3 5\n",
        // Windows line ends and tabs.
        "o w\r\nv 0\t0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 3 2 1\r\n",
    ];
    for (k, text) in texts.iter().enumerate() {
        let fast = irsig::scene::obj::load_obj_plain(text)
            .unwrap_or_else(|| panic!("text {k}: not taken by the fast path"));
        let slow = irsig::scene::obj::load_obj_reference(text, p).unwrap();
        assert_eq!(fast.len(), slow.len(), "text {k}: group count");
        for (f, s) in fast.iter().zip(&slow) {
            assert_eq!(f.name, s.name, "text {k}");
            assert_eq!(f.material_name, s.material_name, "text {k}");
            assert_eq!(f.mesh.indices, s.mesh.indices, "text {k} group {}", f.name);
            let bits = |v: &[glam::Vec3]| -> Vec<[u32; 3]> {
                v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
            };
            assert_eq!(bits(&f.mesh.positions), bits(&s.mesh.positions), "text {k}");
        }
    }
    // The generated scene of `irsig bench facets` (terrain and buildings,
    // one `o` each, world coordinates), as that command writes it.
    let geo = irsig::geometry::procedural::generate(
        &irsig::geometry::procedural::TerrainParams::with_triangles(20_000, 3),
    );
    let mut text = String::new();
    let mut base = 1;
    for (i, inst) in geo.instances.iter().enumerate() {
        let m = &geo.meshes[inst.mesh];
        text.push_str(&format!("o part{i}\n"));
        for q in &m.positions {
            let q = inst.world_from_object.transform_point3(*q);
            text.push_str(&format!("v {} {} {}\n", q.x, q.y, q.z));
        }
        for t in &m.indices {
            text.push_str(&format!(
                "f {} {} {}\n",
                t[0] + base,
                t[1] + base,
                t[2] + base
            ));
        }
        base += m.positions.len() as u32;
    }
    let fast = irsig::scene::obj::load_obj_plain(&text).expect("plain geometry");
    let slow = irsig::scene::obj::load_obj_reference(&text, p).unwrap();
    assert!(fast.len() > 1 && fast.len() == slow.len());
    for (f, s) in fast.iter().zip(&slow) {
        assert_eq!(f.name, s.name);
        assert_eq!(f.mesh.indices, s.mesh.indices);
        assert_eq!(f.mesh.positions, s.mesh.positions);
    }
    // Anything else goes to the reference reader: materials, texture
    // coordinates and normals, `v` with a weight, malformed or
    // out-of-range faces (whose errors the reference reader words).
    for other in [
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n",
        "v 0 0 0 2\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
        "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
        "s off\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    ] {
        assert!(
            irsig::scene::obj::load_obj_plain(other).is_none(),
            "taken by the fast path: {other:?}"
        );
    }
    // And the errors are still the reference reader's, with the line.
    let e = irsig::scene::obj::load_obj_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", p)
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 4"), "{e}");
}

/// The closed-mesh test behind the inward-normals warning: a unit cube
/// with every face's vertices repeated (as OBJ exporters write it) is
/// closed with volume +1 m³ (−1 m³ wound inward); without one face, or
/// with one face doubled, it is not closed.
#[test]
fn closed_signed_volume_of_a_cube_welded_by_position() {
    use glam::Vec3;
    let c = |i: u32| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
    // Quads counter-clockwise from outside, as corner numbers (bit 0 = x,
    // bit 1 = y, bit 2 = z).
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mesh = |faces: &[[u32; 4]], flip: bool| {
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for q in faces {
            let b = positions.len() as u32;
            positions.extend(q.iter().map(|&i| c(i)));
            let (t1, t2) = ([b, b + 1, b + 2], [b, b + 2, b + 3]);
            for mut t in [t1, t2] {
                if flip {
                    t.swap(1, 2);
                }
                indices.push(t);
            }
        }
        (positions, indices)
    };
    let (p, i) = mesh(&quads, false);
    let v = irsig::scene::closed_signed_volume(&p, &i).expect("closed");
    assert!((v - 1.0).abs() < 1e-12, "{v}");
    let (p, i) = mesh(&quads, true);
    let v = irsig::scene::closed_signed_volume(&p, &i).expect("closed");
    assert!((v + 1.0).abs() < 1e-12, "{v}");
    let (p, i) = mesh(&quads[..5], false);
    assert_eq!(irsig::scene::closed_signed_volume(&p, &i), None);
    let mut doubled = quads.to_vec();
    doubled.push(quads[0]);
    let (p, i) = mesh(&doubled, false);
    assert_eq!(irsig::scene::closed_signed_volume(&p, &i), None);
}
