//! The linearised scene-wide thermal solve ([`super::ThermalMethod::Linearized`],
//! the default): a few nonlinear reference solves per material and a
//! Green's-matrix product per facet.
//!
//! # Method
//! Every facet-specific input of the slab model enters only as an additive
//! surface source history (front `S_k`, exposed back `B_k`;
//! [`crate::thermal::linear`]). So:
//! 1. Facets are grouped by property set (equal [`SlabProperties`]).
//! 2. Per group, the facet with the median daily-mean source is solved with
//!    the nonlinear model and linearised ([`thermal::linearize`]: its
//!    Green's matrices `G[t][k] = ∂T(t)/∂S_k`). Every facet's first-order
//!    temperature change from it predicts where the facet lies.
//! 3. Facets are binned per group by that prediction — the change at the
//!    first and last image records and its daily mean, each in bins of
//!    [`LinearizedParams::bin_k`] — and each bin gets its own reference: the
//!    facet closest to the bin's centroid, linearised. The neglected
//!    curvature of the emission grows with the square of the distance from
//!    the reference, so narrow bins bound it.
//! 4. Each pass, each facet: `T = T_ref + G·ΔS (+ G·r(Δ))`, the second term
//!    the second-order correction for the emission's curvature
//!    ([`LinearizedParams::second_order`]). Pass 1 takes the air as
//!    background; pass `p ≥ 2` builds every facet's background from the
//!    previous pass's full temperature histories, exactly as
//!    [`super::solve_facet_temperatures`]'s dedup path does — only the
//!    sources change, so the references and their matrices are reused.
//!
//! Work is per facet and per reference, in facet order; the result does
//! not depend on the thread count.

use std::collections::BTreeMap;
use std::time::Instant;

use rayon::prelude::*;

use super::Exposure;
use super::solve::{FacetThermal, LinearizedParams, PassStats, SceneTemperatures};
use crate::thermal::{self, Background, FacetInputs, Forcing, Linearization, SlabProperties};
use crate::{Error, Result};

/// A reference facet's linearisation in the layout the per-facet products
/// use: `f32`, column-major (`g[k·R + t] = ∂T(t)/∂S_k`).
struct Reference {
    records: usize,
    has_back: bool,
    gt_ff: Vec<f32>,
    gt_fb: Vec<f32>,
    gt_bf: Vec<f32>,
    gt_bb: Vec<f32>,
    s_front: Vec<f64>,
    s_back: Vec<f64>,
    t_front: Vec<f32>,
    t_back: Vec<f32>,
    r_front: f32,
    r_back: f32,
    spinup_change_k: f64,
}

impl Reference {
    fn new(lin: Linearization) -> Reference {
        let r = lin.records;
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
        Reference {
            records: r,
            has_back: lin.has_back(),
            gt_ff: transpose(&lin.front_from_front),
            gt_fb: transpose(&lin.front_from_back),
            gt_bf: transpose(&lin.back_from_front),
            gt_bb: transpose(&lin.back_from_back),
            s_front: lin.sources.front_w_m2.clone(),
            s_back: lin.sources.back_w_m2.clone().unwrap_or_default(),
            t_front: lin
                .solution
                .surface_temperature_k
                .iter()
                .map(|&t| t as f32)
                .collect(),
            t_back: lin
                .solution
                .back_temperature_k
                .iter()
                .map(|&t| t as f32)
                .collect(),
            r_front: lin.front_radiative_w_m2_k4 as f32,
            r_back: lin.back_radiative_w_m2_k4 as f32,
            spinup_change_k: lin.solution.spinup_change_k.unwrap_or(0.0),
        }
    }
}

/// `y = Gᵀ-stored matrix × x` (column-major `g[k·R + t]`), accumulated into
/// `y` when `add`.
#[inline]
fn matvec(g: &[f32], x: &[f32], y: &mut [f32], add: bool) {
    let r = y.len();
    if !add {
        y.iter_mut().for_each(|v| *v = 0.0);
    }
    for (k, &xk) in x.iter().enumerate() {
        if xk == 0.0 {
            continue;
        }
        let col = &g[k * r..(k + 1) * r];
        for (yi, gi) in y.iter_mut().zip(col) {
            *yi += xk * gi;
        }
    }
}

/// Row `t` of a column-major matrix times `x`.
#[inline]
fn row_dot(g: &[f32], t: usize, x: &[f32]) -> f32 {
    let r = x.len();
    x.iter().enumerate().map(|(k, &xk)| xk * g[k * r + t]).sum()
}

/// `−R Δ²(6T² + 4TΔ + Δ²)`, the emission curvature (f32).
#[inline]
fn curvature(r: f32, t: f32, d: f32) -> f32 {
    -r * d * d * (6.0 * t * t + 4.0 * t * d + d * d)
}

/// Scratch buffers of one facet evaluation.
#[derive(Default)]
struct Scratch {
    front: Vec<f64>,
    back: Vec<f64>,
    ds: Vec<f32>,
    db: Vec<f32>,
    d: Vec<f32>,
    dback: Vec<f32>,
    rf: Vec<f32>,
    rb: Vec<f32>,
    bg: Vec<f32>,
}

impl Scratch {
    fn new(r: usize) -> Scratch {
        Scratch {
            front: vec![0.0; r],
            back: vec![0.0; r],
            ds: vec![0.0; r],
            db: vec![0.0; r],
            d: vec![0.0; r],
            dback: vec![0.0; r],
            rf: vec![0.0; r],
            rb: vec![0.0; r],
            bg: Vec::with_capacity(r),
        }
    }
}

/// What to compute for a facet.
#[derive(Clone, Copy)]
enum Want<'a> {
    /// The first-order change at every record (into `Scratch::d`).
    FirstOrder,
    /// The temperature at every record.
    History,
    /// The temperature at these records only.
    Records(&'a [usize]),
}

/// Temperature change (or temperature) of a facet with sources in
/// `s.front`/`s.back` from `rep`, per `want`; the result is in `s.d`
/// (change for `FirstOrder`, temperature otherwise, at every record or
/// at the wanted records' positions).
fn evaluate(rep: &Reference, second_order: bool, want: Want, s: &mut Scratch) {
    let r = rep.records;
    for k in 0..r {
        s.ds[k] = (s.front[k] - rep.s_front[k]) as f32;
    }
    if rep.has_back {
        for k in 0..r {
            s.db[k] = (s.back[k] - rep.s_back[k]) as f32;
        }
    }
    matvec(&rep.gt_ff, &s.ds, &mut s.d, false);
    if rep.has_back {
        matvec(&rep.gt_fb, &s.db, &mut s.d, true);
    }
    if matches!(want, Want::FirstOrder) {
        return;
    }
    if second_order {
        for k in 0..r {
            s.rf[k] = curvature(rep.r_front, rep.t_front[k], s.d[k]);
        }
        if rep.has_back {
            matvec(&rep.gt_bf, &s.ds, &mut s.dback, false);
            matvec(&rep.gt_bb, &s.db, &mut s.dback, true);
            for k in 0..r {
                s.rb[k] = curvature(rep.r_back, rep.t_back[k], s.dback[k]);
            }
        }
        match want {
            Want::Records(records) => {
                for (i, &t) in records.iter().enumerate() {
                    let mut c = row_dot(&rep.gt_ff, t, &s.rf);
                    if rep.has_back {
                        c += row_dot(&rep.gt_fb, t, &s.rb);
                    }
                    s.dback[i] = s.d[t] + c;
                }
                for (i, &t) in records.iter().enumerate() {
                    s.d[i] = s.dback[i] + rep.t_front[t];
                }
                return;
            }
            _ => {
                matvec(&rep.gt_ff, &s.rf, &mut s.d, true);
                if rep.has_back {
                    matvec(&rep.gt_fb, &s.rb, &mut s.d, true);
                }
            }
        }
    }
    match want {
        Want::Records(records) => {
            for (i, &t) in records.iter().enumerate() {
                s.dback[i] = s.d[t] + rep.t_front[t];
            }
            s.d[..records.len()].copy_from_slice(&s.dback[..records.len()]);
        }
        _ => s
            .d
            .iter_mut()
            .zip(&rep.t_front)
            .for_each(|(d, t)| *d += t),
    }
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
    /// Background history of `facet` from the previous pass's `T⁴`
    /// histories (`prev4[f·R + k]`) into `out`; false when it sees only
    /// sky (or in pass 1). Same rule as the dedup path.
    fn background(&self, facet: usize, prev4: Option<&[f32]>, out: &mut Vec<f32>) -> bool {
        out.clear();
        let Some(prev4) = prev4 else {
            return false;
        };
        let r = self.air4.len();
        let sky = &self.exposure.sky;
        let g = sky.ground_weight[facet];
        let entries = sky.background(facet);
        let den: f32 = g + entries.iter().map(|e| e.weight).sum::<f32>();
        if den <= 0.0 {
            return false;
        }
        out.extend(self.air4.iter().map(|a| g * a));
        for e in entries {
            let j = e.facet as usize;
            match self.kinds[j] {
                FacetThermal::Fixed(t) => {
                    let t4 = e.weight * t.powi(4);
                    out.iter_mut().for_each(|o| *o += t4);
                }
                FacetThermal::Solve(_) => {
                    let s = &prev4[j * r..(j + 1) * r];
                    out.iter_mut()
                        .zip(s)
                        .for_each(|(o, t4)| *o += e.weight * t4);
                }
            }
        }
        let inv = 1.0 / den;
        out.iter_mut().for_each(|o| *o = (*o * inv).sqrt().sqrt());
        true
    }

    /// The source histories of a solved facet into `s.front`/`s.back`.
    fn sources(&self, facet: usize, prev4: Option<&[f32]>, s: &mut Scratch) -> Result<()> {
        let FacetThermal::Solve(pi) = self.kinds[facet] else {
            unreachable!("sources of solved facets only")
        };
        let mut bg = std::mem::take(&mut s.bg);
        let background = if self.background(facet, prev4, &mut bg) {
            Background::PerRecord(&bg)
        } else {
            Background::Air
        };
        let inputs = self.inputs(facet, background);
        let r = thermal::source_history_into(
            &self.props[pi as usize],
            self.forcing,
            &inputs,
            &mut s.front,
            &mut s.back,
        )
        .map_err(|e| Error::Other(format!("thermal model of facet {facet}: {e}")));
        s.bg = bg;
        r
    }

    fn inputs<'b>(&'b self, facet: usize, background: Background<'b>) -> FacetInputs<'b> {
        let exposure = self.exposure;
        FacetInputs {
            sun_fraction: exposure.solar.sun_fraction(facet),
            cos_incidence: exposure.solar.cos_incidence(facet),
            shape_factor: exposure.sky.shape_factor[facet] as f64,
            back_shape_factor: exposure.sky.back_shape_factor(facet).map(f64::from),
            background,
        }
    }

    /// Linearise about `facet` with pass-1 inputs.
    fn linearize(&self, facet: usize, lp: &LinearizedParams) -> Result<Reference> {
        let FacetThermal::Solve(pi) = self.kinds[facet] else {
            unreachable!("references are solved facets")
        };
        let lin = thermal::linearize(
            &self.props[pi as usize],
            self.forcing,
            &self.inputs(facet, Background::Air),
            &lp.options,
        )
        .map_err(|e| Error::Other(format!("thermal model of facet {facet}: {e}")))?;
        Ok(Reference::new(lin))
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
    let solved: Vec<usize> = (0..n).filter(|&f| group_of(f).is_some()).collect();

    // 2. Per group, the facet with the median daily-mean front source.
    let means: Vec<Result<f64>> = solved
        .par_iter()
        .map_init(
            || Scratch::new(r),
            |s, &f| {
                ctx.sources(f, None, s)?;
                Ok(s.front.iter().sum::<f64>() / r as f64)
            },
        )
        .collect();
    let mut per_group: Vec<Vec<(f64, usize)>> = vec![Vec::new(); groups];
    for (&f, m) in solved.iter().zip(means) {
        per_group[group_of(f).expect("solved")].push((m?, f));
    }
    let centre: Vec<usize> = per_group
        .iter_mut()
        .map(|v| {
            if v.is_empty() {
                return usize::MAX;
            }
            v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            v[v.len() / 2].1
        })
        .collect();
    drop(per_group);
    let centre_refs: Vec<Option<Reference>> = centre
        .par_iter()
        .map(|&f| (f != usize::MAX).then(|| ctx.linearize(f, lp)).transpose())
        .collect::<Result<_>>()?;

    // 3. Bins by the first-order prediction from the group's centre.
    let first = *image_records.first().unwrap_or(&(r - 1));
    let last = *image_records.last().unwrap_or(&(r - 1));
    let features: Vec<Result<[f32; 3]>> = solved
        .par_iter()
        .map_init(
            || Scratch::new(r),
            |s, &f| {
                ctx.sources(f, None, s)?;
                let rep = centre_refs[group_of(f).expect("solved")]
                    .as_ref()
                    .expect("non-empty group");
                evaluate(rep, false, Want::FirstOrder, s);
                let mean = s.d.iter().sum::<f32>() / r as f32;
                Ok([s.d[first], s.d[last], mean])
            },
        )
        .collect();
    let w = lp.bin_k.max(1e-3);
    let mut bins: BTreeMap<(usize, [i32; 3]), Vec<(usize, [f32; 3])>> = BTreeMap::new();
    for (&f, x) in solved.iter().zip(features) {
        let x = x?;
        let key = x.map(|v| (v / w).round() as i32);
        bins.entry((group_of(f).expect("solved"), key))
            .or_default()
            .push((f, x));
    }
    // The reference of each bin: the member closest to its centroid.
    let mut bin_rep = Vec::with_capacity(bins.len());
    let mut ref_of = vec![u32::MAX; n];
    for (b, members) in bins.values().enumerate() {
        let m = members.len() as f32;
        let c = members.iter().fold([0.0f32; 3], |a, (_, x)| {
            [a[0] + x[0] / m, a[1] + x[1] / m, a[2] + x[2] / m]
        });
        let dist = |x: &[f32; 3]| (0..3).map(|i| (x[i] - c[i]).powi(2)).sum::<f32>();
        let best = members
            .iter()
            .min_by(|a, b| dist(&a.1).total_cmp(&dist(&b.1)).then(a.0.cmp(&b.0)))
            .expect("non-empty bin")
            .0;
        bin_rep.push(best);
        for (f, _) in members {
            ref_of[*f] = b as u32;
        }
    }
    drop(bins);
    let refs: Vec<Reference> = bin_rep
        .par_iter()
        .map(|&f| ctx.linearize(f, lp))
        .collect::<Result<_>>()?;
    let max_spin = refs
        .iter()
        .chain(centre_refs.iter().flatten())
        .map(|x| x.spinup_change_k)
        .fold(0.0, f64::max);
    let setup = t_start.elapsed();

    // 4. The passes.
    let mut stats = Vec::new();
    let mut prev4: Option<Vec<f32>> = None;
    let mut prev_image: Option<Vec<Vec<f32>>> = None;
    let mut image = Vec::new();
    for p in 0..passes {
        let t0 = Instant::now();
        let last_pass = p + 1 == passes;
        let want = if last_pass {
            Want::Records(image_records)
        } else {
            Want::History
        };
        let width = if last_pass { image_records.len() } else { r };
        let mut out = vec![0.0f32; n * width];
        let prev = prev4.as_deref();
        out.par_chunks_mut(width.max(1) * 256)
            .enumerate()
            .try_for_each_init(
                || Scratch::new(r),
                |s, (c, chunk)| -> Result<()> {
                    for (i, o) in chunk.chunks_mut(width.max(1)).enumerate() {
                        let f = c * 256 + i;
                        match kinds[f] {
                            FacetThermal::Fixed(t) => o.iter_mut().for_each(|v| *v = t),
                            FacetThermal::Solve(_) => {
                                ctx.sources(f, prev, s)?;
                                let rep = &refs[ref_of[f] as usize];
                                evaluate(rep, lp.second_order, want, s);
                                o.copy_from_slice(&s.d[..width]);
                            }
                        }
                    }
                    Ok(())
                },
            )?;
        // Image-time temperatures and, for a later pass, the T⁴ histories.
        image = image_records
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                (0..n)
                    .map(|f| {
                        if last_pass {
                            out[f * width + i]
                        } else {
                            out[f * width + t]
                        }
                    })
                    .collect::<Vec<f32>>()
            })
            .collect();
        if !last_pass {
            out.par_iter_mut().for_each(|t| *t = t.powi(4));
            prev4 = Some(out);
        }
        let change = prev_image.as_ref().map(|pi: &Vec<Vec<f32>>| {
            pi.iter()
                .zip(&image)
                .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs() as f64))
                .fold(0.0, f64::max)
        });
        stats.push(PassStats {
            solved_facets: solved.len(),
            classes: refs.len(),
            reused_facets: 0,
            setup: if p == 0 {
                setup
            } else {
                std::time::Duration::ZERO
            },
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
