//! Weather histories: a time series of surface meteorology in SI units,
//! interpolated in time, read from irsig JSON/CSV, EPW, TMY3 and DIRSIG `.wth`.
//!
//! Every reader turns its file into records whose fields may be missing; one common
//! step ([`fill`]) then fills the gaps the way the reference tools do and records which
//! fields were filled:
//!
//! - dew point ↔ relative humidity by the Magnus form of Alduchov & Eskridge (1996);
//! - sky longwave by Clark & Allen as EnergyPlus does ([`physics::clark_allen_sky_longwave_w_m2`]);
//! - a missing direct/diffuse split from global horizontal by Erbs et al. (1982), or the
//!   third of (GHI, DNI, DHI) from the closure GHI = DHI + DNI cos z (both need the site
//!   and the Sun, [`crate::sun`]);
//! - pressure, wind direction and sky cover, when missing, hold the previous good value
//!   (EnergyPlus practice); before any good value: the standard atmosphere at the site's
//!   altitude, 180°, and the other sky-cover field or 5 tenths (EnergyPlus defaults).
//!
//! Air temperature, humidity (dew point or RH), wind speed and solar irradiance are never
//! invented: a record without them is an error naming the file and line.
//!
//! Owns [`WeatherHistory`] (records and their interpolation in time, each
//! field by [`crate::math::lerp`], wind direction the short way round),
//! format detection and loading. Takes a path or text; gives a filled
//! history. Must not know the thermal model that consumes it.

use std::path::Path;

use chrono::{DateTime, FixedOffset, TimeDelta, TimeZone};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Location, Result};
use crate::math::lerp;
use crate::sun::Site;

mod calendar;
mod epw;
mod fill;
pub mod flux;
mod irsig;
pub mod physics;
pub mod synth;
mod text;
mod tmy3;
mod wth;

pub use irsig::{CSV_HEADER, write_csv};

/// One weather record, SI units. Field names carry their units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WeatherRecord {
    /// Time of the record (local time with its UTC offset).
    pub time: DateTime<FixedOffset>,
    /// Dry-bulb air temperature, K.
    pub air_temperature_k: f64,
    /// Dew-point temperature, K.
    pub dew_point_k: f64,
    /// Relative humidity, fraction 0–1.
    pub relative_humidity: f64,
    /// Station pressure, Pa.
    pub pressure_pa: f64,
    /// Wind speed, m/s.
    pub wind_speed_m_s: f64,
    /// Wind direction, degrees clockwise from north (where the wind comes from).
    pub wind_direction_deg: f64,
    /// Direct-normal solar irradiance, W/m².
    pub direct_normal_w_m2: f64,
    /// Diffuse-horizontal solar irradiance, W/m².
    pub diffuse_horizontal_w_m2: f64,
    /// Global-horizontal solar irradiance, W/m².
    pub global_horizontal_w_m2: f64,
    /// Downwelling sky longwave irradiance on a horizontal surface, W/m².
    pub sky_longwave_w_m2: f64,
    /// Total sky cover, fraction 0–1.
    pub total_sky_cover: f64,
    /// Opaque sky cover, fraction 0–1.
    pub opaque_sky_cover: f64,
    /// Liquid precipitation since the previous record, mm (0 where the file
    /// gives none; EPW field 34, irsig CSV/JSON `precipitation_mm`,
    /// flux-tower rain). It wets surfaces (`irsig::thermal::surface`).
    #[serde(default)]
    pub precipitation_mm: f64,
    /// Horizontal visibility (meteorological range) at the ground, km;
    /// `None` where the file gives none (EPW field 25, `9999` = missing;
    /// TMY3 `Hvis (m)`; irsig CSV/JSON `visibility_km`). It sets the
    /// built-in atmosphere's aerosol (`irsig::atmosphere::aerosol`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub visibility_km: Option<f64>,
}

/// The weather file formats irsig reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Format {
    /// irsig CSV (header [`CSV_HEADER`], RFC 3339 times).
    IrsigCsv,
    /// irsig JSON (`{"site": …, "records": […]}`).
    IrsigJson,
    /// EnergyPlus weather (EPW).
    Epw,
    /// NSRDB TMY3 CSV.
    Tmy3,
    /// DIRSIG/THERM `.wth` (fixed width, no date).
    DirsigWth,
}

/// How a file's values relate to their time stamps (each format declares it; irsig CSV
/// and JSON files may say so, see [`crate::weather`]'s `timing` setting).
///
/// A history holds every record at the instant its values represent: values that are
/// means over an interval are placed at the interval's middle, so the thermal model,
/// the direct/diffuse split and the renderer all take the Sun of that same instant
/// (the mid-interval Sun) with the interval's mean irradiance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Timing {
    /// Every value is a reading at its stamp (irsig CSV/JSON by default, DIRSIG `.wth`).
    Instant,
    /// Every value is the mean over the `interval_s` seconds ending at the stamp (irsig
    /// CSV/JSON with `timing: interval-mean N min`). Records are placed `interval_s / 2`
    /// before their stamps.
    MeanEnding {
        /// The interval, s.
        interval_s: u32,
    },
    /// Solar and sky longwave irradiance are means (Wh/m² totals) over the `interval_s`
    /// seconds ending at the stamp; air temperature, humidity, pressure, wind and sky
    /// cover are readings at the stamp (EPW data dictionary; TMY3 manual §4). Records are
    /// placed at mid-interval, the readings interpolated linearly there from the stamps
    /// around it (the first record keeps its own).
    SolarMeanEnding {
        /// The interval, s.
        interval_s: u32,
    },
}

impl Timing {
    /// Offset from a stamp to the instant its record is placed at (zero or −interval/2).
    pub fn placement(self) -> TimeDelta {
        match self {
            Timing::Instant => TimeDelta::zero(),
            Timing::MeanEnding { interval_s } | Timing::SolarMeanEnding { interval_s } => {
                -TimeDelta::milliseconds(i64::from(interval_s) * 500)
            }
        }
    }
}

impl std::str::FromStr for Timing {
    type Err = String;
    /// `instant`, or `interval-mean N min` (also `N h`, `N s`): the mean over the
    /// interval ending at the stamp.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let t = s.trim();
        if t == "instant" {
            return Ok(Timing::Instant);
        }
        let expected = "expected `instant` or `interval-mean N min` (the mean over the N minutes ending at the stamp; also `N h`, `N s`)";
        let Some(rest) = t.strip_prefix("interval-mean") else {
            return Err(format!("timing `{t}`: {expected}"));
        };
        let rest = rest.trim();
        let (num, unit) = rest
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .map_or((rest, ""), |k| (&rest[..k], rest[k..].trim()));
        let n: f64 = num
            .parse()
            .map_err(|_| format!("timing `{t}`: {expected}"))?;
        let scale = match unit {
            "s" => 1.0,
            "min" | "m" => 60.0,
            "h" => 3600.0,
            _ => return Err(format!("timing `{t}`: unit `{unit}`; {expected}")),
        };
        let secs = n * scale;
        if !(1.0..=86_400.0).contains(&secs) || secs.fract() != 0.0 {
            return Err(format!(
                "timing `{t}`: the interval must be a whole number of seconds from 1 s to 24 h"
            ));
        }
        Ok(Timing::MeanEnding {
            interval_s: secs as u32,
        })
    }
}

/// Options for formats that lack information the scene provides.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LoadOptions {
    /// Local date and time of the first row (hour 0) of a DIRSIG `.wth` file, which
    /// carries none. Required for `.wth`, ignored otherwise.
    pub start: Option<DateTime<FixedOffset>>,
    /// The site, for files that carry none (`.wth`, irsig CSV/JSON without one). Needed
    /// where an irradiance split must be computed. A file's own site takes precedence.
    pub site: Option<Site>,
    /// Replace the year of every EPW/TMY3 row, whether or not the file is a typical year.
    pub year: Option<i32>,
    /// The year given to an EPW/TMY3 typical-year file (months from different years;
    /// see `calendar`) when [`LoadOptions::year`] is not set: a scene gives its image
    /// time's year. Files whose rows are in time order keep their own years.
    pub typical_year: Option<i32>,
}

impl LoadOptions {
    /// Options giving the start time of a `.wth` file.
    pub fn with_start(mut self, start: DateTime<FixedOffset>) -> Self {
        self.start = Some(start);
        self
    }
    /// Options giving the site.
    pub fn with_site(mut self, site: Site) -> Self {
        self.site = Some(site);
        self
    }
    /// Options replacing the year of EPW/TMY3 rows.
    pub fn with_year(mut self, year: i32) -> Self {
        self.year = Some(year);
        self
    }
    /// Options giving the year of a typical-year EPW/TMY3 file.
    pub fn with_typical_year(mut self, year: i32) -> Self {
        self.typical_year = Some(year);
        self
    }
}

/// A weather history: records in strictly increasing time, SI units, linearly
/// interpolated in time by [`WeatherHistory::at`].
#[derive(Debug, Clone, PartialEq)]
pub struct WeatherHistory {
    records: Vec<WeatherRecord>,
    site: Option<Site>,
    filled: Vec<Vec<&'static str>>,
    format: Option<Format>,
    timing: Timing,
}

impl WeatherHistory {
    /// A history from complete records (at least two, strictly increasing in time, every
    /// value finite and in range).
    ///
    /// # Errors
    /// [`Error::Invalid`] naming `records[i].<field>` for a bad value or order.
    pub fn new(records: Vec<WeatherRecord>, site: Option<Site>) -> Result<WeatherHistory> {
        if let Some(s) = &site {
            s.validate()?;
        }
        for (i, r) in records.iter().enumerate() {
            fill::check_record(r)
                .map_err(|(field, msg)| Error::invalid(format!("records[{i}].{field}"), msg))?;
        }
        check_times(records.iter().map(|r| r.time), |i| {
            Location::field(format!("records[{i}].time"))
        })?;
        let n = records.len();
        Ok(WeatherHistory {
            records,
            site,
            filled: vec![Vec::new(); n],
            format: None,
            timing: Timing::Instant,
        })
    }

    pub(crate) fn from_parts(
        records: Vec<WeatherRecord>,
        site: Option<Site>,
        filled: Vec<Vec<&'static str>>,
        format: Format,
        timing: Timing,
    ) -> WeatherHistory {
        WeatherHistory {
            records,
            site,
            filled,
            format: Some(format),
            timing,
        }
    }

    /// How the file's values relate to its stamps ([`Timing::Instant`] when built in
    /// memory). The records are already placed at the instants they represent.
    pub fn timing(&self) -> Timing {
        self.timing
    }

    /// The records, in increasing time.
    pub fn records(&self) -> &[WeatherRecord] {
        &self.records
    }

    /// The site the file declared (EPW, TMY3, irsig) or the one given in [`LoadOptions`].
    pub fn site(&self) -> Option<&Site> {
        self.site.as_ref()
    }

    /// The format the history was read from (`None` when built in memory).
    pub fn format(&self) -> Option<Format> {
        self.format
    }

    /// Names of the fields of record `i` that were filled rather than read
    /// (e.g. `["sky_longwave_w_m2"]`). Empty for out-of-range `i`.
    pub fn filled(&self, i: usize) -> &[&'static str] {
        self.filled.get(i).map_or(&[], Vec::as_slice)
    }

    /// The Sun at `t` for the history's site (standard atmosphere, estimated ΔT; see
    /// [`crate::sun::position_standard`]).
    ///
    /// # Errors
    /// [`Error::Invalid`] when the history has no site, or as the solar position.
    pub fn sun_position<Tz: TimeZone>(&self, t: DateTime<Tz>) -> Result<crate::sun::SunPosition> {
        let site = self.site.as_ref().ok_or_else(|| {
            Error::invalid(
                "site",
                "the weather history has no site; give one with LoadOptions::site",
            )
        })?;
        crate::sun::position_standard(site, t)
    }

    /// Time of the first record.
    pub fn start(&self) -> DateTime<FixedOffset> {
        self.records[0].time
    }

    /// Time of the last record.
    pub fn end(&self) -> DateTime<FixedOffset> {
        self.records[self.records.len() - 1].time
    }

    /// The smallest interval between consecutive records (the step of a uniform history).
    pub fn step(&self) -> TimeDelta {
        self.records
            .windows(2)
            .map(|w| w[1].time - w[0].time)
            .min()
            .unwrap_or_default()
    }

    /// Whether all consecutive records are the same interval apart.
    pub fn is_uniform(&self) -> bool {
        let s = self.step();
        self.records.windows(2).all(|w| w[1].time - w[0].time == s)
    }

    /// The weather at `t`, linearly interpolated between the two records around it
    /// (wind direction along the shorter arc). The returned record's `time` is `t` in the
    /// history's UTC offset.
    ///
    /// # Errors
    /// [`Error::Invalid`] (field `time`) naming `t` and the history's span when `t` is
    /// outside it.
    pub fn at<Tz: TimeZone>(&self, t: DateTime<Tz>) -> Result<WeatherRecord> {
        let offset = *self.records[0].time.offset();
        let t = t.with_timezone(&offset);
        let (start, end) = (self.start(), self.end());
        if t < start || t > end {
            return Err(Error::invalid(
                "time",
                format!(
                    "{} is outside the weather history, which covers {} to {}",
                    t.to_rfc3339(),
                    start.to_rfc3339(),
                    end.to_rfc3339()
                ),
            ));
        }
        let j = self.records.partition_point(|r| r.time <= t);
        // j ≥ 1 since records[0].time ≤ t.
        if j >= self.records.len() {
            let mut r = self.records[self.records.len() - 1];
            r.time = t;
            return Ok(r);
        }
        let (a, b) = (&self.records[j - 1], &self.records[j]);
        let span = (b.time - a.time).num_microseconds().unwrap_or(i64::MAX) as f64;
        let w = (t - a.time).num_microseconds().unwrap_or(0) as f64 / span;
        Ok(interpolate(a, b, w, t))
    }
}

fn interpolate(
    a: &WeatherRecord,
    b: &WeatherRecord,
    w: f64,
    t: DateTime<FixedOffset>,
) -> WeatherRecord {
    let mut d = b.wind_direction_deg - a.wind_direction_deg;
    if d > 180.0 {
        d -= 360.0;
    } else if d < -180.0 {
        d += 360.0;
    }
    WeatherRecord {
        time: t,
        air_temperature_k: lerp(a.air_temperature_k, b.air_temperature_k, w),
        dew_point_k: lerp(a.dew_point_k, b.dew_point_k, w),
        relative_humidity: lerp(a.relative_humidity, b.relative_humidity, w),
        pressure_pa: lerp(a.pressure_pa, b.pressure_pa, w),
        wind_speed_m_s: lerp(a.wind_speed_m_s, b.wind_speed_m_s, w),
        wind_direction_deg: (a.wind_direction_deg + d * w).rem_euclid(360.0),
        direct_normal_w_m2: lerp(a.direct_normal_w_m2, b.direct_normal_w_m2, w),
        diffuse_horizontal_w_m2: lerp(a.diffuse_horizontal_w_m2, b.diffuse_horizontal_w_m2, w),
        global_horizontal_w_m2: lerp(a.global_horizontal_w_m2, b.global_horizontal_w_m2, w),
        sky_longwave_w_m2: lerp(a.sky_longwave_w_m2, b.sky_longwave_w_m2, w),
        total_sky_cover: lerp(a.total_sky_cover, b.total_sky_cover, w),
        opaque_sky_cover: lerp(a.opaque_sky_cover, b.opaque_sky_cover, w),
        // An amount over the interval ending at `b`: the part of it up to `t`.
        precipitation_mm: w * b.precipitation_mm,
        visibility_km: lerp_visibility_km(a.visibility_km, b.visibility_km, w),
    }
}

/// Visibility at weight `w` (0 at `a`, 1 at `b`) between two readings:
/// where both are given, linear in the extinction coefficient, which is
/// 3.912/V (Koschmieder), as LOWTRAN 7 interpolates its boundary-layer
/// aerosol in 1/V; where one is missing, the nearer reading (`b` at
/// `w = ½`), which may itself be missing. A visibility of 0 (fog) is an
/// infinite extinction: 0 wherever it weighs.
pub(crate) fn lerp_visibility_km(a: Option<f64>, b: Option<f64>, w: f64) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if w > 0.0 && w < 1.0 => Some(1.0 / ((1.0 - w) / a + w / b)),
        _ if w < 0.5 => a,
        _ => b,
    }
}

/// Times must be at least two and strictly increasing.
pub(crate) fn check_times(
    times: impl Iterator<Item = DateTime<FixedOffset>>,
    loc: impl Fn(usize) -> Location,
) -> Result<()> {
    let mut prev: Option<DateTime<FixedOffset>> = None;
    let mut n = 0;
    for (i, t) in times.enumerate() {
        if let Some(p) = prev {
            if t <= p {
                return Err(Error::parse(
                    loc(i),
                    format!(
                        "time {} is not after the previous record's {}; records must be in strictly increasing time",
                        t.to_rfc3339(),
                        p.to_rfc3339()
                    ),
                ));
            }
        }
        prev = Some(t);
        n += 1;
    }
    if n < 2 {
        return Err(Error::parse(
            loc(n),
            format!("a weather history needs at least 2 records, found {n}"),
        ));
    }
    Ok(())
}

/// Read a weather file, picking the reader by extension and content. Formats that need
/// outside information (a `.wth` file's date) need [`load_with`].
///
/// # Errors
/// I/O errors, and parse/validation errors naming the file, line and column.
pub fn load(path: &Path) -> Result<WeatherHistory> {
    load_with(path, &LoadOptions::default())
}

/// Read a weather file with options (see [`LoadOptions`]).
///
/// # Errors
/// As [`load`]; for `.wth` without `options.start`, an error saying the scene must give it.
pub fn load_with(path: &Path, options: &LoadOptions) -> Result<WeatherHistory> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let text = decode(bytes, path)?;
    let format = detect_format(path, &text)?;
    load_str(&text, path, format, options)
}

/// Lines at the top of a file that may hold free text (station names, comments): EPW's
/// eight header lines, TMY3's two.
const FREE_TEXT_HEADER_LINES: usize = 8;

/// The file's text: UTF-8, or, where the only bytes that are not UTF-8 lie in the
/// free-text header lines (EPW LOCATION…COMMENTS 2, a TMY3 station name), those lines
/// read as Latin-1 (ISO 8859-1: each byte is the code point of the same value), which is
/// how such files are written on Windows (`Montréal` as byte 0xE9).
///
/// # Errors
/// [`Error::Parse`] naming the line and column of the first byte that is not UTF-8 in a
/// data line.
fn decode(bytes: Vec<u8>, path: &Path) -> Result<String> {
    let bytes = match String::from_utf8(bytes) {
        Ok(s) => return Ok(s),
        Err(e) => e.into_bytes(),
    };
    // Only files that announce themselves as EPW (`LOCATION,`) or TMY3 (the date column
    // on line 2) have free-text header lines; other bytes are not guessed at.
    let header_text = bytes.starts_with(b"LOCATION,")
        || bytes
            .split(|&b| b == b'\n')
            .nth(1)
            .is_some_and(|l| l.starts_with(b"Date (MM/DD/YYYY)"));
    let mut out = String::with_capacity(bytes.len());
    for (i, line) in bytes.split_inclusive(|&b| b == b'\n').enumerate() {
        match std::str::from_utf8(line) {
            Ok(s) => out.push_str(s),
            Err(_) if header_text && i < FREE_TEXT_HEADER_LINES => {
                out.extend(line.iter().map(|&b| char::from(b)))
            }
            Err(e) => {
                let col = e.valid_up_to();
                return Err(Error::parse(
                    Location::file(path).at_line(i + 1),
                    format!(
                        "byte 0x{:02X} at column {} is not UTF-8 text (Latin-1 is accepted only \
                         in the header lines of EPW and TMY3 files); save the file as UTF-8",
                        line[col],
                        col + 1
                    ),
                ));
            }
        }
    }
    Ok(out)
}

/// Parse weather text already in memory; `path` is used in messages only.
///
/// # Errors
/// As [`load`].
pub fn load_str(
    text: &str,
    path: &Path,
    format: Format,
    options: &LoadOptions,
) -> Result<WeatherHistory> {
    if let Some(s) = &options.site {
        s.validate()?;
    }
    let parsed = match format {
        Format::IrsigCsv => irsig::read_csv(text, path)?,
        Format::IrsigJson => irsig::read_json(text, path)?,
        Format::Epw => epw::read(text, path, options)?,
        Format::Tmy3 => tmy3::read(text, path, options)?,
        Format::DirsigWth => wth::read(text, path, options)?,
    };
    fill::complete(parsed, path, options.site, format)
}

/// Decide a file's format from its extension, then its content.
///
/// # Errors
/// [`Error::Parse`] when the format cannot be recognised.
pub fn detect_format(path: &Path, text: &str) -> Result<Format> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let first = lines.next().unwrap_or("").trim_start_matches('\u{feff}');
    let second = lines.next().unwrap_or("");
    let tmy3_like = second.starts_with("Date (MM/DD/YYYY)");
    // A DIRSIG atmosphere file names a weather file but is not one.
    if ext.as_deref() == Some("atm") || first.trim_start().starts_with("<atmosphericconditions") {
        return Err(Error::parse(
            Location::file(path).at_line(1),
            "this is a DIRSIG atmosphere file (`.atm`), not weather: give the `.wth` file it \
             names (`<classicdata><filename>`), or import the DIRSIG scene with \
             `irsig import dirsig`",
        ));
    }
    match ext.as_deref() {
        Some("epw") => return Ok(Format::Epw),
        Some("wth") => return Ok(Format::DirsigWth),
        Some("json") => return Ok(Format::IrsigJson),
        Some("csv") if tmy3_like => return Ok(Format::Tmy3),
        Some("csv") => return Ok(Format::IrsigCsv),
        _ => {}
    }
    if first.starts_with("LOCATION,") {
        Ok(Format::Epw)
    } else if tmy3_like {
        Ok(Format::Tmy3)
    } else if first.trim_start().starts_with('{') {
        Ok(Format::IrsigJson)
    } else if first.starts_with('#') || first.starts_with("time,") || first == "time" {
        Ok(Format::IrsigCsv)
    } else if first.split_whitespace().count() == 2
        && first.split_whitespace().all(|w| w.parse::<f64>().is_ok())
    {
        Ok(Format::DirsigWth)
    } else {
        Err(Error::parse(
            Location::file(path).at_line(1),
            "unrecognised weather format: expected irsig CSV (header starting `time,`), irsig JSON, \
             EPW (`LOCATION,…`), TMY3 CSV or DIRSIG .wth (`193 0.25`)",
        ))
    }
}
