//! DIRSIG4 `.scene` files (XML, root `<classicscene>`): the scene origin (geodetic),
//! the geometry and material folders (`$SCENE_DIR` is the `.scene` file's folder), the
//! `<geometrylist>` includes and the material database (`<matfilename>`, emissivity
//! files under `<emsdirectory>`).
//!
//! Mapped: `<sceneorigin>` → `site`; `<geometrylist>` (`<geometrylistinclude>`s, and
//! `<object>`s written inline) → objects; `<odbfilename>` → objects; `<matfilename>` →
//! materials; `<metadata>` `Name` → description. Warned and dropped: enabled material
//! and texture maps (`<maplist>`), other origin frames.
//!
//! Takes the `.scene` XML; gives the importer's site, materials and objects.

use std::path::{Path, PathBuf};

use roxmltree::Node;

use super::{Importer, MatCtx, Placement, xml};
use crate::error::{Error, Result};
use crate::scene::file::SiteSpec;

/// Folders of a scene: where geometry lists and geometry files are looked up.
#[derive(Debug, Clone, Default)]
pub(crate) struct SceneDirs {
    /// `<gdbdirectory>`, `<odbdirectory>`, then the `.scene` folder.
    pub geometry: Vec<PathBuf>,
}

impl Importer<'_> {
    /// Import the `.scene` at `path` (root element `root`).
    pub(crate) fn scene(&mut self, path: &Path, root: Node) -> Result<()> {
        if self.scene_seen {
            self.warn(
                xml::loc(path, root),
                "a second scene: irsig imports the first of a simulation's scenes only",
            );
            return Ok(());
        }
        self.scene_seen = true;
        // Absolute: `$SCENE_DIR/…` expands to a path that must not be joined to the
        // scene's folder a second time when the scene was named relative to the
        // working directory.
        let dir = path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        let dir = std::path::absolute(&dir).unwrap_or(dir);
        let vars = [("SCENE_DIR", dir.as_path())];
        self.scene_dir = Some(dir.clone());
        let folder = |n: Option<Node>| {
            n.map(|n| PathBuf::from(Importer::expand(&xml::text(n), &vars)))
                .filter(|p| !p.as_os_str().is_empty())
                .map(|p| if p.is_absolute() { p } else { dir.join(p) })
        };
        // Site.
        let origin = xml::child(root, "sceneorigin").ok_or_else(|| {
            Error::parse(
                xml::loc(path, root),
                "no `<sceneorigin>`: irsig needs the scene's latitude and longitude",
            )
        })?;
        let loc_node = xml::child(origin, "location").unwrap_or(origin);
        if let Some(f) = xml::attr(loc_node, "frame") {
            if !f.eq_ignore_ascii_case("geodetic") {
                return Err(Error::parse(
                    xml::loc(path, loc_node),
                    format!("scene origin frame `{f}`: irsig imports `geodetic` origins only"),
                ));
            }
        }
        let lat = xml::req_number(path, loc_node, "latitude")?;
        let lon = xml::req_number(path, loc_node, "longitude")?;
        let alt = xml::opt_number(path, loc_node, "altitude")?.unwrap_or(0.0);
        for (name, v, max) in [("latitude", lat, 90.0), ("longitude", lon, 180.0)] {
            if v.abs() > max {
                let at = xml::child(loc_node, name).unwrap_or(loc_node);
                return Err(Error::parse(
                    xml::loc(path, at),
                    format!("{name} {v}°: expected −{max}..={max} (degrees, east positive)"),
                ));
            }
        }
        self.site = Some(SiteSpec {
            latitude_deg: lat,
            longitude_deg: lon,
            altitude_m: alt,
            utc_offset_hours: 0.0,
        });
        // Description.
        if let Some(md) = xml::child(root, "metadata") {
            for e in xml::children(md, "entry") {
                let name = xml::child(e, "name").map(xml::text).unwrap_or_default();
                if name.eq_ignore_ascii_case("name") {
                    self.description = xml::child(e, "value").map(xml::text);
                }
            }
        }
        // Folders.
        let mut dirs = SceneDirs::default();
        for tag in ["gdbdirectory", "odbdirectory"] {
            if let Some(d) = folder(xml::child(root, tag)) {
                if !dirs.geometry.contains(&d) {
                    dirs.geometry.push(d);
                }
            }
        }
        dirs.geometry.push(dir.clone());
        let mut ems_dirs: Vec<PathBuf> = folder(xml::child(root, "emsdirectory"))
            .into_iter()
            .collect();
        // Materials.
        let mut mats = MatCtx::default();
        let mat_nodes: Vec<Node> = xml::elements(root)
            .filter(|n| {
                let t = n.tag_name().name().to_ascii_lowercase();
                t == "matfilename" || t == "materialdatabase"
            })
            .collect();
        for (i, m) in mat_nodes.iter().enumerate() {
            let name = Importer::expand(&xml::text(*m), &vars);
            let at = xml::loc(path, *m);
            let p = self.find(&name, std::slice::from_ref(&dir), "material database", &at)?;
            if let Some(d) = p.parent() {
                ems_dirs.push(d.to_path_buf());
            }
            let lib = self.library(&p, &ems_dirs, &at)?;
            if i == 0 {
                mats.lib = Some(lib);
            } else {
                self.warn(
                    at,
                    "a second material database: irsig uses the first for the scene's geometry",
                );
            }
        }
        // Geometry.
        for n in xml::elements(root) {
            let tag = n.tag_name().name().to_ascii_lowercase();
            match tag.as_str() {
                "geometrylist" => {
                    if xml::disabled(n) {
                        self.warn(xml::loc(path, n), "geometry list disabled: skipped");
                        continue;
                    }
                    self.glist_node(path, n, &dirs, &mats, &Placement::identity(), 0)?;
                }
                "odbfilename" | "odbfile" => {
                    let name = Importer::expand(&xml::text(n), &vars);
                    let at = xml::loc(path, n);
                    let p = self.find(&name, &dirs.geometry, "object database", &at)?;
                    self.odb(&p, &dirs, &mats, &Placement::identity(), 0)?;
                }
                "maplist" => {
                    for m in xml::elements(n).filter(|m| !xml::disabled(*m)) {
                        self.warn(
                            xml::loc(path, m),
                            format!(
                                "`<{}>` `{}`: material and texture maps are not imported \
                                 (irsig has no per-pixel material map); dropped",
                                m.tag_name().name(),
                                xml::attr(m, "name").unwrap_or("")
                            ),
                        );
                    }
                }
                "sceneorigin" | "metadata" | "properties" | "thumbnaillist" | "landmarks"
                | "gdbdirectory" | "odbdirectory" | "emsdirectory" | "extdirectory"
                | "absdirectory" | "srcdirectory" | "mapdirectory" | "matfilename"
                | "materialdatabase" => {}
                other => self.warn(
                    xml::loc(path, n),
                    format!("`<{other}>` is not imported; dropped"),
                ),
            }
        }
        Ok(())
    }
}
