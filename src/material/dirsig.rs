//! DIRSIG import: DIRSIG4 material databases (`.mat`) and classic emissivity
//! files (`.ems`).
//!
//! # `.mat`
//! `MATERIAL_ENTRY { … }` blocks of `KEY = VALUE` lines and nested
//! `NAME { … }` blocks. irsig reads `ID`, `NAME`, `DOUBLE_SIDED`,
//! `TEMP_SOLVER_NAME` (must be `Therm`), the `TEMP_SOLVER` block and
//! `SURFACE_PROPERTIES/EMISSIVITY_PROP` (`FILENAME`, `SPECULAR_FRACTION`).
//! Other keys (editor colour, radiometry solver settings) are ignored. `#`
//! starts a comment only at the start of a line (names contain it).
//!
//! THERM's classic units, converted here to SI (see `../shared/README.md`;
//! inferred from steel, k = 464.4 → 54.0 W/(m·K), and water, 5.13 → 0.597):
//!
//! | key | file unit | SI |
//! |---|---|---|
//! | `THERMAL_CONDUCTIVITY` | cal/(cm·h·°C) | × 4.1868/36 = 0.1163 → W/(m·K) (i.e. ÷ 8.598) |
//! | `SPECIFIC_HEAT` | cal/(g·°C) | × 4186.8 → J/(kg·K) |
//! | `MASS_DENSITY` | g/cm³ | × 1000 → kg/m³ |
//! | `THICKNESS` | cm | ÷ 100 → m |
//! | `SOLAR_ABSORPTION`, `THERMAL_EMISSIVITY`, `EXPOSED_AREA` | fraction | as is |
//! | `SELF_GENERATED_POWER` (if present) | W/m² (assumed) | as is |
//!
//! The calorie is the International Table calorie (4.1868 J).
//!
//! Emissivity files named by `FILENAME` are looked up relative to the `.mat`
//! file; when absent there, the file's base name next to the `.mat` is tried
//! (DIRSIG scenes keep them in `emissivity/`). When neither exists, the
//! material is grey at `THERMAL_EMISSIVITY` and a warning is recorded in
//! [`MaterialDb::warnings`].
//!
//! # `.ems`
//! Line 1: the number of curves N. Then 91 lines, one per view zenith angle
//! 0°, 1°, …, 90°: irsig reads each as a 1-based (possibly fractional) curve
//! index — the curve that applies at that angle, interpolating linearly
//! between curves for fractional values. (With N = 1, as in `gray.ems`, every
//! line is `1.0` and the curve applies at every angle; the interpretation
//! only matters for N > 1.) Then N blocks `CURVE_BEGIN` followed by
//! `wavelength_µm emissivity` pairs. An angle-independent file becomes a
//! single-row [`EmissivityCurve`] (`angles_deg` empty); otherwise 91 rows at
//! 0..=90°, every curve resampled on the union of their wavelengths.
//!
//! Takes DIRSIG files; gives [`Material`]s in SI units and
//! [`EmissivityCurve`]s (curves resampled by [`crate::math::interp1d`]).
//! Must not know irsig's JSON database format ([`super::db`]).

use std::path::Path;

use super::{EmissivityCurve, Material, MaterialDb};
use crate::error::{Error, Location, Result};
use crate::math::interp1d;

/// cal/(cm·h·°C) → W/(m·K): 4.1868 J / (0.01 m · 3600 s).
pub const THERM_CONDUCTIVITY_TO_SI: f64 = 4.1868 / 36.0;
/// cal/(g·°C) → J/(kg·K).
pub const THERM_SPECIFIC_HEAT_TO_SI: f64 = 4186.8;
/// g/cm³ → kg/m³.
pub const THERM_DENSITY_TO_SI: f64 = 1000.0;
/// cm → m.
pub const THERM_THICKNESS_TO_SI: f64 = 0.01;

/// A `{ … }` block of a DIRSIG text file.
#[derive(Debug, Default)]
struct Block {
    name: String,
    line: usize,
    entries: Vec<(String, String, usize)>,
    children: Vec<Block>,
}

impl Block {
    fn get(&self, key: &str) -> Option<(&str, usize)> {
        self.entries
            .iter()
            .find(|(k, _, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v, l)| (v.as_str(), *l))
    }
    fn child(&self, name: &str) -> Option<&Block> {
        self.children
            .iter()
            .find(|b| b.name.eq_ignore_ascii_case(name))
    }
}

/// Parse the nested block structure of a DIRSIG text file.
fn parse_blocks(text: &str, path: &Path) -> Result<Block> {
    let mut stack = vec![Block {
        name: "<root>".into(),
        ..Default::default()
    }];
    let mut pending_name: Option<(String, usize)> = None;
    for (n, raw) in text.lines().enumerate() {
        let ln = n + 1;
        // `#` starts a comment only at the start of a line: names such as
        // `Class #2` contain it.
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if line == "}" {
            if stack.len() == 1 {
                return Err(Error::parse(
                    Location::file(path).at_line(ln),
                    "`}` without a matching `{`",
                ));
            }
            let b = stack.pop().expect("len > 1");
            stack.last_mut().expect("root").children.push(b);
            continue;
        }
        if let Some(head) = line.strip_suffix('{') {
            let head = head.trim();
            let (name, at) = if head.is_empty() {
                pending_name.take().ok_or_else(|| {
                    Error::parse(Location::file(path).at_line(ln), "`{` without a block name")
                })?
            } else {
                (head.to_string(), ln)
            };
            stack.push(Block {
                name,
                line: at,
                ..Default::default()
            });
            continue;
        }
        if let Some((k, v)) = line.split_once('=') {
            stack.last_mut().expect("root").entries.push((
                k.trim().to_string(),
                v.trim().to_string(),
                ln,
            ));
            pending_name = None;
        } else {
            // A bare word: a block name whose `{` is on the next line.
            pending_name = Some((line.to_string(), ln));
        }
    }
    if stack.len() > 1 {
        let b = stack.last().expect("len > 1");
        return Err(Error::parse(
            Location::file(path).at_line(b.line),
            format!("block `{}` is not closed (missing `}}`)", b.name),
        ));
    }
    Ok(stack.pop().expect("root"))
}

/// Load a DIRSIG4 `.mat` material database, converting THERM units to SI.
/// Every `MATERIAL_ENTRY` must have a `Therm` temperature solver. Errors name
/// the file, line and key.
pub fn load_mat(path: &Path) -> Result<MaterialDb> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let root = parse_blocks(&text, path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut db = MaterialDb::new();
    let entries: Vec<&Block> = root
        .children
        .iter()
        .filter(|b| b.name.eq_ignore_ascii_case("MATERIAL_ENTRY"))
        .collect();
    if entries.is_empty() {
        return Err(Error::parse(
            Location::file(path),
            "no `MATERIAL_ENTRY { … }` block found: not a DIRSIG4 material file?",
        ));
    }
    for b in entries {
        let loc = |key: &str, line: usize| Location::file(path).at_line(line).with_field(key);
        let req = |blk: &Block, key: &str| -> Result<(String, usize)> {
            blk.get(key)
                .map(|(v, l)| (v.to_string(), l))
                .ok_or_else(|| {
                    Error::parse(
                        Location::file(path).at_line(blk.line).with_field(key),
                        format!("`{}` block has no `{key}`", blk.name),
                    )
                })
        };
        let num = |blk: &Block, key: &str| -> Result<f64> {
            let (v, l) = req(blk, key)?;
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| Error::parse(loc(key, l), format!("expected a number, found `{v}`")))
        };
        let (id_s, id_line) = req(b, "ID")?;
        let id: u32 = id_s.parse().map_err(|_| {
            Error::parse(
                loc("ID", id_line),
                format!("expected a non-negative integer id, found `{id_s}`"),
            )
        })?;
        let (name, _) = req(b, "NAME")?;
        let double_sided = match b.get("DOUBLE_SIDED") {
            None => false,
            Some((v, l)) => parse_bool(v).ok_or_else(|| {
                Error::parse(
                    loc("DOUBLE_SIDED", l),
                    format!("expected TRUE or FALSE, found `{v}`"),
                )
            })?,
        };
        let (solver, sl) = req(b, "TEMP_SOLVER_NAME")?;
        if !solver.eq_ignore_ascii_case("Therm") {
            return Err(Error::parse(
                loc("TEMP_SOLVER_NAME", sl),
                format!(
                    "material `{name}`: temperature solver `{solver}` is not supported (expected `Therm`)"
                ),
            ));
        }
        let ts = b.child("TEMP_SOLVER").ok_or_else(|| {
            Error::parse(
                loc("TEMP_SOLVER", b.line),
                format!("material `{name}` has no `TEMP_SOLVER {{ … }}` block"),
            )
        })?;
        let self_power = match ts.get("SELF_GENERATED_POWER") {
            Some(_) => num(ts, "SELF_GENERATED_POWER")?,
            None => 0.0,
        };
        let mut specular = match ts.get("SPECULARITY") {
            Some(_) => num(ts, "SPECULARITY")?,
            None => 0.0,
        };
        let mut curve = None;
        if let Some(ep) = b
            .child("SURFACE_PROPERTIES")
            .and_then(|s| s.child("EMISSIVITY_PROP"))
        {
            if ep.get("SPECULAR_FRACTION").is_some() {
                specular = num(ep, "SPECULAR_FRACTION")?;
            }
            if let Some((f, fl)) = ep.get("FILENAME") {
                let direct = base.join(f);
                let by_name = Path::new(f).file_name().map(|n| base.join(n));
                let found = if direct.is_file() {
                    Some(direct)
                } else {
                    by_name.filter(|p| p.is_file())
                };
                match found {
                    Some(p) => {
                        curve = Some(read_ems(&p).map_err(|e| {
                            Error::parse(loc("FILENAME", fl), format!("material `{name}`: {e}"))
                        })?)
                    }
                    None => db.warnings.push(format!(
                        "{}:{fl}: material `{name}`: emissivity file `{f}` not found; using grey THERMAL_EMISSIVITY",
                        path.display()
                    )),
                }
            }
        }
        let m = Material {
            id,
            name: name.clone(),
            specific_heat_j_kg_k: num(ts, "SPECIFIC_HEAT")? * THERM_SPECIFIC_HEAT_TO_SI,
            conductivity_w_m_k: num(ts, "THERMAL_CONDUCTIVITY")? * THERM_CONDUCTIVITY_TO_SI,
            density_kg_m3: num(ts, "MASS_DENSITY")? * THERM_DENSITY_TO_SI,
            thickness_m: num(ts, "THICKNESS")? * THERM_THICKNESS_TO_SI,
            solar_absorptivity: num(ts, "SOLAR_ABSORPTION")?,
            thermal_emissivity: num(ts, "THERMAL_EMISSIVITY")?,
            exposed_area: match ts.get("EXPOSED_AREA") {
                Some(_) => num(ts, "EXPOSED_AREA")?,
                None => 0.0,
            },
            self_power_w_m2: self_power,
            specular_fraction: specular,
            transmissivity: 0.0,
            emissivity_curve: curve,
            double_sided,
            surface_energy: None,
        };
        if let Some((field, msg)) = m.problems().into_iter().next() {
            let key = match field.as_str() {
                "specific_heat_j_kg_k" => "SPECIFIC_HEAT",
                "conductivity_w_m_k" => "THERMAL_CONDUCTIVITY",
                "density_kg_m3" => "MASS_DENSITY",
                "thickness_m" => "THICKNESS",
                "solar_absorptivity" => "SOLAR_ABSORPTION",
                "thermal_emissivity" => "THERMAL_EMISSIVITY",
                "exposed_area" => "EXPOSED_AREA",
                "specular_fraction" => "SPECULAR_FRACTION",
                other => other,
            };
            let line = ts.get(key).map(|(_, l)| l).unwrap_or(b.line);
            return Err(Error::parse(
                loc(key, line),
                format!("material `{name}` (after conversion to SI): {msg}"),
            ));
        }
        if db.index_of(&name).is_some() {
            return Err(Error::parse(
                loc("NAME", b.line),
                format!("material name `{name}` is defined twice"),
            ));
        }
        db.insert(
            m,
            Some(super::MaterialSource::Text(format!(
                "DIRSIG4 material file {}, line {} (THERM units converted to SI)",
                path.display(),
                b.line
            ))),
            path,
        )?;
    }
    Ok(db)
}

fn parse_bool(v: &str) -> Option<bool> {
    match v.to_ascii_uppercase().as_str() {
        "TRUE" | "T" | "YES" | "1" => Some(true),
        "FALSE" | "F" | "NO" | "0" => Some(false),
        _ => None,
    }
}

/// Read a DIRSIG classic emissivity file (`.ems`; format in the module docs).
pub fn read_ems(path: &Path) -> Result<EmissivityCurve> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(n, l)| (n + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let at = |n: usize| Location::file(path).at_line(n);
    let (n0, first) = lines
        .next()
        .ok_or_else(|| Error::parse(Location::file(path), "empty emissivity file"))?;
    let count: usize = first
        .parse::<f64>()
        .ok()
        .filter(|c| c.fract() == 0.0 && *c >= 1.0)
        .map(|c| c as usize)
        .ok_or_else(|| {
            Error::parse(
                at(n0),
                format!("expected the number of curves (an integer ≥ 1), found `{first}`"),
            )
        })?;
    let mut angular = Vec::with_capacity(91);
    for k in 0..91 {
        let (n, l) = lines.next().ok_or_else(|| {
            Error::parse(
                Location::file(path),
                format!("expected 91 angular lines (0..=90°), file ends after {k}"),
            )
        })?;
        let c: f64 = l.parse().map_err(|_| {
            Error::parse(
                at(n),
                format!("angular line for {k}°: expected a curve index, found `{l}`"),
            )
        })?;
        if !(1.0..=count as f64).contains(&c) {
            return Err(Error::parse(
                at(n),
                format!("angular line for {k}°: curve index {c} outside 1..={count}"),
            ));
        }
        angular.push(c);
    }
    let mut curves: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    for (n, l) in lines {
        if l.eq_ignore_ascii_case("CURVE_BEGIN") {
            curves.push((Vec::new(), Vec::new()));
            continue;
        }
        if l.eq_ignore_ascii_case("CURVE_END") {
            continue;
        }
        let cur = curves
            .last_mut()
            .ok_or_else(|| Error::parse(at(n), format!("expected `CURVE_BEGIN`, found `{l}`")))?;
        let v: Vec<f64> = l
            .split_whitespace()
            .map(|s| s.parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| {
                Error::parse(
                    at(n),
                    format!("expected `wavelength_um emissivity`, found `{l}`"),
                )
            })?;
        if v.len() != 2 {
            return Err(Error::parse(
                at(n),
                format!(
                    "expected 2 numbers (wavelength µm, emissivity), found {}",
                    v.len()
                ),
            ));
        }
        if let Some(&prev) = cur.0.last() {
            if v[0] <= prev {
                return Err(Error::parse(
                    at(n),
                    "wavelengths must increase within a curve",
                ));
            }
        }
        if !(0.0..=1.0).contains(&v[1]) {
            return Err(Error::parse(
                at(n),
                format!("emissivity {} outside 0..=1", v[1]),
            ));
        }
        cur.0.push(v[0]);
        cur.1.push(v[1]);
    }
    if curves.len() != count {
        return Err(Error::parse(
            Location::file(path),
            format!(
                "header says {count} curve(s), found {} `CURVE_BEGIN` block(s)",
                curves.len()
            ),
        ));
    }
    if let Some(i) = curves.iter().position(|c| c.0.is_empty()) {
        return Err(Error::parse(
            Location::file(path),
            format!("curve {} has no points", i + 1),
        ));
    }
    // Union wavelength grid.
    let mut wl: Vec<f64> = curves.iter().flat_map(|c| c.0.iter().copied()).collect();
    wl.sort_by(f64::total_cmp);
    wl.dedup();
    let resampled: Vec<Vec<f64>> = curves
        .iter()
        .map(|(x, y)| wl.iter().map(|&w| interp1d(x, y, w)).collect())
        .collect();
    let row_for = |c: f64| -> Vec<f64> {
        let lo = (c.floor() as usize).clamp(1, count) - 1;
        let hi = (c.ceil() as usize).clamp(1, count) - 1;
        let t = c - c.floor();
        resampled[lo]
            .iter()
            .zip(&resampled[hi])
            .map(|(a, b)| (1.0 - t) * a + t * b)
            .collect()
    };
    if angular.iter().all(|&c| c == angular[0]) {
        Ok(EmissivityCurve {
            emissivity: vec![row_for(angular[0])],
            wavelengths_um: wl,
            angles_deg: vec![],
        })
    } else {
        Ok(EmissivityCurve {
            emissivity: angular.iter().map(|&c| row_for(c)).collect(),
            wavelengths_um: wl,
            angles_deg: (0..=90).map(f64::from).collect(),
        })
    }
}
