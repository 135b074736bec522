//! Pinhole frame camera: a `width × height` detector array behind a lens of
//! focal length `f`, pixel pitch `p` (only `f/p` matters for geometry).
//!
//! Camera frame (pbrt / OpenCV convention): `x` right, `y` down (image rows
//! grow downwards), `z` forward along the optical axis. Pixel `(col, row)`
//! covers continuous image coordinates `[col, col+1) × [row, row+1)`, its
//! centre at `(col + ½, row + ½)`; the optical axis pierces the array centre
//! `(W/2, H/2)`. A point at camera coordinates `(x, y, z)`, `z > 0`, images
//! at `u = W/2 + (f/p)·x/z`, `v = H/2 + (f/p)·y/z` (the pinhole projection,
//! e.g. Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., eq. 6.1).

use glam::{DAffine3, DMat3, DVec2, DVec3, Vec3};

use super::Derived;
use crate::trace::Ray;
use crate::{Error, Result};

/// A built frame camera.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameCamera {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Focal length in pixels, `f / pitch`.
    pub focal_px: f64,
    /// Camera → world: columns are the camera's right, down and forward axes
    /// in world (ENU) coordinates; translation is the camera position, m.
    pub world_from_camera: DAffine3,
    /// Sub-pixel rays per pixel side (`N` → `N×N` rays per pixel).
    pub oversample: usize,
    /// The rotation's x term ([`FrameCamera::x_term`]) of each sub-column
    /// of a row (sub-column `k` at `u = (k + ½)/N`), computed once (every
    /// row has the same), with the key of the fields it depends on.
    columns: Box<Derived<[u64; COLUMN_KEY_LEN], ColumnTerms>>,
}

/// See [`FrameCamera::columns`].
#[derive(Clone, PartialEq, Default)]
struct ColumnTerms(Vec<DVec3>);

/// Length of [`FrameCamera::column_key`].
const COLUMN_KEY_LEN: usize = 6;

impl std::fmt::Debug for ColumnTerms {
    /// A summary: the terms are derived from the camera's other fields.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ColumnTerms({} sub-columns)", self.0.len())
    }
}

/// Orthonormal right/down/forward axes for a camera at `position` looking at
/// `look_at`, with `up` giving the image's up direction.
pub fn look_at_axes(position: DVec3, look_at: DVec3, up: DVec3) -> Result<DMat3> {
    let forward = (look_at - position).normalize_or_zero();
    if forward == DVec3::ZERO {
        return Err(Error::invalid(
            "look_at",
            "equals the camera position: expected a distinct point to look at",
        ));
    }
    let right = forward.cross(up).normalize_or_zero();
    if right == DVec3::ZERO {
        return Err(Error::invalid(
            "up",
            "is parallel to the viewing direction: expected an up vector not along it",
        ));
    }
    let down = forward.cross(right);
    Ok(DMat3::from_cols(right, down, forward))
}

/// Right/down/forward axes from a pointing azimuth (`yaw`, clockwise from
/// north), elevation (`pitch`, negative below the horizon, −90° = nadir) and a
/// roll about the viewing axis (positive turns the camera's right axis
/// towards its down axis: clockwise as seen from behind the camera), radians.
pub fn yaw_pitch_roll_axes(yaw: f64, pitch: f64, roll: f64) -> DMat3 {
    let forward = DVec3::new(
        yaw.sin() * pitch.cos(),
        yaw.cos() * pitch.cos(),
        pitch.sin(),
    );
    let right0 = DVec3::new(yaw.cos(), -yaw.sin(), 0.0);
    let down0 = forward.cross(right0);
    let (s, c) = roll.sin_cos();
    let right = right0 * c + down0 * s;
    let down = down0 * c - right0 * s;
    DMat3::from_cols(right, down, forward)
}

impl FrameCamera {
    /// A camera of `width × height` pixels with focal length `focal_px`
    /// pixels, camera→world axes `axes` (right, down, forward) at `position`.
    pub fn new(
        width: usize,
        height: usize,
        focal_px: f64,
        axes: DMat3,
        position: DVec3,
        oversample: usize,
    ) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(Error::invalid(
                "width/height",
                format!("{width}×{height}: expected at least 1×1 pixels"),
            ));
        }
        if !(focal_px.is_finite() && focal_px > 0.0) {
            return Err(Error::invalid(
                "focal length",
                format!("{focal_px} pixels: expected a positive focal length"),
            ));
        }
        if oversample == 0 {
            return Err(Error::invalid("oversample", "0: expected at least 1"));
        }
        let mut camera = FrameCamera {
            width,
            height,
            focal_px,
            world_from_camera: DAffine3::from_mat3_translation(axes, position),
            oversample,
            columns: Box::default(),
        };
        camera.columns = Box::new(Derived::new(camera.column_key(), camera.column_terms()));
        Ok(camera)
    }

    /// The fields the column terms depend on.
    fn column_key(&self) -> [u64; COLUMN_KEY_LEN] {
        let c = self.world_from_camera.matrix3.x_axis;
        [
            self.width as u64,
            self.oversample as u64,
            self.focal_px.to_bits(),
            c.x.to_bits(),
            c.y.to_bits(),
            c.z.to_bits(),
        ]
    }

    /// The x term of every sub-column of a row.
    fn column_terms(&self) -> ColumnTerms {
        let n = self.oversample;
        ColumnTerms(
            (0..self.width * n)
                .map(|k| self.x_term(self.focal_plane((k as f64 + 0.5) / n as f64, 0.0).0))
                .collect(),
        )
    }

    /// The camera position, world metres.
    pub fn position(&self) -> DVec3 {
        self.world_from_camera.translation
    }

    /// Full horizontal field of view, radians.
    pub fn horizontal_fov(&self) -> f64 {
        2.0 * (0.5 * self.width as f64 / self.focal_px).atan()
    }

    /// Unit world direction of the ray through continuous image point
    /// `(u, v)` (pixel centres at `+½`).
    pub fn direction(&self, u: f64, v: f64) -> DVec3 {
        let (x, y) = self.focal_plane(u, v);
        self.direction_through(x, y)
    }

    /// Camera-frame focal-plane coordinates `(x, y)` (units of the focal
    /// length) of image point `(u, v)`.
    #[inline]
    fn focal_plane(&self, u: f64, v: f64) -> (f64, f64) {
        (
            (u - 0.5 * self.width as f64) / self.focal_px,
            (v - 0.5 * self.height as f64) / self.focal_px,
        )
    }

    /// Unit world direction through focal-plane point `(x, y)`: the
    /// camera-to-world rotation of `(x, y, 1)`, normalised.
    #[inline]
    fn direction_through(&self, x: f64, y: f64) -> DVec3 {
        Self::direction_of_terms(self.x_term(x), self.y_term(y), self.z_term())
    }

    /// The rotation's column terms of `(x, y, 1)`: `x·c₀`, `y·c₁`, `c₂`.
    #[inline]
    fn x_term(&self, x: f64) -> DVec3 {
        self.world_from_camera.matrix3.x_axis * x
    }

    /// See [`FrameCamera::x_term`].
    #[inline]
    fn y_term(&self, y: f64) -> DVec3 {
        self.world_from_camera.matrix3.y_axis * y
    }

    /// See [`FrameCamera::x_term`].
    #[inline]
    fn z_term(&self) -> DVec3 {
        self.world_from_camera.matrix3.z_axis
    }

    /// `(x·c₀ + y·c₁ + c₂)` normalised, summed in that order (as
    /// `DAffine3::transform_vector3`).
    #[inline]
    fn direction_of_terms(xt: DVec3, yt: DVec3, zt: DVec3) -> DVec3 {
        (xt + yt + zt).normalize()
    }

    /// A ray's single-precision unit direction from the terms: the sum in
    /// f64, rounded to f32, normalised in f32 (`|d| − 1` within 10⁻⁷, as
    /// the rounding of a unit f64 vector would leave it).
    #[inline]
    fn ray_direction_of_terms(xt: DVec3, yt: DVec3, zt: DVec3) -> Vec3 {
        (xt + yt + zt).as_vec3().normalize()
    }

    /// The primary ray through continuous image point `(u, v)`; `t` is the
    /// distance in metres.
    pub fn ray(&self, u: f64, v: f64) -> Ray {
        let (x, y) = self.focal_plane(u, v);
        let dir = Self::ray_direction_of_terms(self.x_term(x), self.y_term(y), self.z_term());
        Ray::new(self.position().as_vec3(), dir)
    }

    /// Primary rays of pixel row `row`, appended to `out`: `N` sub-rows (at
    /// `v = row + (j+½)/N`), each of `width·N` rays (at `u = col + (i+½)/N`),
    /// so rows of results laid end to end form the `(width·N) × (height·N)`
    /// oversampled image that [`super::effects::reduce_oversampled`] takes.
    ///
    /// The same rays as [`FrameCamera::ray`] at those points, bit for bit,
    /// with the rotation's per-sub-column terms made once per camera
    /// ([`FrameCamera::new`]) and its per-sub-row term once per sub-row (per
    /// ray two additions and the normalisation).
    pub fn rays_for_row(&self, row: usize, out: &mut Vec<Ray>) {
        let n = self.oversample;
        let ws = self.width * n;
        out.reserve(ws * n);
        let origin = self.position().as_vec3();
        // The x term of every sub-column, from the table made once in
        // `new` (or afresh if the camera was changed since).
        let columns = self.columns.get(self.column_key(), || self.column_terms());
        let xts = &columns.0;
        let zt = self.z_term();
        for j in 0..n {
            let v = row as f64 + (j as f64 + 0.5) / n as f64;
            let yt = self.y_term(self.focal_plane(0.0, v).1);
            // Eight rays at a time with the components in separate arrays,
            // so the square roots and divisions vectorise (the operations
            // of `ray_direction_of_terms`, in its order: the same values).
            let start = out.len();
            out.resize(start + ws, Ray::new(origin, Vec3::ZERO));
            let mut dst = out[start..].chunks_exact_mut(8);
            let mut src = xts.chunks_exact(8);
            for (o, c) in (&mut dst).zip(&mut src) {
                let (mut x, mut y, mut z) = ([0.0f32; 8], [0.0f32; 8], [0.0f32; 8]);
                for k in 0..8 {
                    let w = (c[k] + yt + zt).as_vec3();
                    (x[k], y[k], z[k]) = (w.x, w.y, w.z);
                }
                let mut r = [0.0f32; 8];
                for k in 0..8 {
                    r[k] = 1.0 / (x[k] * x[k] + y[k] * y[k] + z[k] * z[k]).sqrt();
                }
                for k in 0..8 {
                    o[k].dir = Vec3::new(x[k] * r[k], y[k] * r[k], z[k] * r[k]);
                }
            }
            for (o, &xt) in dst.into_remainder().iter_mut().zip(src.remainder()) {
                o.dir = Self::ray_direction_of_terms(xt, yt, zt);
            }
        }
    }

    /// Continuous image coordinates `(u, v)` of world point `p`, or `None`
    /// if it is behind the camera (or on its plane). The point may fall
    /// outside the array.
    pub fn project(&self, p: DVec3) -> Option<DVec2> {
        let c = self.world_from_camera.inverse().transform_point3(p);
        if c.z <= 0.0 {
            return None;
        }
        Some(DVec2::new(
            0.5 * self.width as f64 + self.focal_px * c.x / c.z,
            0.5 * self.height as f64 + self.focal_px * c.y / c.z,
        ))
    }
}
