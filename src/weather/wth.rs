//! DIRSIG/THERM `.wth` weather history (fixed width, no date, no site).
//!
//! Layout (DIRSIG documentation "Weather History File", and the real file
//! `saw.wth` from KevinKearney/protoDIRSIG): a header line `N STEP` (N rows, STEP
//! hours apart; DIRSIG requires 193 rows at 0.25 h = 48 h inclusive), then N rows of
//! right-aligned fixed-width columns that may run together (`0.31-20.00`). The first
//! column, the hour since the start, takes whatever is left of the line; the others
//! have these widths, read from the right:
//!
//! | # | width | field | unit → SI |
//! |---|---|---|---|
//! | 1 | rest | hour since start | h |
//! | 2 | 6 | air temperature | °C → K |
//! | 3 | 8 | pressure | mbar → Pa (×100) |
//! | 4 | 6 | relative humidity | fraction |
//! | 5 | 6 | dew point | °C → K |
//! | 6 | 7 | wind speed | m/s (assumed) |
//! | 7 | 9 | direct (normal) insolation | Langley/h → W/m² (× 41 840/3600) |
//! | 8 | 9 | diffuse (horizontal) insolation | Langley/h → W/m² |
//! | 9 | 5 | (undocumented; 1.00 in saw.wth) | not used |
//! | 10 | 3 | cloud cover, tenths (inferred: integer, 0 on a clear day) | → fraction, total and opaque |
//! | 11 | 3 | (cloud type, inferred) | not used |
//! | 12 | 7 | (precipitation, inferred) | not used |
//! | 13 | 6 | (precipitation, inferred) | not used |
//!
//! 1 Langley = 1 cal_th/cm² = 41 840 J/m², so 1 L/h = 11.622 W/m² (1 W/m² = 0.086 L/h).
//! Times are local: hour h of the file is `LoadOptions::start + h`. Global horizontal
//! irradiance is filled from the closure GHI = DHI + DNI cos z, which needs the site;
//! sky longwave by Clark & Allen.

use std::path::Path;

use chrono::TimeDelta;

use super::fill::{Parsed, RawRecord};
use super::text::number;
use super::{LoadOptions, Timing};
use crate::error::{Error, Location, Result};

/// W/m² per Langley/hour.
pub const W_M2_PER_LANGLEY_PER_HOUR: f64 = 41_840.0 / 3600.0;

/// Widths of columns 2..13, left to right.
const WIDTHS: [usize; 12] = [6, 8, 6, 6, 7, 9, 9, 5, 3, 3, 7, 6];
const NAMES: [&str; 12] = [
    "air temperature (°C, column 2)",
    "pressure (mbar, column 3)",
    "relative humidity (fraction, column 4)",
    "dew point (°C, column 5)",
    "wind speed (m/s, column 6)",
    "direct insolation (Langley/h, column 7)",
    "diffuse insolation (Langley/h, column 8)",
    "column 9",
    "cloud cover (tenths, column 10)",
    "column 11",
    "column 12",
    "column 13",
];

pub(crate) fn read(text: &str, path: &Path, options: &LoadOptions) -> Result<Parsed> {
    let start = options.start.ok_or_else(|| {
        Error::parse(
            Location::file(path),
            "a DIRSIG .wth file carries no date: the start (local date and time of hour 0) \
             must be given (scene weather start, or --start RFC3339)",
        )
    })?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (hi, header) = lines.next().ok_or_else(|| {
        Error::parse(Location::file(path), "empty file; expected `N STEP` header")
    })?;
    let hloc = Location::file(path).at_line(hi + 1);
    let parts: Vec<&str> = header.split_whitespace().collect();
    if parts.len() != 2 {
        return Err(Error::parse(
            hloc,
            format!(
                "header `{}`: expected `N STEP` (e.g. `193 0.25`)",
                header.trim()
            ),
        ));
    }
    let n = number(parts[0], &hloc, "row count N")?;
    let step = number(parts[1], &hloc, "time step (hours)")?;
    if n < 2.0 || n.fract() != 0.0 || step <= 0.0 {
        return Err(Error::parse(
            hloc,
            format!(
                "header `{}`: expected an integer N ≥ 2 and a positive step in hours",
                header.trim()
            ),
        ));
    }
    let n = n as usize;
    // Not `with_capacity(n)`: N comes from the file, and a corrupt header
    // (`9999999193 0.25`) must be a row-count error, not an allocation abort.
    let mut records = Vec::new();
    for (i, line) in lines {
        let loc = Location::file(path).at_line(i + 1);
        let line = line.trim_end();
        let fixed: usize = WIDTHS.iter().sum();
        if !line.is_ascii() || line.len() <= fixed {
            return Err(Error::parse(
                loc,
                format!(
                    "expected 13 fixed-width columns (hour, then widths {WIDTHS:?} = {fixed} characters), found {} characters",
                    line.len()
                ),
            ));
        }
        let split = line.len() - fixed;
        let hour = number(
            &line[..split],
            &loc.clone().with_field("hour"),
            "hour (column 1)",
        )?;
        let mut v = [0.0; 12];
        let mut pos = split;
        for (k, w) in WIDTHS.iter().enumerate() {
            let cell = &line[pos..pos + w];
            v[k] = number(
                cell,
                &loc.clone().with_field(format!("column {}", k + 2)),
                NAMES[k],
            )?;
            pos += w;
        }
        let row = records.len();
        let expected = row as f64 * step;
        if (hour - expected).abs() > 0.006 {
            return Err(Error::parse(
                loc.with_field("hour"),
                format!(
                    "hour {hour} at row {}: expected {expected} (row × step {step} h)",
                    row + 1
                ),
            ));
        }
        let cover = v[8];
        if !(0.0..=10.0).contains(&cover) {
            return Err(Error::parse(
                loc.with_field("column 10"),
                format!("cloud cover {cover} tenths is out of range; expected 0..10"),
            ));
        }
        let time = start + TimeDelta::milliseconds((hour * 3_600_000.0).round() as i64);
        let mut r = RawRecord::new(loc, time);
        r.air_temperature_k = Some(v[0] + 273.15);
        r.pressure_pa = Some(v[1] * 100.0);
        r.relative_humidity = Some(v[2]);
        r.dew_point_k = Some(v[3] + 273.15);
        r.wind_speed_m_s = Some(v[4]);
        r.direct_normal_w_m2 = Some(v[5] * W_M2_PER_LANGLEY_PER_HOUR);
        r.diffuse_horizontal_w_m2 = Some(v[6] * W_M2_PER_LANGLEY_PER_HOUR);
        r.total_sky_cover = Some(cover / 10.0);
        r.opaque_sky_cover = Some(cover / 10.0);
        records.push(r);
    }
    if records.len() != n {
        return Err(Error::parse(
            hloc,
            format!(
                "the header promises {n} rows, the file has {}",
                records.len()
            ),
        ));
    }
    Ok(Parsed {
        records,
        site: None,
        timing: Timing::Instant,
    })
}
