//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The project's `../shared/data/<sub>` folder. Tests that call this are
/// `#[ignore = "needs ../shared/data"]`: a user's clone, which has no
/// `../shared`, lists them as ignored (never as passed), and `scripts/test`
/// runs them with `--include-ignored` where `../shared/data` exists (as on CI).
/// Run explicitly without the data, they fail here, naming what is missing.
pub fn shared_data(sub: &str) -> PathBuf {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data")
        .join(sub);
    assert!(
        p.is_dir(),
        "this test needs {} (the project's shared data), which is absent",
        p.display()
    );
    p
}

/// Path of a file in the repository.
pub fn repo_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Path of the built `irsig` binary, for CLI tests.
pub fn irsig_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_irsig"))
}

// ------------------------------------------------ glTF test documents

/// A unit cube `[0, 1]³` (glTF axes), faces counter-clockwise from outside:
/// 8 vertices and 36 `u16` indices.
pub fn gltf_cube() -> (Vec<[f32; 3]>, Vec<u16>) {
    let v: Vec<[f32; 3]> = (0..8)
        .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
        .collect();
    let mut idx = Vec::new();
    // Each face: its four corners in cyclic order, then oriented outward.
    for (axis, side) in [(0, 0), (0, 1), (1, 0), (1, 1), (2, 0), (2, 1)] {
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        let corner = |u: usize, w: usize| -> u16 { ((side << axis) | (u << a) | (w << b)) as u16 };
        let mut q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
        // (a, b, axis) is a cyclic order: this quad's normal is +axis.
        if side == 0 {
            q.reverse();
        }
        idx.extend([q[0], q[1], q[2], q[0], q[2], q[3]]);
    }
    (v, idx)
}

/// A glTF document (JSON) and its one buffer: a cube mesh `crate`
/// (material `painted_steel`) under a node translated by `(10, 0, 0)` with
/// a child scaled by 2, a mirrored second instance (scale −1 in x) at
/// `(0, 0, -5)`, and a triangle-strip quad `panel` (material `glass`,
/// facing +Y = up).
pub fn gltf_doc() -> (serde_json::Value, Vec<u8>) {
    let (v, idx) = gltf_cube();
    let mut bin = Vec::new();
    for p in &v {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
    }
    let idx_off = bin.len();
    for i in &idx {
        bin.extend(i.to_le_bytes());
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let quad_off = bin.len();
    // Strip order 0 1 2 3 on y = 0: (0,0,0) (0,0,1) (1,0,0) (1,0,1); the
    // first triangle (0,0,0) (0,0,1) (1,0,0) faces +Y.
    for p in [
        [0.0f32, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        [1.0, 0.0, 1.0],
    ] {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
    }
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 2, 3]}],
        "nodes": [
            {"name": "placed", "translation": [10.0, 0.0, 0.0], "children": [1]},
            {"mesh": 0, "scale": [2.0, 2.0, 2.0]},
            {"mesh": 0, "translation": [0.0, 0.0, -5.0], "scale": [-1.0, 1.0, 1.0]},
            {"mesh": 1, "translation": [0.0, 3.0, 0.0]},
        ],
        "meshes": [
            {"name": "crate", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]},
            {"name": "panel", "primitives": [{"attributes": {"POSITION": 2}, "mode": 5, "material": 1}]},
        ],
        "materials": [{"name": "painted_steel"}, {"name": "glass"}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
            {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 96},
            {"buffer": 0, "byteOffset": idx_off, "byteLength": 72},
            {"buffer": 0, "byteOffset": quad_off, "byteLength": 48},
        ],
        "buffers": [{"byteLength": bin.len()}],
    });
    (doc, bin)
}

/// `.gltf` text with the buffer as a base64 `data:` URI.
pub fn gltf_embedded(mut doc: serde_json::Value, bin: &[u8]) -> String {
    use base64::Engine;
    doc["buffers"][0]["uri"] = serde_json::json!(format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bin)
    ));
    doc.to_string()
}

/// Binary glTF (GLB): header, JSON chunk, BIN chunk (glTF 2.0 §4.4).
pub fn glb(doc: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut json = doc.to_string().into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(0x4E4F_534Au32.to_le_bytes());
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(0x004E_4942u32.to_le_bytes());
    out.extend(bin);
    out
}

/// The slab properties of stock material `name` (the library built into
/// irsig, `scenes/materials.json`).
pub fn stock_props(name: &str) -> irsig::thermal::SlabProperties {
    let db = irsig::material::stock::stock().unwrap();
    let m = db
        .get(name)
        .unwrap_or_else(|| panic!("no stock material `{name}`"));
    irsig::thermal::SlabProperties::from_material(m).unwrap()
}

/// The sunlit fraction of every facet at every record, facet-major
/// (`[facet · steps + record]`): the exhaustive `f32` layout of a compact
/// solar history.
pub fn sun_fractions(s: &irsig::exposure::SolarHistory) -> Vec<f32> {
    (0..s.facet_count())
        .flat_map(|f| s.sun_fraction(f))
        .collect()
}

/// The cosine of incidence of every facet at every record, facet-major.
pub fn cos_incidences(s: &irsig::exposure::SolarHistory) -> Vec<f32> {
    (0..s.facet_count())
        .flat_map(|f| s.cos_incidence(f))
        .collect()
}
