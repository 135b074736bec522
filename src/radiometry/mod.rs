//! Radiometry: Planck's law, spectral grids and sensor bands, band integrals
//! and brightness temperature, sensor spectral responses, angular spectral
//! emissivity, and the per-hit radiance ("big equation").
//!
//! How the pieces fit:
//! - [`planck`]: B(λ, T) in W·m⁻²·sr⁻¹·µm⁻¹ (CODATA 2018 by default).
//! - [`band`]: [`SpectralGrid`] (wavelengths + trapezoid weights) and
//!   [`Band`] (grid + relative response R, peak 1). Band radiance is
//!   ∫ R L dλ in W·m⁻²·sr⁻¹; [`Band::brightness_temperature`] inverts it.
//! - [`response`]: the spectral response CSV reader.
//! - [`emissivity`]: ε(λ, θ) from material curves, with a Fresnel default
//!   fall-off toward grazing view.
//! - [`equation`]: the per-hit leaving radiance ([`leaving_radiance`], the
//!   "big equation") and the sensor-reaching band radiance ([`at_sensor`]).
//! - [`solar`]: the top-of-atmosphere solar spectrum (ASTM E490 table,
//!   scaled to the solar constant).
//!
//! Internal units: wavelength µm, temperature K, spectral radiance
//! W·m⁻²·sr⁻¹·µm⁻¹, band radiance W·m⁻²·sr⁻¹.
//!
//! Takes temperatures, optical properties and incident terms; gives
//! radiances. It must not know geometry, ray tracing or where the incident
//! terms come from.

pub mod band;
pub mod emissivity;
pub mod equation;
pub mod planck;
pub mod response;
pub mod solar;

pub use band::{Band, DEFAULT_STEP_UM, SpectralGrid};
pub use emissivity::{AngularFalloff, Emissivity, fresnel_emissivity};
pub use equation::{
    ReflectanceSplit, SurfaceInputs, at_sensor, leaving_radiance, reflectance_split,
    solar_irradiance_toa,
};
pub use planck::{Constants, Planck, planck_radiance};
pub use response::{
    NEGATIVE_RESPONSE_TOLERANCE, SpectralResponse, parse_response_csv, read_response_csv,
};
