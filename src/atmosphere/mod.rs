//! Atmosphere: path transmittance and path radiance between a surface and
//! the sensor, and sky downwelling radiance.
//!
//! - [`tape7`]: the MODTRAN tape7 reader (radiance and transmittance modes).

pub mod tape7;

pub use tape7::{Tape7, Tape7Column, Tape7Mode};
