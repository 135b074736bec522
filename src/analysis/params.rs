//! Input parameters of sensitivity studies and calibrations (the PARAMS
//! JSON file), and how each one perturbs a weather history or a material.
//!
//! ```json
//! { "params": [
//!   { "kind": "weather", "property": "air_temperature_offset_k",
//!     "low": -2, "high": 2, "uncertainty": 0.5 },
//!   { "kind": "material", "material": "asphalt", "property": "solar_absorptivity",
//!     "low": 0.85, "high": 0.95, "uncertainty": 0.02 }
//! ] }
//! ```
//!
//! A bare top-level array is accepted too. Per entry: `kind` (`weather` or
//! `material`), `property`, `material` (material entries only), `low` and
//! `high` (the plausible bounds), optional `name` (default
//! `weather.<property>` / `<material>.<property>`), optional `value` (or
//! its older name `nominal`; default: 0 for offsets, 1 for scales, the
//! material's own value for material properties), optional `unit` (checked
//! against the registry's) and optional `uncertainty` (one standard
//! uncertainty, in the parameter's unit; default the standard deviation of
//! a uniform distribution over the bounds, `(high − low)/√12`). The
//! properties, their units and physical bounds are the rows of
//! [`super::registry`]; `irsig calibrate --list-params` prints them in this
//! format.
//!
//! Weather properties (applied to every record of the history):
//! `air_temperature_offset_k` (K added to the air temperature; the dew
//! point is kept, capped at the air temperature, and the relative humidity
//! scaled to keep the vapour pressure; saturation caps it at 1),
//! `wind_speed_scale`, `wind_speed_offset_m_s` (result clamped
//! at 0), `relative_humidity_offset` (fraction added, result clamped to
//! 0.01–1, dew point recomputed), `insolation_scale` (multiplies direct,
//! diffuse and global solar irradiance), `sky_longwave_offset_w_m2` (W/m²
//! added to the downwelling longwave, clamped at 0), `cloud_cover_offset`
//! (fraction added to total and opaque sky cover, clamped to 0–1).
//!
//! The thermal model and the renderer take the sky longwave and the solar
//! irradiances from the record, so humidity and cloud cover act through
//! them, with the relations the weather loader fills missing fields with
//! ([`crate::weather::physics`]):
//! * sky longwave: multiplied by `ε_sky(T_dp', N') / ε_sky(T_dp, N)`, the
//!   ratio of Clark & Allen (1978) sky emissivities with the TARP cloud
//!   factor (opaque cover N) — more humidity or cloud, more longwave;
//! * insolation (cloud cover only): global horizontal multiplied by the
//!   Kasten & Czeplak (1980, Solar Energy 24, 177–189) cloud ratio
//!   `(1 − 0.75 c'^3.4)/(1 − 0.75 c^3.4)` (c the total cover, fraction), and
//!   direct normal and diffuse horizontal moved by the change of their
//!   Erbs et al. (1982) split of the global value at the record's solar
//!   zenith ([`ParamSet::apply_weather_at`] with the site; without a site
//!   both scale with the global value).
//!
//! An offset of 0 leaves a record exactly as it is.
//!
//! Material properties are absolute values in SI units, named as the
//! material JSON spells them (`conductivity_w_m_k`, `specific_heat_j_kg_k`,
//! `density_kg_m3`, `thickness_m`, `solar_absorptivity`,
//! `thermal_emissivity` — a spectral emissivity curve is scaled by the same
//! ratio, capped at 1 —, `exposed_area`, `self_power_w_m2`, and whatever
//! rows [`super::registry::MATERIAL_PARAMETERS`] gains); the short names
//! `conductivity`, `specific_heat`, `density`, `thickness` are still read.

use std::path::Path;

use serde::Deserialize;

use super::registry::{self, MaterialParameter, WeatherParameter};
use crate::material::Material;
use crate::sun::{self, Site};
use crate::weather::WeatherRecord;
use crate::weather::physics::{clark_allen_sky_emissivity, erbs_split};
use crate::{Error, Location, Result};

/// A weather property a parameter perturbs (its name, unit, identity and
/// bounds are the registry row [`WeatherProperty::row`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WeatherProperty {
    /// K added to the air temperature.
    AirTemperatureOffsetK,
    /// Factor on the wind speed.
    WindSpeedScale,
    /// m/s added to the wind speed.
    WindSpeedOffsetMS,
    /// Fraction added to the relative humidity.
    RelativeHumidityOffset,
    /// Factor on all solar irradiances.
    InsolationScale,
    /// W/m² added to the sky longwave irradiance.
    SkyLongwaveOffsetWM2,
    /// Fraction added to total and opaque sky cover.
    CloudCoverOffset,
}

/// In the order of [`registry::WEATHER_PARAMETERS`].
const WEATHER_PROPERTIES: [WeatherProperty; 7] = [
    WeatherProperty::AirTemperatureOffsetK,
    WeatherProperty::WindSpeedScale,
    WeatherProperty::WindSpeedOffsetMS,
    WeatherProperty::RelativeHumidityOffset,
    WeatherProperty::InsolationScale,
    WeatherProperty::SkyLongwaveOffsetWM2,
    WeatherProperty::CloudCoverOffset,
];

impl WeatherProperty {
    /// The property by its name in PARAMS files.
    pub fn from_name(name: &str) -> Option<WeatherProperty> {
        let i = registry::WEATHER_PARAMETERS
            .iter()
            .position(|p| p.name == name)?;
        Some(WEATHER_PROPERTIES[i])
    }
    /// Its registry row (name, unit, identity, bounds).
    pub fn row(&self) -> &'static WeatherParameter {
        let i = WEATHER_PROPERTIES
            .iter()
            .position(|p| p == self)
            .expect("every weather property has a registry row");
        &registry::WEATHER_PARAMETERS[i]
    }
    /// The property's name in PARAMS files.
    pub fn name(&self) -> &'static str {
        self.row().name
    }
    /// The value that leaves the weather unchanged.
    pub fn identity(&self) -> f64 {
        self.row().identity
    }
}

/// A material property a parameter sets: a row of
/// [`registry::MATERIAL_PARAMETERS`] (compared by name).
#[derive(Debug, Clone, Copy)]
pub struct MaterialProperty(&'static MaterialParameter);

impl PartialEq for MaterialProperty {
    fn eq(&self, other: &Self) -> bool {
        self.0.name == other.0.name
    }
}

impl MaterialProperty {
    /// The property by its JSON name or an alias.
    pub fn from_name(name: &str) -> Option<MaterialProperty> {
        registry::material_parameter(name).map(MaterialProperty)
    }
    /// Its registry row (name, unit, bounds, get/set).
    pub fn row(&self) -> &'static MaterialParameter {
        self.0
    }
    /// The property's name (as the material JSON spells it).
    pub fn name(&self) -> &'static str {
        self.0.name
    }
    /// The property's value in `m` (`None`: `m` does not have it).
    pub fn get(&self, m: &Material) -> Option<f64> {
        (self.0.get)(m)
    }
    /// Set the property in `m` to `v` (emissivity also scales a spectral
    /// curve by the same ratio, capped at 1).
    ///
    /// # Errors
    /// `m` cannot take the property (the error names material and property).
    pub fn set(&self, m: &mut Material, v: f64) -> Result<()> {
        (self.0.set)(m, v).map_err(|why| Error::invalid(format!("{}.{}", m.name, self.0.name), why))
    }
}

/// What a parameter perturbs.
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    /// The weather history.
    Weather(WeatherProperty),
    /// A property of the named material.
    Material {
        /// Material name.
        material: String,
        /// Property.
        property: MaterialProperty,
    },
}

/// One uncertain input with its plausible range.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    /// Display name.
    pub name: String,
    /// What it perturbs.
    pub target: Target,
    /// Unit of the values.
    pub unit: &'static str,
    /// Nominal (best-estimate) value: the file's `value` (or `nominal`),
    /// else the material's own or the weather identity.
    pub nominal: f64,
    /// Lower plausible bound.
    pub low: f64,
    /// Upper plausible bound.
    pub high: f64,
    /// One standard uncertainty, parameter unit.
    pub uncertainty: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawParam {
    name: Option<String>,
    kind: String,
    property: String,
    material: Option<String>,
    nominal: Option<f64>,
    value: Option<f64>,
    unit: Option<String>,
    low: f64,
    high: f64,
    uncertainty: Option<f64>,
}

/// The parameters of a study, in file order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParamSet {
    /// The parameters.
    pub params: Vec<Parameter>,
}

fn json_error(path: &Path, e: &serde_json::Error) -> Error {
    Error::parse(
        Location::file(path).at_line(e.line()),
        format!(
            "{e} (expected a PARAMS file: {{\"params\": [{{\"kind\": \"weather\"|\"material\", \"property\": …, \"low\": …, \"high\": …}}]}})"
        ),
    )
}

impl ParamSet {
    /// Read a PARAMS JSON file. Material nominals left out are taken from
    /// `materials` (by name); every referenced material must be there.
    pub fn load(path: impl AsRef<Path>, materials: &[Material]) -> Result<ParamSet> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::parse(&text, path, materials)
    }

    /// Parse PARAMS JSON text (`path` names it in errors).
    pub fn parse(text: &str, path: &Path, materials: &[Material]) -> Result<ParamSet> {
        // Syntax errors carry serde_json's line; entry errors their JSON path.
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| json_error(path, &e))?;
        let list = match value {
            serde_json::Value::Array(a) => a,
            serde_json::Value::Object(mut o) => match o.remove("params") {
                Some(serde_json::Value::Array(a)) if o.is_empty() => a,
                _ => {
                    return Err(Error::parse(
                        Location::file(path),
                        "expected {\"params\": [...]} (and no other key) or a bare array of parameters",
                    ));
                }
            },
            _ => {
                return Err(Error::parse(
                    Location::file(path),
                    "expected {\"params\": [...]} or a bare array of parameters",
                ));
            }
        };
        let raw = list
            .into_iter()
            .enumerate()
            .map(|(i, v)| {
                serde_json::from_value::<RawParam>(v).map_err(|e| {
                    Error::parse(
                        Location::file(path).with_field(format!("params[{i}]")),
                        format!("{e}; expected kind, property, [material], low, high, [value], [unit], [uncertainty], [name]"),
                    )
                })
            })
            .collect::<Result<Vec<_>>>()?;
        if raw.is_empty() {
            return Err(Error::parse(
                Location::file(path).with_field("params"),
                "no parameters listed",
            ));
        }
        let mut params: Vec<Parameter> = Vec::with_capacity(raw.len());
        for (i, r) in raw.into_iter().enumerate() {
            let at = |f: &str| Location::file(path).with_field(format!("params[{i}].{f}"));
            let (target, default_nominal, (dmin, dmax, excl), unit) = match r.kind.as_str() {
                "weather" => {
                    if r.material.is_some() {
                        return Err(Error::parse(
                            at("material"),
                            "a weather parameter takes no `material`",
                        ));
                    }
                    let p = WeatherProperty::from_name(&r.property).ok_or_else(|| {
                        Error::parse(
                            at("property"),
                            format!(
                                "unknown weather property `{}`; expected one of {}",
                                r.property,
                                registry::WEATHER_PARAMETERS
                                    .iter()
                                    .map(|p| p.name)
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ),
                        )
                    })?;
                    let row = p.row();
                    (Target::Weather(p), p.identity(), row.domain, row.unit)
                }
                "material" => {
                    let mname = r.material.clone().ok_or_else(|| {
                        Error::parse(
                            at("material"),
                            "a material parameter needs `material` (its name)",
                        )
                    })?;
                    let p = MaterialProperty::from_name(&r.property).ok_or_else(|| {
                        Error::parse(
                            at("property"),
                            format!(
                                "unknown material property `{}`{}; expected one of {}",
                                r.property,
                                crate::suggest::hint(
                                    &r.property,
                                    registry::MATERIAL_PARAMETERS.iter().map(|p| p.name)
                                ),
                                registry::MATERIAL_PARAMETERS
                                    .iter()
                                    .map(|p| p.name)
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ),
                        )
                    })?;
                    let m = materials.iter().find(|m| m.name == mname).ok_or_else(|| {
                        Error::parse(
                            at("material"),
                            format!(
                                "no material `{mname}` among the materials given (the scene's, or the one studied); known: {}",
                                materials
                                    .iter()
                                    .map(|m| m.name.as_str())
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ),
                        )
                    })?;
                    let current = p.get(m).ok_or_else(|| {
                        Error::parse(
                            at("property"),
                            format!(
                                "material `{mname}` has no `{}` (the block it belongs to is not set)",
                                p.name()
                            ),
                        )
                    })?;
                    let row = p.row();
                    (
                        Target::Material {
                            material: mname,
                            property: p,
                        },
                        current,
                        row.domain,
                        row.unit,
                    )
                }
                other => {
                    return Err(Error::parse(
                        at("kind"),
                        format!("unknown kind `{other}`; expected `weather` or `material`"),
                    ));
                }
            };
            let name = r.name.clone().unwrap_or_else(|| match &target {
                Target::Weather(p) => format!("weather.{}", p.name()),
                Target::Material { material, property } => {
                    format!("{material}.{}", property.name())
                }
            });
            if params.iter().any(|q| q.name == name) {
                return Err(Error::parse(
                    at("name"),
                    format!("duplicate parameter name `{name}`"),
                ));
            }
            if params.iter().any(|q| q.target == target) {
                return Err(Error::parse(
                    at("property"),
                    format!("`{name}` perturbs the same input as an earlier parameter"),
                ));
            }
            if !(r.low.is_finite() && r.high.is_finite() && r.low < r.high) {
                return Err(Error::parse(
                    at("low"),
                    format!(
                        "expected finite bounds with low < high, got [{}, {}]",
                        r.low, r.high
                    ),
                ));
            }
            let below = if excl { r.low <= dmin } else { r.low < dmin };
            if below || r.high > dmax {
                return Err(Error::parse(
                    at("low"),
                    format!(
                        "bounds [{}, {}] leave the property's domain ({}{dmin}, {dmax}]",
                        r.low,
                        r.high,
                        if excl { "(" } else { "[" }
                    ),
                ));
            }
            if let Some(u) = &r.unit {
                if u != unit {
                    return Err(Error::parse(
                        at("unit"),
                        format!("`{name}` is in {unit}, not {u}"),
                    ));
                }
            }
            if r.nominal.is_some() && r.value.is_some() {
                return Err(Error::parse(
                    at("value"),
                    "give `value` or `nominal` (the same thing), not both",
                ));
            }
            let given = r.value.or(r.nominal);
            let nominal = given.unwrap_or(default_nominal);
            if !(nominal >= r.low && nominal <= r.high) {
                return Err(Error::parse(
                    at("nominal"),
                    format!(
                        "nominal {nominal}{} lies outside [{}, {}]",
                        if given.is_none() {
                            " (the current value)"
                        } else {
                            ""
                        },
                        r.low,
                        r.high
                    ),
                ));
            }
            let uncertainty = r.uncertainty.unwrap_or((r.high - r.low) / 12f64.sqrt());
            if !(uncertainty.is_finite() && uncertainty >= 0.0) {
                return Err(Error::parse(
                    at("uncertainty"),
                    format!("expected a non-negative standard uncertainty, got {uncertainty}"),
                ));
            }
            params.push(Parameter {
                name,
                target,
                unit,
                nominal,
                low: r.low,
                high: r.high,
                uncertainty,
            });
        }
        Ok(ParamSet { params })
    }

    /// The parameters at `values` (one per parameter, in order) as a PARAMS
    /// list ([`registry::ListedParameter`]): what `--list-params` prints and
    /// what a calibration writes as its fitted parameters. Bounds are kept.
    pub fn listing(&self, values: &[f64]) -> Result<Vec<registry::ListedParameter>> {
        self.check_len(values)?;
        Ok(self
            .params
            .iter()
            .zip(values)
            .map(|(p, &v)| {
                let (kind, material, property) = match &p.target {
                    Target::Weather(w) => ("weather", None, w.name()),
                    Target::Material { material, property } => {
                        ("material", Some(material.clone()), property.name())
                    }
                };
                let default_name =
                    format!("{}.{property}", material.as_deref().unwrap_or("weather"));
                registry::ListedParameter {
                    name: (p.name != default_name).then(|| p.name.clone()),
                    kind,
                    material,
                    property: property.to_string(),
                    value: v,
                    unit: p.unit,
                    low: p.low,
                    high: p.high,
                }
            })
            .collect())
    }

    /// The nominal values, in order.
    pub fn nominal(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.nominal).collect()
    }

    /// The material names the parameters touch (each once, in order).
    pub fn materials(&self) -> Vec<&str> {
        let mut out: Vec<&str> = Vec::new();
        for p in &self.params {
            if let Target::Material { material, .. } = &p.target {
                if !out.contains(&material.as_str()) {
                    out.push(material);
                }
            }
        }
        out
    }

    /// Whether any parameter perturbs the weather.
    pub fn has_weather(&self) -> bool {
        self.params
            .iter()
            .any(|p| matches!(p.target, Target::Weather(_)))
    }

    fn check_len(&self, values: &[f64]) -> Result<()> {
        if values.len() != self.params.len() {
            return Err(Error::invalid(
                "parameter values",
                format!(
                    "{} values for {} parameters",
                    values.len(),
                    self.params.len()
                ),
            ));
        }
        Ok(())
    }

    /// A copy of `weather` with the weather parameters set to `values`
    /// (one value per parameter, in order; material entries are ignored).
    ///
    /// Without a site a cloud-cover change scales the direct and diffuse
    /// irradiance with the global one; see [`ParamSet::apply_weather_at`].
    pub fn apply_weather(
        &self,
        values: &[f64],
        weather: &[WeatherRecord],
    ) -> Result<Vec<WeatherRecord>> {
        self.apply_weather_at(values, weather, None)
    }

    /// [`ParamSet::apply_weather`] at `site`: a cloud-cover change moves
    /// the direct and diffuse irradiance by the change of their Erbs split
    /// at each record's solar position (see the module docs).
    ///
    /// # Errors
    /// A wrong number of values; a solar-position error (bad site or time).
    pub fn apply_weather_at(
        &self,
        values: &[f64],
        weather: &[WeatherRecord],
        site: Option<&Site>,
    ) -> Result<Vec<WeatherRecord>> {
        self.check_len(values)?;
        let mut w = weather.to_vec();
        for (p, &v) in self.params.iter().zip(values) {
            if let Target::Weather(wp) = p.target {
                for r in &mut w {
                    apply_weather_property(wp, v, r, site)?;
                }
            }
        }
        Ok(w)
    }

    /// A copy of `materials` with the material parameters set to `values`
    /// (weather entries are ignored).
    pub fn apply_materials(&self, values: &[f64], materials: &[Material]) -> Result<Vec<Material>> {
        self.check_len(values)?;
        let mut out = materials.to_vec();
        for (p, &v) in self.params.iter().zip(values) {
            if let Target::Material { material, property } = &p.target {
                let m = out
                    .iter_mut()
                    .find(|m| &m.name == material)
                    .ok_or_else(|| {
                        Error::invalid(&p.name, format!("no material `{material}` to apply it to"))
                    })?;
                property.set(m, v)?;
            }
        }
        Ok(out)
    }

    /// `material` with this set's parameters for it set to `values`.
    pub fn apply_material(&self, values: &[f64], material: &Material) -> Result<Material> {
        self.check_len(values)?;
        let mut m = material.clone();
        for (p, &v) in self.params.iter().zip(values) {
            if let Target::Material { material, property } = &p.target {
                if *material == m.name {
                    property.set(&mut m, v)?;
                }
            }
        }
        Ok(m)
    }
}

/// Saturation vapour pressure over water, Pa, at `t_k` (Magnus form,
/// Alduchov & Eskridge 1996, J. Appl. Meteor. 35, 601–609, eq. 21:
/// 610.94·exp(17.625·t/(t + 243.04)), t in °C; within 0.4 % for −40…50 °C).
pub fn saturation_vapour_pressure_pa(t_k: f64) -> f64 {
    let t = t_k - 273.15;
    610.94 * (17.625 * t / (t + 243.04)).exp()
}

/// Dew point, K, for air at `t_k` with relative humidity `rh` (0–1):
/// the inverse of [`saturation_vapour_pressure_pa`].
pub fn dew_point_k(t_k: f64, rh: f64) -> f64 {
    let g = (rh.max(1e-6) * saturation_vapour_pressure_pa(t_k) / 610.94).ln();
    243.04 * g / (17.625 - g) + 273.15
}

/// Kasten & Czeplak (1980) ratio of cloudy to clear-sky global horizontal
/// irradiance, `1 − 0.75 c^3.4`, for total sky cover `c` (fraction 0–1;
/// their N/8 in oktas). Dimensionless.
pub fn kasten_czeplak_cloud_ratio(total_sky_cover: f64) -> f64 {
    1.0 - 0.75 * total_sky_cover.clamp(0.0, 1.0).powf(3.4)
}

/// Multiply the sky longwave of `r` by the Clark & Allen emissivity ratio
/// between the record's current dew point / opaque cover and the old ones.
fn rescale_sky_longwave(r: &mut WeatherRecord, old_dew_k: f64, old_opaque: f64) {
    let old = clark_allen_sky_emissivity(old_dew_k, old_opaque);
    let new = clark_allen_sky_emissivity(r.dew_point_k, r.opaque_sky_cover);
    if old > 0.0 && new > 0.0 && old != new {
        r.sky_longwave_w_m2 *= new / old;
    }
}

fn apply_weather_property(
    p: WeatherProperty,
    v: f64,
    r: &mut WeatherRecord,
    site: Option<&Site>,
) -> Result<()> {
    match p {
        WeatherProperty::AirTemperatureOffsetK => {
            // Same vapour pressure (dew point) in warmer/cooler air: the
            // relative humidity scales by e_s(T_old)/e_s(T_new); an offset
            // of 0 leaves the record unchanged.
            let t_old = r.air_temperature_k;
            r.air_temperature_k += v;
            let rh = r.relative_humidity * saturation_vapour_pressure_pa(t_old)
                / saturation_vapour_pressure_pa(r.air_temperature_k);
            if rh > 1.0 {
                r.relative_humidity = 1.0;
                r.dew_point_k = r.air_temperature_k;
            } else {
                r.relative_humidity = rh;
            }
        }
        WeatherProperty::WindSpeedScale => r.wind_speed_m_s *= v,
        WeatherProperty::WindSpeedOffsetMS => r.wind_speed_m_s = (r.wind_speed_m_s + v).max(0.0),
        WeatherProperty::RelativeHumidityOffset => {
            // Dew point moved by the Magnus change, so that a record whose
            // fields disagree slightly is left exactly as it is at v = 0.
            let old = r.relative_humidity;
            let old_dew = r.dew_point_k;
            r.relative_humidity = (old + v).clamp(0.01, 1.0);
            r.dew_point_k += dew_point_k(r.air_temperature_k, r.relative_humidity)
                - dew_point_k(r.air_temperature_k, old.max(0.01));
            r.dew_point_k = r.dew_point_k.min(r.air_temperature_k);
            rescale_sky_longwave(r, old_dew, r.opaque_sky_cover);
        }
        WeatherProperty::InsolationScale => {
            r.direct_normal_w_m2 *= v;
            r.diffuse_horizontal_w_m2 *= v;
            r.global_horizontal_w_m2 *= v;
        }
        WeatherProperty::SkyLongwaveOffsetWM2 => {
            r.sky_longwave_w_m2 = (r.sky_longwave_w_m2 + v).max(0.0)
        }
        WeatherProperty::CloudCoverOffset => {
            let (old_total, old_opaque) = (r.total_sky_cover, r.opaque_sky_cover);
            r.total_sky_cover = (old_total + v).clamp(0.0, 1.0);
            r.opaque_sky_cover = (old_opaque + v).clamp(0.0, 1.0);
            rescale_sky_longwave(r, r.dew_point_k, old_opaque);
            let k_old = kasten_czeplak_cloud_ratio(old_total);
            let k_new = kasten_czeplak_cloud_ratio(r.total_sky_cover);
            if k_new != k_old && r.global_horizontal_w_m2 > 0.0 {
                let ghi = r.global_horizontal_w_m2;
                let ghi_new = ghi * k_new / k_old;
                match site {
                    Some(site) => {
                        let sp = sun::position_standard(site, r.time)?;
                        let (b0, d0) = erbs_split(ghi, sp.apparent_zenith_deg, sp.distance_au);
                        let (b1, d1) = erbs_split(ghi_new, sp.apparent_zenith_deg, sp.distance_au);
                        r.direct_normal_w_m2 = (r.direct_normal_w_m2 + b1 - b0).max(0.0);
                        r.diffuse_horizontal_w_m2 = (r.diffuse_horizontal_w_m2 + d1 - d0).max(0.0);
                    }
                    None => {
                        r.direct_normal_w_m2 *= k_new / k_old;
                        r.diffuse_horizontal_w_m2 *= k_new / k_old;
                    }
                }
                r.global_horizontal_w_m2 = ghi_new;
            }
        }
    }
    Ok(())
}
