//! Constructions and back boundaries as material databases and scene files
//! spell them.
//!
//! A material may be a stack of layers from its outer (front) face:
//!
//! ```json
//! { "name": "brick_cavity_wall", "solar_absorptivity": 0.63, "thermal_emissivity": 0.9,
//!   "layers": [
//!     { "material": "brick", "thickness_m": 0.1 },
//!     { "conductivity_w_m_k": 0.035, "density_kg_m3": 30, "specific_heat_j_kg_k": 1450,
//!       "thickness_m": 0.08, "contact_resistance_m2_k_w": 0.0 },
//!     { "material": "gypsum_plaster", "thickness_m": 0.013 } ],
//!   "back": { "interior": { "air_temperature_k": 293.15 } } }
//! ```
//!
//! Each layer names a material of the same database (its conductivity,
//! density and specific heat; the named material must be a single slab) or
//! gives the three inline, plus its thickness and an optional contact
//! resistance to the next layer ([`LayerEntry`]). The material's own
//! conductivity, density, specific heat and thickness are then left out:
//! they come from the layers (the outer layer's, and the total).
//!
//! `back` says what the back face touches ([`BackSpec`]); a material, a
//! scene object and a scene part may each give one (part over object over
//! material; without any, the material's `exposed_area` decides).
//!
//! Owns these JSON forms and their checks ([`BackSpec::problems`],
//! [`MaterialLayer::problems`]). Takes parsed JSON; gives checked values.
//! Must not know the thermal solver that uses them.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// One layer of a construction in a material database file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LayerEntry {
    /// A single-slab material of the same database whose conductivity,
    /// density and specific heat the layer has (leave the three out).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Thermal conductivity, W/(m·K) (without `material`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conductivity_w_m_k: Option<f64>,
    /// Density, kg/m³ (without `material`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density_kg_m3: Option<f64>,
    /// Specific heat, J/(kg·K) (without `material`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specific_heat_j_kg_k: Option<f64>,
    /// Layer thickness, m (> 0).
    pub thickness_m: f64,
    /// Contact resistance between this layer and the next, m²·K/W (≥ 0;
    /// e.g. an air gap, EN ISO 6946 Table 8).
    #[serde(default)]
    pub contact_resistance_m2_k_w: f64,
    /// Free text.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Where the values come from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// One layer of a construction, resolved to numbers (SI units).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct MaterialLayer {
    /// The material the properties came from, if named.
    pub material: Option<String>,
    /// Thermal conductivity, W/(m·K).
    pub conductivity_w_m_k: f64,
    /// Density, kg/m³.
    pub density_kg_m3: f64,
    /// Specific heat, J/(kg·K).
    pub specific_heat_j_kg_k: f64,
    /// Thickness, m.
    pub thickness_m: f64,
    /// Contact resistance to the next layer, m²·K/W.
    pub contact_resistance_m2_k_w: f64,
}

impl MaterialLayer {
    /// Problems as `(field, message)` pairs, fields relative to the layer.
    pub fn problems(&self) -> Vec<(String, String)> {
        let mut p = Vec::new();
        for (name, v, unit) in [
            ("conductivity_w_m_k", self.conductivity_w_m_k, "W/(m·K)"),
            ("density_kg_m3", self.density_kg_m3, "kg/m³"),
            (
                "specific_heat_j_kg_k",
                self.specific_heat_j_kg_k,
                "J/(kg·K)",
            ),
            ("thickness_m", self.thickness_m, "m"),
        ] {
            if !(v.is_finite() && v > 0.0) {
                p.push((
                    name.to_string(),
                    format!("{v} {unit}: expected a finite value > 0"),
                ));
            }
        }
        let r = self.contact_resistance_m2_k_w;
        if !(r.is_finite() && r >= 0.0) {
            p.push((
                "contact_resistance_m2_k_w".to_string(),
                format!("{r} m²·K/W: expected a finite value ≥ 0"),
            ));
        }
        p
    }
}

/// What the back face of a slab touches, as a file spells it:
/// `"insulated"`, `{"outdoor_air": {"fraction": 0.5}}`,
/// `{"ground": {}}` (optional `deep_temperature_k`, `depth_m`) or
/// `{"interior": {…}}` ([`InteriorSpec`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum BackSpec {
    /// No heat through the back face.
    Insulated,
    /// A fraction of the back face in the outdoor air (convection and
    /// longwave, as the front).
    OutdoorAir {
        /// Fraction of the back face exposed, (0, 1].
        fraction: f64,
    },
    /// A column of the (last layer's) material down to the deep ground.
    Ground {
        /// Deep-ground temperature, K (absent: the mean air temperature).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        deep_temperature_k: Option<f64>,
        /// Column depth, m (absent: five diurnal damping depths).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        depth_m: Option<f64>,
    },
    /// A building interior.
    Interior(InteriorSpec),
}

/// Default interior film coefficient `1/R_si` with `R_si = 0.13 m²·K/W`
/// (horizontal heat flow, walls), W/(m²·K): EN ISO 6946:2017 Table 7 (as
/// EN ISO 13789). Heat flow upward (a ceiling in winter): `R_si = 0.10`;
/// downward (a roof over a cooled room in summer): `0.17`.
pub const INTERIOR_FILM_WALL_W_M2_K: f64 = 1.0 / 0.13;

/// A building interior: exactly one of `air_temperature_k`, `schedule_k`
/// or the two set points, and optionally the film coefficient.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InteriorSpec {
    /// A constant air temperature, K.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub air_temperature_k: Option<f64>,
    /// 24 air temperatures, K, one per local hour (entry `h` from `h:00` to
    /// `h+1:00`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub schedule_k: Option<Vec<f64>>,
    /// Heating set point, K: the interior is held here while the outdoor
    /// air is colder (with `cooling_setpoint_k`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heating_setpoint_k: Option<f64>,
    /// Cooling set point, K: held while the outdoor air is warmer; between
    /// the set points the interior follows the outdoor air.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cooling_setpoint_k: Option<f64>,
    /// Interior convective + radiative film coefficient `1/R_si`, W/(m²·K)
    /// (absent: [`INTERIOR_FILM_WALL_W_M2_K`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub film_coefficient_w_m2_k: Option<f64>,
}

/// Hours in an interior schedule.
pub const SCHEDULE_HOURS: usize = 24;

impl BackSpec {
    /// Problems as `(field, message)` pairs, fields relative to the spec
    /// (`interior.schedule_k`, `outdoor_air.fraction`, …).
    pub fn problems(&self) -> Vec<(String, String)> {
        let mut p: Vec<(String, String)> = Vec::new();
        let temp = |p: &mut Vec<(String, String)>, field: &str, t: f64| {
            if !(t.is_finite() && t > 0.0) {
                p.push((
                    field.to_string(),
                    format!("{t} K: expected a temperature > 0 K"),
                ));
            }
        };
        match self {
            BackSpec::Insulated => {}
            BackSpec::OutdoorAir { fraction } => {
                if !(*fraction > 0.0 && *fraction <= 1.0) {
                    p.push((
                        "outdoor_air.fraction".into(),
                        format!("{fraction}: expected an exposed fraction in (0, 1]"),
                    ));
                }
            }
            BackSpec::Ground {
                deep_temperature_k,
                depth_m,
            } => {
                if let Some(t) = deep_temperature_k {
                    temp(&mut p, "ground.deep_temperature_k", *t);
                }
                if let Some(d) = depth_m
                    && !(d.is_finite() && *d > 0.0)
                {
                    p.push(("ground.depth_m".into(), format!("{d} m: expected > 0")));
                }
            }
            BackSpec::Interior(s) => {
                let modes = usize::from(s.air_temperature_k.is_some())
                    + usize::from(s.schedule_k.is_some())
                    + usize::from(s.heating_setpoint_k.is_some() || s.cooling_setpoint_k.is_some());
                if modes != 1 {
                    p.push((
                        "interior".into(),
                        "give exactly one of `air_temperature_k`, `schedule_k`, or \
                         `heating_setpoint_k` with `cooling_setpoint_k`"
                            .into(),
                    ));
                }
                if let Some(t) = s.air_temperature_k {
                    temp(&mut p, "interior.air_temperature_k", t);
                }
                if let Some(h) = &s.schedule_k {
                    if h.len() != SCHEDULE_HOURS {
                        p.push((
                            "interior.schedule_k".into(),
                            format!(
                                "{} values: expected {SCHEDULE_HOURS}, one per local hour (0:00–1:00 first)",
                                h.len()
                            ),
                        ));
                    }
                    for (i, t) in h.iter().enumerate() {
                        temp(&mut p, &format!("interior.schedule_k[{i}]"), *t);
                    }
                }
                match (s.heating_setpoint_k, s.cooling_setpoint_k) {
                    (Some(h), Some(c)) => {
                        temp(&mut p, "interior.heating_setpoint_k", h);
                        temp(&mut p, "interior.cooling_setpoint_k", c);
                        if c < h {
                            p.push((
                                "interior.cooling_setpoint_k".into(),
                                format!("{c} K is below the heating set point {h} K"),
                            ));
                        }
                    }
                    (Some(_), None) => p.push((
                        "interior.cooling_setpoint_k".into(),
                        "missing: set points come in pairs (heating and cooling)".into(),
                    )),
                    (None, Some(_)) => p.push((
                        "interior.heating_setpoint_k".into(),
                        "missing: set points come in pairs (heating and cooling)".into(),
                    )),
                    (None, None) => {}
                }
                if let Some(h) = s.film_coefficient_w_m2_k
                    && !(h.is_finite() && h > 0.0)
                {
                    p.push((
                        "interior.film_coefficient_w_m2_k".into(),
                        format!("{h} W/(m²·K): expected > 0"),
                    ));
                }
            }
        }
        p
    }
}
