//! Wavefront OBJ loading (through `tobj`), triangulated, one [`ObjGroup`]
//! per object/group and material, or as bare geometry
//! ([`load_obj_geometry`]). Knows nothing of materials' properties or of
//! the scene file around the OBJ.
//!
//! The `usemtl` names are kept even when the `.mtl` file is absent (irsig
//! maps them to its own material database, not to the MTL's colours): the
//! text is handed to `tobj` with a synthetic material library naming every
//! `usemtl` in the file.

use std::io::Cursor;
use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Location, Result};
use crate::geometry::{Instance, SceneGeometry, TriangleMesh};

/// One group of an OBJ file: the faces of one `o`/`g` name and `usemtl`.
#[derive(Debug, Clone)]
pub struct ObjGroup {
    /// The object/group name (`o` or `g`), or `"unnamed"`.
    pub name: String,
    /// The `usemtl` name in effect, if any.
    pub material_name: Option<String>,
    /// The triangles (polygons fan-triangulated), in the file's units.
    pub mesh: TriangleMesh,
}

/// Load an OBJ file as scene geometry in its own units: one mesh per
/// group, each instanced once in place (materials ignored).
///
/// # Errors
/// Those of [`load_obj`], and [`Error::Parse`] naming the file when it has
/// no faces.
pub fn load_obj_geometry(path: &Path) -> Result<SceneGeometry> {
    let mut geom = SceneGeometry::default();
    for g in load_obj(path)? {
        geom.meshes.push(g.mesh);
        geom.instances.push(Instance {
            mesh: geom.meshes.len() - 1,
            world_from_object: glam::Affine3A::IDENTITY,
        });
    }
    if geom.facet_count() == 0 {
        return Err(Error::parse(
            Location::file(path),
            "the OBJ file has no faces (expected `f` lines)",
        ));
    }
    Ok(geom)
}

/// Load an OBJ file as triangulated groups. Errors name the file (and, for
/// malformed numbers or indices found by a pre-scan, the line).
pub fn load_obj(path: &Path) -> Result<Vec<ObjGroup>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    load_obj_str(&text, path)
}

/// Load OBJ text; `path` is used in error messages only.
///
/// Files of plain geometry (only `v x y z`, `f` with bare vertex indices,
/// `o`, `g`, comments and blank lines: what exporters write for large
/// terrains) take a one-pass parser ([`load_obj_plain`]), ≈ 5× faster;
/// anything else, and any error, goes through the reference path
/// ([`load_obj_reference`]: a line-checking pre-scan, then `tobj`), which
/// the fast path equals group for group (tested).
pub fn load_obj_str(text: &str, path: &Path) -> Result<Vec<ObjGroup>> {
    match load_obj_plain(text) {
        Some(groups) if !groups.is_empty() => Ok(groups),
        _ => load_obj_reference(text, path),
    }
}

/// The one-pass parser of plain-geometry OBJ text (see [`load_obj_str`]):
/// `None` for any other line or any error, so that the caller falls back
/// to [`load_obj_reference`], which reports it with its line. Gives what
/// `tobj` gives for such a file with triangulation and single indexing:
/// a group per `o`/`g` that has faces, polygons fan-triangulated
/// `(a, b, c), (a, c, d), …`, each group's vertices in the order its faces
/// first use them, coordinates parsed as `f32` by the standard library.
pub fn load_obj_plain(text: &str) -> Option<Vec<ObjGroup>> {
    const NONE: u32 = u32::MAX;
    let mut all: Vec<Vec3> = Vec::new();
    let mut out: Vec<ObjGroup> = Vec::new();
    // The group being read: name, its vertices (global → local index),
    // positions and triangles.
    // `tobj`'s name for faces before any `o`/`g`.
    let mut name = String::from("unnamed_object");
    let mut local: Vec<u32> = Vec::new();
    let mut positions: Vec<Vec3> = Vec::new();
    let mut indices: Vec<[u32; 3]> = Vec::new();
    // Global indices of the group's vertices, to reset `local` after it.
    let mut used: Vec<u32> = Vec::new();
    let mut face: Vec<u32> = Vec::with_capacity(8);
    let finish = |name: &str,
                  positions: &mut Vec<Vec3>,
                  indices: &mut Vec<[u32; 3]>,
                  local: &mut Vec<u32>,
                  used: &mut Vec<u32>,
                  out: &mut Vec<ObjGroup>| {
        for &g in used.iter() {
            local[g as usize] = NONE;
        }
        used.clear();
        if indices.is_empty() {
            return;
        }
        out.push(ObjGroup {
            name: name.to_string(),
            material_name: None,
            mesh: TriangleMesh {
                name: name.to_string(),
                positions: std::mem::take(positions),
                indices: std::mem::take(indices),
            },
        });
    };
    for raw in text.lines() {
        let mut it = raw.split_ascii_whitespace();
        match it.next() {
            None => {}
            Some(w) if w.starts_with('#') => {}
            Some("v") => {
                let mut p = [0f32; 3];
                for c in &mut p {
                    *c = it.next()?.parse::<f32>().ok().filter(|x| x.is_finite())?;
                }
                if it.next().is_some() {
                    return None;
                }
                all.push(Vec3::from_array(p));
            }
            Some("f") => {
                face.clear();
                let n = all.len() as i64;
                for s in it {
                    let i: i64 = s.parse().ok()?;
                    let g = if i > 0 && i <= n {
                        i - 1
                    } else if i < 0 && -i <= n {
                        n + i
                    } else {
                        return None;
                    };
                    if local.len() < all.len() {
                        local.resize(all.len(), NONE);
                    }
                    let l = &mut local[g as usize];
                    if *l == NONE {
                        *l = u32::try_from(positions.len()).ok()?;
                        positions.push(all[g as usize]);
                        used.push(u32::try_from(g).ok()?);
                    }
                    face.push(*l);
                }
                if face.len() < 3 {
                    return None;
                }
                for k in 2..face.len() {
                    indices.push([face[0], face[k - 1], face[k]]);
                }
            }
            Some("o" | "g") => {
                // `tobj` takes the rest of the line after the keyword.
                if !(raw.starts_with('o') || raw.starts_with('g')) {
                    return None;
                }
                finish(
                    &name,
                    &mut positions,
                    &mut indices,
                    &mut local,
                    &mut used,
                    &mut out,
                );
                name = raw[1..].trim().to_string();
                if name.is_empty() {
                    name = "unnamed_object".to_string();
                }
            }
            Some(_) => return None,
        }
    }
    finish(
        &name,
        &mut positions,
        &mut indices,
        &mut local,
        &mut used,
        &mut out,
    );
    Some(out)
}

/// The reference OBJ reader: a pre-scan that checks every line (naming it
/// in errors) and collects the `usemtl` names, then `tobj`.
pub fn load_obj_reference(text: &str, path: &Path) -> Result<Vec<ObjGroup>> {
    // Pre-scan: usemtl names, and line-precise checks tobj does not report.
    let mut names: Vec<String> = Vec::new();
    let mut nverts = 0usize;
    let (mut ntex, mut nnorm) = (0usize, 0usize);
    let mut body = String::with_capacity(text.len() + 32);
    body.push_str("mtllib irsig-usemtl-names\n");
    for (n, raw) in text.lines().enumerate() {
        let line = raw.trim();
        let loc = || Location::file(path).at_line(n + 1);
        let mut it = line.split_whitespace();
        match it.next() {
            Some("mtllib") => {
                // The real MTL only carries colours; skip it.
                body.push('\n');
                continue;
            }
            Some("usemtl") => {
                let name = line["usemtl".len()..].trim().to_string();
                if name.is_empty() {
                    return Err(Error::parse(loc(), "`usemtl` without a material name"));
                }
                if !names.contains(&name) {
                    names.push(name);
                }
            }
            Some("v") => {
                let v: Vec<&str> = it.collect();
                if v.len() < 3
                    || v[..3]
                        .iter()
                        .any(|s| s.parse::<f32>().map_or(true, |x| !x.is_finite()))
                {
                    return Err(Error::parse(
                        loc(),
                        format!("vertex needs 3 finite numbers `v x y z`, found `{line}`"),
                    ));
                }
                nverts += 1;
            }
            // Texture coordinates and normals: counted (and required to be
            // numbers, as tobj reads them) so face indices can be checked;
            // tobj multiplies unchecked indices (overflow, issue 8 fuzzing).
            Some(kw @ ("vt" | "vn")) => {
                let need = if kw == "vt" { 2 } else { 3 };
                let v: Vec<&str> = it.collect();
                if v.len() < need
                    || v[..need]
                        .iter()
                        .any(|s| s.parse::<f32>().map_or(true, |x| !x.is_finite()))
                {
                    return Err(Error::parse(
                        loc(),
                        format!("`{kw}` needs {need} finite number(s), found `{line}`"),
                    ));
                }
                if kw == "vt" {
                    ntex += 1;
                } else {
                    nnorm += 1;
                }
            }
            Some("f") => {
                let idx: Vec<&str> = it.collect();
                if idx.len() < 3 {
                    return Err(Error::parse(
                        loc(),
                        format!("face needs at least 3 vertices, found `{line}`"),
                    ));
                }
                for s in idx {
                    // `v`, `v/vt`, `v//vn` or `v/vt/vn`; empty parts are absent.
                    for (k, (part, what, have)) in s
                        .split('/')
                        .zip([("vertex", nverts), ("texture", ntex), ("normal", nnorm)])
                        .map(|(p, (w, h))| (p, w, h))
                        .enumerate()
                    {
                        if k > 0 && part.is_empty() {
                            continue;
                        }
                        let i: i64 = part
                            .parse()
                            .map_err(|_| Error::parse(loc(), format!("bad face vertex `{s}`")))?;
                        // Texture/normal indices with none defined yet are
                        // ignored by tobj (as the bundled files rely on), but
                        // must stay small enough not to overflow in it.
                        let ok = if i > 0 {
                            i as usize <= have || (k > 0 && have == 0 && i <= i64::from(u32::MAX))
                        } else {
                            i < 0 && i.unsigned_abs() as usize <= have
                        };
                        if !ok {
                            return Err(Error::parse(
                                loc(),
                                format!(
                                    "face {what} index {i} refers to a {what} not defined before (have {have})"
                                ),
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
        body.push_str(raw);
        body.push('\n');
    }
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let mtl_names = names.clone();
    let (models, _) = tobj::load_obj_buf(&mut Cursor::new(body.as_bytes()), &opts, move |_| {
        let mats: Vec<tobj::Material> = mtl_names
            .iter()
            .map(|n| tobj::Material {
                name: n.clone(),
                ..Default::default()
            })
            .collect();
        let map = mtl_names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.clone(), i))
            .collect();
        Ok((mats, map))
    })
    .map_err(|e| Error::parse(Location::file(path), format!("invalid OBJ: {e}")))?;
    let mut out = Vec::with_capacity(models.len());
    for m in models {
        let p = &m.mesh.positions;
        let positions: Vec<Vec3> = p
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect();
        let indices: Vec<[u32; 3]> = m
            .mesh
            .indices
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        if indices.is_empty() {
            continue;
        }
        let name = if m.name.is_empty() {
            "unnamed".to_string()
        } else {
            m.name
        };
        out.push(ObjGroup {
            material_name: m.mesh.material_id.map(|i| names[i].clone()),
            mesh: TriangleMesh {
                name: name.clone(),
                positions,
                indices,
            },
            name,
        });
    }
    if out.is_empty() {
        return Err(Error::parse(Location::file(path), "OBJ file has no faces"));
    }
    Ok(out)
}
