//! Truth points in latitude/longitude: to the scene's east-north-up frame
//! and through a sensor to a pixel.
//!
//! The scene's world frame is the local tangent plane (ENU, metres) at the
//! site (latitude, longitude, altitude = z 0); the conversions are
//! [`crate::geodesy`]'s.

use glam::{DVec2, DVec3};

use super::csv::{PointPosition, TruthPoint};
use crate::render::session::Session;
use crate::sensor::Geometry;
use crate::trace::{Coherence, Ray};
use crate::{Error, Location, Result};

pub use crate::geodesy::{WGS84_A_M, WGS84_F, ecef_from_geodetic, enu_from_geodetic};

/// The continuous image coordinates in sensor `s` of the scene surface at
/// latitude/longitude: the point goes to ENU at the site's altitude, drops
/// vertically onto the scene's top surface (ground beyond the scene:
/// z at the site's altitude), and is projected through the sensor into its
/// written image (after its orientation flip).
///
/// # Errors
/// The point is behind the sensor, outside its image, or hidden from the
/// sensor by the scene (naming `what`).
pub fn pixel_of_latlon(
    session: &Session,
    s: usize,
    lat_deg: f64,
    lon_deg: f64,
    what: &Location,
) -> Result<DVec2> {
    let site = session.scene.site;
    let enu = enu_from_geodetic(&site, lat_deg, lon_deg, site.altitude_m);
    let top = session
        .scene
        .geometry
        .bounds()
        .map(|(_, hi)| hi.z as f64 + 10.0)
        .unwrap_or(10.0)
        .max(enu.z + 10.0);
    let ray = Ray::new(
        DVec3::new(enu.x, enu.y, top).as_vec3(),
        glam::Vec3::new(0.0, 0.0, -1.0),
    );
    let mut hit = [None];
    session
        .tracer
        .intersect(&[ray], Coherence::Incoherent, &mut hit);
    let p = match hit[0] {
        Some(h) => DVec3::new(enu.x, enu.y, top - h.t as f64),
        None => enu,
    };
    let sensor = &session.sensors[s];
    let (w, h) = (sensor.width() as f64, sensor.height() as f64);
    match sensor.project_written(p) {
        Some(uv) if uv.x >= 0.0 && uv.y >= 0.0 && uv.x < w && uv.y < h => {
            // Seen, or hidden behind something nearer the sensor?
            let eye = match &sensor.geometry {
                Geometry::Frame(c) => c.position(),
                Geometry::LineScanner(l) => {
                    let (s, line) = sensor.orientation.apply(uv.x, uv.y, w, h);
                    l.ray(line as usize, s, 0.0).origin.as_dvec3()
                }
            };
            let to_eye = eye - p;
            let dist = to_eye.length();
            let lift = 1e-3 * dist.max(1.0);
            let ray = Ray {
                origin: (p + to_eye / dist * lift).as_vec3(),
                dir: (to_eye / dist).as_vec3(),
                tnear: 0.0,
                tfar: (dist - 2.0 * lift).max(0.0) as f32,
            };
            let mut blocked = [false];
            session
                .tracer
                .occluded(&[ray], Coherence::Incoherent, &mut blocked);
            if blocked[0] {
                return Err(Error::parse(
                    what.clone(),
                    format!(
                        "({lat_deg}, {lon_deg}) = ENU ({:.1}, {:.1}, {:.1}) m is hidden from sensor `{}` by the scene (pixel ({:.1}, {:.1}) sees something nearer)",
                        p.x, p.y, p.z, sensor.name, uv.x, uv.y
                    ),
                ));
            }
            Ok(uv)
        }
        Some(uv) => Err(Error::parse(
            what.clone(),
            format!(
                "({lat_deg}, {lon_deg}) = ENU ({:.1}, {:.1}, {:.1}) m falls at pixel ({:.1}, {:.1}), outside the {w}×{h} image of sensor `{}`",
                p.x, p.y, p.z, uv.x, uv.y, sensor.name
            ),
        )),
        None => Err(Error::parse(
            what.clone(),
            format!(
                "({lat_deg}, {lon_deg}) = ENU ({:.1}, {:.1}, {:.1}) m is not in view of sensor `{}`",
                p.x, p.y, p.z, sensor.name
            ),
        )),
    }
}

/// `points` with lat/lon positions replaced by their pixel in sensor `s`
/// ([`pixel_of_latlon`]); errors name `file` and the point's line.
pub fn points_to_pixels(
    session: &Session,
    s: usize,
    points: &[TruthPoint],
    file: &std::path::Path,
) -> Result<Vec<TruthPoint>> {
    points
        .iter()
        .map(|p| match p.position {
            PointPosition::Pixel { .. } => Ok(p.clone()),
            PointPosition::LatLon { lat, lon } => {
                let at = Location::file(file).at_line(p.line).with_field("lat");
                let uv = pixel_of_latlon(session, s, lat, lon, &at)?;
                Ok(TruthPoint {
                    position: PointPosition::Pixel { x: uv.x, y: uv.y },
                    ..p.clone()
                })
            }
        })
        .collect()
}
