//! Meteorological relations used to fill missing weather fields.
//!
//! Each function cites its source and states its units. Temperatures are kelvin
//! unless a name says otherwise.

/// Stefan–Boltzmann constant, W m⁻² K⁻⁴ (CODATA 2018, exact in SI).
pub const STEFAN_BOLTZMANN_W_M2_K4: f64 = 5.670_374_419e-8;

/// Solar constant used with the Erbs model, W/m² (the 1367 W/m² of Erbs et al. 1982
/// and the WRC scale of the time).
pub const ERBS_SOLAR_CONSTANT_W_M2: f64 = 1367.0;

const ZERO_C_K: f64 = 273.15;
/// Magnus coefficients over liquid water, Alduchov & Eskridge (1996), "Improved Magnus
/// form approximation of saturation vapor pressure", J. Appl. Meteor. 35:601–609,
/// eq. 21 (AERK): e_s = 6.1094 exp(17.625 t / (t + 243.04)) hPa, t in °C; error < 0.4 %
/// for −40..50 °C.
const MAGNUS_A_HPA: f64 = 6.1094;
const MAGNUS_B: f64 = 17.625;
const MAGNUS_C_C: f64 = 243.04;

/// Saturation vapour pressure over liquid water, Pa, at temperature `t_k` (K)
/// (Alduchov & Eskridge 1996, AERK Magnus form).
pub fn saturation_vapour_pressure_pa(t_k: f64) -> f64 {
    let t = t_k - ZERO_C_K;
    100.0 * MAGNUS_A_HPA * (MAGNUS_B * t / (t + MAGNUS_C_C)).exp()
}

/// Relative humidity (fraction) from air temperature and dew point, K:
/// RH = e_s(T_d) / e_s(T) with the Alduchov & Eskridge (1996) Magnus form.
pub fn relative_humidity_from_dew_point(air_k: f64, dew_point_k: f64) -> f64 {
    saturation_vapour_pressure_pa(dew_point_k) / saturation_vapour_pressure_pa(air_k)
}

/// Dew point (K) from air temperature (K) and relative humidity (fraction, > 0):
/// the inverse Magnus form, T_d = c γ / (b − γ), γ = ln RH + b t / (c + t), t in °C
/// (Alduchov & Eskridge 1996 coefficients b = 17.625, c = 243.04 °C).
pub fn dew_point_from_relative_humidity(air_k: f64, relative_humidity: f64) -> f64 {
    let t = air_k - ZERO_C_K;
    let g = relative_humidity.ln() + MAGNUS_B * t / (MAGNUS_C_C + t);
    MAGNUS_C_C * g / (MAGNUS_B - g) + ZERO_C_K
}

/// Clear-and-cloudy sky emissivity of Clark & Allen (1978), with the cloud factor of
/// Walton's TARP, exactly as EnergyPlus fills a missing "Horizontal Infrared Radiation
/// Intensity" (EnergyPlus Engineering Reference, "Sky Radiation Modeling",
/// eq. for ε_sky):
///
/// ε = (0.787 + 0.764 ln(T_dp / 273)) (1 + 0.0224 N − 0.0035 N² + 0.00028 N³)
///
/// with the dew point `dew_point_k` in K and `opaque_sky_cover` as a fraction 0–1
/// (N = 10 × fraction, tenths). Dimensionless.
pub fn clark_allen_sky_emissivity(dew_point_k: f64, opaque_sky_cover: f64) -> f64 {
    let n = 10.0 * opaque_sky_cover;
    (0.787 + 0.764 * (dew_point_k / 273.0).ln())
        * (1.0 + 0.0224 * n - 0.0035 * n * n + 0.00028 * n * n * n)
}

/// Downwelling sky longwave irradiance on a horizontal surface, W/m²:
/// E = ε_sky σ T_db⁴ with ε_sky from [`clark_allen_sky_emissivity`] (EnergyPlus
/// Engineering Reference, "Sky Radiation Modeling"). Temperatures in K, cover 0–1.
pub fn clark_allen_sky_longwave_w_m2(air_k: f64, dew_point_k: f64, opaque_sky_cover: f64) -> f64 {
    clark_allen_sky_emissivity(dew_point_k, opaque_sky_cover)
        * STEFAN_BOLTZMANN_W_M2_K4
        * air_k.powi(4)
}

/// Diffuse fraction k_d = DHI/GHI from the hourly clearness index k_t (Erbs, Klein &
/// Duffie 1982, "Estimation of the diffuse radiation fraction for hourly, daily and
/// monthly-average global radiation", Solar Energy 28(4):293–302, eq. 1):
///
/// - k_t ≤ 0.22: k_d = 1 − 0.09 k_t
/// - 0.22 < k_t ≤ 0.80: k_d = 0.9511 − 0.1604 k_t + 4.388 k_t² − 16.638 k_t³ + 12.336 k_t⁴
/// - k_t > 0.80: k_d = 0.165
pub fn erbs_diffuse_fraction(kt: f64) -> f64 {
    if kt <= 0.22 {
        1.0 - 0.09 * kt
    } else if kt <= 0.80 {
        0.9511 - 0.1604 * kt + 4.388 * kt.powi(2) - 16.638 * kt.powi(3) + 12.336 * kt.powi(4)
    } else {
        0.165
    }
}

/// Cosine of zenith below which the Erbs split treats the sun as at the horizon
/// (zenith ≈ 86.3°), following pvlib's `erbs` (`min_cos_zenith = 0.065`).
pub const ERBS_MIN_COS_ZENITH: f64 = 0.065;
/// Largest zenith (deg) at which the split assigns any direct beam (pvlib `max_zenith`).
pub const ERBS_MAX_ZENITH_DEG: f64 = 87.0;

/// Split global-horizontal irradiance `ghi_w_m2` into (direct normal, diffuse
/// horizontal), W/m², by Erbs et al. (1982). `zenith_deg` is the solar zenith and
/// `distance_au` the Sun–Earth distance (extraterrestrial normal irradiance
/// 1367/R² W/m²). Clearness index k_t = GHI / (E₀ cos z), with cos z floored at
/// [`ERBS_MIN_COS_ZENITH`] and k_t capped at 1; beyond [`ERBS_MAX_ZENITH_DEG`] all of
/// GHI is diffuse (pvlib practice, Holmgren et al. 2018).
pub fn erbs_split(ghi_w_m2: f64, zenith_deg: f64, distance_au: f64) -> (f64, f64) {
    if ghi_w_m2 <= 0.0 {
        return (0.0, 0.0);
    }
    let cos_z = zenith_deg.to_radians().cos();
    let e0 = ERBS_SOLAR_CONSTANT_W_M2 / (distance_au * distance_au);
    let kt = (ghi_w_m2 / (e0 * cos_z.max(ERBS_MIN_COS_ZENITH))).clamp(0.0, 1.0);
    let kd = erbs_diffuse_fraction(kt);
    let dhi = kd * ghi_w_m2;
    if zenith_deg > ERBS_MAX_ZENITH_DEG {
        return (0.0, ghi_w_m2);
    }
    let dni = ((ghi_w_m2 - dhi) / cos_z).max(0.0);
    (dni, dhi)
}
