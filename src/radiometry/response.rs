//! Sensor relative spectral response: the type and its CSV reader.
//!
//! File format: one `wavelength_um, response` pair per line. Separators may
//! be commas, semicolons, tabs or spaces; a header line (any first data line
//! whose first field is not a number) is optional; `#` starts a comment;
//! blank lines are ignored. Wavelengths in µm, strictly increasing; responses
//! finite, not all zero, and ≥ 0 — except that small negative values, down to
//! −1 % of the curve's peak (measurement noise in published curves: the
//! Landsat-8 TIRS band 10 file has −0.00001), are set to zero with a warning
//! ([`SpectralResponse::warnings`]); below that they are an error. Any further columns are an error (they would
//! be silently misread otherwise). Between points the response is linear;
//! outside the first/last point it is zero.
//!
//! Owns [`SpectralResponse`] and its file format (fields split by the crate's
//! one CSV reader, quoted cells allowed). Takes a path or text; gives a
//! validated curve evaluated by [`SpectralResponse::at`]. Must not know
//! spectral grids or band integration ([`super::band`]) or sensors.

use std::path::Path;

use crate::math::interp1d;
use crate::textio::{self, Comments};
use crate::{Error, Location, Result};

/// A relative spectral response curve (dimensionless, any scale).
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralResponse {
    wavelengths_um: Vec<f64>,
    response: Vec<f64>,
    warnings: Vec<String>,
}

/// Negative responses down to this fraction of the peak are noise, set to zero.
pub const NEGATIVE_RESPONSE_TOLERANCE: f64 = 0.01;

impl SpectralResponse {
    /// A response from pairs; validates as the CSV reader does.
    pub fn new(wavelengths_um: Vec<f64>, response: Vec<f64>) -> Result<Self> {
        if wavelengths_um.len() != response.len() {
            return Err(Error::invalid(
                "response",
                "wavelength and response lists differ in length",
            ));
        }
        if wavelengths_um.len() < 2 {
            return Err(Error::invalid(
                "response",
                "a spectral response needs at least two points",
            ));
        }
        for i in 0..wavelengths_um.len() {
            let (l, r) = (wavelengths_um[i], response[i]);
            if !(l.is_finite() && l > 0.0) || (i > 0 && l <= wavelengths_um[i - 1]) {
                return Err(Error::invalid(
                    format!("wavelength_um[{i}]"),
                    format!("expected positive, strictly increasing wavelengths, got {l}"),
                ));
            }
            if !(r.is_finite() && r >= 0.0) {
                return Err(Error::invalid(
                    format!("response[{i}]"),
                    format!("expected a finite response ≥ 0, got {r}"),
                ));
            }
        }
        if response.iter().all(|&r| r == 0.0) {
            return Err(Error::invalid(
                "response",
                "the response is zero everywhere",
            ));
        }
        Ok(SpectralResponse {
            wavelengths_um,
            response,
            warnings: Vec::new(),
        })
    }

    /// What reading the file changed (small negative values set to zero), each naming
    /// the file and line; empty for a curve built in memory.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The wavelengths, µm.
    pub fn wavelengths_um(&self) -> &[f64] {
        &self.wavelengths_um
    }
    /// The response values as given.
    pub fn response(&self) -> &[f64] {
        &self.response
    }
    /// Response at `wavelength_um`: linear between points, 0 outside.
    pub fn at(&self, wavelength_um: f64) -> f64 {
        let w = &self.wavelengths_um;
        if wavelength_um < w[0] || wavelength_um > w[w.len() - 1] {
            return 0.0;
        }
        interp1d(w, &self.response, wavelength_um)
    }
}

/// Read a response CSV file (see the module docs for the format).
pub fn read_response_csv(path: impl AsRef<Path>) -> Result<SpectralResponse> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_response_csv(&text, path)
}

/// Parse response CSV text; `path` is used in error messages only.
pub fn parse_response_csv(text: &str, path: impl AsRef<Path>) -> Result<SpectralResponse> {
    let path = path.as_ref();
    let mut wl = Vec::new();
    let mut resp = Vec::new();
    let mut lines = Vec::new();
    let mut seen_data_or_header = false;
    for row in textio::rows(text, Comments::Trailing) {
        let (lineno, line) = (row.line, row.text);
        let loc = || Location::file(path).at_line(lineno);
        let fields = textio::tokens(&row.fields);
        if !seen_data_or_header {
            seen_data_or_header = true;
            if fields.first().is_some_and(|f| f.parse::<f64>().is_err()) {
                continue; // header
            }
        }
        if fields.len() != 2 {
            return Err(Error::parse(
                loc(),
                format!(
                    "expected two fields `wavelength_um, response`, found {}: `{line}`",
                    fields.len()
                ),
            ));
        }
        let l: f64 = fields[0].parse().map_err(|_| {
            Error::parse(
                loc().with_field("wavelength_um"),
                format!("expected a wavelength in µm, found `{}`", fields[0]),
            )
        })?;
        let r: f64 = fields[1].parse().map_err(|_| {
            Error::parse(
                loc().with_field("response"),
                format!("expected a relative response, found `{}`", fields[1]),
            )
        })?;
        if !(l.is_finite() && l > 0.0) {
            return Err(Error::parse(
                loc().with_field("wavelength_um"),
                format!("expected a positive wavelength in µm, found {l}"),
            ));
        }
        let (lo, hi) = super::band::BAND_LIMITS_UM;
        if !(lo..=hi).contains(&l) {
            return Err(Error::parse(
                loc().with_field("wavelength_um"),
                format!("wavelength {l} µm is outside {lo}–{hi} µm (nanometres or cm⁻¹ given?)"),
            ));
        }
        if let Some(&prev) = wl.last() {
            if l <= prev {
                return Err(Error::parse(
                    loc().with_field("wavelength_um"),
                    format!("wavelengths must increase strictly: {l} follows {prev}"),
                ));
            }
        }
        if !r.is_finite() {
            return Err(Error::parse(
                loc().with_field("response"),
                format!("expected a finite response ≥ 0, found {r}"),
            ));
        }
        wl.push(l);
        resp.push(r);
        lines.push(lineno);
    }
    let peak = resp.iter().copied().fold(0.0, f64::max);
    let mut warnings = Vec::new();
    let mut clamped: Vec<usize> = Vec::new();
    for (i, r) in resp.iter_mut().enumerate() {
        if *r >= 0.0 {
            continue;
        }
        if peak > 0.0 && *r >= -NEGATIVE_RESPONSE_TOLERANCE * peak {
            clamped.push(i);
            *r = 0.0;
        } else {
            return Err(Error::parse(
                Location::file(path)
                    .at_line(lines[i])
                    .with_field("response"),
                if peak > 0.0 {
                    format!(
                        "expected a response ≥ 0, found {r}: values down to −{}% of the peak \
                         ({peak}) are taken for noise and set to zero, this one is {:.3}% of it",
                        NEGATIVE_RESPONSE_TOLERANCE * 100.0,
                        *r / peak * 100.0
                    )
                } else {
                    format!("expected a response ≥ 0, found {r} (and no positive value)")
                },
            ));
        }
    }
    if let (Some(&first), Some(&last)) = (clamped.first(), clamped.last()) {
        warnings.push(
            Error::parse(
                Location::file(path)
                    .at_line(lines[first])
                    .with_field("response"),
                format!(
                    "{} small negative response value(s) (within −{}% of the peak {peak}; lines {}..={}) set to zero",
                    clamped.len(),
                    NEGATIVE_RESPONSE_TOLERANCE * 100.0,
                    lines[first],
                    lines[last]
                ),
            )
            .to_string(),
        );
    }
    if wl.len() < 2 {
        return Err(Error::parse(
            Location::file(path),
            format!("expected at least two response points, found {}", wl.len()),
        ));
    }
    if resp.iter().all(|&r| r == 0.0) {
        return Err(Error::parse(
            Location::file(path),
            "the response is zero at every wavelength",
        ));
    }
    let mut curve = SpectralResponse::new(wl, resp)?;
    curve.warnings = warnings;
    Ok(curve)
}
