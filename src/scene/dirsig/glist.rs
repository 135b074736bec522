//! DIRSIG geometry lists (`.glist`, XML, root `<geometrylist>`; the same element inside
//! a `.scene`).
//!
//! A `<geometrylistinclude>` names a `.glist`, or an `.odb` or `.gdb` (by extension, else
//! by content). Each `<object>` has base geometry (`<basegeometry>` holding `<obj>`, `<gdb>`,
//! `<glist>` or `<odb>`, each with a `<filename>`; `<obj>` may `<assign id="ID">name</assign>`
//! its material names to `.mat` IDs) and instances. Files are looked up in the bundle's
//! folder for `search_paths="local"`, then the scene's geometry folders, then the list's
//! own folder. `<localmaterials>` gives a bundle its own `.mat`.
//!
//! Instances: `<staticinstance>` with `<translation>` (`<point>` x, y, z, m, or a
//! `<location type="scene|geodetic|ecef">` converted about the scene origin, see
//! [`super::scene_point`]; the rotation stays about the scene axes, which differ from the
//! local east-north-up axes at that point by the meridian convergence, under 0.01° per
//! kilometre at mid latitudes),
//! `<scale>` (`<cartesiantriple>`, or one number) and `<rotation>` (`<cartesiantriple>`,
//! degrees, about x then y then z: DIRSIG's fixed order, irsig's `rotate_deg`; an
//! `angularunits`/`units` of `radians` and a `rotationorder`/`order` other than `xyz`
//! are honoured), applied scale → rotation → translation; or a `<matrix>` of 16 numbers
//! (row by row, translation in the fourth column); an empty `<staticinstance/>` is the
//! identity. A `<dynamicinstance>` with a straight-line `<locationengine>` is placed at
//! its `<start>` (the image time is the start of the motion; the motion and the
//! orientation engine are dropped with a warning); other motions (`.mov` keyframes) are
//! dropped with a warning.
//!
//! Primitives: a `<box>` (`<matid>`, `<lowerextent>`, `<upperextent>`) becomes a
//! generated OBJ box (see [`box_obj`]).
//!
//! Dropped with a warning: disabled objects and lists (silently: they are off), point
//! sources (`<basesource>`), other primitives (`<sphere>`, `<cylinder>`, …), unknown
//! elements.
//!
//! Takes the XML; gives the importer's objects and instances.

use std::path::{Path, PathBuf};

use glam::{DMat3, DMat4, DVec3};
use roxmltree::Node;

use super::scene::SceneDirs;
use super::{Geo, Importer, MatCtx, Placement, euler, length_unit, xml};
use crate::error::{Error, Location, Result};
use crate::scene::file::{Scale, SiteSpec, TransformSpec};

/// How deep lists may nest (a list including itself is an error, not a hang).
pub(crate) const MAX_DEPTH: usize = 16;

impl Importer<'_> {
    /// Import the `.glist` file at `path`, placed at `parent`.
    pub(crate) fn glist_file(
        &mut self,
        path: &Path,
        dirs: &SceneDirs,
        mats: &MatCtx,
        parent: &Placement,
        depth: usize,
    ) -> Result<()> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let doc = xml::parse(&text, path)?;
        let root = doc.root_element();
        if !root.tag_name().name().eq_ignore_ascii_case("geometrylist") {
            return Err(Error::parse(
                xml::loc(path, root),
                format!(
                    "root element `<{}>`: expected `<geometrylist>` (a DIRSIG geometry list)",
                    root.tag_name().name()
                ),
            ));
        }
        if xml::disabled(root) {
            self.warn(xml::loc(path, root), "geometry list disabled: skipped");
            return Ok(());
        }
        self.glist_node(path, root, dirs, mats, parent, depth)
    }

    /// Import a `<geometrylist>` element of file `path`.
    pub(crate) fn glist_node(
        &mut self,
        path: &Path,
        list: Node,
        dirs: &SceneDirs,
        mats: &MatCtx,
        parent: &Placement,
        depth: usize,
    ) -> Result<()> {
        if depth > MAX_DEPTH {
            return Err(Error::parse(
                xml::loc(path, list),
                format!("geometry lists nest deeper than {MAX_DEPTH}: a list includes itself?"),
            ));
        }
        let here = path.parent().map(Path::to_path_buf).unwrap_or_default();
        for n in xml::elements(list) {
            match n.tag_name().name().to_ascii_lowercase().as_str() {
                "geometrylistinclude" => {
                    if xml::disabled(n) {
                        continue;
                    }
                    let name = xml::text(n);
                    let at = xml::loc(path, n);
                    let bases: Vec<PathBuf> = dirs
                        .geometry
                        .iter()
                        .cloned()
                        .chain([here.clone()])
                        .collect();
                    let p = self.find(&name, &bases, "geometry list", &at)?;
                    self.include(&p, dirs, mats, parent, depth, &at)?;
                }
                "object" => {
                    if xml::disabled(n) {
                        continue;
                    }
                    self.glist_object(path, n, dirs, mats, parent, depth)?;
                }
                "metadata" => {}
                other => self.warn(
                    xml::loc(path, n),
                    format!("`<{other}>` in a geometry list is not imported; dropped"),
                ),
            }
        }
        Ok(())
    }

    /// A `<geometrylistinclude>`: a `.glist`, or an `.odb` or `.gdb` (a scene's list
    /// "can point at GDB, GLIST, or ODB files": RIT's Tacoma scene includes
    /// `terrain.odb`, `tacoma.odb` and `targets.glist`, as protoDIRSIG's notebook
    /// `tutorial_tacoma_scene.ipynb` lists them), by extension, else by content (an
    /// `.odb` begins `DIRSIG_ODB`). A `.gdb` is placed as it is (metres).
    fn include(
        &mut self,
        p: &Path,
        dirs: &SceneDirs,
        mats: &MatCtx,
        parent: &Placement,
        depth: usize,
        at: &Location,
    ) -> Result<()> {
        let ext = p
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let kind = match ext.as_deref() {
            Some(e @ ("odb" | "gdb" | "obj" | "glist")) => e.to_string(),
            _ => {
                let head = std::fs::read(p).map_err(|e| Error::io(p, e))?;
                let head = String::from_utf8_lossy(&head[..head.len().min(256)]).to_string();
                if head
                    .trim_start()
                    .to_ascii_uppercase()
                    .starts_with("DIRSIG_ODB")
                {
                    "odb".into()
                } else {
                    "glist".into()
                }
            }
        };
        match kind.as_str() {
            "odb" => self.odb(p, dirs, mats, parent, depth + 1),
            "gdb" => self.place(&Geo::Gdb(p.to_path_buf()), mats, None, parent, at),
            "obj" => self.place(&Geo::Obj(p.to_path_buf()), mats, None, parent, at),
            _ => self.glist_file(p, dirs, mats, parent, depth + 1),
        }
    }

    fn glist_object(
        &mut self,
        path: &Path,
        obj: Node,
        dirs: &SceneDirs,
        mats: &MatCtx,
        parent: &Placement,
        depth: usize,
    ) -> Result<()> {
        let here = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let local = xml::attr(obj, "search_paths").is_some_and(|v| v.eq_ignore_ascii_case("local"));
        let mut bases: Vec<PathBuf> = Vec::new();
        if local {
            bases.push(here.clone());
        }
        bases.extend(dirs.geometry.iter().cloned());
        bases.push(here.clone());
        let mut mats = mats.clone();
        if let Some(lm) = xml::child(obj, "localmaterials") {
            let at = xml::loc(path, lm);
            let lbases = [here.clone()];
            let p = self.find(&xml::text(lm), &lbases, "local material database", &at)?;
            let ems = [p.parent().map(Path::to_path_buf).unwrap_or_default()];
            mats.lib = Some(self.library(&p, &ems, &at)?);
            mats.assign.clear();
        }
        // Instances.
        let mut placements = Vec::new();
        for n in xml::elements(obj) {
            match n.tag_name().name().to_ascii_lowercase().as_str() {
                "staticinstance" => placements.push(static_instance(path, n, self.site.as_ref())?),
                "dynamicinstance" => {
                    if let Some(p) = self.dynamic_instance(path, n)? {
                        placements.push(p);
                    }
                }
                "basegeometry" | "localmaterials" | "metadata" => {}
                "basesource" => self.warn(
                    xml::loc(path, n),
                    "sources (`<basesource>`, point sources) are not imported: irsig has no \
                     emitting sources; dropped",
                ),
                other => self.warn(
                    xml::loc(path, n),
                    format!("`<{other}>` in an object is not imported; dropped"),
                ),
            }
        }
        let Some(base) = xml::child(obj, "basegeometry") else {
            if xml::child(obj, "basesource").is_none() {
                self.warn(
                    xml::loc(path, obj),
                    "object without `<basegeometry>`: skipped",
                );
            }
            return Ok(());
        };
        if placements.is_empty() {
            self.warn(
                xml::loc(path, obj),
                "object without an instance irsig can place: not in the scene",
            );
            return Ok(());
        }
        for g in xml::elements(base) {
            let kind = g.tag_name().name().to_ascii_lowercase();
            let at = xml::loc(path, g);
            let file = || {
                xml::child(g, "filename").map(xml::text).ok_or_else(|| {
                    Error::parse(at.clone(), format!("`<{kind}>` needs a `<filename>`"))
                })
            };
            let unit = match xml::attr(g, "units").or_else(|| xml::attr(g, "unit")) {
                None => None,
                Some(u) => Some(length_unit(u).ok_or_else(|| {
                    Error::parse(
                        at.clone(),
                        format!(
                            "units `{u}`: expected METERS, CENTIMETERS, MILLIMETERS, INCHES or FEET"
                        ),
                    )
                })?),
            };
            match kind.as_str() {
                "obj" | "gdb" => {
                    let name = file()?;
                    let what = if kind == "obj" {
                        "OBJ file"
                    } else {
                        "GDB file"
                    };
                    let p = self.find(&name, &bases, what, &at)?;
                    let mut m = mats.clone();
                    for a in xml::children(g, "assign") {
                        let id = xml::attr(a, "id").ok_or_else(|| {
                            Error::parse(xml::loc(path, a), "`<assign>` needs an `id` attribute")
                        })?;
                        m.assign.insert(xml::text(a), id.to_string());
                    }
                    let geo = if kind == "obj" {
                        Geo::Obj(p)
                    } else {
                        Geo::Gdb(p)
                    };
                    for pl in &placements {
                        self.place(&geo, &m, unit, &parent.then(pl), &at)?;
                    }
                }
                "box" => {
                    let geo = box_obj(path, g)?;
                    for pl in &placements {
                        self.place(&geo, &mats, unit, &parent.then(pl), &at)?;
                    }
                }
                "glist" => {
                    let p = self.find(&file()?, &bases, "geometry list", &at)?;
                    for pl in &placements {
                        self.glist_file(&p, dirs, &mats, &parent.then(pl), depth + 1)?;
                    }
                }
                "odb" => {
                    let p = self.find(&file()?, &bases, "object database", &at)?;
                    for pl in &placements {
                        self.odb(&p, dirs, &mats, &parent.then(pl), depth + 1)?;
                    }
                }
                other => self.warn(
                    at,
                    format!(
                        "base geometry `<{other}>` (a DIRSIG primitive or other kind) is not \
                         imported; dropped"
                    ),
                ),
            }
        }
        Ok(())
    }

    /// A `<dynamicinstance>`: placed at the start of a straight-line motion; else dropped.
    fn dynamic_instance(&mut self, path: &Path, n: Node) -> Result<Option<Placement>> {
        let start = xml::path(n, &["motion", "locationengine", "start"]);
        let engine = xml::path(n, &["motion", "locationengine"]);
        let straight = engine
            .and_then(|e| xml::attr(e, "type"))
            .is_some_and(|t| t.eq_ignore_ascii_case("straight"));
        match (straight, start) {
            (true, Some(s)) => {
                if let Some(f) = xml::attr(s, "frame") {
                    if !f.eq_ignore_ascii_case("scene") {
                        self.warn(
                            xml::loc(path, s),
                            format!("motion start in frame `{f}`: only `scene` is imported; instance dropped"),
                        );
                        return Ok(None);
                    }
                }
                let p = xml::triple(path, s, 0.0)?;
                self.warn(
                    xml::loc(path, n),
                    format!(
                        "dynamic instance: placed at its start ({}, {}, {}) m, where it is at \
                         the image time (taken as the start of the motion); the motion \
                         (heading, velocity) and orientation engine are dropped",
                        p[0], p[1], p[2]
                    ),
                );
                Ok(Some(Placement::from_spec(TransformSpec {
                    translate: Some(p),
                    ..Default::default()
                })))
            }
            _ => {
                self.warn(
                    xml::loc(path, n),
                    "dynamic instance (keyframe `.mov` or a motion other than a straight line): \
                     irsig scenes are static; dropped",
                );
                Ok(None)
            }
        }
    }
}

/// A `<staticinstance>` (format in the module docs).
pub(crate) fn static_instance(
    path: &Path,
    n: Node,
    origin: Option<&SiteSpec>,
) -> Result<Placement> {
    if let Some(m) = xml::child(n, "matrix") {
        return matrix(path, m, &xml::text(m));
    }
    let mut spec = TransformSpec::default();
    let mut general: Option<DMat3> = None;
    if let Some(t) = xml::child(n, "translation") {
        spec.translate = Some(match xml::child(t, "location") {
            Some(l) => super::scene_point(path, l, origin)?.to_array(),
            None => xml::triple(path, t, 0.0)?,
        });
    }
    if let Some(s) = xml::child(n, "scale") {
        let t = xml::text(s);
        spec.scale = Some(
            if xml::elements(s).next().is_none() && t.parse::<f64>().is_ok() {
                Scale::Uniform(xml::number(path, s)?)
            } else {
                Scale::PerAxis(xml::triple(path, s, 1.0)?)
            },
        );
    }
    if let Some(r) = xml::child(n, "rotation") {
        let mut a = xml::triple(path, r, 0.0)?;
        let units = xml::attr(r, "angularunits")
            .or_else(|| xml::attr(r, "units"))
            .unwrap_or("degrees")
            .to_ascii_lowercase();
        match units.as_str() {
            "degrees" | "degree" | "deg" => {}
            "radians" | "radian" | "rad" => a = a.map(f64::to_degrees),
            other => {
                return Err(Error::parse(
                    xml::loc(path, r),
                    format!("rotation units `{other}`: expected degrees or radians"),
                ));
            }
        }
        let order = xml::attr(r, "rotationorder")
            .or_else(|| xml::attr(r, "order"))
            .unwrap_or("xyz")
            .to_ascii_lowercase();
        if order == "xyz" {
            spec.rotate_deg = Some(a);
        } else {
            general = Some(euler(&order, a.map(f64::to_radians)).ok_or_else(|| {
                Error::parse(
                    xml::loc(path, r),
                    format!("rotation order `{order}`: expected three of x, y, z (e.g. `zyx`)"),
                )
            })?);
        }
    }
    let p = Placement::from_spec(spec.clone());
    Ok(match general {
        None => p,
        Some(rot) => {
            // Scale, the general rotation, then translation.
            let s = match spec.scale {
                None => DVec3::ONE,
                Some(Scale::Uniform(s)) => DVec3::splat(s),
                Some(Scale::PerAxis(v)) => DVec3::from(v),
            };
            let t = DVec3::from(spec.translate.unwrap_or([0.0; 3]));
            Placement::from_matrix(
                DMat4::from_translation(t) * DMat4::from_mat3(rot * DMat3::from_diagonal(s)),
            )
        }
    })
}

/// A 4×4 matrix as 16 numbers (commas or blanks), row by row with the translation in
/// the fourth column; the transposed layout (translation in the last row) is accepted.
pub(crate) fn matrix(path: &Path, n: Node, text: &str) -> Result<Placement> {
    matrix_at(&xml::loc(path, n), text)
}

/// As [`matrix`], for any location.
pub(crate) fn matrix_at(at: &Location, text: &str) -> Result<Placement> {
    let v: Vec<f64> = text
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .map(str::parse)
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| {
            Error::parse(
                at.clone(),
                format!("matrix: expected 16 numbers, found `{text}`"),
            )
        })?;
    if v.len() != 16 || v.iter().any(|x| !x.is_finite()) {
        return Err(Error::parse(
            at.clone(),
            format!(
                "matrix: expected 16 finite numbers (4 rows of 4), found {}",
                v.len()
            ),
        ));
    }
    let rows = DMat4::from_cols_array(&v.clone().try_into().expect("16")).transpose();
    let m = if v[12..16] == [0.0, 0.0, 0.0, 1.0] {
        rows
    } else if [v[3], v[7], v[11], v[15]] == [0.0, 0.0, 0.0, 1.0] {
        rows.transpose()
    } else {
        return Err(Error::parse(
            at.clone(),
            "matrix: neither the last row nor the last column is 0, 0, 0, 1: not an affine transform",
        ));
    };
    if !(m.determinant().is_finite() && m.determinant() > 0.0) {
        return Err(Error::parse(
            at.clone(),
            format!(
                "matrix has determinant {}: expected > 0 (no zero or mirroring scale)",
                m.determinant()
            ),
        ));
    }
    Ok(Placement::from_matrix(m))
}

/// A `<box>` primitive (`<matid>`, `<lowerextent>` and `<upperextent>` points, m, in the
/// instance's frame; the GeoLocation1 demo's ground) as a closed OBJ box of six quads
/// facing outward, all of material `matid`.
pub(crate) fn box_obj(path: &Path, n: Node) -> Result<Geo> {
    let id = xml::child(n, "matid")
        .map(xml::text)
        .filter(|t| !t.is_empty())
        .ok_or_else(|| Error::parse(xml::loc(path, n), "`<box>` needs a `<matid>`"))?;
    let corner = |name: &str| -> Result<[f64; 3]> {
        let c = xml::child(n, name).ok_or_else(|| {
            Error::parse(xml::loc(path, n), format!("`<box>` needs a `<{name}>`"))
        })?;
        xml::triple(path, c, 0.0)
    };
    let (lo, hi) = (corner("lowerextent")?, corner("upperextent")?);
    if (0..3).any(|k| lo[k] >= hi[k]) {
        return Err(Error::parse(
            xml::loc(path, n),
            format!(
                "`<box>` extents ({}, {}, {}) .. ({}, {}, {}): each lower value must be below \
                 the upper one",
                lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
            ),
        ));
    }
    let mut obj = String::from("# DIRSIG <box> primitive\n");
    for z in [lo[2], hi[2]] {
        for (x, y) in [
            (lo[0], lo[1]),
            (hi[0], lo[1]),
            (hi[0], hi[1]),
            (lo[0], hi[1]),
        ] {
            obj += &format!("v {x} {y} {z}\n");
        }
    }
    obj += &format!("usemtl {id}\n");
    // Counter-clockwise seen from outside: −z, +z, −y, +y, −x, +x.
    for f in [
        [1, 4, 3, 2],
        [5, 6, 7, 8],
        [1, 2, 6, 5],
        [3, 4, 8, 7],
        [4, 1, 5, 8],
        [2, 3, 7, 6],
    ] {
        obj += &format!("f {} {} {} {}\n", f[0], f[1], f[2], f[3]);
    }
    Ok(Geo::Prim {
        kind: "box".into(),
        obj,
        id,
        src: path.to_path_buf(),
    })
}
