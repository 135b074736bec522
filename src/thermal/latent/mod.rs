//! Latent and sensible heat at a surface: the turbulent terms of the surface
//! energy balance that the slab model ([`crate::thermal`]) does not yet have.
//!
//! **Owns** the physics, as pure functions of scalars, each citing its
//! equation:
//! - [`psychrometrics`]: FAO-56 saturation vapour pressure and slope,
//!   pressure from altitude, psychrometric constant, latent heat of
//!   vaporisation, actual vapour pressure, air density (Allen et al. 1998,
//!   FAO Irrigation and Drainage Paper 56);
//! - [`aerodynamic`]: the aerodynamic resistance r_a from wind speed,
//!   measurement heights, roughness lengths and displacement height (FAO-56
//!   eq. 4), corrected for stability with the bulk Richardson number (Louis
//!   1979), finite in free convection at calm wind;
//! - [`surface_resistance`]: the Jarvis–Stewart canopy (surface) resistance
//!   r_s responding to sunlight, vapour-pressure deficit, soil moisture and
//!   temperature (Jarvis 1976; Stewart 1988; the forms of Noilhan & Planton
//!   1989);
//! - [`penman_monteith`]: the big-leaf Penman–Monteith latent flux (FAO-56
//!   eq. 3), the FAO-56 reference ET₀ (daily eq. 6, hourly eq. 53), and
//!   [`TurbulentExchange`]: latent and sensible flux at a given *surface*
//!   temperature, with their derivatives, for a surface-energy-balance
//!   solver;
//! - [`surface_energy`]: [`SurfaceEnergy`], a surface's aerodynamic and
//!   canopy parameters, giving the exchange at one weather record;
//! - [`soil_water`]: [`RootZone`], the root-zone water bucket (ISBA's w₂,
//!   Noilhan & Planton 1989) that rain wets and evaporation dries, and the
//!   capillary rise into it from a water table (Gardner 1958, through the
//!   Clapp & Hornberger 1978 soils, [`SoilTexture`]).
//!
//! **Takes** air temperature, humidity, pressure, wind and the surface's
//! parameters, SI units in every name (Pa, K, s m⁻¹, W m⁻²); the FAO-56
//! reference-ET functions alone keep the paper's units (kPa, MJ, mm), as
//! their names say. **Gives** resistances and fluxes. Fluxes are positive
//! *away from the surface* (upward), as flux towers report them.
//!
//! **Must not know** slabs, facets, scenes, weather files or materials: the
//! thermal solve couples these terms to its front-surface balance, and the
//! material loader builds the parameter structs (whose constructors
//! validate and return [`InputError`] naming the field; the loader adds the
//! file).
//!
//! ```
//! use irsig::thermal::latent::{Aerodynamic, AirState, TurbulentExchange};
//! // Grass 0.12 m tall, wind and air measured at 2 m: r_a = 208/u (FAO-56).
//! let aero = Aerodynamic::from_canopy_height(0.12, 2.0, 2.0).unwrap();
//! let r_a = aero.resistance_s_m(2.0, 300.0, 300.0); // neutral: ΔT = 0
//! assert!((r_a - 104.0).abs() < 1.0);
//! let air = AirState::from_relative_humidity(300.0, 0.5, 101_325.0).unwrap();
//! let x = TurbulentExchange::new(air, r_a, 70.0).unwrap();
//! let le = x.latent_w_m2(303.0); // a surface 3 K above the air evaporates
//! assert!(le > 100.0 && le < 400.0, "{le}");
//! ```

pub mod aerodynamic;
pub mod penman_monteith;
pub mod psychrometrics;
pub mod soil_water;
pub mod surface_energy;
pub mod surface_resistance;

pub use aerodynamic::{Aerodynamic, VON_KARMAN};
pub use penman_monteith::{
    AirState, ReferenceEtInputs, TurbulentExchange, penman_monteith_latent_w_m2,
    reference_et0_daily_mm, reference_et0_hourly_mm,
};
pub use soil_water::{RootZone, SoilTexture, WaterStep, WaterTable};
pub use surface_energy::{SurfaceEnergy, SurfaceResistance, bare_soil_resistance_s_m};
pub use surface_resistance::{CanopyConditions, JarvisStewart, StressFactors};

/// A parameter outside its physical domain. Each variant names the field
/// (as the material file spells it) and carries the bad value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum InputError {
    /// NaN or infinite where a finite number is needed.
    #[error("`{field}` = {value} is not a finite number")]
    NotFinite {
        /// The field.
        field: &'static str,
        /// The value given.
        value: f64,
    },
    /// Negative where only zero or more makes sense (a resistance, a leaf
    /// area index, a height).
    #[error("`{field}` = {value} is negative; expected ≥ 0")]
    Negative {
        /// The field.
        field: &'static str,
        /// The value given.
        value: f64,
    },
    /// Outside a stated range.
    #[error("`{field}` = {value} is out of range; expected {expected}")]
    OutOfRange {
        /// The field.
        field: &'static str,
        /// The value given.
        value: f64,
        /// The range or condition expected.
        expected: String,
    },
    /// A roughness length at or above the height of the measurement above
    /// the displacement height: the log profile is undefined there.
    #[error(
        "`{field}` = {roughness_m} m is not below the measurement height above the \
         displacement height ({height_above_displacement_m} m); expected a roughness \
         length smaller than z − d"
    )]
    RoughnessNotBelowHeight {
        /// The roughness field.
        field: &'static str,
        /// The roughness length given, m.
        roughness_m: f64,
        /// Measurement height minus displacement height, m.
        height_above_displacement_m: f64,
    },
}

impl InputError {
    /// The name of the offending field.
    pub fn field(&self) -> &'static str {
        match self {
            InputError::NotFinite { field, .. }
            | InputError::Negative { field, .. }
            | InputError::OutOfRange { field, .. }
            | InputError::RoughnessNotBelowHeight { field, .. } => field,
        }
    }
}

impl From<InputError> for crate::error::Error {
    fn from(e: InputError) -> Self {
        crate::error::Error::invalid(e.field(), e.to_string())
    }
}

/// `value` finite, else [`InputError::NotFinite`].
pub(crate) fn finite(field: &'static str, value: f64) -> Result<f64, InputError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(InputError::NotFinite { field, value })
    }
}

/// `value` finite and ≥ 0, else the matching [`InputError`].
pub(crate) fn non_negative(field: &'static str, value: f64) -> Result<f64, InputError> {
    finite(field, value)?;
    if value < 0.0 {
        Err(InputError::Negative { field, value })
    } else {
        Ok(value)
    }
}

/// `value` finite and > 0, else the matching [`InputError`].
pub(crate) fn positive(field: &'static str, value: f64) -> Result<f64, InputError> {
    non_negative(field, value)?;
    if value == 0.0 {
        Err(InputError::OutOfRange {
            field,
            value,
            expected: "> 0".into(),
        })
    } else {
        Ok(value)
    }
}

/// `value` finite and in `lo..=hi`, else the matching [`InputError`].
pub(crate) fn in_range(
    field: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
) -> Result<f64, InputError> {
    finite(field, value)?;
    if (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        Err(InputError::OutOfRange {
            field,
            value,
            expected: format!("{lo}..={hi}"),
        })
    }
}
