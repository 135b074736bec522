//! Solar position (NREL SPA), the observer's site, and the time format.
//!
//! Owns [`Site`] (validated; parsed from `LAT,LON[,ALT]` by its
//! [`FromStr`](std::str::FromStr)), [`SunPosition`] and the one RFC 3339
//! time parser, [`parse_time`], that every reader and the command line use.
//! Takes a site and a time, gives the Sun's position. Knows nothing of
//! scenes, weather files or the command line.
//!
//! Positions come from NREL's Solar Position Algorithm, Reda, I. & Andreas, A.
//! (2004), *Solar Position Algorithm for Solar Radiation Applications*, NREL/TP-560-34302
//! (Solar Energy 76(5):577–589, doi:10.1016/j.solener.2003.12.003), as implemented by
//! the `solar-positioning` crate (validated there against NREL's `spa.c`; stated
//! uncertainty ±0.0003° for years −2000..6000). This module adds the site type, input
//! validation with named fields, both the geometric and the refracted (apparent) zenith,
//! the Sun–Earth distance and an ENU direction vector.
//!
//! Conventions: azimuth in degrees clockwise from true north (0° = N, 90° = E);
//! zenith in degrees from the local vertical; time in UTC (UT1 ≈ UTC); ΔT = TT − UT1
//! in seconds.

use chrono::{DateTime, FixedOffset, TimeZone, Utc};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use solar_positioning::{Location, RefractionCorrection, SolarPositions};

use crate::error::{Error, Result};

/// Where the scene is. Conventions: latitude north-positive, longitude
/// east-positive, degrees; altitude above mean sea level, metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Site {
    /// Latitude, degrees (−90..90, north positive).
    pub latitude_deg: f64,
    /// Longitude, degrees (−180..180, east positive).
    pub longitude_deg: f64,
    /// Altitude above mean sea level, m.
    pub altitude_m: f64,
}

/// Altitudes accepted for a site, m (Dead Sea shore to above Everest).
const ALTITUDE_RANGE_M: (f64, f64) = (-1000.0, 10000.0);

impl Site {
    /// A validated site.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the field when latitude is outside −90..90°,
    /// longitude outside −180..180°, altitude outside −1000..10000 m, or any is not finite.
    pub fn new(latitude_deg: f64, longitude_deg: f64, altitude_m: f64) -> Result<Site> {
        let site = Site {
            latitude_deg,
            longitude_deg,
            altitude_m,
        };
        site.validate()?;
        Ok(site)
    }

    /// Great-circle distance to `other`, km: the haversine formula on a
    /// sphere of the IUGG mean Earth radius, 6371.0088 km (Moritz 2000,
    /// "Geodetic Reference System 1980"); within 0.5 % of the ellipsoidal
    /// distance, plenty for telling a weather file of another place.
    pub fn distance_km(&self, other: &Site) -> f64 {
        const MEAN_EARTH_RADIUS_KM: f64 = 6371.0088;
        let (p1, p2) = (
            self.latitude_deg.to_radians(),
            other.latitude_deg.to_radians(),
        );
        let dp = p2 - p1;
        let dl = (other.longitude_deg - self.longitude_deg).to_radians();
        let a = (dp / 2.0).sin().powi(2) + p1.cos() * p2.cos() * (dl / 2.0).sin().powi(2);
        2.0 * MEAN_EARTH_RADIUS_KM * a.sqrt().min(1.0).asin()
    }

    /// Check the site's ranges (see [`Site::new`]).
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the offending field and its value.
    pub fn validate(&self) -> Result<()> {
        if !(self.latitude_deg.is_finite() && (-90.0..=90.0).contains(&self.latitude_deg)) {
            return Err(Error::invalid(
                "latitude_deg",
                format!(
                    "latitude {} is outside −90..90 degrees (north positive)",
                    self.latitude_deg
                ),
            ));
        }
        if !(self.longitude_deg.is_finite() && (-180.0..=180.0).contains(&self.longitude_deg)) {
            return Err(Error::invalid(
                "longitude_deg",
                format!(
                    "longitude {} is outside −180..180 degrees (east positive)",
                    self.longitude_deg
                ),
            ));
        }
        let (lo, hi) = ALTITUDE_RANGE_M;
        if !(self.altitude_m.is_finite() && (lo..=hi).contains(&self.altitude_m)) {
            return Err(Error::invalid(
                "altitude_m",
                format!(
                    "altitude {} m is outside {lo}..{hi} m above mean sea level",
                    self.altitude_m
                ),
            ));
        }
        Ok(())
    }

    /// Station pressure of the ICAO standard atmosphere at the site's altitude, Pa:
    /// p = 101 325 (1 − 2.25577×10⁻⁵ h)^5.25588 (ICAO Doc 7488; troposphere,
    /// lapse rate 6.5 K/km). EnergyPlus uses the same formula for missing pressure.
    pub fn standard_pressure_pa(&self) -> f64 {
        standard_pressure_pa(self.altitude_m)
    }
}

impl std::str::FromStr for Site {
    type Err = Error;

    /// A site written `LAT,LON[,ALT]` (degrees north, degrees east, metres;
    /// ALT default 0), or as keys `latitude_deg=LAT longitude_deg=LON
    /// [altitude_m=ALT]` (the form of an irsig weather CSV's site comment).
    ///
    /// # Errors
    /// [`Error::Invalid`] for field `site` when the text has neither form or
    /// a value is not a number; the errors of [`Site::new`] when a value is
    /// out of range.
    fn from_str(s: &str) -> Result<Site> {
        if s.contains('=') {
            return site_from_keys(s);
        }
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        if !(parts.len() == 2 || parts.len() == 3) {
            return Err(Error::invalid(
                "site",
                format!("`{s}`: expected LAT,LON[,ALT] (degrees north, degrees east, metres)"),
            ));
        }
        let num = |i: usize, what: &str| -> Result<f64> {
            parts[i].parse::<f64>().map_err(|_| {
                Error::invalid(
                    "site",
                    format!(
                        "`{}` is not a number ({what}); expected LAT,LON[,ALT]",
                        parts[i]
                    ),
                )
            })
        };
        let alt = match parts.len() {
            3 => num(2, "altitude, m")?,
            _ => 0.0,
        };
        Site::new(num(0, "latitude, °")?, num(1, "longitude, °")?, alt)
    }
}

/// `latitude_deg=LAT longitude_deg=LON [altitude_m=ALT]` (an empty value
/// counts as absent).
fn site_from_keys(s: &str) -> Result<Site> {
    let (mut lat, mut lon, mut alt) = (None, None, None);
    for kv in s.split_whitespace() {
        let (k, v) = kv
            .split_once('=')
            .ok_or_else(|| Error::invalid("site", format!("expected key=value, found `{kv}`")))?;
        let slot = match k {
            "latitude_deg" => &mut lat,
            "longitude_deg" => &mut lon,
            "altitude_m" => &mut alt,
            _ => {
                return Err(Error::invalid(
                    "site",
                    format!("unknown key `{k}`; expected latitude_deg, longitude_deg, altitude_m"),
                ));
            }
        };
        let v = v.trim();
        *slot = if v.is_empty() {
            None
        } else {
            Some(
                v.parse::<f64>()
                    .map_err(|_| Error::invalid(k, format!("`{v}` is not a number")))?,
            )
        };
    }
    match (lat, lon) {
        (Some(la), Some(lo)) => Site::new(la, lo, alt.unwrap_or(0.0)),
        _ => Err(Error::invalid(
            "site",
            "needs latitude_deg= and longitude_deg=",
        )),
    }
}

/// A time that is not RFC 3339 with a UTC offset (see [`parse_time`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
// chrono's message is part of this one, not a `#[source]`: `{:#}` chains
// would otherwise print it twice.
#[error(
    "`{text}` is not an RFC 3339 time with a UTC offset (e.g. 2025-06-21T14:00:00-04:00): {reason}"
)]
pub struct TimeParseError {
    /// The text, trimmed.
    pub text: String,
    /// Why chrono refused it.
    pub reason: chrono::ParseError,
}

/// Parse an RFC 3339 time with a UTC offset (`2025-06-21T14:00:00-04:00`,
/// `2025-06-21T18:00:00Z`), ignoring surrounding whitespace: the one time
/// format of irsig's files and command line.
///
/// # Errors
/// [`TimeParseError`] naming the text.
pub fn parse_time(s: &str) -> Result<DateTime<FixedOffset>, TimeParseError> {
    let text = s.trim();
    DateTime::parse_from_rfc3339(text).map_err(|reason| TimeParseError {
        text: text.to_string(),
        reason,
    })
}

/// ICAO standard-atmosphere pressure at altitude `altitude_m`, Pa (see
/// [`Site::standard_pressure_pa`]).
pub fn standard_pressure_pa(altitude_m: f64) -> f64 {
    101_325.0 * (1.0 - 2.255_77e-5 * altitude_m).powf(5.255_88)
}

/// ICAO standard-atmosphere temperature at altitude `altitude_m`, °C
/// (15 °C at sea level, −6.5 K/km).
pub fn standard_temperature_c(altitude_m: f64) -> f64 {
    15.0 - 0.0065 * altitude_m
}

/// The Sun seen from a site at one instant (NREL SPA, topocentric).
///
/// Angles in degrees; azimuth clockwise from true north (0° = N, 90° = E, 180° = S).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SunPosition {
    /// Topocentric zenith angle without atmospheric refraction, degrees (0..180).
    pub zenith_deg: f64,
    /// Topocentric zenith angle with atmospheric refraction (SPA eq. 42–43, for the given
    /// pressure and temperature), degrees. Equal to `zenith_deg` when the Sun is far below
    /// the horizon.
    pub apparent_zenith_deg: f64,
    /// Topocentric azimuth, degrees clockwise from north (0..360).
    pub azimuth_deg: f64,
    /// Sun–Earth distance (SPA's radius vector R, §3.2.8), astronomical units.
    pub distance_au: f64,
}

impl SunPosition {
    /// Apparent elevation above the horizon (90° − apparent zenith), degrees.
    pub fn apparent_elevation_deg(&self) -> f64 {
        90.0 - self.apparent_zenith_deg
    }

    /// Whether the Sun's centre is apparently above the horizon.
    pub fn is_up(&self) -> bool {
        self.apparent_zenith_deg < 90.0
    }

    /// Unit vector from the site toward the Sun's apparent (refracted) position, in the
    /// scene's ENU frame: x east, y north, z up.
    pub fn direction_enu(&self) -> DVec3 {
        enu_from_angles(self.apparent_zenith_deg, self.azimuth_deg)
    }

    /// Unit vector toward the Sun's geometric (unrefracted) position, ENU.
    pub fn geometric_direction_enu(&self) -> DVec3 {
        enu_from_angles(self.zenith_deg, self.azimuth_deg)
    }
}

fn enu_from_angles(zenith_deg: f64, azimuth_deg: f64) -> DVec3 {
    let (sz, cz) = zenith_deg.to_radians().sin_cos();
    let (sa, ca) = azimuth_deg.to_radians().sin_cos();
    DVec3::new(sz * sa, sz * ca, cz)
}

fn map_spa_error(e: solar_positioning::Error) -> Error {
    use solar_positioning::Error as E;
    match e {
        E::InvalidLatitude { .. } => Error::invalid("latitude_deg", e.to_string()),
        E::InvalidLongitude { .. } => Error::invalid("longitude_deg", e.to_string()),
        E::InvalidHeight { .. } => Error::invalid("altitude_m", e.to_string()),
        E::InvalidPressure { .. } => Error::invalid("pressure_mbar", e.to_string()),
        E::InvalidTemperature { .. } => Error::invalid("temperature_c", e.to_string()),
        E::InvalidDateTime { .. } => Error::invalid("time", e.to_string()),
        _ => Error::Other(format!("solar position: {e}")),
    }
}

/// Solar position by NREL SPA (Reda & Andreas 2004) at `time` for `site`.
///
/// `delta_t_s` is ΔT = TT − UT1 in seconds (e.g. 67 s in 2003, ~69 s in 2025;
/// see [`delta_t_estimate_s`]); `pressure_mbar` (hPa) and `temperature_c` (°C) are the
/// annual-mean local conditions used only for the refraction of `apparent_zenith_deg`
/// (SPA eq. 42; valid for 0 < p ≤ 2000 mbar, −273 < T ≤ 100 °C).
///
/// # Errors
/// [`Error::Invalid`] naming the field for a latitude outside ±90°, a longitude outside
/// ±180°, an altitude outside −1000..10000 m, a non-finite or |ΔT| > 10⁴ s, pressure or
/// temperature out of range, or a time outside SPA's −2000..6000 range.
pub fn position<Tz: TimeZone>(
    site: &Site,
    time: DateTime<Tz>,
    delta_t_s: f64,
    pressure_mbar: f64,
    temperature_c: f64,
) -> Result<SunPosition> {
    site.validate()?;
    if !(delta_t_s.is_finite() && delta_t_s.abs() <= 1.0e4) {
        return Err(Error::invalid(
            "delta_t_s",
            format!("ΔT {delta_t_s} s is not a finite value within ±10000 s"),
        ));
    }
    let refraction =
        RefractionCorrection::new(pressure_mbar, temperature_c).map_err(map_spa_error)?;
    let time = time.with_timezone(&Utc);
    let prepared = SolarPositions::new()
        .for_time(&time, delta_t_s)
        .map_err(map_spa_error)?;
    let location = Location {
        latitude: site.latitude_deg,
        longitude: site.longitude_deg,
    };
    let geometric = prepared
        .at(location, site.altitude_m, None)
        .map_err(map_spa_error)?;
    let apparent = prepared
        .at(location, site.altitude_m, Some(refraction))
        .map_err(map_spa_error)?;
    let distance_au = prepared
        .earth_radius_vector()
        .ok_or_else(|| Error::Other("SPA did not return the Sun–Earth distance".into()))?;
    Ok(SunPosition {
        zenith_deg: geometric.zenith_angle(),
        apparent_zenith_deg: apparent.zenith_angle(),
        azimuth_deg: geometric.azimuth(),
        distance_au,
    })
}

/// Solar position with the standard atmosphere at the site's altitude for refraction
/// ([`standard_pressure_pa`], [`standard_temperature_c`]) and ΔT from
/// [`delta_t_estimate_s`]. See [`position`].
///
/// # Errors
/// As [`position`].
pub fn position_standard<Tz: TimeZone>(site: &Site, time: DateTime<Tz>) -> Result<SunPosition> {
    site.validate()?;
    let utc = time.with_timezone(&Utc);
    let delta_t = delta_t_estimate_s(&utc)?;
    position(
        site,
        utc,
        delta_t,
        standard_pressure_pa(site.altitude_m) / 100.0,
        standard_temperature_c(site.altitude_m),
    )
}

/// ΔT = TT − UT1 estimate for the month of `time`, seconds: Espenak & Meeus polynomial
/// fits (NASA Five Millennium Canon of Solar Eclipses, 2006), with the `solar-positioning`
/// crate's updated fit after 2015 (about 69 s in 2025). An error of 1 s in ΔT moves the
/// Sun by at most ~0.004°.
///
/// # Errors
/// [`Error::Invalid`] for times before year −500.
pub fn delta_t_estimate_s<Tz: TimeZone>(time: &DateTime<Tz>) -> Result<f64> {
    let utc = time.with_timezone(&Utc);
    solar_positioning::delta_t::estimate_from_date_like(&utc).map_err(map_spa_error)
}

/// Solar positions for many instants at one site (e.g. a weather history or a
/// thermal-model time grid), with the standard atmosphere and estimated ΔT.
///
/// # Errors
/// As [`position`], for the first failing instant.
pub fn positions_standard<Tz: TimeZone>(
    site: &Site,
    times: impl IntoIterator<Item = DateTime<Tz>>,
) -> Result<Vec<SunPosition>> {
    times
        .into_iter()
        .map(|t| position_standard(site, t))
        .collect()
}
