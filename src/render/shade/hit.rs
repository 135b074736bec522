//! Stage 1, the hit: where a ray meets a facet — the hit frame (point,
//! normal facing the ray, unit direction), the view zenith and its row in
//! the 1° emissivity tables, and the hit's own per-hit thermal state
//! ([`crate::render::per_hit`]) where its facet wants one.

use glam::Vec3;

use super::Shader;
use crate::geometry::SceneGeometry;
use crate::render::per_hit::HitState;
use crate::trace::{Hit, Ray};

/// Angle rows of the emissivity tables (0°, 1°, …, 90°).
pub(super) const ANGLE_ROWS: usize = 91;

/// Row `a0` of the 1° emissivity tables and the fraction toward `a0 + 1`
/// for the cosine of the view zenith `cos_view` (clamped to [0, 1]).
#[inline]
pub(super) fn angle_row(cos_view: f32) -> (usize, f64) {
    let theta = acos_unit(cos_view.clamp(0.0, 1.0) as f64).to_degrees();
    // θ ≥ 0: truncation is the floor.
    let a0 = (theta as usize).min(ANGLE_ROWS - 2);
    (a0, theta - a0 as f64)
}

/// arccos x for 0 ≤ x ≤ 1, radians, to 3·10⁻⁸ (Abramowitz & Stegun,
/// *Handbook of Mathematical Functions*, eq. 4.4.46: 2·10⁻⁸ with its
/// ten-digit coefficients; 2·10⁻⁶° is far inside
/// the 1° emissivity rows).
#[inline]
pub(super) fn acos_unit(x: f64) -> f64 {
    pub(super) const A: [f64; 8] = [
        1.570_796_305_0,
        -0.214_598_801_6,
        0.088_978_987_4,
        -0.050_174_304_6,
        0.030_891_881_0,
        -0.017_088_125_6,
        0.006_670_090_1,
        -0.001_262_491_1,
    ];
    let p = A.iter().rev().fold(0.0, |acc, &a| acc * x + a);
    (1.0 - x).max(0.0).sqrt() * p
}

/// arccos x in degrees for 0 ≤ x ≤ 1, single precision: the polynomial of
/// [`acos_unit`] (Abramowitz & Stegun eq. 4.4.46) in f32, written so a loop
/// over many cosines vectorises. Error ≤ 2·10⁻⁵° (f32 rounding; tested),
/// far inside the 1° emissivity rows.
#[inline]
pub(super) fn acos_deg(x: f32) -> f32 {
    pub(super) const A: [f32; 8] = [
        // 1.570 796 305 0: in f32, π/2.
        std::f32::consts::FRAC_PI_2,
        -0.214_598_8,
        0.088_978_99,
        -0.050_174_303,
        0.030_891_88,
        -0.017_088_126,
        0.006_670_09,
        -0.001_262_491_1,
    ];
    // Estrin's scheme: a shorter dependency chain than Horner's.
    let x2 = x * x;
    let x4 = x2 * x2;
    let p01 = A[0] + A[1] * x;
    let p23 = A[2] + A[3] * x;
    let p45 = A[4] + A[5] * x;
    let p67 = A[6] + A[7] * x;
    let p = (p01 + p23 * x2) + (p45 + p67 * x2) * x4;
    (1.0 - x).max(0.0).sqrt() * p * (180.0 / std::f32::consts::PI)
}

/// The per-hit states of a batch's hits ([`Shader::per_hit_states_of`]).
#[derive(Debug, Default)]
pub(super) struct HitStates {
    /// Per ray of the batch: index into `states` (`u32::MAX`: the facet's
    /// state); empty without per-hit temperatures.
    pub(super) state_of: Vec<u32>,
    /// Per-hit states of the batch's hits that have one.
    pub(super) states: Vec<HitState>,
    /// `(facet, point)` of those hits.
    pub(super) points: Vec<(u32, Vec3)>,
}

impl HitStates {
    /// The state of ray `i`, if it has its own.
    #[inline]
    pub(super) fn of(&self, i: usize) -> Option<HitState> {
        match self.state_of.get(i) {
            Some(&k) if k != u32::MAX => Some(self.states[k as usize]),
            _ => None,
        }
    }

    /// Whether ray `i` has its own state.
    #[inline]
    pub(super) fn has(&self, i: usize) -> bool {
        self.state_of.get(i).is_some_and(|&k| k != u32::MAX)
    }
}

/// A hit on the grey path, as [`Shader::shade_fast`] gathers it.
#[derive(Debug, Clone, Copy)]
pub(super) struct GreyHit {
    /// Ray index in the batch.
    pub(super) ray: u32,
    /// Facet.
    pub(super) facet: u32,
    /// `d·n_g` (its sign: which face is seen).
    pub(super) dn: f32,
    /// `|d|²·|n_g|²`, then (second pass) the view zenith θ, degrees.
    pub(super) theta: f32,
    /// Slant range, m.
    pub(super) range: f32,
    /// Height of the hit above the ground datum (scene z), m.
    pub(super) z: f32,
    /// No direct sun on the face seen: the hit's own shadow ray found the
    /// sun blocked, or the face is not the one the sun falls on
    /// ([`Shader::seen_face_lit`]).
    pub(super) shaded: bool,
    /// Where it reads the path's tables ([`Shader::grey_locate`]; with a
    /// path only): path node of range node `ri − 1` at height node `ai`,
    /// the fraction `rx` from range node `ri − 1` toward `ri` and `ax`
    /// from height node `ai` toward `ai + 1`.
    pub(super) node: u32,
    pub(super) rx: f32,
    pub(super) ax: f32,
    /// By day with a path: cos Θ of the ray's scattering angle, then
    /// ([`Shader::grey_locate`]) the fraction toward scattering-angle node
    /// `ks + 1` ([`crate::atmosphere::angle_node`]).
    pub(super) fs: f32,
    pub(super) ks: u32,
}

impl GreyHit {
    /// A hit of ray `ray` on facet `facet` before [`Shader::shade_fast`]'s
    /// later passes: `dn` = `d·n_g`, `n2` = `|d|²·|n_g|²`, slant range
    /// (m), height `z` (m), `cs` = cos Θ of the ray's scattering angle
    /// (1 with no scattered sunlight).
    #[inline]
    pub(super) fn new(
        ray: usize,
        facet: usize,
        [dn, n2, range, z, cs]: [f32; 5],
        shaded: bool,
    ) -> Self {
        GreyHit {
            ray: ray as u32,
            facet: facet as u32,
            dn,
            theta: n2,
            range,
            z,
            shaded,
            node: 0,
            rx: 0.0,
            ax: 0.0,
            fs: cs,
            ks: 0,
        }
    }
}

impl Shader<'_> {
    /// The per-hit states of the hits of a batch whose facets want one,
    /// among the rays `which`, into `sc` (`state_of`, per ray of the
    /// batch: index into `states`, `u32::MAX` for none), all traced in one
    /// call of [`crate::render::per_hit::PerHit::states_of`]; `direct`:
    /// the rays are primary (false: seen through a reflection or a
    /// transmission, whose hits take their own sky view only with
    /// [`crate::render::per_hit::PerHitParams::secondary_sky`]);
    /// `travelled[i]`: the metres ray `i` travelled from the sensor to its
    /// origin (empty: none), so that a hit's footprint is that of its whole
    /// path from the sensor.
    pub(super) fn per_hit_states_of(
        &self,
        rays: &[Ray],
        hits: &[Option<Hit>],
        which: impl IntoIterator<Item = usize>,
        direct: bool,
        travelled: &[f32],
        sc: &mut HitStates,
    ) {
        sc.state_of.clear();
        sc.states.clear();
        let Some(ph) = &self.conditions.per_hit else {
            return;
        };
        sc.state_of.resize(rays.len(), u32::MAX);
        sc.points.clear();
        for i in which {
            let (ray, Some(h)) = (&rays[i], &hits[i]) else {
                continue;
            };
            let f = self.facet_of(h);
            let range = travelled.get(i).copied().unwrap_or(0.0) + h.t * ray.dir.length();
            if ph.wants(f, range, self.pixel_angle_rad) {
                sc.state_of[i] = sc.points.len() as u32;
                sc.points.push((f as u32, ray.origin + ray.dir * h.t));
            }
        }
        ph.states_of(self.tracer, &sc.points, direct, &mut sc.states);
    }

    /// The per-hit state of one hit, if its facet wants one.
    pub(super) fn hit_state(&self, ray: &Ray, h: &Hit) -> Option<HitState> {
        let ph = self.conditions.per_hit.as_ref()?;
        let f = self.facet_of(h);
        if !ph.wants(f, h.t * ray.dir.length(), self.pixel_angle_rad) {
            return None;
        }
        let mut out = Vec::with_capacity(1);
        ph.states(
            self.tracer,
            &[(f as u32, ray.origin + ray.dir * h.t)],
            &mut out,
        );
        out.pop()
    }

    /// Hit point, normal facing the ray's origin, and unit ray direction.
    pub(super) fn hit_frame(&self, ray: &Ray, h: &Hit) -> (Vec3, Vec3, Vec3) {
        let d = ray.dir.normalize_or_zero();
        let p = ray.origin + ray.dir * h.t;
        let mut nrm = h.ng.normalize_or(Vec3::Z);
        if nrm.dot(d) > 0.0 {
            nrm = -nrm;
        }
        (p, nrm, d)
    }

    /// Global facet index of a hit.
    pub fn facet_of(&self, hit: &Hit) -> usize {
        SceneGeometry::facet_id(&self.offsets, hit.instance, hit.prim)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    pub(super) fn acos_deg_is_within_its_stated_bound() {
        for i in 0..=100_000 {
            let x = i as f64 / 100_000.0;
            // The cosine as the renderer has it: in f32.
            let x = x as f32;
            let err = (super::acos_deg(x) as f64 - (x as f64).acos().to_degrees()).abs();
            assert!(err <= 2e-5, "acos({x}): error {err}°");
        }
    }

    #[test]
    pub(super) fn acos_unit_is_within_its_published_bound() {
        for i in 0..=100_000 {
            let x = i as f64 / 100_000.0;
            let err = (super::acos_unit(x) - x.acos()).abs();
            assert!(err <= 3e-8, "acos({x}): error {err}");
        }
    }
}
