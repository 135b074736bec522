//! Small CSV tables of the analysis commands: truth point measurements,
//! geometric control points and surface-temperature time series.
//!
//! The dialect: comma-separated, one header row naming the columns
//! (case-insensitive, surrounding spaces ignored), blank lines and lines
//! starting with `#` skipped, RFC 4180 quoting (`"Smith, J."` is one cell;
//! read by `crate::textio`). Every error names the file, the 1-based line
//! and the column.
//!
//! * Truth points — columns `x,y,value` (pixel coordinates: `x` the column,
//!   `y` the row, the top-left pixel covering `[0,1)×[0,1)`) or
//!   `lat,lon,value` (degrees; needs a georeferenced image), an optional
//!   `material` label and an optional `id`. Without `value` the points
//!   only say where to sample a truth image. `value` is in kelvin when the
//!   compared layer is a temperature, in the layer's radiance unit
//!   otherwise; `temperature_k` and `radiance` are accepted as its name.
//! * Control points — columns `synth_x,synth_y,truth_x,truth_y` (pixels) and
//!   an optional `id`.
//! * Time series — columns `time,surface_temperature_k`, `time` in RFC 3339
//!   (`2024-06-21T14:00:00-04:00`).
//!
//! Owns these three file formats. Takes a path; gives typed rows that keep
//! their line numbers, so later checks can still name the line. Must not know
//! images, georeferencing or how points are compared ([`super::compare`],
//! [`super::geo`]).

use std::path::Path;

use chrono::{DateTime, FixedOffset};

use crate::textio::{self, Comments};
use crate::{Error, Location, Result};

/// A parsed CSV table: header names (lower-case) and rows with line numbers.
struct Table {
    header: Vec<String>,
    rows: Vec<(usize, Vec<String>)>,
}

fn read_table(path: &Path) -> Result<Table> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut header: Option<Vec<String>> = None;
    let mut rows = Vec::new();
    for row in textio::rows(&text, Comments::WholeLine) {
        let cells = row.fields;
        match &header {
            None => header = Some(cells.iter().map(|c| c.to_ascii_lowercase()).collect()),
            Some(h) => {
                if cells.len() != h.len() {
                    return Err(Error::parse(
                        Location::file(path).at_line(row.line),
                        format!(
                            "expected {} comma-separated values (columns {}), found {}",
                            h.len(),
                            h.join(","),
                            cells.len()
                        ),
                    ));
                }
                rows.push((row.line, cells));
            }
        }
    }
    let header = header
        .ok_or_else(|| Error::parse(Location::file(path), "empty file: expected a header row"))?;
    if rows.is_empty() {
        return Err(Error::parse(
            Location::file(path),
            "no data rows after the header",
        ));
    }
    Ok(Table { header, rows })
}

impl Table {
    /// Index of the first present column among `names`.
    fn col(&self, names: &[&str]) -> Option<usize> {
        names
            .iter()
            .find_map(|n| self.header.iter().position(|h| h == n))
    }

    fn check_known(&self, path: &Path, known: &[&str], expected: &str) -> Result<()> {
        for h in &self.header {
            if !known.contains(&h.as_str()) {
                return Err(Error::parse(
                    Location::file(path).at_line(1).with_field(h.clone()),
                    format!(
                        "unknown column{}; expected {expected}",
                        crate::suggest::hint(h, known.iter().copied())
                    ),
                ));
            }
        }
        Ok(())
    }
}

fn number(path: &Path, line: usize, field: &str, cell: &str) -> Result<f64> {
    cell.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| {
            Error::parse(
                Location::file(path).at_line(line).with_field(field),
                format!("expected a finite number, found `{cell}`"),
            )
        })
}

/// Where a truth point lies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PointPosition {
    /// Pixel coordinates (x = column, y = row; pixel (i, j) covers [i,i+1)×[j,j+1)).
    Pixel {
        /// Column coordinate, pixels.
        x: f64,
        /// Row coordinate, pixels.
        y: f64,
    },
    /// Geographic coordinates, degrees.
    LatLon {
        /// Latitude, degrees north.
        lat: f64,
        /// Longitude, degrees east.
        lon: f64,
    },
}

/// One truth measurement.
#[derive(Debug, Clone, PartialEq)]
pub struct TruthPoint {
    /// Identifier (the `id` column, or the line number).
    pub id: String,
    /// Position.
    pub position: PointPosition,
    /// Measured value (K or radiance); `None` when the file has no value
    /// column (the points only say where to sample a truth image).
    pub value: Option<f64>,
    /// Material label, if given.
    pub material: Option<String>,
    /// 1-based line in the file.
    pub line: usize,
}

const TRUTH_COLUMNS: &str = "`x,y,value` or `lat,lon,value`, optionally `material` and `id` (value may be named `temperature_k` or `radiance`)";

/// Read a truth-point CSV (see the module docs for the columns).
pub fn read_truth_points(path: impl AsRef<Path>) -> Result<Vec<TruthPoint>> {
    let path = path.as_ref();
    let t = read_table(path)?;
    t.check_known(
        path,
        &[
            "x",
            "y",
            "lat",
            "lon",
            "value",
            "temperature_k",
            "radiance",
            "material",
            "id",
        ],
        TRUTH_COLUMNS,
    )?;
    let value = t.col(&["value", "temperature_k", "radiance"]);
    let xy = (t.col(&["x"]), t.col(&["y"]));
    let ll = (t.col(&["lat"]), t.col(&["lon"]));
    let pixel = match (xy, ll) {
        ((Some(x), Some(y)), (None, None)) => Some((x, y)),
        ((None, None), (Some(_), Some(_))) => None,
        _ => {
            return Err(Error::parse(
                Location::file(path).at_line(1),
                format!("give either x,y or lat,lon columns (one pair): expected {TRUTH_COLUMNS}"),
            ));
        }
    };
    let mat = t.col(&["material"]);
    let id = t.col(&["id"]);
    let mut out = Vec::with_capacity(t.rows.len());
    for (line, r) in &t.rows {
        let position = match pixel {
            Some((x, y)) => PointPosition::Pixel {
                x: number(path, *line, "x", &r[x])?,
                y: number(path, *line, "y", &r[y])?,
            },
            None => {
                let lat = number(path, *line, "lat", &r[ll.0.unwrap_or(0)])?;
                let lon = number(path, *line, "lon", &r[ll.1.unwrap_or(0)])?;
                if !(-90.0..=90.0).contains(&lat) || !(-180.0..=360.0).contains(&lon) {
                    return Err(Error::parse(
                        Location::file(path).at_line(*line).with_field("lat"),
                        format!("latitude/longitude out of range: {lat}, {lon}"),
                    ));
                }
                PointPosition::LatLon { lat, lon }
            }
        };
        out.push(TruthPoint {
            id: id
                .map(|i| r[i].clone())
                .unwrap_or_else(|| format!("line{line}")),
            position,
            value: match value {
                Some(v) => Some(number(path, *line, &t.header[v], &r[v])?),
                None => None,
            },
            material: mat.map(|m| r[m].clone()).filter(|m| !m.is_empty()),
            line: *line,
        });
    }
    Ok(out)
}

/// One control point: the same ground feature located in both images.
#[derive(Debug, Clone, PartialEq)]
pub struct ControlPoint {
    /// Identifier (the `id` column, or the line number).
    pub id: String,
    /// Position in the synthetic image, pixels (x = column, y = row).
    pub synth: [f64; 2],
    /// Position in the truth image, pixels.
    pub truth: [f64; 2],
}

/// Read a control-point CSV `synth_x,synth_y,truth_x,truth_y[,id]`.
pub fn read_control_points(path: impl AsRef<Path>) -> Result<Vec<ControlPoint>> {
    let path = path.as_ref();
    let t = read_table(path)?;
    let expected = "`synth_x,synth_y,truth_x,truth_y`, optionally `id`";
    t.check_known(
        path,
        &["synth_x", "synth_y", "truth_x", "truth_y", "id"],
        expected,
    )?;
    let mut cols = [0usize; 4];
    for (k, n) in ["synth_x", "synth_y", "truth_x", "truth_y"]
        .iter()
        .enumerate()
    {
        cols[k] = t.col(&[n]).ok_or_else(|| {
            Error::parse(
                Location::file(path).at_line(1),
                format!("missing column `{n}`: expected {expected}"),
            )
        })?;
    }
    let id = t.col(&["id"]);
    t.rows
        .iter()
        .map(|(line, r)| {
            let v = |k: usize, n: &str| number(path, *line, n, &r[cols[k]]);
            Ok(ControlPoint {
                id: id
                    .map(|i| r[i].clone())
                    .unwrap_or_else(|| format!("line{line}")),
                synth: [v(0, "synth_x")?, v(1, "synth_y")?],
                truth: [v(2, "truth_x")?, v(3, "truth_y")?],
            })
        })
        .collect()
}

/// Read a surface-temperature series `time,surface_temperature_k`.
pub fn read_temperature_series(
    path: impl AsRef<Path>,
) -> Result<Vec<(DateTime<FixedOffset>, f64)>> {
    let path = path.as_ref();
    let t = read_table(path)?;
    let expected = "`time,surface_temperature_k` (RFC 3339 time, kelvin)";
    t.check_known(path, &["time", "surface_temperature_k"], expected)?;
    let (Some(tc), Some(vc)) = (t.col(&["time"]), t.col(&["surface_temperature_k"])) else {
        return Err(Error::parse(
            Location::file(path).at_line(1),
            format!("expected columns {expected}"),
        ));
    };
    let mut out: Vec<(DateTime<FixedOffset>, f64)> = Vec::with_capacity(t.rows.len());
    for (line, r) in &t.rows {
        let time = crate::sun::parse_time(&r[tc]).map_err(|e| {
            Error::parse(
                Location::file(path).at_line(*line).with_field("time"),
                e.to_string(),
            )
        })?;
        let v = number(path, *line, "surface_temperature_k", &r[vc])?;
        if v <= 0.0 {
            return Err(Error::parse(
                Location::file(path)
                    .at_line(*line)
                    .with_field("surface_temperature_k"),
                format!("expected a temperature in kelvin (> 0), found {v}"),
            ));
        }
        if let Some((prev, _)) = out.last() {
            if time <= *prev {
                return Err(Error::parse(
                    Location::file(path).at_line(*line).with_field("time"),
                    "times must increase down the file",
                ));
            }
        }
        out.push((time, v));
    }
    Ok(out)
}
