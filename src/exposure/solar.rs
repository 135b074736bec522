//! Solar history: per facet and time step, the sunlit fraction and the cosine
//! of the solar incidence angle.

use std::ops::Range;

use glam::Vec3;
use rayon::prelude::*;

use super::FacetSamples;
use crate::trace::{Coherence, Ray, Tracer};

/// Sunlit fraction and cosine of incidence of every facet at every step of a
/// history window, facet-major (`[facet * steps + step]`).
///
/// - `sun_fraction` ∈ [0, 1]: the share of the facet's sample points from
///   which a ray toward the sun reaches the sky unobstructed (each point
///   stands for an equal area, so this is the sunlit area fraction to
///   `1/n²`). It is exactly 0 when the sun is at or below the horizon, or
///   when a single-sided facet faces away from it, and exactly 0 or 1 when
///   all points agree.
/// - `cos_incidence` ∈ [0, 1]: `n·s` for the unit sun direction `s`, 0 when
///   the sun is below the horizon or behind a single-sided facet. For a
///   double-sided facet it is `|n·s|`: the face toward the sun is lit.
///
/// The absorbed direct solar flux is then
/// `α · E_dn · sun_fraction · cos_incidence` (W/m²).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SolarHistory {
    /// Time steps per facet.
    pub steps: usize,
    /// Sunlit fraction, `[facet * steps + step]`.
    pub sun_fraction: Vec<f32>,
    /// Cosine of the solar incidence angle, `[facet * steps + step]`.
    pub cos_incidence: Vec<f32>,
}

impl SolarHistory {
    /// Number of facets.
    pub fn facet_count(&self) -> usize {
        self.sun_fraction.len().checked_div(self.steps).unwrap_or(0)
    }
    /// Appends the facets of `other` (the same steps) after this
    /// history's.
    pub fn append(&mut self, other: SolarHistory) {
        debug_assert!(self.steps == other.steps || self.sun_fraction.is_empty());
        self.steps = other.steps;
        self.sun_fraction.extend(other.sun_fraction);
        self.cos_incidence.extend(other.cos_incidence);
    }
    /// Sunlit fraction of `facet` at every step.
    pub fn sun_fraction(&self, facet: usize) -> &[f32] {
        &self.sun_fraction[facet * self.steps..(facet + 1) * self.steps]
    }
    /// Cosine of incidence of `facet` at every step.
    pub fn cos_incidence(&self, facet: usize) -> &[f32] {
        &self.cos_incidence[facet * self.steps..(facet + 1) * self.steps]
    }
}

/// How [`solar_history`] hands its rays to the tracer: one step's rays are
/// parallel and start on neighbouring facets, so coherent (Embree's hint;
/// the answers are the same either way).
pub const RAY_COHERENCE: Coherence = Coherence::Coherent;

/// Appends to `rays` the occlusion rays that [`solar_history`] traces for
/// the facets `range` (one of its batches), in its order: step by step
/// (steps with the sun below the horizon skipped), within a step facet by
/// facet (facets facing away from the sun skipped, unless double-sided),
/// within a facet one ray per sample point, lifted off the plane toward the
/// sun. Trace them with [`RAY_COHERENCE`]. `irsig bench trace` uses this
/// to time the tracers on the exposure stage's own shadow rays.
pub fn solar_rays(
    facets: &FacetSamples,
    range: Range<usize>,
    sun_dirs: &[Vec3],
    rays: &mut Vec<Ray>,
) {
    lay_out_rays(facets, range, sun_dirs, rays, |_, _, _| {});
}

/// The rays of [`solar_rays`]; `visit(slot, cos, rays)` is called for each
/// (facet, step) the sun is in front of, `slot = (facet − range.start) ·
/// steps + step`, `cos` the facet normal · sun, `rays` the number of rays
/// pushed for it (`None` when the sun is exactly in the facet's plane).
fn lay_out_rays(
    facets: &FacetSamples,
    range: Range<usize>,
    sun_dirs: &[Vec3],
    rays: &mut Vec<Ray>,
    mut visit: impl FnMut(usize, f32, Option<u32>),
) {
    let steps = sun_dirs.len();
    for (s, &dir) in sun_dirs.iter().enumerate() {
        if dir.z <= 0.0 {
            continue;
        }
        for f in range.clone() {
            let c = facets.normal[f].dot(dir);
            let side = if facets.double_sided[f] {
                c.signum()
            } else if c > 0.0 {
                1.0
            } else {
                continue;
            };
            let slot = (f - range.start) * steps + s;
            if c == 0.0 {
                visit(slot, c, None);
                continue;
            }
            let lift = facets.normal[f] * (side * facets.offset_m);
            let pts = facets.facet_points(f);
            rays.extend(pts.iter().map(|&p| Ray::new(p + lift, dir)));
            visit(slot, c, Some(pts.len() as u32));
        }
    }
}

/// Traces the solar history of every facet: for each step whose sun is above
/// the horizon and in front of the facet, one occlusion ray per sample
/// point toward the sun. `sun_dirs` are unit east-north-up vectors toward
/// the sun, one per step, computed once for the scene (`z ≤ 0`: below the
/// horizon). Facets go through the tracer `batch_facets` at a time, batches
/// in parallel; each ray's answer depends only on its facet and step, so
/// the result is the same for any number of threads.
///
/// `stride` > 1 traces coarse steps first: in each run of consecutive steps
/// with the sun in front of the facet, every `stride`-th step and the run's
/// last. Where a sample point's two neighbouring coarse steps agree (lit at
/// both, or shaded at both) the steps between them take that answer; where
/// they differ, every step between them is traced. A shadow that comes and
/// goes between two coarse steps is missed (`irsig bench exposure` measures
/// how often); `stride` 1 traces every step.
pub fn solar_history<T: Tracer + ?Sized>(
    tracer: &T,
    facets: &FacetSamples,
    sun_dirs: &[Vec3],
    batch_facets: usize,
    stride: u32,
) -> (SolarHistory, u64) {
    solar_history_of(
        tracer,
        facets,
        sun_dirs,
        batch_facets,
        stride,
        0..facets.len(),
        &|_| {},
    )
}

/// [`solar_history`] of the facets `range` only (the history holds those
/// facets, in order), calling `done(n)` as each batch of `n` facets is
/// traced. Batches start at `range.start`: a range that starts on a
/// multiple of `batch_facets` traces the very batches of the whole scene's
/// run, so its facets get the same answers bit for bit.
pub fn solar_history_of<T: Tracer + ?Sized>(
    tracer: &T,
    facets: &FacetSamples,
    sun_dirs: &[Vec3],
    batch_facets: usize,
    stride: u32,
    range: Range<usize>,
    done: &(dyn Fn(u64) + Sync),
) -> (SolarHistory, u64) {
    let steps = sun_dirs.len();
    let (start, end) = (range.start, range.end.min(facets.len()));
    let n = end.saturating_sub(start);
    let batch = batch_facets.max(1);
    let stride = stride.max(1) as usize;
    // Every batch writes straight into its part of the history (no
    // per-batch result vectors, no copy afterwards); each worker reuses
    // its ray and answer buffers from batch to batch.
    let mut out = SolarHistory {
        steps,
        sun_fraction: vec![0.0; n * steps],
        cos_incidence: vec![0.0; n * steps],
    };
    if steps == 0 || n == 0 {
        return (out, 0);
    }
    let rays = out
        .sun_fraction
        .par_chunks_mut(batch * steps)
        .zip(out.cos_incidence.par_chunks_mut(batch * steps))
        .enumerate()
        .map_init(Scratch::default, |scratch, (c, (frac, cosi))| {
            let f0 = start + c * batch;
            let f1 = f0 + frac.len() / steps;
            let r = if stride == 1 {
                exhaustive_batch(tracer, facets, sun_dirs, f0..f1, frac, cosi, scratch)
            } else {
                refined_batch(tracer, facets, sun_dirs, f0..f1, stride, frac, cosi)
            };
            done((f1 - f0) as u64);
            r
        })
        .sum();
    (out, rays)
}

/// A worker's buffers, reused from batch to batch.
#[derive(Default)]
struct Scratch {
    rays: Vec<Ray>,
    occluded: Vec<bool>,
    /// (slot in the batch's history, number of rays) per traced (facet, step).
    slots: Vec<(u32, u32)>,
}

/// One batch of [`solar_history`] with every step traced: fills the
/// batch's `frac` and `cosi` (`[(facet − range.start) · steps + step]`,
/// zero on entry) and returns the number of rays.
fn exhaustive_batch<T: Tracer + ?Sized>(
    tracer: &T,
    facets: &FacetSamples,
    sun_dirs: &[Vec3],
    range: Range<usize>,
    frac: &mut [f32],
    cosi: &mut [f32],
    scratch: &mut Scratch,
) -> u64 {
    let Scratch {
        rays,
        occluded,
        slots,
    } = scratch;
    rays.clear();
    slots.clear();
    lay_out_rays(facets, range, sun_dirs, rays, |slot, c, m| {
        cosi[slot] = c.abs().min(1.0);
        if let Some(m) = m {
            slots.push((slot as u32, m));
        }
    });
    occluded.clear();
    occluded.resize(rays.len(), false);
    tracer.occluded(rays, RAY_COHERENCE, occluded);
    let mut k = 0usize;
    for &(slot, m) in slots.iter() {
        let lit = occluded[k..k + m as usize].iter().filter(|&&o| !o).count();
        frac[slot as usize] = lit as f32 / m as f32;
        k += m as usize;
    }
    rays.len() as u64
}

/// Per (facet, step, point) of a refined batch: not traced yet.
const UNKNOWN: u8 = 0;
/// Lit (the ray reached the sky).
const LIT: u8 = 1;
/// Shaded.
const SHADED: u8 = 2;

/// One batch of [`solar_history`] with coarse steps refined where a sample
/// point's visibility changes.
fn refined_batch<T: Tracer + ?Sized>(
    tracer: &T,
    facets: &FacetSamples,
    sun_dirs: &[Vec3],
    range: Range<usize>,
    stride: usize,
    frac: &mut [f32],
    cosi: &mut [f32],
) -> u64 {
    let steps = sun_dirs.len();
    let (nf, f0, m) = (range.len(), range.start, facets.per_facet);
    // Per (facet, step): the side the sun is on (0: no ray), and whether
    // the step is a coarse one.
    let mut side = vec![0i8; nf * steps];
    let mut coarse = vec![false; nf * steps];
    for f in range.clone() {
        let i = f - f0;
        for (s, &dir) in sun_dirs.iter().enumerate() {
            if dir.z <= 0.0 {
                continue;
            }
            let c = facets.normal[f].dot(dir);
            if facets.double_sided[f] || c >= 0.0 {
                cosi[i * steps + s] = c.abs().min(1.0);
            }
            side[i * steps + s] = if c == 0.0 {
                0
            } else if facets.double_sided[f] {
                c.signum() as i8
            } else if c > 0.0 {
                1
            } else {
                0
            };
        }
        // Runs of consecutive steps with rays from one side: their first,
        // every stride-th and last steps are coarse.
        let side = &side[i * steps..(i + 1) * steps];
        let mut s = 0;
        while s < steps {
            let sd = side[s];
            if sd == 0 {
                s += 1;
                continue;
            }
            let a = s;
            while s + 1 < steps && side[s + 1] == sd {
                s += 1;
            }
            for t in (a..=s).step_by(stride) {
                coarse[i * steps + t] = true;
            }
            coarse[i * steps + s] = true;
            s += 1;
        }
    }
    let mut state = vec![UNKNOWN; nf * steps * m];
    let mut total = 0u64;
    // Traces the points of the (facet, step) slots `want` says, step by
    // step (one step's rays are parallel), and records their answers.
    let trace = |want: &dyn Fn(usize, usize) -> bool, state: &mut [u8]| {
        let mut rays = Vec::new();
        let mut idx = Vec::new();
        for (s, &dir) in sun_dirs.iter().enumerate() {
            for i in 0..nf {
                let slot = i * steps + s;
                if side[slot] == 0 {
                    continue;
                }
                let f = f0 + i;
                let lift = facets.normal[f] * (side[slot] as f32 * facets.offset_m);
                for (p, &pt) in facets.facet_points(f).iter().enumerate() {
                    if want(slot, p) {
                        rays.push(Ray::new(pt + lift, dir));
                        idx.push(slot * m + p);
                    }
                }
            }
        }
        let mut occ = vec![false; rays.len()];
        tracer.occluded(&rays, RAY_COHERENCE, &mut occ);
        for (&k, &o) in idx.iter().zip(&occ) {
            state[k] = if o { SHADED } else { LIT };
        }
        rays.len() as u64
    };
    total += trace(&|slot, _| coarse[slot], &mut state);
    // Between two coarse steps of a run that disagree: trace every step.
    let mut need = vec![false; nf * steps * m];
    for i in 0..nf {
        for p in 0..m {
            let mut prev: Option<usize> = None;
            for s in 0..steps {
                let slot = i * steps + s;
                if side[slot] == 0 {
                    prev = None;
                    continue;
                }
                if !coarse[slot] {
                    continue;
                }
                if let Some(a) = prev
                    && state[(i * steps + a) * m + p] != state[slot * m + p]
                {
                    for t in a + 1..s {
                        need[(i * steps + t) * m + p] = true;
                    }
                }
                prev = Some(s);
            }
        }
    }
    total += trace(&|slot, p| need[slot * m + p], &mut state);
    // The rest take the answer of the coarse step after them.
    let mut lit = vec![0u32; nf * steps];
    for i in 0..nf {
        for p in 0..m {
            let mut next = UNKNOWN;
            for s in (0..steps).rev() {
                let k = (i * steps + s) * m + p;
                if side[i * steps + s] == 0 {
                    next = UNKNOWN;
                    continue;
                }
                if state[k] == UNKNOWN {
                    state[k] = next;
                } else {
                    next = state[k];
                }
                lit[i * steps + s] += (state[k] == LIT) as u32;
            }
        }
    }
    for (f, &l) in frac.iter_mut().zip(&lit) {
        *f = l as f32 / m as f32;
    }
    total
}
