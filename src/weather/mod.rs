//! Weather histories: a time series of surface meteorology in SI units,
//! interpolated in time, read from irsig JSON/CSV, EPW, TMY3 and DIRSIG `.wth`.

use chrono::{DateTime, FixedOffset};
use serde::{Deserialize, Serialize};

/// One weather record, SI units. Field names carry their units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WeatherRecord {
    /// Time of the record (local time with its UTC offset).
    pub time: DateTime<FixedOffset>,
    /// Dry-bulb air temperature, K.
    pub air_temperature_k: f64,
    /// Dew-point temperature, K.
    pub dew_point_k: f64,
    /// Relative humidity, fraction 0–1.
    pub relative_humidity: f64,
    /// Station pressure, Pa.
    pub pressure_pa: f64,
    /// Wind speed, m/s.
    pub wind_speed_m_s: f64,
    /// Wind direction, degrees clockwise from north (where the wind comes from).
    pub wind_direction_deg: f64,
    /// Direct-normal solar irradiance, W/m².
    pub direct_normal_w_m2: f64,
    /// Diffuse-horizontal solar irradiance, W/m².
    pub diffuse_horizontal_w_m2: f64,
    /// Global-horizontal solar irradiance, W/m².
    pub global_horizontal_w_m2: f64,
    /// Downwelling sky longwave irradiance on a horizontal surface, W/m².
    pub sky_longwave_w_m2: f64,
    /// Total sky cover, fraction 0–1.
    pub total_sky_cover: f64,
    /// Opaque sky cover, fraction 0–1.
    pub opaque_sky_cover: f64,
}
