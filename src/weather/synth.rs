//! Synthetic weather histories from published models: the bundled town scene's
//! `scenes/town/weather.csv` (Rochester NY, 19–22 June 2025) is generated here by
//! `irsig weather synth --out scenes/town/weather.csv`, and a test checks that the
//! committed file is what this code produces.
//!
//! Models (all units SI unless stated):
//! - Solar position: NREL SPA ([`crate::sun::position_standard`]).
//! - Clear-sky irradiance: Bird & Hulstrom (1981), *A Simplified Clear Sky Model for
//!   Direct and Diffuse Insolation on Horizontal Surfaces*, SERI/TR-642-761, as in
//!   pvlib's `clearsky.bird` ([`bird_clear_sky`]); relative air mass of Kasten (1966)
//!   on the apparent zenith; extraterrestrial 1367/R² W/m².
//! - Precipitable water from surface humidity: Prata (1996), Q. J. R. Meteorol. Soc.
//!   122:1127–1151, w = 46.5 e/T cm (e in hPa, T in K).
//! - Cloud (first afternoon only): global reduced by Kasten & Czeplak (1980),
//!   Solar Energy 24:177–189, G = G_clear (1 − 0.75 N^3.4); the beam is seen through
//!   gaps with probability 1 − N (N opaque cover fraction); the rest of G is diffuse.
//! - Air temperature: ASHRAE Handbook—Fundamentals (2009) ch. 14, Table 6, fraction of
//!   the daily range by hour of local standard time (minimum near 05:00, maximum at 15:00),
//!   with daily maxima and ranges near Rochester's June normals (NOAA 1991–2020: mean
//!   maximum ≈ 25.6 °C, minimum ≈ 14.3 °C).
//! - Dew point: a slow ±0.7 K diurnal swing about a daily mean; RH from the Magnus form.
//! - Sky longwave: Clark & Allen as EnergyPlus ([`physics::clark_allen_sky_longwave_w_m2`]).
//! - Wind: light south-westerly, calm at night, ~4 m/s mid-afternoon.

use chrono::{DateTime, FixedOffset, TimeDelta, Timelike};

use super::physics;
use super::{WeatherHistory, WeatherRecord};
use crate::error::Result;
use crate::sun::{self, Site};

/// ASHRAE 2009 Fundamentals ch. 14 Table 6: fraction of the daily temperature range
/// below the daily maximum, for hours 1..24 of local standard time (index 0 = hour 1).
pub const ASHRAE_DAILY_RANGE_FRACTION: [f64; 24] = [
    0.87, 0.92, 0.96, 0.99, 1.00, 0.98, 0.93, 0.84, 0.71, 0.56, 0.39, 0.23, 0.11, 0.03, 0.00, 0.03,
    0.10, 0.21, 0.34, 0.47, 0.58, 0.68, 0.76, 0.82,
];

/// Atmosphere of the Bird & Hulstrom clear-sky model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BirdAtmosphere {
    /// Station pressure, Pa.
    pub pressure_pa: f64,
    /// Total column ozone, atm-cm.
    pub ozone_cm: f64,
    /// Precipitable water, cm.
    pub precipitable_water_cm: f64,
    /// Aerosol optical depth at 380 nm.
    pub aod380: f64,
    /// Aerosol optical depth at 500 nm.
    pub aod500: f64,
    /// Aerosol forward-scattering ratio (Bird's B_a), 0.85 recommended.
    pub asymmetry: f64,
    /// Ground albedo (multiple reflections ground–sky).
    pub albedo: f64,
}

/// Clear-sky irradiance (direct normal, diffuse horizontal, global horizontal), W/m²,
/// by Bird & Hulstrom (1981), following pvlib's `clearsky.bird` term by term:
/// transmittances of Rayleigh scattering, ozone, mixed gases, water vapour and aerosol
/// (broadband τ_a = 0.2758 τ₃₈₀ + 0.35 τ₅₀₀), aerosol absorptance T_AA, sky albedo r_s;
/// DNI = 0.9662 E₀ T_R T_O T_UM T_W T_A; GHI = (DNI cos z + I_as)/(1 − ρ_g r_s).
/// `zenith_deg` is the apparent zenith; `distance_au` the Sun–Earth distance.
/// Zero when the Sun is at or below the horizon.
pub fn bird_clear_sky(zenith_deg: f64, distance_au: f64, atm: &BirdAtmosphere) -> (f64, f64, f64) {
    if zenith_deg >= 90.0 {
        return (0.0, 0.0, 0.0);
    }
    let etr = physics::ERBS_SOLAR_CONSTANT_W_M2 / (distance_au * distance_au);
    let cos_z = zenith_deg.to_radians().cos();
    // Kasten (1966) relative air mass.
    let am = 1.0 / (cos_z + 0.15 * (93.885 - zenith_deg).powf(-1.253));
    let amp = am * atm.pressure_pa / 101_325.0;
    let t_rayleigh = (-0.0903 * amp.powf(0.84) * (1.0 + amp - amp.powf(1.01))).exp();
    let xo = atm.ozone_cm * am;
    let t_ozone = 1.0
        - 0.1611 * xo * (1.0 + 139.48 * xo).powf(-0.3034)
        - 0.002715 * xo / (1.0 + 0.044 * xo + 0.0003 * xo * xo);
    let t_gases = (-0.0127 * amp.powf(0.26)).exp();
    let xw = am * atm.precipitable_water_cm;
    let t_water = 1.0 - 2.4959 * xw / ((1.0 + 79.034 * xw).powf(0.6828) + 6.385 * xw);
    let tau_a = 0.2758 * atm.aod380 + 0.35 * atm.aod500;
    let t_aerosol =
        (-(tau_a.powf(0.873)) * (1.0 + tau_a - tau_a.powf(0.7088)) * am.powf(0.9108)).exp();
    let taa = 1.0 - 0.1 * (1.0 - am + am.powf(1.06)) * (1.0 - t_aerosol);
    let rs = 0.0685 + (1.0 - atm.asymmetry) * (1.0 - t_aerosol / taa);
    let dni = 0.9662 * etr * t_aerosol * t_water * t_gases * t_ozone * t_rayleigh;
    let ias = etr
        * cos_z
        * 0.79
        * t_ozone
        * t_gases
        * t_water
        * taa
        * (0.5 * (1.0 - t_rayleigh) + atm.asymmetry * (1.0 - t_aerosol / taa))
        / (1.0 - am + am.powf(1.02));
    let ghi = (dni * cos_z + ias) / (1.0 - atm.albedo * rs);
    let dhi = ghi - dni * cos_z;
    (dni.max(0.0), dhi.max(0.0), ghi.max(0.0))
}

/// Precipitable water, cm, from screen-level vapour pressure and temperature:
/// w = 46.5 e/T (Prata 1996), e in hPa, T in K.
pub fn prata_precipitable_water_cm(air_k: f64, dew_point_k: f64) -> f64 {
    let e_hpa = physics::saturation_vapour_pressure_pa(dew_point_k) / 100.0;
    46.5 * e_hpa / air_k
}

/// The bundled town scene's site: Rochester NY (Kodak Hawkeye plant area).
pub const TOWN_SITE: Site = Site {
    latitude_deg: 43.16,
    longitude_deg: -77.61,
    altitude_m: 170.0,
};

/// First record of the town history (local daylight time, UTC−4).
pub const TOWN_START: &str = "2025-06-19T00:00:00-04:00";
/// Number of 15-min records of the town history (72 h inclusive).
pub const TOWN_RECORDS: usize = 289;

/// Daily (maximum °C, range K, mean dew point °C) for 19, 20, 21, 22 June.
const TOWN_DAYS: [(f64, f64, f64); 4] = [
    (24.0, 10.0, 12.5),
    (26.0, 11.0, 13.0),
    (27.5, 12.0, 13.5),
    (27.5, 12.0, 13.5),
];

fn day_param(day_f: f64, k: usize) -> f64 {
    // Daily values hold at 15:00; linear in between.
    let x = (day_f - 15.0 / 24.0).clamp(0.0, (TOWN_DAYS.len() - 1) as f64);
    let i = (x.floor() as usize).min(TOWN_DAYS.len() - 2);
    let w = x - i as f64;
    let get = |d: (f64, f64, f64)| match k {
        0 => d.0,
        1 => d.1,
        _ => d.2,
    };
    get(TOWN_DAYS[i]) * (1.0 - w) + get(TOWN_DAYS[i + 1]) * w
}

fn ashrae_fraction(hour_lst: f64) -> f64 {
    // Table hours 1..24; hour 0 ≡ 24.
    let h = hour_lst.rem_euclid(24.0);
    let i0 = h.floor() as usize; // hour value i0 → table index i0−1 (0 → 23)
    let f = |hv: usize| ASHRAE_DAILY_RANGE_FRACTION[(hv + 23) % 24];
    let w = h - h.floor();
    f(i0) * (1.0 - w) + f(i0 + 1) * w
}

/// Opaque cloud fraction of the town history: a cumulus bump on the first afternoon
/// (19 June, 11:00–18:00 local, peak 0.6 at 14:30), clear otherwise.
fn town_cloud(hours_since_start: f64) -> f64 {
    let (a, b) = (11.0, 18.0);
    if hours_since_start <= a || hours_since_start >= b {
        0.0
    } else {
        0.6 * (std::f64::consts::PI * (hours_since_start - a) / (b - a))
            .sin()
            .powi(2)
    }
}

/// Generate the town scene's weather history (see the module docs), with comment lines
/// describing it for the CSV header.
///
/// # Errors
/// Only if the solar position fails (it does not for these fixed inputs).
pub fn town_history() -> Result<(WeatherHistory, Vec<String>)> {
    let start = DateTime::<FixedOffset>::parse_from_rfc3339(TOWN_START)
        .map_err(|e| crate::error::Error::Other(format!("TOWN_START: {e}")))?;
    let site = TOWN_SITE;
    let p0 = sun::standard_pressure_pa(site.altitude_m);
    let mut records = Vec::with_capacity(TOWN_RECORDS);
    for i in 0..TOWN_RECORDS {
        let t = start + TimeDelta::minutes(15 * i as i64);
        let hours = i as f64 * 0.25;
        let day_f = hours / 24.0;
        // Local standard time (EST = EDT − 1 h) for the ASHRAE profile.
        let local = t.time();
        let hour_lst = local.hour() as f64 + local.minute() as f64 / 60.0 - 1.0;
        let tmax = day_param(day_f, 0);
        let range = day_param(day_f, 1);
        let air_k = tmax - ashrae_fraction(hour_lst) * range + 273.15;
        let hour_local = local.hour() as f64 + local.minute() as f64 / 60.0;
        let dew_k = day_param(day_f, 2)
            + 0.7 * (2.0 * std::f64::consts::PI * (hour_local - 7.0) / 24.0).sin()
            + 273.15;
        let rh = physics::relative_humidity_from_dew_point(air_k, dew_k);
        let pressure = p0 + 300.0 * (2.0 * std::f64::consts::PI * hours / 72.0).sin();
        let wind = 1.5
            + 2.5
                * (std::f64::consts::PI * (hour_local - 7.0) / 14.0)
                    .sin()
                    .max(0.0);
        let wind_dir = 225.0 + 20.0 * (2.0 * std::f64::consts::PI * hours / 30.0).sin();

        let sp = sun::position_standard(&site, t)?;
        let atm = BirdAtmosphere {
            pressure_pa: pressure,
            ozone_cm: 0.33,
            precipitable_water_cm: prata_precipitable_water_cm(air_k, dew_k),
            aod380: 0.30,
            aod500: 0.20,
            asymmetry: 0.85,
            albedo: 0.2,
        };
        let (dni_c, _dhi_c, ghi_c) = bird_clear_sky(sp.apparent_zenith_deg, sp.distance_au, &atm);
        let n = town_cloud(hours);
        let cos_z = sp.apparent_zenith_deg.to_radians().cos().max(0.0);
        let ghi = ghi_c * (1.0 - 0.75 * n.powf(3.4));
        let dni = dni_c * (1.0 - n);
        let dhi = (ghi - dni * cos_z).max(0.0);
        let total = (n * 1.25).min(1.0);
        let sky = physics::clark_allen_sky_longwave_w_m2(air_k, dew_k, n);
        records.push(WeatherRecord {
            time: t,
            air_temperature_k: air_k,
            dew_point_k: dew_k,
            relative_humidity: rh,
            pressure_pa: pressure,
            wind_speed_m_s: wind,
            wind_direction_deg: wind_dir,
            direct_normal_w_m2: dni,
            diffuse_horizontal_w_m2: dhi,
            global_horizontal_w_m2: ghi,
            sky_longwave_w_m2: sky,
            total_sky_cover: total,
            opaque_sky_cover: n,
            precipitation_mm: 0.0,
            visibility_km: None,
        });
    }
    let comments = vec![
        "Synthetic weather for the bundled town scene (Rochester NY), generated by".to_string(),
        "`irsig weather synth --out scenes/town/weather.csv` (src/weather/synth.rs).".to_string(),
        "Clear sky: Bird & Hulstrom 1981 (SPA sun, AOD380 0.30, AOD500 0.20, ozone 0.33 cm,"
            .to_string(),
        "precipitable water by Prata 1996); cumulus on 19 June 11:00-18:00 (Kasten & Czeplak 1980);"
            .to_string(),
        "air temperature: ASHRAE 2009 daily-range profile; sky longwave: Clark & Allen (EnergyPlus)."
            .to_string(),
    ];
    Ok((WeatherHistory::new(records, Some(site))?, comments))
}
