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
//!
//! ## The front
//!
//! A program (the `irsig` command line, a binding) starts from a scene file
//! through [`Session`], re-exported here with its [`RunOptions`] and the
//! [`Progress`] observer long operations report to:
//!
//! ```no_run
//! use std::path::Path;
//! use std::sync::Arc;
//!
//! use irsig::{Backend, Progress, RunOptions, Session, Stage};
//!
//! /// Print each stage as it starts.
//! struct Log;
//! impl Progress for Log {
//!     fn start(&self, stage: Stage, total: u64) {
//!         eprintln!("{stage:?}: {total} {}", stage.unit());
//!     }
//! }
//!
//! // Load the scene and build the tracer.
//! let mut session = Session::open(Path::new("scenes/town/scene.json"), Backend::Embree)?;
//! // Every sensor at the scene's time: EXR, ENVI and PNG files in `out/`.
//! let options = RunOptions {
//!     progress: Some(Arc::new(Log)),
//!     ..RunOptions::default()
//! };
//! let stems = session.run(Path::new("out"), &options)?;
//! // Or step by step: the thermal state at some times, then one sensor.
//! let states = session.thermal(&[session.scene.time])?;
//! let rows = session.render_rows(0, &states.conditions[0], 0..8, &|_| {})?;
//! # let _ = (stems, rows);
//! # Ok::<(), irsig::Error>(())
//! ```
//!
//! Studies of a scene or of one facet — comparison with truth, sensitivity,
//! calibration, diurnal contrast — are in [`analysis`]. The other modules
//! are the stages themselves, for programs that assemble their own chain;
//! the command line calls them directly only where a command is a view of
//! one of them (`irsig sun`, `irsig weather`, `irsig radiance`, `irsig
//! info`, `irsig scene`).
//!
//! The library knows no command line: errors name the field or parameter
//! (`sensor`, `tilt_deg`), never a flag, and nothing here prints or draws.
#![warn(missing_docs)]
// `unsafe` lives only in `trace::embree` (the Embree FFI layer), which is
// allowed it explicitly; `deny` rather than `forbid` so that one module can.
#![deny(unsafe_code)]

pub mod analysis;
pub mod atmosphere;
pub mod error;
pub mod exposure;
pub mod geodesy;
pub mod geometry;
pub mod material;
pub mod math;
pub mod output;
pub mod progress;
pub mod radiometry;
pub mod render;
pub mod scene;
pub mod sensor;
pub mod simd;
pub mod suggest;
pub mod sun;
pub(crate) mod textio;
pub mod thermal;
pub mod trace;
pub mod weather;

pub use error::{Error, Location, Result};
pub use progress::{NoProgress, Progress, Stage};
pub use render::session::{RunOptions, Session, ThermalStates, Timings};
pub use trace::Backend;
