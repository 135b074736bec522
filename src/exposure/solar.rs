//! Solar history: per facet and time step, the sunlit fraction and the cosine
//! of the solar incidence angle.

use std::ops::Range;

use glam::Vec3;
use rayon::prelude::*;

use super::FacetSamples;
use crate::trace::{Coherence, Ray, Tracer};
use crate::{Error, Result};

/// The solar history of every facet over a history window, stored compactly:
/// per facet and **day record** (the sun above the horizon; the records are
/// the same for every facet), the number of its sample points that see the
/// sun, one byte (two when a facet has more than 255 points). Night records
/// hold nothing, and the cosine of incidence is not stored: it follows from
/// the facet's normal and the sun's direction at the record
/// ([`crate::geometry::sun_cosine`]). Per facet and record:
///
/// - `sun_fraction` ∈ [0, 1] = lit points / points: the share of the facet's
///   sample points from which a ray toward the sun reaches the sky
///   unobstructed (each point stands for an equal area, so this is the
///   sunlit area fraction to `1/n²`). It is exactly 0 when the sun is at or
///   below the horizon, or when a single-sided facet faces away from it, and
///   exactly 0 or 1 when all points agree. As `f32` it is `lit as f32 /
///   points as f32`, the value the exhaustive per-record arrays held.
/// - `cos_incidence` ∈ [0, 1]: `n·s` for the unit sun direction `s`, 0 when
///   the sun is below the horizon or behind a single-sided facet. For a
///   double-sided facet it is `|n·s|`: the face toward the sun is lit.
///
/// The absorbed direct solar flux is then
/// `α · E_dn · sun_fraction · cos_incidence` (W/m²).
///
/// Memory: `day records` bytes per facet (≈ 60 in June at 15 min) plus
/// 13 bytes of normal and flag, against 8 bytes per record (≈ 780) as two
/// `f32` arrays.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SolarHistory {
    /// Records (time steps) per facet.
    pub steps: usize,
    /// Facets.
    pub facets: usize,
    /// The records with the sun above the horizon (`z > 0`), ascending.
    pub day: Vec<u32>,
    /// Sample points per facet.
    pub points: u32,
    /// Lit sample points per facet and day record, `[facet · day.len() +
    /// d]`: one byte each, or two (little-endian) when `points > 255`.
    pub lit: Vec<u8>,
    /// Unit vector toward the sun at each record (`steps` of them).
    pub sun: Vec<Vec3>,
    /// Unit front normal per facet.
    pub normal: Vec<Vec3>,
    /// Whether the facet is double-sided, per facet.
    pub double_sided: Vec<bool>,
}

impl SolarHistory {
    /// An empty history of no facet over the records of `sun` (directions
    /// toward the sun, one per record) with `points` sample points per
    /// facet.
    pub fn empty(sun: &[Vec3], points: u32) -> SolarHistory {
        SolarHistory {
            steps: sun.len(),
            facets: 0,
            day: day_records(sun),
            points: points.max(1),
            lit: Vec::new(),
            sun: sun.to_vec(),
            normal: Vec::new(),
            double_sided: Vec::new(),
        }
    }

    /// The compact history of sun fractions given as one `f32` per facet
    /// and record (`[facet · steps + record]`, the exhaustive layout), for
    /// facets with `normal` and `double_sided`, `points` sample points
    /// each, under the sun directions `sun` (one per record).
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the facet and record where a value is not
    /// a multiple of `1/points` in [0, 1], or is not 0 with the sun below
    /// the horizon; or lengths that do not match.
    pub fn from_fractions(
        sun_fraction: &[f32],
        sun: &[Vec3],
        points: u32,
        normal: &[Vec3],
        double_sided: &[bool],
    ) -> Result<SolarHistory> {
        let (steps, n) = (sun.len(), normal.len());
        if sun_fraction.len() != n * steps || double_sided.len() != n {
            return Err(Error::invalid(
                "sun_fraction",
                format!(
                    "expected {steps} records for each of {n} facets (and {n} flags), got {} \
                     values and {} flags",
                    sun_fraction.len(),
                    double_sided.len()
                ),
            ));
        }
        let mut h = SolarHistory::empty(sun, points);
        h.facets = n;
        h.normal = normal.to_vec();
        h.double_sided = double_sided.to_vec();
        let nd = h.day.len();
        let w = h.width();
        h.lit = vec![0; n * nd * w];
        let m = h.points;
        for f in 0..n {
            for r in 0..steps {
                let s = sun_fraction[f * steps + r];
                let k = (s * m as f32).round();
                let d = h.day.binary_search(&(r as u32));
                let ok =
                    (0.0..=m as f32).contains(&k) && s == k / m as f32 && (d.is_ok() || k == 0.0);
                if !ok {
                    return Err(Error::invalid(
                        format!("sun_fraction[facet {f}, record {r}]"),
                        format!(
                            "{s} is not a multiple of 1/{m} in [0, 1]{}",
                            if d.is_err() {
                                " that is 0 with the sun below the horizon"
                            } else {
                                ""
                            }
                        ),
                    ));
                }
                if let Ok(d) = d {
                    h.set_lit(f * nd + d, k as u32);
                }
            }
        }
        Ok(h)
    }

    /// Bytes per lit count: 1, or 2 for more than 255 points.
    #[inline]
    pub fn width(&self) -> usize {
        lit_width(self.points)
    }

    /// Number of facets.
    pub fn facet_count(&self) -> usize {
        self.facets
    }

    /// Lit points of entry `i` (`facet · day.len() + d`).
    #[inline]
    fn lit_of(&self, i: usize) -> u32 {
        lit_get(&self.lit, self.width(), i)
    }

    fn set_lit(&mut self, i: usize, v: u32) {
        let w = self.width();
        lit_set(&mut self.lit, w, i, v);
    }

    /// Lit sample points of `facet` at day record `d` (the record
    /// `day[d]`).
    #[inline]
    pub fn lit_points(&self, facet: usize, d: usize) -> u32 {
        self.lit_of(facet * self.day.len() + d)
    }

    /// Appends the facets of `other` (the same records and points) after
    /// this history's.
    pub fn append(&mut self, other: SolarHistory) {
        debug_assert!((self.day == other.day && self.points == other.points) || self.facets == 0);
        if self.facets == 0 {
            self.steps = other.steps;
            self.day = other.day;
            self.points = other.points;
            self.sun = other.sun;
        }
        self.facets += other.facets;
        self.lit.extend(other.lit);
        self.normal.extend(other.normal);
        self.double_sided.extend(other.double_sided);
    }

    /// Sunlit fraction of `facet` at `record`.
    #[inline]
    pub fn sun_fraction_at(&self, facet: usize, record: usize) -> f32 {
        match self.day.binary_search(&(record as u32)) {
            Ok(d) => self.lit_points(facet, d) as f32 / self.points as f32,
            Err(_) => 0.0,
        }
    }

    /// Cosine of incidence of `facet` at `record`
    /// ([`crate::geometry::sun_cosine`]).
    #[inline]
    pub fn cos_incidence_at(&self, facet: usize, record: usize) -> f32 {
        crate::geometry::sun_cosine(
            self.normal[facet],
            self.double_sided[facet],
            self.sun[record],
        )
    }

    /// Writes the sunlit fraction of `facet` at every record into `out`
    /// (`steps` values).
    pub fn sun_fraction_into(&self, facet: usize, out: &mut [f32]) {
        out.fill(0.0);
        let (nd, m) = (self.day.len(), self.points as f32);
        for (d, &r) in self.day.iter().enumerate() {
            out[r as usize] = self.lit_of(facet * nd + d) as f32 / m;
        }
    }

    /// Writes the cosine of incidence of `facet` at every record into `out`
    /// (`steps` values).
    pub fn cos_incidence_into(&self, facet: usize, out: &mut [f32]) {
        let (n, ds) = (self.normal[facet], self.double_sided[facet]);
        for (o, &s) in out.iter_mut().zip(&self.sun) {
            *o = crate::geometry::sun_cosine(n, ds, s);
        }
    }

    /// Sunlit fraction of `facet` at every record.
    pub fn sun_fraction(&self, facet: usize) -> Vec<f32> {
        let mut v = vec![0.0; self.steps];
        self.sun_fraction_into(facet, &mut v);
        v
    }

    /// Cosine of incidence of `facet` at every record.
    pub fn cos_incidence(&self, facet: usize) -> Vec<f32> {
        let mut v = vec![0.0; self.steps];
        self.cos_incidence_into(facet, &mut v);
        v
    }

    /// Heap bytes held.
    pub fn heap_bytes(&self) -> usize {
        self.lit.capacity()
            + 4 * self.day.capacity()
            + 12 * (self.sun.capacity() + self.normal.capacity())
            + self.double_sided.capacity()
    }
}

/// The records of `sun` with the sun above the horizon.
pub(crate) fn day_records(sun: &[Vec3]) -> Vec<u32> {
    (0..sun.len() as u32)
        .filter(|&r| sun[r as usize].z > 0.0)
        .collect()
}

/// Bytes per lit count for `points` sample points.
#[inline]
fn lit_width(points: u32) -> usize {
    if points > 255 { 2 } else { 1 }
}

#[inline]
fn lit_get(lit: &[u8], w: usize, i: usize) -> u32 {
    if w == 1 {
        lit[i] as u32
    } else {
        u16::from_le_bytes([lit[2 * i], lit[2 * i + 1]]) as u32
    }
}

#[inline]
fn lit_set(lit: &mut [u8], w: usize, i: usize, v: u32) {
    if w == 1 {
        lit[i] = v as u8;
    } else {
        lit[2 * i..2 * i + 2].copy_from_slice(&(v as u16).to_le_bytes());
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
    lay_out_rays(facets, range, sun_dirs, rays, |_, _| {});
}

/// The rays of [`solar_rays`]; `visit(slot, rays)` is called for each
/// (facet, day record) the sun is in front of, `slot = (facet −
/// range.start) · day records + d` (`d` counting the records with the sun
/// above the horizon), `rays` the number of rays pushed for it (`None` when
/// the sun is exactly in the facet's plane).
fn lay_out_rays(
    facets: &FacetSamples,
    range: Range<usize>,
    sun_dirs: &[Vec3],
    rays: &mut Vec<Ray>,
    mut visit: impl FnMut(usize, Option<u32>),
) {
    let nd = sun_dirs.iter().filter(|d| d.z > 0.0).count();
    for (d, &dir) in sun_dirs.iter().filter(|d| d.z > 0.0).enumerate() {
        for f in range.clone() {
            let c = facets.normal[f].dot(dir);
            let side = if facets.double_sided[f] {
                c.signum()
            } else if c > 0.0 {
                1.0
            } else {
                continue;
            };
            let slot = (f - range.start) * nd + d;
            if c == 0.0 {
                visit(slot, None);
                continue;
            }
            let lift = facets.normal[f] * (side * facets.offset_m);
            let pts = facets.facet_points(f);
            rays.extend(pts.iter().map(|&p| Ray::new(p + lift, dir)));
            visit(slot, Some(pts.len() as u32));
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
    let (start, end) = (range.start, range.end.min(facets.len()));
    let n = end.saturating_sub(start);
    let batch = batch_facets.max(1);
    let stride = stride.max(1) as usize;
    // Every batch writes straight into its part of the history (no
    // per-batch result vectors, no copy afterwards); each worker reuses
    // its ray and answer buffers from batch to batch.
    let mut out = SolarHistory::empty(sun_dirs, facets.per_facet as u32);
    out.facets = n;
    out.normal = facets.normal[start..start + n].to_vec();
    out.double_sided = facets.double_sided[start..start + n].to_vec();
    let (nd, w) = (out.day.len(), out.width());
    out.lit = vec![0; n * nd * w];
    if nd == 0 || n == 0 {
        return (out, 0);
    }
    let rays = out
        .lit
        .par_chunks_mut(batch * nd * w)
        .enumerate()
        .map_init(Scratch::default, |scratch, (c, lit)| {
            let f0 = start + c * batch;
            let f1 = f0 + lit.len() / (nd * w);
            let r = if stride == 1 {
                exhaustive_batch(tracer, facets, sun_dirs, f0..f1, lit, w, scratch)
            } else {
                refined_batch(tracer, facets, sun_dirs, f0..f1, stride, lit, w)
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
    /// (day slot in the batch's history, number of rays) per traced (facet,
    /// day record).
    slots: Vec<(u32, u32)>,
}

/// One batch of [`solar_history`] with every step traced: fills the
/// batch's lit counts `lit` (`[(facet − range.start) · day records + d]`,
/// `w` bytes each, zero on entry) and returns the number of rays.
fn exhaustive_batch<T: Tracer + ?Sized>(
    tracer: &T,
    facets: &FacetSamples,
    sun_dirs: &[Vec3],
    range: Range<usize>,
    lit: &mut [u8],
    w: usize,
    scratch: &mut Scratch,
) -> u64 {
    let Scratch {
        rays,
        occluded,
        slots,
    } = scratch;
    rays.clear();
    slots.clear();
    lay_out_rays(facets, range, sun_dirs, rays, |slot, m| {
        if let Some(m) = m {
            slots.push((slot as u32, m));
        }
    });
    occluded.clear();
    occluded.resize(rays.len(), false);
    tracer.occluded(rays, RAY_COHERENCE, occluded);
    let mut k = 0usize;
    for &(slot, m) in slots.iter() {
        let n = occluded[k..k + m as usize].iter().filter(|&&o| !o).count();
        lit_set(lit, w, slot as usize, n as u32);
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
/// point's visibility changes; fills `lit` as [`exhaustive_batch`] does.
fn refined_batch<T: Tracer + ?Sized>(
    tracer: &T,
    facets: &FacetSamples,
    sun_dirs: &[Vec3],
    range: Range<usize>,
    stride: usize,
    lit_out: &mut [u8],
    w: usize,
) -> u64 {
    // The day records only; a run of steps never spans a night (two day
    // records that are not consecutive records).
    let day: Vec<usize> = (0..sun_dirs.len())
        .filter(|&s| sun_dirs[s].z > 0.0)
        .collect();
    let steps = day.len();
    let (nf, f0, m) = (range.len(), range.start, facets.per_facet);
    // Per (facet, day record): the side the sun is on (0: no ray), and
    // whether the step is a coarse one.
    let mut side = vec![0i8; nf * steps];
    let mut coarse = vec![false; nf * steps];
    for f in range.clone() {
        let i = f - f0;
        for (s, &r) in day.iter().enumerate() {
            let c = facets.normal[f].dot(sun_dirs[r]);
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
        // every stride-th and last steps are coarse. A run ends at a night.
        let side = &side[i * steps..(i + 1) * steps];
        let mut s = 0;
        while s < steps {
            let sd = side[s];
            if sd == 0 {
                s += 1;
                continue;
            }
            let a = s;
            while s + 1 < steps && side[s + 1] == sd && day[s + 1] == day[s] + 1 {
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
        for (s, &r) in day.iter().enumerate() {
            let dir = sun_dirs[r];
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
                if side[slot] == 0 || (s > 0 && day[s] != day[s - 1] + 1) {
                    prev = None;
                }
                if side[slot] == 0 {
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
                if side[i * steps + s] == 0 || (s + 1 < steps && day[s + 1] != day[s] + 1) {
                    next = UNKNOWN;
                }
                if side[i * steps + s] == 0 {
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
    for (i, &l) in lit.iter().enumerate() {
        lit_set(lit_out, w, i, l);
    }
    total
}
