//! # irsig — a physics-based thermal-infrared synthetic image generator
//!
//! irsig models the imaging chain of an infrared camera from first principles,
//! in the manner of RIT's DIRSIG. Data flows one way, each stage in its own
//! module:
//!
//! ```text
//! scene (geometry, material, weather, sun)
//!   → trace   (Embree / obvhs: solar history, shape factor, primary rays)
//!   → thermal (THERM-style 1-D slab model per facet)
//!   → radiometry + atmosphere (the "big equation", band-integrated)
//!   → sensor  (frame camera / line scanner, PSF, noise, quantisation)
//!   → output  (EXR, ENVI, PNG) → analysis (compare, sensitivity, calibrate)
//! ```
//!
//! Internal units are SI (m, K, W, W·m⁻²·sr⁻¹·µm⁻¹); conversions happen at the
//! file boundary. World space is east-north-up metres ([`geometry`]).
#![warn(missing_docs)]
// `unsafe` lives only in `trace::embree` (the Embree FFI layer), which is
// allowed it explicitly; `deny` rather than `forbid` so that one module can.
#![deny(unsafe_code)]

pub mod analysis;
pub mod atmosphere;
pub mod bench;
pub mod error;
pub mod exposure;
pub mod geometry;
pub mod material;
pub mod output;
pub mod radiometry;
pub mod render;
pub mod scene;
pub mod sensor;
pub mod sun;
pub mod thermal;
pub mod trace;
pub mod weather;

pub use error::{Error, Location, Result};
