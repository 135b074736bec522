//! glTF 2.0 mesh import (`.gltf` JSON with embedded or external buffers, or
//! binary `.glb`), through the `gltf` crate's document model.
//!
//! The triangles of every mesh primitive reachable from the default scene
//! (else the first scene, else every root node) are placed by their node
//! transforms and converted from glTF's Y-up axes to irsig's ENU Z-up:
//! `(x, y, z)_glTF → (x, −z, y)` (the inverse of Blender's glTF export), so
//! a model's up stays up and its front (+Z) faces south (−Y). Units are
//! metres in both. Faces are grouped as for OBJ ([`ObjGroup`]): `name` is the
//! mesh's name (else its node's, else `mesh<i>`) and `material_name` the
//! glTF material's name, which the scene maps to its own material database
//! (the PBR colours are not used).
//!
//! Accessor data are read here with checked bounds (not with the crate's
//! reader, which may panic on inconsistent files): positions must be float
//! `VEC3`, indices unsigned scalars; sparse and quantised accessors are
//! refused with a clear error. Triangle strips and fans are converted;
//! points and lines carry no surface and are skipped.

use std::path::Path;

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use glam::{Affine3A, Mat4, Vec3};

use super::obj::ObjGroup;
use crate::error::{Error, Location, Result};
use crate::geometry::TriangleMesh;

/// Most triangles one glTF file may produce (after node instancing).
pub const MAX_TRIANGLES: usize = 50_000_000;

/// Load a `.gltf` or `.glb` file: triangulated groups in irsig's axes.
/// External buffers are read relative to the file's folder. Errors name the
/// file and the glTF field (`meshes[0].primitives[1].indices`, …).
pub fn load_gltf(path: &Path) -> Result<Vec<ObjGroup>> {
    let data = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    load_gltf_slice(&data, path, path.parent())
}

/// Extensions a file may require: none is read by irsig, so a required one is an error
/// naming it (before validation, whose messages — "Missing data" for a Draco-compressed
/// accessor without a buffer view — would not say why). Known ones get their purpose.
fn check_required_extensions(required: &[String], used: &[String], path: &Path) -> Result<()> {
    let what = |name: &str| match name {
        "KHR_draco_mesh_compression" => " (Draco-compressed geometry)",
        "EXT_meshopt_compression" | "KHR_meshopt_compression" => {
            " (meshoptimizer-compressed buffers)"
        }
        "KHR_mesh_quantization" => " (quantized vertex attributes)",
        "EXT_mesh_gpu_instancing" => " (GPU instancing)",
        "KHR_texture_basisu" | "EXT_texture_webp" => " (compressed textures)",
        _ => "",
    };
    if required.is_empty() {
        return Ok(());
    }
    let names: Vec<String> = required
        .iter()
        .map(|n| format!("`{n}`{}", what(n)))
        .collect();
    let also_used: Vec<&String> = used.iter().filter(|u| !required.contains(u)).collect();
    Err(Error::parse(
        Location::file(path).with_field("extensionsRequired"),
        format!(
            "the file requires glTF extension{} {}, which irsig does not read; re-export it \
             without compression or quantization (e.g. Blender's glTF exporter with \
             \"Compression\" off){}",
            if names.len() > 1 { "s" } else { "" },
            names.join(", "),
            if also_used.is_empty() {
                String::new()
            } else {
                format!(
                    " (it also uses {}, which are optional)",
                    also_used
                        .iter()
                        .map(|u| format!("`{u}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            }
        ),
    ))
}

/// Load glTF/GLB bytes; `path` names the file in errors, `base` is the
/// folder external buffer URIs are relative to (`None`: external buffers
/// are an error).
pub fn load_gltf_slice(data: &[u8], path: &Path, base: Option<&Path>) -> Result<Vec<ObjGroup>> {
    let at = |field: &str| Location::file(path).with_field(field.to_string());
    // The crate subtracts the 12-byte header from the GLB's declared length
    // unchecked (an overflow panic with overflow checks): check it first.
    if let Some(len) = data
        .strip_prefix(b"glTF")
        .and_then(|rest| rest.get(4..8))
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        && len < 12
    {
        return Err(Error::parse(
            Location::file(path),
            format!("GLB header declares {len} bytes in all: expected at least the 12-byte header"),
        ));
    }
    let invalid = |e: ::gltf::Error| match e {
        ::gltf::Error::Validation(errs) => {
            let (field, what) = errs
                .first()
                .map(|(p, e)| (p.to_string(), e.to_string()))
                .unwrap_or_default();
            Error::parse(
                at(&field),
                format!(
                    "invalid glTF: {what}{}",
                    if errs.len() > 1 {
                        format!(" (and {} more problems)", errs.len() - 1)
                    } else {
                        String::new()
                    }
                ),
            )
        }
        other => Error::parse(
            Location::file(path),
            format!("not a glTF 2.0 file (JSON or GLB): {other}"),
        ),
    };
    let ::gltf::Gltf { document, blob } =
        ::gltf::Gltf::from_slice_without_validation(data).map_err(invalid)?;
    // The crate's validation indexes the accessors by each primitive's
    // POSITION unchecked (a panic when out of range): check that first.
    let root = document.into_json();
    check_required_extensions(&root.extensions_required, &root.extensions_used, path)?;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (k, prim) in mesh.primitives.iter().enumerate() {
            let positions =
                ::gltf::json::validation::Checked::Valid(::gltf::json::mesh::Semantic::Positions);
            if let Some(i) = prim.attributes.get(&positions)
                && i.value() >= root.accessors.len()
            {
                return Err(Error::parse(
                    at(&format!("meshes[{m}].primitives[{k}].attributes.POSITION")),
                    format!(
                        "accessor {} does not exist ({} accessors)",
                        i.value(),
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    let doc = ::gltf::Gltf {
        document: ::gltf::Document::from_json(root).map_err(invalid)?,
        blob,
    };
    let buffers = load_buffers(&doc, path, base)?;

    // Roots: the default scene, else the first, else every node no other
    // node lists as a child.
    let nodes: Vec<::gltf::Node> = doc.nodes().collect();
    let mut parents = vec![0usize; nodes.len()];
    for n in &nodes {
        for c in n.children() {
            parents[c.index()] += 1;
            if parents[c.index()] > 1 {
                return Err(Error::parse(
                    at(&format!("nodes[{}].children", n.index())),
                    format!(
                        "node {} is a child of more than one node: expected a tree",
                        c.index()
                    ),
                ));
            }
        }
    }
    let (roots, roots_field): (Vec<usize>, String) =
        match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(s) => (
                s.nodes().map(|n| n.index()).collect(),
                format!("scenes[{}].nodes", s.index()),
            ),
            None => (
                (0..nodes.len()).filter(|&i| parents[i] == 0).collect(),
                "nodes".into(),
            ),
        };

    let y_up_to_z_up = Mat4::from_cols_array_2d(&[
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]);
    let mut groups: Vec<ObjGroup> = Vec::new();
    let mut visited = vec![false; nodes.len()];
    let mut triangles = 0usize;
    let mut stack: Vec<(usize, Mat4)> = roots.iter().rev().map(|&r| (r, y_up_to_z_up)).collect();
    while let Some((i, parent)) = stack.pop() {
        let node = &nodes[i];
        let field = format!("nodes[{i}]");
        if std::mem::replace(&mut visited[i], true) {
            return Err(Error::parse(
                at(&roots_field),
                format!("node {i} is reached twice (a cycle, or listed twice): expected a tree"),
            ));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(Error::parse(
                at(&format!("{field}.matrix")),
                "the node transform is not finite",
            ));
        }
        if let Some(mesh) = node.mesh() {
            let affine = Affine3A::from_mat4(world);
            let det = affine.matrix3.determinant();
            if !(det.is_finite() && det != 0.0) {
                return Err(Error::parse(
                    at(&format!("{field}.matrix")),
                    "the node transform is singular (zero scale?)",
                ));
            }
            let name = mesh
                .name()
                .or(node.name())
                .map(str::to_string)
                .unwrap_or_else(|| format!("mesh{}", mesh.index()));
            for prim in mesh.primitives() {
                let pf = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
                let Some(tris) = primitive_triangles(&prim, &buffers, &pf, path)? else {
                    continue;
                };
                triangles += tris.indices.len();
                if triangles > MAX_TRIANGLES {
                    return Err(Error::parse(
                        at(&pf),
                        format!("more than {MAX_TRIANGLES} triangles in the file"),
                    ));
                }
                let material_name = prim.material().name().map(str::to_string);
                let gi = match groups
                    .iter()
                    .position(|g| g.name == name && g.material_name == material_name)
                {
                    Some(g) => g,
                    None => {
                        groups.push(ObjGroup {
                            name: name.clone(),
                            material_name,
                            mesh: TriangleMesh {
                                name: name.clone(),
                                positions: Vec::new(),
                                indices: Vec::new(),
                            },
                        });
                        groups.len() - 1
                    }
                };
                let m = &mut groups[gi].mesh;
                let base = m.positions.len() as u32;
                for p in &tris.positions {
                    let w = affine.transform_point3(*p);
                    if !w.is_finite() {
                        return Err(Error::parse(
                            at(&format!("{pf}.attributes.POSITION")),
                            format!("vertex {p} placed by node {i} is not finite"),
                        ));
                    }
                    m.positions.push(w);
                }
                for t in &tris.indices {
                    let t = t.map(|k| k + base);
                    // Mirroring transforms keep faces counter-clockwise
                    // from the front.
                    m.indices
                        .push(if det < 0.0 { [t[0], t[2], t[1]] } else { t });
                }
            }
        }
        for c in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((c.index(), world));
        }
    }
    if groups.iter().all(|g| g.mesh.indices.is_empty()) {
        return Err(Error::parse(
            Location::file(path),
            "no triangles: expected at least one mesh primitive of mode TRIANGLES, \
             TRIANGLE_STRIP or TRIANGLE_FAN placed by a node of the scene",
        ));
    }
    Ok(groups)
}

/// The data of each buffer (GLB binary chunk, `data:` URI, or external file).
fn load_buffers(doc: &::gltf::Gltf, path: &Path, base: Option<&Path>) -> Result<Vec<Vec<u8>>> {
    use base64::Engine;
    let mut out = Vec::new();
    for b in doc.buffers() {
        let field = format!("buffers[{}]", b.index());
        let at = || Location::file(path).with_field(field.clone());
        let data = match b.source() {
            ::gltf::buffer::Source::Bin => doc.blob.clone().ok_or_else(|| {
                Error::parse(
                    at(),
                    "no `uri` and no GLB binary chunk: expected the buffer's data",
                )
            })?,
            ::gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let (_, payload) = uri
                    .split_once(";base64,")
                    .ok_or_else(|| Error::parse(at(), "a `data:` URI without `;base64,`"))?;
                base64::engine::general_purpose::STANDARD
                    .decode(payload)
                    .map_err(|e| Error::parse(at(), format!("bad base64 in the data URI: {e}")))?
            }
            ::gltf::buffer::Source::Uri(uri) => {
                let Some(dir) = base else {
                    return Err(Error::parse(
                        at(),
                        format!("external buffer `{uri}` cannot be resolved here"),
                    ));
                };
                let p = dir.join(uri);
                std::fs::read(&p).map_err(|e| {
                    Error::parse(at(), format!("cannot read buffer `{}`: {e}", p.display()))
                })?
            }
        };
        if data.len() < b.length() {
            return Err(Error::parse(
                at(),
                format!(
                    "byteLength is {} but only {} bytes of data are there",
                    b.length(),
                    data.len()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// One primitive's vertices (object space) and triangles.
struct Triangles {
    positions: Vec<Vec3>,
    indices: Vec<[u32; 3]>,
}

/// The triangles of a primitive (`None` for points and lines).
fn primitive_triangles(
    prim: &::gltf::Primitive,
    buffers: &[Vec<u8>],
    field: &str,
    path: &Path,
) -> Result<Option<Triangles>> {
    let at = |f: &str| Location::file(path).with_field(format!("{field}{f}"));
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Ok(None);
    }
    let pos = prim.get(&::gltf::Semantic::Positions).ok_or_else(|| {
        Error::parse(
            at(".attributes"),
            "no POSITION attribute: expected vertex positions",
        )
    })?;
    if pos.data_type() != DataType::F32 || pos.dimensions() != Dimensions::Vec3 {
        return Err(Error::parse(
            at(".attributes.POSITION"),
            format!(
                "{:?} {:?} positions: expected float VEC3 (quantised positions are not supported)",
                pos.data_type(),
                pos.dimensions()
            ),
        ));
    }
    let raw = accessor_elements(&pos, buffers, &at(".attributes.POSITION"))?;
    let mut positions = Vec::with_capacity(raw.len());
    for (k, e) in raw.iter().enumerate() {
        let f = |j: usize| f32::from_le_bytes([e[4 * j], e[4 * j + 1], e[4 * j + 2], e[4 * j + 3]]);
        let p = Vec3::new(f(0), f(1), f(2));
        if !p.is_finite() {
            return Err(Error::parse(
                at(".attributes.POSITION"),
                format!("vertex {k} is {p}: expected finite coordinates"),
            ));
        }
        positions.push(p);
    }
    let n = positions.len();
    let order: Vec<u32> = match prim.indices() {
        None => (0..n as u32).collect(),
        Some(acc) => {
            let loc = at(".indices");
            let width = match (acc.data_type(), acc.dimensions()) {
                (DataType::U8, Dimensions::Scalar) => 1,
                (DataType::U16, Dimensions::Scalar) => 2,
                (DataType::U32, Dimensions::Scalar) => 4,
                (t, d) => {
                    return Err(Error::parse(
                        loc,
                        format!("{t:?} {d:?} indices: expected unsigned byte/short/int scalars"),
                    ));
                }
            };
            let raw = accessor_elements(&acc, buffers, &loc)?;
            let mut v = Vec::with_capacity(raw.len());
            for (k, e) in raw.iter().enumerate() {
                let i = match width {
                    1 => e[0] as u32,
                    2 => u16::from_le_bytes([e[0], e[1]]) as u32,
                    _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
                };
                if i as usize >= n {
                    return Err(Error::parse(
                        loc,
                        format!("index {k} is {i}, beyond the {n} vertices"),
                    ));
                }
                v.push(i);
            }
            v
        }
    };
    let mut indices = Vec::new();
    match mode {
        Mode::Triangles => {
            if !order.len().is_multiple_of(3) {
                return Err(Error::parse(
                    at(".indices"),
                    format!(
                        "{} vertices drawn: expected a multiple of 3 for TRIANGLES",
                        order.len()
                    ),
                ));
            }
            indices.extend(order.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        }
        Mode::TriangleStrip => {
            // glTF 2.0 §3.7.2.1: triangle i is (i, i+1, i+2) for even i,
            // (i, i+2, i+1) for odd i (keeps the winding).
            for i in 0..order.len().saturating_sub(2) {
                let (a, b, c) = (order[i], order[i + 1], order[i + 2]);
                indices.push(if i % 2 == 0 { [a, b, c] } else { [a, c, b] });
            }
        }
        _ => {
            // TRIANGLE_FAN: (i+1, i+2, 0).
            for i in 1..order.len().saturating_sub(1) {
                indices.push([order[i], order[i + 1], order[0]]);
            }
        }
    }
    // Degenerate triangles (repeated vertex) carry no surface.
    indices.retain(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
    Ok(Some(Triangles { positions, indices }))
}

/// The bytes of each element of a (non-sparse) accessor, bounds-checked
/// against its buffer view and buffer.
fn accessor_elements<'b>(
    acc: &::gltf::Accessor,
    buffers: &'b [Vec<u8>],
    loc: &Location,
) -> Result<Vec<&'b [u8]>> {
    let bad = |m: String| Error::parse(loc.clone(), m);
    if acc.sparse().is_some() {
        return Err(bad(format!(
            "accessor {} is sparse: not supported",
            acc.index()
        )));
    }
    let view = acc.view().ok_or_else(|| {
        bad(format!(
            "accessor {} has no bufferView: expected data",
            acc.index()
        ))
    })?;
    let data = buffers
        .get(view.buffer().index())
        .ok_or_else(|| bad(format!("buffer {} is missing", view.buffer().index())))?;
    let size = acc.size();
    let stride = view.stride().unwrap_or(size);
    let count = acc.count();
    let view_end = view.offset().checked_add(view.length());
    let start = view.offset().checked_add(acc.offset());
    let end = match (start, count) {
        (Some(s), 0) => Some(s),
        (Some(s), c) => (c - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(size))
            .and_then(|x| x.checked_add(s)),
        _ => None,
    };
    match (start, end, view_end) {
        (Some(s), Some(e), Some(ve)) if stride >= size && e <= ve && ve <= data.len() => Ok((0
            ..count)
            .map(|k| &data[s + k * stride..s + k * stride + size])
            .collect()),
        _ => Err(bad(format!(
            "accessor {} ({count} elements of {size} bytes, stride {stride}, offset {}) does \
             not fit its buffer view ({} bytes at {}) and buffer ({} bytes)",
            acc.index(),
            acc.offset(),
            view.length(),
            view.offset(),
            data.len()
        ))),
    }
}
