//! The truth layers ([`crate::render::TRUTH_LAYERS`]) of pixel-centre
//! rays: surface temperature, material id, object id, shape factor, sun
//! fraction and depth, written as a batch is shaded.

use super::Shader;
use super::sources::SunRays;
use super::surface::PLANCK_TABLE_STEP_K;
use crate::render::per_hit::HitState;
use crate::trace::{Hit, Ray};

/// Where [`Shader::shade_fast`] writes the truth values
/// ([`crate::render::TRUTH_LAYERS`] order) of a batch's pixel-centre rays: rays
/// `first`, `first + stride`, … (one per value of each layer slice).
pub struct TruthOut<'a, 'b> {
    /// Index of the first pixel-centre ray in the batch.
    pub first: usize,
    /// Rays from one pixel-centre ray to the next (≥ 1).
    pub stride: usize,
    /// One slice per truth layer, a value per pixel-centre ray.
    pub layers: &'a mut [&'b mut [f32]],
}

impl TruthOut<'_, '_> {
    /// The ray index and column after column `col` (`usize::MAX` past
    /// the last column).
    #[inline]
    pub(super) fn advance(&self, col: usize) -> (usize, usize) {
        let col = col + 1;
        if col < self.layers[0].len() {
            (self.first + col * self.stride.max(1), col)
        } else {
            (usize::MAX, col)
        }
    }
}

/// The truth values of up to [`TruthBlock::LEN`] consecutive pixels, per
/// layer, on their way to a [`TruthOut`]: written to the layers a block at
/// a time (one bounds check and one copy per layer and block instead of
/// one per value). Columns come in order from 0; column `c` is held at
/// `c % LEN`.
pub(super) struct TruthBlock {
    /// Per layer, the block's values.
    pub(super) values: [[f32; TruthBlock::LEN]; 6],
}

impl TruthBlock {
    pub(super) const LEN: usize = 8;

    pub(super) fn new() -> Self {
        TruthBlock {
            values: [[0.0; Self::LEN]; 6],
        }
    }

    /// Hold column `col`'s values; a full block goes to `t`.
    #[inline]
    pub(super) fn push(&mut self, t: &mut TruthOut<'_, '_>, col: usize, v: [f32; 6]) {
        let j = col % Self::LEN;
        for (layer, v) in self.values.iter_mut().zip(v) {
            layer[j] = v;
        }
        if j == Self::LEN - 1 {
            let s = col + 1 - Self::LEN;
            for (layer, v) in t.layers.iter_mut().zip(&self.values) {
                layer[s..s + Self::LEN].copy_from_slice(v);
            }
        }
    }

    /// Write the values of a partial last block to `t`, `cols` columns
    /// having been pushed.
    pub(super) fn flush(&self, t: &mut TruthOut<'_, '_>, cols: usize) {
        let n = cols % Self::LEN;
        let s = cols - n;
        for (layer, v) in t.layers.iter_mut().zip(&self.values) {
            layer[s..s + n].copy_from_slice(&v[..n]);
        }
    }
}

impl Shader<'_> {
    /// The truth values ([`crate::render::TRUTH_LAYERS`] order) of the pixel whose
    /// centre ray `ray` hits `h`: surface temperature, material id, object
    /// id, shape factor, sun fraction, depth (m). Read from the facet's
    /// grey-path record where it has one (the temperature recovered from
    /// its Planck table node and fraction: within 2·10⁻⁹ K in f64, so the
    /// same f32), from the per-facet arrays otherwise.
    /// The sun fraction is the hit's own where it has a per-hit state or
    /// traces a shadow ray ([`super::sources::sun_ray_facets`]).
    pub fn truth_of(&self, ray: &Ray, h: &Hit) -> [f32; 6] {
        let state = self.hit_state(ray, h);
        let mut v = self.truth_of_hit(ray, h, state);
        let mut sun = SunRays::default();
        let hit = [Some(*h)];
        self.sun_visibility(
            std::slice::from_ref(ray),
            &hit,
            |_| state.is_some(),
            &mut sun,
        );
        if let Some(x) = sun.of(0) {
            v[4] = x;
        }
        v
    }

    /// [`Shader::truth_of`] of the hit `h` of `ray` with its own `state`
    /// (per-hit temperatures) or its facet's; the shape factor of the face
    /// the ray sees ([`Shader::seen_sky`]).
    #[inline]
    pub(super) fn truth_of_hit(&self, ray: &Ray, h: &Hit, state: Option<HitState>) -> [f32; 6] {
        let f = self.facet_of(h);
        let mut v = self.truth_of_facet(f, h.t * ray.dir.length());
        if let Some(st) = state {
            v[0] = self.conditions.surface.temperature_k[f] + st.dt_k;
            v[4] = st.sun_fraction;
        }
        if self.rule[f] & super::RULE_BACK_SKY != 0 || state.is_some_and(|st| st.sky.is_some()) {
            v[3] = self.seen_sky(f, h.ng, ray.dir, state).0;
        }
        v
    }

    /// [`Shader::truth_of`] of a hit on facet `f` at range `d` (m).
    #[inline]
    pub(super) fn truth_of_facet(&self, f: usize, d: f32) -> [f32; 6] {
        let depth = if d.is_finite() { d } else { 0.0 };
        let g = &self.grey[f];
        if g.mi != u32::MAX {
            let t = self.table.t0 + (g.kt as f64 + g.ft as f64) * PLANCK_TABLE_STEP_K;
            return [
                t as f32,
                self.optics.materials[g.mi as usize].id as f32,
                g.object as f32,
                g.big_f,
                self.conditions.surface.sun_fraction[f],
                depth,
            ];
        }
        let s = &self.conditions.surface;
        [
            s.temperature_k[f],
            self.material_id_of(f),
            self.optics.facet_object[f] as f32,
            s.shape_factor[f],
            s.sun_fraction[f],
            depth,
        ]
    }
}
