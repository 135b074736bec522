//! The fast primary pipeline: band radiances at the sensor straight from
//! the stages' tables, for the hits that need no secondary ray; the others
//! go to the spectral reference ([`super::spectral`]).

use super::Shader;
use super::hit::{GreyHit, HitStates, acos_deg};
use super::sources::{SunRays, sky_node};
use super::truth::{TruthBlock, TruthOut};
use super::{RULE_BACK_SKY, RULE_GREY, RULE_PER_HIT_BY_RANGE};
use crate::trace::{Hit, Ray};

/// Which primary hits [`Shader::fast_primary`] leaves to the spectral
/// reference ([`Shader::shade_primary`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FastMiss {
    /// The material is specular or transmissive and the bounce budget
    /// allows secondary rays.
    Secondary,
    /// A temperature lies off the tabulated Planck function.
    OffTable,
    /// The material reflects the sun through a glint lobe
    /// ([`crate::render::glint`]).
    Glint,
}

/// Working memory of [`Shader::shade_fast`], reused from call to call.
#[derive(Debug, Default)]
pub struct FastScratch {
    pub(super) grey: Vec<GreyHit>,
    /// Rays of the batch whose hits are not plain grey (see
    /// [`Shader::shade_fast`]).
    pub(super) special: Vec<u32>,
    pub(super) sun: SunRays,
    pub(super) bands: Vec<f32>,
    pub(super) states: HitStates,
}

impl Shader<'_> {
    /// Band radiances at the sensor (W·m⁻²·sr⁻¹, one per band into `out`)
    /// of the primary ray `ray` (unit direction) hitting `h`, without the
    /// spectral intermediate of [`Shader::shade_primary`]: per band one
    /// fused pass over the grid of
    ///
    /// ```text
    /// Σ_λ w·τ₂(λ, R) · [ε·B(T) + r·(env + (1 − s)·E_s·cos σ·f_sun/π) + t·env]
    ///   + Σ_λ w·L_u(λ, R),      r = max(1 − ε − t, 0),
    ///   env = F·L_eq(β) + (1 − F)·B(T_bg)
    /// ```
    ///
    /// (the big equation of the module docs with `L_spec = L_behind = env`,
    /// which is what the reference evaluates for a hit without secondary
    /// rays), with the same interpolations as the reference — ε linear in
    /// the 1° angle rows, B linear on the Planck table, τ₂ and L_u linear
    /// in range — so the two agree to single-precision rounding
    /// (~10⁻⁶ relative; `tests/render.rs` checks ≤ 10⁻⁵). The band weights
    /// `w` (response × trapezoid) are folded into `w·τ₂` and `Σ w·L_u`
    /// per range node, which is exact because both are linear in the range
    /// interpolation. Returns `Err` (and leaves `out` alone) for hits that
    /// need the reference: secondary rays, or temperatures off the table.
    pub fn fast_primary(&self, ray: &Ray, h: &Hit, out: &mut [f32]) -> Result<(), FastMiss> {
        let mut slow = Vec::new();
        let mut o = vec![0f32; self.fast.len()];
        self.shade_fast(
            std::slice::from_ref(ray),
            &[Some(*h)],
            &mut o,
            &mut slow,
            &mut FastScratch::default(),
            None,
        );
        if slow.is_empty() {
            out.copy_from_slice(&o);
            Ok(())
        } else if self.spawns_secondary(self.facet_of(h)) {
            Err(FastMiss::Secondary)
        } else if self.glint_m2[self.optics.facet_material[self.facet_of(h)] as usize] > 0.0 {
            Err(FastMiss::Glint)
        } else {
            Err(FastMiss::OffTable)
        }
    }

    /// [`Shader::fast_primary`] and [`Shader::fast_miss`] for a batch of
    /// primary rays (unit directions) and their hits: band radiances into
    /// `out` band-major (`out[b · n + i]` for ray `i` of `n`), the indices
    /// of the hits left to the spectral reference appended to `slow`
    /// (their `out` values untouched).
    ///
    /// One pass over the batch reads one byte per hit, its facet's rule
    /// ([`super::RULE_GREY`] …): hits on materials grey in every band
    /// (without secondary rays, on the Planck table) that need no per-hit
    /// state at their range and no shadow ray of their own go straight to
    /// the grey path; only the others have their per-hit states
    /// ([`crate::render::per_hit`], all traced in one call) and shadow
    /// rays toward the sun (one call) looked up, then join the grey path
    /// or take the per-hit fused spectral sums. The grey path then runs in
    /// three more passes — the view zeniths of all its hits at once (a loop
    /// that vectorises); their path nodes (per hit a range bin's node and
    /// one compare, [`super::band::GreyTables::locate_binned`], in a short
    /// loop); then per band
    /// `ε(θ)·ΣqB(T) + r·(env + sd·Σq·E_s) + t·env + Σw·L_u` from
    /// [`super::band::GreyTables`], with `q` the range-interpolated path
    /// weights — so that no per-hit latency chain stalls the others.
    ///
    /// With `truth`, the truth values of the pixel-centre rays it names are
    /// written once their states and shadow rays are known
    /// ([`Shader::truth_of`]).
    pub fn shade_fast(
        &self,
        rays: &[Ray],
        hits: &[Option<Hit>],
        out: &mut [f32],
        slow: &mut Vec<usize>,
        sc: &mut FastScratch,
        truth: Option<TruthOut<'_, '_>>,
    ) {
        let n = rays.len();
        let nb = self.fast.len();
        debug_assert!(hits.len() == n && out.len() >= nb * n);
        sc.grey.clear();
        sc.special.clear();
        sc.bands.resize(nb, 0.0);
        // Pass 1, per ray: misses, and hits on facets whose rule
        // ([`Shader::rule`]) is the plain grey path (no per-hit state at
        // this range, no shadow ray of their own) straight to the grey
        // path; the others to `special`.
        let ph = self.conditions.per_hit.as_deref();
        let beta = self.pixel_angle_rad;
        // cos Θ of a ray's scattering angle, by day with a path.
        let sun_sc = self.fast_path.as_ref().and_then(|p| p.sun);
        let cos_sc = |ray: &Ray| match sun_sc {
            Some(s) => ray.dir.dot(s) / ray.dir.length(),
            None => 1.0,
        };
        for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
            let Some(h) = hit else {
                let up = ray.dir.z >= 0.0;
                let (k, f) = sky_node(ray.dir.z as f64, ray.dir.length() as f64);
                let ka = self.sky_angle(ray.dir);
                for (b, fb) in self.fast.iter().enumerate() {
                    out[b * n + i] = if up {
                        fb.miss_sky_at(k, f, ka)
                    } else {
                        fb.miss_ground
                    } as f32;
                }
                continue;
            };
            let f = self.facet_of(h);
            let rule = self.rule[f];
            // (A back face with its own sky view is not the grey record's
            // face: such hits take the general path.)
            if rule & !(RULE_PER_HIT_BY_RANGE | RULE_BACK_SKY) == RULE_GREY {
                let dn = ray.dir.dot(h.ng);
                let range = h.t * ray.dir.length();
                let by_range = rule & RULE_PER_HIT_BY_RANGE != 0;
                let n2 = ray.dir.length_squared() * h.ng.length_squared();
                let per_hit = by_range && ph.is_some_and(|p| p.large(f, range, beta));
                let own_back = rule & RULE_BACK_SKY != 0 && dn > 0.0;
                if !(per_hit || own_back) && n2 > 0.0 && n2.is_finite() {
                    let z = ray.origin.z + ray.dir.z * h.t;
                    // A double-sided facet's face turned from the sun takes
                    // no sun (the grey record's rule lights either face).
                    let unlit =
                        !self.seen_face_lit(self.optics.facet_material[f] as usize, h.ng, ray.dir);
                    sc.grey
                        .push(GreyHit::new(i, f, [dn, n2, range, z, cos_sc(ray)], unlit));
                    continue;
                }
            }
            sc.special.push(i as u32);
        }
        // The special hits' per-hit states and shadow rays.
        self.per_hit_states_of(
            rays,
            hits,
            sc.special.iter().map(|&i| i as usize),
            true,
            &[],
            &mut sc.states,
        );
        {
            let st = &sc.states;
            self.sun_visibility_of(
                rays,
                hits,
                sc.special.iter().map(|&i| i as usize),
                |i| st.has(i),
                &mut sc.sun,
            );
        }
        for &i in &sc.special {
            let i = i as usize;
            let (ray, Some(h)) = (&rays[i], &hits[i]) else {
                continue;
            };
            let f = self.facet_of(h);
            if let Some(st) = sc.states.of(i) {
                if self
                    .fast_general(ray, h, Some(st), None, &mut sc.bands)
                    .is_err()
                {
                    slow.push(i);
                    continue;
                }
                for (b, &v) in sc.bands.iter().enumerate() {
                    out[b * n + i] = v;
                }
                continue;
            }
            let vis = sc.sun.of(i);
            let n2 = ray.dir.length_squared() * h.ng.length_squared();
            let dn = ray.dir.dot(h.ng);
            if self.grey[f].mi != u32::MAX
                && !(self.rule[f] & RULE_BACK_SKY != 0 && dn > 0.0)
                && n2 > 0.0
                && n2.is_finite()
            {
                let range = h.t * ray.dir.length();
                let z = ray.origin.z + ray.dir.z * h.t;
                sc.grey.push(GreyHit::new(
                    i,
                    f,
                    [dn, n2, range, z, cos_sc(ray)],
                    vis == Some(0.0)
                        || !self.seen_face_lit(
                            self.optics.facet_material[f] as usize,
                            h.ng,
                            ray.dir,
                        ),
                ));
                continue;
            }
            if self.fast_general(ray, h, None, vis, &mut sc.bands).is_err() {
                slow.push(i);
                continue;
            }
            for (b, &v) in sc.bands.iter().enumerate() {
                out[b * n + i] = v;
            }
        }
        if let Some(t) = truth {
            self.truth_pass(rays, hits, sc, t);
        }
        // View zeniths, degrees: cos θ = |d·n_g| / (|d|·|n_g|).
        for g in &mut sc.grey {
            g.theta = acos_deg((g.dn.abs() / g.theta.sqrt()).min(1.0));
        }
        if self.grey_terms.is_empty() {
            self.grey_locate(&mut sc.grey);
            self.grey_pass(sc, n, out);
        } else {
            self.grey_terms_pass(sc, n, out);
        }
    }

    /// The truth values of a batch's pixel-centre rays (those `truth`
    /// names), from the hits' per-hit states and shadow rays in `sc`.
    fn truth_pass(
        &self,
        rays: &[Ray],
        hits: &[Option<Hit>],
        sc: &FastScratch,
        mut t: TruthOut<'_, '_>,
    ) {
        if t.layers.is_empty() || t.layers[0].is_empty() {
            return;
        }
        let mut block = TruthBlock::new();
        let (mut i, mut col) = (t.first, 0usize);
        while i < rays.len() {
            let v = match &hits[i] {
                None => crate::render::MISS_TRUTH,
                Some(h) => {
                    let mut v = self.truth_of_hit(&rays[i], h, sc.states.of(i));
                    if let Some(x) = sc.sun.of(i) {
                        v[4] = x;
                    }
                    v
                }
            };
            block.push(&mut t, col, v);
            (i, col) = t.advance(col);
        }
        // `col`: the columns written.
        block.flush(&mut t, col);
    }
}
