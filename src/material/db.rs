//! irsig's JSON material database.
//!
//! ```json
//! {
//!   "description": "free text",
//!   "notes": { "anything": "free-form, ignored" },
//!   "materials": [
//!     { "id": 1, "name": "asphalt",
//!       "specific_heat_j_kg_k": 920, "conductivity_w_m_k": 0.75,
//!       "density_kg_m3": 2110, "thickness_m": 0.1,
//!       "solar_absorptivity": 0.9, "thermal_emissivity": 0.95,
//!       "exposed_area": 0, "self_power_w_m2": 0,
//!       "specular_fraction": 0, "transmissivity": 0, "double_sided": false,
//!       "emissivity_file": "asphalt.ems",
//!       "source": { "density_kg_m3": "Oke (1987) Table 2.1", "...": "..." } }
//!   ]
//! }
//! ```
//! A material may instead be a layered construction (`layers`, outer face
//! first, each naming a single-slab material of the same file or giving
//! its properties inline) and may say what its back face touches (`back`):
//! see [`crate::material::construction`].
//! `exposed_area`, `self_power_w_m2`, `specular_fraction`, `transmissivity`
//! and `double_sided` default to 0/false. Spectral emissivity is either
//! inline (`emissivity_curve`: `{wavelengths_um, emissivity, angles_deg}`,
//! `emissivity` one list or one list per angle) or `emissivity_file` (a
//! DIRSIG `.ems`, or a CSV read by [`read_emissivity_csv`]), relative to the
//! database file. Unknown keys are errors (they are usually typos).
//!
//! Owns the JSON database format and the emissivity CSV format. Takes a
//! path; gives a [`MaterialDb`] (every problem collected, each naming file,
//! line and JSON path) or an [`EmissivityCurve`]. Must not know the thermal
//! model or the radiometry that use the values.

use std::path::Path;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{EmissivityCurve, Material, MaterialDb, MaterialSource, dirsig};
use crate::error::{Error, Location, Result};
use crate::scene::jsonloc::JsonLines;
use crate::textio::{self, Comments};

/// The top level of a JSON material database file.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MaterialFile {
    /// JSON Schema reference for editors (ignored).
    #[serde(rename = "$schema", default, skip_serializing_if = "Option::is_none")]
    pub schema: Option<String>,
    /// Free text.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Free-form notes (conventions, references); ignored by irsig.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub notes: Option<serde_json::Value>,
    /// The materials.
    pub materials: Vec<MaterialEntry>,
}

/// Emissivity values: one list (normal view) or one list per angle.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum EmissivityRows {
    /// One row at normal view.
    Single(Vec<f64>),
    /// One row per angle of `angles_deg`.
    PerAngle(Vec<Vec<f64>>),
}

/// An inline emissivity curve.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EmissivityCurveSpec {
    /// Wavelengths, µm, increasing.
    pub wavelengths_um: Vec<f64>,
    /// Emissivity per wavelength (or per angle, per wavelength).
    pub emissivity: EmissivityRows,
    /// View zenith angles of the rows, degrees (omit for one row).
    #[serde(default)]
    pub angles_deg: Vec<f64>,
}

impl From<EmissivityCurveSpec> for EmissivityCurve {
    fn from(s: EmissivityCurveSpec) -> Self {
        EmissivityCurve {
            wavelengths_um: s.wavelengths_um,
            emissivity: match s.emissivity {
                EmissivityRows::Single(r) => vec![r],
                EmissivityRows::PerAngle(r) => r,
            },
            angles_deg: s.angles_deg,
        }
    }
}

/// One material of a JSON database (SI units; field names carry them).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MaterialEntry {
    /// Numeric id.
    pub id: u32,
    /// Unique name; scene parts refer to it.
    pub name: String,
    /// Free text.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Specific heat, J/(kg·K) (required without `layers`; left out with them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specific_heat_j_kg_k: Option<f64>,
    /// Thermal conductivity, W/(m·K) (as `specific_heat_j_kg_k`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conductivity_w_m_k: Option<f64>,
    /// Density, kg/m³ (as `specific_heat_j_kg_k`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density_kg_m3: Option<f64>,
    /// Slab thickness, m (as `specific_heat_j_kg_k`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness_m: Option<f64>,
    /// The construction's layers from the outer face
    /// ([`crate::material::construction`]); absent: a single slab.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub layers: Vec<crate::material::LayerEntry>,
    /// What the back face touches (absent: decided by `exposed_area`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub back: Option<crate::material::BackSpec>,
    /// Solar absorptivity, 0–1.
    pub solar_absorptivity: f64,
    /// Broadband thermal emissivity, 0–1.
    pub thermal_emissivity: f64,
    /// Fraction of the back face exposed to air (see `irsig::material`), −1..=1.
    #[serde(default)]
    pub exposed_area: f64,
    /// Self-generated power, W/m².
    #[serde(default)]
    pub self_power_w_m2: f64,
    /// Specular fraction of reflection, 0–1.
    #[serde(default)]
    pub specular_fraction: f64,
    /// RMS facet slope of the glint lobe, ≥ 0 (absent: 0.05; not for water).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specular_roughness: Option<f64>,
    /// Transmissivity, 0–1.
    #[serde(default)]
    pub transmissivity: f64,
    /// Both faces are front faces.
    #[serde(default)]
    pub double_sided: bool,
    /// Inline spectral emissivity.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emissivity_curve: Option<EmissivityCurveSpec>,
    /// Spectral emissivity file (DIRSIG `.ems` or CSV), relative to this file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emissivity_file: Option<String>,
    /// How the surface evaporates (latent heat, canopy, water); absent: a
    /// dry surface.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface_energy: Option<crate::material::SurfaceEnergySpec>,
    /// How a dry surface convects (default DOE-2, medium rough).
    #[serde(
        default,
        skip_serializing_if = "crate::material::ConvectionSpec::is_default"
    )]
    pub convection: crate::material::ConvectionSpec,
    /// Where the values come from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<MaterialSource>,
}

/// Load a JSON material database, collecting every problem found (each
/// naming the file, line and JSON path).
pub fn load_json_all(path: &Path) -> std::result::Result<MaterialDb, Vec<Error>> {
    let text = std::fs::read_to_string(path).map_err(|e| vec![Error::io(path, e)])?;
    load_json_str_all(&text, path)
}

/// As [`load_json_all`] for text in memory; `path` names it in messages and is the
/// folder emissivity files are relative to.
pub fn load_json_str_all(text: &str, path: &Path) -> std::result::Result<MaterialDb, Vec<Error>> {
    let file: MaterialFile = serde_json::from_str(text)
        .map_err(|e| vec![crate::scene::jsonloc::serde_error(path, &e)])?;
    let base = path.parent().unwrap_or(Path::new("."));
    let lines = std::cell::OnceCell::new();
    let at = |field: String| {
        let l = lines.get_or_init(|| JsonLines::new(text));
        let mut loc = Location::file(path);
        if let Some((n, c)) = l.position(&field) {
            loc = loc.at(n, c);
        }
        loc.with_field(field)
    };
    let mut errors = Vec::new();
    let mut db = MaterialDb::new();
    // Layers name single-slab materials of this file.
    let singles: std::collections::HashMap<&str, &MaterialEntry> = file
        .materials
        .iter()
        .filter(|e| e.layers.is_empty())
        .map(|e| (e.name.as_str(), e))
        .collect();
    let mut resolved = Vec::with_capacity(file.materials.len());
    for (i, e) in file.materials.iter().enumerate() {
        resolved.push(resolve_thermal(e, &singles, &file.materials, &|f| {
            at(format!("materials[{i}].{f}"))
        }));
    }
    for (i, (e, thermal)) in file.materials.into_iter().zip(resolved).enumerate() {
        let (k, rho, c, thickness, layers) = match thermal {
            Ok(t) => t,
            Err(mut errs) => {
                errors.append(&mut errs);
                continue;
            }
        };
        let curve = match (&e.emissivity_curve, &e.emissivity_file) {
            (Some(_), Some(_)) => {
                errors.push(Error::parse(
                    at(format!("materials[{i}].emissivity_file")),
                    "give either `emissivity_curve` or `emissivity_file`, not both",
                ));
                None
            }
            (Some(c), None) => Some(EmissivityCurve::from(c.clone())),
            (None, Some(f)) => match read_emissivity_file(&base.join(f)) {
                Ok(c) => Some(c),
                Err(err) => {
                    errors.push(Error::parse(
                        at(format!("materials[{i}].emissivity_file")),
                        format!("cannot use emissivity file: {err}"),
                    ));
                    None
                }
            },
            (None, None) => None,
        };
        let m = Material {
            id: e.id,
            name: e.name.clone(),
            specific_heat_j_kg_k: c,
            conductivity_w_m_k: k,
            density_kg_m3: rho,
            thickness_m: thickness,
            solar_absorptivity: e.solar_absorptivity,
            thermal_emissivity: e.thermal_emissivity,
            exposed_area: e.exposed_area,
            self_power_w_m2: e.self_power_w_m2,
            specular_fraction: e.specular_fraction,
            specular_roughness: e.specular_roughness,
            transmissivity: e.transmissivity,
            emissivity_curve: curve,
            double_sided: e.double_sided,
            surface_energy: e.surface_energy,
            convection: e.convection,
            layers,
            back: e.back,
        };
        let problems = m.problems();
        if !problems.is_empty() {
            for (field, msg) in problems {
                errors.push(Error::parse(
                    at(format!("materials[{i}].{field}")),
                    format!("material `{}`: {msg}", m.name),
                ));
            }
            continue;
        }
        if db.index_of(&m.name).is_some() {
            errors.push(Error::parse(
                at(format!("materials[{i}].name")),
                format!("material name `{}` is defined twice", m.name),
            ));
            continue;
        }
        db.insert(m, e.source, path)
            .expect("validated and unique above");
    }
    if errors.is_empty() {
        Ok(db)
    } else {
        Err(errors)
    }
}

/// A material entry's thermal values `(k, ρ, c, thickness, layers)`: its
/// own fields (all four required) without layers; with layers, each layer
/// resolved (a named single-slab material of `singles`, or inline values)
/// and the top-level values the outer layer's and the total thickness
/// (the four then must be absent). Errors name the field through `at`.
type Thermal = (f64, f64, f64, f64, Vec<crate::material::MaterialLayer>);
fn resolve_thermal(
    e: &MaterialEntry,
    singles: &std::collections::HashMap<&str, &MaterialEntry>,
    all: &[MaterialEntry],
    at: &dyn Fn(&str) -> Location,
) -> std::result::Result<Thermal, Vec<Error>> {
    let mut errors = Vec::new();
    let top = [
        ("conductivity_w_m_k", e.conductivity_w_m_k),
        ("density_kg_m3", e.density_kg_m3),
        ("specific_heat_j_kg_k", e.specific_heat_j_kg_k),
        ("thickness_m", e.thickness_m),
    ];
    if e.layers.is_empty() {
        for (f, v) in top {
            if v.is_none() {
                errors.push(Error::parse(
                    at(f),
                    format!(
                        "material `{}`: missing `{f}` (required for a single slab; a construction gives `layers` instead)",
                        e.name
                    ),
                ));
            }
        }
        return if errors.is_empty() {
            Ok((
                e.conductivity_w_m_k.expect("checked"),
                e.density_kg_m3.expect("checked"),
                e.specific_heat_j_kg_k.expect("checked"),
                e.thickness_m.expect("checked"),
                Vec::new(),
            ))
        } else {
            Err(errors)
        };
    }
    for (f, v) in top {
        if v.is_some() {
            errors.push(Error::parse(
                at(f),
                format!(
                    "material `{}`: has `layers`, so `{f}` comes from them (the outer layer's, the total thickness); leave it out",
                    e.name
                ),
            ));
        }
    }
    let mut layers = Vec::with_capacity(e.layers.len());
    for (j, l) in e.layers.iter().enumerate() {
        let f = |name: &str| format!("layers[{j}].{name}");
        let inline = [
            ("conductivity_w_m_k", l.conductivity_w_m_k),
            ("density_kg_m3", l.density_kg_m3),
            ("specific_heat_j_kg_k", l.specific_heat_j_kg_k),
        ];
        let (k, rho, c) = match &l.material {
            Some(name) => {
                if let Some((n, _)) = inline.iter().find(|(_, v)| v.is_some()) {
                    errors.push(Error::parse(
                        at(&f(n)),
                        format!(
                            "material `{}`: the layer names material `{name}`, whose `{n}` it takes; leave it out",
                            e.name
                        ),
                    ));
                    continue;
                }
                match singles.get(name.as_str()) {
                    Some(m) => (
                        m.conductivity_w_m_k.unwrap_or(f64::NAN),
                        m.density_kg_m3.unwrap_or(f64::NAN),
                        m.specific_heat_j_kg_k.unwrap_or(f64::NAN),
                    ),
                    None => {
                        let why = if all.iter().any(|m| &m.name == name) {
                            format!(
                                "material `{name}` is itself layered; a layer must name a single-slab material"
                            )
                        } else {
                            let mut near: Vec<&str> = singles
                                .keys()
                                .copied()
                                .filter(|n| {
                                    let (a, b) = (n.to_lowercase(), name.to_lowercase());
                                    a.contains(&b) || b.contains(&a)
                                })
                                .collect();
                            near.sort_unstable();
                            let hint = if near.is_empty() {
                                String::new()
                            } else {
                                format!(" (similar: {})", near.join(", "))
                            };
                            format!("no material `{name}` in this file{hint}")
                        };
                        errors.push(Error::parse(
                            at(&f("material")),
                            format!("material `{}`: {why}", e.name),
                        ));
                        continue;
                    }
                }
            }
            None => {
                let missing: Vec<&str> = inline
                    .iter()
                    .filter(|(_, v)| v.is_none())
                    .map(|(n, _)| *n)
                    .collect();
                if !missing.is_empty() {
                    errors.push(Error::parse(
                        at(&format!("layers[{j}]")),
                        format!(
                            "material `{}`: the layer needs `material` or inline {}",
                            e.name,
                            missing
                                .iter()
                                .map(|n| format!("`{n}`"))
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    ));
                    continue;
                }
                (
                    l.conductivity_w_m_k.expect("checked"),
                    l.density_kg_m3.expect("checked"),
                    l.specific_heat_j_kg_k.expect("checked"),
                )
            }
        };
        layers.push(crate::material::MaterialLayer {
            material: l.material.clone(),
            conductivity_w_m_k: k,
            density_kg_m3: rho,
            specific_heat_j_kg_k: c,
            thickness_m: l.thickness_m,
            contact_resistance_m2_k_w: l.contact_resistance_m2_k_w,
        });
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    let outer = &layers[0];
    Ok((
        outer.conductivity_w_m_k,
        outer.density_kg_m3,
        outer.specific_heat_j_kg_k,
        layers.iter().map(|l| l.thickness_m).sum(),
        layers,
    ))
}

/// Read a spectral emissivity file: DIRSIG `.ems` by extension, else CSV.
pub fn read_emissivity_file(path: &Path) -> Result<EmissivityCurve> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ems"))
    {
        dirsig::read_ems(path)
    } else {
        read_emissivity_csv(path)
    }
}

/// Read a CSV emissivity curve: comma (or whitespace or `;`) separated
/// columns, quoted cells allowed, `#` comments (read by `crate::textio`). Two columns: wavelength (µm), emissivity. More columns: a
/// header line is required, `wavelength_um,<angle>,<angle>,…` with view
/// zenith angles in degrees, one emissivity column per angle. A header
/// line (non-numeric first field) is optional with two columns.
pub fn read_emissivity_csv(path: &Path) -> Result<EmissivityCurve> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut angles: Option<Vec<f64>> = None;
    let mut wl = Vec::new();
    let mut cols: Vec<Vec<f64>> = Vec::new();
    let mut ncols = 0;
    for row in textio::rows(&text, Comments::Trailing) {
        let line = row.text;
        let f = textio::tokens(&row.fields);
        let loc = || Location::file(path).at_line(row.line);
        if wl.is_empty() && angles.is_none() && f.first().is_some_and(|s| s.parse::<f64>().is_err())
        {
            // Header.
            let a: std::result::Result<Vec<f64>, _> =
                f[1..].iter().map(|s| s.parse::<f64>()).collect();
            match a {
                Ok(a) if f.len() > 2 => angles = Some(a),
                _ if f.len() == 2 => angles = Some(vec![]),
                _ => {
                    return Err(Error::parse(
                        loc(),
                        "header must be `wavelength_um,<angle_deg>,<angle_deg>,…` (angles as numbers)",
                    ));
                }
            }
            continue;
        }
        let v: std::result::Result<Vec<f64>, _> = f.iter().map(|s| s.parse::<f64>()).collect();
        let v = v.map_err(|_| {
            Error::parse(
                loc(),
                format!("expected numbers (wavelength µm, emissivity…), found `{line}`"),
            )
        })?;
        if ncols == 0 {
            ncols = v.len();
            if ncols < 2 {
                return Err(Error::parse(
                    loc(),
                    "expected at least 2 columns: wavelength_um, emissivity",
                ));
            }
            if ncols > 2 && angles.as_ref().is_none_or(|a| a.len() != ncols - 1) {
                return Err(Error::parse(
                    loc(),
                    format!(
                        "{ncols} columns need a header `wavelength_um,<angle_deg>…` with {} angles",
                        ncols - 1
                    ),
                ));
            }
            cols = vec![Vec::new(); ncols - 1];
        }
        if v.len() != ncols {
            return Err(Error::parse(
                loc(),
                format!("expected {ncols} columns, found {}", v.len()),
            ));
        }
        wl.push(v[0]);
        for (c, x) in cols.iter_mut().zip(&v[1..]) {
            c.push(*x);
        }
    }
    if wl.is_empty() {
        return Err(Error::parse(Location::file(path), "no data rows"));
    }
    let angles = if ncols > 2 {
        angles.unwrap_or_default()
    } else {
        vec![]
    };
    let curve = EmissivityCurve {
        wavelengths_um: wl,
        emissivity: cols,
        angles_deg: angles,
    };
    if let Some(p) = curve.problems().into_iter().next() {
        return Err(Error::parse(Location::file(path), p));
    }
    Ok(curve)
}
