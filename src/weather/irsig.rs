//! irsig's own weather formats: CSV and JSON, SI units, RFC 3339 times.
//!
//! CSV: lines starting with `#` are comments; a comment
//! `# site: latitude_deg=43.16 longitude_deg=-77.61 altitude_m=170` declares the site, and
//! `# timing: instant` (the default) or `# timing: interval-mean 60 min` how the values
//! relate to their times ([`super::Timing`]: readings at the time, or means over the
//! interval ending at it).
//! The header names the columns (any order, any subset of [`CSV_HEADER`] that includes
//! `time`); an empty cell is a missing value, filled as documented in [`crate::weather`].
//! Cells may be quoted (RFC 4180, as spreadsheets write them).
//!
//! JSON: `{"site": {"latitude_deg":…, "longitude_deg":…, "altitude_m":…} | null,
//! "timing": "instant" | "interval-mean 60 min" (optional, default instant),
//! "records": [{"time": "RFC 3339", "air_temperature_k": …, …}]}` with the same field
//! names; absent or `null` fields are missing values.
//!
//! Both take the optional `precipitation_mm` (mm since the previous record) and
//! `visibility_km` (horizontal visibility at the ground, km) besides [`CSV_HEADER`]'s.
//!
//! Owns both formats, reading and writing. Takes text and the path (for
//! messages); gives records whose fields may be missing. Must not know gap
//! filling or interpolation in time ([`super::fill`], [`super::WeatherHistory`]).

use std::io::Write;
use std::path::Path;

use chrono::{DateTime, FixedOffset};
use serde::Deserialize;

use super::fill::{Parsed, RawRecord};
use super::text::opt_number;
use super::{Timing, WeatherHistory, WeatherRecord};
use crate::error::{Error, Location, Result};
use crate::sun::Site;
use crate::textio;

/// The full header of an irsig weather CSV (also the column order [`write_csv`] uses).
pub const CSV_HEADER: &str = "time,air_temperature_k,dew_point_k,relative_humidity,pressure_pa,wind_speed_m_s,wind_direction_deg,direct_normal_w_m2,diffuse_horizontal_w_m2,global_horizontal_w_m2,sky_longwave_w_m2,total_sky_cover,opaque_sky_cover";

fn parse_time(s: &str, loc: &Location) -> Result<DateTime<FixedOffset>> {
    crate::sun::parse_time(s).map_err(|e| Error::parse(loc.clone(), format!("time {e}")))
}

fn parse_site_comment(rest: &str, loc: &Location) -> Result<Site> {
    rest.parse::<Site>()
        .map_err(|e| Error::parse(loc.clone(), format!("site comment: {e}")))
}

fn set_field(r: &mut RawRecord, name: &str, v: Option<f64>) {
    match name {
        "air_temperature_k" => r.air_temperature_k = v,
        "dew_point_k" => r.dew_point_k = v,
        "relative_humidity" => r.relative_humidity = v,
        "pressure_pa" => r.pressure_pa = v,
        "wind_speed_m_s" => r.wind_speed_m_s = v,
        "wind_direction_deg" => r.wind_direction_deg = v,
        "direct_normal_w_m2" => r.direct_normal_w_m2 = v,
        "diffuse_horizontal_w_m2" => r.diffuse_horizontal_w_m2 = v,
        "global_horizontal_w_m2" => r.global_horizontal_w_m2 = v,
        "sky_longwave_w_m2" => r.sky_longwave_w_m2 = v,
        "total_sky_cover" => r.total_sky_cover = v,
        "opaque_sky_cover" => r.opaque_sky_cover = v,
        "precipitation_mm" => r.precipitation_mm = v,
        "visibility_km" => r.visibility_km = v,
        _ => {}
    }
}

pub(crate) fn read_csv(text: &str, path: &Path) -> Result<Parsed> {
    // The columns of `CSV_HEADER`, and the optional `precipitation_mm` and
    // `visibility_km`.
    let known: Vec<&str> = CSV_HEADER
        .split(',')
        .chain(["precipitation_mm", "visibility_km"])
        .collect();
    let mut site = None;
    let mut timing = Timing::Instant;
    let mut header: Option<Vec<String>> = None;
    let mut records = Vec::new();
    let mut csv = textio::Splitter::new();
    for (lineno, line) in textio::lines(text) {
        let loc = Location::file(path).at_line(lineno);
        let line = line.trim_start_matches('\u{feff}').trim_end();
        if line.trim().is_empty() {
            continue;
        }
        if let Some(c) = line.strip_prefix('#') {
            if let Some(rest) = c.trim_start().strip_prefix("site:") {
                site = Some(parse_site_comment(rest, &loc)?);
            } else if let Some(rest) = c.trim_start().strip_prefix("timing:") {
                timing = rest
                    .parse()
                    .map_err(|e: String| Error::parse(loc.with_field("timing"), e))?;
            }
            continue;
        }
        let cells = csv.split(line);
        let Some(cols) = &header else {
            let cols = cells;
            for (j, c) in cols.iter().enumerate() {
                if !known.contains(&c.as_str()) {
                    return Err(Error::parse(
                        loc.with_field(c.clone()),
                        format!(
                            "unknown column `{c}` (column {}){}; expected names from `{CSV_HEADER}`",
                            j + 1,
                            crate::suggest::hint(c, known.iter().copied())
                        ),
                    ));
                }
                if cols[..j].contains(c) {
                    return Err(Error::parse(
                        loc.with_field(c.clone()),
                        format!("column `{c}` appears twice"),
                    ));
                }
            }
            if !cols.iter().any(|c| c == "time") {
                return Err(Error::parse(
                    loc.with_field("time"),
                    "the header has no `time` column",
                ));
            }
            header = Some(cols);
            continue;
        };
        if cells.len() != cols.len() {
            let field = cols.get(cells.len()).cloned().unwrap_or_default();
            return Err(Error::parse(
                if cells.len() < cols.len() {
                    loc.with_field(field)
                } else {
                    loc
                },
                format!(
                    "{} columns, expected {} as in the header{}",
                    cells.len(),
                    cols.len(),
                    if cells.len() < cols.len() {
                        " (missing columns from the one named)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        let ti = cols.iter().position(|c| c == "time").unwrap_or(0);
        let time = parse_time(&cells[ti], &loc.clone().with_field("time"))?;
        let mut r = RawRecord::new(loc.clone(), time);
        for (c, cell) in cols.iter().zip(&cells) {
            if c == "time" {
                continue;
            }
            let v = opt_number(cell, &loc.clone().with_field(c.clone()), c)?;
            set_field(&mut r, c, v);
        }
        records.push(r);
    }
    if header.is_none() {
        return Err(Error::parse(
            Location::file(path),
            format!("no header line; expected `{CSV_HEADER}`"),
        ));
    }
    Ok(Parsed {
        records,
        site,
        timing,
    })
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonFile {
    #[serde(default)]
    site: Option<Site>,
    #[serde(default)]
    timing: Option<String>,
    records: Vec<JsonRecord>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonRecord {
    time: String,
    air_temperature_k: Option<f64>,
    dew_point_k: Option<f64>,
    relative_humidity: Option<f64>,
    pressure_pa: Option<f64>,
    wind_speed_m_s: Option<f64>,
    wind_direction_deg: Option<f64>,
    direct_normal_w_m2: Option<f64>,
    diffuse_horizontal_w_m2: Option<f64>,
    global_horizontal_w_m2: Option<f64>,
    sky_longwave_w_m2: Option<f64>,
    total_sky_cover: Option<f64>,
    opaque_sky_cover: Option<f64>,
    #[serde(default)]
    precipitation_mm: Option<f64>,
    #[serde(default)]
    visibility_km: Option<f64>,
}

pub(crate) fn read_json(text: &str, path: &Path) -> Result<Parsed> {
    let f: JsonFile = serde_json::from_str(text).map_err(|e| {
        Error::parse(
            Location::file(path).at_line(e.line()),
            format!("{e}; expected {{\"site\": …, \"records\": [{{\"time\": …, …}}]}}"),
        )
    })?;
    if let Some(s) = &f.site {
        s.validate()
            .map_err(|e| Error::parse(Location::file(path).with_field("site"), e.to_string()))?;
    }
    let timing = match &f.timing {
        None => Timing::Instant,
        Some(t) => t
            .parse()
            .map_err(|e: String| Error::parse(Location::file(path).with_field("timing"), e))?,
    };
    let mut records = Vec::with_capacity(f.records.len());
    for (i, j) in f.records.into_iter().enumerate() {
        let loc = Location::file(path).with_field(format!("records[{i}]"));
        let time = parse_time(
            &j.time,
            &Location::file(path).with_field(format!("records[{i}].time")),
        )?;
        let mut r = RawRecord::new(loc, time);
        r.air_temperature_k = j.air_temperature_k;
        r.dew_point_k = j.dew_point_k;
        r.relative_humidity = j.relative_humidity;
        r.pressure_pa = j.pressure_pa;
        r.wind_speed_m_s = j.wind_speed_m_s;
        r.wind_direction_deg = j.wind_direction_deg;
        r.direct_normal_w_m2 = j.direct_normal_w_m2;
        r.diffuse_horizontal_w_m2 = j.diffuse_horizontal_w_m2;
        r.global_horizontal_w_m2 = j.global_horizontal_w_m2;
        r.sky_longwave_w_m2 = j.sky_longwave_w_m2;
        r.total_sky_cover = j.total_sky_cover;
        r.opaque_sky_cover = j.opaque_sky_cover;
        r.precipitation_mm = j.precipitation_mm;
        r.visibility_km = j.visibility_km;
        records.push(r);
    }
    Ok(Parsed {
        records,
        site: f.site,
        timing,
    })
}

fn csv_row(r: &WeatherRecord) -> [String; 13] {
    [
        r.time.to_rfc3339(),
        format!("{:.3}", r.air_temperature_k),
        format!("{:.3}", r.dew_point_k),
        format!("{:.4}", r.relative_humidity),
        format!("{:.1}", r.pressure_pa),
        format!("{:.2}", r.wind_speed_m_s),
        format!("{:.1}", r.wind_direction_deg),
        format!("{:.2}", r.direct_normal_w_m2),
        format!("{:.2}", r.diffuse_horizontal_w_m2),
        format!("{:.2}", r.global_horizontal_w_m2),
        format!("{:.2}", r.sky_longwave_w_m2),
        format!("{:.3}", r.total_sky_cover),
        format!("{:.3}", r.opaque_sky_cover),
    ]
}

/// Write a history as irsig CSV (site comment when known, then [`CSV_HEADER`], then
/// one row per record; `comments` are written first, each prefixed with `# `).
/// Rows go through the `csv` crate's writer (quoting only where a cell needs it).
///
/// # Errors
/// I/O errors of `w`.
pub fn write_csv(
    history: &WeatherHistory,
    comments: &[&str],
    w: &mut impl Write,
) -> std::io::Result<()> {
    for c in comments {
        writeln!(w, "# {c}")?;
    }
    if let Some(s) = history.site() {
        writeln!(
            w,
            "# site: latitude_deg={} longitude_deg={} altitude_m={}",
            s.latitude_deg, s.longitude_deg, s.altitude_m
        )?;
    }
    let mut out = csv::Writer::from_writer(w);
    // `precipitation_mm` only when the history has some, so that a dry
    // history writes the columns of `CSV_HEADER` alone.
    // Likewise `visibility_km` only when some record has one (empty cells
    // where others have none).
    let rain = history.records().iter().any(|r| r.precipitation_mm > 0.0);
    let vis = history.records().iter().any(|r| r.visibility_km.is_some());
    let mut header: Vec<&str> = CSV_HEADER.split(',').collect();
    if rain {
        header.push("precipitation_mm");
    }
    if vis {
        header.push("visibility_km");
    }
    out.write_record(&header)?;
    for r in history.records() {
        let mut row = csv_row(r).to_vec();
        if rain {
            row.push(format!("{:.2}", r.precipitation_mm));
        }
        if vis {
            row.push(r.visibility_km.map_or(String::new(), |v| format!("{v:.3}")));
        }
        out.write_record(row)?;
    }
    out.flush()
}
