//! Stage 4 of the linearised solve: the passes, facet by facet, from the
//! references chosen in stages 1–3.
//!
//! Owns the pass loop's per-facet work: which facets keep full histories
//! ([`Slots`]), the background term, and the first- and second-order
//! products with a reference's Green's matrices. Takes the facets, groups,
//! references and bins of [`super`]; knows nothing of how they were chosen.

use rayon::prelude::*;

use super::kernels::{columns, curvature, dot, matvec_cols};
use super::reference::{Coarse, Diff, NodeGreen, Reference};
use super::{CHUNK, Facets, Groups, Scratch};
use crate::thermal;
use crate::thermal::linear::latent_curvature_about;
use crate::thermal::scene::{FacetThermal, SceneInputs};

/// The facets some facet sees: each gets a slot in the `T⁴` histories a
/// pass before the last stores for the next pass's backgrounds (none with
/// one pass). Slots are in facet order, so a chunk of `CHUNK` facets has a
/// contiguous run of them.
pub(super) struct Slots {
    /// Slot of each facet (`u32::MAX`: none).
    of_facet: Vec<u32>,
    /// Number of slots.
    count: usize,
    /// First slot of each chunk of facets (one more than chunks).
    chunk_start: Vec<usize>,
}

impl Slots {
    /// Slot of each facet (`u32::MAX`: none).
    pub(super) fn of_facet(&self) -> &[u32] {
        &self.of_facet
    }

    pub(super) fn new(inputs: &SceneInputs, kinds: &[FacetThermal], passes: u32) -> Slots {
        let n = kinds.len();
        let mut slot = vec![u32::MAX; n];
        let mut slots = 0usize;
        if passes > 1 {
            let mut needed = vec![false; n];
            for e in inputs.background {
                needed[e.facet as usize] = true;
            }
            for f in 0..n {
                if needed[f] && matches!(kinds[f], FacetThermal::Solve(_)) {
                    slot[f] = slots as u32;
                    slots += 1;
                }
            }
        }
        let chunks = n.div_ceil(CHUNK);
        let mut chunk_slot = vec![0usize; chunks + 1];
        for (c, ch) in slot.chunks(CHUNK).enumerate() {
            chunk_slot[c + 1] = chunk_slot[c] + ch.iter().filter(|&&x| x != u32::MAX).count();
        }
        Slots {
            of_facet: slot,
            count: slots,
            chunk_start: chunk_slot,
        }
    }
}

/// Stage 4: the passes. Pass 1 takes the air as background; a later pass
/// adds the background excess over the air, `c·σ(T_bg⁴ − T_air⁴)`, to the
/// sources. A pass that is not the last yields (first-order) `T⁴`
/// histories of the facets others see ([`Slots`]), for the next one's
/// backgrounds; every pass yields the image records. Pass 1's image
/// records (first order, air background) are kept: a later pass adds to
/// them the background term `G·(c·bg)` at the image rows alone, unless it
/// needs the facet's full history.
pub(super) struct PassPlan<'a> {
    pub facets: &'a Facets<'a>,
    pub groups: &'a Groups<'a>,
    pub refs: &'a [Reference],
    /// Reference (bin) of each facet.
    pub ref_of: &'a [u32],
    /// Whether each facet lies near its reference (`Bins::near`).
    pub near: &'a [bool],
    pub slots: Slots,
    pub image_records: &'a [usize],
    /// Add the second-order correction in the last pass.
    pub second_order: bool,
    /// Let the second pass reuse pass 1's first order
    /// ([`super::LinearizedParams::reuse_first_pass`]).
    pub reuse_first_pass: bool,
}

/// What changes from pass to pass.
#[derive(Clone, Copy)]
struct Pass<'a> {
    /// The last pass: no `T⁴` histories to store.
    last: bool,
    /// The second-order correction (last pass only).
    second: bool,
    /// The previous pass's `T⁴` histories, by slot (`None` in pass 1).
    prev4: Option<&'a [f32]>,
    /// Pass 1's image records, `[facet·W + image]` (`None` in pass 1).
    base: Option<&'a [f32]>,
    /// `prev4` is pass 1's (first order, air background), and the second
    /// order may take its first-order change at the nodes from it
    /// ([`PassPlan::second_order_from_first_pass`]).
    reuse: bool,
}

impl PassPlan<'_> {
    /// Width of a facet's row of image records in the pass output.
    fn width(&self) -> usize {
        self.image_records.len().max(1)
    }

    /// One pass: every facet's image records (`[facet·W + image]`,
    /// [`PassPlan::width`]) and, unless it is the `last`, the `T⁴`
    /// histories of the slotted facets (`[slot·R + record]`). Written in
    /// place, chunk by chunk (no per-chunk copies). `prev_is_first`: `prev4`
    /// is pass 1's.
    pub(super) fn run(
        &self,
        last: bool,
        prev4: Option<&[f32]>,
        base: Option<&[f32]>,
        prev_is_first: bool,
    ) -> (Vec<f32>, Vec<f32>) {
        let pass = Pass {
            last,
            second: last && self.second_order,
            prev4,
            base,
            reuse: self.reuse_first_pass && prev_is_first && prev4.is_some() && base.is_some(),
        };
        let n = self.facets.len();
        let r = self.facets.forcing.len();
        let wi = self.width();
        let chunks = n.div_ceil(CHUNK);
        let store4 = !last;
        let chunk_slot = &self.slots.chunk_start;
        let mut img = vec![0.0f32; n * wi];
        let mut next4 = vec![0.0f32; if store4 { self.slots.count * r } else { 0 }];
        let mut parts: Vec<&mut [f32]> = Vec::with_capacity(chunks);
        let mut rest: &mut [f32] = &mut next4;
        for c in 0..chunks {
            let len = if store4 {
                (chunk_slot[c + 1] - chunk_slot[c]) * r
            } else {
                0
            };
            let (a, b) = std::mem::take(&mut rest).split_at_mut(len);
            parts.push(a);
            rest = b;
        }
        let ni = self.image_records.len();
        img.par_chunks_mut(CHUNK * wi)
            .zip(parts.into_par_iter())
            .enumerate()
            .for_each_init(
                || Scratch::new(r),
                |s, (c, (img, out4))| {
                    let range = c * CHUNK..((c + 1) * CHUNK).min(n);
                    for (i, f) in range.enumerate() {
                        let o = &mut img[i * wi..i * wi + ni];
                        let slot = self.slots.of_facet[f];
                        let out4 = if store4 && slot != u32::MAX {
                            let k = (slot as usize - chunk_slot[c]) * r;
                            Some(&mut out4[k..k + r])
                        } else {
                            None
                        };
                        self.facet(&pass, s, f, o, out4);
                    }
                },
            );
        (img, next4)
    }

    /// The image-time temperatures `[image][facet]` of a pass's output.
    pub(super) fn image_temperatures(&self, img: &[f32]) -> Vec<Vec<f32>> {
        let (n, wi) = (self.facets.len(), self.width());
        (0..self.image_records.len())
            .map(|i| (0..n).map(|f| img[f * wi + i]).collect::<Vec<f32>>())
            .collect()
    }

    /// One facet of a pass: its image records into `o` and, when it has a
    /// slot and the pass is not the last, its `T⁴` history into `out4`.
    fn facet(
        &self,
        pass: &Pass,
        s: &mut Scratch,
        f: usize,
        o: &mut [f32],
        out4: Option<&mut [f32]>,
    ) {
        let facets = self.facets;
        if let FacetThermal::Fixed(t) = facets.kinds[f] {
            o.iter_mut().for_each(|v| *v = t);
            return;
        }
        let rep = &self.refs[self.ref_of[f] as usize];
        let has_slot = self.slots.of_facet[f] != u32::MAX;
        let bgc = self.background_term(pass, f, s);
        // The second order: asked for, or for a surface that evaporates (the
        // curvature of e°(T) is not negligible) or convects with DOE-2 (its
        // small convection lets facets stray further from their reference,
        // where the curvature of T⁴ shows), unless the facet lies near its
        // reference and its background is small.
        // (The background is scanned only where it decides.)
        let curved = !rep.front.latent.is_empty()
            || matches!(facets.kinds[f], FacetThermal::Solve(i)
                if facets.props[i as usize].surface.is_none()
                    && facets.props[i as usize].convection.model
                        == crate::material::ConvectionModel::Doe2);
        let second = pass.second
            || (pass.last
                && curved
                && !(self.near[f]
                    && bgc.is_none_or(|(cf, cb)| {
                        let c = cf.abs().max(cb.abs());
                        s.bg.iter()
                            .all(|e| (c * e).abs() < super::SMALL_BACKGROUND_W_M2)
                    })));
        let full = second || (!pass.last && has_slot);
        if !full && let Some(base) = pass.base {
            self.image_from_base(rep, base, f, bgc, s, o);
            return;
        }
        let slot = self.slots.of_facet[f];
        if second
            && pass.reuse
            && slot != u32::MAX
            && let (Some(coarse), Some(first4), Some(base)) = (&rep.coarse, pass.prev4, pass.base)
        {
            let r = facets.forcing.len();
            let first4 = &first4[slot as usize * r..(slot as usize + 1) * r];
            self.second_order_from_first_pass(rep, coarse, f, first4, base, bgc, s, o);
            return;
        }
        let diff = Diff::of(&facets.state(f), &rep.facet);
        facets.sunlit_cos_into(f, &mut s.sc);
        if !full {
            // Pass 1, image records only.
            for (i, v) in o.iter_mut().enumerate() {
                *v = rep.front.temperature_k[self.image_records[i]] + rep.probe(i, &s.sc, diff);
            }
            return;
        }
        // The full first-order history of the front node: ΔS = ΔF·∂S/∂F
        // + (s cos θ − s cos θ_ref)·αE_dn (+ c·bg), the F terms and the
        // reference's sun one column each.
        let g = self.groups.of_solved(f);
        let sun = &self.groups.sun32[g];
        columns(s.sc.iter().zip(sun).map(|(a, b)| a * b), 1.0, &mut s.cols);
        let change = Change { diff, bgc };
        if second && let Some(coarse) = &rep.coarse {
            self.second_order_at_nodes(rep, coarse, g, change, s, o);
            return;
        }
        change.history(
            &rep.front,
            rep.has_back,
            &s.bg,
            &s.cols,
            &mut s.cols_bg,
            &mut s.d,
        );
        if second {
            if rep.has_back {
                change.history(
                    &rep.back,
                    rep.has_back,
                    &s.bg,
                    &s.cols,
                    &mut s.cols_bg,
                    &mut s.dback,
                );
            }
            self.second_order_image(rep, g, change, s, o);
            return;
        }
        for (v, &t) in o.iter_mut().zip(self.image_records) {
            *v = rep.front.temperature_k[t] + s.d[t];
        }
        let out4 = out4.expect("a full history before the last pass has a slot");
        for ((o, d), t) in out4.iter_mut().zip(&s.d).zip(&rep.front.temperature_k) {
            *o = (t + d).powi(4);
        }
    }

    /// From pass 2 on: the background excess history of `f` into `s.bg`
    /// and its coefficients `(c_front, c_back)` in the facet's sources;
    /// `None` in pass 1 or when the facet sees only sky.
    fn background_term(&self, pass: &Pass, f: usize, s: &mut Scratch) -> Option<(f32, f32)> {
        let facets = self.facets;
        let prev = pass.prev4?;
        if !facets.background_excess(f, prev, &self.slots.of_facet, &mut s.bg, &mut s.cols_bg) {
            return None;
        }
        let inputs = facets.inputs;
        let (cf, cb) = thermal::background_coefficients(
            facets.props_of(f),
            inputs.shape_factor[f] as f64,
            inputs.slab_back_shape_factor(f).map(f64::from),
        );
        Some((cf as f32, cb as f32))
    }

    /// A later pass without the full history: pass 1's image records plus
    /// the background term at the image rows.
    fn image_from_base(
        &self,
        rep: &Reference,
        base: &[f32],
        f: usize,
        bgc: Option<(f32, f32)>,
        s: &Scratch,
        o: &mut [f32],
    ) {
        let (wi, ni) = (self.width(), o.len());
        o.copy_from_slice(&base[f * wi..f * wi + ni]);
        if let Some((cf, cb)) = bgc {
            for (i, v) in o.iter_mut().enumerate() {
                *v += cf * dot(rep.row_front(i), &s.bg);
                if rep.has_back {
                    *v += cb * dot(rep.row_back(i), &s.bg);
                }
            }
        }
    }

    /// The second pass with the second-order correction at the curvature
    /// nodes, for a facet pass 1 kept the history of (its `T⁴`, `first4`):
    /// pass 1's first-order change `Δ¹ = T¹ − T_ref` at the front's nodes
    /// plus the background term `G·(c·bg)` there is the change
    /// [`PassPlan::second_order_at_nodes`] forms from the facet's sources
    /// (its reference path), and pass 1's image records plus the
    /// background term at the image rows ([`PassPlan::image_from_base`]) its
    /// first order. Only the back node (an exposed back; pass 1 keeps the
    /// front alone) is formed from the sources. The fourth root of the
    /// `f32` `T⁴` costs ≈ 3·10⁻⁵ K of `Δ¹` (the `f32` resolution at 300 K),
    /// far below what moves the curvature.
    #[allow(clippy::too_many_arguments)]
    fn second_order_from_first_pass(
        &self,
        rep: &Reference,
        coarse: &Coarse,
        f: usize,
        first4: &[f32],
        base: &[f32],
        bgc: Option<(f32, f32)>,
        s: &mut Scratch,
        o: &mut [f32],
    ) {
        let facets = self.facets;
        let nn = coarse.front.temperature_k.len();
        let nodes = &coarse.records;
        // The front's first-order change at the nodes: pass 1's, plus the
        // background term.
        for ((d, &t), tr) in s.d[..nn]
            .iter_mut()
            .zip(nodes)
            .zip(&coarse.front.temperature_k)
        {
            *d = first4[t as usize].sqrt().sqrt() - tr;
        }
        if let Some((cf, cb)) = bgc {
            columns(s.bg.iter().copied(), cf, &mut s.cols_bg);
            matvec_cols(&coarse.front.from_front, &s.cols_bg, &mut s.d[..nn]);
            if rep.has_back {
                columns(s.bg.iter().copied(), cb, &mut s.cols_bg);
                matvec_cols(&coarse.front.from_back, &s.cols_bg, &mut s.d[..nn]);
            }
        }
        // The back node's, from the sources.
        if rep.has_back {
            let diff = Diff::of(&facets.state(f), &rep.facet);
            facets.sunlit_cos_into(f, &mut s.sc);
            let sun = &self.groups.sun32[self.groups.of_solved(f)];
            columns(s.sc.iter().zip(sun).map(|(a, b)| a * b), 1.0, &mut s.cols);
            Change { diff, bgc }.history(
                &coarse.back,
                rep.has_back,
                &s.bg,
                &s.cols,
                &mut s.cols_bg,
                &mut s.dback[..nn],
            );
        }
        self.node_curvatures(rep, coarse, s);
        self.image_from_base(rep, base, f, bgc, s, o);
        for (i, v) in o.iter_mut().enumerate() {
            let w = &coarse.weights_front[i * nn..(i + 1) * nn];
            let mut x = dot(w, &s.curv[..nn]);
            if rep.has_back {
                let w = &coarse.weights_back[i * nn..(i + 1) * nn];
                x += dot(w, &s.curv_back[..nn]);
            }
            *v += x;
        }
    }

    /// The curvature at the nodes of the front (`s.curv`) and back
    /// (`s.curv_back`) nodes from their first-order changes there (`s.d`,
    /// `s.dback`).
    fn node_curvatures(&self, rep: &Reference, coarse: &Coarse, s: &mut Scratch) {
        let nn = coarse.front.temperature_k.len();
        let (latent, sat) = (&coarse.front.latent, &coarse.front.saturation);
        for (n, (c, (d, t))) in s.curv[..nn]
            .iter_mut()
            .zip(s.d.iter().zip(&coarse.front.temperature_k))
            .enumerate()
        {
            *c = curvature(coarse.front.radiative, *t, *d);
            if let (Some(&gv), Some(&e)) = (latent.get(n), sat.get(n)) {
                *c += latent_curvature_about(gv, e, f64::from(*t), f64::from(*d)) as f32;
            }
        }
        if rep.has_back {
            for (c, (d, t)) in s.curv_back[..nn]
                .iter_mut()
                .zip(s.dback.iter().zip(&coarse.back.temperature_k))
            {
                *c = curvature(coarse.back.radiative, *t, *d);
            }
        }
    }

    /// The last pass with the second-order correction at the curvature
    /// nodes (`super::nodes`): `T = T_ref + G ΔS + Σ_n w_n r(Δ_n)` at the
    /// image records, the first order `G ΔS` exact, `Δ_n` the first-order
    /// change of the front and back nodes at the node records only. With
    /// every record a node it is [`PassPlan::second_order_image`].
    fn second_order_at_nodes(
        &self,
        rep: &Reference,
        coarse: &Coarse,
        g: usize,
        change: Change,
        s: &mut Scratch,
        o: &mut [f32],
    ) {
        let groups = self.groups;
        let nn = coarse.front.temperature_k.len();
        // The first-order change at the nodes.
        change.history(
            &coarse.front,
            rep.has_back,
            &s.bg,
            &s.cols,
            &mut s.cols_bg,
            &mut s.d[..nn],
        );
        if rep.has_back {
            change.history(
                &coarse.back,
                rep.has_back,
                &s.bg,
                &s.cols,
                &mut s.cols_bg,
                &mut s.dback[..nn],
            );
        }
        // Its curvature there.
        self.node_curvatures(rep, coarse, s);
        // The first-order sources at every record.
        let Change {
            diff: Diff { df, dfb, db },
            bgc,
        } = change;
        for (((((o, sc), rsc), w), sh), rd) in
            s.ds.iter_mut()
                .zip(&s.sc)
                .zip(&rep.facet.sc)
                .zip(&groups.sun32[g])
                .zip(&groups.shape32[g])
                .zip(&groups.refl_diffuse32[g])
        {
            *o = df * sh + db * rd + (sc - rsc) * w;
        }
        if let Some((cf, _)) = bgc {
            s.ds.iter_mut().zip(&s.bg).for_each(|(o, e)| *o += cf * e);
        }
        if rep.has_back {
            for (o, sh) in s.db.iter_mut().zip(&groups.back_shape32[g]) {
                *o = dfb * sh;
            }
            if let Some((_, cb)) = bgc {
                s.db.iter_mut().zip(&s.bg).for_each(|(o, e)| *o += cb * e);
            }
        }
        for (i, v) in o.iter_mut().enumerate() {
            let w = &coarse.weights_front[i * nn..(i + 1) * nn];
            let mut x = dot(rep.row_front(i), &s.ds) + dot(w, &s.curv[..nn]);
            if rep.has_back {
                let w = &coarse.weights_back[i * nn..(i + 1) * nn];
                x += dot(rep.row_back(i), &s.db) + dot(w, &s.curv_back[..nn]);
            }
            *v = rep.front.temperature_k[self.image_records[i]] + x;
        }
    }

    /// The last pass with the second-order correction: `T = T_ref + G (ΔS
    /// + r(Δ))` at the image records, `Δ = G ΔS` the first-order change of
    /// the front (`s.d`) and back (`s.dback`) nodes.
    fn second_order_image(
        &self,
        rep: &Reference,
        g: usize,
        change: Change,
        s: &mut Scratch,
        o: &mut [f32],
    ) {
        let groups = self.groups;
        let Change {
            diff: Diff { df, dfb, db },
            bgc,
        } = change;
        let sun = &groups.sun32[g];
        let refl = &groups.refl_diffuse32[g];
        let (latent, sat) = (&rep.front.latent, &rep.front.saturation);
        for (k, ((((((o, sc), rsc), w), sh), rd), (d, t))) in
            s.ds.iter_mut()
                .zip(&s.sc)
                .zip(&rep.facet.sc)
                .zip(sun)
                .zip(&groups.shape32[g])
                .zip(refl)
                .zip(s.d.iter().zip(&rep.front.temperature_k))
                .enumerate()
        {
            *o = df * sh + db * rd + (sc - rsc) * w + curvature(rep.front.radiative, *t, *d);
            if let (Some(&gv), Some(&e)) = (latent.get(k), sat.get(k)) {
                *o += latent_curvature_about(gv, e, f64::from(*t), f64::from(*d)) as f32;
            }
        }
        if let Some((cf, _)) = bgc {
            s.ds.iter_mut().zip(&s.bg).for_each(|(o, e)| *o += cf * e);
        }
        if rep.has_back {
            for ((o, sh), (d, t)) in
                s.db.iter_mut()
                    .zip(&groups.back_shape32[g])
                    .zip(s.dback.iter().zip(&rep.back.temperature_k))
            {
                *o = dfb * sh + curvature(rep.back.radiative, *t, *d);
            }
            if let Some((_, cb)) = bgc {
                s.db.iter_mut().zip(&s.bg).for_each(|(o, e)| *o += cb * e);
            }
        }
        for (i, v) in o.iter_mut().enumerate() {
            let mut x = dot(rep.row_front(i), &s.ds);
            if rep.has_back {
                x += dot(rep.row_back(i), &s.db);
            }
            *v = rep.front.temperature_k[self.image_records[i]] + x;
        }
    }
}

/// A facet's source differences from its reference: shape factors and
/// reflected diffuse coefficient, and the background coefficients
/// `(c_front, c_back)` when it has a background term.
#[derive(Clone, Copy)]
struct Change {
    diff: Diff,
    bgc: Option<(f32, f32)>,
}

impl Change {
    /// The first-order change history `y = G ΔS` of one node: the
    /// precomputed `ΔF·G∂S/∂F − G(s cos θ_ref αE_dn)` (`+ ΔF_b·G_b∂B/∂F_b`),
    /// plus `G` times the facet's sun columns `cols` (`s cos θ·αE_dn`) and
    /// its background term `c·bg`.
    fn history(
        &self,
        node: &NodeGreen,
        has_back: bool,
        bg: &[f32],
        cols: &[(u32, f32)],
        cols_bg: &mut Vec<(u32, f32)>,
        y: &mut [f32],
    ) {
        let Diff { df, dfb, db } = self.diff;
        for (((v, a), b), rd) in y
            .iter_mut()
            .zip(&node.shape)
            .zip(&node.reference_sun)
            .zip(&node.reflected_diffuse)
        {
            *v = df * a - b + db * rd;
        }
        if has_back {
            for (v, g) in y.iter_mut().zip(&node.back_shape) {
                *v += dfb * g;
            }
        }
        matvec_cols(&node.from_front, cols, y);
        if let Some((cf, cb)) = self.bgc {
            columns(bg.iter().copied(), cf, cols_bg);
            matvec_cols(&node.from_front, cols_bg, y);
            if has_back {
                columns(bg.iter().copied(), cb, cols_bg);
                matvec_cols(&node.from_back, cols_bg, y);
            }
        }
    }
}
