//! The atmosphere along the sensor's primary rays, tabulated.

use rayon::prelude::*;

use glam::DVec3;

use crate::Result;
use crate::atmosphere::{
    ANGLE_NODES, Atmosphere, PathGeometry, PreparedPaths, Sun, SunColumn, angle_node,
    angle_node_cos,
};
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
/// By day the single-scattered sunlight ([`crate::atmosphere::scatter`])
/// is tabulated apart, [`PathScatter`]: per node against the scattering
/// angle Θ on [`ANGLE_NODES`] nodes, so that each pixel adds the
/// scattered sunlight of its own Θ (cos Θ = ŝ·l̂, ŝ toward the sun, l̂ the
/// ray's direction), linear in `sin(Θ/2)` between the nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct PathTables {
    /// Ranges of the nodes, m (increasing, from 0).
    pub ranges_m: Vec<f64>,
    /// Target heights of the nodes above the ground datum (scene z), m
    /// (increasing; one node for a flat scene).
    pub heights_m: Vec<f64>,
    /// Per band, per node (height `a`, range `i` at `a · ranges + i`):
    /// (τ₂(λ), L_u(λ)) on the band's grid; L_u thermal only.
    pub bands: Vec<Vec<(Vec<f64>, Vec<f64>)>>,
    /// The single-scattered sunlight, by day (`None`: at night, or no
    /// scattering model).
    pub scatter: Option<PathScatter>,
}

/// The single-scattered sunlight of the path tables' nodes against the
/// scattering angle.
#[derive(Debug, Clone, PartialEq)]
pub struct PathScatter {
    /// Unit vector toward the sun (scene coordinates: x east, y north,
    /// z up).
    pub sun_direction: [f64; 3],
    /// Per band, per node (as [`PathTables::bands`]), per scattering-angle
    /// node `k` ([`angle_node_cos`]): L_ss(λ) on the band's grid,
    /// W·m⁻²·sr⁻¹·µm⁻¹.
    pub bands: Vec<Vec<Vec<Vec<f64>>>>,
}

impl PathScatter {
    /// cos Θ for a ray of direction `dir` (from the sensor; any length):
    /// `ŝ·d/|d|` (1 for a zero direction).
    #[inline]
    pub fn cos_theta(&self, dir: [f64; 3]) -> f64 {
        let s = self.sun_direction;
        let len = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
        if len > 0.0 {
            (s[0] * dir[0] + s[1] * dir[1] + s[2] * dir[2]) / len
        } else {
            1.0
        }
    }
}

/// The sun for the path tables' scattered sunlight: its zenith (the
/// relative azimuth of [`Sun`] is unused: each node is tabulated at every
/// scattering angle) and its direction, for each ray's own angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathSun {
    /// The sun (zenith, distance, beam attenuation).
    pub sun: Sun,
    /// Unit vector toward the sun (x east, y north, z up).
    pub direction: DVec3,
}

impl PathSun {
    /// The sun toward east-north-up `direction`; `None` for the sun at or
    /// below the horizon. The sun–earth distance is taken as 1 AU (the
    /// render's conditions carry no date; ±3.4 % in the irradiance over
    /// the year).
    pub fn new(direction: DVec3) -> Option<PathSun> {
        let d = direction.normalize_or_zero();
        if d.z <= 0.0 {
            return None;
        }
        Sun::new(d.z.clamp(-1.0, 1.0).acos().to_degrees(), 0.0, 1.0)
            .ok()
            .map(|sun| PathSun { sun, direction: d })
    }

    /// [`PathSun::new`] for the sun of a render's conditions (`None` at
    /// night). The scattered beam is the clear-sky beam attenuated as the
    /// render's direct sun is: by `c = min(1, DNI / DNI_clear)`, the
    /// weather's measured direct normal irradiance over the modelled
    /// clear-sky one ([`crate::render::shade::surface_solar_spectrum`]), so
    /// a cloud that dims the direct sun dims the sunlight scattered into
    /// the path; `None` where that leaves no beam.
    pub fn for_scene(sun: Option<&crate::render::shade::SunInput>) -> Option<PathSun> {
        let sun = sun?;
        let mut p = PathSun::new(sun.direction.as_dvec3())?;
        let c = crate::render::shade::beam_attenuation(sun);
        if c <= 0.0 {
            return None;
        }
        p.sun = p.sun.with_attenuation(c).ok()?;
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
        let cos_nodes: Vec<f64> = (0..ANGLE_NODES).map(angle_node_cos).collect();
        // One node: τ₂, the thermal L_u and, by day, L_ss at every
        // scattering-angle node.
        type Node = (Vec<f64>, Vec<f64>, Option<Vec<Vec<f64>>>);
        // What the model needs of a band's grid is the same for every node
        // of the band: prepared once per band.
        let path =
            |b: &PreparedPaths, col: Option<&SunColumn>, target: f64, r: f64| -> Result<Node> {
                let (p, ss) = b.path_sunlit_angles(
                    &PathGeometry {
                        sensor_altitude_m: sensor_alt,
                        target_altitude_m: target,
                        range_m: r,
                    },
                    col,
                    &cos_nodes,
                )?;
                Ok((p.transmittance, p.path_radiance, ss))
            };
        // Every node is independent: bands, heights and ranges in parallel
        // (the same values as in turn).
        let tables = bands
            .par_iter()
            .map(|b| -> Result<Vec<Node>> {
                let b = &atmosphere.prepare(b.grid());
                // The sun's beam once per band (one slant path).
                let col = sun.map(|s| b.sun_column(&s.sun)).transpose()?.flatten();
                let col = col.as_ref();
                let per_height = heights
                    .par_iter()
                    .map(|&z| -> Result<Vec<Node>> {
                        let target = ground_altitude_m + z;
                        // Ranges below the height difference `d` cannot
                        // reach a target at this height. Their nodes lie on
                        // the line through the vertical path (range d) and
                        // the first node beyond it, so that interpolating
                        // between the last of them and that node gives the
                        // vertical path exactly at d (τ₂ clamped to [0, 1],
                        // L_u and L_ss to ≥ 0 further out).
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
                        if let Some((t_d, l_d, s_d)) = vertical {
                            let (t_1, l_1, s_1) = &reach[0];
                            let r1 = ranges_m[first];
                            for &r in &ranges_m[..first] {
                                let s = if r1 > d { (r - d) / (r1 - d) } else { 0.0 };
                                let line = |x0: &[f64], x1: &[f64], lo: f64, hi: f64| -> Vec<f64> {
                                    x0.iter()
                                        .zip(x1)
                                        .map(|(a, b)| (a + s * (b - a)).clamp(lo, hi))
                                        .collect()
                                };
                                let ss = match (&s_d, s_1) {
                                    (Some(a), Some(b)) => Some(
                                        a.iter()
                                            .zip(b)
                                            .map(|(a, b)| line(a, b, 0.0, f64::INFINITY))
                                            .collect(),
                                    ),
                                    _ => None,
                                };
                                nodes.push((
                                    line(&t_d, t_1, 0.0, 1.0),
                                    line(&l_d, l_1, 0.0, f64::INFINITY),
                                    ss,
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
        let lit = tables.iter().flatten().all(|n| n.2.is_some()) && !tables.is_empty();
        let mut scatter = Vec::with_capacity(tables.len());
        let bands = tables
            .into_iter()
            .map(|nodes| {
                let (paths, ss): (Vec<_>, Vec<_>) =
                    nodes.into_iter().map(|(t, l, s)| ((t, l), s)).unzip();
                if lit {
                    scatter.push(ss.into_iter().map(Option::unwrap_or_default).collect());
                }
                paths
            })
            .collect();
        let scatter = match sun {
            Some(s) if lit => Some(PathScatter {
                sun_direction: s.direction.to_array(),
                bands: scatter,
            }),
            _ => None,
        };
        Ok(Some(PathTables {
            ranges_m,
            heights_m: heights,
            bands,
            scatter,
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
    /// above the ground datum), the scattered sunlight at cos Θ =
    /// `cos_theta` included in L_u (by day), interpolated as
    /// [`PathTables::apply`].
    pub fn at(&self, b: usize, r: f64, z: f64, cos_theta: f64) -> (Vec<f64>, Vec<f64>) {
        let n = self.bands[b][0].0.len();
        let mut tau = vec![0.0; n];
        let mut lu = vec![0.0; n];
        self.each(b, r, z, cos_theta, |j, t, l| {
            tau[j] = t;
            lu[j] = l;
        });
        (tau, lu)
    }

    /// Call `f(j, τ₂, L_u)` for every wavelength `j` of band `b` at range
    /// `r`, height `z`: linear in range at each bracketing height node,
    /// then linear in height; by day L_u holds the scattered sunlight at
    /// cos Θ = `cos_theta`, linear in `sin(Θ/2)` between the angle nodes
    /// ([`angle_node`]) first, then in range and height as the rest.
    fn each(&self, b: usize, r: f64, z: f64, cos_theta: f64, mut f: impl FnMut(usize, f64, f64)) {
        let (i, t) = self.locate(r);
        let (a, u) = self.locate_height(z);
        let (k, w) = angle_node(cos_theta);
        let lerp = |x: f64, y: f64, s: f64| x + s * (y - x);
        let ss = self.scatter.as_ref().map(|s| &s.bands[b]);
        // L_ss at wavelength j of node n, at the angle.
        let ss_at = |n: usize, j: usize| ss.map_or(0.0, |s| lerp(s[n][k][j], s[n][k + 1][j], w));
        let at = |a: usize| {
            let (n0, n1) = (self.node(a, i - 1), self.node(a, i));
            let (t0, l0) = &self.bands[b][n0];
            let (t1, l1) = &self.bands[b][n1];
            move |j: usize| {
                (
                    lerp(t0[j], t1[j], t),
                    lerp(l0[j] + ss_at(n0, j), l1[j] + ss_at(n1, j), t),
                )
            }
        };
        let n = self.bands[b][0].0.len();
        let lo = at(a);
        if self.heights_m.len() < 2 {
            for j in 0..n {
                let (tau, lu) = lo(j);
                f(j, tau, lu);
            }
            return;
        }
        let hi = at(a + 1);
        for j in 0..n {
            let ((t0, l0), (t1, l1)) = (lo(j), hi(j));
            f(j, lerp(t0, t1, u), lerp(l0, l1, u));
        }
    }

    /// Apply the path of range `r` (m) to a target at height `z` (m above
    /// the ground datum), seen along a ray of scattering-angle cosine
    /// `cos_theta` ([`PathScatter::cos_theta`]; unused at night), to band
    /// `b`'s leaving spectrum in place: `L ← L·τ₂ + L_u + L_ss(Θ)`.
    pub fn apply(&self, b: usize, r: f64, z: f64, cos_theta: f64, spectrum: &mut [f64]) {
        self.each(b, r, z, cos_theta, |j, tau, lu| {
            spectrum[j] = spectrum[j] * tau + lu;
        });
    }

    /// cos Θ of a ray of direction `dir` from the sensor
    /// ([`PathScatter::cos_theta`]; 1 at night).
    pub fn cos_theta(&self, dir: [f64; 3]) -> f64 {
        self.scatter.as_ref().map_or(1.0, |s| s.cos_theta(dir))
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
