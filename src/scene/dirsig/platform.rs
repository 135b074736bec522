//! DIRSIG platforms (`.platform`) and platform motion (`.ppd`) → irsig frame cameras.
//!
//! Each enabled `<focalplane>` of each `<instrument>` becomes one `frame` sensor:
//! - optics: `<focallength>` (mm) → `focal_length_m`; `<aperturediameter>` (m) → an
//!   aperture `mtf` at the band centre;
//! - `<detectorarray>`: `<xelementcount>` × `<yelementcount>` → `width` × `height`;
//!   `<xelementspacing>` (else `<xelementsize>`, in the array's `spatialunits`, microns by
//!   default) → `pixel_pitch_m`;
//! - `<spectralresponse>`: each `<channel>` → a band `[centre − width/2, centre + width/2]`
//!   µm (a Gaussian channel becomes flat over its full width at half maximum, with a
//!   warning); no channel: the `<bandpass>` `<minimum>`..`<maximum>`;
//! - position and pointing: the `.ppd` at the image time (entry times in seconds from the
//!   task list's reference time; the position interpolated linearly between the entries
//!   around it, the orientation of the nearest entry; `<location>` of type `scene` (m),
//!   `geodetic` or `ecef` (converted about the scene origin, see
//!   [`super::scene_point`]), or an old-format scene point; `<eulerangles>` in the
//!   `<data>`'s `angularunits` and `rotationorder`, about fixed scene ENU axes, composed
//!   with the static mount's
//!   rotations). DIRSIG's platform at zero rotation looks straight down (−z) with the
//!   array's +y toward +y (north): irsig's `look_at` is along R·(0, 0, −1) and `up` is
//!   R·(0, 1, 0). Without a `.ppd` the sensor is dropped with a warning.
//!
//! Dropped with a warning: temporal integration, clocks, truth collections, output file
//! settings, spatial response, polarisation, hypersampling, non-static mounts, motion
//! files other than raw entries (way points, orbits, flexible `.motion` files).
//!
//! Takes the XML; gives the importer's sensors.

use std::path::Path;

use glam::{DMat3, DVec3};
use roxmltree::Node;
use serde_json::{Map, Value, json};

use super::{Importer, euler, xml};
use crate::error::{Error, Result};

/// A pose from a `.ppd`: position (m) and rotation (scene ← platform).
struct Pose {
    position: DVec3,
    rotation: DMat3,
}

/// Angles (radians) from a `<data>`/mount element's `angularunits`.
fn to_radians(units: Option<&str>, a: [f64; 3]) -> Option<[f64; 3]> {
    match units.unwrap_or("radians").to_ascii_lowercase().as_str() {
        "radians" | "radian" | "rad" => Some(a),
        "degrees" | "degree" | "deg" => Some(a.map(f64::to_radians)),
        _ => None,
    }
}

impl Importer<'_> {
    /// Read a `.platform` (and its motion `.ppd`).
    pub(crate) fn platform(&mut self, path: &Path, motion: Option<&Path>) -> Result<()> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let doc = xml::parse(&text, path)?;
        let root = xml::root(&doc, path, "platform", "")?;
        let pose = match motion {
            Some(m) => self.motion(m)?,
            None => None,
        };
        let Some(pose) = pose else {
            self.warn(
                xml::loc(path, root),
                "no platform position (no `.ppd` motion irsig can read): the platform's sensors are dropped",
            );
            return Ok(());
        };
        for inst in root
            .descendants()
            .filter(|n| n.tag_name().name().eq_ignore_ascii_case("instrument"))
        {
            // The mounts above the instrument.
            let mut mount = DMat3::IDENTITY;
            for m in inst
                .ancestors()
                .filter(|n| n.tag_name().name().eq_ignore_ascii_case("mount"))
            {
                let ty = xml::attr(m, "type").unwrap_or("static");
                if !ty.eq_ignore_ascii_case("static") {
                    self.warn(
                        xml::loc(path, m),
                        format!(
                            "mount type `{ty}` is not imported; treated as static at zero rotation"
                        ),
                    );
                    continue;
                }
                if let Some(d) = xml::child(m, "data") {
                    let a = [
                        xml::opt_number(path, d, "xrotation")?.unwrap_or(0.0),
                        xml::opt_number(path, d, "yrotation")?.unwrap_or(0.0),
                        xml::opt_number(path, d, "zrotation")?.unwrap_or(0.0),
                    ];
                    let a = to_radians(xml::attr(d, "angularunits"), a).ok_or_else(|| {
                        Error::parse(
                            xml::loc(path, d),
                            "angularunits: expected radians or degrees",
                        )
                    })?;
                    let order = xml::attr(d, "rotationorder").unwrap_or("xyz");
                    let r = euler(order, a).ok_or_else(|| {
                        Error::parse(xml::loc(path, d), format!("rotation order `{order}`"))
                    })?;
                    mount = r * mount;
                }
            }
            let props = xml::child(inst, "properties");
            let focal_mm = props
                .map(|p| xml::opt_number(path, p, "focallength"))
                .transpose()?
                .flatten();
            let aperture_m = props
                .map(|p| xml::opt_number(path, p, "aperturediameter"))
                .transpose()?
                .flatten();
            let Some(focal_mm) = focal_mm.filter(|f| *f > 0.0) else {
                self.warn(
                    xml::loc(path, inst),
                    "instrument without a focal length > 0: dropped",
                );
                continue;
            };
            for fp in xml::children(inst, "focalplane") {
                if xml::disabled(fp) {
                    continue;
                }
                self.focal_plane(path, fp, &pose, mount, focal_mm, aperture_m)?;
            }
        }
        Ok(())
    }

    fn focal_plane(
        &mut self,
        path: &Path,
        fp: Node,
        pose: &Pose,
        mount: DMat3,
        focal_mm: f64,
        aperture_m: Option<f64>,
    ) -> Result<()> {
        let Some(da) = xml::child(fp, "detectorarray") else {
            self.warn(
                xml::loc(path, fp),
                "focal plane without a `<detectorarray>`: dropped",
            );
            return Ok(());
        };
        let count = |name: &str| -> Result<usize> {
            let v = xml::req_number(path, da, name)?;
            if v >= 1.0 && v.fract() == 0.0 && v <= 100_000.0 {
                Ok(v as usize)
            } else {
                Err(Error::parse(
                    xml::loc(path, da),
                    format!("`<{name}>` {v}: expected a whole number ≥ 1"),
                ))
            }
        };
        let (w, h) = (count("xelementcount")?, count("yelementcount")?);
        let unit = match xml::attr(da, "spatialunits")
            .unwrap_or("microns")
            .to_ascii_lowercase()
            .as_str()
        {
            "microns" | "micrometers" | "um" => 1e-6,
            "millimeters" | "mm" => 1e-3,
            "meters" | "m" => 1.0,
            other => {
                return Err(Error::parse(
                    xml::loc(path, da),
                    format!("spatialunits `{other}`: expected microns, millimeters or meters"),
                ));
            }
        };
        let pitch =
            |axis: &str| -> Result<Option<f64>> {
                Ok(xml::opt_number(path, da, &format!("{axis}elementspacing"))?
                    .or(xml::opt_number(path, da, &format!("{axis}elementsize"))?))
            };
        let px = pitch("x")?.filter(|p| *p > 0.0).ok_or_else(|| {
            Error::parse(
                xml::loc(path, da),
                "no `<xelementspacing>` or `<xelementsize>` > 0",
            )
        })?;
        if let Some(py) = pitch("y")? {
            if (py - px).abs() > 1e-9 * px.abs() {
                self.warn(
                    xml::loc(path, da),
                    format!("pixel spacing {px} × {py}: irsig pixels are square; {px} used"),
                );
            }
        }
        if h == 1 {
            self.warn(
                xml::loc(path, da),
                "a one-line array (push-broom): imported as a frame camera of one row",
            );
        }
        // Bands.
        let sr = xml::path(fp, &["capturemethod", "spectralresponse"])
            .or_else(|| xml::child(fp, "spectralresponse"));
        let mut bands = Vec::new();
        let mut centre_um = None;
        if let Some(sr) = sr {
            let um = |n: Node| match xml::attr(n, "spectralunits")
                .unwrap_or("microns")
                .to_ascii_lowercase()
                .as_str()
            {
                "nanometers" | "nm" => 1e-3,
                _ => 1.0,
            };
            let bp = xml::child(sr, "bandpass");
            let scale = bp.map_or(1.0, um);
            let channels: Vec<Node> = xml::path(sr, &["channellist"])
                .map(|c| xml::children(c, "channel").collect())
                .unwrap_or_default();
            for (k, c) in channels.iter().enumerate() {
                let name = xml::attr(*c, "name")
                    .map(sanitize)
                    .unwrap_or_else(|| format!("band{k}"));
                let centre = xml::opt_number(path, *c, "center")?;
                let width = xml::opt_number(path, *c, "width")?;
                let shape = xml::attr(*c, "shape").unwrap_or("").to_ascii_lowercase();
                match (centre, width) {
                    (Some(ce), Some(wi)) if wi > 0.0 => {
                        let (ce, wi) = (ce * scale, wi * scale);
                        if shape != "rectangle" && shape != "rectangular" && shape != "tophat" {
                            self.warn(
                                xml::loc(path, *c),
                                format!(
                                    "channel `{name}` shape `{shape}`: imported as a flat band over \
                                     its width, {:.4}–{:.4} µm",
                                    ce - wi / 2.0,
                                    ce + wi / 2.0
                                ),
                            );
                        }
                        centre_um.get_or_insert(ce);
                        bands.push(
                            json!({"name": name, "response": [ce - wi / 2.0, ce + wi / 2.0]}),
                        );
                    }
                    _ => self.warn(
                        xml::loc(path, *c),
                        format!("channel `{name}` without a centre and width > 0: dropped"),
                    ),
                }
            }
            if bands.is_empty() {
                if let Some(bp) = bp {
                    let lo = xml::req_number(path, bp, "minimum")? * scale;
                    let hi = xml::req_number(path, bp, "maximum")? * scale;
                    centre_um = Some(0.5 * (lo + hi));
                    bands.push(json!({"name": "band", "response": [lo, hi]}));
                }
            }
        }
        if bands.is_empty() {
            self.warn(
                xml::loc(path, fp),
                "focal plane without a spectral response: dropped",
            );
            return Ok(());
        }
        // Pointing.
        let r = pose.rotation * mount;
        let look = r * DVec3::new(0.0, 0.0, -1.0);
        let up = r * DVec3::new(0.0, 1.0, 0.0);
        let range = pose.position.z.abs().max(1.0);
        let target = pose.position + look * range;
        if !(target.is_finite() && up.is_finite()) {
            return Err(Error::parse(
                xml::loc(path, fp),
                format!(
                    "the platform at {} looks at a point beyond finite numbers: expected a \
                     position within the scene's range",
                    pose.position
                ),
            ));
        }
        let name = xml::attr(fp, "name")
            .map(sanitize)
            .unwrap_or_else(|| "camera".into());
        let mut s = Map::new();
        s.insert("type".into(), "frame".into());
        s.insert("name".into(), name.into());
        s.insert("width".into(), w.into());
        s.insert("height".into(), h.into());
        s.insert("pixel_pitch_m".into(), (px * unit).into());
        s.insert("focal_length_m".into(), (focal_mm * 1e-3).into());
        s.insert("position".into(), json!(pose.position.to_array()));
        s.insert("look_at".into(), json!(target.to_array()));
        s.insert("up".into(), json!(up.to_array()));
        s.insert("bands".into(), Value::Array(bands));
        if let Some(a) = aperture_m.filter(|a| *a > 0.0) {
            let mut mtf = json!({"aperture_diameter_m": a});
            if let Some(c) = centre_um {
                mtf["wavelength_um"] = c.into();
            }
            s.insert("mtf".into(), mtf);
        }
        let dropped: Vec<&str> = [
            "temporalintegration",
            "spatialresponse",
            "samplestrategy",
            "truthcollection",
            "clock",
            "imagefile",
            "polarizer",
        ]
        .into_iter()
        .filter(|t| {
            fp.descendants()
                .any(|n| n.tag_name().name().eq_ignore_ascii_case(t))
        })
        .collect();
        if !dropped.is_empty() {
            self.warn(
                xml::loc(path, fp),
                format!(
                    "focal plane: {} not imported (irsig renders radiance per band at one \
                     instant); dropped",
                    dropped
                        .iter()
                        .map(|d| format!("`<{d}>`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            );
        }
        self.sensors.push(s);
        Ok(())
    }

    /// The pose of a `.ppd` at the image time: the entry nearest it.
    fn motion(&mut self, path: &Path) -> Result<Option<Pose>> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let doc = xml::parse(&text, path)?;
        // A flexible motion (`<motion type="flexible">`, a `.motion` file: location and
        // orientation engines, DIRSIG's flex_motion.html), which BasicPlatform also
        // takes, is not imported: the sensor is dropped with a warning, not the scene.
        if doc
            .root_element()
            .tag_name()
            .name()
            .eq_ignore_ascii_case("motion")
        {
            self.warn(
                xml::loc(path, doc.root_element()),
                "flexible motion (`<motion>` with location and orientation engines) is not \
                 imported: the platform has no pose; its sensors are dropped",
            );
            return Ok(None);
        }
        let root = xml::root(&doc, path, "platformmotion", " or `<motion>`")?;
        let Some(data) = xml::child(root, "data") else {
            self.warn(
                xml::loc(path, root),
                "platform motion without raw `<data>` entries (way points, orbits): not imported",
            );
            return Ok(None);
        };
        let frame = xml::attr(data, "rotationframe").unwrap_or("sceneenu");
        if !frame.eq_ignore_ascii_case("sceneenu") {
            self.warn(
                xml::loc(path, data),
                format!("rotation frame `{frame}`: irsig reads `sceneenu`; angles taken as such"),
            );
        }
        let order = xml::attr(data, "rotationorder")
            .unwrap_or("xyz")
            .to_string();
        let units = xml::attr(data, "angularunits").map(str::to_string);
        if let Some(u) = xml::attr(data, "spatialunits") {
            if !u.eq_ignore_ascii_case("meters") {
                return Err(Error::parse(
                    xml::loc(path, data),
                    format!("spatialunits `{u}`: irsig reads meters"),
                ));
            }
        }
        // Entry times in seconds from the task list's reference time, "the simulation's
        // absolute time variable" that relative times count from (DIRSIG manual, Task
        // List, dirsig.org/docs/manual/xml-tasks.html); the image is at the task start
        // (or the given time). Without a reference, relative time 0 is the image time.
        let image = match &self.opts.time {
            Some(t) => crate::sun::parse_time(t).ok(),
            None => self.time,
        };
        let reference = self.time_reference.or(image);
        let target = match (image, reference) {
            (Some(i), Some(r)) => (i - r).num_milliseconds() as f64 / 1000.0,
            _ => 0.0,
        };
        let mut timed: Vec<(f64, Node)> = Vec::new();
        for e in xml::children(data, "entry") {
            let t = match xml::child(e, "datetime") {
                Some(d)
                    if xml::attr(d, "type").is_none_or(|t| t.eq_ignore_ascii_case("relative")) =>
                {
                    xml::number(path, d)?
                }
                Some(d) => {
                    let abs = crate::sun::parse_time(&xml::text(d)).map_err(|err| {
                        Error::parse(xml::loc(path, d), format!("datetime: {err}"))
                    })?;
                    match reference {
                        Some(r) => (abs - r).num_milliseconds() as f64 / 1000.0,
                        None => 0.0,
                    }
                }
                None => 0.0,
            };
            timed.push((t, e));
        }
        if timed.is_empty() {
            self.warn(
                xml::loc(path, data),
                "platform motion without entries: not imported",
            );
            return Ok(None);
        }
        timed.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Position: linear between the entries around the image time (DIRSIG
        // interpolates generic motion between entries); orientation: the nearest entry.
        let k = timed.partition_point(|(t, _)| *t <= target);
        let nearest = (0..timed.len())
            .min_by(|&a, &b| {
                (timed[a].0 - target)
                    .abs()
                    .total_cmp(&(timed[b].0 - target).abs())
            })
            .expect("not empty");
        let point = |e: Node| -> Result<DVec3> {
            let pos = xml::child(e, "position").ok_or_else(|| {
                Error::parse(xml::loc(path, e), "motion entry without `<position>`")
            })?;
            // New format: `<location type=…>` (scene, geodetic or ECEF); old format: a
            // scene-frame `<point>`/`<cartesiantriple>` or bare x, y, z.
            match xml::child(pos, "location") {
                Some(loc) => super::scene_point(path, loc, self.site.as_ref()),
                None => Ok(DVec3::from(xml::triple(path, pos, 0.0)?)),
            }
        };
        let p = if k > 0 && k < timed.len() && timed[k].0 > timed[k - 1].0 {
            let ((t0, e0), (t1, e1)) = (timed[k - 1], timed[k]);
            let w = (target - t0) / (t1 - t0);
            point(e0)? * (1.0 - w) + point(e1)? * w
        } else {
            point(timed[nearest].1)?
        };
        let (t_first, t_last) = (timed[0].0, timed[timed.len() - 1].0);
        if target < t_first || target > t_last {
            self.warn(
                xml::loc(path, data),
                format!(
                    "the image time ({target} s from the task reference) is outside the motion's \
                     entries ({t_first} .. {t_last} s): the platform is at the nearest entry"
                ),
            );
        } else if timed.len() > 1 {
            self.warn(
                xml::loc(path, data),
                format!(
                    "{} motion entries: the platform is placed where they put it at the image \
                     time ({target} s from the task reference; position interpolated, \
                     orientation of the nearest entry); the motion is dropped",
                    timed.len()
                ),
            );
        }
        let e = timed[nearest].1;
        let angles = match xml::path(e, &["orientation", "eulerangles"]) {
            Some(a) => xml::triple(path, a, 0.0)?,
            None => [0.0; 3],
        };
        let a = to_radians(units.as_deref(), angles).ok_or_else(|| {
            Error::parse(
                xml::loc(path, data),
                "angularunits: expected radians or degrees",
            )
        })?;
        let rotation = euler(&order, a).ok_or_else(|| {
            Error::parse(xml::loc(path, data), format!("rotation order `{order}`"))
        })?;
        Ok(Some(Pose {
            position: p,
            rotation,
        }))
    }
}

/// A name usable as an output file stem.
fn sanitize(s: &str) -> String {
    let t: String = s
        .trim()
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if t.is_empty() { "sensor".into() } else { t }
}
