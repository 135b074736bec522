//! The scene file's render sections — `render`, `atmosphere` and `sensors` —
//! typed and checked in one place, for [`super::Session`] and for `scene
//! check` alike ([`super::checks::render_problems`]), so that a scene that
//! passes the check does not fail the render over them.
//!
//! Every error names the scene file, the line and column of the offending
//! key (found again in the text, [`crate::scene::jsonloc::JsonLines`]) and
//! the field's JSON path; misspelt keys and names get a "did you mean" hint
//! ([`crate::suggest`]). Takes a loaded [`Scene`]; gives typed sections.
//! Knows nothing of the command line.

use std::cell::OnceCell;
use std::path::Path;

use serde::de::DeserializeOwned;

use super::session::AtmosphereConfig;
use super::{RenderConfig, sensor_bands};
use crate::radiometry::Band;
use crate::scene::Scene;
use crate::scene::jsonloc::JsonLines;
use crate::sensor::{Sensor, SensorConfig};
use crate::{Error, Location, Result};

/// The typed render sections of a scene.
#[derive(Debug, Clone)]
pub struct Sections {
    /// The `render` section.
    pub config: RenderConfig,
    /// The `atmosphere` section.
    pub atmosphere: AtmosphereConfig,
    /// The sensors, in file order.
    pub sensors: Vec<Sensor>,
    /// Each sensor's bands on the render's spectral grid.
    pub bands: Vec<Vec<Band>>,
}

/// Type and check `scene`'s `render`, `atmosphere` and `sensors` sections.
///
/// # Errors
/// The first problem, as [`Error::Parse`] naming the scene file, line,
/// column and field: an unknown or misspelt key, a value of the wrong type
/// or out of range, an unknown atmosphere or profile, a sensor name used
/// twice, a missing or bad response file, or no sensor at all.
pub fn parse(scene: &Scene) -> Result<Sections> {
    let lines = OnceCell::new();
    let place = |e: Error| locate(e, &scene.path, &lines);
    parse_unplaced(scene).map_err(place)
}

fn parse_unplaced(scene: &Scene) -> Result<Sections> {
    let file = Location::file(&scene.path);
    let config = RenderConfig::from_json(scene.render.as_ref(), &file)?;
    let atmosphere = match &scene.atmosphere {
        None => AtmosphereConfig::default(),
        Some(v) => typed(
            v,
            &file,
            "atmosphere",
            "\"none\", a profile name, {\"model\": \"none\"}, {\"model\": \"builtin\"}, \
             {\"model\": \"standard\", \"profile\": NAME} or {\"model\": \"tape7\", \"index\": FILE}",
        )?,
    };
    let base = scene.path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut sensors: Vec<Sensor> = Vec::new();
    let mut bands = Vec::new();
    for (i, v) in scene.sensors.iter().enumerate() {
        let field = format!("sensors[{i}]");
        let c = sensor_config(v, &file, &field)?;
        let loc = file.clone().with_field(&field);
        let s = Sensor::from_config(&c, &loc)?;
        if sensors.iter().any(|o| o.name == s.name) {
            return Err(Error::parse(
                file.clone().with_field(format!("{field}.name")),
                format!("`{}` is used twice: expected unique sensor names", s.name),
            ));
        }
        let b = sensor_bands(&s, &base, config.spectral_step_um, &loc)?;
        check_band_range(&atmosphere, &b, &loc)?;
        bands.push(b);
        sensors.push(s);
    }
    if sensors.is_empty() {
        return Err(Error::parse(
            file.with_field("sensors"),
            "no sensors: expected at least one frame camera or line scanner",
        ));
    }
    Ok(Sections {
        config,
        atmosphere,
        sensors,
        bands,
    })
}

/// A sensor's bands must lie inside the spectral range of the built-in
/// atmosphere when the scene uses it: outside it the model has no
/// transmittance or sky, and the image would be silently near zero.
fn check_band_range(atmosphere: &AtmosphereConfig, bands: &[Band], loc: &Location) -> Result<()> {
    if !matches!(
        atmosphere,
        AtmosphereConfig::Builtin { .. } | AtmosphereConfig::Standard { .. }
    ) {
        return Ok(());
    }
    let (a, b) = crate::atmosphere::BUILTIN_RANGE_UM;
    for band in bands {
        let wl = band.wavelengths_um();
        let (lo, hi) = (wl[0], wl[wl.len() - 1]);
        if lo < a - 1e-9 || hi > b + 1e-9 {
            return Err(Error::parse(
                loc.clone(),
                format!(
                    "band {lo}–{hi} µm lies outside the built-in atmosphere's spectral range \
                     {a}–{b} µm: use \"atmosphere\": \"none\" (no atmosphere) or a MODTRAN \
                     tape7 table covering the band ({{\"model\": \"tape7\", \"index\": FILE}})"
                ),
            ));
        }
    }
    Ok(())
}

/// `v` (the value at JSON path `field` of the file at `file`) as a `T`.
/// The error names the deepest field `serde` reached (an unknown key
/// itself), hints at the closest known key or variant, and ends with
/// `expected` unless `serde` already listed what it expected.
///
/// # Errors
/// [`Error::Parse`] as described.
pub(crate) fn typed<T: DeserializeOwned>(
    v: &serde_json::Value,
    file: &Location,
    field: &str,
    expected: &str,
) -> Result<T> {
    serde_path_to_error::deserialize(v).map_err(|e| {
        let inner = e.inner().to_string();
        let mut path = field.to_string();
        for seg in e.path().iter() {
            use serde_path_to_error::Segment;
            match seg {
                Segment::Seq { index } => path.push_str(&format!("[{index}]")),
                Segment::Map { key } | Segment::Enum { variant: key } => {
                    path.push('.');
                    path.push_str(key);
                }
                Segment::Unknown => {}
            }
        }
        if let Some(key) = unknown_field(&inner) {
            if !path.ends_with(&format!(".{key}")) {
                path = format!("{path}.{key}");
            }
        }
        let listed = inner.contains("expected");
        let mut message = crate::suggest::with_suggestion(&inner);
        if !listed {
            message = format!("{message}: expected {expected}");
        }
        Error::parse(file.clone().with_field(path), message)
    })
}

/// Sensor `v` (at JSON path `field`) as a [`SensorConfig`]: its `type` read
/// first, then the variant's own struct from the other keys, so that an error
/// names the key inside the sensor (`sensors[0].width`, with its line and
/// column). Deserialised as the internally tagged enum, serde buffers the
/// sensor's content and the key's path is lost. An unknown or missing `type`
/// goes through the enum, whose error lists (and suggests) the types.
///
/// # Errors
/// [`Error::Parse`] as [`typed`].
fn sensor_config(v: &serde_json::Value, file: &Location, field: &str) -> Result<SensorConfig> {
    let obj = v.as_object();
    let tag = obj
        .and_then(|m| m.get("type"))
        .and_then(serde_json::Value::as_str);
    let body = || {
        let mut m = obj.cloned().unwrap_or_default();
        m.remove("type");
        serde_json::Value::Object(m)
    };
    match tag {
        Some("frame") => Ok(SensorConfig::Frame(typed(
            &body(),
            file,
            field,
            "a frame camera (`\"type\": \"frame\"`)",
        )?)),
        Some("line_scanner") => Ok(SensorConfig::LineScanner(typed(
            &body(),
            file,
            field,
            "a line scanner (`\"type\": \"line_scanner\"`)",
        )?)),
        _ => typed(
            v,
            file,
            field,
            "a sensor with \"type\": \"frame\" or \"line_scanner\"",
        ),
    }
}

/// The key of a `serde` "unknown field `k`" message.
fn unknown_field(message: &str) -> Option<&str> {
    let rest = &message[message.find("unknown field `")? + "unknown field `".len()..];
    Some(&rest[..rest.find('`')?])
}

/// `e` with the line and column of its field when it is an error in the
/// file at `path` that names a field but no line (the text is scanned once,
/// on the first such error).
pub(crate) fn locate(e: Error, path: &Path, lines: &OnceCell<Option<JsonLines>>) -> Error {
    match e {
        Error::Parse {
            mut location,
            message,
        } if location.line.is_none() && location.path.as_deref() == Some(path) => {
            let found = location.field.as_deref().and_then(|f| {
                lines
                    .get_or_init(|| {
                        std::fs::read_to_string(path)
                            .ok()
                            .map(|t| JsonLines::new(&t))
                    })
                    .as_ref()?
                    .position(f)
            });
            if let Some((l, c)) = found {
                location = location.at(l, c);
            }
            Error::Parse { location, message }
        }
        other => other,
    }
}

/// The JSON Schema of the whole scene file (`irsig scene schema`,
/// `scenes/scene.schema.json`): the scene module's own
/// ([`crate::scene::schema_json`]) with its free-form `sensors`, `render`
/// and `atmosphere` replaced by the schemas of the types they are read as
/// here, so that editors can check and complete every section.
pub fn schema_json() -> String {
    use serde_json::Value;
    let mut root: Value =
        serde_json::from_str(&crate::scene::schema_json()).expect("the scene schema is JSON");
    let mut defs = root
        .get_mut("$defs")
        .and_then(Value::as_object_mut)
        .map(std::mem::take)
        .unwrap_or_default();
    let mut section = |schema: schemars::Schema| -> Value {
        let mut v = schema.to_value();
        if let Some(obj) = v.as_object_mut() {
            obj.remove("$schema");
            if let Some(Value::Object(d)) = obj.remove("$defs") {
                defs.extend(d);
            }
        }
        v
    };
    let sensor = section(schemars::schema_for!(SensorConfig));
    let render = section(schemars::schema_for!(RenderConfig));
    let atmosphere = section(schemars::schema_for!(AtmosphereConfig));
    let props = &mut root["properties"];
    let describe = |mut v: Value, old: &Value| {
        if let Some(d) = old.get("description") {
            v["description"] = d.clone();
        }
        v
    };
    props["sensors"]["items"] = sensor;
    props["render"] = describe(render, &props["render"]);
    props["atmosphere"] = describe(atmosphere, &props["atmosphere"]);
    root["$defs"] = Value::Object(defs);
    serde_json::to_string_pretty(&root).expect("schema serialises") + "\n"
}
