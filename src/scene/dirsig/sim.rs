//! DIRSIG simulations: DIRSIG5 `.jsim` (JSON), DIRSIG4 `.sim` (XML), and the files they
//! name that set the time and the atmosphere: `.tasks` and `.atm`.
//!
//! - `.jsim`: a JSON array of simulations (the first is imported), each with a
//!   `scene_list` (`{"inputs": "x.scene"}`; the first scene is imported) and a
//!   `plugin_list`: `BasicPlatform` (`platform_filename`, `motion_filename`,
//!   `tasks_filename` → sensors and time, see [`super::platform`]), `ThermWeather`
//!   (`filename` → weather), `BasicAtmosphere` (`atmosphere_filename`, a `.atm`),
//!   `NewAtmosphere` (its MODTRAN `atmospheric_model` → the AFGL profile of irsig's
//!   built-in atmosphere; the aerosol model and the `.hdf` table are dropped with a
//!   warning). Ephemeris plugins need nothing (irsig computes the sun with NREL SPA);
//!   other plugins are dropped with a warning. Paths written for another machine
//!   (`C:/DIRSIG/…`) are looked up in the simulation's folders and the search folders.
//! - `.sim`: `<simulation>` with `<scene>`, `<atmosphericconditions>`, `<platform>`,
//!   `<platformmotion>`, `<tasklist>`, each `externalfile="…"` or written inline.
//! - `.tasks`: `<tasklist>` with a `<reference><datetime type="absolute">` (RFC 3339)
//!   and `<task>`s whose `<start>` is `relative` (seconds after the reference) or
//!   `absolute`: the image time is the first task's start (the task's duration and
//!   further tasks are dropped with a warning; `irsig render --times` renders more).
//! - `.atm`: `<atmosphericconditions>`: `<uniformweather><classicdata><filename>` (a
//!   `.wth`) → weather; `<simpleradiativetransfer><apparentskytemperature>` (K) → no
//!   atmosphere (`"none"`) and `render.sky_temperature_k`; other radiative transfer →
//!   irsig's default atmosphere, with a warning.
//!
//! Takes the files; gives the importer's scene, time, weather, atmosphere and sensors.

use std::path::{Path, PathBuf};

use roxmltree::Node;
use serde_json::Value;

use super::{Importer, xml};
use crate::error::{Error, Location, Result};
use crate::scene::jsonloc::JsonLines;

/// The MODTRAN model atmosphere names DIRSIG writes, and irsig's AFGL profile for each.
const MODTRAN_PROFILES: [(&str, &str); 6] = [
    ("tropical", "tropical"),
    ("midlatitudesummer", "mid-latitude-summer"),
    ("midlatitudewinter", "mid-latitude-winter"),
    ("subarcticsummer", "sub-arctic-summer"),
    ("subarcticwinter", "sub-arctic-winter"),
    ("us1976", "us-standard"),
];

/// The files a simulation names, once found.
#[derive(Default)]
struct SimFiles {
    scene: Option<(PathBuf, Location)>,
    tasks: Option<(PathBuf, Location)>,
    platform: Option<(PathBuf, Location)>,
    motion: Option<(PathBuf, Location)>,
    atm: Option<(PathBuf, Location)>,
}

impl Importer<'_> {
    /// Folders a simulation's relative paths are looked up in: its own and the two above.
    fn sim_bases(path: &Path) -> Vec<PathBuf> {
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut v = vec![dir.clone()];
        if let Some(up) = dir.parent() {
            v.push(up.to_path_buf());
            if let Some(up2) = up.parent() {
                v.push(up2.to_path_buf());
            }
        }
        v
    }

    /// Import a DIRSIG5 `.jsim`.
    pub(crate) fn jsim(&mut self, path: &Path, text: &str) -> Result<()> {
        let v: Value =
            serde_json::from_str(text).map_err(|e| crate::scene::jsonloc::serde_error(path, &e))?;
        let lines = JsonLines::new(text);
        let at = |p: &str| {
            let mut l = Location::file(path).with_field(p.trim_start_matches('.'));
            if let Some(n) = lines.line(p) {
                l = l.at_line(n);
            }
            l
        };
        let (sim, prefix) = match &v {
            Value::Array(a) => {
                if a.len() > 1 {
                    self.warn(
                        at("[1]"),
                        format!("{} simulations: irsig imports the first", a.len()),
                    );
                }
                (
                    a.first()
                        .ok_or_else(|| Error::parse(at(""), "empty simulation list"))?,
                    "[0]",
                )
            }
            Value::Object(_) => (&v, ""),
            _ => {
                return Err(Error::parse(
                    at(""),
                    "expected a JSON array of simulations (DIRSIG5 `.jsim`)",
                ));
            }
        };
        let bases = Self::sim_bases(path);
        let mut files = SimFiles::default();
        let scenes = sim.get("scene_list").and_then(Value::as_array);
        let Some(scenes) = scenes.filter(|s| !s.is_empty()) else {
            return Err(Error::parse(
                at(prefix),
                "no `scene_list`: a simulation needs a scene",
            ));
        };
        for (i, s) in scenes.iter().enumerate() {
            let p = format!("{prefix}.scene_list[{i}]");
            if i > 0 {
                self.warn(
                    at(&p),
                    "a second scene: irsig imports the first only; dropped",
                );
                continue;
            }
            let name = s
                .get("inputs")
                .and_then(Value::as_str)
                .or_else(|| s.as_str())
                .ok_or_else(|| {
                    Error::parse(at(&p), "a scene entry needs `inputs` (the `.scene` file)")
                })?;
            // A zero offset (`"0,0,0"`, `[0, 0, 0]`) changes nothing.
            let zero = |v: &Value| match v {
                Value::String(t) => t
                    .split(|c: char| c == ',' || c.is_whitespace())
                    .filter(|x| !x.is_empty())
                    .all(|x| x.parse::<f64>() == Ok(0.0)),
                Value::Array(a) => a.iter().all(|x| x.as_f64() == Some(0.0)),
                _ => false,
            };
            if let Some(off) = s.get("offset").filter(|o| !zero(o)) {
                self.warn(
                    at(&format!("{p}.offset")),
                    format!("scene offset {off} is not imported; dropped"),
                );
            }
            let l = at(&format!("{p}.inputs"));
            files.scene = Some((self.find(name, &bases, "scene", &l)?, l));
        }
        for (i, pl) in sim
            .get("plugin_list")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .enumerate()
        {
            let p = format!("{prefix}.plugin_list[{i}]");
            let name = pl.get("name").and_then(Value::as_str).unwrap_or("");
            let inputs = pl.get("inputs").cloned().unwrap_or(Value::Null);
            let file = |key: &str| inputs.get(key).and_then(Value::as_str).map(str::to_string);
            match name {
                "BasicPlatform" => {
                    for (key, slot, what) in [
                        ("platform_filename", 0, "platform"),
                        ("motion_filename", 1, "platform motion"),
                        ("tasks_filename", 2, "task list"),
                    ] {
                        let Some(f) = file(key) else { continue };
                        let l = at(&format!("{p}.inputs.{key}"));
                        let found = Some((self.find(&f, &bases, what, &l)?, l));
                        match slot {
                            0 => files.platform = found,
                            1 => files.motion = found,
                            _ => files.tasks = found,
                        }
                    }
                }
                "ThermWeather" => {
                    if let Some(f) = file("filename") {
                        let l = at(&format!("{p}.inputs.filename"));
                        self.weather = Some(self.find(&f, &bases, "weather file", &l)?);
                    }
                }
                "BasicAtmosphere" => {
                    if let Some(f) = file("atmosphere_filename").or_else(|| file("filename")) {
                        let l = at(&format!("{p}.inputs"));
                        files.atm = Some((self.find(&f, &bases, "atmosphere", &l)?, l));
                    }
                }
                "NewAtmosphere" => {
                    let model = inputs
                        .pointer("/backend/tape5_parameters/atmospheric_model")
                        .and_then(Value::as_str)
                        .unwrap_or("");
                    let key = model.to_ascii_lowercase().replace(['_', ' ', '-'], "");
                    match MODTRAN_PROFILES.iter().find(|(k, _)| *k == key) {
                        Some((_, profile)) => {
                            self.atmosphere = Some(Value::String((*profile).into()));
                            self.warn(
                                at(&p),
                                format!(
                                    "NewAtmosphere: MODTRAN model `{model}` → irsig's built-in \
                                     atmosphere on the `{profile}` AFGL profile; the aerosol \
                                     model, multiple scattering and the atmosphere table \
                                     (`hdf_filename`) are dropped"
                                ),
                            );
                        }
                        None => self.warn(
                            at(&p),
                            format!(
                                "NewAtmosphere with model `{model}` is not imported: irsig's \
                                 default atmosphere (the AFGL profile of the site and month) is used"
                            ),
                        ),
                    }
                }
                "SpiceEphemeris" | "SimpleEphemeris" | "BasicEphemeris" => {}
                other => self.warn(at(&p), format!("plugin `{other}` is not imported; dropped")),
            }
        }
        self.run_files(path, files)
    }

    /// Import a DIRSIG4 `.sim` (`<simulation>`).
    pub(crate) fn sim(&mut self, path: &Path, root: Node) -> Result<()> {
        let bases = Self::sim_bases(path);
        let mut files = SimFiles::default();
        let mut inline_tasks = None;
        let mut inline_atm = None;
        for n in xml::elements(root) {
            let tag = n.tag_name().name().to_ascii_lowercase();
            let at = xml::loc(path, n);
            let ext = xml::attr(n, "externalfile");
            let found = match ext {
                Some(f) => {
                    let what = match tag.as_str() {
                        "scene" => "scene",
                        "atmosphericconditions" => "atmosphere",
                        "platform" => "platform",
                        "platformmotion" => "platform motion",
                        "tasklist" => "task list",
                        _ => "file",
                    };
                    Some((self.find(f, &bases, what, &at)?, at.clone()))
                }
                None => None,
            };
            match tag.as_str() {
                "scene" => files.scene = found,
                "atmosphericconditions" => match found {
                    Some(f) => files.atm = Some(f),
                    None => inline_atm = Some(n),
                },
                "platform" => files.platform = found,
                "platformmotion" => files.motion = found,
                "tasklist" => match found {
                    Some(f) => files.tasks = Some(f),
                    None => inline_tasks = Some(n),
                },
                "metadata" | "options" => {}
                other => self.warn(at, format!("`<{other}>` is not imported; dropped")),
            }
            if ext.is_none() && matches!(tag.as_str(), "scene" | "platform" | "platformmotion") {
                self.warn(
                    xml::loc(path, n),
                    format!(
                        "inline `<{tag}>`: irsig reads it from an `externalfile` only; dropped"
                    ),
                );
            }
        }
        if let Some(n) = inline_tasks {
            self.tasks_node(path, n)?;
        }
        if let Some(n) = inline_atm {
            self.atm_node(path, n)?;
        }
        self.run_files(path, files)
    }

    /// Read the files a simulation names, in dependency order.
    fn run_files(&mut self, sim: &Path, f: SimFiles) -> Result<()> {
        let Some((scene, at)) = f.scene else {
            return Err(Error::parse(
                Location::file(sim).with_field("scene"),
                "the simulation names no scene",
            ));
        };
        let text = std::fs::read_to_string(&scene).map_err(|e| Error::io(&scene, e))?;
        let doc = xml::parse(&text, &scene)?;
        let root = doc.root_element();
        let tag = root.tag_name().name();
        if !(tag.eq_ignore_ascii_case("classicscene") || tag.eq_ignore_ascii_case("scene")) {
            return Err(Error::parse(
                at,
                format!(
                    "{} has root `<{}>`: expected a DIRSIG `<classicscene>`",
                    scene.display(),
                    root.tag_name().name()
                ),
            ));
        }
        self.scene(&scene, root)?;
        if let Some((p, _)) = f.tasks {
            self.tasks(&p)?;
        }
        if let Some((p, _)) = f.atm {
            self.atm(&p)?;
        }
        match (f.platform, f.motion) {
            (Some((p, _)), m) => self.platform(&p, m.as_ref().map(|(m, _)| m.as_path()))?,
            (None, Some((_, l))) => self.warn(l, "platform motion without a platform: dropped"),
            (None, None) => {}
        }
        Ok(())
    }

    /// Read a `.tasks` file.
    pub(crate) fn tasks(&mut self, path: &Path) -> Result<()> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let doc = xml::parse(&text, path)?;
        let root = xml::root(&doc, path, "tasklist", "")?;
        self.tasks_node(path, root)
    }

    /// A `<tasklist>` element.
    fn tasks_node(&mut self, path: &Path, root: Node) -> Result<()> {
        let reference = xml::path(root, &["reference", "datetime"]);
        let parse_abs = |n: Node| -> Result<chrono::DateTime<chrono::FixedOffset>> {
            let t = xml::text(n);
            crate::sun::parse_time(&t)
                .map_err(|e| Error::parse(xml::loc(path, n), format!("datetime: {e}")))
        };
        let reference = reference.map(parse_abs).transpose()?;
        let tasks: Vec<Node> = xml::children(root, "task").collect();
        let Some(task) = tasks.first() else {
            return Err(Error::parse(
                xml::loc(path, root),
                "a task list without a `<task>`",
            ));
        };
        if tasks.len() > 1 {
            self.warn(
                xml::loc(path, tasks[1]),
                format!(
                    "{} tasks: the image time is the first task's start; the others are dropped",
                    tasks.len()
                ),
            );
        }
        let moment = |n: Option<Node>| -> Result<Option<chrono::DateTime<chrono::FixedOffset>>> {
            let Some(d) = n.and_then(|n| xml::child(n, "datetime")) else {
                return Ok(None);
            };
            let ty = xml::attr(d, "type")
                .unwrap_or("absolute")
                .to_ascii_lowercase();
            if ty == "relative" {
                let s = xml::number(path, d)?;
                let r = reference.ok_or_else(|| {
                    Error::parse(
                        xml::loc(path, d),
                        "a relative datetime needs the task list's `<reference>` datetime",
                    )
                })?;
                chrono::TimeDelta::try_milliseconds((s * 1000.0).round() as i64)
                    .and_then(|d| r.checked_add_signed(d))
                    .map(Some)
                    .ok_or_else(|| {
                        Error::parse(
                            xml::loc(path, d),
                            format!("{s} s after the reference time is beyond the calendar"),
                        )
                    })
            } else {
                parse_abs(d).map(Some)
            }
        };
        let start = moment(xml::child(*task, "start"))?;
        let stop = moment(xml::child(*task, "stop"))?;
        let start = start.or(reference).ok_or_else(|| {
            Error::parse(
                xml::loc(path, *task),
                "the task has no start and the list no reference time",
            )
        })?;
        if stop.is_some_and(|s| s != start) {
            self.warn(
                xml::loc(path, *task),
                "the task spans a time interval: the image is at its start (irsig renders \
                 instants; `irsig render --times` renders several)",
            );
        }
        self.time = Some(start);
        self.time_reference = reference;
        Ok(())
    }

    /// Read a `.atm` file.
    pub(crate) fn atm(&mut self, path: &Path) -> Result<()> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let doc = xml::parse(&text, path)?;
        let root = xml::root(&doc, path, "atmosphericconditions", " (a DIRSIG `.atm`)")?;
        self.atm_node(path, root)
    }

    /// An `<atmosphericconditions>` element.
    fn atm_node(&mut self, path: &Path, root: Node) -> Result<()> {
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        for n in xml::elements(root) {
            let tag = n.tag_name().name().to_ascii_lowercase();
            match tag.as_str() {
                "metadata" => {}
                "uniformweather" => match xml::path(n, &["classicdata", "filename"]) {
                    Some(f) => {
                        let name = Importer::expand(&xml::text(f), &[]);
                        let at = xml::loc(path, f);
                        self.weather = Some(self.find(
                            &name,
                            std::slice::from_ref(&dir),
                            "weather file",
                            &at,
                        )?);
                    }
                    None => self.warn(
                        xml::loc(path, n),
                        "uniform weather without `<classicdata><filename>`: not imported; dropped",
                    ),
                },
                "simpleradiativetransfer" => {
                    self.atmosphere = Some(Value::String("none".into()));
                    match xml::child(n, "apparentskytemperature") {
                        Some(t) => {
                            let k = xml::number(path, t)?;
                            if !(k > 0.0 && k < 400.0) {
                                return Err(Error::parse(
                                    xml::loc(path, t),
                                    format!("apparent sky temperature {k} K: expected 0..400 K"),
                                ));
                            }
                            self.render.insert("sky_temperature_k".into(), k.into());
                        }
                        None => self.warn(
                            xml::loc(path, n),
                            "simple radiative transfer without an apparent sky temperature: the \
                             sky is grey at the air temperature",
                        ),
                    }
                }
                other => self.warn(
                    xml::loc(path, n),
                    format!(
                        "`<{other}>` is not imported: irsig's default atmosphere (the AFGL \
                         profile of the site and month) is used"
                    ),
                ),
            }
        }
        Ok(())
    }
}
