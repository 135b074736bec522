//! Where a sensor's written image lies on the map: [`georeference`] fits
//! the affine pixel → map transform of [`crate::output::Georef`] to the
//! sensor's exact lines of sight, where the geometry allows.
//!
//! The rule. The map is WGS 84 / UTM in the zone of the scene's site
//! ([`crate::geodesy::UtmZone::of`]; one zone for the whole image, even
//! where it spills into the next), or, beyond UTM's latitudes (84°N,
//! 80°S), the scene's own east-north-up plane in metres from the site. The
//! surface mapped is the horizontal plane `z = 0` (the site altitude):
//! things standing above it are displaced in the image as in any
//! perspective image (relief displacement). The transform is made from the
//! ground points of three image corners (upper-left, upper-right,
//! lower-left) and checked against the exact ground points of a 9 × 9 grid
//! over the image; it is given only when every one lies within
//! [`MAX_ERROR_PX`] of where the transform puts it. A nadir frame camera
//! passes (its image of a plane is exactly affine); oblique cameras
//! (perspective) and wide line scanners (panoramic distortion) do not.
//!
//! Takes a sensor and the site; gives a georeference or none. Knows
//! nothing of the scene's geometry (the plane is the datum, not the
//! terrain).

use glam::DVec3;

use super::{Geometry, Sensor};
use crate::geodesy::{UtmZone, geodetic_from_enu, utm_from_geodetic};
use crate::output::{Georef, MapSystem};
use crate::sun::Site;

/// Largest distance (pixels) between the affine transform and the exact
/// ground point anywhere on the image for a georeference to be given.
pub const MAX_ERROR_PX: f64 = 0.1;

/// The georeference of `sensor`'s written image (after its
/// [`super::Orientation`]) for a scene at `site`, or `None` where no
/// affine transform is within [`MAX_ERROR_PX`] of the exact projection (see
/// the module docs for the rule).
pub fn georeference(sensor: &Sensor, site: &Site) -> Option<Georef> {
    let (w, h) = (sensor.width() as f64, sensor.height() as f64);
    let system = match UtmZone::of(site.latitude_deg, site.longitude_deg) {
        Some(z) => MapSystem::Utm(z),
        None => MapSystem::LocalEnu {
            latitude_deg: site.latitude_deg,
            longitude_deg: site.longitude_deg,
        },
    };
    let to_map = |p: DVec3| -> Option<(f64, f64)> {
        match system {
            MapSystem::Utm(z) => {
                let (lat, lon, _) = geodetic_from_enu(site, p);
                utm_from_geodetic(z, lat, lon).ok()
            }
            MapSystem::LocalEnu { .. } => Some((p.x, p.y)),
        }
    };
    // Map point of continuous written-image point (u, v).
    let map = |u: f64, v: f64| -> Option<(f64, f64)> {
        let (su, sv) = sensor.orientation.apply(u, v, w, h);
        to_map(sensor.ground_point(su, sv, 0.0)?)
    };
    let o = map(0.0, 0.0)?;
    let a = map(w, 0.0)?;
    let b = map(0.0, h)?;
    let transform = [
        o.0,
        (a.0 - o.0) / w,
        (b.0 - o.0) / h,
        o.1,
        (a.1 - o.1) / w,
        (b.1 - o.1) / h,
    ];
    let mut georef = Georef {
        system,
        transform,
        max_error_px: 0.0,
        size: (sensor.width(), sensor.height()),
        note: String::new(),
    };
    let mut worst = 0.0f64;
    for i in 0..=8 {
        for j in 0..=8 {
            let (u, v) = (w * i as f64 / 8.0, h * j as f64 / 8.0);
            let (x, y) = map(u, v)?;
            let (pu, pv) = georef.pixel_of_map(x, y)?;
            worst = worst.max((pu - u).hypot(pv - v));
        }
    }
    if worst.is_nan() || worst > MAX_ERROR_PX {
        return None;
    }
    georef.max_error_px = worst;
    let what = match &sensor.geometry {
        Geometry::Frame(_) => "frame camera".to_string(),
        Geometry::LineScanner(_) if sensor.orientation.is_identity() => {
            "line scanner, as flown (row 0 = first line, column 0 = port)".to_string()
        }
        Geometry::LineScanner(_) => format!(
            "line scanner, north-up ({} reversed from as flown)",
            if sensor.orientation.flip_rows {
                "rows"
            } else {
                "columns"
            },
        ),
    };
    georef.note = format!(
        "{what}; ground plane z = 0 (site altitude {} m); things above it are displaced",
        site.altitude_m
    );
    Some(georef)
}
