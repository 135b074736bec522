//! The linearised scene-wide thermal solve ([`super::ThermalMethod::Linearized`],
//! the default): a few nonlinear reference solves per material and a
//! Green's-matrix product per facet.
//!
//! # Method
//! Every facet-specific input of the slab model enters only as an additive
//! surface source history (front `S_k`, exposed back `B_k`;
//! [`crate::thermal::linear`]). So:
//! 1. Facets are grouped by property set (equal [`SlabProperties`]).
//! 2. Per group, the facet with the median daily-mean source (over at most
//!    1024 members evenly spaced in facet order) is solved with
//!    the nonlinear model and linearised ([`thermal::linearize`]: its
//!    Green's matrices `G[t][k] = ∂T(t)/∂S_k`). Every facet's first-order
//!    temperature change from it predicts where the facet lies.
//! 3. Facets are binned per group by that prediction — the change at the
//!    first and last image records and its daily mean, each in bins of
//!    [`LinearizedParams::bin_k`] — and each bin gets its own reference: the
//!    facet closest to the bin's centroid, linearised. The neglected
//!    curvature of the emission grows with the square of the distance from
//!    the reference, so narrow bins bound it.
//! 4. Each pass, each facet: `T = T_ref + G·ΔS`, plus, in the last pass
//!    and with [`LinearizedParams::second_order`], `G·r(Δ)` for the
//!    curvature of the emission. Pass 1 takes the air as background; pass
//!    `p ≥ 2` adds to each facet's sources its background's excess over the
//!    air, `c·σ(T_bg⁴ − T_air⁴)` ([`thermal::background_coefficients`]),
//!    with `T_bg⁴` the radiative mean of the previous pass's temperatures of
//!    what its blocked hemisphere rays hit — the rule of the per-class path
//!    ([`super::solve_facet_temperatures`]). Only the sources change, so the
//!    references and their matrices serve every pass. A pass before the last
//!    computes full histories only for the facets some facet sees (stored
//!    as `T⁴` for the next pass's backgrounds); the image records need only
//!    a row of `G` each, and a later pass adds to pass 1's image records
//!    just the background term `G·(c·σ(T_bg⁴ − T_air⁴))`.
//!
//! The sources of all facets of a property set come from one
//! [`thermal::SourceModel`] (affine in `F`, `F_b`, `s·cos θ`), so the
//! products with a reference's `G` split into precomputed products with
//! the model's parts and, per facet, one product over its `s·max(cos θ, 0)`
//! history (only its non-zero records for a full history).
//!
//! Work is per facet and per reference, in facet order; the result does
//! not depend on the thread count.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::Exposure;
use super::solve::{FacetThermal, LinearizedParams, PassStats, SceneTemperatures};
use crate::thermal::{self, Background, FacetInputs, Forcing, Linearization, SlabProperties};
use crate::{Error, Result};

/// Facets per work item of the parallel loops.
const CHUNK: usize = 256;

/// Most members of a property set whose daily-mean sources choose its
/// centre facet (their median).
const MEDIAN_SAMPLE: usize = 1024;

/// A reference facet's linearisation in the layout the per-facet products
/// use: `f32`, column-major (`g[k·R + t] = ∂T(t)/∂S_k`), plus the rows of
/// the image records row-major, and the products of its Green's matrices
/// with the parts of the affine source model
/// ([`thermal::SourceModel`]: `S = base + F·∂S/∂F + s cos θ·αE_dn`), so
/// that a facet's first-order change at a probed record is one dot product
/// over its `s·max(cos θ, 0)` history plus a few scalars.
struct Reference {
    has_back: bool,
    gt_ff: Vec<f32>,
    gt_fb: Vec<f32>,
    gt_bf: Vec<f32>,
    gt_bb: Vec<f32>,
    /// Rows `[i][k]` of `∂T_front(rows[i])/∂S_k` and `/∂B_k`.
    rows_ff: Vec<f32>,
    rows_fb: Vec<f32>,
    /// Probes `j` (the rows, then the column means `(1/R) Σ_t G[t][k]`):
    /// `P_j[k]·αE_dn[k]` (`[j][k]`), `P_j·∂S/∂F`, `P_fb,j·∂B/∂F_b`,
    /// `P_j·(s cos θ_ref·αE_dn)` (K per unit and K).
    probe_sun: Vec<f32>,
    probe_shape: Vec<f32>,
    probe_back: Vec<f32>,
    probe_ref: Vec<f32>,
    t_front: Vec<f32>,
    t_back: Vec<f32>,
    r_front: f32,
    r_back: f32,
    spinup_change_k: f64,
    /// The reference's shape factors and `s·max(cos θ, 0)` history.
    f: f32,
    f_back: f32,
    sc: Vec<f32>,
    /// `G·∂S/∂F`, `G·∂B/∂F_b`, `G·(s cos θ_ref·αE_dn)` of the front (and
    /// back) node, K per unit and K.
    g_shape: Vec<f32>,
    g_back_shape: Vec<f32>,
    g_ref: Vec<f32>,
    gb_shape: Vec<f32>,
    gb_back_shape: Vec<f32>,
    gb_ref: Vec<f32>,
}

/// What a facet's sources are made of (see [`thermal::SourceModel`]).
#[derive(Clone, Copy)]
struct FacetState<'a> {
    f: f32,
    f_back: f32,
    sun_fraction: &'a [f32],
    cos_incidence: &'a [f32],
}

impl Reference {
    fn new(
        lin: Linearization,
        rows: &[usize],
        model: &thermal::SourceModel,
        st: FacetState,
    ) -> Reference {
        let r = lin.records;
        let sc: Vec<f32> = sunlit_cos(st).collect();
        let sun = model.front_per_sunlit_cos();
        let ref_sun: Vec<f64> = sc.iter().zip(sun).map(|(&c, w)| c as f64 * w).collect();
        let times = |g: &[f64], v: &[f64]| -> Vec<f32> {
            if g.is_empty() || v.is_empty() {
                return Vec::new();
            }
            (0..r)
                .map(|t| {
                    g[t * r..(t + 1) * r]
                        .iter()
                        .zip(v)
                        .map(|(a, b)| a * b)
                        .sum::<f64>() as f32
                })
                .collect()
        };
        let shape = model.front_per_shape_factor();
        let back_shape = model.back_per_shape_factor();
        let transpose = |g: &[f64]| -> Vec<f32> {
            if g.is_empty() {
                return Vec::new();
            }
            let mut out = vec![0.0f32; r * r];
            for t in 0..r {
                for k in 0..r {
                    out[k * r + t] = g[t * r + k] as f32;
                }
            }
            out
        };
        // Probe vectors (f64): the rows, then the column means.
        let probes = |g: &[f64]| -> Vec<Vec<f64>> {
            if g.is_empty() {
                return Vec::new();
            }
            let mut p: Vec<Vec<f64>> = rows
                .iter()
                .map(|&t| g[t * r..(t + 1) * r].to_vec())
                .collect();
            p.push(
                (0..r)
                    .map(|k| (0..r).map(|t| g[t * r + k]).sum::<f64>() / r as f64)
                    .collect(),
            );
            p
        };
        let (pf, pb) = (probes(&lin.front_from_front), probes(&lin.front_from_back));
        let dot64 = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let rows_of = |p: &[Vec<f64>]| -> Vec<f32> {
            p.iter()
                .take(rows.len())
                .flat_map(|v| v.iter().map(|&x| x as f32))
                .collect()
        };
        let f32s = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
        Reference {
            has_back: lin.has_back(),
            gt_ff: transpose(&lin.front_from_front),
            gt_fb: transpose(&lin.front_from_back),
            gt_bf: transpose(&lin.back_from_front),
            gt_bb: transpose(&lin.back_from_back),
            rows_ff: rows_of(&pf),
            rows_fb: rows_of(&pb),
            probe_sun: pf
                .iter()
                .flat_map(|p| p.iter().zip(sun).map(|(a, b)| (a * b) as f32))
                .collect(),
            probe_shape: pf.iter().map(|p| dot64(p, shape) as f32).collect(),
            probe_back: pb.iter().map(|p| dot64(p, back_shape) as f32).collect(),
            probe_ref: pf.iter().map(|p| dot64(p, &ref_sun) as f32).collect(),
            t_front: f32s(&lin.solution.surface_temperature_k),
            t_back: f32s(&lin.solution.back_temperature_k),
            r_front: lin.front_radiative_w_m2_k4 as f32,
            r_back: lin.back_radiative_w_m2_k4 as f32,
            spinup_change_k: lin.solution.spinup_change_k.unwrap_or(0.0),
            f: st.f,
            f_back: st.f_back,
            sc,
            g_shape: times(&lin.front_from_front, shape),
            g_back_shape: times(&lin.front_from_back, back_shape),
            g_ref: times(&lin.front_from_front, &ref_sun),
            gb_shape: times(&lin.back_from_front, shape),
            gb_back_shape: times(&lin.back_from_back, back_shape),
            gb_ref: times(&lin.back_from_front, &ref_sun),
        }
    }

    /// First-order change of the front temperature at probe `j` (K) of a
    /// facet with `s·max(cos θ, 0)` history `sc` and shape factors `df`,
    /// `dfb` from the reference's, with the air as background.
    #[inline]
    fn probe(&self, j: usize, sc: &[f32], df: f32, dfb: f32) -> f32 {
        let r = sc.len();
        let mut v = dot(&self.probe_sun[j * r..(j + 1) * r], sc) - self.probe_ref[j]
            + df * self.probe_shape[j];
        if self.has_back {
            v += dfb * self.probe_back[j];
        }
        v
    }
}

/// `s·max(cos θ, 0)` at each record.
fn sunlit_cos<'a>(st: FacetState<'a>) -> impl Iterator<Item = f32> + 'a {
    st.sun_fraction
        .iter()
        .zip(st.cos_incidence)
        .map(|(s, c)| s.clamp(0.0, 1.0) * c.max(0.0))
}

/// `y += Σ x_k G[:, k]` over the listed columns `(k, x_k)` of a
/// column-major `G` (`g[k·R + t]`, `R = y.len()`), in blocks of `y` that
/// stay in registers.
#[inline]
fn matvec_cols(g: &[f32], cols: &[(u32, f32)], y: &mut [f32]) {
    const B: usize = 32;
    let r = y.len();
    let mut blocks = y.chunks_exact_mut(B);
    for (b, yb) in (&mut blocks).enumerate() {
        let t0 = b * B;
        let mut acc = [0.0f32; B];
        acc.copy_from_slice(yb);
        for &(k, x) in cols {
            let col = &g[k as usize * r + t0..k as usize * r + t0 + B];
            for i in 0..B {
                acc[i] += x * col[i];
            }
        }
        yb.copy_from_slice(&acc);
    }
    let tail = blocks.into_remainder();
    let t0 = r - tail.len();
    for (i, v) in tail.iter_mut().enumerate() {
        let t = t0 + i;
        *v += cols
            .iter()
            .map(|&(k, x)| x * g[k as usize * r + t])
            .sum::<f32>();
    }
}

/// `y[t] += Σ_j c_j·h_j[t]` over `items` `(j, c_j)` in order, `h_j` the
/// `j`-th history of `hist` (`R = y.len()` records each), or `y[t] += c_j`
/// where `j` is `u32::MAX`; in blocks of `y` that stay in registers.
#[inline]
fn accumulate_rows(hist: &[f32], items: &[(u32, f32)], y: &mut [f32]) {
    const B: usize = 32;
    let r = y.len();
    let mut blocks = y.chunks_exact_mut(B);
    for (b, yb) in (&mut blocks).enumerate() {
        let t0 = b * B;
        let mut acc = [0.0f32; B];
        acc.copy_from_slice(yb);
        for &(j, c) in items {
            if j == u32::MAX {
                acc.iter_mut().for_each(|a| *a += c);
            } else {
                let h = &hist[j as usize * r + t0..j as usize * r + t0 + B];
                for i in 0..B {
                    acc[i] += c * h[i];
                }
            }
        }
        yb.copy_from_slice(&acc);
    }
    let tail = blocks.into_remainder();
    let t0 = r - tail.len();
    for (i, v) in tail.iter_mut().enumerate() {
        let mut a = *v;
        for &(j, c) in items {
            a += if j == u32::MAX {
                c
            } else {
                c * hist[j as usize * r + t0 + i]
            };
        }
        *v = a;
    }
}

/// The non-zero entries `(k, c·v_k)` of `c·v` into `out`.
#[inline]
fn columns(v: impl Iterator<Item = f32>, c: f32, out: &mut Vec<(u32, f32)>) {
    out.clear();
    out.extend(
        v.enumerate()
            .filter(|&(_, x)| x != 0.0)
            .map(|(k, x)| (k as u32, c * x)),
    );
}

/// `a · b`, in eight lanes (vectorisable).
#[inline]
fn dot(a: &[f32], b: &[f32]) -> f32 {
    let mut acc = [0.0f32; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for i in 0..8 {
            acc[i] += x[i] * y[i];
        }
    }
    let tail: f32 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    acc.iter().sum::<f32>() + tail
}

/// `−R Δ²(6T² + 4TΔ + Δ²)`, the emission curvature (f32).
#[inline]
fn curvature(r: f32, t: f32, d: f32) -> f32 {
    -r * d * d * (6.0 * t * t + 4.0 * t * d + d * d)
}

/// Everything fixed over the passes.
struct Ctx<'a> {
    exposure: &'a Exposure,
    kinds: &'a [FacetThermal],
    props: &'a [SlabProperties],
    forcing: &'a Forcing,
    air4: Vec<f32>,
}

impl Ctx<'_> {
    /// `σ(T_bg⁴ − T_air⁴)` history of `facet` from the previous pass's
    /// `T⁴` histories (`prev4[slot[f]·R + k]`) into `out` (W m⁻²); false
    /// when it sees only sky. `T_bg⁴` is the radiative mean of the dedup
    /// path ([`super::solve_facet_temperatures`]).
    fn background_excess(
        &self,
        facet: usize,
        prev4: &[f32],
        slot: &[u32],
        out: &mut [f32],
        items: &mut Vec<(u32, f32)>,
    ) -> bool {
        let sky = &self.exposure.sky;
        let g = sky.ground_weight[facet];
        let entries = sky.background(facet);
        let den: f32 = g + entries.iter().map(|e| e.weight).sum::<f32>();
        if den <= 0.0 {
            return false;
        }
        out.iter_mut().zip(&self.air4).for_each(|(o, a)| *o = g * a);
        // (slot, weight) of the solved facets seen, (MAX, w·T⁴) of the
        // fixed ones, in entry order.
        items.clear();
        items.extend(entries.iter().map(|e| {
            let j = e.facet as usize;
            match self.kinds[j] {
                FacetThermal::Fixed(t) => (u32::MAX, e.weight * t.powi(4)),
                FacetThermal::Solve(_) => (slot[j], e.weight),
            }
        }));
        accumulate_rows(prev4, items, out);
        let k = thermal::STEFAN_BOLTZMANN_W_M2_K4 as f32 / den;
        let sa = thermal::STEFAN_BOLTZMANN_W_M2_K4 as f32;
        out.iter_mut()
            .zip(&self.air4)
            .for_each(|(o, a)| *o = *o * k - sa * a);
        true
    }

    fn inputs(&self, facet: usize) -> FacetInputs<'_> {
        let exposure = self.exposure;
        FacetInputs {
            sun_fraction: exposure.solar.sun_fraction(facet),
            cos_incidence: exposure.solar.cos_incidence(facet),
            shape_factor: exposure.sky.shape_factor[facet] as f64,
            back_shape_factor: exposure.sky.back_shape_factor(facet).map(f64::from),
            background: Background::Air,
        }
    }

    fn props_of(&self, facet: usize) -> &SlabProperties {
        let FacetThermal::Solve(pi) = self.kinds[facet] else {
            unreachable!("solved facets only")
        };
        &self.props[pi as usize]
    }

    /// Linearise about `facet` (air as background).
    fn linearize(
        &self,
        facet: usize,
        lp: &LinearizedParams,
        rows: &[usize],
        model: &thermal::SourceModel,
    ) -> Result<Reference> {
        let lin = thermal::linearize(
            self.props_of(facet),
            self.forcing,
            &self.inputs(facet),
            &lp.options,
        )
        .map_err(|e| Error::Other(format!("thermal model of facet {facet}: {e}")))?;
        Ok(Reference::new(lin, rows, model, self.state(facet)))
    }

    /// The inputs a facet's sources are made of.
    fn state(&self, facet: usize) -> FacetState<'_> {
        let sky = &self.exposure.sky;
        let f = sky.shape_factor[facet];
        FacetState {
            f,
            f_back: sky.back_shape_factor(facet).unwrap_or(1.0 - f),
            sun_fraction: self.exposure.solar.sun_fraction(facet),
            cos_incidence: self.exposure.solar.cos_incidence(facet),
        }
    }
}

/// Key of a property set: its fields' bits.
fn prop_key(p: &SlabProperties) -> Vec<u64> {
    let mut k = vec![
        p.conductivity_w_m_k.to_bits(),
        p.density_kg_m3.to_bits(),
        p.specific_heat_j_kg_k.to_bits(),
        p.thickness_m.to_bits(),
        p.solar_absorptivity.to_bits(),
        p.thermal_emissivity.to_bits(),
        p.self_power_w_m2.to_bits(),
    ];
    match p.back {
        thermal::BackBoundary::Insulated => k.push(0),
        thermal::BackBoundary::Exposed { fraction } => k.extend([1, fraction.to_bits()]),
        thermal::BackBoundary::Ground {
            deep_temperature_k,
            depth_m,
        } => k.extend([
            2,
            deep_temperature_k.map_or(u64::MAX, f64::to_bits),
            depth_m.map_or(u64::MAX, f64::to_bits),
        ]),
        thermal::BackBoundary::Interior {
            air_temperature_k,
            film_coefficient_w_m2_k,
        } => k.extend([
            3,
            air_temperature_k.to_bits(),
            film_coefficient_w_m2_k.to_bits(),
        ]),
    }
    k
}

/// Scratch buffers of one worker.
struct Scratch {
    sc: Vec<f32>,
    ds: Vec<f32>,
    db: Vec<f32>,
    d: Vec<f32>,
    dback: Vec<f32>,
    bg: Vec<f32>,
    cols: Vec<(u32, f32)>,
    cols_bg: Vec<(u32, f32)>,
}

impl Scratch {
    fn new(r: usize) -> Scratch {
        Scratch {
            sc: vec![0.0; r],
            ds: vec![0.0; r],
            db: vec![0.0; r],
            d: vec![0.0; r],
            dback: vec![0.0; r],
            bg: vec![0.0; r],
            cols: Vec::with_capacity(r),
            cols_bg: Vec::with_capacity(r),
        }
    }
}

/// The linearised solve (module docs). Inputs are validated by the caller.
pub(super) fn solve(
    exposure: &Exposure,
    kinds: &[FacetThermal],
    props: &[SlabProperties],
    forcing: &Forcing,
    image_records: &[usize],
    passes: u32,
    lp: &LinearizedParams,
) -> Result<SceneTemperatures> {
    let n = kinds.len();
    let r = forcing.len();
    let t_start = Instant::now();
    let ctx = Ctx {
        exposure,
        kinds,
        props,
        forcing,
        air4: forcing
            .air_temperature_k
            .iter()
            .map(|&t| (t as f32).powi(4))
            .collect(),
    };
    let first = *image_records.first().unwrap_or(&(r - 1));
    let last = *image_records.last().unwrap_or(&(r - 1));
    // Rows kept row-major: the image records, then the first and last.
    let mut rows: Vec<usize> = image_records.to_vec();
    rows.extend([first, last]);
    let (row_first, row_last) = (image_records.len(), image_records.len() + 1);

    // 1. Groups of equal property sets.
    let mut group_ids: BTreeMap<Vec<u64>, u32> = BTreeMap::new();
    let prop_group: Vec<u32> = props
        .iter()
        .map(|p| {
            let next = group_ids.len() as u32;
            *group_ids.entry(prop_key(p)).or_insert(next)
        })
        .collect();
    let groups = group_ids.len();
    let group_of = |f: usize| match kinds[f] {
        FacetThermal::Solve(pi) => Some(prop_group[pi as usize] as usize),
        FacetThermal::Fixed(_) => None,
    };
    // 2. Source models per group; a facet's pass-1 sources (air as
    // background) are formed on the fly from them, never stored.
    // Group representatives' property sets → source models.
    let mut group_props: Vec<Option<&SlabProperties>> = vec![None; groups];
    for (p, &g) in props.iter().zip(&prop_group) {
        group_props[g as usize].get_or_insert(p);
    }
    let models: Vec<thermal::SourceModel> = group_props
        .iter()
        .map(|p| thermal::SourceModel::new(p.expect("every group has a property set"), forcing))
        .collect();
    let f32s = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
    // ∂S/∂F, ∂B/∂F_b and α E_dn (the weight of s·cos θ) per record and
    // group (f32).
    let shape32: Vec<Vec<f32>> = models
        .iter()
        .map(|m| f32s(m.front_per_shape_factor()))
        .collect();
    let back_shape32: Vec<Vec<f32>> = models
        .iter()
        .map(|m| f32s(m.back_per_shape_factor()))
        .collect();
    let sun32: Vec<Vec<f32>> = models
        .iter()
        .map(|m| f32s(m.front_per_sunlit_cos()))
        .collect();
    // Daily means of the front sources: mean(base) + F·mean(∂S/∂F) +
    // mean(s cos θ · αE_dn).
    let base_mean: Vec<f64> = models
        .iter()
        .map(|m| {
            let mut out = vec![0.0f32; r];
            m.front_into(&vec![0.0; r], &vec![0.0; r], 0.0, &mut out);
            out.iter().map(|&v| v as f64).sum::<f64>() / r as f64
        })
        .collect();
    let shape_mean: Vec<f64> = models
        .iter()
        .map(|m| m.front_per_shape_factor().iter().sum::<f64>() / r as f64)
        .collect();
    let mean_of = |f: usize, g: usize| -> f64 {
        let sun: f64 = sunlit_cos(ctx.state(f))
            .zip(&sun32[g])
            .map(|(sc, w)| (sc * w) as f64)
            .sum();
        base_mean[g] + exposure.sky.shape_factor[f] as f64 * shape_mean[g] + sun / r as f64
    };

    // 3. Per group, the facet with the median daily-mean source, linearised.
    // The median is taken over at most `MEDIAN_SAMPLE` members evenly spaced
    // in facet order: it only centres the first-order predictions that bin
    // the facets (step 4), and reading every facet's history for it cost as
    // much as the binning itself.
    let mut per_group: Vec<Vec<usize>> = vec![Vec::new(); groups];
    for f in 0..n {
        if let Some(g) = group_of(f) {
            per_group[g].push(f);
        }
    }
    let centre: Vec<usize> = per_group
        .par_iter()
        .enumerate()
        .map(|(g, v)| {
            if v.is_empty() {
                return usize::MAX;
            }
            let stride = v.len().div_ceil(MEDIAN_SAMPLE);
            let mut sample: Vec<(f64, usize)> = v
                .iter()
                .step_by(stride)
                .map(|&f| (mean_of(f, g), f))
                .collect();
            // The median of a total order (mean, then facet).
            let mid = sample.len() / 2;
            sample.select_nth_unstable_by(mid, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            sample[mid].1
        })
        .collect();
    drop(per_group);
    let g_of = |f: usize| group_of(f).expect("references are solved facets");
    let centre_refs: Vec<Option<Reference>> = centre
        .par_iter()
        .map(|&f| {
            (f != usize::MAX)
                .then(|| ctx.linearize(f, lp, &rows, &models[g_of(f)]))
                .transpose()
        })
        .collect::<Result<_>>()?;

    // 4. Bins of the first-order change from the group's centre.
    let mean_probe = rows.len();
    let features: Vec<(usize, [f32; 3])> = (0..n)
        .into_par_iter()
        .filter_map(|f| group_of(f).map(|g| (f, g)))
        .map_init(
            || Scratch::new(r),
            |s, (f, g)| {
                let rep = centre_refs[g].as_ref().expect("non-empty group");
                let st = ctx.state(f);
                s.sc.iter_mut()
                    .zip(sunlit_cos(st))
                    .for_each(|(o, v)| *o = v);
                let (df, dfb) = (st.f - rep.f, st.f_back - rep.f_back);
                let p = |j: usize| rep.probe(j, &s.sc, df, dfb);
                (f, [p(row_first), p(row_last), p(mean_probe)])
            },
        )
        .collect();
    let w = lp.bin_k;
    // Facets sorted by (group, bin key, facet): the bins in key order. The
    // key packed in a u128 (group, then the three bin indices with their
    // sign bit flipped, so unsigned order is signed order) beside the
    // facet's index in `features` (which is in facet order).
    let flip = |k: f32| ((k / w).round() as i32 as u32 ^ 0x8000_0000) as u128;
    let mut keyed: Vec<(u128, u32)> = features
        .par_iter()
        .enumerate()
        .map(|(i, &(f, x))| {
            let g = group_of(f).expect("solved") as u128;
            let key = (g << 96) | (flip(x[0]) << 64) | (flip(x[1]) << 32) | flip(x[2]);
            (key, i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    // The reference of each bin: the member closest to its centroid.
    let mut bin_rep = Vec::new();
    let mut ref_of = vec![u32::MAX; n];
    for (b, members) in keyed.chunk_by(|a, b| a.0 == b.0).enumerate() {
        let m = members.len() as f32;
        let c = members.iter().fold([0.0f32; 3], |a, &(_, i)| {
            let x = features[i as usize].1;
            [a[0] + x[0] / m, a[1] + x[1] / m, a[2] + x[2] / m]
        });
        let dist = |x: &[f32; 3]| (0..3).map(|i| (x[i] - c[i]).powi(2)).sum::<f32>();
        let best = members
            .iter()
            .map(|&(_, i)| features[i as usize])
            .min_by(|a, b| dist(&a.1).total_cmp(&dist(&b.1)).then(a.0.cmp(&b.0)))
            .expect("non-empty bin")
            .0;
        bin_rep.push(best);
        for &(_, i) in members {
            ref_of[features[i as usize].0] = b as u32;
        }
    }
    drop(keyed);
    let refs: Vec<Reference> = bin_rep
        .par_iter()
        .map(|&f| ctx.linearize(f, lp, &rows, &models[g_of(f)]))
        .collect::<Result<_>>()?;
    let max_spin = refs
        .iter()
        .chain(centre_refs.iter().flatten())
        .map(|x| x.spinup_change_k)
        .fold(0.0, f64::max);
    drop(centre_refs);
    let setup = t_start.elapsed();

    // 5. The passes. Pass 1 takes the air as background; a later pass adds
    // the background excess over the air, `c·σ(T_bg⁴ − T_air⁴)`, to the
    // sources. A pass that is not the last yields (first-order) `T⁴`
    // histories of the facets others see, for the next one's backgrounds;
    // every pass yields the image records. Pass 1's image records (first
    // order, air background) are kept: a later pass adds to them the
    // background term `G·(c·bg)` at the image rows alone, unless it needs
    // the facet's full history.
    // Facets some facet sees get a slot in the `T⁴` histories.
    let sky = &exposure.sky;
    let mut slot = vec![u32::MAX; n];
    let mut slots = 0usize;
    if passes > 1 {
        let mut needed = vec![false; n];
        for e in &sky.entries {
            needed[e.facet as usize] = true;
        }
        for f in 0..n {
            if needed[f] && matches!(kinds[f], FacetThermal::Solve(_)) {
                slot[f] = slots as u32;
                slots += 1;
            }
        }
    }
    let ni = image_records.len();
    let chunks = n.div_ceil(CHUNK);
    // First slot of each chunk of facets.
    let mut chunk_slot = vec![0usize; chunks + 1];
    for (c, ch) in slot.chunks(CHUNK).enumerate() {
        chunk_slot[c + 1] = chunk_slot[c] + ch.iter().filter(|&&x| x != u32::MAX).count();
    }
    let wi = ni.max(1);
    let mut stats = Vec::new();
    let mut prev4: Option<Vec<f32>> = None;
    let mut base: Option<Vec<f32>> = None;
    let mut prev_image: Option<Vec<Vec<f32>>> = None;
    let mut image = Vec::new();
    for p in 0..passes {
        let t0 = Instant::now();
        let last_pass = p + 1 == passes;
        let second = last_pass && lp.second_order;
        let prev = prev4.as_deref();
        let base_img = base.as_deref();
        // Written in place, chunk by chunk (no per-chunk copies).
        let store4 = !last_pass;
        let mut img = vec![0.0f32; n * wi];
        let mut next4 = vec![0.0f32; if store4 { slots * r } else { 0 }];
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
        img.par_chunks_mut(CHUNK * wi)
            .zip(parts.into_par_iter())
            .enumerate()
            .for_each_init(
                || Scratch::new(r),
                |s, (c, (img, out4))| {
                    let range = c * CHUNK..((c + 1) * CHUNK).min(n);
                    for (i, f) in range.enumerate() {
                        let o = &mut img[i * wi..i * wi + ni];
                        if let FacetThermal::Fixed(t) = kinds[f] {
                            o.iter_mut().for_each(|v| *v = t);
                            continue;
                        }
                        let rep = &refs[ref_of[f] as usize];
                        let has_slot = slot[f] != u32::MAX;
                        let full = second || (!last_pass && has_slot);
                        let bgc = match prev {
                            Some(prev)
                                if ctx.background_excess(
                                    f,
                                    prev,
                                    &slot,
                                    &mut s.bg,
                                    &mut s.cols_bg,
                                ) =>
                            {
                                let (cf, cb) = thermal::background_coefficients(
                                    ctx.props_of(f),
                                    exposure.sky.shape_factor[f] as f64,
                                    exposure.sky.back_shape_factor(f).map(f64::from),
                                );
                                Some((cf as f32, cb as f32))
                            }
                            _ => None,
                        };
                        if !full && let Some(base) = base_img {
                            // Pass 1's image records plus the background
                            // term at the image rows.
                            o.copy_from_slice(&base[f * wi..f * wi + ni]);
                            if let Some((cf, cb)) = bgc {
                                for (i, v) in o.iter_mut().enumerate() {
                                    *v += cf * dot(&rep.rows_ff[i * r..(i + 1) * r], &s.bg);
                                    if rep.has_back {
                                        *v += cb * dot(&rep.rows_fb[i * r..(i + 1) * r], &s.bg);
                                    }
                                }
                            }
                            continue;
                        }
                        let st = ctx.state(f);
                        let (df, dfb) = (st.f - rep.f, st.f_back - rep.f_back);
                        s.sc.iter_mut()
                            .zip(sunlit_cos(st))
                            .for_each(|(o, v)| *o = v);
                        if !full {
                            // Pass 1, image records only.
                            for (i, v) in o.iter_mut().enumerate() {
                                *v = rep.t_front[image_records[i]] + rep.probe(i, &s.sc, df, dfb);
                            }
                            continue;
                        }
                        // The full first-order history of the front (and,
                        // for the second order, back) node: ΔS = ΔF·∂S/∂F
                        // + (s cos θ − s cos θ_ref)·αE_dn (+ c·bg), the F
                        // terms and the reference's sun one column each.
                        let sun = &sun32[g_of(f)];
                        columns(s.sc.iter().zip(sun).map(|(a, b)| a * b), 1.0, &mut s.cols);
                        let node = |gt_f: &[f32],
                                    gt_b: &[f32],
                                    g_shape: &[f32],
                                    g_back_shape: &[f32],
                                    g_ref: &[f32],
                                    bg: &[f32],
                                    cols: &[(u32, f32)],
                                    cols_bg: &mut Vec<(u32, f32)>,
                                    y: &mut [f32]| {
                            for ((v, a), b) in y.iter_mut().zip(g_shape).zip(g_ref) {
                                *v = df * a - b;
                            }
                            if rep.has_back {
                                for (v, g) in y.iter_mut().zip(g_back_shape) {
                                    *v += dfb * g;
                                }
                            }
                            matvec_cols(gt_f, cols, y);
                            if let Some((cf, cb)) = bgc {
                                columns(bg.iter().copied(), cf, cols_bg);
                                matvec_cols(gt_f, cols_bg, y);
                                if rep.has_back {
                                    columns(bg.iter().copied(), cb, cols_bg);
                                    matvec_cols(gt_b, cols_bg, y);
                                }
                            }
                        };
                        node(
                            &rep.gt_ff,
                            &rep.gt_fb,
                            &rep.g_shape,
                            &rep.g_back_shape,
                            &rep.g_ref,
                            &s.bg,
                            &s.cols,
                            &mut s.cols_bg,
                            &mut s.d,
                        );
                        if second {
                            if rep.has_back {
                                node(
                                    &rep.gt_bf,
                                    &rep.gt_bb,
                                    &rep.gb_shape,
                                    &rep.gb_back_shape,
                                    &rep.gb_ref,
                                    &s.bg,
                                    &s.cols,
                                    &mut s.cols_bg,
                                    &mut s.dback,
                                );
                            }
                            // T = T_ref + G (ΔS + r(Δ)), Δ = G ΔS.
                            let g = g_of(f);
                            for (((((o, sc), rsc), w), sh), (d, t)) in
                                s.ds.iter_mut()
                                    .zip(&s.sc)
                                    .zip(&rep.sc)
                                    .zip(sun)
                                    .zip(&shape32[g])
                                    .zip(s.d.iter().zip(&rep.t_front))
                            {
                                *o = df * sh + (sc - rsc) * w + curvature(rep.r_front, *t, *d);
                            }
                            if let Some((cf, _)) = bgc {
                                s.ds.iter_mut().zip(&s.bg).for_each(|(o, e)| *o += cf * e);
                            }
                            if rep.has_back {
                                for ((o, sh), (d, t)) in
                                    s.db.iter_mut()
                                        .zip(&back_shape32[g])
                                        .zip(s.dback.iter().zip(&rep.t_back))
                                {
                                    *o = dfb * sh + curvature(rep.r_back, *t, *d);
                                }
                                if let Some((_, cb)) = bgc {
                                    s.db.iter_mut().zip(&s.bg).for_each(|(o, e)| *o += cb * e);
                                }
                            }
                            for (i, v) in o.iter_mut().enumerate() {
                                let mut x = dot(&rep.rows_ff[i * r..(i + 1) * r], &s.ds);
                                if rep.has_back {
                                    x += dot(&rep.rows_fb[i * r..(i + 1) * r], &s.db);
                                }
                                *v = rep.t_front[image_records[i]] + x;
                            }
                            continue;
                        }
                        for (v, &t) in o.iter_mut().zip(image_records) {
                            *v = rep.t_front[t] + s.d[t];
                        }
                        let k = (slot[f] as usize - chunk_slot[c]) * r;
                        for ((o, d), t) in out4[k..k + r].iter_mut().zip(&s.d).zip(&rep.t_front) {
                            *o = (t + d).powi(4);
                        }
                    }
                },
            );
        // Image-time temperatures.
        image = (0..ni)
            .map(|i| (0..n).map(|f| img[f * wi + i]).collect::<Vec<f32>>())
            .collect();
        prev4 = store4.then_some(next4);
        if p == 0 {
            base = Some(img);
        }
        let change = prev_image.as_ref().map(|pi: &Vec<Vec<f32>>| {
            pi.iter()
                .zip(&image)
                .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs() as f64))
                .fold(0.0, f64::max)
        });
        stats.push(PassStats {
            solved_facets: n - kinds
                .iter()
                .filter(|k| matches!(k, FacetThermal::Fixed(_)))
                .count(),
            classes: refs.len(),
            reused_facets: 0,
            setup: if p == 0 { setup } else { Duration::ZERO },
            solve: t0.elapsed(),
            max_spinup_change_k: max_spin,
            max_change_from_previous_pass_k: change,
        });
        prev_image = Some(image.clone());
    }
    Ok(SceneTemperatures {
        image_records: image_records.to_vec(),
        surface_temperature_k: image,
        passes: stats,
    })
}
