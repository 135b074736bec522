//! Stage 5, the band: the big equation integrated over each sensor band —
//! the fused single-precision spectral sum ([`band_sum`]) and, for
//! materials grey within a band, per-band integrals ([`Integrals`],
//! [`GreyTables`]) that ε and r leave.

use super::fast::{FastMiss, FastScratch};
use super::hit::{ANGLE_ROWS, GreyHit, angle_row};
use super::reflected_sky::{TILT_NODES, tilt_at};
use super::surface::{GreyFacet, PlanckTable, hit_temperature};
use super::{BandTables, Shader};
use crate::atmosphere::{ANGLE_NODES, scatter::angle_node_f32};
use crate::material::Material;
use crate::render::per_hit::HitState;
use crate::trace::{Hit, Ray};
use glam::Vec3;

/// One band's tables for [`Shader::fast_primary`], single precision, the
/// quadrature weights (response × trapezoid) folded in where they multiply.
#[derive(Debug, Clone)]
pub(super) struct FastBand {
    /// Number of wavelengths, rounded up to a multiple of [`LANES`]; every
    /// row below is padded with zeros to it (zero weight: the padding adds
    /// nothing).
    pub(super) len: usize,
    /// Planck's function on [`Shader`]'s temperature table, `nodes × len`.
    pub(super) planck: Vec<f32>,
    /// Quadrature weights × response, µm.
    pub(super) w: Vec<f32>,
    /// The diffusely reflected sky `L_eq(λ)` per tilt node
    /// ([`super::reflected_sky`]).
    pub(super) sky: Vec<Vec<f32>>,
    /// Solar spectral irradiance normal to the sun.
    pub(super) sun: Vec<f32>,
    /// Per material: `ANGLE_ROWS × len` emissivities.
    pub(super) eps: Vec<Vec<f32>>,
    /// Band radiance of a ray leaving the scene upward, per sky node
    /// ([`sky_node_cos`]), and downward (ground beyond), W·m⁻²·sr⁻¹.
    pub(super) miss_sky: Vec<f64>,
    pub(super) miss_ground: f64,
    /// By day: the band radiance of the sky's scattered sunlight per sky
    /// node `k` and scattering-angle node `a` at `[k · ANGLE_NODES + a]`,
    /// W·m⁻²·sr⁻¹ (empty: none).
    pub(super) miss_scatter: Vec<f64>,
    /// Per material: when its emissivity is the same at every wavelength
    /// of the band (at each angle row), the `ANGLE_ROWS` values.
    pub(super) grey: Vec<Option<Vec<f64>>>,
    /// Band integrals with the plain weights (no path).
    pub(super) plain: Integrals,
}

impl FastBand {
    /// The band radiance of the sky at fraction `f` from node `k` to node
    /// `k + 1` (see [`super::sources::sky_node`]), the thermal sky
    /// and the scattered sunlight at scattering-angle node and fraction
    /// `(ka, fa)` ([`Shader::sky_angle`]).
    #[inline]
    pub(super) fn miss_sky_at(&self, k: usize, f: f64, (ka, fa): (usize, f64)) -> f64 {
        let (a, b) = (self.miss_sky[k], self.miss_sky[k + 1]);
        let mut v = a + f * (b - a);
        if !self.miss_scatter.is_empty() {
            let s = &self.miss_scatter;
            let at = |k: usize| {
                let o = k * ANGLE_NODES + ka;
                s[o] + fa * (s[o + 1] - s[o])
            };
            let (x, y) = (at(k), at(k + 1));
            v += x + f * (y - x);
        }
        v
    }
}

/// Band integrals `Σ_λ q(λ)·X(λ)` of one band for one weighting `q`
/// (`w`, or `w·τ₂` at one range node): what a hit on a material that is
/// grey within the band needs, since ε and r then leave the sums.
#[derive(Debug, Clone)]
pub(super) struct Integrals {
    /// Per node of the Planck table: `Σ q·B(λ, T_k)`.
    pub(super) planck: Vec<f64>,
    /// Per tilt node: `Σ q·L_eq`.
    pub(super) sky: Vec<f64>,
    /// `Σ q·E_s`.
    pub(super) sun: f64,
}

impl Integrals {
    pub(super) fn new(q: &[f64], t: &BandTables, table: &PlanckTable, total: usize) -> Self {
        let dot = |v: &[f64]| q.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
        let nl = t.band.len();
        Integrals {
            planck: table
                .values
                .chunks(total)
                .map(|node| dot(&node[t.start..t.start + nl]))
                .collect(),
            sky: t.sky_tilt.iter().map(|v| dot(v)).collect(),
            sun: dot(&t.sun),
        }
    }

    /// `Σ q·L_eq` at tilt node `k` + fraction `w`.
    #[inline]
    pub(super) fn sky_at(&self, k: usize, w: f64) -> f64 {
        let s = &self.sky;
        s[k] + w * (s[k + 1] - s[k])
    }

    /// `Σ q·B(T)` at table node `k` + fraction `f`.
    #[inline]
    pub(super) fn planck_at(&self, k: usize, f: f64) -> f64 {
        let p = &self.planck;
        p[k] + f * (p[k + 1] - p[k])
    }
}

/// The band integrals of the grey path, single precision, flat: per band
/// the Planck integrals `Σ q_i·B(T_k)` of every temperature node `k` and
/// path node `i` (weights `q_i = w·τ₂(R_i)`; without a path two equal
/// nodes of the plain weights `w`), per path node the sky, sun and path
/// terms, and the grey emissivities of every material. Every table is
/// band-interleaved (the bands of one entry are adjacent), so one hit reads
/// each entry of all its bands from one place; the Planck integrals are
/// stored path node by path node, so the two temperature nodes a hit
/// interpolates between are adjacent (one cache line) and the hits of a
/// row, which share few path nodes, read a few kilobytes of the table
/// whatever their temperatures.
#[derive(Debug, Clone, Default)]
pub(super) struct GreyTables {
    /// Bands.
    pub(super) bands: usize,
    /// Range nodes per height node (the path nodes, at least 2, are
    /// height nodes × range nodes, node `a · range_nodes + i`:
    /// [`PathTables::node`]).
    pub(super) range_nodes: usize,
    /// Heights of the height nodes above the ground datum, m (one node:
    /// no height interpolation).
    pub(super) heights: Vec<f32>,
    /// `1 / (heights[a + 1] − heights[a])`.
    pub(super) inv_height_spacing: Vec<f32>,
    /// Ranges of the nodes, m (empty without a path: every hit is at
    /// node 1, fraction 0).
    pub(super) ranges: Vec<f32>,
    /// `1 / (ranges[i] − ranges[i − 1])`.
    pub(super) inv_spacing: Vec<f32>,
    /// First guess of the node of range `r`: `√r · sqrt_scale` (exact for
    /// the quadratic spacing of [`PathTables`], refined for any spacing;
    /// [`GreyTables::locate`], the reference of [`GreyTables::locate_binned`]).
    pub(super) sqrt_scale: f32,
    /// Per range bin `k` (uniform bins, `k = ⌊r · bin_scale⌋` clamped to
    /// the last bin, [`range_bin`]): the node `i` of the bin's smallest
    /// ranges, `1 +` the number of nodes `1..last` in lower bins. No two of
    /// those nodes share a bin, so a range's node is this or the next
    /// ([`GreyTables::locate_binned`]). Empty when the nodes are too
    /// unevenly spaced for [`GreyTables::MAX_BINS`] bins (or fewer than 3).
    pub(super) range_bins: Vec<u16>,
    /// Range bins per metre.
    pub(super) bin_scale: f32,
    /// Temperature nodes (of the Planck table).
    pub(super) temperatures: usize,
    /// `Σ q_i·B(T_k)` of band `b` at `[(i · temperatures + k) · bands + b]`.
    pub(super) planck: Vec<f32>,
    /// Per path node `i`: `Σ q_i·L_eq` of tilt node `j`, `Σ q_i·E_s` and
    /// `Σ w·L_u` of band `b` at `[(NODE_TERMS·i + j, TILT_NODES,
    /// TILT_NODES + 1) · bands + b]` ([`NODE_TERMS`]).
    pub(super) node: Vec<f32>,
    /// Grey emissivity at `[(material · ANGLE_ROWS + angle row) · bands + b]`
    /// (0 for materials not grey in every band: never read).
    pub(super) eps: Vec<f32>,
    /// Per material: transmissivity t.
    pub(super) tr: Vec<f32>,
    /// By day: `Σ w·L_ss` of band `b` at path node `i`, scattering-angle
    /// node `k` at `[(i · ANGLE_NODES + k) · bands + b]` (empty at night
    /// or without a path: nothing to add).
    pub(super) scatter: Vec<f32>,
}

impl GreyTables {
    /// Tables from each band's integrals and path radiance per range node
    /// (`nodes[b][i]`), at `ranges` (empty: no path).
    pub(super) fn new(
        fast: &[FastBand],
        nodes: &[Vec<(&Integrals, f64)>],
        ranges: &[f64],
        heights: &[f64],
        materials: &[Material],
    ) -> Self {
        let nb = nodes.len();
        let r = nodes.first().map_or(2, Vec::len);
        let nt = nodes
            .first()
            .and_then(|b| b.first())
            .map_or(0, |(i, _)| i.planck.len());
        let mut planck = vec![0f32; nt * r * nb];
        let mut node = vec![0f32; NODE_TERMS * r * nb];
        for (b, band) in nodes.iter().enumerate() {
            for (i, (ig, lu)) in band.iter().enumerate() {
                for (k, &x) in ig.planck.iter().enumerate() {
                    planck[(i * nt + k) * nb + b] = x as f32;
                }
                let q = NODE_TERMS * i;
                for (j, &x) in ig.sky.iter().enumerate() {
                    node[(q + j) * nb + b] = x as f32;
                }
                node[(q + TILT_NODES) * nb + b] = ig.sun as f32;
                node[(q + TILT_NODES + 1) * nb + b] = *lu as f32;
            }
        }
        let grey_everywhere = |mi: usize| fast.iter().all(|fb| fb.grey[mi].is_some());
        let mut eps = vec![0f32; materials.len() * ANGLE_ROWS * nb];
        for mi in (0..materials.len()).filter(|&mi| grey_everywhere(mi)) {
            for (b, fb) in fast.iter().enumerate() {
                let rows = fb.grey[mi].as_ref().expect("grey in every band");
                for (a, &e) in rows.iter().enumerate() {
                    eps[(mi * ANGLE_ROWS + a) * nb + b] = e as f32;
                }
            }
        }
        let ranges: Vec<f32> = ranges.iter().map(|&x| x as f32).collect();
        let inv_spacing = (0..ranges.len())
            .map(|i| {
                if i == 0 {
                    0.0
                } else {
                    1.0 / (ranges[i] - ranges[i - 1])
                }
            })
            .collect();
        let sqrt_scale = match ranges.last() {
            Some(&last) if last > 0.0 => (ranges.len() - 1) as f32 / last.sqrt(),
            _ => 0.0,
        };
        let (range_bins, bin_scale) = range_bins(&ranges);
        let heights: Vec<f32> = heights.iter().map(|&x| x as f32).collect();
        let inv_height_spacing = heights.windows(2).map(|w| 1.0 / (w[1] - w[0])).collect();
        GreyTables {
            bands: nb,
            temperatures: nt,
            range_nodes: if ranges.is_empty() { r } else { ranges.len() },
            heights,
            inv_height_spacing,
            ranges,
            inv_spacing,
            sqrt_scale,
            range_bins,
            bin_scale,
            planck,
            node,
            eps,
            tr: materials
                .iter()
                .map(|m| m.transmissivity.clamp(0.0, 1.0) as f32)
                .collect(),
            scatter: Vec::new(),
        }
    }

    /// These tables with the path's scattered sunlight `Σ w·L_ss`
    /// (`scatter[b][i][k]`: band, path node, scattering-angle node; empty:
    /// none) and the sun it needs (`None`: none).
    pub(super) fn with_scatter(mut self, scatter: &[Vec<Vec<f64>>], sun: Option<Vec3>) -> Self {
        let nb = self.bands;
        if sun.is_none() || scatter.len() != nb || nb == 0 {
            return self;
        }
        let nodes = scatter[0].len();
        let mut v = vec![0f32; nodes * ANGLE_NODES * nb];
        for (b, band) in scatter.iter().enumerate() {
            for (i, angles) in band.iter().enumerate() {
                for (k, &x) in angles.iter().enumerate() {
                    v[(i * ANGLE_NODES + k) * nb + b] = x as f32;
                }
            }
        }
        self.scatter = v;
        self
    }

    /// The range nodes bracketing range `r` (m): `(i, x)` with `r` at
    /// fraction `x` (clamped to [0, 1]) from node `i − 1` to node `i`, as
    /// [`PathTables::locate`]; `(1, 0)` without a path.
    #[inline(always)]
    pub(super) fn locate(&self, r: f32) -> (usize, f32) {
        let x = &self.ranges;
        if x.len() < 2 {
            return (1, 0.0);
        }
        let last = x.len() - 1;
        // (Saturating: `as` maps +∞ to `usize::MAX`.)
        let mut i = ((r.max(0.0).sqrt() * self.sqrt_scale) as usize)
            .saturating_add(1)
            .min(last);
        // One step each way without a branch (the guess is exact up to
        // rounding for the quadratic spacing, so the loops below, which
        // find the same node from any start, then rarely run: a
        // data-dependent branch here mispredicted on most hits).
        i += usize::from((i < last) & (x[i] <= r));
        i -= usize::from((i > 1) & (x[i - 1] > r));
        while i < last && x[i] <= r {
            i += 1;
        }
        while i > 1 && x[i - 1] > r {
            i -= 1;
        }
        (i, ((r - x[i - 1]) * self.inv_spacing[i]).clamp(0.0, 1.0))
    }

    /// Most range bins of [`GreyTables::range_bins`] (16 KB of `u16`).
    const MAX_BINS: usize = 8192;

    /// [`GreyTables::locate`] from the range bins: the node of the bin's
    /// smallest ranges, one step on if the range is at or beyond it — one
    /// table load and one compare per hit, no square root and no loop.
    /// Falls back to [`GreyTables::locate`] without bins.
    #[inline(always)]
    pub(super) fn locate_binned(&self, r: f32) -> (usize, f32) {
        let bins = &self.range_bins;
        if bins.is_empty() {
            return self.locate(r);
        }
        let x = &self.ranges;
        let last = x.len() - 1;
        let mut i = bins[range_bin(r, self.bin_scale, bins.len())] as usize;
        i += usize::from((i < last) & (x[i] <= r));
        (i, ((r - x[i - 1]) * self.inv_spacing[i]).clamp(0.0, 1.0))
    }

    /// The height nodes bracketing height `z` (m): `(a, u)` with `z` at
    /// fraction `u` (clamped to [0, 1]) from node `a` to `a + 1`, as
    /// [`PathTables::locate_height`]; `(0, 0)` with one node.
    #[inline(always)]
    pub(super) fn locate_height(&self, z: f32) -> (usize, f32) {
        let x = &self.heights;
        if x.len() < 2 {
            return (0, 0.0);
        }
        let mut a = 0;
        while a + 2 < x.len() && x[a + 1] <= z {
            a += 1;
        }
        (a, ((z - x[a]) * self.inv_height_spacing[a]).clamp(0.0, 1.0))
    }
}

/// The range bin of range `r` (m) among `bins` bins of `1 / scale` m:
/// `⌊r · scale⌋`, clamped to `0..bins` (below 0 and NaN: bin 0; beyond,
/// and +∞: the last bin). Non-decreasing in `r`, which is all that
/// [`GreyTables::locate_binned`]'s exactness needs.
#[inline(always)]
fn range_bin(r: f32, scale: f32, bins: usize) -> usize {
    // `as` saturates: negative and NaN to 0, +∞ to `usize::MAX`.
    ((r * scale) as usize).min(bins - 1)
}

/// The range bins of [`GreyTables`] for nodes `x` (m, increasing) and their
/// scale (bins per metre): as few bins as keep every node `1..last` in a
/// bin of its own, at most [`GreyTables::MAX_BINS`] (else none: the nodes
/// are too unevenly spaced, and [`GreyTables::locate`] serves).
fn range_bins(x: &[f32]) -> (Vec<u16>, f32) {
    let none = (Vec::new(), 0.0);
    if x.len() < 3 || x.len() > usize::from(u16::MAX) || !x.iter().all(|v| v.is_finite()) {
        return none;
    }
    let last = x.len() - 1;
    // The nodes the lookup compares against: 1..last (node 0 and the last
    // only clamp).
    let inner = &x[1..last];
    let span = inner[inner.len() - 1].max(0.0);
    // (All finite: no NaN below.)
    if span <= 0.0 {
        return none;
    }
    // Bins no wider than the closest two inner nodes, then twice as many
    // until the rounding of `r · scale` parts every two of them.
    let spacing = inner.windows(2).map(|w| w[1] - w[0]).fold(span, f32::min);
    if spacing <= 0.0 {
        // Nodes out of order or repeated.
        return none;
    }
    let mut bins = ((span / spacing).ceil() as usize).clamp(1, GreyTables::MAX_BINS) + 1;
    while bins <= GreyTables::MAX_BINS {
        let scale = bins as f32 / span;
        let of = |v: f32| range_bin(v, scale, bins);
        if inner.windows(2).all(|w| of(w[0]) < of(w[1])) {
            // Node of bin k: 1 + the inner nodes in lower bins.
            let mut table = vec![0u16; bins];
            let mut j = 0;
            for (k, t) in table.iter_mut().enumerate() {
                while j < inner.len() && of(inner[j]) < k {
                    j += 1;
                }
                *t = (1 + j) as u16;
            }
            return (table, scale);
        }
        bins *= 2;
    }
    none
}

/// One band of [`Shader::grey_terms_pass`]: with `ε` interpolated between
/// the angle rows' `e0` and `e1` at fraction `ta`, and `r = max(1 − ε − t,
/// 0)`, the radiance `ε·x + r·(env + lit·w) + z` from the facet's terms
/// `[x, env, w, z]` ([`grey_facets`]).
#[inline(always)]
pub(super) fn grey_terms_band(
    e0: f32,
    e1: f32,
    ta: f32,
    tr: f32,
    lit: bool,
    [x, env, w, z]: [f32; 4],
) -> f32 {
    let eps = e0 + ta * (e1 - e0);
    let r = (1.0 - eps - tr).max(0.0);
    eps * x + r * (env + if lit { w } else { 0.0 }) + z
}

/// `a + x·(b − a)`: every interpolation of the grey path, in the
/// reference's order.
#[inline(always)]
fn lerp(a: f32, b: f32, x: f32) -> f32 {
    a + x * (b - a)
}

/// One height node's Planck integrals `Σq·B(T)` of `NB` bands for
/// [`Shader::grey_pass`]: linear in temperature (fraction `f` from the
/// entries at `o` to the next temperature node's, `NB` on), then in range
/// (fraction `rx` toward the next range node's, `rs` on).
#[inline(always)]
fn grey_planck<const NB: usize>(pl: &[f32], o: usize, rs: usize, f: f32, rx: f32) -> [f32; NB] {
    let a = &pl[o..o + 2 * NB];
    let c = &pl[o + rs..o + rs + 2 * NB];
    // (Loops, not `array::from_fn`, which was not always inlined.)
    let mut v = [0f32; NB];
    for (b, v) in v.iter_mut().enumerate() {
        *v = lerp(lerp(a[b], a[NB + b], f), lerp(c[b], c[NB + b], f), rx);
    }
    v
}

/// One height node's scattered sunlight `Σw·L_ss` of band `b` of `nb`
/// ([`GreyTables::scatter`]): linear in the scattering angle (fraction
/// `fs` from the entries at `o`, angle node `ks`, to the next angle node's,
/// `nb` on), then in range (fraction `rx`; the next range node
/// `ANGLE_NODES·nb` on).
#[inline(always)]
fn grey_scatter(sc: &[f32], o: usize, nb: usize, b: usize, fs: f32, rx: f32) -> f32 {
    let rs = ANGLE_NODES * nb;
    let v0 = lerp(sc[o + b], sc[o + nb + b], fs);
    let v1 = lerp(sc[o + rs + b], sc[o + rs + nb + b], fs);
    lerp(v0, v1, rx)
}

/// Entries per path node of [`GreyTables::node`]: the reflected sky at
/// every tilt node, the sun, the path radiance.
pub(super) const NODE_TERMS: usize = TILT_NODES + 2;

/// One height node's sky, sun and path terms `[Σq·L_eq, Σq·E_s, Σw·L_u]`
/// of `NB` bands, linear in range (fraction `rx` from the entries at `q`
/// to the next range node's, `NODE_TERMS·NB` on), the sky linear in tilt
/// (fraction `wb` from tilt node `kb` to the next).
#[inline(always)]
fn grey_node_terms<const NB: usize>(
    nd: &[f32],
    q: usize,
    (kb, wb): (usize, f32),
    rx: f32,
) -> [[f32; NB]; 3] {
    let s = &nd[q..q + 2 * NODE_TERMS * NB];
    let at = |j: usize, b: usize| lerp(s[j * NB + b], s[(NODE_TERMS + j) * NB + b], rx);
    let (mut sky, mut sun, mut lu) = ([0f32; NB], [0f32; NB], [0f32; NB]);
    for (b, ((sky, sun), lu)) in sky.iter_mut().zip(&mut sun).zip(&mut lu).enumerate() {
        *sky = lerp(at(kb, b), at(kb + 1, b), wb);
        *sun = at(TILT_NODES, b);
        *lu = at(TILT_NODES + 1, b);
    }
    [sky, sun, lu]
}

/// One height node's grey-path terms of band `b` of `nb`
/// ([`Shader::grey_pass_any`]): `[Σq·B(T), Σq·B(T_bg), Σq·L_eq, Σq·E_s,
/// Σw·L_u]`, the Planck integrals linear in temperature (fractions `ft`,
/// `fg` from the entries at `t0`, `g0`; the next temperature node `nb` on)
/// then in range (fraction `rx`; the next range node `rs` on), the node
/// terms at `q` linear in range (the next range node `NODE_TERMS·nb` on),
/// the sky then in tilt (fraction `wb` from tilt node `kb`).
#[inline(always)]
pub(super) fn grey_node(
    pl: &[f32],
    nd: &[f32],
    [nb, rs, b, kb]: [usize; 4],
    [t0, g0, q]: [usize; 3],
    [ft, fg, rx, wb]: [f32; 4],
) -> [f32; 5] {
    let bilerp = |o: usize, f: f32| {
        let v0 = lerp(pl[o + b], pl[o + nb + b], f);
        let v1 = lerp(pl[o + rs + b], pl[o + rs + nb + b], f);
        lerp(v0, v1, rx)
    };
    let node = |j: usize| lerp(nd[q + j * nb + b], nd[q + (NODE_TERMS + j) * nb + b], rx);
    [
        bilerp(t0, ft),
        bilerp(g0, fg),
        lerp(node(kb), node(kb + 1), wb),
        node(TILT_NODES),
        node(TILT_NODES + 1),
    ]
}

/// Where a gathered hit reads the grey path's tables
/// ([`Shader::grey_place`]).
struct GreyPlace<'s> {
    g: &'s GreyFacet,
    mi: usize,
    a0: usize,
    ta: f32,
    /// Path node of height node `ai`, range node `ri − 1`.
    n0: usize,
    rx: f32,
    ax: f32,
    sd: f32,
    /// Tilt node of the reflected sky and the fraction toward the next.
    kb: usize,
    wb: f32,
}

/// The spectral rows one band of [`Shader::fast_primary`] reads (all of
/// the band's length): emissivity at the two angle rows, Planck at the two
/// table nodes of the surface and of the background temperature, `w·τ₂` at
/// the two range nodes, the reflected sky at the two tilt nodes and solar
/// irradiance.
pub(super) struct BandStreams<'s> {
    pub(super) e0: &'s [f32],
    pub(super) e1: &'s [f32],
    pub(super) t0: &'s [f32],
    pub(super) t1: &'s [f32],
    pub(super) g0: &'s [f32],
    pub(super) g1: &'s [f32],
    pub(super) q0: &'s [f32],
    pub(super) q1: &'s [f32],
    pub(super) sky0: &'s [f32],
    pub(super) sky1: &'s [f32],
    pub(super) sun: &'s [f32],
}

/// Lanes of the partial sums of [`band_sum`] (a fixed order: the result
/// does not depend on the machine), and the padding of its rows.
pub(super) const LANES: usize = 8;

/// `Σ_λ w·τ₂ · [ε·B(T) + r·(env + sd·E_s) + tr·env]` over one band (see
/// [`Shader::fast_primary`]); `frac` = the interpolation fractions of
/// angle, temperature, background temperature, range and tilt. All rows
/// are [`FastBand::len`] long, a multiple of [`LANES`].
#[inline]
pub(super) fn band_sum(s: &BandStreams, frac: [f32; 5], big_f: f32, sd: f32, tr: f32) -> f32 {
    let [ta, ft, fg, fr, fb] = frac;
    let one_f = 1.0 - big_f;
    let one_t = 1.0 - tr;
    let lane = |v: &[f32], c: usize| -> [f32; LANES] {
        v[c..c + LANES].try_into().expect("rows are whole lanes")
    };
    let mut acc = [0f32; LANES];
    for c in (0..s.e0.len()).step_by(LANES) {
        let (e0, e1, t0, t1) = (lane(s.e0, c), lane(s.e1, c), lane(s.t0, c), lane(s.t1, c));
        let (g0, g1, q0, q1) = (lane(s.g0, c), lane(s.g1, c), lane(s.q0, c), lane(s.q1, c));
        let (s0, s1, sun) = (lane(s.sky0, c), lane(s.sky1, c), lane(s.sun, c));
        for l in 0..LANES {
            let sky = s0[l] + fb * (s1[l] - s0[l]);
            let eps = e0[l] + ta * (e1[l] - e0[l]);
            let bt = t0[l] + ft * (t1[l] - t0[l]);
            let bg = g0[l] + fg * (g1[l] - g0[l]);
            let wt = q0[l] + fr * (q1[l] - q0[l]);
            let env = big_f * sky + one_f * bg;
            let r = one_t - eps;
            let r = if r > 0.0 { r } else { 0.0 };
            acc[l] += wt * (eps * bt + r * (env + sd * sun[l]) + tr * env);
        }
    }
    acc.iter().sum()
}

impl Shader<'_> {
    /// The grey path's last pass without a sensor path: per band
    /// `ε(θ)·x + r·(env + lit·w) + z` from the facet's precomputed terms
    /// ([`grey_facets`]), `r = max(1 − ε − t, 0)`. One and two bands (the
    /// common cases) have their own loops with the band count known.
    pub(super) fn grey_terms_pass(&self, sc: &FastScratch, n: usize, out: &mut [f32]) {
        match self.grey_tables.bands {
            1 => self.grey_terms_pass_n::<1>(sc, n, out),
            2 => self.grey_terms_pass_n::<2>(sc, n, out),
            _ => self.grey_terms_pass_any(sc, n, out),
        }
    }

    /// A gathered hit's place in the grey tables: its facet's material
    /// `mi`, the emissivity angle row `a0` and the fraction `ta` toward
    /// `a0 + 1`, and whether its sunlit face is seen.
    #[inline(always)]
    pub(super) fn grey_hit_rows(&self, hit: &GreyHit) -> (usize, usize, f32, bool) {
        let mi = self.grey[hit.facet as usize].mi as usize;
        let th = hit.theta;
        // θ ≥ 0: truncation is the floor.
        let a0 = (th as usize).min(ANGLE_ROWS - 2);
        let lit = !hit.shaded;
        (mi, a0, th - a0 as f32, lit)
    }

    /// [`Shader::grey_terms_pass`] with `NB` bands.
    pub(super) fn grey_terms_pass_n<const NB: usize>(
        &self,
        sc: &FastScratch,
        n: usize,
        out: &mut [f32],
    ) {
        let gt = &self.grey_tables;
        debug_assert_eq!(gt.bands, NB);
        let (out, _) = out.split_at_mut(NB * n);
        for hit in &sc.grey {
            let (i, f) = (hit.ray as usize, hit.facet as usize);
            let (mi, a0, ta, lit) = self.grey_hit_rows(hit);
            let tr = gt.tr[mi];
            // Angle rows a0 and a0 + 1, and the terms: one bounds check
            // each (the lengths are constants).
            let row = (mi * ANGLE_ROWS + a0) * NB;
            let e0: &[f32; NB] = (&gt.eps[row..][..NB]).try_into().expect("angle row");
            let e1: &[f32; NB] = (&gt.eps[row + NB..][..NB])
                .try_into()
                .expect("next angle row");
            let t: &[[f32; 4]; NB] = (&self.grey_terms[f * NB..][..NB])
                .try_into()
                .expect("one facet's terms");
            for b in 0..NB {
                out[b * n + i] = grey_terms_band(e0[b], e1[b], ta, tr, lit, t[b]);
            }
        }
    }

    /// [`Shader::grey_terms_pass`] with any number of bands.
    pub(super) fn grey_terms_pass_any(&self, sc: &FastScratch, n: usize, out: &mut [f32]) {
        let gt = &self.grey_tables;
        let nb = gt.bands;
        for hit in &sc.grey {
            let (i, f) = (hit.ray as usize, hit.facet as usize);
            let (mi, a0, ta, lit) = self.grey_hit_rows(hit);
            let tr = gt.tr[mi];
            let e = &gt.eps[(mi * ANGLE_ROWS + a0) * nb..][..2 * nb];
            let terms = &self.grey_terms[f * nb..][..nb];
            for (b, &t) in terms.iter().enumerate() {
                out[b * n + i] = grey_terms_band(e[b], e[nb + b], ta, tr, lit, t);
            }
        }
    }

    /// The grey path's last pass over every hit gathered in `sc` (see
    /// [`Shader::shade_fast`]): per band
    /// `ε(θ)·ΣqB(T) + r·(env + sd·Σq·E_s) + t·env + Σw·L_u`, with
    /// `env = F·Σq·L_eq(β) + (1 − F)·ΣqB(T_bg)`, `r = max(1 − ε − t, 0)`, the
    /// integrals bilinear in temperature then range, then linear in height,
    /// as in the reference. The bands of one entry are adjacent in
    /// [`GreyTables`]: the offsets are computed once per hit, then each
    /// band is a few loads. One and two bands (the common cases) have
    /// their own loops with the band count known.
    pub(super) fn grey_pass(&self, sc: &FastScratch, n: usize, out: &mut [f32]) {
        match self.grey_tables.bands {
            1 => self.grey_pass_n::<1>(sc, n, out),
            2 => self.grey_pass_n::<2>(sc, n, out),
            _ => self.grey_pass_any(sc, n, out),
        }
    }

    /// Each gathered hit's place in the path's tables (its `node`, `rx`
    /// and `ax`, [`GreyHit`]), in a pass of its own: the range from its
    /// bin ([`GreyTables::locate_binned`]), the height by a short scan.
    pub(super) fn grey_locate(&self, grey: &mut [GreyHit]) {
        let gt = &self.grey_tables;
        let rn = gt.range_nodes;
        let lit = !gt.scatter.is_empty();
        for hit in grey {
            let (ri, rx) = gt.locate_binned(hit.range);
            let (ai, ax) = gt.locate_height(hit.z);
            hit.node = (ai * rn + ri - 1) as u32;
            hit.rx = rx;
            hit.ax = ax;
            if lit {
                let (k, f) = angle_node_f32(hit.fs);
                hit.ks = k as u32;
                hit.fs = f;
            }
        }
    }

    /// A gathered hit's place in the grey path's tables: its facet's
    /// record, material `mi`, the emissivity angle row `a0` and the
    /// fraction `ta` toward `a0 + 1`, the path node and fractions of
    /// [`Shader::grey_locate`], and the diffuse-reflected sun `sd` of its
    /// seen face.
    #[inline(always)]
    fn grey_place(&self, hit: &GreyHit) -> GreyPlace<'_> {
        let g = &self.grey[hit.facet as usize];
        let mi = g.mi as usize;
        let th = hit.theta;
        // θ ≥ 0: truncation is the floor.
        let a0 = (th as usize).min(ANGLE_ROWS - 2);
        let sd = if !hit.shaded { g.sd } else { 0.0 };
        let (kb, wb) = tilt_at(g.tilt);
        GreyPlace {
            g,
            mi,
            a0,
            ta: th - a0 as f32,
            n0: hit.node as usize,
            rx: hit.rx,
            ax: hit.ax,
            sd,
            kb,
            wb,
        }
    }

    /// [`Shader::grey_pass`] with `NB` bands.
    fn grey_pass_n<const NB: usize>(&self, sc: &FastScratch, n: usize, out: &mut [f32]) {
        let gt = &self.grey_tables;
        debug_assert_eq!(gt.bands, NB);
        let (out, _) = out.split_at_mut(NB * n);
        let (pl, nd, ep) = (&gt.planck[..], &gt.node[..], &gt.eps[..]);
        let nt = gt.temperatures;
        // Steps in the Planck table: to the next range node, to the next
        // height node (`range_nodes` path nodes on); in the node terms, to
        // the next height node.
        let rs = nt * NB;
        let two = gt.heights.len() >= 2;
        let (hp, hq) = (gt.range_nodes * nt * NB, NODE_TERMS * gt.range_nodes * NB);
        let sct = &gt.scatter[..];
        let hs = ANGLE_NODES * gt.range_nodes * NB;
        for hit in &sc.grey {
            let i = hit.ray as usize;
            let p = self.grey_place(hit);
            let g = p.g;
            let tr = gt.tr[p.mi];
            let one_f = 1.0 - g.big_f;
            let t0 = (p.n0 * nt + g.kt as usize) * NB;
            let g0 = (p.n0 * nt + g.kg as usize) * NB;
            let q = NODE_TERMS * p.n0 * NB;
            let tb = (p.kb, p.wb);
            // Temperature first, then range, then height, as the reference.
            let mut bt = grey_planck::<NB>(pl, t0, rs, g.ft, p.rx);
            let mut bg = grey_planck::<NB>(pl, g0, rs, g.fg, p.rx);
            let [mut sky, mut sun, mut lu] = grey_node_terms::<NB>(nd, q, tb, p.rx);
            // (At a height node's own height, `ax = 0`, the next node adds
            // exactly nothing: `lerp(a, b, 0) = a`.)
            let two = two && p.ax != 0.0;
            if two {
                let bt1 = grey_planck::<NB>(pl, t0 + hp, rs, g.ft, p.rx);
                let bg1 = grey_planck::<NB>(pl, g0 + hp, rs, g.fg, p.rx);
                let [sky1, sun1, lu1] = grey_node_terms::<NB>(nd, q + hq, tb, p.rx);
                for b in 0..NB {
                    bt[b] = lerp(bt[b], bt1[b], p.ax);
                    bg[b] = lerp(bg[b], bg1[b], p.ax);
                    sky[b] = lerp(sky[b], sky1[b], p.ax);
                    sun[b] = lerp(sun[b], sun1[b], p.ax);
                    lu[b] = lerp(lu[b], lu1[b], p.ax);
                }
            }
            if !sct.is_empty() {
                // The scattered sunlight of the ray's own angle.
                let o = (p.n0 * ANGLE_NODES + hit.ks as usize) * NB;
                for (b, lu) in lu.iter_mut().enumerate() {
                    let mut v = grey_scatter(sct, o, NB, b, hit.fs, p.rx);
                    if two {
                        let v1 = grey_scatter(sct, o + hs, NB, b, hit.fs, p.rx);
                        v = lerp(v, v1, p.ax);
                    }
                    *lu += v;
                }
            }
            let e = &ep[(p.mi * ANGLE_ROWS + p.a0) * NB..][..2 * NB];
            for b in 0..NB {
                let eps = lerp(e[b], e[NB + b], p.ta);
                let r = (1.0 - eps - tr).max(0.0);
                let env = g.big_f * sky[b] + one_f * bg[b];
                out[b * n + i] = eps * bt[b] + r * (env + p.sd * sun[b]) + tr * env + lu[b];
            }
        }
    }

    /// [`Shader::grey_pass`] with any number of bands.
    fn grey_pass_any(&self, sc: &FastScratch, n: usize, out: &mut [f32]) {
        let gt = &self.grey_tables;
        let nb = gt.bands;
        let (pl, nd, ep) = (&gt.planck[..], &gt.node[..], &gt.eps[..]);
        let nt = gt.temperatures;
        let rs = nt * nb;
        let two = gt.heights.len() >= 2;
        let (hp, hq) = (gt.range_nodes * nt * nb, NODE_TERMS * gt.range_nodes * nb);
        let sct = &gt.scatter[..];
        let hs = ANGLE_NODES * gt.range_nodes * nb;
        for hit in &sc.grey {
            let i = hit.ray as usize;
            let p = self.grey_place(hit);
            let g = p.g;
            let tr = gt.tr[p.mi];
            let one_f = 1.0 - g.big_f;
            let e = (p.mi * ANGLE_ROWS + p.a0) * nb;
            let t0 = (p.n0 * nt + g.kt as usize) * nb;
            let g0 = (p.n0 * nt + g.kg as usize) * nb;
            let q = NODE_TERMS * p.n0 * nb;
            let two = two && p.ax != 0.0;
            for b in 0..nb {
                let eps = lerp(ep[e + b], ep[e + nb + b], p.ta);
                // Temperature first, then range, then height, as the
                // reference.
                let [mut bt, mut bg, mut sky, mut sun, mut lu] = grey_node(
                    pl,
                    nd,
                    [nb, rs, b, p.kb],
                    [t0, g0, q],
                    [g.ft, g.fg, p.rx, p.wb],
                );
                if two {
                    let [bt1, bg1, sky1, sun1, lu1] = grey_node(
                        pl,
                        nd,
                        [nb, rs, b, p.kb],
                        [t0 + hp, g0 + hp, q + hq],
                        [g.ft, g.fg, p.rx, p.wb],
                    );
                    bt = lerp(bt, bt1, p.ax);
                    bg = lerp(bg, bg1, p.ax);
                    sky = lerp(sky, sky1, p.ax);
                    sun = lerp(sun, sun1, p.ax);
                    lu = lerp(lu, lu1, p.ax);
                }
                if !sct.is_empty() {
                    let o = (p.n0 * ANGLE_NODES + hit.ks as usize) * nb;
                    let mut v = grey_scatter(sct, o, nb, b, hit.fs, p.rx);
                    if two {
                        v = lerp(v, grey_scatter(sct, o + hs, nb, b, hit.fs, p.rx), p.ax);
                    }
                    lu += v;
                }
                let r = (1.0 - eps - tr).max(0.0);
                let env = g.big_f * sky + one_f * bg;
                out[b * n + i] = eps * bt + r * (env + p.sd * sun) + tr * env + lu;
            }
        }
    }

    /// [`Shader::fast_primary`] of a hit off the grey path: per band the
    /// grey integrals or the fused spectral sum.
    /// `vis`: the hit's own sun visibility (its shadow ray), if traced.
    pub(super) fn fast_general(
        &self,
        ray: &Ray,
        h: &Hit,
        state: Option<HitState>,
        vis: Option<f32>,
        out: &mut [f32],
    ) -> Result<(), FastMiss> {
        let f = self.facet_of(h);
        if self.spawns_secondary(f) {
            return Err(FastMiss::Secondary);
        }
        let mi = self.optics.facet_material[f] as usize;
        if self.glint_m2[mi] > 0.0 {
            return Err(FastMiss::Glint);
        }
        let s = &self.conditions.surface;
        let (t_hit, sun_fraction) = hit_temperature(s, f, state);
        let sun_fraction = vis.unwrap_or(sun_fraction);
        let m = &self.optics.materials[mi];
        let (_, nrm, d) = self.hit_frame(ray, h);
        let (shape_factor, background_k, tilt) = self.seen_sky(f, h.ng, d, state);
        let (kt, ft) = self.table_position(t_hit).ok_or(FastMiss::OffTable)?;
        let (kg, fg) = self
            .table_position(background_k as f64)
            .ok_or(FastMiss::OffTable)?;
        let (a0, ta) = angle_row(-d.dot(nrm));
        let big_f = (shape_factor as f64).clamp(0.0, 1.0);
        let (kb, wb) = tilt_at(tilt);
        let sun_w = if self.seen_face_lit(mi, h.ng, d) {
            (s.cos_sun[f] as f64).max(0.0) * (sun_fraction as f64).clamp(0.0, 1.0)
                / std::f64::consts::PI
        } else {
            0.0
        };
        let sd = (1.0 - m.specular_fraction.clamp(0.0, 1.0)) * sun_w;
        let tr = m.transmissivity.clamp(0.0, 1.0);
        // The path nodes: range node i − 1 → i at fraction x, of height
        // node a (and a + 1 at fraction u when the table has two or more).
        let node = match (&self.path, &self.fast_path) {
            (Some(p), Some(_)) => {
                let (i, x) = p.locate((h.t * ray.dir.length()) as f64);
                let (a, u) = p.locate_height((ray.origin.z + ray.dir.z * h.t) as f64);
                let next = (p.heights_m.len() >= 2).then(|| p.node(a + 1, i - 1));
                Some((p.node(a, i - 1), x, next, u))
            }
            _ => None,
        };
        // The scattered sunlight of the ray's own angle, by day: per band
        // `Σw·L_ss` linear in the angle, then range, then height.
        let (ks, fs) = match self.fast_path.as_ref().and_then(|p| p.sun) {
            Some(sun) => {
                let (k, f) = angle_node_f32(ray.dir.dot(sun) / ray.dir.length());
                (k, f as f64)
            }
            None => (0, 0.0),
        };
        let scattered = |b: usize| -> f64 {
            let (Some((n0, x, next, u)), Some(fp)) = (node, &self.fast_path) else {
                return 0.0;
            };
            let Some(s) = fp.scatter.get(b) else {
                return 0.0;
            };
            let lerp = |a: f64, b: f64, x: f64| a + x * (b - a);
            let at = |n: usize| lerp(s[n][ks], s[n][ks + 1], fs);
            let v = lerp(at(n0), at(n0 + 1), x);
            match next {
                Some(n1) => lerp(v, lerp(at(n1), at(n1 + 1), x), u),
                None => v,
            }
        };
        for (b, fb) in self.fast.iter().enumerate() {
            if let Some(g) = &fb.grey[mi] {
                // ε and r leave the sums: Σ q·ε·B(T) = ε·Σ q·B(T), …
                let eps = g[a0] + ta * (g[a0 + 1] - g[a0]);
                let r = (1.0 - eps - tr).max(0.0);
                let (bt, bg, sky, sun, lu) = match (node, &self.fast_path) {
                    (Some((n0, x, next, u)), Some(fp)) => {
                        let lerp = |a: f64, b: f64, x: f64| a + x * (b - a);
                        // Linear in range at the height node of `n0`.
                        let at = |n0: usize| {
                            let (p, q) = (&fp.integrals[b][n0], &fp.integrals[b][n0 + 1]);
                            let w = &fp.path_radiance[b];
                            [
                                lerp(p.planck_at(kt, ft), q.planck_at(kt, ft), x),
                                lerp(p.planck_at(kg, fg), q.planck_at(kg, fg), x),
                                lerp(p.sky_at(kb, wb as f64), q.sky_at(kb, wb as f64), x),
                                lerp(p.sun, q.sun, x),
                                lerp(w[n0], w[n0 + 1], x),
                            ]
                        };
                        let mut v = at(n0);
                        if let Some(n1) = next {
                            let v1 = at(n1);
                            for (a, b) in v.iter_mut().zip(v1) {
                                *a = lerp(*a, b, u);
                            }
                        }
                        (v[0], v[1], v[2], v[3], v[4])
                    }
                    _ => {
                        let p = &fb.plain;
                        let sky = p.sky_at(kb, wb as f64);
                        (p.planck_at(kt, ft), p.planck_at(kg, fg), sky, p.sun, 0.0)
                    }
                };
                let env = big_f * sky + (1.0 - big_f) * bg;
                let v = eps * bt + r * (env + sd * sun) + tr * env;
                out[b] = (v + lu + scattered(b)) as f32;
                continue;
            }
            let nl = fb.len;
            let e = &fb.eps[mi];
            let row = |k: usize| &fb.planck[k * nl..(k + 1) * nl];
            // The fused sum with path weights `w·τ₂` linear in range
            // between `q0` and `q1`, plus the band path radiance.
            let sum_with = |q0: &[f32], q1: &[f32], fr: f32| {
                band_sum(
                    &BandStreams {
                        e0: &e[a0 * nl..(a0 + 1) * nl],
                        e1: &e[(a0 + 1) * nl..(a0 + 2) * nl],
                        t0: row(kt),
                        t1: row(kt + 1),
                        g0: row(kg),
                        g1: row(kg + 1),
                        q0,
                        q1,
                        sky0: &fb.sky[kb],
                        sky1: &fb.sky[kb + 1],
                        sun: &fb.sun,
                    },
                    [ta as f32, ft as f32, fg as f32, fr, wb],
                    big_f as f32,
                    sd as f32,
                    tr as f32,
                ) as f64
            };
            out[b] = (match (node, &self.fast_path) {
                (Some((n0, x, next, u)), Some(fp)) => {
                    let at = |n0: usize| {
                        let (q, w) = (&fp.weighted_tau[b], &fp.path_radiance[b]);
                        sum_with(&q[n0], &q[n0 + 1], x as f32) + w[n0] + x * (w[n0 + 1] - w[n0])
                    };
                    let v = at(n0);
                    match next {
                        Some(n1) => v + u * (at(n1) - v),
                        None => v,
                    }
                }
                _ => sum_with(&fb.w, &fb.w, 0.0),
            } + scattered(b)) as f32;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::GreyTables;

    /// The node a range lies in, from its definition: `i` in
    /// `1..=last` with `x[i − 1] ≤ r < x[i]` (clamped at both ends), and
    /// the fraction from `x[i − 1]`.
    fn brute(x: &[f32], r: f32) -> (usize, f32) {
        let last = x.len() - 1;
        let i = x.partition_point(|&v| v <= r).clamp(1, last);
        (i, ((r - x[i - 1]) / (x[i] - x[i - 1])).clamp(0.0, 1.0))
    }

    /// `n + 1` increasing range nodes from 0 m with pseudo-random steps of
    /// 1 to `1 + max_step` m (a linear congruential sequence from `seed`).
    fn irregular_ranges(mut seed: u64, n: usize, max_step: f64) -> Vec<f64> {
        let mut r = vec![0.0];
        for _ in 0..n {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            let step = 1.0 + (seed >> 40) as f64 / (1u64 << 24) as f64 * max_step;
            r.push(r.last().unwrap() + step);
        }
        r
    }

    /// [`GreyTables::locate`] (first guess from √r, then a branch-free step
    /// each way, then the loops) finds the node of its definition for the
    /// quadratic spacing of the path tables and for irregular spacings,
    /// at, between, before and beyond the nodes.
    #[test]
    fn locate_finds_the_node_of_any_range_for_any_spacing() {
        let quadratic: Vec<f64> = (0..48)
            .map(|i| 5000.0 * (i as f64 / 47.0).powi(2))
            .collect();
        let irregular = irregular_ranges(0x2545_f491, 12, 900.0);
        for ranges in [quadratic, irregular, vec![0.0, 10.0]] {
            let t = GreyTables::new(&[], &[], &ranges, &[], &[]);
            let x = &t.ranges;
            let last = *x.last().unwrap();
            let mut probes: Vec<f32> = x.clone();
            probes.extend(x.windows(2).map(|w| 0.5 * (w[0] + w[1])));
            probes.extend(x.iter().map(|&v| v * (1.0 + 1e-7)));
            probes.extend(x.iter().map(|&v| v * (1.0 - 1e-7)));
            probes.extend([-5.0, 0.0, last * 1.5, last * 10.0]);
            for r in probes {
                let (i, f) = t.locate(r);
                let (j, g) = brute(x, r);
                assert_eq!(i, j, "range {r} with nodes {x:?}");
                assert!((f - g).abs() <= 1e-6, "range {r}: fraction {f} against {g}");
            }
        }
    }

    /// [`GreyTables::locate_binned`] (one bin load, one compare) gives
    /// exactly what the reference [`GreyTables::locate`] gives — node and
    /// fraction bit for bit — for every range: the nodes and one ulp
    /// either side, every bin edge and one ulp either side, a dense sweep,
    /// below the first node, beyond the last, ±∞, −0 and NaN; for the path
    /// tables' quadratic spacing at small and large scenes (where the bins
    /// must exist, else this test would only compare the reference with
    /// itself), for irregular spacings, three nodes, and for nodes too
    /// unevenly spaced or repeated (no bins: the reference serves).
    #[test]
    fn locate_binned_equals_the_reference_for_every_range() {
        let quadratic =
            |max: f64| -> Vec<f64> { (0..48).map(|i| max * (i as f64 / 47.0).powi(2)).collect() };
        let irregular = irregular_ranges(0x9e37_79b9, 20, 700.0);
        let cases: Vec<(Vec<f64>, bool)> = vec![
            (quadratic(1.0), true),
            (quadratic(2.0 * (300.0 + 400.0) + 1.0), true),
            (quadratic(2.0 * (3000.0 + 25_000.0) + 1.0), true),
            (quadratic(4.0e5), true),
            (irregular, true),
            (vec![0.0, 10.0, 35.0], true),
            (vec![-20.0, 3.0, 7.0, 9.0], true),
            (vec![0.0, 1.0, 1.0 + 1e-4, 1e5], false),
            (vec![0.0, 5.0, 5.0, 9.0], false),
            (vec![0.0, 10.0], false),
        ];
        for (ranges, binned) in cases {
            let t = GreyTables::new(&[], &[], &ranges, &[], &[]);
            assert_eq!(
                !t.range_bins.is_empty(),
                binned,
                "bins for nodes {ranges:?}"
            );
            let x = &t.ranges;
            let last = *x.last().unwrap();
            let mut probes: Vec<f32> = Vec::new();
            for &v in x {
                probes.extend([v, v.next_up(), v.next_down()]);
            }
            for k in 0..=t.range_bins.len() {
                let v = k as f32 / t.bin_scale;
                probes.extend([v, v.next_up(), v.next_down()]);
            }
            probes.extend((0..20_000).map(|k| last * 1.2 * k as f32 / 20_000.0));
            probes.extend([
                -5.0,
                -0.0,
                0.0,
                last * 10.0,
                f32::MAX,
                f32::INFINITY,
                f32::NEG_INFINITY,
                f32::NAN,
            ]);
            for r in probes {
                let (i, f) = t.locate_binned(r);
                let (j, g) = t.locate(r);
                assert_eq!(i, j, "range {r} with nodes {x:?}");
                assert!(
                    f.to_bits() == g.to_bits() || (f.is_nan() && g.is_nan()),
                    "range {r}: fraction {f} against {g}"
                );
                if !r.is_nan() {
                    let (b, h) = brute(x, r);
                    assert_eq!(i, b, "range {r} with nodes {x:?}");
                    assert!((f - h).abs() <= 1e-6, "range {r}: {f} against {h}");
                }
            }
        }
    }

    /// [`GreyTables::locate_height`] finds the node of its definition —
    /// the last `a ≤ len − 2` with `x[a] ≤ z`, else 0 — for even, uneven
    /// and single-step spacings, at, between, below and above the nodes,
    /// and for a NaN height.
    #[test]
    fn locate_height_finds_the_node_of_any_height_for_any_spacing() {
        fn brute(x: &[f32], z: f32) -> (usize, f32) {
            let top = x.len() - 2;
            let a = (1..=top).filter(|&k| x[k] <= z).count();
            (a, ((z - x[a]) / (x[a + 1] - x[a])).clamp(0.0, 1.0))
        }
        let even: Vec<f64> = (0..=7).map(|a| -3.0 + 45.0 * a as f64 / 7.0).collect();
        let uneven = vec![0.0, 1.0, 30.0, 31.0, 90.0];
        for heights in [even, uneven, vec![2.0, 27.0]] {
            let t = GreyTables::new(&[], &[], &[], &heights, &[]);
            let x = t.heights.clone();
            let mut probes: Vec<f32> = x.clone();
            probes.extend(x.windows(2).map(|w| 0.5 * (w[0] + w[1])));
            probes.extend(x.iter().map(|&v| v + 1e-4));
            probes.extend(x.iter().map(|&v| v - 1e-4));
            probes.extend([-1e4, 1e4, f32::INFINITY, f32::NEG_INFINITY]);
            for z in probes {
                let (a, u) = t.locate_height(z);
                let (b, v) = brute(&x, z);
                assert_eq!(a, b, "height {z} with nodes {x:?}");
                assert!(
                    (u - v).abs() <= 1e-6,
                    "height {z}: fraction {u} against {v}"
                );
            }
            let (a, _) = t.locate_height(f32::NAN);
            assert_eq!(a, 0, "NaN height with nodes {x:?}");
        }
    }
}
