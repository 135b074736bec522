//! Psychrometrics of FAO-56 (Allen, Pereira, Raes & Smith 1998, *Crop
//! evapotranspiration*, FAO Irrigation and Drainage Paper 56, chapter 3 and
//! Annex 3): saturation vapour pressure and its slope, atmospheric pressure
//! from altitude, the psychrometric constant, latent heat of vaporisation,
//! actual vapour pressure from dew point or relative humidity, moist-air
//! density.
//!
//! FAO-56 writes these in kPa, °C and MJ kg⁻¹; here every function takes and
//! returns SI (Pa, K, J kg⁻¹), as the unit suffixes say. The FAO forms are
//! kept exactly (the Tetens coefficients 0.6108, 17.27, 237.3 of eq. 11), so
//! the worked examples of the paper are reproduced to their printed
//! precision. This is a different fit from the Alduchov & Eskridge Magnus
//! form that [`crate::weather::physics`] uses to fill dew points (they agree
//! within 0.3 % over 0–40 °C); the surface-energy balance uses this one so
//! that its latent flux matches the Penman–Monteith literature it is
//! validated against.

const ZERO_C_K: f64 = 273.15;

/// Tetens coefficients of FAO-56 eq. 11: e°(T) = 0.6108 exp(17.27 T / (T + 237.3)) kPa, T in °C.
const TETENS_A_PA: f64 = 610.8;
const TETENS_B: f64 = 17.27;
const TETENS_C_C: f64 = 237.3;

/// Latent heat of vaporisation FAO-56 uses throughout (λ = 2.45 MJ kg⁻¹, the
/// value at about 20 °C; chapter 3, "Latent heat of vaporization"), J kg⁻¹.
pub const FAO_LATENT_HEAT_J_KG: f64 = 2.45e6;

/// Specific heat of moist air at constant pressure, J kg⁻¹ K⁻¹ (FAO-56 eq. 8:
/// c_p = 1.013 × 10⁻³ MJ kg⁻¹ °C⁻¹).
pub const AIR_SPECIFIC_HEAT_J_KG_K: f64 = 1013.0;

/// Ratio of the molecular weights of water vapour and dry air, ε = 0.622
/// (FAO-56 eq. 8).
pub const MOLECULAR_WEIGHT_RATIO: f64 = 0.622;

/// Specific gas constant of dry air, J kg⁻¹ K⁻¹ (FAO-56 Annex 3, eq. 3-5:
/// R = 0.287 kJ kg⁻¹ K⁻¹).
pub const DRY_AIR_GAS_CONSTANT_J_KG_K: f64 = 287.0;

/// Saturation vapour pressure over water at `t_k`, Pa (FAO-56 eq. 11, Tetens
/// 1930): e°(T) = 610.8 exp(17.27 t / (t + 237.3)), t = T − 273.15 in °C.
#[inline]
pub fn saturation_vapour_pressure_pa(t_k: f64) -> f64 {
    let t = t_k - ZERO_C_K;
    TETENS_A_PA * (TETENS_B * t / (t + TETENS_C_C)).exp()
}

/// Slope Δ = de°/dT of the saturation vapour pressure curve at `t_k`, Pa K⁻¹
/// (FAO-56 eq. 13): Δ = 4098 e°(T) / (t + 237.3)². The exact derivative of
/// eq. 11 has 17.27 × 237.3 = 4098.171 where FAO-56 prints 4098; this uses
/// the exact product, so that Δ is the derivative of
/// [`saturation_vapour_pressure_pa`] (a Newton solve relies on it; the
/// difference is 4 × 10⁻⁵ relative, below the paper's printed precision).
#[inline]
pub fn saturation_vapour_pressure_slope_pa_k(t_k: f64) -> f64 {
    let t = t_k - ZERO_C_K;
    let denom = t + TETENS_C_C;
    TETENS_B * TETENS_C_C * saturation_vapour_pressure_pa(t_k) / (denom * denom)
}

/// Mean saturation vapour pressure of a day, Pa, from its extreme
/// temperatures (FAO-56 eq. 12): e_s = (e°(T_max) + e°(T_min)) / 2.
pub fn mean_saturation_vapour_pressure_pa(t_min_k: f64, t_max_k: f64) -> f64 {
    0.5 * (saturation_vapour_pressure_pa(t_max_k) + saturation_vapour_pressure_pa(t_min_k))
}

/// Atmospheric pressure at altitude `z_m` above sea level, Pa (FAO-56 eq. 7,
/// a simplified ideal-gas law with a standard atmosphere at 20 °C):
/// P = 101.3 ((293 − 0.0065 z) / 293)^5.26 kPa.
pub fn atmospheric_pressure_pa(z_m: f64) -> f64 {
    101_300.0 * ((293.0 - 0.0065 * z_m) / 293.0).powf(5.26)
}

/// Latent heat of vaporisation of water at `t_k`, J kg⁻¹ (FAO-56 Annex 3,
/// eq. 3-1, after Harrison 1963): λ = 2.501 − 0.002361 t MJ kg⁻¹, t in °C.
/// FAO-56 otherwise uses the constant [`FAO_LATENT_HEAT_J_KG`].
#[inline]
pub fn latent_heat_of_vaporisation_j_kg(t_k: f64) -> f64 {
    (2.501 - 0.002_361 * (t_k - ZERO_C_K)) * 1.0e6
}

/// Psychrometric constant γ at pressure `pressure_pa` for latent heat
/// `latent_heat_j_kg`, Pa K⁻¹ (FAO-56 eq. 8): γ = c_p P / (ε λ). With
/// λ = [`FAO_LATENT_HEAT_J_KG`] this is FAO's γ = 0.665 × 10⁻³ P.
#[inline]
pub fn psychrometric_constant_pa_k(pressure_pa: f64, latent_heat_j_kg: f64) -> f64 {
    AIR_SPECIFIC_HEAT_J_KG_K * pressure_pa / (MOLECULAR_WEIGHT_RATIO * latent_heat_j_kg)
}

/// Actual vapour pressure from the dew point `dew_point_k`, Pa (FAO-56
/// eq. 14): e_a = e°(T_dew).
#[inline]
pub fn vapour_pressure_from_dew_point_pa(dew_point_k: f64) -> f64 {
    saturation_vapour_pressure_pa(dew_point_k)
}

/// Actual vapour pressure from a relative humidity `relative_humidity`
/// (fraction 0–1) at `t_k`, Pa: e_a = RH e°(T) (FAO-56 eq. 10 inverted; the
/// hourly form of eq. 54).
#[inline]
pub fn vapour_pressure_from_relative_humidity_pa(t_k: f64, relative_humidity: f64) -> f64 {
    relative_humidity * saturation_vapour_pressure_pa(t_k)
}

/// Actual vapour pressure of a day from its extreme temperatures and extreme
/// relative humidities (fractions), Pa (FAO-56 eq. 17):
/// e_a = (e°(T_min) RH_max + e°(T_max) RH_min) / 2.
pub fn vapour_pressure_from_rh_extremes_pa(
    t_min_k: f64,
    t_max_k: f64,
    rh_min: f64,
    rh_max: f64,
) -> f64 {
    0.5 * (saturation_vapour_pressure_pa(t_min_k) * rh_max
        + saturation_vapour_pressure_pa(t_max_k) * rh_min)
}

/// Actual vapour pressure of a day from its mean relative humidity
/// `rh_mean` (fraction), Pa (FAO-56 eq. 19):
/// e_a = RH_mean (e°(T_max) + e°(T_min)) / 2.
pub fn vapour_pressure_from_rh_mean_pa(t_min_k: f64, t_max_k: f64, rh_mean: f64) -> f64 {
    rh_mean * mean_saturation_vapour_pressure_pa(t_min_k, t_max_k)
}

/// Vapour-pressure deficit e°(T) − e_a at `t_k` for actual vapour pressure
/// `vapour_pressure_pa`, Pa (FAO-56 chapter 3, "Vapour pressure deficit").
/// Negative when the air is supersaturated with respect to `t_k`.
#[inline]
pub fn vapour_pressure_deficit_pa(t_k: f64, vapour_pressure_pa: f64) -> f64 {
    saturation_vapour_pressure_pa(t_k) - vapour_pressure_pa
}

/// Density of moist air, kg m⁻³ (FAO-56 Annex 3, eq. 3-5): ρ = P / (T_kv R),
/// with the virtual temperature approximated as T_kv = 1.01 T (eq. 3-6 for
/// the usual vapour pressures) and R = [`DRY_AIR_GAS_CONSTANT_J_KG_K`].
#[inline]
pub fn air_density_kg_m3(pressure_pa: f64, t_k: f64) -> f64 {
    pressure_pa / (1.01 * t_k * DRY_AIR_GAS_CONSTANT_J_KG_K)
}

#[cfg(test)]
mod tests {
    use super::*;

    const K: f64 = ZERO_C_K;

    /// Round `x` to `d` decimals, as the paper prints.
    fn printed(x: f64, d: i32) -> f64 {
        let s = 10f64.powi(d);
        (x * s).round() / s
    }

    #[test]
    fn fao56_example_2_pressure_and_psychrometric_constant() {
        // Example 2: z = 1800 m → P = 81.8 kPa, γ = 0.054 kPa/°C.
        let p = atmospheric_pressure_pa(1800.0);
        assert_eq!(printed(p / 1000.0, 1), 81.8);
        let g = psychrometric_constant_pa_k(p, FAO_LATENT_HEAT_J_KG);
        assert_eq!(printed(g / 1000.0, 3), 0.054);
        // γ = 0.665e-3 P (eq. 8's constant form).
        assert!((g / p - 0.665e-3).abs() < 0.5e-6, "γ/P = {}", g / p);
    }

    #[test]
    fn fao56_example_3_saturation_vapour_pressure() {
        // Example 3: T_max 24.5 °C, T_min 15 °C → e°(24.5) = 3.075 kPa,
        // e°(15) = 1.705 kPa, e_s = 2.39 kPa.
        assert_eq!(
            printed(saturation_vapour_pressure_pa(24.5 + K) / 1e3, 3),
            3.075
        );
        assert_eq!(
            printed(saturation_vapour_pressure_pa(15.0 + K) / 1e3, 3),
            1.705
        );
        let es = mean_saturation_vapour_pressure_pa(15.0 + K, 24.5 + K);
        assert_eq!(printed(es / 1e3, 2), 2.39);
    }

    #[test]
    fn fao56_example_5_actual_vapour_pressure_from_rh() {
        // Example 5: T_min 18 °C, T_max 25 °C, RH_max 82 %, RH_min 54 %:
        // e°(18) = 2.064, e°(25) = 3.168 kPa; e_a = 1.70 kPa (eq. 17),
        // 1.69 kPa from RH_max only (eq. 18), 1.78 kPa from RH_mean = 68 % (eq. 19).
        let (tn, tx) = (18.0 + K, 25.0 + K);
        assert_eq!(printed(saturation_vapour_pressure_pa(tn) / 1e3, 3), 2.064);
        assert_eq!(printed(saturation_vapour_pressure_pa(tx) / 1e3, 3), 3.168);
        let ea = vapour_pressure_from_rh_extremes_pa(tn, tx, 0.54, 0.82);
        assert_eq!(printed(ea / 1e3, 2), 1.70);
        let ea_max = vapour_pressure_from_relative_humidity_pa(tn, 0.82);
        assert_eq!(printed(ea_max / 1e3, 2), 1.69);
        let ea_mean = vapour_pressure_from_rh_mean_pa(tn, tx, 0.68);
        assert_eq!(printed(ea_mean / 1e3, 2), 1.78);
    }

    #[test]
    fn fao56_slope_of_the_vapour_pressure_curve() {
        // Example 17 (T_mean 30.2 °C → Δ = 0.246 kPa/°C) and Example 18
        // (T_mean 16.9 °C → Δ = 0.122 kPa/°C).
        assert_eq!(
            printed(saturation_vapour_pressure_slope_pa_k(30.2 + K) / 1e3, 3),
            0.246
        );
        assert_eq!(
            printed(saturation_vapour_pressure_slope_pa_k(16.9 + K) / 1e3, 3),
            0.122
        );
    }

    #[test]
    fn fao56_example_20_dew_point() {
        // Example 20: T_dew = T_min = 14.8 °C → e_a = 1.68 kPa (eq. 14).
        assert_eq!(
            printed(vapour_pressure_from_dew_point_pa(14.8 + K) / 1e3, 2),
            1.68
        );
    }

    #[test]
    fn slope_is_the_derivative_of_saturation_vapour_pressure() {
        for t_c in [-20.0, 0.0, 15.0, 30.0, 45.0] {
            let t = t_c + K;
            let h = 1e-3;
            let fd = (saturation_vapour_pressure_pa(t + h) - saturation_vapour_pressure_pa(t - h))
                / (2.0 * h);
            let d = saturation_vapour_pressure_slope_pa_k(t);
            assert!((fd - d).abs() < 1e-6 * d, "T = {t_c} °C: {fd} vs {d}");
        }
    }

    #[test]
    fn latent_heat_and_density_are_physical() {
        // λ(20 °C) = 2.454 MJ/kg, FAO's 2.45 to its precision.
        assert_eq!(
            printed(latent_heat_of_vaporisation_j_kg(20.0 + K) / 1e6, 2),
            2.45
        );
        // ρ at 101.3 kPa, 20 °C ≈ 1.19 kg/m³ (1.01 T_v approximation).
        let rho = air_density_kg_m3(101_300.0, 20.0 + K);
        assert!((rho - 1.19).abs() < 0.01, "ρ = {rho}");
        assert!(vapour_pressure_deficit_pa(20.0 + K, 1000.0) > 0.0);
    }
}
