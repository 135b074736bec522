//! Geodesy on the WGS-84 ellipsoid: the scene's local east-north-up frame,
//! geodetic latitude/longitude, and UTM grid coordinates.
//!
//! - The scene's world frame is the local tangent plane at the site: x east,
//!   y north, z up, metres, origin at the site's latitude/longitude and
//!   altitude (z = 0). [`enu_from_geodetic`] and [`geodetic_from_enu`] go
//!   between it and geodetic coordinates through Earth-centred Earth-fixed
//!   (ECEF) coordinates (Hofmann-Wellenhof, Lichtenegger & Wasle, *GNSS*,
//!   Springer 2008, eqs. 3.18, 3.27 and the iteration of §3.2.1; ellipsoid
//!   constants from NGA TR8350.2, 3rd ed., table 3.1). The site altitude is
//!   taken as ellipsoidal height: the geoid undulation is a constant offset
//!   within one scene and cancels.
//! - [`utm_from_geodetic`]: the transverse Mercator projection by Krüger's
//!   series to sixth order in the third flattening `n` (Karney, "Transverse
//!   Mercator with an accuracy of a few nanometers", *J. Geodesy* 85,
//!   475–485, 2011, doi:10.1007/s00190-011-0445-3, eqs. 7–11 and 35;
//!   error below 5 nm within 3900 km of the central meridian), with the UTM
//!   scale 0.9996, false easting 500 km and false northing 10 000 km in the
//!   southern hemisphere. [`UtmZone::of`] picks the zone of a point, with the
//!   Norway and Svalbard exceptions (NGA, *The Universal Grids*, DMATM
//!   8358.2, 1989).
//!
//! Angles are in degrees at the interface, lengths in metres. Takes and
//! gives coordinates; knows nothing of scenes, sensors or files.

use glam::DVec3;

use crate::sun::Site;
use crate::{Error, Result};

/// WGS-84 semi-major axis, m.
pub const WGS84_A_M: f64 = 6_378_137.0;
/// WGS-84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// UTM central scale factor.
pub const UTM_K0: f64 = 0.9996;
/// UTM false easting, m.
pub const UTM_FALSE_EASTING_M: f64 = 500_000.0;
/// UTM false northing in the southern hemisphere, m.
pub const UTM_FALSE_NORTHING_SOUTH_M: f64 = 10_000_000.0;
/// Latitudes UTM covers, degrees (south inclusive, north exclusive).
pub const UTM_LATITUDES_DEG: (f64, f64) = (-80.0, 84.0);

/// First eccentricity squared, `e² = f(2 − f)`.
fn e2() -> f64 {
    WGS84_F * (2.0 - WGS84_F)
}

/// Earth-centred Earth-fixed coordinates (m) of geodetic latitude and
/// longitude (degrees) and ellipsoidal height `h_m` (m) on WGS-84:
/// `x = (N + h) cos φ cos λ`, `y = (N + h) cos φ sin λ`,
/// `z = (N(1 − e²) + h) sin φ`, `N = a / √(1 − e² sin² φ)`.
pub fn ecef_from_geodetic(lat_deg: f64, lon_deg: f64, h_m: f64) -> DVec3 {
    let e2 = e2();
    let (sp, cp) = lat_deg.to_radians().sin_cos();
    let (sl, cl) = lon_deg.to_radians().sin_cos();
    let n = WGS84_A_M / (1.0 - e2 * sp * sp).sqrt();
    DVec3::new(
        (n + h_m) * cp * cl,
        (n + h_m) * cp * sl,
        (n * (1.0 - e2) + h_m) * sp,
    )
}

/// Geodetic latitude, longitude (degrees) and ellipsoidal height (m) of ECEF
/// point `p`: `λ = atan2(y, x)` and the fixed-point iteration
/// `φ = atan2(z, p(1 − e² N/(N + h)))`, `h = p/cos φ − N` (Hofmann-Wellenhof
/// et al. 2008, §3.2.1), run until φ changes by less than 10⁻¹⁴ rad (a few
/// steps near the Earth's surface: far below a millimetre). Near the poles
/// `h` comes from `z` instead of `p`.
pub fn geodetic_from_ecef(p: DVec3) -> (f64, f64, f64) {
    let e2 = e2();
    let lon = p.y.atan2(p.x);
    let r = p.x.hypot(p.y);
    let mut lat = p.z.atan2(r * (1.0 - e2));
    let mut h = 0.0;
    for _ in 0..20 {
        let s = lat.sin();
        let n = WGS84_A_M / (1.0 - e2 * s * s).sqrt();
        h = if lat.cos().abs() > 1e-3 {
            r / lat.cos() - n
        } else {
            p.z / s - n * (1.0 - e2)
        };
        let next = p.z.atan2(r * (1.0 - e2 * n / (n + h)));
        let done = (next - lat).abs() < 1e-14;
        lat = next;
        if done {
            break;
        }
    }
    (lat.to_degrees(), lon.to_degrees(), h)
}

/// The rotation from ECEF to the local ENU frame at `site`, as rows
/// (east, north, up).
fn enu_axes(site: &Site) -> [DVec3; 3] {
    let (sp, cp) = site.latitude_deg.to_radians().sin_cos();
    let (sl, cl) = site.longitude_deg.to_radians().sin_cos();
    [
        DVec3::new(-sl, cl, 0.0),
        DVec3::new(-sp * cl, -sp * sl, cp),
        DVec3::new(cp * cl, cp * sl, sp),
    ]
}

/// East-north-up coordinates (m) of a geodetic point relative to `origin`
/// (the scene's site; its altitude is the height of z = 0).
pub fn enu_from_geodetic(origin: &Site, lat_deg: f64, lon_deg: f64, h_m: f64) -> DVec3 {
    let d = ecef_from_geodetic(lat_deg, lon_deg, h_m)
        - ecef_from_geodetic(origin.latitude_deg, origin.longitude_deg, origin.altitude_m);
    let [e, n, u] = enu_axes(origin);
    DVec3::new(e.dot(d), n.dot(d), u.dot(d))
}

/// Geodetic latitude, longitude (degrees) and height (m, the site altitude
/// at z = 0) of scene point `enu` (m) of the scene at `origin`.
pub fn geodetic_from_enu(origin: &Site, enu: DVec3) -> (f64, f64, f64) {
    let [e, n, u] = enu_axes(origin);
    let o = ecef_from_geodetic(origin.latitude_deg, origin.longitude_deg, origin.altitude_m);
    geodetic_from_ecef(o + e * enu.x + n * enu.y + u * enu.z)
}

/// A UTM zone: number 1–60 and hemisphere.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UtmZone {
    /// Zone number, 1–60 (zone 1: 180°W–174°W).
    pub number: u8,
    /// Northern hemisphere (false easting only) or southern (false northing
    /// 10 000 km).
    pub north: bool,
}

impl UtmZone {
    /// The zone of a point (the standard 6° zones, with zone 32V widened
    /// over western Norway, 56°–64°N 3°–12°E, and zones 31X–37X over
    /// Svalbard, 72°–84°N), or `None` outside UTM's latitudes
    /// ([`UTM_LATITUDES_DEG`]; the polar regions use UPS, not provided).
    pub fn of(lat_deg: f64, lon_deg: f64) -> Option<UtmZone> {
        let (lo, hi) = UTM_LATITUDES_DEG;
        if !(lat_deg.is_finite() && lon_deg.is_finite() && lat_deg >= lo && lat_deg < hi) {
            return None;
        }
        let lon = (lon_deg + 180.0).rem_euclid(360.0) - 180.0;
        let mut number = (((lon + 180.0) / 6.0).floor() as i32).clamp(0, 59) + 1;
        if (56.0..64.0).contains(&lat_deg) && (3.0..12.0).contains(&lon) {
            number = 32;
        }
        if lat_deg >= 72.0 && (0.0..42.0).contains(&lon) {
            number = match lon {
                l if l < 9.0 => 31,
                l if l < 21.0 => 33,
                l if l < 33.0 => 35,
                _ => 37,
            };
        }
        Some(UtmZone {
            number: number as u8,
            north: lat_deg >= 0.0,
        })
    }

    /// Longitude of the zone's central meridian, degrees.
    pub fn central_meridian_deg(&self) -> f64 {
        6.0 * self.number as f64 - 183.0
    }

    /// The EPSG code of WGS 84 / UTM in this zone: 326zz north, 327zz south.
    pub fn epsg(&self) -> u16 {
        (if self.north { 32600 } else { 32700 }) + self.number as u16
    }

    /// The zone's name, e.g. `18N`.
    pub fn name(&self) -> String {
        format!("{}{}", self.number, if self.north { 'N' } else { 'S' })
    }

    /// The OGC WKT (version 1, as GDAL writes it) of WGS 84 / UTM in this
    /// zone.
    pub fn wkt(&self) -> String {
        format!(
            "PROJCS[\"WGS 84 / UTM zone {name}\",GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",\
             SPHEROID[\"WGS 84\",6378137,298.257223563,AUTHORITY[\"EPSG\",\"7030\"]],\
             AUTHORITY[\"EPSG\",\"6326\"]],PRIMEM[\"Greenwich\",0,AUTHORITY[\"EPSG\",\"8901\"]],\
             UNIT[\"degree\",0.0174532925199433,AUTHORITY[\"EPSG\",\"9122\"]],\
             AUTHORITY[\"EPSG\",\"4326\"]],PROJECTION[\"Transverse_Mercator\"],\
             PARAMETER[\"latitude_of_origin\",0],PARAMETER[\"central_meridian\",{cm}],\
             PARAMETER[\"scale_factor\",0.9996],PARAMETER[\"false_easting\",500000],\
             PARAMETER[\"false_northing\",{fn_}],UNIT[\"metre\",1,AUTHORITY[\"EPSG\",\"9001\"]],\
             AXIS[\"Easting\",EAST],AXIS[\"Northing\",NORTH],AUTHORITY[\"EPSG\",\"{epsg}\"]]",
            name = self.name(),
            cm = self.central_meridian_deg(),
            fn_ = if self.north { 0 } else { 10_000_000 },
            epsg = self.epsg(),
        )
    }
}

/// Krüger's α coefficients (Karney 2011, eq. 35) to order n⁶.
fn kruger_alpha(n: f64) -> [f64; 6] {
    let (n2, n3) = (n * n, n * n * n);
    let (n4, n5, n6) = (n2 * n2, n2 * n3, n3 * n3);
    [
        n / 2.0 - 2.0 * n2 / 3.0 + 5.0 * n3 / 16.0 + 41.0 * n4 / 180.0 - 127.0 * n5 / 288.0
            + 7891.0 * n6 / 37800.0,
        13.0 * n2 / 48.0 - 3.0 * n3 / 5.0 + 557.0 * n4 / 1440.0 + 281.0 * n5 / 630.0
            - 1_983_433.0 * n6 / 1_935_360.0,
        61.0 * n3 / 240.0 - 103.0 * n4 / 140.0
            + 15061.0 * n5 / 26880.0
            + 167_603.0 * n6 / 181_440.0,
        49561.0 * n4 / 161_280.0 - 179.0 * n5 / 168.0 + 6_601_661.0 * n6 / 7_257_600.0,
        34729.0 * n5 / 80640.0 - 3_418_889.0 * n6 / 1_995_840.0,
        212_378_941.0 * n6 / 319_334_400.0,
    ]
}

/// Transverse Mercator easting and northing (m, scale `k0`, no false
/// origin) of a point `dlon_deg` east of the central meridian at latitude
/// `lat_deg` (Karney 2011, eqs. 7–11).
pub fn transverse_mercator(lat_deg: f64, dlon_deg: f64, k0: f64) -> (f64, f64) {
    let f = WGS84_F;
    let n = f / (2.0 - f);
    let e = e2().sqrt();
    // Rectifying radius A (eq. 14).
    let n2 = n * n;
    let a_r = WGS84_A_M / (1.0 + n) * (1.0 + n2 / 4.0 + n2 * n2 / 64.0 + n2 * n2 * n2 / 256.0);
    let phi = lat_deg.to_radians();
    let lam = dlon_deg.to_radians();
    // Conformal latitude τ' (eq. 7) and the spherical TM (eq. 10).
    let tau = phi.tan();
    let sigma = (e * (e * tau / (1.0 + tau * tau).sqrt()).atanh()).sinh();
    let tau_p = tau * (1.0 + sigma * sigma).sqrt() - sigma * (1.0 + tau * tau).sqrt();
    let xi_p = tau_p.atan2(lam.cos());
    let eta_p = (lam.sin() / (tau_p * tau_p + lam.cos().powi(2)).sqrt()).asinh();
    // Krüger's series (eq. 11).
    let alpha = kruger_alpha(n);
    let (mut xi, mut eta) = (xi_p, eta_p);
    for (j, a) in alpha.iter().enumerate() {
        let k = 2.0 * (j + 1) as f64;
        xi += a * (k * xi_p).sin() * (k * eta_p).cosh();
        eta += a * (k * xi_p).cos() * (k * eta_p).sinh();
    }
    (k0 * a_r * eta, k0 * a_r * xi)
}

/// UTM easting and northing (m) of a geodetic point in zone `zone` (which
/// need not be the point's own: a scene keeps the zone of its site).
///
/// # Errors
/// [`Error::Invalid`] for a non-finite point, or one more than 30° of
/// longitude from the zone's central meridian (where the series no longer
/// holds its accuracy).
pub fn utm_from_geodetic(zone: UtmZone, lat_deg: f64, lon_deg: f64) -> Result<(f64, f64)> {
    let dlon = (lon_deg - zone.central_meridian_deg() + 180.0).rem_euclid(360.0) - 180.0;
    if !(lat_deg.is_finite() && dlon.is_finite()) || dlon.abs() > 30.0 || lat_deg.abs() > 90.0 {
        return Err(Error::invalid(
            "UTM",
            format!(
                "({lat_deg}°, {lon_deg}°) cannot be projected to UTM zone {}",
                zone.name()
            ),
        ));
    }
    let (x, y) = transverse_mercator(lat_deg, dlon, UTM_K0);
    let false_northing = if zone.north {
        0.0
    } else {
        UTM_FALSE_NORTHING_SOUTH_M
    };
    Ok((UTM_FALSE_EASTING_M + x, false_northing + y))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// UTM of published and PROJ-computed points. The first is the example
    /// of GeographicLib's GeoConvert manual (`33.3 44.4` → `38n 444140.54
    /// 3684706.36`); all are checked against PROJ 9.1.1
    /// (`cs2cs -f %.6f EPSG:4326 EPSG:326zz/327zz`), whose extended
    /// transverse Mercator (Poder/Engsager) agrees with Krüger's series to
    /// well under a millimetre inside a zone.
    #[test]
    fn utm_matches_published_points_within_a_millimetre() {
        let cases = [
            (33.3, 44.4, 38, true, 444140.544918, 3684706.355550),
            (43.16, -77.61, 18, true, 287811.200796, 4781889.867966),
            (-33.8688, 151.2093, 56, false, 334368.633648, 6250948.345385),
            (0.5, 2.99, 31, true, 498887.292451, 55265.037990),
            (60.0, 5.0, 32, true, 276979.926401, 6658157.202407),
            (-79.5, -120.0, 11, false, 438993.455565, 1172650.181101),
            (83.9, 12.0, 33, true, 464424.319810, 9317856.466148),
            (43.16, -80.99, 17, true, 500812.965407, 4778582.821793),
        ];
        for (lat, lon, zn, north, e, n) in cases {
            let zone = UtmZone::of(lat, lon).unwrap();
            assert_eq!((zone.number, zone.north), (zn, north), "{lat} {lon}");
            let (ee, nn) = utm_from_geodetic(zone, lat, lon).unwrap();
            assert!(
                (ee - e).abs() < 1e-3 && (nn - n).abs() < 1e-3,
                "{lat} {lon}: {ee} {nn} vs {e} {n}"
            );
        }
        // The published GeoConvert value, to its centimetre.
        let (e, n) = utm_from_geodetic(UtmZone::of(33.3, 44.4).unwrap(), 33.3, 44.4).unwrap();
        assert_eq!(
            (format!("{e:.2}"), format!("{n:.2}")),
            ("444140.54".into(), "3684706.36".into())
        );
    }

    #[test]
    fn zones_and_codes() {
        let z = UtmZone::of(43.16, -77.61).unwrap();
        assert_eq!(
            (z.number, z.epsg(), z.central_meridian_deg()),
            (18, 32618, -75.0)
        );
        assert_eq!(UtmZone::of(-1.0, 179.9).unwrap().epsg(), 32760);
        assert_eq!(UtmZone::of(0.0, -180.0).unwrap().number, 1);
        assert_eq!(UtmZone::of(78.0, 20.0).unwrap().number, 33);
        assert_eq!(UtmZone::of(84.0, 0.0), None);
        assert_eq!(UtmZone::of(-80.5, 0.0), None);
        assert!(z.wkt().contains("AUTHORITY[\"EPSG\",\"32618\"]]"));
    }

    #[test]
    fn enu_and_geodetic_round_trip_below_a_millimetre() {
        let site = Site::new(43.16, -77.61, 160.0).unwrap();
        for p in [
            DVec3::ZERO,
            DVec3::new(1234.5, -987.25, 12.0),
            DVec3::new(-20_000.0, 35_000.0, -50.0),
        ] {
            let (lat, lon, h) = geodetic_from_enu(&site, p);
            let back = enu_from_geodetic(&site, lat, lon, h);
            assert!((back - p).length() < 1e-3, "{p} → {back}");
        }
        let (lat, lon, h) = geodetic_from_enu(&site, DVec3::ZERO);
        assert!((lat - 43.16).abs() < 1e-12 && (lon + 77.61).abs() < 1e-12);
        assert!((h - 160.0).abs() < 1e-6);
        // Near a pole.
        let (lat, _, h) = geodetic_from_ecef(ecef_from_geodetic(89.9999, 10.0, 100.0));
        assert!((lat - 89.9999).abs() < 1e-11 && (h - 100.0).abs() < 1e-6);
    }
}
