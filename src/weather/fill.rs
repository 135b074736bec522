//! Records with missing fields → complete, validated [`WeatherRecord`]s.
//!
//! The rules are listed in the module documentation of [`crate::weather`].

use std::path::Path;

use chrono::{DateTime, FixedOffset, TimeDelta};

use super::physics;
use super::{Format, Timing, WeatherHistory, WeatherRecord, check_times};
use crate::error::{Error, Location, Result};
use crate::sun::{self, Site};

/// A record as read, SI units, `None` where the file had no value.
#[derive(Debug, Clone)]
pub(crate) struct RawRecord {
    /// Where the record came from (file and line, or JSON path).
    pub loc: Location,
    pub time: DateTime<FixedOffset>,
    pub air_temperature_k: Option<f64>,
    pub dew_point_k: Option<f64>,
    pub relative_humidity: Option<f64>,
    pub pressure_pa: Option<f64>,
    pub wind_speed_m_s: Option<f64>,
    pub wind_direction_deg: Option<f64>,
    pub direct_normal_w_m2: Option<f64>,
    pub diffuse_horizontal_w_m2: Option<f64>,
    pub global_horizontal_w_m2: Option<f64>,
    pub sky_longwave_w_m2: Option<f64>,
    pub total_sky_cover: Option<f64>,
    pub opaque_sky_cover: Option<f64>,
    pub precipitation_mm: Option<f64>,
    pub visibility_km: Option<f64>,
}

impl RawRecord {
    pub fn new(loc: Location, time: DateTime<FixedOffset>) -> RawRecord {
        RawRecord {
            loc,
            time,
            air_temperature_k: None,
            dew_point_k: None,
            relative_humidity: None,
            pressure_pa: None,
            wind_speed_m_s: None,
            wind_direction_deg: None,
            direct_normal_w_m2: None,
            diffuse_horizontal_w_m2: None,
            global_horizontal_w_m2: None,
            sky_longwave_w_m2: None,
            total_sky_cover: None,
            opaque_sky_cover: None,
            precipitation_mm: None,
            visibility_km: None,
        }
    }
}

/// What a reader hands to [`complete`].
#[derive(Debug, Clone)]
pub(crate) struct Parsed {
    pub records: Vec<RawRecord>,
    /// The file's own site, if it declares one.
    pub site: Option<Site>,
    /// How the values relate to the stamps in `records[i].time`.
    pub timing: Timing,
}

/// Valid range and description of each field (SI).
pub(crate) const RANGES: &[(&str, f64, f64, &str)] = &[
    ("air_temperature_k", 180.0, 340.0, "K"),
    ("dew_point_k", 150.0, 340.0, "K"),
    ("relative_humidity", 0.0, 1.0, "(fraction)"),
    ("pressure_pa", 30_000.0, 110_000.0, "Pa"),
    ("wind_speed_m_s", 0.0, 75.0, "m/s"),
    ("wind_direction_deg", 0.0, 360.0, "degrees"),
    ("direct_normal_w_m2", 0.0, 2000.0, "W/m²"),
    ("diffuse_horizontal_w_m2", 0.0, 2000.0, "W/m²"),
    ("global_horizontal_w_m2", 0.0, 2000.0, "W/m²"),
    ("sky_longwave_w_m2", 0.0, 1000.0, "W/m²"),
    ("total_sky_cover", 0.0, 1.0, "(fraction)"),
    ("opaque_sky_cover", 0.0, 1.0, "(fraction)"),
    ("precipitation_mm", 0.0, 500.0, "mm"),
    // 0 (fog) to beyond the clearest air's ~300 km (Rayleigh scattering alone).
    ("visibility_km", 0.0, 1000.0, "km"),
];

fn check_value(field: &'static str, v: f64) -> std::result::Result<(), (&'static str, String)> {
    let (_, lo, hi, unit) =
        RANGES
            .iter()
            .find(|r| r.0 == field)
            .copied()
            .unwrap_or((field, f64::MIN, f64::MAX, ""));
    if v.is_nan() {
        return Err((
            field,
            format!("{field} is NaN; expected a number in {lo}..{hi} {unit}"),
        ));
    }
    if !(lo..=hi).contains(&v) {
        let what = if lo == 0.0 && v < 0.0 && field.ends_with("_w_m2") {
            "negative irradiance"
        } else {
            "out of range"
        };
        return Err((
            field,
            format!("{field} = {v} {unit} is {what}; expected {lo}..{hi} {unit}"),
        ));
    }
    Ok(())
}

/// Validate a complete record: every field finite and in range, dew point not above the
/// air temperature by more than 1 K.
pub(crate) fn check_record(r: &WeatherRecord) -> std::result::Result<(), (&'static str, String)> {
    let fields = [
        ("air_temperature_k", r.air_temperature_k),
        ("dew_point_k", r.dew_point_k),
        ("relative_humidity", r.relative_humidity),
        ("pressure_pa", r.pressure_pa),
        ("wind_speed_m_s", r.wind_speed_m_s),
        ("wind_direction_deg", r.wind_direction_deg),
        ("direct_normal_w_m2", r.direct_normal_w_m2),
        ("diffuse_horizontal_w_m2", r.diffuse_horizontal_w_m2),
        ("global_horizontal_w_m2", r.global_horizontal_w_m2),
        ("sky_longwave_w_m2", r.sky_longwave_w_m2),
        ("total_sky_cover", r.total_sky_cover),
        ("opaque_sky_cover", r.opaque_sky_cover),
        ("precipitation_mm", r.precipitation_mm),
    ];
    for (f, v) in fields {
        check_value(f, v)?;
    }
    if let Some(v) = r.visibility_km {
        check_value("visibility_km", v)?;
    }
    check_dew(r.air_temperature_k, r.dew_point_k)
}

fn check_dew(air: f64, dew: f64) -> std::result::Result<(), (&'static str, String)> {
    if dew > air + 1.0 {
        return Err((
            "dew_point_k",
            format!(
                "dew point {dew} K is above the air temperature {air} K; expected dew point ≤ air temperature"
            ),
        ));
    }
    Ok(())
}

fn err_at(loc: &Location, (field, msg): (&'static str, String)) -> Error {
    Error::parse(loc.clone().with_field(field), msg)
}

fn require(loc: &Location, field: &'static str, v: Option<f64>, what: &str) -> Result<f64> {
    v.ok_or_else(|| {
        Error::parse(
            loc.clone().with_field(field),
            format!("{what} is missing; it is required and never filled"),
        )
    })
}

/// Fill and validate every record (see the module docs of [`crate::weather`]).
pub(crate) fn complete(
    parsed: Parsed,
    path: &Path,
    option_site: Option<Site>,
    format: Format,
) -> Result<WeatherHistory> {
    let site = parsed.site.or(option_site);
    if let Some(s) = &site {
        s.validate()
            .map_err(|e| Error::parse(Location::file(path), e.to_string()))?;
    }
    check_times(parsed.records.iter().map(|r| r.time), |i| {
        parsed
            .records
            .get(i)
            .map_or_else(|| Location::file(path), |r| r.loc.clone())
    })
    .map_err(|e| match (format, e) {
        (Format::Epw | Format::Tmy3, Error::Parse { location, message }) => Error::parse(
            location,
            format!("{message} (a typical-year file needs one year applied)"),
        ),
        (_, e) => e,
    })?;
    let timing = parsed.timing;
    let records = place_at_represented_instants(parsed.records, timing);

    let mut out = Vec::with_capacity(records.len());
    let mut filled_all = Vec::with_capacity(records.len());
    let mut last_pressure: Option<f64> = None;
    let mut last_wind_dir: Option<f64> = None;
    let mut last_total: Option<f64> = None;
    let mut last_opaque: Option<f64> = None;

    for raw in &records {
        let loc = &raw.loc;
        // Range checks of what the file gave.
        let given = [
            ("air_temperature_k", raw.air_temperature_k),
            ("dew_point_k", raw.dew_point_k),
            ("relative_humidity", raw.relative_humidity),
            ("pressure_pa", raw.pressure_pa),
            ("wind_speed_m_s", raw.wind_speed_m_s),
            ("wind_direction_deg", raw.wind_direction_deg),
            ("direct_normal_w_m2", raw.direct_normal_w_m2),
            ("diffuse_horizontal_w_m2", raw.diffuse_horizontal_w_m2),
            ("global_horizontal_w_m2", raw.global_horizontal_w_m2),
            ("sky_longwave_w_m2", raw.sky_longwave_w_m2),
            ("total_sky_cover", raw.total_sky_cover),
            ("opaque_sky_cover", raw.opaque_sky_cover),
            ("precipitation_mm", raw.precipitation_mm),
            ("visibility_km", raw.visibility_km),
        ];
        for (f, v) in given {
            if let Some(v) = v {
                check_value(f, v).map_err(|e| err_at(loc, e))?;
            }
        }
        let mut filled: Vec<&'static str> = Vec::new();

        let air = require(
            loc,
            "air_temperature_k",
            raw.air_temperature_k,
            "air temperature",
        )?;
        let (dew, rh) = match (raw.dew_point_k, raw.relative_humidity) {
            (Some(d), Some(h)) => (d, h),
            (Some(d), None) => {
                check_dew(air, d).map_err(|e| err_at(loc, e))?;
                filled.push("relative_humidity");
                (
                    d,
                    physics::relative_humidity_from_dew_point(air, d).min(1.0),
                )
            }
            (None, Some(h)) => {
                if h <= 0.0 {
                    return Err(Error::parse(
                        loc.clone().with_field("relative_humidity"),
                        "relative humidity 0 gives no dew point; expected a value in (0, 1]",
                    ));
                }
                filled.push("dew_point_k");
                (physics::dew_point_from_relative_humidity(air, h), h)
            }
            (None, None) => {
                return Err(Error::parse(
                    loc.clone().with_field("dew_point_k"),
                    "both dew point and relative humidity are missing; one is required",
                ));
            }
        };
        check_dew(air, dew).map_err(|e| err_at(loc, e))?;

        let pressure = match raw.pressure_pa.or(last_pressure) {
            Some(p) => {
                if raw.pressure_pa.is_none() {
                    filled.push("pressure_pa");
                }
                p
            }
            None => {
                filled.push("pressure_pa");
                sun::standard_pressure_pa(site.map_or(0.0, |s| s.altitude_m))
            }
        };
        if raw.pressure_pa.is_some() {
            last_pressure = raw.pressure_pa;
        }
        let wind = require(loc, "wind_speed_m_s", raw.wind_speed_m_s, "wind speed")?;
        let wind_dir = match raw.wind_direction_deg {
            Some(d) => {
                last_wind_dir = Some(d);
                d
            }
            None => {
                filled.push("wind_direction_deg");
                last_wind_dir.unwrap_or(180.0)
            }
        };

        // Sky cover: the other field, then the previous good value, then 5 tenths.
        let (total, opaque) = match (raw.total_sky_cover, raw.opaque_sky_cover) {
            (Some(t), Some(o)) => (t, o),
            (Some(t), None) => {
                filled.push("opaque_sky_cover");
                (t, last_opaque.unwrap_or(t))
            }
            (None, Some(o)) => {
                filled.push("total_sky_cover");
                (last_total.unwrap_or(o), o)
            }
            (None, None) => {
                filled.push("total_sky_cover");
                filled.push("opaque_sky_cover");
                (last_total.unwrap_or(0.5), last_opaque.unwrap_or(0.5))
            }
        };
        if raw.total_sky_cover.is_some() {
            last_total = raw.total_sky_cover;
        }
        if raw.opaque_sky_cover.is_some() {
            last_opaque = raw.opaque_sky_cover;
        }

        // Solar irradiance.
        let sun_at = |what: &str| -> Result<sun::SunPosition> {
            let s = site.ok_or_else(|| {
                Error::parse(
                    loc.clone(),
                    format!(
                        "{what} needs the solar position, but the file gives no site; \
                         supply it (scene site, or --lat/--lon/--alt)"
                    ),
                )
            })?;
            let t = raw.time;
            sun::position_standard(&s, t).map_err(|e| {
                Error::parse(
                    loc.clone(),
                    format!("{what} needs the solar position at {t}: {e}"),
                )
            })
        };
        let (dni, dhi, ghi) = match (
            raw.direct_normal_w_m2,
            raw.diffuse_horizontal_w_m2,
            raw.global_horizontal_w_m2,
        ) {
            (Some(b), Some(d), Some(g)) => (b, d, g),
            (Some(b), Some(d), None) => {
                let p = sun_at("global horizontal irradiance from direct and diffuse")?;
                filled.push("global_horizontal_w_m2");
                let cz = p.apparent_zenith_deg.to_radians().cos().max(0.0);
                (b, d, d + b * cz)
            }
            (None, Some(d), Some(g)) => {
                let p = sun_at("direct normal irradiance from global and diffuse")?;
                filled.push("direct_normal_w_m2");
                let cz = p.apparent_zenith_deg.to_radians().cos();
                let b = if p.apparent_zenith_deg > physics::ERBS_MAX_ZENITH_DEG {
                    0.0
                } else {
                    ((g - d) / cz).clamp(0.0, 2000.0)
                };
                (b, d, g)
            }
            (Some(b), None, Some(g)) => {
                let p = sun_at("diffuse horizontal irradiance from global and direct")?;
                filled.push("diffuse_horizontal_w_m2");
                let cz = p.apparent_zenith_deg.to_radians().cos().max(0.0);
                (b, (g - b * cz).max(0.0), g)
            }
            (None, None, Some(g)) => {
                let p = sun_at("the Erbs direct/diffuse split of global horizontal irradiance")?;
                filled.push("direct_normal_w_m2");
                filled.push("diffuse_horizontal_w_m2");
                let (b, d) = physics::erbs_split(g, p.apparent_zenith_deg, p.distance_au);
                (b, d, g)
            }
            _ => {
                return Err(Error::parse(
                    loc.clone().with_field("global_horizontal_w_m2"),
                    "solar irradiance is missing: expected global horizontal, or two of \
                     (global horizontal, direct normal, diffuse horizontal)",
                ));
            }
        };

        let sky = match raw.sky_longwave_w_m2 {
            Some(l) => l,
            None => {
                filled.push("sky_longwave_w_m2");
                physics::clark_allen_sky_longwave_w_m2(air, dew, opaque)
            }
        };

        let rec = WeatherRecord {
            time: raw.time,
            air_temperature_k: air,
            dew_point_k: dew,
            relative_humidity: rh,
            pressure_pa: pressure,
            wind_speed_m_s: wind,
            wind_direction_deg: wind_dir,
            direct_normal_w_m2: dni,
            diffuse_horizontal_w_m2: dhi,
            global_horizontal_w_m2: ghi,
            sky_longwave_w_m2: sky,
            total_sky_cover: total,
            opaque_sky_cover: opaque,
            precipitation_mm: raw.precipitation_mm.unwrap_or(0.0),
            visibility_km: raw.visibility_km,
        };
        check_record(&rec).map_err(|(f, m)| {
            err_at(
                loc,
                (f, format!("{m} (after filling {})", filled.join(", "))),
            )
        })?;
        out.push(rec);
        filled_all.push(filled);
    }
    Ok(WeatherHistory::from_parts(
        out, site, filled_all, format, timing,
    ))
}

/// Move records from their stamps to the instants their values represent
/// ([`Timing`]): interval means to mid-interval; for [`Timing::SolarMeanEnding`] the
/// readings at the stamps (air, humidity, pressure, wind, sky cover) are interpolated
/// linearly to the mid-interval from the previous stamp (visibility in its
/// extinction, [`super::lerp_visibility_km`]), where that is exactly one
/// interval earlier and both have the value (else the record keeps its own).
fn place_at_represented_instants(mut records: Vec<RawRecord>, timing: Timing) -> Vec<RawRecord> {
    let shift = timing.placement();
    if shift.is_zero() {
        return records;
    }
    if let Timing::SolarMeanEnding { interval_s } = timing {
        let interval = TimeDelta::seconds(i64::from(interval_s));
        let mean = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) => Some(0.5 * (a + b)),
            (_, b) => b,
        };
        for i in (1..records.len()).rev() {
            let (head, tail) = records.split_at_mut(i);
            let (a, b) = (&head[i - 1], &mut tail[0]);
            if b.time - a.time != interval {
                continue;
            }
            b.air_temperature_k = mean(a.air_temperature_k, b.air_temperature_k);
            b.dew_point_k = mean(a.dew_point_k, b.dew_point_k);
            b.relative_humidity = mean(a.relative_humidity, b.relative_humidity);
            b.pressure_pa = mean(a.pressure_pa, b.pressure_pa);
            b.wind_speed_m_s = mean(a.wind_speed_m_s, b.wind_speed_m_s);
            b.total_sky_cover = mean(a.total_sky_cover, b.total_sky_cover);
            b.opaque_sky_cover = mean(a.opaque_sky_cover, b.opaque_sky_cover);
            b.visibility_km = super::lerp_visibility_km(a.visibility_km, b.visibility_km, 0.5);
            if let (Some(da), Some(db)) = (a.wind_direction_deg, b.wind_direction_deg) {
                // Halfway along the shorter arc.
                let mut d = db - da;
                if d > 180.0 {
                    d -= 360.0;
                } else if d < -180.0 {
                    d += 360.0;
                }
                b.wind_direction_deg = Some((da + 0.5 * d).rem_euclid(360.0));
            }
        }
    }
    for r in &mut records {
        r.time += shift;
    }
    records
}
