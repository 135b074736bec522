//! Latent and sensible heat fluxes: the big-leaf Penman–Monteith equation,
//! FAO-56's reference evapotranspiration, and the fluxes at a given surface
//! temperature for a surface-energy-balance solver.
//!
//! - [`penman_monteith_latent_w_m2`]: FAO-56 eq. 3 (Monteith 1965), the
//!   latent flux of a big-leaf surface given its available energy Rn − G,
//!   with the saturation curve linearised about the air temperature.
//! - [`reference_et0_daily_mm`], [`reference_et0_hourly_mm`]: FAO-56 eq. 6
//!   and eq. 53, in the paper's units (the grass reference: eq. 3 with
//!   r_s = 70 s m⁻¹ and r_a = 208/u₂).
//! - [`TurbulentExchange`]: the same physics without the linearisation, as
//!   functions of the surface temperature T_s, which is what a slab model
//!   solves for:
//!
//!   LE(T_s) = (ρ c_p / γ) (e°(T_s) − e_a) / (r_a + r_s),
//!   H(T_s) = ρ c_p (T_s − T_a) / r_a,
//!
//!   and their derivatives dLE/dT_s = (ρ c_p / γ) Δ(T_s) / (r_a + r_s) and
//!   dH/dT_s = ρ c_p / r_a, for a Newton or linearised solve. The
//!   resistances are held fixed over a step (a stability-corrected r_a is
//!   evaluated at the previous iterate, the usual lag), so the derivatives
//!   are at fixed r_a and r_s.
//!
//! Fluxes are positive away from the surface. Negative LE is condensation
//! (dew): through stomata that is unphysical, so a caller modelling dew sets
//! r_s = 0 when e°(T_s) < e_a.

use super::psychrometrics::{
    AIR_SPECIFIC_HEAT_J_KG_K, FAO_LATENT_HEAT_J_KG, air_density_kg_m3,
    latent_heat_of_vaporisation_j_kg, psychrometric_constant_pa_k, saturation_vapour_pressure_pa,
    saturation_vapour_pressure_slope_pa_k, vapour_pressure_from_dew_point_pa,
    vapour_pressure_from_relative_humidity_pa,
};
use super::{InputError, finite, in_range};

/// The air at the measurement height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirState {
    temperature_k: f64,
    vapour_pressure_pa: f64,
    pressure_pa: f64,
}

impl AirState {
    /// Air at `temperature_k` with actual vapour pressure
    /// `vapour_pressure_pa` and pressure `pressure_pa`.
    ///
    /// # Errors
    /// [`InputError`] naming the field: temperature outside 180..340 K,
    /// vapour pressure negative or above the pressure, pressure outside
    /// 30..110 kPa, anything not finite.
    pub fn new(
        temperature_k: f64,
        vapour_pressure_pa: f64,
        pressure_pa: f64,
    ) -> Result<AirState, InputError> {
        in_range("air_temperature_k", temperature_k, 180.0, 340.0)?;
        in_range("pressure_pa", pressure_pa, 30_000.0, 110_000.0)?;
        in_range("vapour_pressure_pa", vapour_pressure_pa, 0.0, pressure_pa)?;
        Ok(AirState {
            temperature_k,
            vapour_pressure_pa,
            pressure_pa,
        })
    }

    /// Air at `temperature_k` and relative humidity `relative_humidity`
    /// (fraction 0–1), e_a = RH e°(T) (FAO-56 eq. 54).
    ///
    /// # Errors
    /// As [`AirState::new`], and `relative_humidity` outside 0..1.
    pub fn from_relative_humidity(
        temperature_k: f64,
        relative_humidity: f64,
        pressure_pa: f64,
    ) -> Result<AirState, InputError> {
        in_range("relative_humidity", relative_humidity, 0.0, 1.0)?;
        in_range("air_temperature_k", temperature_k, 180.0, 340.0)?;
        AirState::new(
            temperature_k,
            vapour_pressure_from_relative_humidity_pa(temperature_k, relative_humidity),
            pressure_pa,
        )
    }

    /// Air at `temperature_k` with dew point `dew_point_k`, e_a = e°(T_dew)
    /// (FAO-56 eq. 14).
    ///
    /// # Errors
    /// As [`AirState::new`], and a dew point not finite.
    pub fn from_dew_point(
        temperature_k: f64,
        dew_point_k: f64,
        pressure_pa: f64,
    ) -> Result<AirState, InputError> {
        finite("dew_point_k", dew_point_k)?;
        AirState::new(
            temperature_k,
            vapour_pressure_from_dew_point_pa(dew_point_k),
            pressure_pa,
        )
    }

    /// Air temperature T_a, K.
    pub fn temperature_k(&self) -> f64 {
        self.temperature_k
    }
    /// Actual vapour pressure e_a, Pa.
    pub fn vapour_pressure_pa(&self) -> f64 {
        self.vapour_pressure_pa
    }
    /// Pressure P, Pa.
    pub fn pressure_pa(&self) -> f64 {
        self.pressure_pa
    }
    /// Vapour-pressure deficit e°(T_a) − e_a, Pa.
    pub fn vapour_pressure_deficit_pa(&self) -> f64 {
        saturation_vapour_pressure_pa(self.temperature_k) - self.vapour_pressure_pa
    }
    /// Moist-air density ρ, kg m⁻³ (FAO-56 Annex 3 eq. 3-5).
    pub fn density_kg_m3(&self) -> f64 {
        air_density_kg_m3(self.pressure_pa, self.temperature_k)
    }
    /// Latent heat of vaporisation at the air temperature λ(T_a), J kg⁻¹
    /// (FAO-56 Annex 3 eq. 3-1).
    pub fn latent_heat_j_kg(&self) -> f64 {
        latent_heat_of_vaporisation_j_kg(self.temperature_k)
    }
    /// Psychrometric constant γ = c_p P / (ε λ(T_a)), Pa K⁻¹ (FAO-56 eq. 8).
    pub fn psychrometric_constant_pa_k(&self) -> f64 {
        psychrometric_constant_pa_k(self.pressure_pa, self.latent_heat_j_kg())
    }
}

/// r_a (> 0, may be +∞) and r_s (≥ 0, may be +∞) checked.
fn check_resistances(r_a: f64, r_s: f64) -> Result<(), InputError> {
    if r_a.is_nan() || r_a <= 0.0 {
        return Err(if r_a < 0.0 {
            InputError::Negative {
                field: "aerodynamic_resistance_s_m",
                value: r_a,
            }
        } else {
            InputError::OutOfRange {
                field: "aerodynamic_resistance_s_m",
                value: r_a,
                expected: "> 0 s/m (+∞ for no exchange)".into(),
            }
        });
    }
    if r_s.is_nan() {
        return Err(InputError::NotFinite {
            field: "surface_resistance_s_m",
            value: r_s,
        });
    }
    if r_s < 0.0 {
        return Err(InputError::Negative {
            field: "surface_resistance_s_m",
            value: r_s,
        });
    }
    Ok(())
}

/// Big-leaf Penman–Monteith latent heat flux λE, W m⁻² (FAO-56 eq. 3;
/// Monteith 1965):
///
/// λE = [Δ (Rn − G) + ρ c_p (e_s − e_a) / r_a] / [Δ + γ (1 + r_s / r_a)]
///
/// with `available_energy_w_m2` = Rn − G, Δ, ρ, γ and e_s at the air
/// temperature, resistances in s m⁻¹. r_s = +∞ gives 0; r_a = +∞ gives the
/// limit of the formula, Δ(Rn − G)/(Δ + γ).
///
/// # Errors
/// [`InputError`] naming the field for r_a ≤ 0 or NaN, r_s < 0 or NaN, or
/// a non-finite available energy.
pub fn penman_monteith_latent_w_m2(
    available_energy_w_m2: f64,
    air: &AirState,
    aerodynamic_resistance_s_m: f64,
    surface_resistance_s_m: f64,
) -> Result<f64, InputError> {
    finite("available_energy_w_m2", available_energy_w_m2)?;
    check_resistances(aerodynamic_resistance_s_m, surface_resistance_s_m)?;
    let (r_a, r_s) = (aerodynamic_resistance_s_m, surface_resistance_s_m);
    if r_s == f64::INFINITY {
        return Ok(0.0);
    }
    let delta = saturation_vapour_pressure_slope_pa_k(air.temperature_k);
    let gamma = air.psychrometric_constant_pa_k();
    let rho_cp = air.density_kg_m3() * AIR_SPECIFIC_HEAT_J_KG_K;
    // r_a = +∞ (no turbulent exchange) is eq. 3's limit, the equilibrium
    // evaporation Δ(Rn − G)/(Δ + γ) of a fully decoupled surface.
    let (aero, ratio) = if r_a == f64::INFINITY {
        (0.0, 0.0)
    } else {
        (rho_cp * air.vapour_pressure_deficit_pa() / r_a, r_s / r_a)
    };
    Ok((delta * available_energy_w_m2 + aero) / (delta + gamma * (1.0 + ratio)))
}

/// Inputs of FAO-56's reference evapotranspiration, in the paper's units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceEtInputs {
    /// Net radiation at the crop surface Rn over the period, MJ m⁻² (per day
    /// for eq. 6, per hour for eq. 53).
    pub net_radiation_mj_m2: f64,
    /// Soil heat flux G over the period, MJ m⁻².
    pub soil_heat_flux_mj_m2: f64,
    /// Mean air temperature at 2 m over the period, °C.
    pub air_temperature_c: f64,
    /// Wind speed at 2 m u₂, m s⁻¹.
    pub wind_speed_2m_m_s: f64,
    /// Saturation vapour pressure e_s, kPa.
    pub saturation_vapour_pressure_kpa: f64,
    /// Actual vapour pressure e_a, kPa.
    pub actual_vapour_pressure_kpa: f64,
    /// Atmospheric pressure P, kPa (γ = 0.665 × 10⁻³ P, FAO-56 eq. 8).
    pub pressure_kpa: f64,
}

impl ReferenceEtInputs {
    /// FAO-56's common form of eqs. 6 and 53 with numerator constant `cn`
    /// (900 daily, 37 hourly) and denominator constant 0.34.
    fn et0(&self, cn: f64) -> f64 {
        let t = self.air_temperature_c;
        let delta = saturation_vapour_pressure_slope_pa_k(t + 273.15) / 1000.0;
        let gamma =
            psychrometric_constant_pa_k(self.pressure_kpa * 1000.0, FAO_LATENT_HEAT_J_KG) / 1000.0;
        let u2 = self.wind_speed_2m_m_s;
        let vpd = self.saturation_vapour_pressure_kpa - self.actual_vapour_pressure_kpa;
        (0.408 * delta * (self.net_radiation_mj_m2 - self.soil_heat_flux_mj_m2)
            + gamma * cn / (t + 273.0) * u2 * vpd)
            / (delta + gamma * (1.0 + 0.34 * u2))
    }
}

/// FAO-56 daily reference evapotranspiration ET₀, mm day⁻¹ (eq. 6; radiation
/// in MJ m⁻² day⁻¹).
pub fn reference_et0_daily_mm(inputs: &ReferenceEtInputs) -> f64 {
    inputs.et0(900.0)
}

/// FAO-56 hourly reference evapotranspiration ET₀, mm hour⁻¹ (eq. 53;
/// radiation in MJ m⁻² hour⁻¹, the hour's mean temperature).
pub fn reference_et0_hourly_mm(inputs: &ReferenceEtInputs) -> f64 {
    inputs.et0(37.0)
}

/// Latent and sensible exchange between a surface and the air through fixed
/// resistances, as functions of the surface temperature (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TurbulentExchange {
    air: AirState,
    aerodynamic_resistance_s_m: f64,
    surface_resistance_s_m: f64,
    /// ρ c_p, J m⁻³ K⁻¹.
    rho_cp: f64,
}

impl TurbulentExchange {
    /// Exchange with `air` through the aerodynamic resistance
    /// `aerodynamic_resistance_s_m` (> 0; +∞: none) and the surface
    /// resistance `surface_resistance_s_m` (≥ 0; 0 for a wet surface, +∞ for
    /// a dry one), s m⁻¹.
    ///
    /// # Errors
    /// [`InputError`] naming the resistance that is negative, zero (r_a) or
    /// NaN.
    pub fn new(
        air: AirState,
        aerodynamic_resistance_s_m: f64,
        surface_resistance_s_m: f64,
    ) -> Result<TurbulentExchange, InputError> {
        check_resistances(aerodynamic_resistance_s_m, surface_resistance_s_m)?;
        Ok(TurbulentExchange {
            air,
            aerodynamic_resistance_s_m,
            surface_resistance_s_m,
            rho_cp: air.density_kg_m3() * AIR_SPECIFIC_HEAT_J_KG_K,
        })
    }

    /// The air.
    pub fn air(&self) -> &AirState {
        &self.air
    }
    /// r_a, s m⁻¹.
    pub fn aerodynamic_resistance_s_m(&self) -> f64 {
        self.aerodynamic_resistance_s_m
    }
    /// r_s, s m⁻¹.
    pub fn surface_resistance_s_m(&self) -> f64 {
        self.surface_resistance_s_m
    }

    /// ρ c_p / (γ (r_a + r_s)), W m⁻² Pa⁻¹: the vapour conductance in energy
    /// units (0 when either resistance is infinite): the
    /// `vapour_conductance_w_m2_pa` of the slab model's
    /// [`crate::thermal::SurfaceFlux`].
    pub fn vapour_conductance_w_m2_pa(&self) -> f64 {
        let r = self.aerodynamic_resistance_s_m + self.surface_resistance_s_m;
        self.rho_cp / (self.air.psychrometric_constant_pa_k() * r)
    }

    /// Latent heat flux at surface temperature `surface_temperature_k`,
    /// W m⁻² (positive: evaporation):
    /// LE = ρ c_p / γ · (e°(T_s) − e_a) / (r_a + r_s).
    pub fn latent_w_m2(&self, surface_temperature_k: f64) -> f64 {
        self.vapour_conductance_w_m2_pa()
            * (saturation_vapour_pressure_pa(surface_temperature_k) - self.air.vapour_pressure_pa)
    }

    /// dLE/dT_s at `surface_temperature_k`, W m⁻² K⁻¹ (≥ 0):
    /// ρ c_p / γ · Δ(T_s) / (r_a + r_s).
    pub fn latent_derivative_w_m2_k(&self, surface_temperature_k: f64) -> f64 {
        self.vapour_conductance_w_m2_pa()
            * saturation_vapour_pressure_slope_pa_k(surface_temperature_k)
    }

    /// Sensible heat flux at `surface_temperature_k`, W m⁻² (positive:
    /// surface warmer than the air): H = ρ c_p (T_s − T_a) / r_a.
    pub fn sensible_w_m2(&self, surface_temperature_k: f64) -> f64 {
        self.sensible_coefficient_w_m2_k() * (surface_temperature_k - self.air.temperature_k)
    }

    /// dH/dT_s = ρ c_p / r_a, W m⁻² K⁻¹: the convective heat-transfer
    /// coefficient of the surface.
    pub fn sensible_coefficient_w_m2_k(&self) -> f64 {
        self.rho_cp / self.aerodynamic_resistance_s_m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::thermal::latent::Aerodynamic;
    use crate::thermal::latent::psychrometrics::atmospheric_pressure_pa;

    fn printed(x: f64, d: i32) -> f64 {
        let s = 10f64.powi(d);
        (x * s).round() / s
    }

    #[test]
    fn fao56_example_17_monthly_et0() {
        // Example 17 (Bangkok, April, z = 2 m): T_mean 30.2 °C, u₂ 2 m/s,
        // e_s 4.42 kPa, e_a 2.85 kPa, Rn 14.33 MJ/m²/day, G 0.14 →
        // ET₀ = 5.72 mm/day. With the rounded intermediate values the paper
        // prints, the last digit can move by one.
        let et0 = reference_et0_daily_mm(&ReferenceEtInputs {
            net_radiation_mj_m2: 14.33,
            soil_heat_flux_mj_m2: 0.14,
            air_temperature_c: 30.2,
            wind_speed_2m_m_s: 2.0,
            saturation_vapour_pressure_kpa: 4.42,
            actual_vapour_pressure_kpa: 2.85,
            pressure_kpa: atmospheric_pressure_pa(2.0) / 1000.0,
        });
        assert!((et0 - 5.72).abs() <= 0.011, "ET₀ = {et0}");
    }

    #[test]
    fn fao56_example_18_daily_et0() {
        // Example 18 (Brussels, 6 July, z = 100 m): T 16.9 °C, u₂ 2.078 m/s,
        // e_s 1.997 kPa, e_a 1.409 kPa, Rn 13.28 MJ/m²/day, G 0, γ 0.0666 →
        // ET₀ = 3.9 mm/day.
        let p = atmospheric_pressure_pa(100.0);
        assert_eq!(
            printed(
                psychrometric_constant_pa_k(p, FAO_LATENT_HEAT_J_KG) / 1000.0,
                4
            ),
            0.0666
        );
        let et0 = reference_et0_daily_mm(&ReferenceEtInputs {
            net_radiation_mj_m2: 13.28,
            soil_heat_flux_mj_m2: 0.0,
            air_temperature_c: 16.9,
            wind_speed_2m_m_s: 2.078,
            saturation_vapour_pressure_kpa: 1.997,
            actual_vapour_pressure_kpa: 1.409,
            pressure_kpa: p / 1000.0,
        });
        assert_eq!(printed(et0, 1), 3.9, "ET₀ = {et0}");
    }

    #[test]
    fn fao56_example_19_hourly_et0() {
        // Example 19 (N'Diaye, Senegal, 16°13'N, z = 8 m, 1 October,
        // 14:00–15:00): T_hr 38 °C, RH_hr 52 %, u₂ 3.3 m/s; the example's
        // Rn = 1.749 and G = 0.1 Rn = 0.175 MJ/m²/hour → ET₀ = 0.63 mm/hour.
        let t = 38.0 + 273.15;
        let es = saturation_vapour_pressure_pa(t);
        let ea = vapour_pressure_from_relative_humidity_pa(t, 0.52);
        let et0 = reference_et0_hourly_mm(&ReferenceEtInputs {
            net_radiation_mj_m2: 1.749,
            soil_heat_flux_mj_m2: 0.175,
            air_temperature_c: 38.0,
            wind_speed_2m_m_s: 3.3,
            saturation_vapour_pressure_kpa: es / 1000.0,
            actual_vapour_pressure_kpa: ea / 1000.0,
            pressure_kpa: atmospheric_pressure_pa(8.0) / 1000.0,
        });
        assert_eq!(printed(et0, 2), 0.63, "ET₀ = {et0}");
    }

    #[test]
    fn eq6_is_eq3_for_the_grass_reference() {
        // FAO-56 derives eq. 6 from eq. 3 with r_s = 70 s/m and
        // r_a = 208/u₂ (λ = 2.45 MJ/kg): both agree within the rounding of
        // its constants (900, 0.34).
        let grass = Aerodynamic::from_canopy_height(0.12, 2.0, 2.0).unwrap();
        for (t_c, rh, u2, rn_mj) in [(16.9, 0.7, 2.078, 13.28), (30.2, 0.64, 2.0, 14.33)] {
            let t = t_c + 273.15;
            let p = 101_300.0;
            let air = AirState::from_relative_humidity(t, rh, p).unwrap();
            let r_a = grass.neutral_resistance_s_m(u2);
            let le = penman_monteith_latent_w_m2(rn_mj * 1e6 / 86_400.0, &air, r_a, 70.0).unwrap();
            let eq3_mm_day = le * 86_400.0 / air.latent_heat_j_kg();
            let eq6 = reference_et0_daily_mm(&ReferenceEtInputs {
                net_radiation_mj_m2: rn_mj,
                soil_heat_flux_mj_m2: 0.0,
                air_temperature_c: t_c,
                wind_speed_2m_m_s: u2,
                saturation_vapour_pressure_kpa: saturation_vapour_pressure_pa(t) / 1e3,
                actual_vapour_pressure_kpa: air.vapour_pressure_pa() / 1e3,
                pressure_kpa: p / 1e3,
            });
            assert!(
                (eq3_mm_day - eq6).abs() < 0.02 * eq6,
                "{eq3_mm_day} vs {eq6}"
            );
        }
    }

    fn sunny_air() -> AirState {
        AirState::from_relative_humidity(300.0, 0.5, 100_000.0).unwrap()
    }

    #[test]
    fn infinite_surface_resistance_stops_evaporation() {
        let air = sunny_air();
        let mut last = f64::INFINITY;
        for r_s in [0.0, 50.0, 500.0, 5e3, 5e5, 5e8] {
            let le = TurbulentExchange::new(air, 50.0, r_s)
                .unwrap()
                .latent_w_m2(305.0);
            assert!(le > 0.0 && le < last, "r_s = {r_s}: {le}");
            last = le;
        }
        assert!(last < 1e-3, "{last}");
        let dry = TurbulentExchange::new(air, 50.0, f64::INFINITY).unwrap();
        assert_eq!(dry.latent_w_m2(305.0), 0.0);
        assert_eq!(dry.latent_derivative_w_m2_k(305.0), 0.0);
        // Sensible heat does not depend on r_s.
        assert_eq!(
            dry.sensible_w_m2(305.0),
            TurbulentExchange::new(air, 50.0, 0.0)
                .unwrap()
                .sensible_w_m2(305.0)
        );
        assert_eq!(
            penman_monteith_latent_w_m2(500.0, &air, 50.0, f64::INFINITY).unwrap(),
            0.0
        );
        // No turbulent exchange: the equilibrium evaporation, eq. 3's limit.
        let delta = saturation_vapour_pressure_slope_pa_k(air.temperature_k());
        let eq = delta * 500.0 / (delta + air.psychrometric_constant_pa_k());
        let le = penman_monteith_latent_w_m2(500.0, &air, f64::INFINITY, 70.0).unwrap();
        assert!((le - eq).abs() < 1e-9 * eq, "{le} vs {eq}");
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let air = sunny_air();
        for (r_a, r_s) in [(20.0, 0.0), (50.0, 70.0), (200.0, 1000.0)] {
            let x = TurbulentExchange::new(air, r_a, r_s).unwrap();
            for t in [280.0, 300.0, 320.0] {
                let h = 1e-3;
                let fd = (x.latent_w_m2(t + h) - x.latent_w_m2(t - h)) / (2.0 * h);
                let d = x.latent_derivative_w_m2_k(t);
                assert!(
                    (fd - d).abs() < 1e-6 * d.abs().max(1e-9),
                    "LE': {fd} vs {d}"
                );
                let fd = (x.sensible_w_m2(t + h) - x.sensible_w_m2(t - h)) / (2.0 * h);
                let d = x.sensible_coefficient_w_m2_k();
                assert!((fd - d).abs() < 1e-6 * d, "H': {fd} vs {d}");
            }
        }
    }

    #[test]
    fn penman_monteith_is_the_linearised_energy_balance() {
        // Solve Rn − G = H(T_s) + LE(T_s) by Newton with the derivatives; the
        // LE found equals eq. 3 up to the linearisation of e°(T_s) about T_a
        // (a few per cent for a few kelvin).
        let air = sunny_air();
        for (a, r_a, r_s) in [
            (400.0, 40.0, 70.0),
            (200.0, 100.0, 200.0),
            (600.0, 30.0, 0.0),
        ] {
            let x = TurbulentExchange::new(air, r_a, r_s).unwrap();
            let mut t = air.temperature_k();
            for _ in 0..20 {
                let f = x.sensible_w_m2(t) + x.latent_w_m2(t) - a;
                let df = x.sensible_coefficient_w_m2_k() + x.latent_derivative_w_m2_k(t);
                t -= f / df;
            }
            let closure = x.sensible_w_m2(t) + x.latent_w_m2(t) - a;
            assert!(closure.abs() < 1e-9 * a, "residual {closure}");
            let pm = penman_monteith_latent_w_m2(a, &air, r_a, r_s).unwrap();
            let le = x.latent_w_m2(t);
            assert!(
                (le - pm).abs() < 0.05 * pm,
                "A = {a}: LE {le} vs PM {pm} (T_s − T_a = {})",
                t - 300.0
            );
        }
    }

    #[test]
    fn bad_resistances_and_air_are_errors_naming_the_field() {
        let air = sunny_air();
        let e = TurbulentExchange::new(air, 50.0, -1.0).unwrap_err();
        assert_eq!(
            e,
            InputError::Negative {
                field: "surface_resistance_s_m",
                value: -1.0
            }
        );
        let e = TurbulentExchange::new(air, -3.0, 70.0).unwrap_err();
        assert_eq!(e.field(), "aerodynamic_resistance_s_m");
        let e = TurbulentExchange::new(air, 0.0, 70.0).unwrap_err();
        assert_eq!(e.field(), "aerodynamic_resistance_s_m");
        let e = penman_monteith_latent_w_m2(300.0, &air, 50.0, f64::NAN).unwrap_err();
        assert_eq!(e.field(), "surface_resistance_s_m");
        let e = AirState::from_relative_humidity(300.0, 1.2, 1e5).unwrap_err();
        assert_eq!(e.field(), "relative_humidity");
        let e = AirState::new(300.0, 2e5, 1e5).unwrap_err();
        assert_eq!(e.field(), "vapour_pressure_pa");
        let e = AirState::new(300.0, 1000.0, 5e6).unwrap_err();
        assert_eq!(e.field(), "pressure_pa");
    }
}
