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

pub mod calibrate;
pub mod compare;
pub mod csv;
pub mod diurnal;
pub mod image;
pub mod params;
pub mod plot;
pub mod sensitivity;
pub mod stats;

use std::io::Write;
use std::path::Path;

use crate::{Error, Result};

/// Write `bytes` to `path` atomically: a temporary file in the same
/// directory, flushed and synced, then renamed over `path`.
pub fn write_file_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| {
            Error::invalid("output path", format!("`{}` names no file", path.display()))
        })?
        .to_string_lossy();
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(Error::io(path, e));
    }
    Ok(())
}
