//! Shape factor (sky view factor) and background of every facet, from
//! hemisphere rays.
//!
//! Owns the hemisphere sampling choice ([`SkySampling`]) and the ray casting
//! of it. Takes the facets' sample points and a [`Tracer`]; gives a
//! [`SkyView`] (each facet face's shape factor and the facets its rays
//! hit, with weights) and the ray count. Must not know temperatures or the
//! thermal solve that consumes them.

use rand::Rng;
use rayon::prelude::*;

use super::FacetSamples;
use super::sampling::{
    HemiSample, dirsig_grid, jitter_rng, r2_shift, rotated_cosine_into, stratified_side,
};
use crate::geometry::{BackgroundEntry, SceneGeometry};
use crate::trace::{Coherence, Hit, Ray, Tracer};

/// How the hemisphere over a facet is sampled for its shape factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SkySampling {
    /// A fixed grid of zenith bands × azimuth sectors, one ray per cell,
    /// cosine-weighted cell weights. [`SkySampling::DIRSIG`] (15° × 30°, 72
    /// rays) is DIRSIG's grid. It is exact for an unobstructed horizontal
    /// facet; for tilted facets the horizon cuts cells, and its quadrature
    /// error reaches a few per cent (15°×30°: −3.8 % at 75° tilt).
    Grid {
        /// Zenith band width, degrees (90 / it is rounded to an integer).
        zenith_step_deg: f32,
        /// Azimuth sector width, degrees (360 / it is rounded to an integer).
        azimuth_step_deg: f32,
    },
    /// Stratified cosine-weighted sampling: `m × m` jittered strata with
    /// `m = ⌈√samples⌉` rounded up to even. The strata's jitter is drawn
    /// once from the seed and rotated per facet by the facet's point of a
    /// low-discrepancy sequence ([`super::sampling::rotated_cosine`]): every
    /// facet's estimate is unbiased, neighbouring facets' errors partly
    /// cancel, no direction is favoured across the scene (no azimuthal
    /// star), and the result is reproducible.
    Stratified {
        /// Requested number of rays per facet face.
        samples: u32,
    },
}

impl SkySampling {
    /// What every face's pattern is made from: the fixed directions of a
    /// [`SkySampling::Grid`], or the fixed jitter of the strata of
    /// [`SkySampling::Stratified`] (drawn once from `seed`).
    fn base(self, seed: u64) -> Base {
        match self {
            SkySampling::Grid {
                zenith_step_deg,
                azimuth_step_deg,
            } => Base::Grid(dirsig_grid(zenith_step_deg, azimuth_step_deg)),
            SkySampling::Stratified { samples } => {
                let m = stratified_side(samples);
                let mut rng = jitter_rng(seed, u64::MAX);
                Base::Stratified(
                    m,
                    (0..m * m)
                        .map(|_| (rng.random::<f32>(), rng.random::<f32>()))
                        .collect(),
                )
            }
        }
    }

    /// DIRSIG's fixed grid: 15° zenith × 30° azimuth (72 rays per face).
    pub const DIRSIG: SkySampling = SkySampling::Grid {
        zenith_step_deg: 15.0,
        azimuth_step_deg: 30.0,
    };

    /// Rays per facet face.
    pub fn rays_per_face(&self) -> usize {
        match *self {
            SkySampling::Grid {
                zenith_step_deg,
                azimuth_step_deg,
            } => {
                let nz = (90.0 / zenith_step_deg).round().max(1.0) as usize;
                let na = (360.0 / azimuth_step_deg).round().max(1.0) as usize;
                nz * na
            }
            SkySampling::Stratified { samples } => {
                let m = super::sampling::stratified_side(samples) as usize;
                m * m
            }
        }
    }
}

impl std::str::FromStr for SkySampling {
    type Err = crate::Error;
    /// `dirsig` (or `grid`): DIRSIG's 15°×30° grid; `grid:DZxDA` (degrees,
    /// e.g. `grid:5x10`); `stratified:N` (N rays per face).
    fn from_str(s: &str) -> crate::Result<Self> {
        let bad = || {
            crate::Error::invalid(
                "sky sampling",
                format!("`{s}`: expected `dirsig`, `grid:DZxDA` (degrees) or `stratified:N`"),
            )
        };
        match s.split_once(':') {
            None if s == "dirsig" || s == "grid" => Ok(SkySampling::DIRSIG),
            Some(("grid", g)) => {
                let (z, a) = g.split_once('x').ok_or_else(bad)?;
                let (z, a): (f32, f32) =
                    (z.parse().map_err(|_| bad())?, a.parse().map_err(|_| bad())?);
                if !(z.is_finite()
                    && (0.5..=90.0).contains(&z)
                    && a.is_finite()
                    && (0.5..=360.0).contains(&a))
                {
                    return Err(bad());
                }
                Ok(SkySampling::Grid {
                    zenith_step_deg: z,
                    azimuth_step_deg: a,
                })
            }
            Some(("stratified", n)) => match n.parse::<u32>() {
                Ok(samples @ 1..=1_048_576) => Ok(SkySampling::Stratified { samples }),
                _ => Err(bad()),
            },
            _ => Err(bad()),
        }
    }
}

impl Default for SkySampling {
    /// Stratified, 64 rays per face (8 × 8 strata): fewer rays than DIRSIG's
    /// 72-ray grid, and no azimuthal star around tall objects.
    fn default() -> Self {
        SkySampling::Stratified { samples: 64 }
    }
}

impl<'de> serde::Deserialize<'de> for SkySampling {
    /// From the text of [`std::str::FromStr`] (`stratified:64`, `dirsig`,
    /// `grid:15x30`).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse()
            .map_err(|e: crate::Error| serde::de::Error::custom(e))
    }
}

/// The sky view of every facet, in global facet order.
///
/// For every facet, the view factors add up to one:
/// `shape_factor + ground_weight + Σ background.weight = 1`, where
/// - `shape_factor` F is the view factor to the sky dome: rays that hit
///   nothing and leave upward (`z > 0`);
/// - `ground_weight` is rays that hit nothing and leave downward (`z ≤ 0`,
///   possible for tilted facets): the ground beyond the modelled scene, or
///   below the horizon, whose temperature is taken as air-like;
/// - `background` lists the facets hit, merged by id, sorted by id.
///
/// For a double-sided facet `shape_factor` is its front face's F,
/// `back_shape_factor` its back face's, and the ground weight and background
/// are the mean over both faces (each face's rays carry half weight), so
/// that `(F + F_back)/2 + ground_weight + Σ background.weight = 1`.
/// The longwave background term of the thermal balance uses `1 − F` with
/// the radiative mean `T_bg⁴ = (Σ wᵢ Tᵢ⁴ + g·T_ground⁴) / (1 − F)`
/// ([`SkyView::background_temperature`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SkyView {
    /// Shape factor F (view factor to the sky) of the front face, per facet.
    pub shape_factor: Vec<f32>,
    /// Shape factor of the back face of double-sided facets (`None` for
    /// single-sided ones).
    pub back_shape_factor: Vec<Option<f32>>,
    /// Estimated standard error of F, per facet: from the squared
    /// differences of paired neighbouring cells/strata,
    /// `SE² = Σ_pairs w² (yₐ − y_b)²` (a conservative estimate for stratified
    /// sampling; for the fixed grid an indication of its quadrature error).
    /// For a double-sided facet, the error of the mean over both faces.
    pub std_error: Vec<f32>,
    /// View factor to the ground beyond the scene / below the horizon.
    pub ground_weight: Vec<f32>,
    /// Start of each facet's entries in `entries`; one more than facets.
    pub offsets: Vec<u32>,
    /// All background entries, facet after facet.
    pub entries: Vec<BackgroundEntry>,
}

impl SkyView {
    /// Number of facets.
    pub fn facet_count(&self) -> usize {
        self.shape_factor.len()
    }
    /// Shape factor of the back face of `facet` when it is double-sided.
    pub fn back_shape_factor(&self, facet: usize) -> Option<f32> {
        self.back_shape_factor[facet]
    }
    /// Mean sky view factor over the facet's faces: F, or `(F + F_back)/2`
    /// for a double-sided facet. `1 −` it is the view factor to the
    /// background (neighbours and ground).
    pub fn mean_shape_factor(&self, facet: usize) -> f32 {
        match self.back_shape_factor(facet) {
            Some(b) => 0.5 * (self.shape_factor[facet] + b),
            None => self.shape_factor[facet],
        }
    }
    /// Appends the facets of `other` after this view's (the views of two
    /// consecutive facet ranges become the view of both).
    pub fn append(&mut self, other: SkyView) {
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        let base = self.entries.len() as u32;
        self.shape_factor.extend(other.shape_factor);
        self.back_shape_factor.extend(other.back_shape_factor);
        self.std_error.extend(other.std_error);
        self.ground_weight.extend(other.ground_weight);
        self.offsets
            .extend(other.offsets.iter().skip(1).map(|o| o + base));
        self.entries.extend(other.entries);
    }

    /// The facets seen by `facet`, with their view factors.
    pub fn background(&self, facet: usize) -> &[BackgroundEntry] {
        &self.entries[self.offsets[facet] as usize..self.offsets[facet + 1] as usize]
    }

    /// Background (non-sky) temperature of `facet`, K: the radiative mean
    /// over what it sees below the sky, `T_bg = ((Σ wᵢ Tᵢ⁴ + g T_ground⁴) /
    /// (1 − F))^¼` (`F` the mean over faces for double-sided facets), given
    /// every facet's temperature (`temps`, K) and the ground-beyond-the-scene
    /// temperature. Returns `t_ground` when the facet sees only sky.
    pub fn background_temperature(&self, facet: usize, temps: &[f32], t_ground: f32) -> f32 {
        let g = self.ground_weight[facet];
        let mut num = g * t_ground.powi(4);
        let mut den = g;
        for e in self.background(facet) {
            num += e.weight * temps[e.facet as usize].powi(4);
            den += e.weight;
        }
        if den > 0.0 {
            (num / den).powf(0.25)
        } else {
            t_ground
        }
    }
}

/// A worker's buffers, reused from batch to batch.
#[derive(Default)]
struct Scratch {
    rays: Vec<Ray>,
    /// Each ray's weight.
    weights: Vec<f32>,
    /// Start of each facet's rays, then the end of the last.
    ranges: Vec<usize>,
    hits: Vec<Option<Hit>>,
    /// One facet's hits, before merging by facet id.
    seen: Vec<BackgroundEntry>,
    /// One face's hemisphere pattern.
    pat: Vec<HemiSample>,
}

/// The scene-wide part of a sampling pattern ([`SkySampling::base`]).
#[derive(Debug, Clone, PartialEq)]
enum Base {
    /// The grid's directions, the same for every face.
    Grid(Vec<HemiSample>),
    /// Strata per side and each stratum's jitter.
    Stratified(u32, Vec<(f32, f32)>),
}

/// Hemisphere pattern of one facet face (local frame): the grid, or the
/// strata's fixed jitter rotated by the face's point of the R2 sequence
/// (front face of facet `f`: point `f`; back face: the same, shifted by
/// half a stratum both ways). `buf` holds the rotated pattern.
fn pattern<'a>(
    base: &'a Base,
    facet: usize,
    back: bool,
    buf: &'a mut Vec<HemiSample>,
) -> &'a [HemiSample] {
    match base {
        Base::Grid(g) => g,
        Base::Stratified(m, jitter) => {
            let (a, b) = r2_shift(facet as u64);
            let h = if back { 0.5 } else { 0.0 };
            buf.clear();
            rotated_cosine_into(*m, jitter, (a + h, b + h), buf);
            buf
        }
    }
}

/// The hemisphere patterns [`sky_view`] traces over facets' front faces,
/// for tracing the same directions from other points of a facet (a hit's
/// own sky view, `crate::render::per_hit`).
#[derive(Debug, Clone, PartialEq)]
pub struct FacePatterns(Base);

impl FacePatterns {
    /// The patterns of `sampling` with `seed`, as [`sky_view`] draws them.
    pub fn new(sampling: SkySampling, seed: u64) -> FacePatterns {
        FacePatterns(sampling.base(seed))
    }

    /// The front face's pattern of `facet` (local frame; `buf` holds it
    /// when it is rotated).
    pub fn front<'a>(&'a self, facet: usize, buf: &'a mut Vec<HemiSample>) -> &'a [HemiSample] {
        pattern(&self.0, facet, false, buf)
    }

    /// The back face's pattern of a double-sided `facet` (local frame of
    /// the back face: [`FacetSamples::to_world`] with side −1).
    pub fn back<'a>(&'a self, facet: usize, buf: &'a mut Vec<HemiSample>) -> &'a [HemiSample] {
        pattern(&self.0, facet, true, buf)
    }
}

/// How [`sky_view`] hands its rays to the tracer: a facet's hemisphere rays
/// share a neighbourhood but not a direction.
pub const RAY_COHERENCE: Coherence = Coherence::Incoherent;

/// Appends to `rays` the hemisphere rays that [`sky_view`] traces for the
/// facets `range` (one of its batches), in its order: facet by facet, front
/// face then (double-sided facets) back face, the face's pattern
/// ([`SkySampling::rays_per_face`] rays: 64 stratified by default, 72 on
/// DIRSIG's grid) with ray `k` from sample point `k mod n²`, lifted off the plane.
/// Trace them with [`RAY_COHERENCE`]. `irsig bench trace` uses this to
/// time the tracers on the exposure stage's own hemisphere rays.
pub fn sky_rays(
    facets: &FacetSamples,
    range: std::ops::Range<usize>,
    sampling: SkySampling,
    seed: u64,
    rays: &mut Vec<Ray>,
) {
    let base = sampling.base(seed);
    let (mut weights, mut ranges, mut pat) = (Vec::new(), Vec::new(), Vec::new());
    lay_out_rays(
        facets,
        range,
        &base,
        rays,
        &mut weights,
        &mut ranges,
        &mut pat,
    );
}

/// The rays of [`sky_rays`], each ray's weight in `weights` and the
/// start of each facet's rays, then the end of the last, in `ranges`.
fn lay_out_rays(
    facets: &FacetSamples,
    range: std::ops::Range<usize>,
    base: &Base,
    rays: &mut Vec<Ray>,
    weights: &mut Vec<f32>,
    ranges: &mut Vec<usize>,
    pat: &mut Vec<HemiSample>,
) {
    for f in range {
        ranges.push(rays.len());
        let pts = facets.facet_points(f);
        let sides: &[f32] = if facets.double_sided[f] {
            &[1.0, -1.0]
        } else {
            &[1.0]
        };
        let scale = 1.0 / sides.len() as f32;
        for (si, &side) in sides.iter().enumerate() {
            let lift = facets.normal[f] * (side * facets.offset_m);
            for (k, h) in pattern(base, f, si == 1, pat).iter().enumerate() {
                let dir = facets.to_world(f, h.dir, side);
                rays.push(Ray::new(pts[k % pts.len()] + lift, dir));
                weights.push(h.weight * scale);
            }
        }
    }
    ranges.push(rays.len());
}

/// Traces the shape factor and background of every facet. Rays of a face
/// start from its sample points in turn (ray `k` from point `k mod n²`),
/// lifted off the plane. Facets go through the tracer `batch_facets` at a
/// time, batches in parallel; the result is the same for any number of
/// threads.
pub fn sky_view<T: Tracer + ?Sized>(
    tracer: &T,
    facets: &FacetSamples,
    sampling: SkySampling,
    seed: u64,
    batch_facets: usize,
) -> (SkyView, u64) {
    sky_view_of(
        tracer,
        facets,
        sampling,
        seed,
        batch_facets,
        0..facets.len(),
        &|_| {},
    )
}

/// [`sky_view`] of the facets `range` only (the view holds those facets,
/// in order; background entries still name facets by their global id),
/// calling `done(n)` as each batch of `n` facets is traced. Each facet's
/// pattern depends only on its id and `seed`, and batches start at
/// `range.start`: a range starting on a multiple of `batch_facets` gets
/// the whole scene's answers bit for bit.
pub fn sky_view_of<T: Tracer + ?Sized>(
    tracer: &T,
    facets: &FacetSamples,
    sampling: SkySampling,
    seed: u64,
    batch_facets: usize,
    range: std::ops::Range<usize>,
    done: &(dyn Fn(u64) + Sync),
) -> (SkyView, u64) {
    let (start, n) = (range.start, range.end.min(facets.len()));
    let batch = batch_facets.max(1);
    let base = sampling.base(seed);
    let face_rays = sampling.rays_per_face();
    let chunks: Vec<(SkyView, u64)> = (0..n.saturating_sub(start).div_ceil(batch))
        .into_par_iter()
        .map_init(Scratch::default, |scratch, c| {
            let (f0, f1) = (start + c * batch, (start + (c + 1) * batch).min(n));
            let Scratch {
                rays,
                weights,
                ranges,
                hits,
                seen,
                pat,
            } = scratch;
            rays.clear();
            weights.clear();
            ranges.clear();
            lay_out_rays(facets, f0..f1, &base, rays, weights, ranges, pat);
            hits.clear();
            hits.resize(rays.len(), None);
            tracer.intersect(rays, RAY_COHERENCE, hits);
            let nf = f1 - f0;
            let mut out = SkyView {
                shape_factor: Vec::with_capacity(nf),
                back_shape_factor: Vec::with_capacity(nf),
                std_error: Vec::with_capacity(nf),
                ground_weight: Vec::with_capacity(nf),
                offsets: Vec::with_capacity(nf + 1),
                entries: Vec::new(),
            };
            out.offsets.push(0);
            for w in ranges.windows(2) {
                let (r0, r1) = (w[0], w[1]);
                let (mut sky, mut ground, mut var) = ([0.0f64; 2], 0.0f64, 0.0f64);
                seen.clear();
                let is_sky = |i: usize| hits[i].is_none() && rays[i].dir.z > 0.0;
                // Rays of the back face follow those of the front.
                let per_face = (r1 - r0) / if r1 - r0 == 2 * face_rays { 2 } else { 1 };
                for i in r0..r1 {
                    match hits[i] {
                        Some(h) => seen.push(BackgroundEntry {
                            facet: SceneGeometry::facet_id(
                                &facets.instance_offsets,
                                h.instance,
                                h.prim,
                            ) as u32,
                            weight: weights[i],
                        }),
                        None if rays[i].dir.z > 0.0 => {
                            sky[(i - r0) / per_face] += weights[i] as f64
                        }
                        None => ground += weights[i] as f64,
                    }
                }
                // Pairs (2k, 2k+1): neighbouring cells / strata of one face.
                let mut i = r0;
                while i + 1 < r1 {
                    if is_sky(i) != is_sky(i + 1) {
                        var += (weights[i] as f64).powi(2);
                    }
                    i += 2;
                }
                seen.sort_unstable_by_key(|e| e.facet);
                let start = out.entries.len();
                for e in seen.iter() {
                    match out.entries[start..].last_mut() {
                        Some(last) if last.facet == e.facet => last.weight += e.weight,
                        _ => out.entries.push(*e),
                    }
                }
                if r1 - r0 == per_face {
                    out.shape_factor.push(sky[0] as f32);
                    out.back_shape_factor.push(None);
                } else {
                    // Each face's rays carried half weight.
                    out.shape_factor.push((2.0 * sky[0]) as f32);
                    out.back_shape_factor.push(Some((2.0 * sky[1]) as f32));
                }
                out.ground_weight.push(ground as f32);
                out.std_error.push(var.sqrt() as f32);
                out.offsets.push(out.entries.len() as u32);
            }
            done((f1 - f0) as u64);
            (out, rays.len() as u64)
        })
        .collect();
    let mut out = SkyView {
        offsets: vec![0],
        ..Default::default()
    };
    let mut total = 0;
    for (c, r) in chunks {
        let base = out.entries.len() as u32;
        out.shape_factor.extend(c.shape_factor);
        out.back_shape_factor.extend(c.back_shape_factor);
        out.std_error.extend(c.std_error);
        out.ground_weight.extend(c.ground_weight);
        out.offsets.extend(c.offsets[1..].iter().map(|o| o + base));
        out.entries.extend(c.entries);
        total += r;
    }
    (out, total)
}

/// The back faces' own shape factors of the single-sided facets flagged in
/// `exposed_back` (one flag per facet of `facets`): facets whose slab has
/// an exposed back ([`crate::thermal::BackBoundary::Exposed`]: a wall with
/// a ventilated cavity, a vehicle panel) but whose material is not
/// double-sided, so that [`sky_view`] traces their front face only.
///
/// Without it the thermal model takes `F_b = 1 − F`
/// ([`crate::thermal::FacetInputs::back_shape_factor`] `None`), exact only
/// for an unobstructed plane: a wall in a street canyon of `H/W = 1` has
/// `F = 0.29` (Masson 2000) and so `1 − F = 0.71`, while its back, open to
/// the outside, sees `(1 − cos 90°)/2 = 0.5` of the sky; a panel facing a
/// closed space sees none. Each flagged facet's back face traces its
/// [`SkySampling`] pattern (the same back-face pattern a double-sided facet
/// traces, [`FacePatterns::back`]) from its sample points lifted to the
/// back (ray `k` from point `k mod n²`), as occlusion queries: `F_b` is the
/// weight of the rays that are not blocked and leave upward. The facets
/// seen from the back are not added to the background: the background
/// list stays the front face's (the exposed back exchanges with the
/// front's background temperature in the slab model).
///
/// Returns, per facet, `Some(F_b)` for a flagged single-sided facet and
/// `None` otherwise (a double-sided facet's back face is in
/// [`SkyView::back_shape_factor()`]), and the number of rays traced. The
/// result is the same for any number of threads.
pub fn exposed_back_shape_factors<T: Tracer + ?Sized>(
    tracer: &T,
    facets: &FacetSamples,
    exposed_back: &[bool],
    sampling: SkySampling,
    seed: u64,
    batch_facets: usize,
) -> (Vec<Option<f32>>, u64) {
    let n = facets.len();
    let wanted =
        |f: usize| exposed_back.get(f).copied().unwrap_or(false) && !facets.double_sided[f];
    let batch = batch_facets.max(1);
    let base = sampling.base(seed);
    let chunks: Vec<(Vec<Option<f32>>, u64)> = (0..n.div_ceil(batch))
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new()),
            |(rays, weights, ranges, occ, pat), c| {
                let (f0, f1) = (c * batch, ((c + 1) * batch).min(n));
                rays.clear();
                weights.clear();
                ranges.clear();
                for f in f0..f1 {
                    ranges.push(rays.len());
                    if !wanted(f) {
                        continue;
                    }
                    let pts = facets.facet_points(f);
                    let lift = facets.normal[f] * -facets.offset_m;
                    for (k, h) in pattern(&base, f, true, pat).iter().enumerate() {
                        rays.push(Ray::new(
                            pts[k % pts.len()] + lift,
                            facets.to_world(f, h.dir, -1.0),
                        ));
                        weights.push(h.weight);
                    }
                }
                ranges.push(rays.len());
                occ.clear();
                occ.resize(rays.len(), false);
                if !rays.is_empty() {
                    tracer.occluded(rays, RAY_COHERENCE, occ);
                }
                let out = (f0..f1)
                    .zip(ranges.windows(2))
                    .map(|(f, w)| {
                        wanted(f).then(|| {
                            let sky: f64 = (w[0]..w[1])
                                .filter(|&i| !occ[i] && rays[i].dir.z > 0.0)
                                .map(|i| weights[i] as f64)
                                .sum();
                            sky as f32
                        })
                    })
                    .collect();
                (out, rays.len() as u64)
            },
        )
        .collect();
    let mut out = Vec::with_capacity(n);
    let mut total = 0;
    for (c, r) in chunks {
        out.extend(c);
        total += r;
    }
    (out, total)
}
