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
