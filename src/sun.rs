//! Solar position (NREL SPA) and the observer's site.

use serde::{Deserialize, Serialize};

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
