//! NSRDB TMY3 CSV (Wilcox & Marion 2008, *Users Manual for TMY3 Data Sets*,
//! NREL/TP-581-43156).
//!
//! Line 1: `USAF,"station name",state,time zone (h),latitude,longitude,elevation (m)`.
//! Line 2: column names, e.g. `Date (MM/DD/YYYY),Time (HH:MM),…,GHI (W/m^2),…`.
//! Rows are hour-ending local standard time (`01:00`..`24:00`); solar values are the
//! hour's totals (Wh/m² = mean W/m²), so an irradiance split uses the Sun at the hour's
//! midpoint. Missing values are written −9900 (manual §4) or left empty. Columns are
//! found by name; the units are those in the names (°C, %, mbar, m/s, tenths,
//! m for the horizontal visibility `Hvis`).
//!
//! Rain: `Lprecip depth (mm)` is the liquid precipitation over the `Lprecip quantity (hr)`
//! hours ending at the row (manual, table 1-4; empty or missing quantity: one hour). A
//! depth over several hours is spread evenly over those rows, back to (not including) the
//! previous row with a reading of its own, so each record carries the millimetres of its
//! own hour ([`crate::weather::WeatherRecord::precipitation_mm`]). Rows without a reading
//! are dry. NSRDB's TMY3 precipitation comes from a sparse gauge network and is known to be
//! unreliable in amount; a wet-surface model (surface water stores that overflow) depends
//! mostly on whether and when it rained.
//!
//! Takes text, the path (for messages) and [`LoadOptions`]; gives records
//! whose fields may be missing, the site, and the half-hour by which
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

/// Values at or below this are TMY3's "missing" code (−9900).
const MISSING: f64 = -9900.0;

const DATE: &str = "Date (MM/DD/YYYY)";
const TIME: &str = "Time (HH:MM)";
/// (column name, required)
const COLUMNS: [(&str, bool); 14] = [
    ("GHI (W/m^2)", true),
    ("DNI (W/m^2)", true),
    ("DHI (W/m^2)", true),
    ("TotCld (tenths)", false),
    ("OpqCld (tenths)", false),
    ("Dry-bulb (C)", true),
    ("Dew-point (C)", false),
    ("RHum (%)", false),
    ("Pressure (mbar)", false),
    ("Wdir (degrees)", false),
    ("Wspd (m/s)", true),
    ("Hvis (m)", false),
    ("Lprecip depth (mm)", false),
    ("Lprecip quantity (hr)", false),
];

pub(crate) fn read(text: &str, path: &Path, options: &LoadOptions) -> Result<Parsed> {
    let mut lines = textio::lines(text);
    let (_, meta) = lines
        .next()
        .ok_or_else(|| Error::parse(Location::file(path), "empty TMY3 file"))?;
    let mloc = Location::file(path).at_line(1);
    let mut csv = textio::Splitter::new();
    let m = csv.split(meta);
    if m.len() < 7 {
        return Err(Error::parse(
            mloc,
            "expected site metadata `USAF,name,state,time zone,latitude,longitude,elevation`",
        ));
    }
    let tz = number(
        &m[3],
        &mloc.clone().with_field("time zone"),
        "time zone (h)",
    )?;
    let lat = number(&m[4], &mloc.clone().with_field("latitude"), "latitude (°)")?;
    let lon = number(
        &m[5],
        &mloc.clone().with_field("longitude"),
        "longitude (°)",
    )?;
    let elev = number(
        &m[6],
        &mloc.clone().with_field("elevation"),
        "elevation (m)",
    )?;
    let site = Site::new(lat, lon, elev).map_err(|e| Error::parse(mloc.clone(), e.to_string()))?;
    let offset = if (-14.0..=14.0).contains(&tz) {
        FixedOffset::east_opt((tz * 3600.0).round() as i32)
    } else {
        None
    }
    .ok_or_else(|| {
        Error::parse(
            mloc.clone().with_field("time zone"),
            format!("time zone {tz} h: expected −14..14"),
        )
    })?;

    let (hi, header) = lines
        .next()
        .ok_or_else(|| Error::parse(Location::file(path).at_line(2), "missing column-name line"))?;
    let hloc = Location::file(path).at_line(hi);
    let names = csv.split(header);
    let find = |name: &str| names.iter().position(|n| n == name);
    let date_i = find(DATE).ok_or_else(|| {
        Error::parse(hloc.clone().with_field(DATE), format!("no `{DATE}` column"))
    })?;
    let time_i = find(TIME).ok_or_else(|| {
        Error::parse(hloc.clone().with_field(TIME), format!("no `{TIME}` column"))
    })?;
    let mut idx = [None; COLUMNS.len()];
    for (k, (name, required)) in COLUMNS.iter().enumerate() {
        idx[k] = find(name);
        if *required && idx[k].is_none() {
            return Err(Error::parse(
                hloc.clone().with_field(*name),
                format!("no `{name}` column"),
            ));
        }
    }

    let mut rows = Vec::new();
    // Per row: the precipitation reading (mm) and its accumulation period (h).
    let mut rain: Vec<Option<(f64, f64)>> = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let loc = Location::file(path).at_line(i);
        let f = csv.split(line);
        if f.len() < names.len() {
            return Err(Error::parse(
                loc.with_field(names[f.len()].clone()),
                format!(
                    "{} columns, expected {} as in the header",
                    f.len(),
                    names.len()
                ),
            ));
        }
        let dloc = loc.clone().with_field(DATE);
        let date_s = f[date_i].trim();
        let mut dp = date_s.split('/').map(|p| p.trim().parse::<u32>().ok());
        let (month, day, year) = match (dp.next(), dp.next(), dp.next(), dp.next()) {
            (Some(Some(mo)), Some(Some(da)), Some(Some(yr)), None)
                if (1..=12).contains(&mo) && (1..=31).contains(&da) =>
            {
                (mo, da, yr)
            }
            _ => {
                return Err(Error::parse(
                    dloc,
                    format!("`{date_s}` is not a MM/DD/YYYY date"),
                ));
            }
        };
        let time_s = f[time_i].trim();
        let hm = time_s
            .split_once(':')
            .and_then(|(h, m)| Some((h.parse::<i64>().ok()?, m.parse::<i64>().ok()?)))
            .filter(|&(h, m)| (0..=24).contains(&h) && (0..60).contains(&m))
            .ok_or_else(|| {
                Error::parse(
                    loc.clone().with_field(TIME),
                    format!("`{time_s}` is not HH:MM (01:00..24:00, hour-ending)"),
                )
            })?;
        let stamp = Stamp {
            year: year as i32,
            month,
            day,
            minutes: hm.0 * 60 + hm.1,
        };
        let get = |k: usize| -> Result<Option<f64>> {
            let Some(j) = idx[k] else { return Ok(None) };
            let s = f[j].trim();
            if s.is_empty() {
                return Ok(None);
            }
            let v = number(s, &loc.clone().with_field(COLUMNS[k].0), COLUMNS[k].0)?;
            Ok(if v <= MISSING { None } else { Some(v) })
        };
        let mut r = RawRecord::new(loc.clone(), DateTime::default());
        r.global_horizontal_w_m2 = get(0)?;
        r.direct_normal_w_m2 = get(1)?;
        r.diffuse_horizontal_w_m2 = get(2)?;
        r.total_sky_cover = get(3)?.map(|t| t / 10.0);
        r.opaque_sky_cover = get(4)?.map(|t| t / 10.0);
        r.air_temperature_k = get(5)?.map(|c| c + 273.15);
        r.dew_point_k = get(6)?.map(|c| c + 273.15);
        r.relative_humidity = get(7)?.map(|p| p / 100.0);
        r.pressure_pa = get(8)?.map(|p| p * 100.0);
        r.wind_direction_deg = get(9)?;
        r.wind_speed_m_s = get(10)?;
        r.visibility_km = get(11)?.map(|m| m / 1000.0);
        let depth = get(12)?;
        if let Some(d) = depth.filter(|d| *d < 0.0) {
            return Err(Error::parse(
                loc.clone().with_field(COLUMNS[12].0),
                format!("negative precipitation depth {d} mm"),
            ));
        }
        let hours = get(13)?.unwrap_or(1.0);
        if !(0.0..=744.0).contains(&hours) {
            return Err(Error::parse(
                loc.clone().with_field(COLUMNS[13].0),
                format!("accumulation period {hours} h: expected 0..744 h"),
            ));
        }
        rain.push(depth.map(|d| (d, hours)));
        rows.push((stamp, r));
    }
    for (k, mm) in spread_precipitation(&rain).into_iter().enumerate() {
        rows[k].1.precipitation_mm = mm;
    }
    Ok(Parsed {
        records: calendar::place(rows, offset, options)?,
        site: Some(site),
        timing: Timing::SolarMeanEnding { interval_s: 3600 },
    })
}

/// Each row's own precipitation (mm) from TMY3's readings (`depth` mm over `hours` h
/// ending at the row, `None` where the row has no reading): a depth over `n > 1` hours
/// is shared evenly by its row and the `n − 1` rows before it, stopping after the
/// previous row with a reading. Rows no reading reaches stay `None` (dry).
fn spread_precipitation(readings: &[Option<(f64, f64)>]) -> Vec<Option<f64>> {
    let mut out: Vec<Option<f64>> = vec![None; readings.len()];
    let mut last_reading: Option<usize> = None;
    for (i, r) in readings.iter().enumerate() {
        let Some((depth, hours)) = *r else { continue };
        let span = (hours.round() as usize).max(1);
        let first = (i + 1).saturating_sub(span);
        let first = last_reading.map_or(first, |l| first.max(l + 1));
        let share = depth / (i + 1 - first) as f64;
        for o in &mut out[first..=i] {
            *o = Some(share);
        }
        last_reading = Some(i);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::spread_precipitation;

    #[test]
    fn a_depth_over_several_hours_is_shared_by_the_rows_it_covers() {
        // 6 mm over 3 h at row 4 (rows 2–4 have no reading of their own), 1 mm in row 1's
        // own hour; 4 mm over 6 h at row 6 reaches back only to row 5 (row 4 has a reading).
        let r = [
            None,
            Some((1.0, 1.0)),
            None,
            None,
            Some((6.0, 3.0)),
            None,
            Some((4.0, 6.0)),
        ];
        assert_eq!(
            spread_precipitation(&r),
            vec![
                None,
                Some(1.0),
                Some(2.0),
                Some(2.0),
                Some(2.0),
                Some(2.0),
                Some(2.0)
            ]
        );
        // Quantity 0 (or missing, read as 1) keeps the depth in its own row.
        assert_eq!(
            spread_precipitation(&[None, Some((3.0, 0.0))]),
            vec![None, Some(3.0)]
        );
    }
}
