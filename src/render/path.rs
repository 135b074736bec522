//! The atmosphere along the sensor's primary rays, tabulated.

use crate::Result;
use crate::atmosphere::{Atmosphere, PathGeometry};
use crate::radiometry::Band;
use crate::sensor::{Geometry, Sensor};

/// Atmospheric path transmittance τ₂ and path radiance L_u from the sensor
/// to a hit, tabulated per band against the slant range (targets at the
/// site's ground level; flat-earth geometry, see [`crate::atmosphere`]) and
/// interpolated linearly in range.
#[derive(Debug, Clone, PartialEq)]
pub struct PathTables {
    /// Ranges of the nodes, m (increasing, from 0).
    pub ranges_m: Vec<f64>,
    /// Per band, per node: (τ₂(λ), L_u(λ)) on the band's grid.
    pub bands: Vec<Vec<(Vec<f64>, Vec<f64>)>>,
}

impl PathTables {
    /// Nodes of the range table.
    const NODES: usize = 48;

    /// Tables for `sensor` (`None` for no atmosphere: τ₂ = 1, L_u = 0,
    /// nothing to apply). `scene_size_m` bounds the ranges beyond the
    /// sensor's height.
    pub fn new(
        atmosphere: &Atmosphere,
        sensor: &Sensor,
        bands: &[Band],
        ground_altitude_m: f64,
        scene_size_m: f64,
    ) -> Result<Option<PathTables>> {
        if matches!(atmosphere, Atmosphere::None) {
            return Ok(None);
        }
        let height = match &sensor.geometry {
            Geometry::Frame(c) => c.position().z,
            Geometry::LineScanner(s) => s.position(0.0).z,
        };
        let max_range = 2.0 * (height.abs() + scene_size_m) + 1.0;
        let ranges_m: Vec<f64> = (0..Self::NODES)
            .map(|i| max_range * (i as f64 / (Self::NODES - 1) as f64).powi(2))
            .collect();
        let sensor_alt = ground_altitude_m + height;
        let bands = bands
            .iter()
            .map(|b| {
                ranges_m
                    .iter()
                    .map(|&r| {
                        let p = atmosphere.path(
                            &PathGeometry {
                                sensor_altitude_m: sensor_alt,
                                target_altitude_m: ground_altitude_m,
                                // Nodes nearer than the sensor's height above the
                                // ground are unreachable for ground targets: clamp
                                // them to the shortest possible (vertical) path.
                                range_m: r.max((sensor_alt - ground_altitude_m).abs()),
                            },
                            b.grid(),
                        )?;
                        Ok((p.transmittance, p.path_radiance))
                    })
                    .collect::<Result<Vec<_>>>()
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Some(PathTables { ranges_m, bands }))
    }

    /// The nodes bracketing range `r` (m): `(i, t)` with `r` at fraction
    /// `t` (clamped to [0, 1]) from node `i − 1` to node `i`.
    pub fn locate(&self, r: f64) -> (usize, f64) {
        let x = &self.ranges_m;
        let i = x.partition_point(|&v| v <= r).clamp(1, x.len() - 1);
        (i, ((r - x[i - 1]) / (x[i] - x[i - 1])).clamp(0.0, 1.0))
    }

    /// Apply the path of range `r` to band `b`'s leaving spectrum in place:
    /// `L ← L·τ₂ + L_u`.
    pub fn apply(&self, b: usize, r: f64, spectrum: &mut [f64]) {
        let (i, t) = self.locate(r);
        let (t0, l0) = &self.bands[b][i - 1];
        let (t1, l1) = &self.bands[b][i];
        for (j, v) in spectrum.iter_mut().enumerate() {
            let tau = t0[j] + t * (t1[j] - t0[j]);
            let lu = l0[j] + t * (l1[j] - l0[j]);
            *v = *v * tau + lu;
        }
    }
}
