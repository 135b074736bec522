//! The scene-wide thermal solve: every facet's temperature through the
//! history, from its ray-traced inputs ([`Exposure`]) and the 1-D slab model
//! ([`crate::thermal::solve`]).
//!
//! Two methods ([`ThermalMethod`]): the default,
//! [`ThermalMethod::Linearized`], solves a few reference facets per
//! property set with the nonlinear model and every facet by their
//! Green's matrices ([`super::linear`]); [`ThermalMethod::PerClass`], below,
//! solves every class of facets with equal quantised inputs with the
//! nonlinear model.
//!
//! # Per-class method
//! 1. Facets whose inputs coincide are solved once. The dedup key is the
//!    property set, the quantised shape factor(s), the sun-fraction history
//!    and the quantised cos-incidence history (orientation enters the slab
//!    model only through these two), and from the second pass on the
//!    quantised background-temperature history ([`Dedup`]). Each class is
//!    solved with the exact inputs of its first facet (in facet order).
//! 2. Pass 1 takes the air temperature as every facet's background
//!    temperature. Pass `p ≥ 2` takes, for every facet and record, the
//!    radiative mean of what its blocked hemisphere rays hit:
//!    `T_bg⁴ = (Σ wᵢ Tᵢ⁴ + g T_air⁴) / (Σ wᵢ + g)` with the neighbours'
//!    surface temperatures `Tᵢ` from pass `p − 1` and `g` the ground beyond
//!    the scene at air temperature ([`super::SkyView`]).
//! 3. Fixed-temperature facets (and temperatures read from a file) bypass
//!    the solver; they still act as neighbours.
//! 4. From pass 2 on, facets that see only sky keep their previous result
//!    (their inputs do not change), and in pass 2 so do facets whose
//!    background term barely changes (open ground seeing almost only sky;
//!    [`Dedup::reuse_tolerance_w_m2`]).
//!
//! Classes are solved in parallel (rayon); the result is the same for any
//! thread count.

use std::collections::HashMap;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::Exposure;
use crate::thermal::{self, Background, FacetInputs, Forcing, SlabProperties, SolveOptions};
use crate::{Error, Result};

/// How a facet's temperature is obtained.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FacetThermal {
    /// Solved by the slab model with the property set of this index.
    Solve(u32),
    /// Held at this temperature, K, at every record (fixed-temperature
    /// facets, temperatures from a file).
    Fixed(f32),
}

/// Quanta of the dedup key: facets whose quantised inputs agree share one
/// solve (each class is solved with the exact inputs of its first facet).
///
/// The defaults are coarse enough that the facets of a terrain (each with a
/// slightly different orientation) share classes: on the bundled town
/// (240 626 facets, 24 h history) they cut the classes of pass 1 from
/// ~198 000 to a few thousand, with a surface-temperature difference at
/// the image time from [`Dedup::fine`] of RMS ≈ 0.1 K, max ≈ 1 K (README,
/// "Solar history and shape factor").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dedup {
    /// Quantum of the components of the facet's unit normal, which fixes
    /// its cos θ history (default `Some(1/128)`: cos θ within
    /// √3/256 ≈ 0.007 of the representative's, ≲ 6 W/m² of direct flux);
    /// `None` keys on the cos θ history itself, to [`Dedup::cos_quantum`].
    pub normal_quantum: Option<f32>,
    /// Quantum of cos θ at each record when `normal_quantum` is `None`.
    pub cos_quantum: f32,
    /// Quantum of the shape factor (default 1/64).
    pub shape_factor_quantum: f32,
    /// Quantum of the sun fraction (default 1/8: partly shaded records at
    /// penumbra edges only).
    pub sun_fraction_quantum: f32,
    /// Quantum of the background term's excess over pass 1's,
    /// `ε(1−F)σ(T_bg⁴ − T_air⁴)`, W/m² (default 2 W/m²: members within
    /// 1 W/m² of the representative, ≲ 0.1 K with a total surface
    /// conductance ≳ 10 W/(m²·K)).
    pub background_quantum_w_m2: f32,
    /// In pass 2, a facet whose background longwave term
    /// `ε(1−F)σ T_bg⁴` differs from pass 1's (`T_bg = T_air`) by less than
    /// this at every record keeps its pass-1 temperature, W/m² (default
    /// 0.5 W/m²: ≲ 0.05 K with a total surface conductance ≳ 10 W/(m²·K)).
    pub reuse_tolerance_w_m2: f32,
}

impl Default for Dedup {
    fn default() -> Self {
        Dedup {
            normal_quantum: Some(1.0 / 128.0),
            cos_quantum: 1.0 / 64.0,
            shape_factor_quantum: 1.0 / 64.0,
            sun_fraction_quantum: 1.0 / 8.0,
            background_quantum_w_m2: 2.0,
            reuse_tolerance_w_m2: 0.5,
        }
    }
}

impl Dedup {
    /// Fine quanta (cos θ history 1/1024, shape factor 1/512, sun fraction 1/65535,
    /// background term 0.25 W/m², about 0.1 K): merging error ≲ 0.5 W/m² (≈ 0.05 K), but few
    /// merges on real terrain. The reference for the defaults' error.
    pub fn fine() -> Self {
        Dedup {
            normal_quantum: None,
            cos_quantum: 1.0 / 1024.0,
            shape_factor_quantum: 1.0 / 512.0,
            sun_fraction_quantum: 1.0 / 65535.0,
            background_quantum_w_m2: 0.25,
            reuse_tolerance_w_m2: 0.5,
        }
    }
}

/// Parameters of the linearised scene solve
/// ([`ThermalMethod::Linearized`]; method in [`super::linear`]'s docs).
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
}

impl Default for LinearizedParams {
    fn default() -> Self {
        LinearizedParams {
            bin_k: 3.0,
            second_order: false,
            options: SolveOptions::default(),
        }
    }
}

/// How the scene-wide solve gets each facet's temperatures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ThermalMethod {
    /// A few nonlinear reference solves per property set and a
    /// Green's-matrix product per facet (default; fast).
    Linearized(LinearizedParams),
    /// One nonlinear slab solve per dedup class
    /// ([`ThermalParams::dedup`], [`ThermalParams::options`]).
    PerClass,
}

impl Default for ThermalMethod {
    fn default() -> Self {
        ThermalMethod::Linearized(LinearizedParams::default())
    }
}

/// Parameters of the scene-wide solve.
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalParams {
    /// Passes (≥ 1; default 2): pass `p ≥ 2` uses pass `p−1`'s neighbour
    /// temperatures as background.
    pub passes: u32,
    /// Options of the slab solver of [`ThermalMethod::PerClass`] (grid,
    /// sub-steps, spin-up; default [`ThermalParams::scene_options`]).
    pub options: SolveOptions,
    /// Dedup quanta of [`ThermalMethod::PerClass`]; `None` solves every
    /// facet on its own.
    pub dedup: Option<Dedup>,
    /// The method (default [`ThermalMethod::Linearized`]).
    pub method: ThermalMethod,
}

impl Default for ThermalParams {
    fn default() -> Self {
        ThermalParams {
            passes: 2,
            options: ThermalParams::scene_options(),
            dedup: Some(Dedup::default()),
            method: ThermalMethod::default(),
        }
    }
}

impl ThermalParams {
    /// The per-class (dedup) solve with these quanta and slab options.
    pub fn per_class(dedup: Option<Dedup>, options: SolveOptions) -> Self {
        ThermalParams {
            options,
            dedup,
            method: ThermalMethod::PerClass,
            ..ThermalParams::default()
        }
    }

    /// The reference of the accuracy figures: every facet's exact inputs
    /// to fine quanta ([`Dedup::fine`]), [`SolveOptions::default`].
    pub fn fine_reference() -> Self {
        ThermalParams::per_class(Some(Dedup::fine()), SolveOptions::default())
    }
}

impl ThermalParams {
    /// The slab options of per-class scene solves: [`SolveOptions::fast`] (8 cells,
    /// one sub-step per 15-min record) with one spin-up day. On the bundled
    /// town this is about twice as fast as [`SolveOptions::default`] (12
    /// cells, up to 3 spin-up days) and within RMS 0.17 K, max 0.27 K of
    /// it at the image time; [`SolveOptions::fast`] alone (no spin-up) is
    /// twice as fast again but within RMS 0.35 K, max 0.57 K.
    pub fn scene_options() -> SolveOptions {
        SolveOptions {
            spinup: thermal::Spinup {
                max_cycles: 1,
                ..thermal::Spinup::default()
            },
            ..SolveOptions::fast()
        }
    }
}

/// Work and convergence of one pass.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PassStats {
    /// Facets solved (not fixed).
    pub solved_facets: usize,
    /// Distinct classes actually solved.
    pub classes: usize,
    /// Facets that kept the previous pass's temperature (seeing only sky, or
    /// within [`Dedup::reuse_tolerance_w_m2`] in pass 2).
    pub reused_facets: usize,
    /// Time building keys and background histories.
    pub setup: Duration,
    /// Time in the slab solver.
    pub solve: Duration,
    /// Largest spin-up change over the classes (last spin-up cycle), K.
    pub max_spinup_change_k: f64,
    /// Largest |T − T_previous pass| over facets and image records, K
    /// (`None` for pass 1): the convergence of the background iteration.
    pub max_change_from_previous_pass_k: Option<f64>,
}

/// Surface temperatures of every facet at the image records.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneTemperatures {
    /// Record indices of the image times.
    pub image_records: Vec<usize>,
    /// Surface temperature, K, `[image][facet]`.
    pub surface_temperature_k: Vec<Vec<f32>>,
    /// One entry per pass.
    pub passes: Vec<PassStats>,
}

impl SceneTemperatures {
    /// Total time in the solver and its setup over all passes.
    pub fn total_time(&self) -> Duration {
        self.passes.iter().map(|p| p.setup + p.solve).sum()
    }
}

/// Per-pass result: class of every facet and the temperature history of
/// every class.
struct PassResult {
    /// Class of each facet; `u32::MAX` for fixed facets.
    class_of: Vec<u32>,
    /// Surface temperature per class and record, K.
    series: Vec<Vec<f32>>,
}

impl PassResult {
    fn temperature(&self, kinds: &[FacetThermal], facet: usize, record: usize) -> f32 {
        match kinds[facet] {
            FacetThermal::Fixed(t) => t,
            FacetThermal::Solve(_) => self.series[self.class_of[facet] as usize][record],
        }
    }
}

/// Solves every facet's surface temperature over the history of `forcing`
/// (one record per solar-history step of `exposure`) and returns it at the
/// `image_records`.
///
/// `kinds` has one entry per facet; `props` holds the property sets that
/// [`FacetThermal::Solve`] indexes.
///
/// # Errors
/// [`Error::Invalid`] for mismatched lengths, a property index out of range,
/// an image record out of range, zero passes; the slab solver's errors,
/// naming the facet.
pub fn solve_facet_temperatures(
    exposure: &Exposure,
    kinds: &[FacetThermal],
    props: &[SlabProperties],
    forcing: &Forcing,
    image_records: &[usize],
    params: &ThermalParams,
) -> Result<SceneTemperatures> {
    let n = exposure.facets.len();
    let records = forcing.len();
    if kinds.len() != n {
        return Err(Error::invalid(
            "facet thermal kinds",
            format!("expected one per facet ({n}), got {}", kinds.len()),
        ));
    }
    if exposure.solar.steps != records {
        return Err(Error::invalid(
            "forcing",
            format!(
                "the weather history has {records} records but the solar history {} steps; \
                 trace the sun at the record times",
                exposure.solar.steps
            ),
        ));
    }
    if let Some((f, i)) = kinds.iter().enumerate().find_map(|(f, k)| match *k {
        FacetThermal::Solve(i) if i as usize >= props.len() => Some((f, i)),
        _ => None,
    }) {
        return Err(Error::invalid(
            format!("facet {f}"),
            format!(
                "property set {i} does not exist (there are {})",
                props.len()
            ),
        ));
    }
    if let Some(&r) = image_records.iter().find(|&&r| r >= records) {
        return Err(Error::invalid(
            "image_records",
            format!("record {r} is beyond the history ({records} records)"),
        ));
    }
    if params.passes == 0 {
        return Err(Error::invalid("passes", "expected at least 1 pass"));
    }
    if let ThermalMethod::Linearized(lp) = &params.method {
        if !(lp.bin_k.is_finite() && lp.bin_k > 0.0) {
            return Err(Error::invalid(
                "bin_k",
                format!("expected a positive bin width (K), got {}", lp.bin_k),
            ));
        }
        return super::linear::solve(
            exposure,
            kinds,
            props,
            forcing,
            image_records,
            params.passes,
            lp,
        );
    }
    let air4: Vec<f32> = forcing
        .air_temperature_k
        .iter()
        .map(|&t| (t as f32).powi(4))
        .collect();
    let mut passes: Vec<PassStats> = Vec::new();
    let mut prev: Option<PassResult> = None;
    let mut prev_image: Option<Vec<Vec<f32>>> = None;
    for _ in 0..params.passes {
        let t0 = Instant::now();
        // T⁴ histories of the previous pass, per class.
        let prev4: Option<Vec<Vec<f32>>> = prev.as_ref().map(|p| {
            p.series
                .par_iter()
                .map(|s| s.iter().map(|t| t.powi(4)).collect())
                .collect()
        });
        let ctx = Ctx {
            exposure,
            kinds,
            props,
            prev_used_air: passes.len() == 1,
            air4: &air4,
            prev: prev.as_ref(),
            prev4: prev4.as_deref(),
            records,
        };
        let (class_of, reps) = classify(&ctx, params.dedup);
        let t1 = Instant::now();
        let solved: Vec<Result<(Vec<f32>, f64)>> = reps
            .par_iter()
            .map(|&rep| {
                let f = match rep {
                    Rep::Solve(f) => f,
                    Rep::Reuse(c) => {
                        let p = prev.as_ref().expect("reuse only from pass 2");
                        return Ok((p.series[c as usize].clone(), 0.0));
                    }
                };
                let mut bg = Vec::new();
                let background = if ctx.background_history(f, &mut bg) {
                    Background::PerRecord(&bg)
                } else {
                    Background::Air
                };
                let FacetThermal::Solve(pi) = kinds[f] else {
                    unreachable!("representatives are solved facets")
                };
                let inputs = FacetInputs {
                    sun_fraction: exposure.solar.sun_fraction(f),
                    cos_incidence: exposure.solar.cos_incidence(f),
                    shape_factor: exposure.sky.shape_factor[f] as f64,
                    back_shape_factor: exposure.sky.back_shape_factor(f).map(f64::from),
                    background,
                };
                let sol = thermal::solve(&props[pi as usize], forcing, &inputs, &params.options)
                    .map_err(|e| Error::Other(format!("thermal model of facet {f}: {e}")))?;
                Ok((
                    sol.surface_temperature_k
                        .iter()
                        .map(|&t| t as f32)
                        .collect(),
                    sol.spinup_change_k.unwrap_or(0.0),
                ))
            })
            .collect();
        let mut series = Vec::with_capacity(solved.len());
        let mut max_spin: f64 = 0.0;
        for r in solved {
            let (s, c) = r?;
            series.push(s);
            max_spin = max_spin.max(c);
        }
        let t2 = Instant::now();
        let result = PassResult { class_of, series };
        let image: Vec<Vec<f32>> = image_records
            .iter()
            .map(|&r| (0..n).map(|f| result.temperature(kinds, f, r)).collect())
            .collect();
        let change = prev_image.as_ref().map(|p| {
            p.iter()
                .zip(&image)
                .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs() as f64))
                .fold(0.0, f64::max)
        });
        passes.push(PassStats {
            solved_facets: kinds
                .iter()
                .filter(|k| matches!(k, FacetThermal::Solve(_)))
                .count(),
            classes: reps.iter().filter(|r| matches!(r, Rep::Solve(_))).count(),
            reused_facets: (0..n)
                .filter(|&f| {
                    result.class_of[f] != u32::MAX
                        && matches!(reps[result.class_of[f] as usize], Rep::Reuse(_))
                })
                .count(),
            setup: t1 - t0,
            solve: t2 - t1,
            max_spinup_change_k: max_spin,
            max_change_from_previous_pass_k: change,
        });
        prev = Some(result);
        prev_image = Some(image);
    }
    Ok(SceneTemperatures {
        image_records: image_records.to_vec(),
        surface_temperature_k: prev_image.expect("at least one pass"),
        passes,
    })
}

/// What a pass needs to build keys and background histories.
struct Ctx<'a> {
    exposure: &'a Exposure,
    kinds: &'a [FacetThermal],
    props: &'a [SlabProperties],
    /// Whether the previous pass used the air as background (pass 2).
    prev_used_air: bool,
    air4: &'a [f32],
    prev: Option<&'a PassResult>,
    prev4: Option<&'a [Vec<f32>]>,
    records: usize,
}

impl Ctx<'_> {
    /// Background temperature history of `facet` from the previous pass into
    /// `out`; false (and `out` empty) in pass 1 or when the facet sees only
    /// sky.
    fn background_history(&self, facet: usize, out: &mut Vec<f32>) -> bool {
        out.clear();
        let (Some(prev), Some(prev4)) = (self.prev, self.prev4) else {
            return false;
        };
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
                    let s = &prev4[prev.class_of[j] as usize];
                    out.iter_mut()
                        .zip(s)
                        .for_each(|(o, t4)| *o += e.weight * t4);
                }
            }
        }
        let inv = 1.0 / den;
        out.iter_mut().for_each(|o| *o = (*o * inv).powf(0.25));
        debug_assert_eq!(out.len(), self.records);
        true
    }

    /// Dedup key of a solved facet.
    fn key(&self, facet: usize, dedup: &Dedup, scratch: &mut Vec<f32>, key: &mut Vec<u16>) {
        key.clear();
        let FacetThermal::Solve(pi) = self.kinds[facet] else {
            return;
        };
        key.extend([(pi >> 16) as u16, pi as u16]);
        let q = |v: f32, quantum: f32| (v / quantum).round().clamp(0.0, 65534.0) as u16;
        let sky = &self.exposure.sky;
        key.push(q(sky.shape_factor[facet], dedup.shape_factor_quantum));
        key.push(
            sky.back_shape_factor(facet)
                .map_or(u16::MAX, |b| q(b, dedup.shape_factor_quantum)),
        );
        let solar = &self.exposure.solar;
        key.extend(
            solar
                .sun_fraction(facet)
                .iter()
                .map(|&s| q(s, dedup.sun_fraction_quantum)),
        );
        match dedup.normal_quantum {
            // cos θ = n·s (|n·s| double-sided, 0 at night or behind) is
            // fixed by the normal: rounding its components to `nq` bounds
            // the cos θ difference from the representative by √3·nq/2.
            Some(nq) => {
                let n = self.exposure.facets.normal[facet];
                let qs = |v: f32| ((v / nq).round() as i32 + 32768).clamp(0, 65534) as u16;
                key.extend([qs(n.x), qs(n.y), qs(n.z)]);
                key.push(self.exposure.facets.double_sided[facet] as u16);
            }
            None => key.extend(
                solar
                    .cos_incidence(facet)
                    .iter()
                    .map(|&c| q(c, dedup.cos_quantum)),
            ),
        }
        let Some(prev) = self.prev else {
            return;
        };
        // From pass 2 on: a facet that sees only sky has the same inputs as
        // in every pass, and one whose background term barely moves from
        // pass 1's keeps its previous result.
        let has_bg = self.background_history(facet, scratch);
        if !has_bg || (self.prev_used_air && self.barely_changes(facet, dedup, scratch)) {
            // Keep the previous pass's class: a marker key no property index
            // can produce.
            let c = prev.class_of[facet];
            key.clear();
            key.extend([u16::MAX, u16::MAX, (c >> 16) as u16, c as u16]);
            return;
        }
        // The background enters the slab model as ε(1−F)σT_bg⁴: quantise
        // its excess over the air's (pass 1) in W/m².
        let k = self.background_coefficient(facet);
        key.extend(scratch.iter().zip(self.air4).map(|(t, a4)| {
            let v = (k * (t.powi(4) - a4) / dedup.background_quantum_w_m2).round();
            (v as i32 + 32768).clamp(0, 65534) as u16
        }));
    }

    /// `ε(1−F)σ` of a solved facet (0 for fixed ones), W/(m²·K⁴).
    fn background_coefficient(&self, facet: usize) -> f32 {
        let FacetThermal::Solve(pi) = self.kinds[facet] else {
            return 0.0;
        };
        let eps = self.props[pi as usize].thermal_emissivity as f32;
        eps * (1.0 - self.exposure.sky.mean_shape_factor(facet))
            * thermal::STEFAN_BOLTZMANN_W_M2_K4 as f32
    }

    /// Whether the background term `ε(1−F)σT_bg⁴` with `t_bg` stays within
    /// the reuse tolerance of its value with the air as background.
    fn barely_changes(&self, facet: usize, dedup: &Dedup, t_bg: &[f32]) -> bool {
        let k = self.background_coefficient(facet);
        t_bg.iter()
            .zip(self.air4)
            .all(|(t, a4)| k * (t.powi(4) - a4).abs() < dedup.reuse_tolerance_w_m2)
    }
}

/// Class of every facet and the representative (first facet) of every
/// class, in facet order.
/// How a class gets its temperature history.
#[derive(Debug, Clone, Copy)]
enum Rep {
    /// Solved with the inputs of this facet.
    Solve(usize),
    /// The previous pass's history of this class.
    Reuse(u32),
}

fn classify(ctx: &Ctx, dedup: Option<Dedup>) -> (Vec<u32>, Vec<Rep>) {
    let n = ctx.kinds.len();
    let mut class_of = vec![u32::MAX; n];
    let mut reps = Vec::new();
    let Some(dedup) = dedup else {
        for (f, k) in ctx.kinds.iter().enumerate() {
            if let FacetThermal::Solve(_) = k {
                class_of[f] = reps.len() as u32;
                reps.push(Rep::Solve(f));
            }
        }
        return (class_of, reps);
    };
    let mut map: HashMap<Vec<u16>, u32> = HashMap::new();
    const CHUNK: usize = 8192;
    for c0 in (0..n).step_by(CHUNK) {
        let c1 = (c0 + CHUNK).min(n);
        let keys: Vec<Vec<u16>> = (c0..c1)
            .into_par_iter()
            .map_init(
                || Vec::with_capacity(ctx.records),
                |scratch, f| {
                    let mut k = Vec::new();
                    ctx.key(f, &dedup, scratch, &mut k);
                    k
                },
            )
            .collect();
        for (f, k) in (c0..c1).zip(keys) {
            if k.is_empty() {
                continue;
            }
            let reuse = k[..2] == [u16::MAX, u16::MAX];
            let prev_class = if reuse {
                Some((k[2] as u32) << 16 | k[3] as u32)
            } else {
                None
            };
            let next = reps.len() as u32;
            let c = *map.entry(k).or_insert(next);
            if c == next {
                reps.push(match prev_class {
                    Some(pc) => Rep::Reuse(pc),
                    None => Rep::Solve(f),
                });
            }
            class_of[f] = c;
        }
    }
    (class_of, reps)
}
