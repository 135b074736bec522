//! Airborne whiskbroom line scanner with panoramic geometry (the Bendix-style
//! scanner of the original irsig seed).
//!
//! A mirror rotating about the aircraft's flight (forward) axis sweeps the
//! detector's instantaneous field of view (IFOV) across track; each
//! revolution records one scan line of `samples_per_line` samples spread
//! evenly over the total scan angle `A`, so sample `s` looks at scan angle
//! `θ = (s + ½ − S/2)·A/S` from the body's down axis (positive to
//! starboard). The aircraft flies on, so line `l` is taken at time
//! `t_l = start_time + l / scan_rate` from its own position: equal angular
//! steps give ground steps growing as `h·Δθ / cos²θ` across track (panoramic
//! distortion; Schott, *Remote Sensing: The Image Chain Approach*, 2nd ed.,
//! §3.3; Lillesand & Kiefer, *Remote Sensing and Image Interpretation*, §4.4).
//!
//! With `mirror_sweep` on, sample times within a line follow the mirror:
//! one revolution per line, so the sample at scan angle `θ` is taken
//! `(θ + A/2) / (2π·scan_rate)` seconds after the line start (the aircraft
//! moves during the sweep). Off (default), a whole line is taken at `t_l`.
//!
//! Frames: the aircraft body axes are forward–right–down (FRD). `heading`
//! (clockwise from north) sets the ground track and the zero-attitude body
//! axes; `roll` (right wing down positive), `pitch` (nose up positive) and
//! `yaw` (nose right positive, i.e. crab) rotate the body from there in the
//! aerospace z-y-x order: `nav_from_body = Rz(yaw)·Ry(pitch)·Rx(roll)`.
//! The ground track stays along `heading` at `ground_speed`, the aircraft at
//! constant `altitude` above the world origin's `z = 0`, on a flat Earth.
//!
//! Continuous image coordinates follow the frame camera's: line `l`, sample
//! `s` covers `[l, l+1) × [s, s+1)`, its centre at `(l + ½, s + ½)`.

use glam::{DMat3, DVec2, DVec3, Vec3};

use super::Derived;
use crate::trace::Ray;
use crate::{Error, Result};

/// A built line scanner (angles in radians, SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct LineScanner {
    /// Instantaneous field of view (square), rad.
    pub ifov_rad: f64,
    /// Total scan angle (edge to edge), rad.
    pub scan_angle_rad: f64,
    /// Samples per scan line.
    pub samples_per_line: usize,
    /// Number of lines.
    pub lines: usize,
    /// Lines (mirror revolutions) per second.
    pub scan_rate_hz: f64,
    /// Aircraft altitude above `z = 0`, m.
    pub altitude_m: f64,
    /// Ground speed along the track, m/s.
    pub ground_speed_m_s: f64,
    /// Ground track direction, clockwise from north, rad.
    pub heading_rad: f64,
    /// Aircraft → world rotation (columns: body forward, right, down in ENU).
    pub world_from_body: DMat3,
    /// Aircraft ground position (east, north) at `start_time_s`, m.
    pub start: DVec2,
    /// Time of line 0 relative to the scene time, s.
    pub start_time_s: f64,
    /// Whether samples within a line are taken at the mirror's sweep times.
    pub mirror_sweep: bool,
    /// Sub-sample rays per side (`N×N` rays per sample).
    pub oversample: usize,
    /// World directions and sweep delays of one line's sub-samples,
    /// computed once (every line has the same), with the key of the fields
    /// they depend on.
    scan: Box<Derived<[u64; SCAN_KEY_LEN], ScanTable>>,
}

/// The world direction and sweep delay of each of a line's sub-samples.
#[derive(Clone, PartialEq, Default)]
struct ScanTable {
    /// Per sub-line `j` (`N` of them), the world direction of each
    /// sub-sample ([`LineScanner::direction_of`]): the attitude is fixed,
    /// so every line has the same.
    dirs: Vec<Vec3>,
    /// Sweep delay ([`LineScanner::sweep_delay`]) of each sub-sample, s.
    delays: Vec<f64>,
}

/// Length of [`LineScanner::scan_key`].
const SCAN_KEY_LEN: usize = 15;

impl std::fmt::Debug for ScanTable {
    /// A summary: the table is derived from the scanner's other fields.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "ScanTable({} sweep delays, {} directions)",
            self.delays.len(),
            self.dirs.len()
        )
    }
}

/// Parameters of [`LineScanner::new`] (angles in radians).
#[derive(Debug, Clone, PartialEq)]
pub struct LineScannerParams {
    /// IFOV, rad.
    pub ifov_rad: f64,
    /// Total scan angle, rad.
    pub scan_angle_rad: f64,
    /// Samples per line.
    pub samples_per_line: usize,
    /// Lines.
    pub lines: usize,
    /// Lines per second.
    pub scan_rate_hz: f64,
    /// Altitude, m.
    pub altitude_m: f64,
    /// Ground speed, m/s.
    pub ground_speed_m_s: f64,
    /// Heading, rad clockwise from north.
    pub heading_rad: f64,
    /// Roll, pitch, yaw, rad.
    pub roll_pitch_yaw_rad: [f64; 3],
    /// Start ground position (east, north), m.
    pub start: DVec2,
    /// Time of line 0, s.
    pub start_time_s: f64,
    /// Model the mirror sweep time within a line.
    pub mirror_sweep: bool,
    /// Oversampling factor.
    pub oversample: usize,
}

/// `nav_from_body` for aerospace roll/pitch/yaw (FRD axes, z-y-x order).
fn attitude(roll: f64, pitch: f64, yaw: f64) -> DMat3 {
    DMat3::from_rotation_z(yaw) * DMat3::from_rotation_y(pitch) * DMat3::from_rotation_x(roll)
}

impl LineScanner {
    /// Build and validate a scanner.
    pub fn new(p: &LineScannerParams) -> Result<Self> {
        let positive = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(
                    name,
                    format!("{v}: expected a positive number"),
                ))
            }
        };
        positive("ifov_rad", p.ifov_rad)?;
        positive("scan_angle_deg", p.scan_angle_rad)?;
        positive("scan_rate_hz", p.scan_rate_hz)?;
        positive("altitude_m", p.altitude_m)?;
        if p.scan_angle_rad >= std::f64::consts::PI {
            return Err(Error::invalid(
                "scan_angle_deg",
                format!(
                    "{}°: expected less than 180° (the scan must stay below the horizon)",
                    p.scan_angle_rad.to_degrees()
                ),
            ));
        }
        if !(p.ground_speed_m_s.is_finite() && p.ground_speed_m_s >= 0.0) {
            return Err(Error::invalid(
                "ground_speed_m_s",
                format!("{}: expected a non-negative speed", p.ground_speed_m_s),
            ));
        }
        if p.samples_per_line == 0 || p.lines == 0 || p.oversample == 0 {
            return Err(Error::invalid(
                "samples_per_line/lines/oversample",
                "expected at least 1 each",
            ));
        }
        let [roll, pitch, yaw] = p.roll_pitch_yaw_rad;
        for (n, v) in [("roll_deg", roll), ("pitch_deg", pitch), ("yaw_deg", yaw)] {
            if !v.is_finite() || v.abs() >= std::f64::consts::FRAC_PI_2 {
                return Err(Error::invalid(
                    n,
                    format!("{}°: expected |angle| < 90°", v.to_degrees()),
                ));
            }
        }
        let (sh, ch) = p.heading_rad.sin_cos();
        let nav = DMat3::from_cols(
            DVec3::new(sh, ch, 0.0),
            DVec3::new(ch, -sh, 0.0),
            DVec3::new(0.0, 0.0, -1.0),
        );
        let mut scanner = LineScanner {
            ifov_rad: p.ifov_rad,
            scan_angle_rad: p.scan_angle_rad,
            samples_per_line: p.samples_per_line,
            lines: p.lines,
            scan_rate_hz: p.scan_rate_hz,
            altitude_m: p.altitude_m,
            ground_speed_m_s: p.ground_speed_m_s,
            heading_rad: p.heading_rad,
            world_from_body: nav * attitude(roll, pitch, yaw),
            start: p.start,
            start_time_s: p.start_time_s,
            mirror_sweep: p.mirror_sweep,
            oversample: p.oversample,
            scan: Box::default(),
        };
        scanner.scan = Box::new(Derived::new(scanner.scan_key(), scanner.scan_table()));
        Ok(scanner)
    }

    /// The fields the scan table depends on.
    fn scan_key(&self) -> [u64; SCAN_KEY_LEN] {
        let m = self.world_from_body.to_cols_array();
        [
            self.ifov_rad.to_bits(),
            self.scan_angle_rad.to_bits(),
            self.samples_per_line as u64,
            self.oversample as u64,
            self.scan_rate_hz.to_bits(),
            self.mirror_sweep as u64,
            m[0].to_bits(),
            m[1].to_bits(),
            m[2].to_bits(),
            m[3].to_bits(),
            m[4].to_bits(),
            m[5].to_bits(),
            m[6].to_bits(),
            m[7].to_bits(),
            m[8].to_bits(),
        ]
    }

    /// The scan table: from the scan angles of one line's sub-samples
    /// (sample `s`, sub-column `i` at `s·N + i`:
    /// `θ(s + ½ + ((i+½)/N − ½)·IFOV/step)`), their sweep delays and, per
    /// sub-line, their world directions.
    fn scan_table(&self) -> ScanTable {
        let n = self.oversample;
        let step = self.sample_step_rad();
        let mut theta_sin_cos = Vec::with_capacity(self.samples_per_line * n);
        for s in 0..self.samples_per_line {
            for i in 0..n {
                let ds = ((i as f64 + 0.5) / n as f64 - 0.5) * self.ifov_rad / step;
                let theta = self.scan_angle(s as f64 + 0.5 + ds);
                let (sin, cos) = theta.sin_cos();
                theta_sin_cos.push([theta, sin, cos]);
            }
        }
        let mut dirs = Vec::with_capacity(theta_sin_cos.len() * n);
        for j in 0..n {
            let sc_phi = self.sub_line_phi(j).sin_cos();
            dirs.extend(
                theta_sin_cos
                    .iter()
                    .map(|&[_, sin_t, cos_t]| self.direction_of((sin_t, cos_t), sc_phi).as_vec3()),
            );
        }
        let delays = theta_sin_cos
            .iter()
            .map(|&[theta, ..]| self.sweep_delay(theta))
            .collect();
        ScanTable { dirs, delays }
    }

    /// Along-track offset of sub-line `j` of `N` within the IFOV, rad.
    fn sub_line_phi(&self, j: usize) -> f64 {
        ((j as f64 + 0.5) / self.oversample as f64 - 0.5) * self.ifov_rad
    }

    /// Angular step between samples, `A / S`, rad.
    pub fn sample_step_rad(&self) -> f64 {
        self.scan_angle_rad / self.samples_per_line as f64
    }

    /// Scan angle (rad, + to starboard) at continuous sample coordinate `s`.
    pub fn scan_angle(&self, s: f64) -> f64 {
        (s - 0.5 * self.samples_per_line as f64) * self.sample_step_rad()
    }

    /// Unit ground-track direction (ENU).
    pub fn track(&self) -> DVec3 {
        DVec3::new(self.heading_rad.sin(), self.heading_rad.cos(), 0.0)
    }

    /// Delay of the sample at scan angle `theta` after its line's start, s.
    pub fn sweep_delay(&self, theta: f64) -> f64 {
        if self.mirror_sweep {
            (theta + 0.5 * self.scan_angle_rad) / (std::f64::consts::TAU * self.scan_rate_hz)
        } else {
            0.0
        }
    }

    /// Start time of line `line` (integer index), s relative to the scene time.
    pub fn line_time(&self, line: usize) -> f64 {
        self.start_time_s + line as f64 / self.scan_rate_hz
    }

    /// Aircraft (sensor) position at time `t`, world metres.
    pub fn position(&self, t: f64) -> DVec3 {
        self.position_on(self.track().truncate(), t)
    }

    /// [`LineScanner::position`] with the unit ground track (east, north)
    /// given.
    #[inline]
    fn position_on(&self, track: DVec2, t: f64) -> DVec3 {
        let g = self.start + self.ground_speed_m_s * (t - self.start_time_s) * track;
        DVec3::new(g.x, g.y, self.altitude_m)
    }

    /// Unit world look direction at scan angle `theta` and along-track
    /// angle `phi` (rad, + forward).
    pub fn direction(&self, theta: f64, phi: f64) -> DVec3 {
        self.direction_of(theta.sin_cos(), phi.sin_cos())
    }

    /// [`LineScanner::direction`] from `(sin θ, cos θ)` and `(sin φ, cos φ)`.
    #[inline]
    fn direction_of(&self, (sin_t, cos_t): (f64, f64), (sin_p, cos_p): (f64, f64)) -> DVec3 {
        let body = DVec3::new(sin_p, cos_p * sin_t, cos_p * cos_t);
        (self.world_from_body * body).normalize()
    }

    /// The ray at continuous sample coordinate `s` of integer line `line`,
    /// offset `phi` rad along track within the IFOV; `t` in metres.
    pub fn ray(&self, line: usize, s: f64, phi: f64) -> Ray {
        let theta = self.scan_angle(s);
        let t = self.line_time(line) + self.sweep_delay(theta);
        Ray::new(
            self.position(t).as_vec3(),
            self.direction(theta, phi).as_vec3(),
        )
    }

    /// Rays of scan line `line`, appended to `out`: `N` sub-lines (along-track
    /// offsets `φ = ((j+½)/N − ½)·IFOV`), each of `samples·N` rays (scan
    /// angles of sample `s` at `θ(s+½) + ((i+½)/N − ½)·IFOV`), in the layout
    /// [`super::effects::reduce_oversampled`] takes. The sub-rays cover the
    /// detector footprint; they form a regular grid in sample units exactly
    /// when `IFOV = A/S`.
    ///
    /// The same rays as [`LineScanner::ray`] at those coordinates, bit for
    /// bit, from the table made once in [`LineScanner::new`] (the attitude
    /// is fixed, so every line has the same directions and sweep delays):
    /// per ray only the aircraft position, and that once per line without
    /// the mirror sweep.
    pub fn rays_for_line(&self, line: usize, out: &mut Vec<Ray>) {
        let table = self.scan.get(self.scan_key(), || self.scan_table());
        let per_sub_line = table.delays.len();
        out.reserve(table.dirs.len());
        let line_t = self.line_time(line);
        let track = self.track().truncate();
        if self.mirror_sweep {
            // Each sample from the aircraft's position at its sweep time.
            for dirs in table.dirs.chunks_exact(per_sub_line) {
                out.extend(table.delays.iter().zip(dirs).map(|(&d, &dir)| {
                    Ray::new(self.position_on(track, line_t + d).as_vec3(), dir)
                }));
            }
        } else {
            // The whole line from one position.
            let origin = self.position_on(track, line_t + self.sweep_delay(0.0));
            let origin = origin.as_vec3();
            out.extend(table.dirs.iter().map(|&dir| Ray::new(origin, dir)));
        }
    }

    /// Forward model: the continuous `(line, sample)` coordinates at which
    /// world point `p` is imaged (centre of line `l` at `l + ½`), or `None`
    /// if the scan plane never crosses it below the aircraft. The point may
    /// fall outside the image.
    ///
    /// The point is in the scan plane when its body-frame forward component
    /// vanishes; with constant attitude that is linear in time, so
    /// `τ = f·(p − a₀) / (v f·d)` (f: body forward axis, d: track, a₀: start
    /// position); then `θ = atan2(right, down)` and the line follows from
    /// `τ = (l − ½)/rate + sweep_delay(θ)`.
    pub fn project(&self, p: DVec3) -> Option<DVec2> {
        let fwd = self.world_from_body.x_axis;
        let a0 = self.position(self.start_time_s);
        let closing = self.ground_speed_m_s * fwd.dot(self.track());
        let tau = if closing.abs() > 1e-12 {
            fwd.dot(p - a0) / closing
        } else if fwd.dot(p - a0).abs() < 1e-9 {
            0.0
        } else {
            return None;
        };
        let body = self.world_from_body.transpose() * (p - self.position(self.start_time_s + tau));
        if body.z <= 0.0 {
            return None;
        }
        let theta = body.y.atan2(body.z);
        let sample = theta / self.sample_step_rad() + 0.5 * self.samples_per_line as f64;
        let line = (tau - self.sweep_delay(theta)) * self.scan_rate_hz + 0.5;
        Some(DVec2::new(line, sample))
    }
}
