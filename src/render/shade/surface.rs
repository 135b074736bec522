//! Stage 2, surface terms: the temperature at a hit and its Planck
//! radiance (tabulated on a temperature grid, [`PLANCK_TABLE_STEP_K`]),
//! emissivity and the Kirchhoff reflectance split, and the per-facet
//! records of the grey path ([`GreyFacet`], [`grey_facets`]).

use super::Shader;
use super::band::FastBand;
use super::conditions::{Conditions, SceneOptics, ShadeOptions, SurfaceState};
use crate::render::per_hit::HitState;

/// Temperature step of the tabulated Planck function, K.
pub const PLANCK_TABLE_STEP_K: f64 = 0.05;

/// Most nodes of the Planck table (beyond: exact evaluation).
pub(super) const PLANCK_TABLE_MAX_NODES: usize = 16384;

/// Planck's function on a temperature grid, all bands' wavelengths
/// concatenated.
#[derive(Debug, Clone)]
pub(super) struct PlanckTable {
    pub(super) t0: f64,
    pub(super) nodes: usize,
    /// `nodes × total` values.
    pub(super) values: Vec<f64>,
}

impl PlanckTable {
    /// Node `k` and fraction of temperature `t` (K), when it lies on the
    /// table.
    pub(super) fn position(&self, t: f64) -> Option<(usize, f64)> {
        let x = (t - self.t0) / PLANCK_TABLE_STEP_K;
        if self.nodes >= 2 && x >= 0.0 && x < (self.nodes - 1) as f64 {
            let k = x as usize;
            Some((k, x - k as f64))
        } else {
            None
        }
    }
}

/// What a hit on a facet needs in [`Shader::shade_fast`]'s grey path (its
/// material is grey in every band, so ε and r leave the band sums; it
/// spawns no secondary ray; its temperatures lie on the Planck table) and
/// the truth values of the pixel it is seen in: one cache line's half, the
/// one random access of a hit.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(32))]
pub(super) struct GreyFacet {
    /// Material index; `u32::MAX`: the facet is not on the grey path.
    pub(super) mi: u32,
    /// Object id.
    pub(super) object: u32,
    /// Planck table nodes of the surface and background temperatures.
    pub(super) kt: u16,
    pub(super) kg: u16,
    /// Their fractions toward the next node.
    pub(super) ft: f32,
    pub(super) fg: f32,
    /// Sky shape factor F.
    pub(super) big_f: f32,
    /// Diffuse-reflected sun on the lit face: `(1 − s)·cos σ·f_sun/π`
    /// (`f_sun = 1` for a facet whose hits trace a shadow ray).
    pub(super) sd: f32,
    /// Position of the front face's tilt on the reflected sky's tilt table
    /// ([`super::tilt_position`]).
    pub(super) tilt: f32,
}

impl GreyFacet {
    pub(super) const NONE: GreyFacet = GreyFacet {
        mi: u32::MAX,
        object: 0,
        kt: 0,
        kg: 0,
        ft: 0.0,
        fg: 0.0,
        big_f: 0.0,
        sd: 0.0,
        tilt: 0.0,
    };
}

/// The per-facet records of the grey path and, for renders without a
/// sensor path, each grey facet's view-independent terms per band (built
/// once per image, in parallel): `[Σw·B(T), env, sd·Σw·E_s, t·env]` with
/// `env = F·Σw·L_eq(β) + (1 − F)·Σw·B(T_bg)` (`L_eq` at the facet's tilt
/// `tilt[f]`, [`super::reflected_sky`]), so that a hit needs only
/// `ε(θ)·x + r·(env + lit·w) + z`.
#[allow(clippy::too_many_arguments)]
pub(super) fn grey_facets(
    optics: &SceneOptics,
    conditions: &Conditions,
    options: &ShadeOptions,
    fast: &[FastBand],
    table: &PlanckTable,
    sun_ray: &[bool],
    glint_m2: &[f64],
    tilt: &[f32],
) -> (Vec<GreyFacet>, Vec<[f32; 4]>) {
    use rayon::prelude::*;
    let s = &conditions.surface;
    let nb = fast.len();
    // Per material: on the grey path at all.
    let eligible: Vec<bool> = optics
        .materials
        .iter()
        .enumerate()
        .map(|(mi, m)| {
            let secondary =
                options.max_bounces > 0 && (m.specular_fraction > 0.0 || m.transmissivity > 0.0);
            nb > 0
                && !secondary
                && glint_m2[mi] <= 0.0
                && fast.iter().all(|fb| fb.grey[mi].is_some())
        })
        .collect();
    // Node indices are stored in 16 bits.
    let nodes_fit = table.nodes <= u16::MAX as usize;
    let mut grey = vec![GreyFacet::NONE; s.len()];
    let mut terms = vec![[0f32; 4]; s.len() * nb];
    grey.par_iter_mut()
        .zip(terms.par_chunks_mut(nb.max(1)))
        .enumerate()
        .for_each(|(f, (g, terms))| {
            let mi = optics.facet_material[f] as usize;
            // (A shape factor outside [0, 1] takes the general path, which
            // clamps it, so the truth layer keeps the value as given.)
            if !(eligible[mi] && nodes_fit && (0.0..=1.0).contains(&s.shape_factor[f])) {
                return;
            }
            let (Some((kt, ft)), Some((kg, fg))) = (
                table.position(s.temperature_k[f] as f64),
                table.position(s.background_k[f] as f64),
            ) else {
                return;
            };
            let m = &optics.materials[mi];
            // A facet whose hits trace their own shadow ray: the sun at full
            // strength, the hit's visibility applied per hit.
            let fs = if sun_ray[f] {
                1.0
            } else {
                (s.sun_fraction[f] as f64).clamp(0.0, 1.0)
            };
            let sun_front = (s.cos_sun[f] as f64).max(0.0) * fs / std::f64::consts::PI;
            let sd = (1.0 - m.specular_fraction.clamp(0.0, 1.0)) * sun_front;
            let big_f = s.shape_factor[f] as f64;
            let tr = m.transmissivity.clamp(0.0, 1.0);
            let (kb, wb) = super::tilt_at(tilt[f]);
            for (t, fb) in terms.iter_mut().zip(fast) {
                let p = &fb.plain;
                let env = big_f * p.sky_at(kb, wb as f64) + (1.0 - big_f) * p.planck_at(kg, fg);
                *t = [
                    p.planck_at(kt, ft) as f32,
                    env as f32,
                    (sd * p.sun) as f32,
                    (tr * env) as f32,
                ];
            }
            *g = GreyFacet {
                mi: mi as u32,
                object: optics.facet_object[f],
                kt: kt as u16,
                kg: kg as u16,
                ft: ft as f32,
                fg: fg as f32,
                big_f: s.shape_factor[f],
                sd: sd as f32,
                tilt: tilt[f],
            };
        });
    (grey, terms)
}

/// The temperature (K) and sunlit fraction of a hit on facet `f`: its own
/// (per-hit `state`) or its facet's.
#[inline]
pub(super) fn hit_temperature(s: &SurfaceState, f: usize, state: Option<HitState>) -> (f64, f32) {
    match state {
        Some(st) => ((s.temperature_k[f] + st.dt_k) as f64, st.sun_fraction),
        None => (s.temperature_k[f] as f64, s.sun_fraction[f]),
    }
}

/// The shape factor and background temperature (K) of a hit on facet
/// `f`: its own (per-hit `state` with its own sky view) or its facet's, of
/// the face the ray sees (`back`: the back face of a double-sided facet;
/// its own shape factor where known, else the front face's). The
/// background temperature is the mean over both faces
/// ([`crate::exposure::SkyView`]).
#[inline]
pub(super) fn hit_sky(
    s: &SurfaceState,
    f: usize,
    state: Option<HitState>,
    back: bool,
) -> (f32, f32) {
    match state.and_then(|st| st.sky) {
        Some(k) => match k.back_shape_factor.filter(|_| back) {
            Some(b) => (b, k.background_k),
            None => (k.shape_factor, k.background_k),
        },
        None => match s.back_shape_factor(f).filter(|_| back) {
            Some(b) => (b, s.background_k[f]),
            None => (s.shape_factor[f], s.background_k[f]),
        },
    }
}

impl Shader<'_> {
    /// What a hit on facet `f` seen along `d` (from the ray's origin)
    /// reflects of the sky: the shape factor and background temperature
    /// (K) of [`hit_sky`] and the position of the seen face's tilt on the
    /// reflected sky's tilt table. A ray that reaches the back face of a
    /// double-sided facet sees the sky that face sees: its own shape factor
    /// (when known) and tilt 180° − β. Otherwise (the front face, a
    /// single-sided facet, or a back face whose view is not known) the
    /// front face's: `F` and β.
    #[inline]
    pub(super) fn seen_sky(
        &self,
        f: usize,
        ng: glam::Vec3,
        d: glam::Vec3,
        state: Option<HitState>,
    ) -> (f32, f32, f32) {
        let s = &self.conditions.surface;
        let mi = self.optics.facet_material[f] as usize;
        let back = ng.dot(d) > 0.0 && self.optics.materials[mi].double_sided;
        let known = back
            && match state.and_then(|st| st.sky) {
                Some(k) => k.back_shape_factor.is_some(),
                None => s.back_shape_factor(f).is_some(),
            };
        let (big_f, t_bg) = hit_sky(s, f, state, known);
        let tilt = if known {
            self.back_tilt[f]
        } else {
            self.tilt[f]
        };
        (big_f, t_bg, tilt)
    }

    /// Whether a hit on facet `f` spawns secondary rays (specular or
    /// transmissive material, bounce budget left).
    pub fn spawns_secondary(&self, f: usize) -> bool {
        let m = &self.optics.materials[self.optics.facet_material[f] as usize];
        self.options.max_bounces > 0 && (m.specular_fraction > 0.0 || m.transmissivity > 0.0)
    }

    /// Node `k` and fraction of temperature `t` on the Planck table, when
    /// it lies on it.
    pub(super) fn table_position(&self, t: f64) -> Option<(usize, f64)> {
        self.table.position(t)
    }

    /// B(λ, T) for all wavelengths into `out`: tabulated, or exact off the
    /// table.
    pub(super) fn planck_into(&self, t: f64, out: &mut [f64]) {
        let tab = &self.table;
        let x = (t - tab.t0) / PLANCK_TABLE_STEP_K;
        if tab.nodes >= 2 && x >= 0.0 && x < (tab.nodes - 1) as f64 {
            let k = x as usize;
            let f = x - k as f64;
            let a = &tab.values[k * self.total..(k + 1) * self.total];
            let b = &tab.values[(k + 1) * self.total..(k + 2) * self.total];
            for ((o, &va), &vb) in out.iter_mut().zip(a).zip(b) {
                *o = va + f * (vb - va);
            }
        } else {
            for (o, &l) in out.iter_mut().zip(&self.wavelengths) {
                *o = self.planck.radiance(l, t);
            }
        }
    }
}
