//! DIRSIG object databases (`.odb`, text; DIRSIG documentation "Object Database").
//!
//! ```text
//! DIRSIG_ODB = 1.0
//! OBJECT {
//!     GDB_FILENAME = building.gdb        (or OBJ_FILENAME, or ODB_FILENAME: nested)
//!     UNITS = INCHES                     (METERS, CENTIMETERS, MILLIMETERS, FEET)
//!     INSTANCES {
//!         INFO = tx, ty, tz, sx, sy, sz, rx, ry, rz
//!         INFO = m11 m12 m13 m14 m21 … m44
//!         INFO = path.mov
//!     }
//! }
//! ```
//!
//! An `INFO` of 9 numbers is translation (m), scale, and rotations about x, y, z in
//! degrees, applied scale → rotation (x, then y, then z) → translation, as a `.glist`
//! static instance; 16 numbers are a 4×4 matrix (row by row, translation in the fourth
//! column); a `.mov` keyframe file is a moving instance, dropped with a warning. `UNITS`
//! is the unit of the geometry file's coordinates (irsig's shape `unit`); translations
//! are scene metres. Geometry files are relative to the scene's geometry folders, then
//! the `.odb` file's folder. Other top-level blocks are dropped with a warning.
//!
//! Takes the text; gives the importer's objects and instances.

use std::path::{Path, PathBuf};

use super::glist::{MAX_DEPTH, matrix_at};
use super::scene::SceneDirs;
use super::{Geo, Importer, MatCtx, Placement, length_unit};
use crate::error::{Error, Location, Result};
use crate::material::dirsig::parse_blocks;
use crate::scene::file::{Scale, TransformSpec};

impl Importer<'_> {
    /// Import the `.odb` file at `path`, placed at `parent`.
    pub(crate) fn odb(
        &mut self,
        path: &Path,
        dirs: &SceneDirs,
        mats: &MatCtx,
        parent: &Placement,
        depth: usize,
    ) -> Result<()> {
        if depth > MAX_DEPTH {
            return Err(Error::parse(
                Location::file(path),
                format!("object databases nest deeper than {MAX_DEPTH}: one includes itself?"),
            ));
        }
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let root = parse_blocks(&text, path)?;
        if root.get("DIRSIG_ODB").is_none() {
            self.warn(
                Location::file(path).at_line(1),
                "no `DIRSIG_ODB = 1.0` header: read as an object database anyway",
            );
        }
        let here = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let bases: Vec<PathBuf> = dirs.geometry.iter().cloned().chain([here]).collect();
        for (k, _, line) in &root.entries {
            if !k.eq_ignore_ascii_case("DIRSIG_ODB") {
                self.warn(
                    Location::file(path).at_line(*line).with_field(k.as_str()),
                    format!("`{k}` is not imported; dropped"),
                );
            }
        }
        for b in &root.children {
            let at = |line: usize| Location::file(path).at_line(line);
            if !b.name.eq_ignore_ascii_case("OBJECT") {
                self.warn(
                    at(b.line),
                    format!(
                        "`{}` block is not imported (irsig reads OBJECT blocks); dropped",
                        b.name
                    ),
                );
                continue;
            }
            let unit = match b.get("UNITS") {
                None => None,
                Some((u, l)) => Some(length_unit(u).ok_or_else(|| {
                    Error::parse(
                        at(l).with_field("UNITS"),
                        format!("`{u}`: expected METERS, CENTIMETERS, MILLIMETERS, INCHES or FEET"),
                    )
                })?),
            };
            let file = ["GDB_FILENAME", "OBJ_FILENAME", "ODB_FILENAME"]
                .iter()
                .find_map(|k| b.get(k).map(|(v, l)| (*k, v.to_string(), l)));
            let Some((key, name, fl)) = file else {
                return Err(Error::parse(
                    at(b.line),
                    "OBJECT block without GDB_FILENAME, OBJ_FILENAME or ODB_FILENAME",
                ));
            };
            let mut placements = Vec::new();
            match b.child("INSTANCES") {
                None => {
                    return Err(Error::parse(
                        at(b.line),
                        "OBJECT block without an `INSTANCES { INFO = … }` block",
                    ));
                }
                Some(inst) => {
                    for (k, v, l) in &inst.entries {
                        if !k.eq_ignore_ascii_case("INFO") {
                            self.warn(
                                at(*l).with_field(k.as_str()),
                                format!("`{k}` is not imported; dropped"),
                            );
                            continue;
                        }
                        if let Some(p) = self.info(&at(*l).with_field("INFO"), v)? {
                            placements.push(p);
                        }
                    }
                }
            }
            let loc = at(fl).with_field(key);
            match key {
                "ODB_FILENAME" => {
                    let p = self.find(&name, &bases, "object database", &loc)?;
                    for pl in &placements {
                        self.odb(&p, dirs, mats, &parent.then(pl), depth + 1)?;
                    }
                }
                _ => {
                    let what = if key == "GDB_FILENAME" {
                        "GDB file"
                    } else {
                        "OBJ file"
                    };
                    let p = self.find(&name, &bases, what, &loc)?;
                    let geo = if key == "GDB_FILENAME" {
                        Geo::Gdb(p)
                    } else {
                        Geo::Obj(p)
                    };
                    for pl in &placements {
                        self.place(&geo, mats, unit, &parent.then(pl), &loc)?;
                    }
                }
            }
        }
        Ok(())
    }

    /// One `INFO` value (format in the module docs); `None` for a dropped `.mov`.
    fn info(&mut self, at: &Location, v: &str) -> Result<Option<Placement>> {
        let t = v.trim();
        if t.to_ascii_lowercase().ends_with(".mov") {
            self.warn(
                at.clone(),
                format!("moving instance `{t}` (keyframe file): irsig scenes are static; dropped"),
            );
            return Ok(None);
        }
        let n: Vec<&str> = t
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .collect();
        match n.len() {
            9 => {
                let x: Vec<f64> = n
                    .iter()
                    .map(|s| s.parse::<f64>())
                    .collect::<std::result::Result<_, _>>()
                    .ok()
                    .filter(|x: &Vec<f64>| x.iter().all(|v| v.is_finite()))
                    .ok_or_else(|| {
                        Error::parse(at.clone(), format!("expected 9 numbers, found `{t}`"))
                    })?;
                if x[3..6].iter().any(|s| *s <= 0.0) {
                    return Err(Error::parse(
                        at.clone(),
                        format!("scale {}, {}, {}: expected > 0", x[3], x[4], x[5]),
                    ));
                }
                Ok(Some(Placement::from_spec(TransformSpec {
                    translate: Some([x[0], x[1], x[2]]),
                    scale: Some(Scale::PerAxis([x[3], x[4], x[5]])),
                    rotate_deg: Some([x[6], x[7], x[8]]),
                    matrix: None,
                })))
            }
            16 => matrix_at(at, t).map(Some),
            k => Err(Error::parse(
                at.clone(),
                format!(
                    "expected 9 numbers (translation, scale, rotation in degrees), 16 (a 4×4 \
                     matrix) or a `.mov` file, found {k} value(s): `{t}`"
                ),
            )),
        }
    }
}
