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
//!
//! # What it owns, takes and gives
//! Owns the method: the groups of equal property sets, the choice of
//! references (`reference` lays each out for the products) and the pass
//! loop (`passes`: the per-facet products; `kernels`: their arithmetic).
//! Takes and gives what [`super::solve_facet_temperatures`] does (which
//! validates the inputs first); knows nothing of how the
//! inputs were traced.

mod kernels;
mod nodes;
mod passes;
mod reference;

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use self::kernels::accumulate_rows;
use self::nodes::CurvatureNodes;
use self::passes::{PassPlan, Slots};
use self::reference::{Diff, FacetState, Reference};
use super::{
    FacetReflected, FacetThermal, PassStats, PropertySets, SceneInputs, SceneTemperatures,
};
use crate::thermal::{
    self, Background, Exchange, FacetInputs, Forcing, SlabProperties, SolveOptions, SourceModel,
};
use crate::{Error, Result};

/// Parameters of the linearised scene solve
/// ([`super::ThermalMethod::Linearized`]; method in the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearizedParams {
    /// Width of the bins of the predicted temperature change (at the first
    /// and last image records and its daily mean) that share one
    /// reference facet, K (default 3 K).
    pub bin_k: f32,
    /// Add the second-order correction for the curvature of the emission
    /// (default false: with 3 K bins the first order is within RMS 0.01 K,
    /// max 0.31 K of the fine reference on the bundled town, and the
    /// correction needs every facet's full history, ≈ 1.5× the work; it
    /// matters with wide bins: one reference per material is within RMS
    /// 0.05 K, max 0.8 K first order, RMS 0.01 K, max 0.31 K second order).
    pub second_order: bool,
    /// Slab options of the reference solves (default
    /// [`SolveOptions::default`]: they are few, so the accurate grid and
    /// spin-up cost little).
    pub options: SolveOptions,
    /// Records between the curvature nodes of the second order away from
    /// the image records (`nodes` module: the curvature is evaluated at
    /// every record within 2 h of an image record and every `stride`-th
    /// record elsewhere, linear in between; the first order stays exact).
    /// Default [`CURVATURE_STRIDE`]; 1 evaluates it at every record (the
    /// reference path).
    pub curvature_stride: usize,
    /// With two passes and curvature nodes: the last pass takes a facet's
    /// first-order change at the nodes from the history pass 1 kept of it
    /// (its `T⁴`, for the backgrounds), adding only its background term,
    /// and its image records from pass 1's, instead of forming both again
    /// from its sources (default true; false forms them again, the
    /// reference path). The two agree to rounding (`f32`; within 1e-4 K).
    pub reuse_first_pass: bool,
}

/// Default [`LinearizedParams::curvature_stride`]: hourly nodes at 15-min
/// records (32 of a 97-record window), a third of the last pass's
/// second-order products; on the yard test scene within 0.004 K of the
/// curvature at every record (`docs/physics/thermal.md`).
pub const CURVATURE_STRIDE: usize = 4;

impl Default for LinearizedParams {
    fn default() -> Self {
        LinearizedParams {
            bin_k: 3.0,
            second_order: false,
            options: SolveOptions::default(),
            curvature_stride: CURVATURE_STRIDE,
            reuse_first_pass: true,
        }
    }
}

/// Dry property sets with DOE-2 convection ([`crate::thermal::convection`])
/// get the same second-order correction: their convection (≈ 3–10 W m⁻²
/// K⁻¹, against McAdams' 5.7 + 3.8u) lets facets stray further from their
/// reference, and on the yard test scene the first order alone was 0.078 K
/// off at worst (a steel fence), the second order 0.003 K.
///
/// The curvature of the latent term's `e°(T)` is far larger than the
/// emission's `T⁴` (at 300 K, `g_v·d²e°/dT² ≈ 2 W m⁻² K⁻²` for a transpiring
/// canopy against `6εσT² ≈ 0.03`), so the facets of a property set that
/// evaporates get the second-order correction with the latent curvature
/// ([`thermal::linear::latent_curvature`]), unless they lie near their
/// reference ([`NEAR_REFERENCE_K`]). This keeps the checked accuracy (RMS <
/// 0.01 K, max < 0.05 K; `tests/scene_thermal.rs` measured RMS 0.002 K,
/// max 0.015 K); the first order alone does not.
///
/// A facet of an evaporating property set whose first-order change at the
/// probes (first and last image records, daily mean) lies within this of
/// its reference's, K, and whose background adds less than
/// [`SMALL_BACKGROUND_W_M2`] to its sources, skips the second order: the
/// neglected curvature grows with the square of the distance, and at
/// 0.25 K it is below 0.01 W m⁻² (`g_v·d²e°/dT²·Δ²/2` with 2 W m⁻² K⁻²).
pub const NEAR_REFERENCE_K: f32 = 0.25;

/// Largest background source `c·σ(T_bg⁴ − T_air⁴)` at any record of a
/// facet that may skip the second order ([`NEAR_REFERENCE_K`]), W m⁻²
/// (about 0.25 K of change at a total surface conductance of 20 W m⁻² K⁻¹).
pub const SMALL_BACKGROUND_W_M2: f32 = 5.0;

/// Facets per work item of the parallel loops.
const CHUNK: usize = 256;

/// Most members of a property set whose daily-mean sources choose its
/// centre facet (their median).
const MEDIAN_SAMPLE: usize = 1024;

/// The linearised solve (module docs). Inputs are validated by the caller.
pub(super) fn solve(
    inputs: &SceneInputs,
    kinds: &[FacetThermal],
    sets: PropertySets,
    forcing: &Forcing,
    image_records: &[usize],
    passes: u32,
    lp: &LinearizedParams,
) -> Result<SceneTemperatures> {
    let PropertySets {
        props,
        exchanges,
        wind_class,
    } = sets;
    let t_start = Instant::now();
    let facets = Facets {
        inputs,
        kinds,
        props,
        exchanges,
        forcing,
        air4: forcing
            .air_temperature_k
            .iter()
            .map(|&t| (t as f32).powi(4))
            .collect(),
    };
    let rows = Rows::new(image_records, forcing.len());
    let nodes = (lp.curvature_stride > 1)
        .then(|| CurvatureNodes::new(forcing.len(), image_records, lp.curvature_stride));
    let lin = Linearize {
        lp,
        rows: &rows.all,
        images: image_records.len(),
        nodes: nodes.as_ref(),
    };
    // 1. Groups of equal property sets and their source models.
    let groups = Groups::new(props, exchanges, wind_class, kinds, forcing);
    // 2. Per group, the centre facet, linearised.
    let centre_refs: Vec<Option<Reference>> = groups
        .centre_facets(&facets)
        .par_iter()
        .map(|&f| {
            (f != usize::MAX)
                .then(|| facets.linearize(f, &lin, groups.model_of(f)))
                .transpose()
        })
        .collect::<Result<_>>()?;
    // 3. Bins of the first-order change from the centre, each with its
    // reference, linearised.
    let bins = Bins::new(&facets, &groups, &centre_refs, &rows, lp.bin_k);
    let refs: Vec<Reference> = bins
        .reference
        .par_iter()
        .map(|&f| facets.linearize(f, &lin, groups.model_of(f)))
        .collect::<Result<_>>()?;
    let max_spin = refs
        .iter()
        .chain(centre_refs.iter().flatten())
        .map(|x| x.spinup_change_k)
        .fold(0.0, f64::max);
    drop(centre_refs);
    let setup = t_start.elapsed();

    // 4. The passes (see `PassPlan`).
    let plan = PassPlan {
        facets: &facets,
        groups: &groups,
        refs: &refs,
        ref_of: &bins.of_facet,
        near: &bins.near,
        slots: Slots::new(inputs, kinds, passes),
        image_records,
        second_order: lp.second_order,
        reuse_first_pass: lp.reuse_first_pass,
    };
    let n = kinds.len();
    let mut stats = Vec::new();
    let mut prev4: Option<Vec<f32>> = None;
    let mut base: Option<Vec<f32>> = None;
    let mut prev_image: Option<Vec<Vec<f32>>> = None;
    let mut image = Vec::new();
    // The histories the last pass's backgrounds used (per-hit sky views).
    let mut last4: Option<Vec<f32>> = None;
    for p in 0..passes {
        let t0 = Instant::now();
        let last = p + 1 == passes;
        // Pass 1's `T⁴` histories are first order with the air as
        // background: the second pass may reuse them (`PassPlan::run`).
        let (img, next4) = plan.run(last, prev4.as_deref(), base.as_deref(), p == 1);
        image = plan.image_temperatures(&img);
        if last {
            last4 = prev4.take();
        } else {
            prev4 = Some(next4);
        }
        if p == 0 {
            base = Some(img);
        }
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
            max_change_from_previous_pass_k: prev_image
                .as_ref()
                .map(|pi| super::max_change(pi, &image)),
        });
        prev_image = Some(image.clone());
    }
    let mut point_response =
        point_response(&groups, &refs, &bins, image_records.len(), facets.len());
    add_point_sky(
        &mut point_response,
        &groups,
        &refs,
        &bins,
        &facets,
        &plan,
        last4,
    );
    Ok(SceneTemperatures {
        image_records: image_records.to_vec(),
        surface_temperature_k: image,
        passes: stats,
        point_response: Some(point_response),
        unsettled_exchanges: Vec::new(),
    })
}

/// Each reference's image rows times its property set's `∂S/∂(s cos θ)`
/// ([`super::PointResponse`]), and each facet's reference.
fn point_response(
    groups: &Groups,
    refs: &[Reference],
    bins: &Bins,
    images: usize,
    n: usize,
) -> super::PointResponse {
    let r = groups.sun32.first().map_or(0, Vec::len);
    let mut sun_rows = Vec::with_capacity(refs.len() * images * r);
    let mut rows = Vec::with_capacity(refs.len() * images * r);
    let mut green = Vec::with_capacity(refs.len() * r * r);
    let mut reference_k = Vec::with_capacity(refs.len() * r);
    let mut suns = Vec::with_capacity(refs.len() * r);
    for (b, rep) in refs.iter().enumerate() {
        let sun = &groups.sun32[groups.of_solved(bins.reference[b])];
        for i in 0..images {
            sun_rows.extend(rep.row_front(i).iter().zip(sun).map(|(g, w)| g * w));
            rows.extend_from_slice(rep.row_front(i));
        }
        green.extend_from_slice(&rep.front.from_front[..r * r]);
        reference_k.extend_from_slice(&rep.front.temperature_k);
        suns.extend_from_slice(sun);
    }
    super::PointResponse {
        records: r,
        images,
        block_of: (0..n).map(|f| bins.of_facet[f]).collect(),
        sun_rows,
        rows,
        green,
        reference_k,
        sun: suns,
        radiative: refs.iter().map(|x| x.front.radiative).collect(),
        latent: Vec::new(),
        shape: Vec::new(),
        back_rows: Vec::new(),
        back_shape: Vec::new(),
        back_radiative: Vec::new(),
        air4: Vec::new(),
        background4: Default::default(),
        slot_of: Default::default(),
    }
}

/// What a point's own sky view needs ([`super::PointResponse`]): each
/// reference's latent conductance and `∂S/∂F`, `T_air⁴`, and the `T⁴`
/// histories the last pass's backgrounds used (`last4`).
fn add_point_sky(
    pr: &mut super::PointResponse,
    groups: &Groups,
    refs: &[Reference],
    bins: &Bins,
    facets: &Facets,
    plan: &PassPlan,
    last4: Option<Vec<f32>>,
) {
    let r = pr.records;
    if refs.iter().any(|x| !x.front.latent.is_empty()) {
        pr.latent = refs
            .iter()
            .flat_map(|x| {
                let l = &x.front.latent;
                (0..r).map(move |t| l.get(t).copied().unwrap_or(0.0))
            })
            .collect();
    }
    pr.shape = (0..refs.len())
        .flat_map(|b| {
            groups.shape32[groups.of_solved(bins.reference[b])]
                .iter()
                .copied()
        })
        .collect();
    if refs.iter().any(|x| x.has_back) {
        let images = pr.images;
        pr.back_rows = refs
            .iter()
            .flat_map(|x| {
                (0..images).flat_map(move |i| {
                    let row: &[f32] = if x.has_back { x.row_back(i) } else { &[] };
                    (0..r).map(move |k| row.get(k).copied().unwrap_or(0.0))
                })
            })
            .collect();
        pr.back_shape = (0..refs.len())
            .flat_map(|b| {
                let g = groups.of_solved(bins.reference[b]);
                let sh = if refs[b].has_back {
                    &groups.back_shape32[g][..]
                } else {
                    &[]
                };
                (0..r).map(move |k| sh.get(k).copied().unwrap_or(0.0))
            })
            .collect();
        pr.back_radiative = refs
            .iter()
            .map(|x| if x.has_back { x.back.radiative } else { 0.0 })
            .collect();
    }
    pr.air4 = facets.air4.clone();
    if let Some(h) = last4 {
        pr.background4 = std::sync::Arc::new(h);
        pr.slot_of = std::sync::Arc::new(plan.slots.of_facet().to_vec());
    }
}

/// Everything fixed over the passes: the facets, their inputs and
/// property sets, and the weather.
struct Facets<'a> {
    inputs: &'a SceneInputs<'a>,
    kinds: &'a [FacetThermal],
    props: &'a [SlabProperties],
    exchanges: &'a [Exchange],
    forcing: &'a Forcing,
    /// `T_air⁴` per record.
    air4: Vec<f32>,
}

impl Facets<'_> {
    /// Number of facets.
    fn len(&self) -> usize {
        self.kinds.len()
    }

    /// `σ(T_bg⁴ − T_air⁴)` history of `facet` from the previous pass's
    /// `T⁴` histories (`prev4[slot[f]·R + k]`) into `out` (W m⁻²); false
    /// when it sees only sky. `T_bg⁴` is the radiative mean of the module
    /// docs of [`super`].
    fn background_excess(
        &self,
        facet: usize,
        prev4: &[f32],
        slot: &[u32],
        out: &mut [f32],
        items: &mut Vec<(u32, f32)>,
    ) -> bool {
        let g = self.inputs.ground_weight[facet];
        let entries = self.inputs.background(facet);
        let den: f32 = g + entries.iter().map(|e| e.weight).sum::<f32>();
        if den <= 0.0 {
            return false;
        }
        out.iter_mut().zip(&self.air4).for_each(|(o, a)| *o = g * a);
        // (slot, weight) of the solved facets seen, (MAX, w·T⁴) of the
        // fixed ones, in entry order. Every solved facet seen has a slot
        // (`passes::Slots`), so only the fixed ones read their kind.
        items.clear();
        items.extend(entries.iter().map(|e| {
            let j = e.facet as usize;
            match slot[j] {
                u32::MAX => match self.kinds[j] {
                    FacetThermal::Fixed(t) => (u32::MAX, e.weight * t.powi(4)),
                    FacetThermal::Solve(_) => unreachable!("a solved facet seen has a slot"),
                },
                s => (s, e.weight),
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

    /// The slab model's inputs of `facet` with its solar history `sun`,
    /// `cos` ([`SceneInputs::sun_fraction`], [`SceneInputs::cos_incidence`]),
    /// with the air as background.
    fn slab_inputs<'b>(
        &'b self,
        facet: usize,
        sun: &'b [f32],
        cos: &'b [f32],
        refl: &'b FacetReflected,
    ) -> FacetInputs<'b> {
        let inputs = self.inputs;
        FacetInputs {
            sun_fraction: sun,
            cos_incidence: cos,
            shape_factor: inputs.shape_factor[facet] as f64,
            back_shape_factor: inputs.slab_back_shape_factor(facet).map(f64::from),
            background: Background::Air,
            reflected: refl.as_reflected(),
        }
    }

    fn props_of(&self, facet: usize) -> &SlabProperties {
        let FacetThermal::Solve(pi) = self.kinds[facet] else {
            unreachable!("solved facets only")
        };
        &self.props[pi as usize]
    }

    /// Linearise about `facet` (air as background).
    fn linearize(&self, facet: usize, how: &Linearize, model: &SourceModel) -> Result<Reference> {
        let FacetThermal::Solve(pi) = self.kinds[facet] else {
            unreachable!("solved facets only")
        };
        let (sun, cos) = (
            self.inputs.sun_fraction(facet),
            self.inputs.cos_incidence(facet),
        );
        let lin = thermal::linearize_with(
            self.props_of(facet),
            self.forcing,
            &self.exchanges[pi as usize],
            &self.slab_inputs(facet, &sun, &cos, &self.inputs.reflected(facet)),
            &how.lp.options,
        )
        .map_err(|e| Error::Other(format!("thermal model of facet {facet}: {e}")))?;
        let mut sc = vec![0.0; self.forcing.len()];
        self.sunlit_cos_into(facet, &mut sc);
        Ok(Reference::new(
            lin,
            how.rows,
            how.images,
            model,
            self.state(facet),
            sc,
            how.nodes,
        ))
    }

    /// The scalar inputs a facet's sources are made of.
    #[inline]
    fn state(&self, facet: usize) -> FacetState {
        let inputs = self.inputs;
        let f = inputs.shape_factor[facet];
        FacetState {
            f,
            f_back: inputs.slab_back_shape_factor(facet).unwrap_or(1.0 - f),
            b: inputs.reflected_diffuse(facet) as f32,
        }
    }

    /// `s·max(cos θ, 0) + a` of `facet` at every record into `out`: its
    /// direct sunlight and the reflected shortwave that weighs like it
    /// (`α E_dn`; [`SourceModel`]), decoded without a copy of either
    /// history.
    #[inline]
    fn sunlit_cos_into(&self, facet: usize, out: &mut [f32]) {
        self.inputs.solar.sunlit_cos_into(facet, out);
        self.inputs.add_reflected_direct(facet, out);
    }
}

/// How references are linearised and laid out: the parameters, the probed
/// records ([`Rows::all`]; the first `images` are the image records) and
/// the curvature nodes of the second order (`None`: every record).
struct Linearize<'a> {
    lp: &'a LinearizedParams,
    rows: &'a [usize],
    images: usize,
    nodes: Option<&'a CurvatureNodes>,
}

/// The records whose front-temperature rows a reference keeps row-major
/// (its probes): the image records, then the first and last image records
/// (the last history record without image records); probe `mean` is the
/// column mean.
struct Rows {
    /// The probed records.
    all: Vec<usize>,
    /// Probe of the first image record.
    first: usize,
    /// Probe of the last image record.
    last: usize,
    /// Probe of the daily mean (after the rows).
    mean: usize,
}

impl Rows {
    fn new(image_records: &[usize], records: usize) -> Rows {
        let first = *image_records.first().unwrap_or(&(records - 1));
        let last = *image_records.last().unwrap_or(&(records - 1));
        let mut all: Vec<usize> = image_records.to_vec();
        all.extend([first, last]);
        let ni = image_records.len();
        Rows {
            mean: all.len(),
            all,
            first: ni,
            last: ni + 1,
        }
    }
}

/// Stage 1: the groups of equal property sets, with one source model each
/// (a facet's pass-1 sources, air as background, are formed on the fly
/// from it, never stored).
struct Groups<'a> {
    kinds: &'a [FacetThermal],
    /// Group of each property set.
    of_props: Vec<u32>,
    /// Source model per group.
    models: Vec<SourceModel>,
    /// `∂S/∂F` per group and record (f32).
    shape32: Vec<Vec<f32>>,
    /// `∂B/∂F_b` per group and record (f32).
    back_shape32: Vec<Vec<f32>>,
    /// `αE_dn` (the weight of `s·cos θ`) per group and record (f32).
    sun32: Vec<Vec<f32>>,
    /// `αE_d` (the weight of the reflected diffuse coefficient `b`) per
    /// group and record (f32).
    refl_diffuse32: Vec<Vec<f32>>,
    /// Daily mean of `αE_d` per group.
    refl_diffuse_mean: Vec<f64>,
    /// Daily mean of the front sources of `F = 0`, no sun, per group.
    base_mean: Vec<f64>,
    /// Daily mean of `∂S/∂F` per group.
    shape_mean: Vec<f64>,
}

impl<'a> Groups<'a> {
    fn new(
        props: &[SlabProperties],
        exchanges: &[Exchange],
        wind_class: &[u32],
        kinds: &'a [FacetThermal],
        forcing: &Forcing,
    ) -> Self {
        let r = forcing.len();
        let mut group_ids: BTreeMap<Vec<u64>, u32> = BTreeMap::new();
        let of_props: Vec<u32> = props
            .iter()
            .zip(wind_class)
            .map(|(p, &w)| {
                let next = group_ids.len() as u32;
                let mut key = prop_key(p);
                key.push(w as u64);
                *group_ids.entry(key).or_insert(next)
            })
            .collect();
        let groups = group_ids.len();
        // Group representatives' property sets → source models.
        let mut group_props: Vec<Option<usize>> = vec![None; groups];
        for (i, &g) in of_props.iter().enumerate() {
            group_props[g as usize].get_or_insert(i);
        }
        let models: Vec<SourceModel> = group_props
            .iter()
            .map(|p| {
                let i = p.expect("every group has a property set");
                SourceModel::new(&props[i], forcing, &exchanges[i])
            })
            .collect();
        let f32s = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
        let shape32 = models
            .iter()
            .map(|m| f32s(m.front_per_shape_factor()))
            .collect();
        let back_shape32 = models
            .iter()
            .map(|m| f32s(m.back_per_shape_factor()))
            .collect();
        let sun32 = models
            .iter()
            .map(|m| f32s(m.front_per_sunlit_cos()))
            .collect();
        let refl_diffuse32 = models
            .iter()
            .map(|m| f32s(m.front_per_reflected_diffuse()))
            .collect();
        let refl_diffuse_mean = models
            .iter()
            .map(|m| m.front_per_reflected_diffuse().iter().sum::<f64>() / r as f64)
            .collect();
        // Daily means of the front sources: mean(base) + F·mean(∂S/∂F) +
        // mean(s cos θ · αE_dn).
        let base_mean = models
            .iter()
            .map(|m| {
                let mut out = vec![0.0f32; r];
                m.front_into(&vec![0.0; r], &vec![0.0; r], 0.0, &mut out);
                out.iter().map(|&v| v as f64).sum::<f64>() / r as f64
            })
            .collect();
        let shape_mean = models
            .iter()
            .map(|m| m.front_per_shape_factor().iter().sum::<f64>() / r as f64)
            .collect();
        Groups {
            kinds,
            of_props,
            models,
            shape32,
            back_shape32,
            sun32,
            refl_diffuse32,
            refl_diffuse_mean,
            base_mean,
            shape_mean,
        }
    }

    /// Number of groups.
    fn len(&self) -> usize {
        self.models.len()
    }

    /// Group of `facet`; `None` for a fixed facet.
    #[inline]
    fn of(&self, facet: usize) -> Option<usize> {
        match self.kinds[facet] {
            FacetThermal::Solve(pi) => Some(self.of_props[pi as usize] as usize),
            FacetThermal::Fixed(_) => None,
        }
    }

    /// Group of a solved facet.
    #[inline]
    fn of_solved(&self, facet: usize) -> usize {
        self.of(facet).expect("references are solved facets")
    }

    /// Source model of a solved facet.
    fn model_of(&self, facet: usize) -> &SourceModel {
        &self.models[self.of_solved(facet)]
    }

    /// Daily mean of the front sources of `facet` (air as background) in
    /// group `g`, W m⁻².
    fn daily_mean_source(&self, facets: &Facets, f: usize, g: usize) -> f64 {
        let r = facets.forcing.len();
        let st = facets.state(f);
        let mut sc = vec![0.0; r];
        facets.sunlit_cos_into(f, &mut sc);
        let sun: f64 = sc
            .iter()
            .zip(&self.sun32[g])
            .map(|(sc, w)| (sc * w) as f64)
            .sum();
        self.base_mean[g]
            + facets.inputs.shape_factor[f] as f64 * self.shape_mean[g]
            + st.b as f64 * self.refl_diffuse_mean[g]
            + sun / r as f64
    }

    /// Stage 2: per group, the facet with the median daily-mean source
    /// (`usize::MAX` for a group without facets). The median is taken over
    /// at most `MEDIAN_SAMPLE` members evenly spaced in facet order: it
    /// only centres the first-order predictions that bin the facets
    /// (stage 3), and reading every facet's history for it cost as much as
    /// the binning itself.
    fn centre_facets(&self, facets: &Facets) -> Vec<usize> {
        let mut per_group: Vec<Vec<usize>> = vec![Vec::new(); self.len()];
        for f in 0..facets.len() {
            if let Some(g) = self.of(f) {
                per_group[g].push(f);
            }
        }
        per_group
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
                    .map(|&f| (self.daily_mean_source(facets, f, g), f))
                    .collect();
                // The median of a total order (mean, then facet).
                let mid = sample.len() / 2;
                sample.select_nth_unstable_by(mid, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                sample[mid].1
            })
            .collect()
    }
}

/// Stage 3: the facets binned per group by their first-order change from
/// the group's centre — at the first and last image records and its daily
/// mean, each in bins of `bin_k` — and each bin's reference: the member
/// closest to the bin's centroid.
struct Bins {
    /// Reference facet of each bin, in bin order.
    reference: Vec<usize>,
    /// Bin of each facet (`u32::MAX` for fixed facets).
    of_facet: Vec<u32>,
    /// Whether a facet's first-order change at the probes lies within
    /// [`NEAR_REFERENCE_K`] of its reference's (false for fixed facets).
    near: Vec<bool>,
}

impl Bins {
    fn new(
        facets: &Facets,
        groups: &Groups,
        centre_refs: &[Option<Reference>],
        rows: &Rows,
        bin_k: f32,
    ) -> Bins {
        let n = facets.len();
        let r = facets.forcing.len();
        let features: Vec<(usize, [f32; 3])> = (0..n)
            .into_par_iter()
            .filter_map(|f| groups.of(f).map(|g| (f, g)))
            .map_init(
                || Scratch::new(r),
                |s, (f, g)| {
                    let rep = centre_refs[g].as_ref().expect("non-empty group");
                    let st = facets.state(f);
                    facets.sunlit_cos_into(f, &mut s.sc);
                    let d = Diff::of(&st, &rep.facet);
                    let p = |j: usize| rep.probe(j, &s.sc, d);
                    (f, [p(rows.first), p(rows.last), p(rows.mean)])
                },
            )
            .collect();
        let w = bin_k;
        // Facets sorted by (group, bin key, facet): the bins in key order. The
        // key packed in a u128 (group, then the three bin indices with their
        // sign bit flipped, so unsigned order is signed order) beside the
        // facet's index in `features` (which is in facet order).
        let flip = |k: f32| ((k / w).round() as i32 as u32 ^ 0x8000_0000) as u128;
        let mut keyed: Vec<(u128, u32)> = features
            .par_iter()
            .enumerate()
            .map(|(i, &(f, x))| {
                let g = groups.of(f).expect("solved") as u128;
                let key = (g << 96) | (flip(x[0]) << 64) | (flip(x[1]) << 32) | flip(x[2]);
                (key, i as u32)
            })
            .collect();
        keyed.par_sort_unstable();
        // The reference of each bin: the member closest to its centroid.
        let mut reference = Vec::new();
        let mut of_facet = vec![u32::MAX; n];
        let mut near = vec![false; n];
        for (b, members) in keyed.chunk_by(|a, b| a.0 == b.0).enumerate() {
            let m = members.len() as f32;
            let c = members.iter().fold([0.0f32; 3], |a, &(_, i)| {
                let x = features[i as usize].1;
                [a[0] + x[0] / m, a[1] + x[1] / m, a[2] + x[2] / m]
            });
            let dist = |x: &[f32; 3]| (0..3).map(|i| (x[i] - c[i]).powi(2)).sum::<f32>();
            let (best, xb) = members
                .iter()
                .map(|&(_, i)| features[i as usize])
                .min_by(|a, b| dist(&a.1).total_cmp(&dist(&b.1)).then(a.0.cmp(&b.0)))
                .expect("non-empty bin");
            reference.push(best);
            for &(_, i) in members {
                let (f, x) = features[i as usize];
                of_facet[f] = b as u32;
                near[f] = (0..3).all(|j| (x[j] - xb[j]).abs() <= NEAR_REFERENCE_K);
            }
        }
        Bins {
            reference,
            of_facet,
            near,
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
            air,
            film_coefficient_w_m2_k,
        } => {
            k.extend([3, film_coefficient_w_m2_k.to_bits()]);
            match air {
                thermal::InteriorAir::Constant(t) => k.extend([0, t.to_bits()]),
                thermal::InteriorAir::Hourly(h) => {
                    k.push(1);
                    k.extend(h.iter().map(|t| t.to_bits()));
                }
                thermal::InteriorAir::SetPoints {
                    heating_k,
                    cooling_k,
                } => k.extend([2, heating_k.to_bits(), cooling_k.to_bits()]),
            }
        }
    }
    // The layers, outer face first.
    for l in p.layers.as_slice() {
        k.extend([
            5,
            l.conductivity_w_m_k.to_bits(),
            l.density_kg_m3.to_bits(),
            l.specific_heat_j_kg_k.to_bits(),
            l.thickness_m.to_bits(),
            l.contact_resistance_m2_k_w.to_bits(),
        ]);
    }
    // The surface's parameters, by their exact (round-trip) decimal form.
    if let Some(s) = &p.surface {
        k.push(4);
        k.extend(format!("{s:?}").bytes().map(u64::from));
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
    /// Curvature at the nodes, front and back.
    curv: Vec<f32>,
    curv_back: Vec<f32>,
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
            curv: vec![0.0; r],
            curv_back: vec![0.0; r],
        }
    }
}
