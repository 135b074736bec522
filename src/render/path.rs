//! The atmosphere along the sensor's primary rays, tabulated.

use rayon::prelude::*;

use glam::DVec3;

use crate::Result;
use crate::atmosphere::{Atmosphere, PathGeometry, PreparedPaths, Sun, SunColumn};
use crate::radiometry::Band;
use crate::sensor::{Geometry, Sensor};

/// Atmospheric path transmittance τ₂ and path radiance L_u from the sensor
/// to a hit, tabulated per band against the hit's height above the ground
/// datum (the scene's z, m) and the slant range, and interpolated
/// bilinearly (range, then height). Every node is
/// [`Atmosphere::path`] of its (sensor altitude, target altitude, range):
/// the path `irsig atmosphere --sensor-altitude … --target-altitude …
/// --range …` prints (flat-earth geometry, see [`crate::atmosphere`]).
///
/// By day the path radiance holds the single-scattered sunlight
/// ([`crate::atmosphere::scatter`]) of each node's own line-of-sight zenith
/// and one relative azimuth for the whole table, [`PathSun`]'s: the
/// scattering angle of a pixel off the sensor's mean azimuth is
/// approximated (see [`PathSun`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PathTables {
    /// Ranges of the nodes, m (increasing, from 0).
    pub ranges_m: Vec<f64>,
    /// Target heights of the nodes above the ground datum (scene z), m
    /// (increasing; one node for a flat scene).
    pub heights_m: Vec<f64>,
    /// Per band, per node (height `a`, range `i` at `a · ranges + i`):
    /// (τ₂(λ), L_u(λ)) on the band's grid.
    pub bands: Vec<Vec<(Vec<f64>, Vec<f64>)>>,
}

/// The sun for the path tables' scattered sunlight.
///
/// A node knows its line of sight's zenith (from its height and range) but
/// not its azimuth: the table takes the azimuth from the sensor toward the
/// scene's centre, or — for a sensor within 1 % of its height of straight
/// above the centre, where pixels look every way — a relative azimuth of
/// 90°, at which cos Θ = cos θ_sun·cos θ_los, the azimuthal mean.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathSun {
    /// The sun (zenith, azimuth relative to the lines of sight, distance).
    pub sun: Sun,
}

impl PathSun {
    /// The sun toward unit east-north-up `direction` for a sensor at
    /// `sensor` looking at a scene centred on `centre` (scene coordinates,
    /// x east, y north, m); `None` for the sun at or below the horizon. The
    /// sun–earth distance is taken as 1 AU (the render's conditions carry
    /// no date; ±3.4 % in the irradiance over the year).
    pub fn new(direction: DVec3, sensor: DVec3, centre: DVec3) -> Option<PathSun> {
        let d = direction.normalize_or_zero();
        if d.z <= 0.0 {
            return None;
        }
        let sun_az = d.x.atan2(d.y).to_degrees();
        let h = sensor - centre;
        let horizontal = (h.x * h.x + h.y * h.y).sqrt();
        let rel = if horizontal <= 0.01 * h.z.abs() {
            90.0
        } else {
            sun_az - (-h.x).atan2(-h.y).to_degrees()
        };
        Sun::new(d.z.clamp(-1.0, 1.0).acos().to_degrees(), rel, 1.0)
            .ok()
            .map(|sun| PathSun { sun })
    }

    /// [`PathSun::new`] for the sun of a render's conditions (`None` at
    /// night), `sensor` and the scene's geometry (its bounds' centre). The
    /// scattered beam is the clear-sky beam attenuated as the render's
    /// direct sun is: by `c = min(1, DNI / DNI_clear)`, the weather's
    /// measured direct normal irradiance over the modelled clear-sky one
    /// ([`crate::render::shade::surface_solar_spectrum`]), so a cloud that
    /// dims the direct sun dims the sunlight scattered into the path.
    pub fn for_scene(
        sun: Option<&crate::render::shade::SunInput>,
        sensor: &Sensor,
        geometry: &crate::geometry::SceneGeometry,
    ) -> Option<PathSun> {
        let sun = sun?;
        let centre = geometry
            .bounds()
            .map_or(DVec3::ZERO, |(lo, hi)| (0.5 * (lo + hi)).as_dvec3());
        let mut p = PathSun::new(sun.direction.as_dvec3(), sensor_position(sensor), centre)?;
        p.sun = p
            .sun
            .with_attenuation(crate::render::shade::beam_attenuation(sun))
            .ok()?;
        Some(p)
    }
}

fn sensor_position(sensor: &Sensor) -> DVec3 {
    match &sensor.geometry {
        Geometry::Frame(c) => c.position(),
        Geometry::LineScanner(s) => s.position(0.0),
    }
}

impl PathTables {
    /// Nodes of the range table.
    const NODES: usize = 48;
    /// Largest spacing of the height nodes, m. τ₂ and L_u vary with the
    /// target's height on the scale of the water-vapour scale height
    /// (≈ 2 km), so linear interpolation over 25 m errs by
    /// ≈ (25 m)²/8 / (2 km)² ≈ 2·10⁻⁵ relative.
    const HEIGHT_STEP_M: f64 = 25.0;
    /// Most height nodes.
    const MAX_HEIGHTS: usize = 64;

    /// Tables for `sensor` (`None` for no atmosphere: τ₂ = 1, L_u = 0,
    /// nothing to apply). `scene_size_m` bounds the ranges beyond the
    /// sensor's height; `heights_m` (lowest, highest) the heights above
    /// the ground datum of what the sensor can hit (the scene's z extent);
    /// `sun` the sun by day ([`PathSun::for_scene`]; `None` at night or for
    /// the thermal path alone).
    pub fn new(
        atmosphere: &Atmosphere,
        sensor: &Sensor,
        bands: &[Band],
        ground_altitude_m: f64,
        scene_size_m: f64,
        heights_m: (f64, f64),
        sun: Option<&PathSun>,
    ) -> Result<Option<PathTables>> {
        if matches!(atmosphere, Atmosphere::None) {
            return Ok(None);
        }
        let height = sensor_position(sensor).z;
        let max_range = 2.0 * (height.abs() + scene_size_m) + 1.0;
        let ranges_m: Vec<f64> = (0..Self::NODES)
            .map(|i| max_range * (i as f64 / (Self::NODES - 1) as f64).powi(2))
            .collect();
        let (lo, hi) = heights_m;
        let (lo, hi) = if lo.is_finite() && hi.is_finite() && hi >= lo {
            (lo, hi)
        } else {
            (0.0, 0.0)
        };
        let steps = ((hi - lo) / Self::HEIGHT_STEP_M)
            .ceil()
            .clamp(0.0, (Self::MAX_HEIGHTS - 1) as f64) as usize;
        let heights: Vec<f64> = if steps == 0 {
            vec![lo]
        } else {
            (0..=steps)
                .map(|a| lo + (hi - lo) * a as f64 / steps as f64)
                .collect()
        };
        let sensor_alt = ground_altitude_m + height;
        // What the model needs of a band's grid is the same for every node
        // of the band: prepared once per band.
        let path = |b: &PreparedPaths,
                    col: Option<&SunColumn>,
                    target: f64,
                    r: f64|
         -> Result<(Vec<f64>, Vec<f64>)> {
            let p = b.path_sunlit(
                &PathGeometry {
                    sensor_altitude_m: sensor_alt,
                    target_altitude_m: target,
                    range_m: r,
                },
                col,
            )?;
            Ok((p.transmittance, p.path_radiance))
        };
        // Every node is independent: bands, heights and ranges in parallel
        // (the same values as in turn).
        let tables = bands
            .par_iter()
            .map(|b| -> Result<Vec<(Vec<f64>, Vec<f64>)>> {
                let b = &atmosphere.prepare(b.grid());
                // The sun's beam once per band (one slant path).
                let col = sun.map(|s| b.sun_column(&s.sun)).transpose()?.flatten();
                let col = col.as_ref();
                let per_height = heights
                    .par_iter()
                    .map(|&z| -> Result<Vec<(Vec<f64>, Vec<f64>)>> {
                        let target = ground_altitude_m + z;
                        // Ranges below the height difference `d` cannot
                        // reach a target at this height. Their nodes lie on
                        // the line through the vertical path (range d) and
                        // the first node beyond it, so that interpolating
                        // between the last of them and that node gives the
                        // vertical path exactly at d (τ₂ clamped to [0, 1],
                        // L_u to ≥ 0 further out).
                        let d = (sensor_alt - target).abs();
                        let first = ranges_m.partition_point(|&r| r < d).min(ranges_m.len() - 1);
                        let (reach, vertical) = rayon::join(
                            || {
                                ranges_m[first..]
                                    .par_iter()
                                    .map(|&r| path(b, col, target, r.max(d)))
                                    .collect::<Result<Vec<_>>>()
                            },
                            || (first > 0).then(|| path(b, col, target, d)).transpose(),
                        );
                        let (reach, vertical) = (reach?, vertical?);
                        let mut nodes = Vec::with_capacity(ranges_m.len());
                        if let Some((t_d, l_d)) = vertical {
                            let (t_1, l_1) = &reach[0];
                            let r1 = ranges_m[first];
                            for &r in &ranges_m[..first] {
                                let s = if r1 > d { (r - d) / (r1 - d) } else { 0.0 };
                                let line = |x0: &[f64], x1: &[f64], lo: f64, hi: f64| -> Vec<f64> {
                                    x0.iter()
                                        .zip(x1)
                                        .map(|(a, b)| (a + s * (b - a)).clamp(lo, hi))
                                        .collect()
                                };
                                nodes.push((
                                    line(&t_d, t_1, 0.0, 1.0),
                                    line(&l_d, l_1, 0.0, f64::INFINITY),
                                ));
                            }
                        }
                        nodes.extend(reach);
                        Ok(nodes)
                    })
                    .collect::<Result<Vec<_>>>()?;
                Ok(per_height.into_iter().flatten().collect())
            })
            .collect::<Result<Vec<_>>>()?;
        let bands = tables;
        Ok(Some(PathTables {
            ranges_m,
            heights_m: heights,
            bands,
        }))
    }

    /// The nodes bracketing range `r` (m): `(i, t)` with `r` at fraction
    /// `t` (clamped to [0, 1]) from node `i − 1` to node `i`.
    pub fn locate(&self, r: f64) -> (usize, f64) {
        let x = &self.ranges_m;
        let i = x.partition_point(|&v| v <= r).clamp(1, x.len() - 1);
        (i, ((r - x[i - 1]) / (x[i] - x[i - 1])).clamp(0.0, 1.0))
    }

    /// The height nodes bracketing height `z` (m above the ground datum):
    /// `(a, t)` with `z` at fraction `t` (clamped to [0, 1]) from node `a`
    /// to node `a + 1`; `(0, 0)` with one node.
    pub fn locate_height(&self, z: f64) -> (usize, f64) {
        let x = &self.heights_m;
        if x.len() < 2 {
            return (0, 0.0);
        }
        let a = x
            .partition_point(|&v| v <= z)
            .saturating_sub(1)
            .min(x.len() - 2);
        (a, ((z - x[a]) / (x[a + 1] - x[a])).clamp(0.0, 1.0))
    }

    /// Index of the node at height node `a`, range node `i`.
    #[inline]
    pub fn node(&self, a: usize, i: usize) -> usize {
        a * self.ranges_m.len() + i
    }

    /// τ₂ and L_u of band `b` at range `r` (m) and target height `z` (m
    /// above the ground datum), interpolated as [`PathTables::apply`].
    pub fn at(&self, b: usize, r: f64, z: f64) -> (Vec<f64>, Vec<f64>) {
        let n = self.bands[b][0].0.len();
        let mut tau = vec![0.0; n];
        let mut lu = vec![0.0; n];
        self.each(b, r, z, |j, t, l| {
            tau[j] = t;
            lu[j] = l;
        });
        (tau, lu)
    }

    /// Call `f(j, τ₂, L_u)` for every wavelength `j` of band `b` at range
    /// `r`, height `z`: linear in range at each bracketing height node,
    /// then linear in height.
    fn each(&self, b: usize, r: f64, z: f64, mut f: impl FnMut(usize, f64, f64)) {
        let (i, t) = self.locate(r);
        let (a, u) = self.locate_height(z);
        let lerp = |x: f64, y: f64, s: f64| x + s * (y - x);
        let at = |a: usize| {
            let (t0, l0) = &self.bands[b][self.node(a, i - 1)];
            let (t1, l1) = &self.bands[b][self.node(a, i)];
            (t0, l0, t1, l1)
        };
        let (t0, l0, t1, l1) = at(a);
        if self.heights_m.len() < 2 {
            for j in 0..t0.len() {
                f(j, lerp(t0[j], t1[j], t), lerp(l0[j], l1[j], t));
            }
            return;
        }
        let (s0, m0, s1, m1) = at(a + 1);
        for j in 0..t0.len() {
            let tau = lerp(lerp(t0[j], t1[j], t), lerp(s0[j], s1[j], t), u);
            let lu = lerp(lerp(l0[j], l1[j], t), lerp(m0[j], m1[j], t), u);
            f(j, tau, lu);
        }
    }

    /// Apply the path of range `r` (m) to a target at height `z` (m above
    /// the ground datum) to band `b`'s leaving spectrum in place:
    /// `L ← L·τ₂ + L_u`.
    pub fn apply(&self, b: usize, r: f64, z: f64, spectrum: &mut [f64]) {
        self.each(b, r, z, |j, tau, lu| {
            spectrum[j] = spectrum[j] * tau + lu;
        });
    }
}

/// The heights above the ground datum (lowest, highest) of a scene's
/// geometry, m: the height range of [`PathTables::new`]; `(0, 0)` for an
/// empty scene.
pub fn scene_heights(geometry: &crate::geometry::SceneGeometry) -> (f64, f64) {
    geometry
        .bounds()
        .map_or((0.0, 0.0), |(lo, hi)| (lo.z as f64, hi.z as f64))
}
