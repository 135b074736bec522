//! The parameter registry: every input of the one-facet and scene thermal
//! models that a sensitivity study may perturb or a calibration may fit,
//! one table row each, with its unit and physical bounds.
//!
//! Two tables:
//! * [`MATERIAL_PARAMETERS`] — properties of a [`Material`], named as the
//!   material JSON spells them (dotted for nested fields, e.g.
//!   `surface_energy.leaf_area_index`), with a getter (`None` when the
//!   material does not have the property, e.g. no such block) and a setter;
//! * [`WEATHER_PARAMETERS`] — scalings and offsets applied to every record
//!   of a weather history (their effect on a record is in
//!   [`super::params`]).
//!
//! [`list`] gives every registered parameter of one material plus the
//! weather scalings, at their current values, as a PARAMS list (the format
//! [`super::params::ParamSet`] reads).
//!
//! # Adding a parameter
//! A material property is one row of [`MATERIAL_PARAMETERS`]: its JSON name,
//! older names still accepted (usually none), unit, physical bounds, the
//! mathematical domain the model accepts, a getter and a setter. The setter
//! returns an error message when the property cannot be set on this
//! material (e.g. the material has no `surface_energy` block); the getter
//! returns `None` then, and [`list`] leaves the row out. Nothing else
//! changes: parsing, listing, sensitivity, calibration, the fitted material
//! file and `irsig thermal --params` all go through the table.
//!
//! # Layered constructions
//! For a material with `layers`, `conductivity_w_m_k`, `density_kg_m3` and
//! `specific_heat_j_kg_k` are the **outer layer's** (setting one sets that
//! layer's); `thickness_m` is refused (not listed, and a PARAMS file that
//! names it gets the setter's error): the total thickness is the layers'.
//!
//! # Bounds
//! `low`/`high` are the **physical** range of the property over the
//! materials a thermal scene holds (sources per row). They are the default
//! search range of a calibration that starts from [`list`]; narrow them in
//! the PARAMS file when better knowledge exists. A material whose current
//! value lies outside them is listed with the bound widened to that value
//! (the list stays a valid PARAMS file). Weather bounds are the plausible
//! error of measured or modelled forcing (irsig choices, stated per row).
//!
//! Owns the tables and the listing. Takes materials; gives names, units,
//! bounds and values. Must not know the command line or the solvers.

use serde::Serialize;

use crate::material::{Material, SurfaceKind};

/// The domain a value must lie in for the model to accept it:
/// `(min, max, min exclusive)`.
pub type Domain = (f64, f64, bool);

/// One fittable/perturbable property of a material.
#[derive(Debug)]
pub struct MaterialParameter {
    /// Name as the material JSON spells it (dotted for nested fields).
    pub name: &'static str,
    /// Older names still accepted in PARAMS files.
    pub aliases: &'static [&'static str],
    /// Unit (SI; `1` for fractions).
    pub unit: &'static str,
    /// Physical lower bound.
    pub low: f64,
    /// Physical upper bound.
    pub high: f64,
    /// Values the model accepts.
    pub domain: Domain,
    /// The value in a material; `None` where the material lacks it.
    pub get: fn(&Material) -> Option<f64>,
    /// Set the value; `Err(why)` where the material cannot take it.
    pub set: fn(&mut Material, f64) -> Result<(), String>,
    /// Where the bounds come from.
    pub source: &'static str,
}

const POSITIVE: Domain = (0.0, f64::INFINITY, true);
const FRACTION: Domain = (0.0, 1.0, false);

/// Scale a spectral emissivity curve by `new/old` (capped at 1) and set the
/// broadband emissivity.
fn set_emissivity(m: &mut Material, v: f64) -> Result<(), String> {
    let old = m.thermal_emissivity;
    if let Some(c) = &mut m.emissivity_curve {
        if old > 0.0 {
            let r = v / old;
            for row in &mut c.emissivity {
                for e in row {
                    *e = (*e * r).min(1.0);
                }
            }
        }
    }
    m.thermal_emissivity = v;
    Ok(())
}

/// A row of a parameter of the `surface_energy` block: read through the
/// block's effective value (its default where the file leaves it out), set
/// into the block (a defaulted field stays defaulted when set to its
/// default, so it keeps following what it derives from, e.g. the roughness
/// the canopy height); absent where the material has no block.
macro_rules! surface_param {
    ($name:literal, $unit:literal, $low:expr, $high:expr, $domain:expr,
     |$g:ident| $get:expr, |$s:ident, $v:ident| $set:expr, $source:literal) => {
        MaterialParameter {
            name: concat!("surface_energy.", $name),
            aliases: &[],
            unit: $unit,
            low: $low,
            high: $high,
            domain: $domain,
            get: |m| m.surface_energy.as_ref().and_then(|$g| $get),
            set: |m, $v| match &mut m.surface_energy {
                Some($s) => {
                    $set;
                    Ok(())
                }
                None => Err("the material has no `surface_energy` block to set it in".into()),
            },
            source: $source,
        }
    };
}

/// Every material property the thermal model and the radiometry use that a
/// study may vary. Add a row here to make a new property fittable (see the
/// module docs).
pub static MATERIAL_PARAMETERS: &[MaterialParameter] = &[
    MaterialParameter {
        name: "conductivity_w_m_k",
        aliases: &["conductivity"],
        unit: "W/(m·K)",
        low: 0.02,
        high: 430.0,
        domain: POSITIVE,
        get: |m| Some(m.conductivity_w_m_k),
        set: |m, v| {
            // A layered material's top-level value is its outer layer's.
            m.conductivity_w_m_k = v;
            if let Some(l) = m.layers.first_mut() {
                l.conductivity_w_m_k = v;
            }
            Ok(())
        },
        source: "Incropera et al., Fundamentals of Heat and Mass Transfer, 6th ed., Tables A.1–A.3: insulating foams ≈ 0.026 to silver 429 W/(m·K)",
    },
    MaterialParameter {
        name: "specific_heat_j_kg_k",
        aliases: &["specific_heat"],
        unit: "J/(kg·K)",
        low: 100.0,
        high: 4220.0,
        domain: POSITIVE,
        get: |m| Some(m.specific_heat_j_kg_k),
        set: |m, v| {
            // A layered material's top-level value is its outer layer's.
            m.specific_heat_j_kg_k = v;
            if let Some(l) = m.layers.first_mut() {
                l.specific_heat_j_kg_k = v;
            }
            Ok(())
        },
        source: "Incropera et al., 6th ed., Tables A.1 and A.6: lead/gold ≈ 129 to liquid water 4217 J/(kg·K) at 0 °C",
    },
    MaterialParameter {
        name: "density_kg_m3",
        aliases: &["density"],
        unit: "kg/m³",
        low: 10.0,
        high: 22_600.0,
        domain: POSITIVE,
        get: |m| Some(m.density_kg_m3),
        set: |m, v| {
            // A layered material's top-level value is its outer layer's.
            m.density_kg_m3 = v;
            if let Some(l) = m.layers.first_mut() {
                l.density_kg_m3 = v;
            }
            Ok(())
        },
        source: "Incropera et al., 6th ed., Tables A.1–A.3: expanded foams ≈ 16 to osmium/iridium ≈ 22 600 kg/m³",
    },
    MaterialParameter {
        name: "thickness_m",
        aliases: &["thickness"],
        unit: "m",
        low: 1e-4,
        high: 10.0,
        domain: POSITIVE,
        get: |m| m.layers.is_empty().then_some(m.thickness_m),
        set: |m, v| {
            if !m.layers.is_empty() {
                return Err(
                    "the material is a layered construction: its thickness is its layers' (set them in the material file)"
                        .into(),
                );
            }
            m.thickness_m = v;
            Ok(())
        },
        source: "irsig choice: a 0.1 mm foil to a 10 m column (many annual damping depths of soil)",
    },
    MaterialParameter {
        name: "solar_absorptivity",
        aliases: &[],
        unit: "1",
        low: 0.0,
        high: 1.0,
        domain: FRACTION,
        get: |m| Some(m.solar_absorptivity),
        set: |m, v| {
            m.solar_absorptivity = v;
            Ok(())
        },
        source: "a fraction",
    },
    MaterialParameter {
        name: "thermal_emissivity",
        aliases: &[],
        unit: "1",
        low: 0.02,
        high: 1.0,
        domain: (0.0, 1.0, true),
        get: |m| Some(m.thermal_emissivity),
        set: set_emissivity,
        source: "Incropera et al., 6th ed., Table A.11: polished silver ≈ 0.02 to black paint/water ≈ 0.96–0.98; a spectral curve is scaled by the same ratio, capped at 1",
    },
    MaterialParameter {
        name: "exposed_area",
        aliases: &[],
        unit: "1",
        low: 0.0,
        high: 1.0,
        domain: (-1.0, 1.0, false),
        get: |m| Some(m.exposed_area),
        set: |m, v| {
            m.exposed_area = v;
            Ok(())
        },
        source: "fraction of the back face in the air (irsig::material docs; the model uses |value|)",
    },
    MaterialParameter {
        name: "self_power_w_m2",
        aliases: &[],
        unit: "W/m²",
        low: -500.0,
        high: 500.0,
        domain: (f64::NEG_INFINITY, f64::INFINITY, false),
        get: |m| Some(m.self_power_w_m2),
        set: |m, v| {
            m.self_power_w_m2 = v;
            Ok(())
        },
        source: "irsig choice: heated or cooled surfaces (engines, exhausts, chilled roofs) within a few hundred W/m²",
    },
    surface_param!(
        "leaf_area_index",
        "m²/m²",
        0.1,
        8.0,
        (0.0, f64::INFINITY, false),
        |s| (s.kind == SurfaceKind::Canopy).then_some(s.leaf_area_index),
        |s, v| s.leaf_area_index = v,
        "Asner, Scurlock & Hicke (2003), Global Ecol. Biogeogr. 12:191, global LAI database: crops 3.6 ± 2.1, grasslands 1.7 ± 1.2, forests up to ≈ 8"
    ),
    surface_param!(
        "min_stomatal_resistance_s_m",
        "s/m",
        20.0,
        400.0,
        (0.0, f64::INFINITY, false),
        |s| (s.kind == SurfaceKind::Canopy).then_some(s.min_stomatal_resistance_s_m),
        |s, v| s.min_stomatal_resistance_s_m = v,
        "Noilhan & Planton (1989) and the ECMWF/Noah vegetation tables: r_s,min 40 (crops) to 400 s/m (sparse, evergreen)"
    ),
    surface_param!(
        "soil_moisture_m3_m3",
        "m³/m³",
        0.02,
        0.5,
        FRACTION,
        |s| (s.kind != SurfaceKind::Water).then_some(s.soil_moisture_m3_m3),
        |s, v| s.soil_moisture_m3_m3 = v,
        "Noilhan & Planton (1989), Table 2: air-dry soil ≈ 0.02 to saturation (porosity) ≈ 0.5"
    ),
    surface_param!(
        "root_zone_depth_m",
        "m",
        0.1,
        3.0,
        POSITIVE,
        |s| s.root_zone_depth_m.filter(|_| s.kind != SurfaceKind::Water),
        |s, v| s.root_zone_depth_m = Some(v),
        "FAO-56 (Allen et al. 1998) Table 22, maximum effective rooting depth: shallow vegetables ≈ 0.3 m, grass 0.5–1.5 m, field crops 0.6–1.7 m, orchards to 2 m; irsig widens to 0.1–3 m (only where a root zone is on)"
    ),
    surface_param!(
        "water_table_depth_m",
        "m",
        0.3,
        10.0,
        POSITIVE,
        |s| s
            .water_table_depth_m
            .filter(|_| s.root_zone_depth_m.is_some()),
        |s, v| s.water_table_depth_m = Some(v),
        "depth of a water table under the root zone: tile-drained Midwest fields 1–2 m (drains at 0.5–1.5 m), shallow groundwater 0.3 m to none felt at the surface below ≈ 10 m (Gardner 1958's capillary rise falls as L^−n); must stay below root_zone_depth_m (only where a water table is set)"
    ),
    surface_param!(
        "canopy_height_m",
        "m",
        0.02,
        40.0,
        POSITIVE,
        |s| s.canopy_height_m.filter(|_| s.kind == SurfaceKind::Canopy),
        |s, v| s.canopy_height_m = Some(v),
        "mown lawn 0.02 m to tall forest 40 m"
    ),
    surface_param!(
        "leaf_area_per_height_per_m",
        "1/m",
        1.0,
        30.0,
        POSITIVE,
        |s| s
            .leaf_area_per_height_per_m
            .filter(|_| s.kind == SurfaceKind::Canopy),
        |s, v| s.leaf_area_per_height_per_m = Some(v),
        "leaf area per metre of canopy height (LAI = min(a·h, LAI)): field crops 6.8 (METRIC z_om = 0.018 LAI, Allen et al. 2007, with FAO-56's z_om = 0.123 h) to clipped grass 24 (FAO-56 ch. 2, with eq. 5); irsig widens to 1–30 (taller, sparser crops below)"
    ),
    surface_param!(
        "roughness_length_m",
        "m",
        1.0e-4,
        2.0,
        POSITIVE,
        |s| Some(s.roughness_m()),
        |s, v| if v != s.roughness_m() {
            s.roughness_length_m = Some(v)
        },
        "Oke (1987) Boundary Layer Climates, Table 2.2: water ≈ 1e-4 m to forest ≈ 1–2 m"
    ),
    surface_param!(
        "leaf_width_m",
        "m",
        0.005,
        0.3,
        POSITIVE,
        |s| (s.heat_roughness == crate::material::HeatRoughness::Su2001).then(|| s.leaf_width()),
        |s, v| if v != s.leaf_width() {
            s.leaf_width_m = Some(v)
        },
        "characteristic leaf dimension for kB⁻¹ (su2001): grass blades ≈ 5 mm to broad leaves ≈ 0.3 m (Campbell & Norman 1998, Introduction to Environmental Biophysics, ch. 7)"
    ),
    surface_param!(
        "clumping_index",
        "1",
        0.3,
        1.0,
        (0.0, 1.0, true),
        |s| (s.canopy == crate::material::CanopyModel::TwoSource).then(|| s.clumping()),
        |s, v| if v != s.clumping() {
            s.clumping_index = Some(v)
        },
        "two_source foliage clumping Ω: row crops and shrubs 0.5–0.9, random leaves 1 (Kustas & Norman 1999, Agric. For. Meteorol. 94:13; Campbell & Norman 1998, ch. 15)"
    ),
    surface_param!(
        "saturation_m3_m3",
        "m³/m³",
        0.3,
        0.6,
        FRACTION,
        |s| (s.canopy == crate::material::CanopyModel::TwoSource).then(|| s.saturation()),
        |s, v| if v != s.saturation() {
            s.saturation_m3_m3 = Some(v)
        },
        "two_source soil porosity for the soil's evaporation resistance: sand 0.395 to clay 0.482 (Clapp & Hornberger 1978, Water Resour. Res. 14:601, Table 2); irsig widens to 0.3–0.6"
    ),
    surface_param!(
        "skin_conductance_w_m2_k",
        "W/(m²·K)",
        3.0,
        50.0,
        POSITIVE,
        |s| s.has_skin().then(|| s.skin_conductance()),
        |s, v| if v != s.skin_conductance() {
            s.skin_conductance_w_m2_k = Some(v)
        },
        "ECMWF IFS Cy47r3 Part IV §8.3 skin conductivities 7–20 (unstable up to ≈ 40) W/(m² K); irsig widens to 3–50"
    ),
    surface_param!(
        "canopy_heat_capacity_j_m2_k",
        "J/(m²·K)",
        500.0,
        50_000.0,
        POSITIVE,
        |s| s.has_skin().then(|| s.canopy_capacity()),
        |s, v| if v != s.canopy_capacity() {
            s.canopy_heat_capacity_j_m2_k = Some(v)
        },
        "leaf water 0.1–0.5 kg per m² of leaf × LAI 1–8, plus stems and litter: ≈ 0.5–50 kJ/(m² K)"
    ),
    surface_param!(
        "vpd_sensitivity_per_pa",
        "1/Pa",
        0.0,
        1.0e-3,
        (0.0, f64::INFINITY, false),
        |s| (s.kind == SurfaceKind::Canopy).then_some(s.vpd_sensitivity_per_pa),
        |s, v| s.vpd_sensitivity_per_pa = v,
        "Noilhan & Planton (1989): g_D = 0.025 per hPa (2.5e-4 per Pa) for forest, 0 for crops; up to 1e-3 per Pa"
    ),
];

/// One weather scaling or offset (applied to every record).
#[derive(Debug)]
pub struct WeatherParameter {
    /// Name in PARAMS files.
    pub name: &'static str,
    /// Unit (`1` for factors and fractions).
    pub unit: &'static str,
    /// The value that leaves the weather unchanged.
    pub identity: f64,
    /// Plausible lower bound of the forcing error.
    pub low: f64,
    /// Plausible upper bound of the forcing error.
    pub high: f64,
    /// Values the perturbation accepts.
    pub domain: Domain,
    /// Where the bounds come from.
    pub source: &'static str,
}

const ANY: Domain = (f64::NEG_INFINITY, f64::INFINITY, false);

/// The weather perturbations, in the order of
/// [`super::params::WeatherProperty`].
pub static WEATHER_PARAMETERS: &[WeatherParameter] = &[
    WeatherParameter {
        name: "air_temperature_offset_k",
        unit: "K",
        identity: 0.0,
        low: -5.0,
        high: 5.0,
        domain: ANY,
        source: "irsig choice: a sensor off site or poorly shielded, a few K",
    },
    WeatherParameter {
        name: "wind_speed_scale",
        unit: "1",
        identity: 1.0,
        low: 0.2,
        high: 5.0,
        domain: (0.0, 10.0, false),
        source: "irsig choice: wind at another height or exposure (log-profile ratios between 0.5 m and 10 m over rough ground reach 2–3; sheltered sites less)",
    },
    WeatherParameter {
        name: "wind_speed_offset_m_s",
        unit: "m/s",
        identity: 0.0,
        low: -5.0,
        high: 5.0,
        domain: ANY,
        source: "irsig choice (result clamped at 0)",
    },
    WeatherParameter {
        name: "relative_humidity_offset",
        unit: "1",
        identity: 0.0,
        low: -0.5,
        high: 0.5,
        domain: (-1.0, 1.0, false),
        source: "irsig choice (result clamped to 0.01–1)",
    },
    WeatherParameter {
        name: "insolation_scale",
        unit: "1",
        identity: 1.0,
        low: 0.5,
        high: 1.5,
        domain: (0.0, 10.0, false),
        source: "irsig choice: modelled or distant irradiance, ±50 %",
    },
    WeatherParameter {
        name: "sky_longwave_offset_w_m2",
        unit: "W/m²",
        identity: 0.0,
        low: -100.0,
        high: 100.0,
        domain: ANY,
        source: "irsig choice: clear-sky parameterisations scatter by 20–40 W/m², cloud adds up to ~100 W/m²",
    },
    WeatherParameter {
        name: "cloud_cover_offset",
        unit: "1",
        identity: 0.0,
        low: -1.0,
        high: 1.0,
        domain: (-1.0, 1.0, false),
        source: "a fraction (result clamped to 0–1)",
    },
];

/// The registry row of a material property by its name or an alias.
pub fn material_parameter(name: &str) -> Option<&'static MaterialParameter> {
    MATERIAL_PARAMETERS
        .iter()
        .find(|p| p.name == name || p.aliases.contains(&name))
}

/// The registry row of a weather perturbation by name.
pub fn weather_parameter(name: &str) -> Option<&'static WeatherParameter> {
    WEATHER_PARAMETERS.iter().find(|p| p.name == name)
}

/// One entry of a PARAMS list: what [`list`] prints and
/// [`super::params::ParamSet`] reads back.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ListedParameter {
    /// Display name, where it is not the default `<material|weather>.<property>`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// `material` or `weather`.
    pub kind: &'static str,
    /// The material (material entries).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Property name.
    pub property: String,
    /// Current value (the material's own, or the weather identity).
    pub value: f64,
    /// Unit.
    pub unit: &'static str,
    /// Lower bound.
    pub low: f64,
    /// Upper bound.
    pub high: f64,
}

/// A PARAMS file, `{"params": [...]}` (fields in the order above).
#[derive(Debug, Clone, Serialize)]
pub struct ParamsFile<'a> {
    /// The entries.
    pub params: &'a [ListedParameter],
}

impl ParamsFile<'_> {
    /// Pretty JSON text, ending with a newline.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("plain numbers and strings serialize") + "\n"
    }
}

/// Every registered parameter of `material` (those it has) at its current
/// value, then the weather perturbations at their identity, each with its
/// physical bounds (widened to the value where it lies outside them).
pub fn list(material: &Material) -> Vec<ListedParameter> {
    let mut out = Vec::new();
    for p in MATERIAL_PARAMETERS {
        if let Some(v) = (p.get)(material) {
            out.push(ListedParameter {
                name: None,
                kind: "material",
                material: Some(material.name.clone()),
                property: p.name.to_string(),
                value: v,
                unit: p.unit,
                low: p.low.min(v),
                high: p.high.max(v),
            });
        }
    }
    for p in WEATHER_PARAMETERS {
        out.push(ListedParameter {
            name: None,
            kind: "weather",
            material: None,
            property: p.name.to_string(),
            value: p.identity,
            unit: p.unit,
            low: p.low,
            high: p.high,
        });
    }
    out
}
