//! Analysis of synthetic imagery: validation against truth, input
//! sensitivity, calibration of inputs, and best-contrast timing.
//!
//! * [`stats`] — bias, MAE, RMSE, Pearson, Spearman (average ranks for
//!   ties), histograms: the numbers every other part reports.
//! * [`image`] / [`csv`] — readers for truth imagery (TIFF/PNG/EXR/ENVI) and
//!   the CSV tables (truth points, control points, temperature series).
//! * [`compare`] — synthetic vs truth image or points, per material, and
//!   geometric accuracy from control points.
//! * [`plot`] — histograms, tornado plots and curves as PNG (embedded font).
//!
//! Residuals are always `synthetic − truth`.
//!
//! Takes rendered or truth images, tables and scenes (through
//! [`crate::render::session::Session`]); gives reports as plain data. It
//! must not know the command line: it prints nothing and names fields, not
//! flags, in its errors.

pub mod calibrate;
pub mod compare;
pub mod csv;
pub mod diurnal;
pub mod facet;
pub mod geo;
pub mod image;
pub mod params;
pub mod plot;
pub mod registry;
pub mod scene;
pub mod sensitivity;
pub mod stats;
pub mod study;

use std::path::Path;

use crate::Result;

/// Write `bytes` to `path` atomically (see [`crate::output::write_atomic`]).
pub fn write_file_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    crate::output::write_atomic(path, |w| {
        w.write_all(bytes).map_err(|e| crate::Error::io(path, e))
    })
}
