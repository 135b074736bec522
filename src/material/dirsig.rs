//! DIRSIG import: DIRSIG4 material databases (`.mat`) and classic emissivity
//! files (`.ems`).
//!
//! # `.mat`
//! `MATERIAL_ENTRY { … }` blocks of `KEY = VALUE` lines and nested
//! `NAME { … }` blocks. irsig reads `ID` (a number, or a label such as
//! `Gidder_mat`, DIRSIG ≥ 4.7, which gets the next number after the file's numeric
//! IDs), `NAME` (an entry without one, such as a `MATERIAL_MAP` proxy, is named by its
//! ID), `DOUBLE_SIDED`, `TEMP_SOLVER_NAME`, the `TEMP_SOLVER` block and
//! `SURFACE_PROPERTIES/EMISSIVITY_PROP` (`FILENAME`, or a `ShellTarget`'s
//! `EMISSIVITY_FILE`, which may also sit in `REFLECTANCE_PROP`; `SPECULAR_FRACTION`). Entries
//! whose solver is not `Therm` (`Null`, `DataDriven`, …), that have none, or whose
//! `Therm` block lacks a property THERM needs (or the block itself) are left
//! out with a warning in [`MaterialDb::warnings`]: a library loads for the entries a
//! scene uses.
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
//! | `SOLAR_ABSORPTION` (else `VISIBLE_EMISSIVITY`), `THERMAL_EMISSIVITY`, `EXPOSED_AREA` | fraction | as is |
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
//! (DIRSIG documentation "Emissivity file (.ems)"; `../shared/data/dirsig/FORMAT_NOTES.md`.)
//! Line 1: the number of curves N. Then 91 angular weights, one per view zenith angle
//! 0°, 1°, …, 90°, each 0..=1: the emissivity at that angle is the weight times the
//! spectral curve (real files fall off toward grazing: `muddy_water.ems` 0.456 at 80°,
//! 0 at 89°). Then N curves in either form:
//!
//! - new: a `CURVE_BEGIN` line, then `wavelength_µm emissivity` pairs (blanks or tabs),
//!   wavelengths increasing, any sampling;
//! - old: a line holding the curve's 0-based index (`0`, `1`, …), then
//!   `wavenumber_cm⁻¹ emissivity` pairs, wavenumbers decreasing (39850 → 350 cm⁻¹ in
//!   real files), turned to µm by λ = 10⁴/ν.
//!
//! Several curves are DIRSIG's "texture" variants of one material (spectral variety
//! within a surface); irsig has no emissivity texture and uses their mean, every curve
//! resampled on the union of their wavelengths. A file whose weights are all 1 becomes
//! a single-row [`EmissivityCurve`] (`angles_deg` empty); otherwise 91 rows at 0..=90°.
//!
//! Takes DIRSIG files; gives [`Material`]s in SI units and
//! [`EmissivityCurve`]s (curves resampled by [`crate::math::interp1d`]).
//! Must not know irsig's JSON database format ([`super::db`]).

use std::path::{Path, PathBuf};

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
pub(crate) struct Block {
    pub(crate) name: String,
    pub(crate) line: usize,
    pub(crate) entries: Vec<(String, String, usize)>,
    pub(crate) children: Vec<Block>,
}

impl Block {
    pub(crate) fn get(&self, key: &str) -> Option<(&str, usize)> {
        self.entries
            .iter()
            .find(|(k, _, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v, l)| (v.as_str(), *l))
    }
    pub(crate) fn child(&self, name: &str) -> Option<&Block> {
        self.children
            .iter()
            .find(|b| b.name.eq_ignore_ascii_case(name))
    }
}

/// Parse the nested block structure of a DIRSIG text file.
pub(crate) fn parse_blocks(text: &str, path: &Path) -> Result<Block> {
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

/// The temperature solver of a `.mat` entry (`TEMP_SOLVER_NAME`).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum TempSolver {
    /// THERM: irsig's slab model ([`MatEntry::material`] holds the properties in SI).
    Therm,
    /// `DataDriven`: the surface temperature is given (`TEMPERATURE`, taken as kelvin, as
    /// DIRSIG's radiometry uses; `../shared/data/dirsig/FORMAT_NOTES.md`: a hypersonic
    /// vehicle skin at 1500).
    DataDriven {
        /// The temperature, K.
        temperature_k: f64,
    },
    /// Another solver (`Null`, `Balfour`, …): no thermal model irsig can use.
    Other(String),
    /// No `TEMP_SOLVER_NAME`.
    Missing,
}

/// One `MATERIAL_ENTRY` of a `.mat` file, whatever its solver.
#[derive(Debug, Clone)]
pub struct MatEntry {
    /// `ID` as written: a number or a label (`Gidder_mat`).
    pub id: String,
    /// The numeric id irsig gives it (a label gets the next number after the file's
    /// numeric IDs).
    pub numeric_id: u32,
    /// `NAME`.
    pub name: String,
    /// Line of the entry.
    pub line: usize,
    /// The temperature solver.
    pub solver: TempSolver,
    /// The material in SI: for `Therm` entries that map onto the slab model; `None`
    /// otherwise (see `skipped`).
    pub material: Option<Material>,
    /// Why the entry gives no [`Material`] (file, line, reason), if it does not.
    pub skipped: Option<String>,
    /// Spectral emissivity: from `EMISSIVITY_PROP` (`.ems`), else from
    /// `REFLECTANCE_PROP` `SimpleReflectance` as 1 − ρ (an opaque surface, Kirchhoff's
    /// law); read for every solver.
    pub emissivity: Option<EmissivityCurve>,
    /// `DOUBLE_SIDED`.
    pub double_sided: bool,
    /// `SPECULAR_FRACTION` (or `SPECULARITY`), 0 when absent.
    pub specular_fraction: f64,
    /// Non-fatal notes about the entry (a missing emissivity file), each naming file
    /// and line.
    pub warnings: Vec<String>,
}

/// Every entry of a `.mat` file.
#[derive(Debug, Clone, Default)]
pub struct MatFile {
    /// The entries, in file order.
    pub entries: Vec<MatEntry>,
}

/// Load a DIRSIG4 `.mat` material database, converting THERM units to SI: the
/// entries [`read_mat`] gives a [`Material`]; the others are left out with a warning in
/// [`MaterialDb::warnings`]. Errors name the file, line and key.
pub fn load_mat(path: &Path) -> Result<MaterialDb> {
    let file = read_mat(path, &[])?;
    let mut db = MaterialDb::new();
    for e in file.entries {
        db.warnings.extend(e.warnings);
        let Some(m) = e.material else {
            db.warnings.extend(e.skipped);
            continue;
        };
        if db.index_of(&m.name).is_some() {
            return Err(Error::parse(
                Location::file(path).at_line(e.line).with_field("NAME"),
                format!("material name `{}` is defined twice", m.name),
            ));
        }
        db.insert(
            m,
            Some(super::MaterialSource::Text(format!(
                "DIRSIG4 material file {}, line {}{} (THERM units converted to SI)",
                path.display(),
                e.line,
                if e.id.parse::<u32>().is_ok() {
                    String::new()
                } else {
                    format!(", ID `{}`", e.id)
                }
            ))),
            path,
        )?;
    }
    Ok(db)
}

/// Find a file a `.mat` names (`FILENAME = emissivity/x.ems`): relative to each of
/// `dirs` (a scene's `<emsdirectory>`), then to the `.mat` file's folder, then its base
/// name in that folder.
fn find_relative(f: &str, base: &Path, dirs: &[PathBuf]) -> Option<PathBuf> {
    let name = Path::new(f).file_name().map(|n| base.join(n));
    dirs.iter()
        .map(|d| d.join(f))
        .chain([base.join(f)])
        .chain(name)
        .find(|p| p.is_file())
}

/// Read every `MATERIAL_ENTRY` of a DIRSIG4 `.mat` file, whatever its solver (format in
/// the module docs). Emissivity files are looked up relative to `ems_dirs`, then to the
/// `.mat` file (see [`find_relative`]). Errors (naming file, line and key) are kept for
/// real corruption: unbalanced braces, an entry without `ID`/`NAME`, a `Therm` entry
/// with a missing or non-numeric property, an unreadable emissivity file.
pub fn read_mat(path: &Path, ems_dirs: &[PathBuf]) -> Result<MatFile> {
    read_mat_with(path, ems_dirs, &mut |_| None)
}

/// As [`read_mat`]; a file found nowhere else is asked of `fallback` (given the name as
/// written), which may say where it is.
pub fn read_mat_with(
    path: &Path,
    ems_dirs: &[PathBuf],
    fallback: &mut dyn FnMut(&str) -> Option<PathBuf>,
) -> Result<MatFile> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let root = parse_blocks(&text, path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut out = MatFile::default();
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
    let mut next_label_id = entries
        .iter()
        .filter_map(|b| b.get("ID").and_then(|(v, _)| v.parse::<u32>().ok()))
        .max()
        .unwrap_or(0);
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
        // A label ID (`ID = Gidder_mat`, DIRSIG ≥ 4.7) gets the next number after the
        // file's numeric IDs; the label stays in the material's source.
        let id = match id_s.parse::<u32>() {
            Ok(id) => id,
            Err(_) if !id_s.is_empty() && !id_s.contains(char::is_whitespace) => {
                next_label_id += 1;
                next_label_id
            }
            Err(_) => {
                return Err(Error::parse(
                    loc("ID", id_line),
                    format!("expected an integer or a label without blanks, found `{id_s}`"),
                ));
            }
        };
        // An entry without NAME (a `MATERIAL_MAP` proxy, as in the material-map
        // entries protoDIRSIG's scene-coverage tests write) is named by its ID.
        let (name, no_name) = match b.get("NAME") {
            Some((v, _)) => (v.to_string(), false),
            None => (id_s.clone(), true),
        };
        let double_sided = match b.get("DOUBLE_SIDED") {
            None => false,
            Some((v, l)) => parse_bool(v).ok_or_else(|| {
                Error::parse(
                    loc("DOUBLE_SIDED", l),
                    format!("expected TRUE or FALSE, found `{v}`"),
                )
            })?,
        };
        let solver_kv = b.get("TEMP_SOLVER_NAME");
        let ts = b.child("TEMP_SOLVER");
        let solver = match solver_kv {
            None => TempSolver::Missing,
            Some((v, _)) if v.eq_ignore_ascii_case("Therm") => TempSolver::Therm,
            Some((v, l)) if v.eq_ignore_ascii_case("DataDriven") => {
                let t = ts.and_then(|ts| ts.get("TEMPERATURE"));
                let Some((tv, tl)) = t else {
                    return Err(Error::parse(
                        loc("TEMPERATURE", l),
                        format!("material `{name}`: `DataDriven` solver without `TEMPERATURE`"),
                    ));
                };
                let k = tv.parse::<f64>().ok().filter(|k| k.is_finite() && *k > 0.0);
                let Some(temperature_k) = k else {
                    return Err(Error::parse(
                        loc("TEMPERATURE", tl),
                        format!("material `{name}`: expected a temperature > 0 K, found `{tv}`"),
                    ));
                };
                TempSolver::DataDriven { temperature_k }
            }
            Some((v, _)) => TempSolver::Other(v.to_string()),
        };
        // Surface properties, read for every solver.
        let mut specular = match ts.and_then(|ts| ts.get("SPECULARITY")) {
            Some(_) => num(ts.expect("has key"), "SPECULARITY")?,
            None => 0.0,
        };
        let mut curve = None;
        let mut warnings = Vec::new();
        let props = b.child("SURFACE_PROPERTIES");
        if let Some(ep) = props.and_then(|s| s.child("EMISSIVITY_PROP")) {
            if ep.get("SPECULAR_FRACTION").is_some() {
                specular = num(ep, "SPECULAR_FRACTION")?;
            }
            // `ClassicEmissivity` names its file `FILENAME`; a `ShellTarget` property
            // `EMISSIVITY_FILE` (RIT's Tacoma scene, as protoDIRSIG's scene_coverage.py
            // reads it).
            if let Some((f, fl)) = ep.get("FILENAME").or_else(|| ep.get("EMISSIVITY_FILE")) {
                match find_relative(f, base, ems_dirs).or_else(|| fallback(f)) {
                    Some(p) => {
                        curve = Some(read_ems(&p).map_err(|e| {
                            Error::parse(loc("FILENAME", fl), format!("material `{name}`: {e}"))
                        })?)
                    }
                    None => warnings.push(format!(
                        "{}:{fl}: material `{name}`: emissivity file `{f}` not found; using grey THERMAL_EMISSIVITY",
                        path.display()
                    )),
                }
            }
        }
        if curve.is_none() {
            if let Some(rp) = props.and_then(|s| s.child("REFLECTANCE_PROP")) {
                if let Some((f, fl)) = rp.get("EMISSIVITY_FILE") {
                    // A `ShellTarget` reflectance property carries its emissivity file.
                    match find_relative(f, base, ems_dirs).or_else(|| fallback(f)) {
                        Some(p) => {
                            curve = Some(read_ems(&p).map_err(|e| {
                                Error::parse(
                                    loc("EMISSIVITY_FILE", fl),
                                    format!("material `{name}`: {e}"),
                                )
                            })?)
                        }
                        None => warnings.push(format!(
                            "{}:{fl}: material `{name}`: emissivity file `{f}` not found; using grey THERMAL_EMISSIVITY",
                            path.display()
                        )),
                    }
                } else if let Some((f, fl)) = rp.get("TXT_FILENAME").or_else(|| rp.get("FILENAME"))
                {
                    match find_relative(f, base, ems_dirs).or_else(|| fallback(f)) {
                        Some(p) => {
                            curve = Some(read_reflectance_as_emissivity(&p).map_err(|e| {
                                Error::parse(
                                    loc("TXT_FILENAME", fl),
                                    format!("material `{name}`: {e}"),
                                )
                            })?)
                        }
                        None => warnings.push(format!(
                            "{}:{fl}: material `{name}`: reflectance file `{f}` not found",
                            path.display()
                        )),
                    }
                }
            }
        }
        if no_name {
            warnings.push(format!(
                "{}:{}: material entry with ID {id_s} has no NAME: named `{id_s}`",
                path.display(),
                b.line
            ));
        }
        let mut entry = MatEntry {
            id: id_s.clone(),
            numeric_id: id,
            name: name.clone(),
            line: b.line,
            solver: solver.clone(),
            material: None,
            skipped: None,
            emissivity: curve.clone(),
            double_sided,
            specular_fraction: specular,
            warnings,
        };
        // Only THERM maps onto irsig's slab model. Other solvers (Null, DataDriven, …)
        // and entries without one give no material here, with the reason, so that a
        // library is usable for the entries a scene needs (the scene importer maps
        // `DataDriven` to fixed-temperature parts).
        if solver != TempSolver::Therm {
            let line = solver_kv.map_or(b.line, |(_, l)| l);
            let why = match &solver {
                TempSolver::Missing => "has no temperature solver (TEMP_SOLVER_NAME)".to_string(),
                TempSolver::DataDriven { temperature_k } => format!(
                    "uses temperature solver `DataDriven` (TEMPERATURE = {temperature_k}), which a \
                     material database cannot hold; give the parts that use it \
                     `fixed_temperature_k` (`irsig import dirsig` does)"
                ),
                TempSolver::Other(v) => {
                    format!("uses temperature solver `{v}`; irsig imports `Therm` only")
                }
                TempSolver::Therm => unreachable!("excluded above"),
            };
            entry.skipped = Some(
                Error::parse(
                    loc("TEMP_SOLVER_NAME", line),
                    format!(
                        "material `{name}` (ID {id_s}) {why}: not loaded (a surface that uses it is an error)"
                    ),
                )
                .to_string(),
            );
            out.entries.push(entry);
            continue;
        }
        // A THERM entry short of a property THERM needs is left out like the other
        // unusable entries (the library still loads for the entries a scene uses). The
        // solar absorptance may be given as `VISIBLE_EMISSIVITY`, the older key of the
        // DIRSIG manual's examples (nefmaterial-howto.html): a surface's solar-band
        // emissivity is its solar absorptance (Kirchhoff's law).
        let solar_key = match ts {
            Some(ts)
                if ts.get("SOLAR_ABSORPTION").is_none()
                    && ts.get("VISIBLE_EMISSIVITY").is_some() =>
            {
                "VISIBLE_EMISSIVITY"
            }
            _ => "SOLAR_ABSORPTION",
        };
        let needed = [
            "SPECIFIC_HEAT",
            "THERMAL_CONDUCTIVITY",
            "MASS_DENSITY",
            "THICKNESS",
            solar_key,
            "THERMAL_EMISSIVITY",
        ];
        let missing: Vec<&str> = match ts {
            None => vec!["TEMP_SOLVER { … }"],
            Some(ts) => needed.into_iter().filter(|k| ts.get(k).is_none()).collect(),
        };
        if !missing.is_empty() {
            let line = ts.map_or(b.line, |t| t.line);
            entry.skipped = Some(
                Error::parse(
                    loc(missing[0], line),
                    format!(
                        "material `{name}` (ID {id_s}): its Therm solver has no {}: not loaded \
                         (a surface that uses it is an error)",
                        missing.join(", ")
                    ),
                )
                .to_string(),
            );
            out.entries.push(entry);
            continue;
        }
        let ts = ts.expect("checked above");
        let self_power = match ts.get("SELF_GENERATED_POWER") {
            Some(_) => num(ts, "SELF_GENERATED_POWER")?,
            None => 0.0,
        };
        let m = Material {
            id,
            name: name.clone(),
            specific_heat_j_kg_k: num(ts, "SPECIFIC_HEAT")? * THERM_SPECIFIC_HEAT_TO_SI,
            conductivity_w_m_k: num(ts, "THERMAL_CONDUCTIVITY")? * THERM_CONDUCTIVITY_TO_SI,
            density_kg_m3: num(ts, "MASS_DENSITY")? * THERM_DENSITY_TO_SI,
            thickness_m: num(ts, "THICKNESS")? * THERM_THICKNESS_TO_SI,
            solar_absorptivity: num(ts, solar_key)?,
            thermal_emissivity: num(ts, "THERMAL_EMISSIVITY")?,
            exposed_area: match ts.get("EXPOSED_AREA") {
                Some(_) => num(ts, "EXPOSED_AREA")?,
                None => 0.0,
            },
            self_power_w_m2: self_power,
            specular_fraction: specular,
            specular_roughness: None,
            transmissivity: 0.0,
            emissivity_curve: curve,
            double_sided,
            surface_energy: None,
            convection: Default::default(),
            layers: Vec::new(),
            back: None,
        };
        // Real libraries hold THERM entries with THICKNESS = 0 (anadirsig.mat: water,
        // grass) whose meaning in THERM is not documented; irsig's slab cannot represent
        // them, so such entries are left out with a warning.
        if m.thickness_m <= 0.0 {
            let (v, line) = ts.get("THICKNESS").unwrap_or(("", b.line));
            entry.skipped = Some(
                Error::parse(
                    loc("THICKNESS", line),
                    format!(
                        "material `{name}` (ID {id_s}): THICKNESS = {v} (≤ 0) has no equivalent in \
                         irsig's slab model: not loaded (a surface that uses it is an error)"
                    ),
                )
                .to_string(),
            );
            out.entries.push(entry);
            continue;
        }
        if let Some((field, msg)) = m.problems().into_iter().next() {
            let key = match field.as_str() {
                "specific_heat_j_kg_k" => "SPECIFIC_HEAT",
                "conductivity_w_m_k" => "THERMAL_CONDUCTIVITY",
                "density_kg_m3" => "MASS_DENSITY",
                "thickness_m" => "THICKNESS",
                "solar_absorptivity" => solar_key,
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
        entry.material = Some(m);
        out.entries.push(entry);
    }
    Ok(out)
}

/// Read a DIRSIG `SimpleReflectance` text file (`wavelength_µm reflectance` per line,
/// blanks, tabs or commas, CRLF allowed) as the emissivity of an opaque surface,
/// ε(λ) = 1 − ρ(λ) (Kirchhoff's law for zero transmittance).
pub fn read_reflectance_as_emissivity(path: &Path) -> Result<EmissivityCurve> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let (mut wl, mut em) = (Vec::new(), Vec::new());
    for (n, l) in text.lines().enumerate() {
        let l = l.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let at = Location::file(path).at_line(n + 1);
        let v: Vec<f64> = l
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .map(str::parse)
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| {
                Error::parse(
                    at.clone(),
                    format!("expected `wavelength_µm reflectance`, found `{l}`"),
                )
            })?;
        if v.len() != 2 {
            return Err(Error::parse(
                at,
                format!(
                    "expected 2 numbers (wavelength µm, reflectance), found {}",
                    v.len()
                ),
            ));
        }
        if !(0.0..=1.0).contains(&v[1]) {
            return Err(Error::parse(
                at,
                format!("reflectance {} outside 0..=1", v[1]),
            ));
        }
        if wl.last().is_some_and(|&p| v[0] <= p) || !v[0].is_finite() || v[0] <= 0.0 {
            return Err(Error::parse(at, "wavelengths must be > 0 and increase"));
        }
        wl.push(v[0]);
        em.push(1.0 - v[1]);
    }
    if wl.is_empty() {
        return Err(Error::parse(Location::file(path), "no reflectance values"));
    }
    Ok(EmissivityCurve {
        wavelengths_um: wl,
        emissivity: vec![em],
        angles_deg: vec![],
    })
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
    let mut weights = Vec::with_capacity(91);
    for k in 0..91 {
        let (n, l) = lines.next().ok_or_else(|| {
            Error::parse(
                Location::file(path),
                format!("expected 91 angular lines (0..=90°), file ends after {k}"),
            )
        })?;
        let w: f64 = l.parse().map_err(|_| {
            Error::parse(
                at(n),
                format!("angular weight for {k}°: expected a number 0..=1, found `{l}`"),
            )
        })?;
        if !(0.0..=1.0).contains(&w) {
            return Err(Error::parse(
                at(n),
                format!("angular weight for {k}°: {w} is outside 0..=1"),
            ));
        }
        weights.push(w);
    }
    // Curves: `CURVE_BEGIN` then `µm emissivity` pairs (new format), or a line holding the
    // curve's 0-based index then `cm⁻¹ emissivity` pairs (old format).
    struct Curve {
        wavenumber: bool,
        line: usize,
        x: Vec<f64>,
        y: Vec<f64>,
    }
    let mut curves: Vec<Curve> = Vec::new();
    for (n, l) in lines {
        if l.eq_ignore_ascii_case("CURVE_BEGIN") {
            curves.push(Curve {
                wavenumber: false,
                line: n,
                x: Vec::new(),
                y: Vec::new(),
            });
            continue;
        }
        if l.eq_ignore_ascii_case("CURVE_END") {
            continue;
        }
        let fields: Vec<&str> = l.split_whitespace().collect();
        if fields.len() == 1 && fields[0].parse::<usize>().ok() == Some(curves.len()) {
            curves.push(Curve {
                wavenumber: true,
                line: n,
                x: Vec::new(),
                y: Vec::new(),
            });
            continue;
        }
        let cur = curves.last_mut().ok_or_else(|| {
            Error::parse(
                at(n),
                format!("expected `CURVE_BEGIN` or the curve index `0`, found `{l}`"),
            )
        })?;
        let unit = if cur.wavenumber {
            "wavenumber cm⁻¹"
        } else {
            "wavelength µm"
        };
        let v: Vec<f64> = fields
            .iter()
            .map(|s| s.parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| {
                Error::parse(at(n), format!("expected `{unit} emissivity`, found `{l}`"))
            })?;
        if v.len() != 2 {
            return Err(Error::parse(
                at(n),
                format!("expected 2 numbers ({unit}, emissivity), found {}", v.len()),
            ));
        }
        if !(v[0].is_finite() && v[0] > 0.0) {
            return Err(Error::parse(at(n), format!("{unit} {} must be > 0", v[0])));
        }
        if let Some(&prev) = cur.x.last() {
            let ordered = if cur.wavenumber {
                v[0] < prev
            } else {
                v[0] > prev
            };
            if !ordered {
                return Err(Error::parse(
                    at(n),
                    if cur.wavenumber {
                        "wavenumbers must decrease within a curve (old format: 39850 → 350 cm⁻¹)"
                    } else {
                        "wavelengths must increase within a curve"
                    },
                ));
            }
        }
        if !(0.0..=1.0).contains(&v[1]) {
            return Err(Error::parse(
                at(n),
                format!("emissivity {} outside 0..=1", v[1]),
            ));
        }
        cur.x.push(v[0]);
        cur.y.push(v[1]);
    }
    if curves.len() != count {
        return Err(Error::parse(
            Location::file(path),
            format!(
                "header says {count} curve(s), found {} (each begins with `CURVE_BEGIN` or its 0-based index)",
                curves.len()
            ),
        ));
    }
    if let Some(c) = curves.iter().find(|c| c.x.is_empty()) {
        return Err(Error::parse(at(c.line), "this curve has no points"));
    }
    // Old-format curves to µm, increasing: λ = 10⁴ / ν.
    let curves: Vec<(Vec<f64>, Vec<f64>)> = curves
        .into_iter()
        .map(|c| {
            if c.wavenumber {
                // ν decreasing → λ increasing.
                (c.x.iter().map(|nu| 1e4 / nu).collect(), c.y)
            } else {
                (c.x, c.y)
            }
        })
        .collect();
    // Union wavelength grid; several curves (texture variants) → their mean.
    let mut wl: Vec<f64> = curves.iter().flat_map(|c| c.0.iter().copied()).collect();
    wl.sort_by(f64::total_cmp);
    wl.dedup();
    let mean: Vec<f64> = wl
        .iter()
        .map(|&w| curves.iter().map(|(x, y)| interp1d(x, y, w)).sum::<f64>() / count as f64)
        .collect();
    if weights.iter().all(|&w| w == 1.0) {
        Ok(EmissivityCurve {
            emissivity: vec![mean],
            wavelengths_um: wl,
            angles_deg: vec![],
        })
    } else {
        Ok(EmissivityCurve {
            emissivity: weights
                .iter()
                .map(|&a| mean.iter().map(|e| a * e).collect())
                .collect(),
            wavelengths_um: wl,
            angles_deg: (0..=90).map(f64::from).collect(),
        })
    }
}
