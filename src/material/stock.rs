//! The stock material library (`scenes/materials.json`), built into the library so
//! that it is found wherever irsig is installed or run from, not relative to the
//! working directory.
//!
//! Owns the embedded copy and its name in messages. Takes nothing; gives a
//! [`MaterialDb`]. Must not know where a command line looks for files.

use std::path::Path;

use super::MaterialDb;
use crate::error::Result;

/// The stock library's text, as in the source tree's `scenes/materials.json`.
pub const STOCK_JSON: &str = include_str!("../../scenes/materials.json");

/// How the built-in library is named in messages.
pub const STOCK_NAME: &str = "<built-in scenes/materials.json>";

/// The stock material library (the built-in copy of `scenes/materials.json`).
///
/// # Errors
/// Only if the embedded file were invalid (a test keeps it valid).
pub fn stock() -> Result<MaterialDb> {
    super::db::load_json_str_all(STOCK_JSON, Path::new(STOCK_NAME))
        .map_err(|mut v| v.swap_remove(0))
}
