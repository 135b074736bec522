//! EnergyPlus weather files (EPW).
//!
//! Format: EnergyPlus *Auxiliary Programs*, "Weather Converter Program — EnergyPlus
//! Weather File (EPW) Data Dictionary". Eight header lines (LOCATION, DESIGN CONDITIONS,
//! TYPICAL/EXTREME PERIODS, GROUND TEMPERATURES, HOLIDAYS/DAYLIGHT SAVINGS, COMMENTS 1,
//! COMMENTS 2, DATA PERIODS), then one comma-separated row per interval with 35 fields.
//! `LOCATION,city,state,country,source,WMO,latitude,longitude,time zone,elevation`
//! gives the site (longitude east-positive) and the time zone (hours from UTC) in which
//! rows are *local standard time*. Hour 1..24 is hour-ending: hour 1 covers 00:00–01:00
//! and is stamped 01:00. Solar fields are Wh/m² over the interval (equal to the mean
//! W/m² of an hourly interval); the solar position for an irradiance split is taken at
//! the interval's midpoint.
//!
//! Fields used (0-based) and their "missing" codes: 6 dry bulb °C (≥ 99.9),
//! 7 dew point °C (≥ 99.9), 8 RH % (≥ 999), 9 station pressure Pa (≥ 999 999),
//! 12 horizontal infrared Wh/m² (≥ 9999), 13 GHI, 14 DNI, 15 DHI Wh/m² (≥ 9999),
//! 20 wind direction ° (≥ 999), 21 wind speed m/s (≥ 999), 22 total and 23 opaque sky
//! cover tenths (≥ 99), 24 visibility km (≥ 9999; field 25 counting from 1).
//!
//! Takes text, the path (for messages) and [`LoadOptions`]; gives records
//! whose fields may be missing, the site, and the half-interval by which
//! irradiance lags the stamps. Must not fill gaps ([`super::fill`]).

use std::path::Path;

use chrono::{DateTime, FixedOffset};

use super::calendar::{self, Stamp};
use super::fill::{Parsed, RawRecord};
use super::text::number;
use super::{LoadOptions, Timing};
use crate::error::{Error, Location, Result};
use crate::sun::Site;
use crate::textio;

const FIELDS: [&str; 24] = [
    "year",
    "month",
    "day",
    "hour",
    "minute",
    "data source flags",
    "dry bulb temperature (°C)",
    "dew point temperature (°C)",
    "relative humidity (%)",
    "atmospheric station pressure (Pa)",
    "extraterrestrial horizontal radiation",
    "extraterrestrial direct normal radiation",
    "horizontal infrared radiation intensity (Wh/m²)",
    "global horizontal radiation (Wh/m²)",
    "direct normal radiation (Wh/m²)",
    "diffuse horizontal radiation (Wh/m²)",
    "global horizontal illuminance",
    "direct normal illuminance",
    "diffuse horizontal illuminance",
    "zenith luminance",
    "wind direction (°)",
    "wind speed (m/s)",
    "total sky cover (tenths)",
    "opaque sky cover (tenths)",
];

/// Parse the LOCATION line: site and UTC offset.
fn location(line: &str, loc: &Location) -> Result<(Site, FixedOffset)> {
    let f = textio::Splitter::new().split(line);
    if f.len() < 10 || f[0].trim() != "LOCATION" {
        return Err(Error::parse(
            loc.clone(),
            "expected `LOCATION,city,state,country,source,WMO,latitude,longitude,time zone,elevation`",
        ));
    }
    let lat = number(&f[6], &loc.clone().with_field("latitude"), "latitude (°)")?;
    let lon = number(&f[7], &loc.clone().with_field("longitude"), "longitude (°)")?;
    let tz = number(
        &f[8],
        &loc.clone().with_field("time zone"),
        "time zone (hours)",
    )?;
    let elev = number(&f[9], &loc.clone().with_field("elevation"), "elevation (m)")?;
    let site = Site::new(lat, lon, elev).map_err(|e| Error::parse(loc.clone(), e.to_string()))?;
    let offset = if (-14.0..=14.0).contains(&tz) {
        FixedOffset::east_opt((tz * 3600.0).round() as i32)
    } else {
        None
    }
    .ok_or_else(|| {
        Error::parse(
            loc.clone().with_field("time zone"),
            format!("time zone {tz} h: expected −14..14 hours from UTC"),
        )
    })?;
    Ok((site, offset))
}

pub(crate) fn read(text: &str, path: &Path, options: &LoadOptions) -> Result<Parsed> {
    let lines: Vec<&str> = textio::lines(text).map(|(_, l)| l).collect();
    if lines.len() < 9 {
        return Err(Error::parse(
            Location::file(path),
            format!(
                "{} lines; an EPW file has 8 header lines and then data rows",
                lines.len()
            ),
        ));
    }
    let (site, offset) = location(lines[0], &Location::file(path).at_line(1))?;
    // DATA PERIODS,<n periods>,<records per hour>,…
    let mut per_hour = 1.0;
    let mut csv = textio::Splitter::new();
    let dp = csv.split(lines[7]);
    if dp.first().map(|s| s.trim()) == Some("DATA PERIODS") && dp.len() > 2 {
        per_hour = number(
            &dp[2],
            &Location::file(path)
                .at_line(8)
                .with_field("records per hour"),
            "records per hour",
        )?;
        if !(1.0..=60.0).contains(&per_hour) {
            return Err(Error::parse(
                Location::file(path)
                    .at_line(8)
                    .with_field("records per hour"),
                format!("{per_hour} records per hour; expected 1..60"),
            ));
        }
    }
    let interval_min = 60.0 / per_hour;

    let mut rows = Vec::new();
    for (i, line) in lines.iter().enumerate().skip(8) {
        if line.trim().is_empty() {
            continue;
        }
        let loc = Location::file(path).at_line(i + 1);
        let f = csv.split(line);
        if f.len() < FIELDS.len() {
            return Err(Error::parse(
                loc.with_field(FIELDS[f.len()]),
                format!(
                    "{} fields; an EPW data row has 35 (missing from field {}, {})",
                    f.len(),
                    f.len() + 1,
                    FIELDS[f.len()]
                ),
            ));
        }
        let val = |k: usize| number(&f[k], &loc.clone().with_field(FIELDS[k]), FIELDS[k]);
        let opt = |k: usize, missing: f64| -> Result<Option<f64>> {
            let v = val(k)?;
            Ok(if v >= missing { None } else { Some(v) })
        };
        let (year, month, day, hour, minute) = (val(0)?, val(1)?, val(2)?, val(3)?, val(4)?);
        if !(1.0..=12.0).contains(&month) || month.fract() != 0.0 {
            return Err(Error::parse(
                loc.with_field("month"),
                format!("month {month}: expected an integer 1..12"),
            ));
        }
        if !(1.0..=31.0).contains(&day) || day.fract() != 0.0 {
            return Err(Error::parse(
                loc.with_field("day"),
                format!("day {day}: expected an integer 1..31"),
            ));
        }
        if !(1.0..=24.0).contains(&hour) || hour.fract() != 0.0 {
            return Err(Error::parse(
                loc.with_field("hour"),
                format!("hour {hour}: expected an integer 1..24 (hour-ending)"),
            ));
        }
        // Hour-ending: hour H, minute M in 1..59 → (H−1):M; minute 0 or 60 → H:00.
        let minutes = if minute > 0.0 && minute < 60.0 {
            (hour - 1.0) * 60.0 + minute
        } else {
            hour * 60.0
        };
        let stamp = Stamp {
            year: year as i32,
            month: month as u32,
            day: day as u32,
            minutes: minutes.round() as i64,
        };
        let mut r = RawRecord::new(loc.clone(), DateTime::default());
        r.air_temperature_k = opt(6, 99.9)?.map(|c| c + 273.15);
        r.dew_point_k = opt(7, 99.9)?.map(|c| c + 273.15);
        r.relative_humidity = opt(8, 999.0)?.map(|p| p / 100.0);
        r.pressure_pa = opt(9, 999_999.0)?;
        r.sky_longwave_w_m2 = opt(12, 9999.0)?;
        r.global_horizontal_w_m2 = opt(13, 9999.0)?;
        r.direct_normal_w_m2 = opt(14, 9999.0)?;
        r.diffuse_horizontal_w_m2 = opt(15, 9999.0)?;
        r.wind_direction_deg = opt(20, 999.0)?;
        r.wind_speed_m_s = opt(21, 999.0)?;
        r.total_sky_cover = opt(22, 99.0)?.map(|t| t / 10.0);
        r.opaque_sky_cover = opt(23, 99.0)?.map(|t| t / 10.0);
        // Horizontal visibility, km (field 25; 9999 is missing).
        const VIS: &str = "visibility (km)";
        r.visibility_km = match f.get(24).map(|c| c.trim()) {
            None | Some("") => None,
            Some(_) => {
                let v = number(&f[24], &loc.clone().with_field(VIS), VIS)?;
                (v < 9999.0).then_some(v)
            }
        };
        // Liquid precipitation depth, mm (field 34; older files end before it;
        // 999 or empty is missing).
        const PRECIP: &str = "liquid precipitation depth (mm)";
        r.precipitation_mm = match f.get(33).map(|c| c.trim()) {
            None | Some("") => None,
            Some(_) => {
                let v = number(&f[33], &loc.clone().with_field(PRECIP), PRECIP)?;
                (v < 999.0 && v > 0.0).then_some(v)
            }
        };
        rows.push((stamp, r));
    }
    Ok(Parsed {
        records: calendar::place(rows, offset, options)?,
        site: Some(site),
        timing: Timing::SolarMeanEnding {
            interval_s: (interval_min * 60.0).round() as u32,
        },
    })
}
