//! DIRSIG geometric databases (`.gdb`, text; DIRSIG manual "GDB file format"), turned
//! into OBJ text irsig's OBJ reader takes.
//!
//! One item per line, in a hierarchy ended by `END`:
//!
//! ```text
//! OBJECT  name  1-0-0
//! PART    name  1-1-0
//! FACE    name  1-1-1  material_name  material_id  [facet_name]
//!         temperature_°C (−1: THERM)  thickness_cm  power  exposed_area  NULL NULL NULL
//!         vertex_count (3 or 4)  x y z (one line per vertex)  nx ny nz  zenith  azimuth  [0]
//! ```
//!
//! Keywords are case-insensitive (`FACE` or `FACET`); the unused facet name and the
//! `NULL` fields may be absent. Each facet's material is its material ID (the `.mat`
//! ID); a facet temperature other than −1 °C is a fixed temperature (a part with
//! `fixed_temperature_k` = T + 273.15). Vertex order gives the front face
//! (counter-clockwise seen from the front, as OBJ); the stored normal, zenith and azimuth
//! are not used (one warning when a stored normal disagrees with the vertex order). The
//! per-facet thickness, power and exposed area are not used (DIRSIG ≥ 3.1 takes them from
//! the material; one warning when any is non-zero).
//!
//! Takes a `.gdb` path; gives OBJ text with one `usemtl` group per material ID (and
//! fixed temperature).

use std::fmt::Write as _;
use std::path::Path;

use glam::DVec3;

use crate::error::{Error, Location, Result};

/// Per `usemtl` group: its name, its `.mat` ID, its fixed temperature (K) if any.
pub type Groups = Vec<(String, String, Option<f64>)>;

/// A `.gdb` file as OBJ.
#[derive(Debug, Clone)]
pub struct GdbObj {
    /// OBJ text: `v` and `f` lines in `usemtl` groups.
    pub obj: String,
    /// Per group: its `usemtl` name, its `.mat` ID, its fixed temperature (K) if any.
    pub groups: Groups,
    /// What was not used, naming file and line.
    pub warnings: Vec<String>,
}

/// Read a `.gdb` file (format in the module docs).
pub fn to_obj(path: &Path) -> Result<GdbObj> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    from_str(&text, path)
}

/// As [`to_obj`] for text in memory.
pub fn from_str(text: &str, path: &Path) -> Result<GdbObj> {
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(n, l)| (n + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
        .collect();
    let at = |n: usize| Location::file(path).at_line(n);
    let kw = |l: &str| {
        l.split_whitespace()
            .next()
            .unwrap_or("")
            .to_ascii_uppercase()
    };
    let num = |(n, l): (usize, &str), what: &str| -> Result<f64> {
        l.split_whitespace()
            .next()
            .and_then(|t| t.parse::<f64>().ok())
            .filter(|v| v.is_finite())
            .ok_or_else(|| Error::parse(at(n), format!("{what}: expected a number, found `{l}`")))
    };
    let vec3 = |(n, l): (usize, &str), what: &str| -> Result<DVec3> {
        let v: Vec<f64> = l
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .map(str::parse)
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| Error::parse(at(n), format!("{what}: expected `x y z`, found `{l}`")))?;
        if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
            return Err(Error::parse(
                at(n),
                format!("{what}: expected 3 numbers, found `{l}`"),
            ));
        }
        Ok(DVec3::new(v[0], v[1], v[2]))
    };
    let mut out = GdbObj {
        obj: format!("# converted by irsig from DIRSIG GDB {}\n", path.display()),
        groups: Vec::new(),
        warnings: Vec::new(),
    };
    // Per group (usemtl name): its faces (vertex indices, 1-based).
    let mut faces: Vec<Vec<Vec<usize>>> = Vec::new();
    let mut verts: Vec<DVec3> = Vec::new();
    let (mut warned_attr, mut warned_normal) = (false, false);
    let mut i = 0;
    let next = |i: &mut usize, what: &str| -> Result<(usize, &str)> {
        let r = lines.get(*i).copied().ok_or_else(|| {
            Error::parse(
                Location::file(path),
                format!("file ends inside a facet: expected {what}"),
            )
        })?;
        *i += 1;
        Ok(r)
    };
    let mut seen_object = false;
    while i < lines.len() {
        let (n, l) = lines[i];
        match kw(l).as_str() {
            "END" => break,
            "OBJECT" | "PART" => {
                seen_object |= kw(l) == "OBJECT";
                // Keyword, then name and ID lines (or the same line).
                i += match l.split_whitespace().count() {
                    1 => 3,
                    2 => 2,
                    _ => 1,
                };
            }
            "FACE" | "FACET" => {
                if !seen_object {
                    return Err(Error::parse(at(n), "FACE before any OBJECT"));
                }
                i += 1;
                let _name = next(&mut i, "the facet name")?;
                let _id = next(&mut i, "the facet ID")?;
                let _mat_name = next(&mut i, "the material name")?;
                let (mn, mat_id) = next(&mut i, "the material ID")?;
                let mat_id = mat_id.split_whitespace().next().unwrap_or("").to_string();
                if mat_id.is_empty() {
                    return Err(Error::parse(at(mn), "empty material ID"));
                }
                // Optional unused facet name (not a number).
                if lines.get(i).is_some_and(|(_, l)| {
                    l.split_whitespace()
                        .next()
                        .and_then(|t| t.parse::<f64>().ok())
                        .is_none()
                }) {
                    i += 1;
                }
                let temp_c = num(next(&mut i, "the temperature")?, "facet temperature (°C)")?;
                let mut attrs = [0.0; 3];
                for (k, what) in ["thickness", "power", "exposed area"].iter().enumerate() {
                    attrs[k] = num(next(&mut i, what)?, what)?;
                }
                if attrs.iter().any(|a| *a != 0.0) && !warned_attr {
                    warned_attr = true;
                    out.warnings.push(
                        Error::parse(
                            at(n),
                            "per-facet thickness, power and exposed area are not used (DIRSIG ≥ 3.1 \
                             takes them from the material); dropped (noted once per file)",
                        )
                        .to_string(),
                    );
                }
                while lines
                    .get(i)
                    .is_some_and(|(_, l)| l.eq_ignore_ascii_case("null"))
                {
                    i += 1;
                }
                let (cn, cl) = next(&mut i, "the vertex count")?;
                let count = num((cn, cl), "vertex count")?;
                if count != 3.0 && count != 4.0 {
                    return Err(Error::parse(
                        at(cn),
                        format!("vertex count {count}: expected 3 or 4"),
                    ));
                }
                let first = verts.len() + 1;
                let mut poly = Vec::new();
                for k in 0..count as usize {
                    let v = vec3(next(&mut i, "a vertex")?, &format!("vertex {}", k + 1))?;
                    verts.push(v);
                    poly.push(first + k);
                }
                let (nn, nl) = next(&mut i, "the normal")?;
                let normal = vec3((nn, nl), "normal")?;
                let p: Vec<DVec3> = poly.iter().map(|&k| verts[k - 1]).collect();
                let geo = (p[1] - p[0]).cross(p[2] - p[0]);
                if geo.dot(normal) < 0.0 && !warned_normal {
                    warned_normal = true;
                    out.warnings.push(
                        Error::parse(
                            at(nn),
                            "a stored facet normal points against its vertex order; irsig uses \
                             the vertex order (counter-clockwise = front) (noted once per file)",
                        )
                        .to_string(),
                    );
                }
                // Zenith, azimuth and any unused numbers up to the next keyword.
                while lines.get(i).is_some_and(|(_, l)| {
                    !matches!(kw(l).as_str(), "FACE" | "FACET" | "PART" | "OBJECT" | "END")
                }) {
                    i += 1;
                }
                let fixed = (temp_c != -1.0).then_some(temp_c + 273.15);
                let group = match fixed {
                    None => mat_id.clone(),
                    Some(_) => format!("{mat_id}_at_{temp_c}C"),
                };
                let g = match out.groups.iter().position(|(name, _, _)| *name == group) {
                    Some(g) => g,
                    None => {
                        out.groups.push((group, mat_id, fixed));
                        faces.push(Vec::new());
                        out.groups.len() - 1
                    }
                };
                faces[g].push(poly);
            }
            other => {
                return Err(Error::parse(
                    at(n),
                    format!("expected OBJECT, PART, FACE or END, found `{other}`"),
                ));
            }
        }
    }
    if verts.is_empty() {
        return Err(Error::parse(
            Location::file(path),
            "no facets: not a DIRSIG GDB file?",
        ));
    }
    for v in &verts {
        let _ = writeln!(out.obj, "v {} {} {}", v.x, v.y, v.z);
    }
    for (g, fs) in out.groups.iter().zip(&faces) {
        let _ = writeln!(out.obj, "g {}\nusemtl {}", g.0, g.0);
        for f in fs {
            let idx: Vec<String> = f.iter().map(usize::to_string).collect();
            let _ = writeln!(out.obj, "f {}", idx.join(" "));
        }
    }
    Ok(out)
}
