//! The per-class scene solve ([`super::ThermalMethod::PerClass`]): one
//! nonlinear slab solve per class of facets with equal quantised inputs.
//!
//! Owns the dedup rule ([`Dedup`]) and the pass loop of this method. Takes
//! and gives what [`super::solve_facet_temperatures`] does (which validates
//! the inputs first); knows nothing of how the inputs were traced.
//!
//! # Stages of a pass
//! 1. **Classes** (`classify`): facets whose inputs coincide are solved
//!    once. The dedup key is the property set, the quantised shape
//!    factor(s), the sun-fraction history, the reflected-shortwave
//!    coefficients (to the shape factor's quantum) and the quantised
//!    cos-incidence history (orientation enters the slab model only through these two),
//!    and from the second pass on the quantised background-temperature
//!    history ([`Dedup`]). Each class is solved with the exact inputs of its
//!    first facet (in facet order). From pass 2 on, facets that see only
//!    sky keep their previous result (their inputs do not change), and in
//!    pass 2 so do facets whose background term barely changes (open
//!    ground seeing almost only sky; [`Dedup::reuse_tolerance_w_m2`]).
//! 2. **Solve** (`solve_classes`): each class representative through
//!    [`crate::thermal::solve`], with the air (pass 1) or the radiative mean
//!    of the previous pass's neighbours (pass `p ≥ 2`) as background
//!    (`PassInputs::background_history`).
//! 3. **Image records** (`PassResult::image_temperatures`): every facet's
//!    temperature at the image records, and the largest change from the
//!    previous pass.
//!
//! Fixed-temperature facets bypass the solver; they still act as
//! neighbours. Classes are solved in parallel (rayon); the result is the
//! same for any thread count.

use std::collections::HashMap;
use std::time::Instant;

use rayon::prelude::*;

use super::{FacetThermal, PassStats, SceneInputs, SceneTemperatures, ThermalParams};
use crate::thermal::{self, Background, Exchange, FacetInputs, Forcing, SlabProperties};
use crate::{Error, Result};

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

/// The per-class solve (module docs). Inputs are validated by the caller.
pub(super) fn solve(
    inputs: &SceneInputs,
    kinds: &[FacetThermal],
    props: &[SlabProperties],
    exchanges: &[Exchange],
    forcing: &Forcing,
    image_records: &[usize],
    params: &ThermalParams,
) -> Result<SceneTemperatures> {
    let air4: Vec<f32> = forcing
        .air_temperature_k
        .iter()
        .map(|&t| (t as f32).powi(4))
        .collect();
    let mut passes: Vec<PassStats> = Vec::new();
    let mut prev: Option<PassResult> = None;
    let mut prev_image: Option<Vec<Vec<f32>>> = None;
    for pass in 0..params.passes {
        let t0 = Instant::now();
        let prev4 = prev.as_ref().map(PassResult::fourth_powers);
        let ctx = PassInputs {
            inputs,
            kinds,
            props,
            exchanges,
            prev_used_air: pass == 1,
            air4: &air4,
            prev: prev.as_ref(),
            prev4: prev4.as_deref(),
            records: forcing.len(),
        };
        let (class_of, reps) = classify(&ctx, params.dedup);
        let t1 = Instant::now();
        let (series, max_spin) = solve_classes(&ctx, &reps, forcing, params)?;
        let t2 = Instant::now();
        let result = PassResult { class_of, series };
        let image = result.image_temperatures(kinds, image_records);
        passes.push(PassStats {
            solved_facets: kinds
                .iter()
                .filter(|k| matches!(k, FacetThermal::Solve(_)))
                .count(),
            classes: reps.iter().filter(|r| matches!(r, Rep::Solve(_))).count(),
            reused_facets: result.reused_facets(&reps),
            setup: t1 - t0,
            solve: t2 - t1,
            max_spinup_change_k: max_spin,
            max_change_from_previous_pass_k: prev_image
                .as_ref()
                .map(|p| super::max_change(p, &image)),
        });
        prev = Some(result);
        prev_image = Some(image);
    }
    Ok(SceneTemperatures {
        image_records: image_records.to_vec(),
        surface_temperature_k: prev_image.expect("at least one pass"),
        passes,
        point_response: None,
        unsettled_exchanges: Vec::new(),
    })
}

/// Stage 2 of a pass: the temperature history of every class — its
/// representative through the slab model, or the previous pass's history
/// ([`Rep::Reuse`]) — and the largest spin-up change over them.
///
/// # Errors
/// The slab solver's, naming the facet.
fn solve_classes(
    ctx: &PassInputs,
    reps: &[Rep],
    forcing: &Forcing,
    params: &ThermalParams,
) -> Result<(Vec<Vec<f32>>, f64)> {
    let solved: Vec<Result<(Vec<f32>, f64)>> = reps
        .par_iter()
        .map(|&rep| {
            let f = match rep {
                Rep::Solve(f) => f,
                Rep::Reuse(c) => {
                    let p = ctx.prev.expect("reuse only from pass 2");
                    return Ok((p.series[c as usize].clone(), 0.0));
                }
            };
            let mut bg = Vec::new();
            let background = if ctx.background_history(f, &mut bg) {
                Background::PerRecord(&bg)
            } else {
                Background::Air
            };
            let FacetThermal::Solve(pi) = ctx.kinds[f] else {
                unreachable!("representatives are solved facets")
            };
            let (sun, cos) = (ctx.inputs.sun_fraction(f), ctx.inputs.cos_incidence(f));
            let refl = ctx.inputs.reflected(f);
            let inputs = FacetInputs {
                sun_fraction: &sun,
                cos_incidence: &cos,
                shape_factor: ctx.inputs.shape_factor[f] as f64,
                back_shape_factor: ctx.inputs.slab_back_shape_factor(f).map(f64::from),
                background,
                reflected: refl.as_reflected(),
            };
            let pi = pi as usize;
            let sol = thermal::solve_with(
                &ctx.props[pi],
                forcing,
                &ctx.exchanges[pi],
                &inputs,
                &params.options,
            )
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
    Ok((series, max_spin))
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

    /// `T⁴` histories per class, for the next pass's backgrounds.
    fn fourth_powers(&self) -> Vec<Vec<f32>> {
        self.series
            .par_iter()
            .map(|s| s.iter().map(|t| t.powi(4)).collect())
            .collect()
    }

    /// Stage 3 of a pass: every facet's temperature at the image records,
    /// `[image][facet]`.
    fn image_temperatures(&self, kinds: &[FacetThermal], image_records: &[usize]) -> Vec<Vec<f32>> {
        image_records
            .iter()
            .map(|&r| {
                (0..kinds.len())
                    .map(|f| self.temperature(kinds, f, r))
                    .collect()
            })
            .collect()
    }

    /// Solved facets whose class kept the previous pass's history.
    fn reused_facets(&self, reps: &[Rep]) -> usize {
        self.class_of
            .iter()
            .filter(|&&c| c != u32::MAX && matches!(reps[c as usize], Rep::Reuse(_)))
            .count()
    }
}

/// What a pass needs to build keys and background histories.
struct PassInputs<'a> {
    inputs: &'a SceneInputs<'a>,
    kinds: &'a [FacetThermal],
    props: &'a [SlabProperties],
    /// The exchange of each property set.
    exchanges: &'a [Exchange],
    /// Whether the previous pass used the air as background (pass 2).
    prev_used_air: bool,
    air4: &'a [f32],
    prev: Option<&'a PassResult>,
    prev4: Option<&'a [Vec<f32>]>,
    records: usize,
}

impl PassInputs<'_> {
    /// Background temperature history of `facet` from the previous pass into
    /// `out`; false (and `out` empty) in pass 1 or when the facet sees only
    /// sky.
    fn background_history(&self, facet: usize, out: &mut Vec<f32>) -> bool {
        out.clear();
        let (Some(prev), Some(prev4)) = (self.prev, self.prev4) else {
            return false;
        };
        let g = self.inputs.ground_weight[facet];
        let entries = self.inputs.background(facet);
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
        let inputs = self.inputs;
        key.push(q(inputs.shape_factor[facet], dedup.shape_factor_quantum));
        key.push(
            inputs
                .slab_back_shape_factor(facet)
                .map_or(u16::MAX, |b| q(b, dedup.shape_factor_quantum)),
        );
        key.extend(
            inputs
                .sun_fraction(facet)
                .iter()
                .map(|&s| q(s, dedup.sun_fraction_quantum)),
        );
        // The reflected shortwave, in units of the sun fraction's quantum
        // (it weighs like `s·cos θ`: [`thermal::SourceModel`]).
        let refl = inputs.reflected(facet);
        if !refl.direct.is_empty() || refl.diffuse > 0.0 {
            key.push(q(refl.diffuse as f32, dedup.shape_factor_quantum));
            key.extend(
                refl.direct
                    .iter()
                    .map(|&a| q(a, dedup.shape_factor_quantum)),
            );
        }
        match dedup.normal_quantum {
            // cos θ = n·s (|n·s| double-sided, 0 at night or behind) is
            // fixed by the normal: rounding its components to `nq` bounds
            // the cos θ difference from the representative by √3·nq/2.
            Some(nq) => {
                let n = inputs.normal[facet];
                let qs = |v: f32| ((v / nq).round() as i32 + 32768).clamp(0, 65534) as u16;
                key.extend([qs(n.x), qs(n.y), qs(n.z)]);
                key.push(inputs.double_sided[facet] as u16);
            }
            None => key.extend(
                inputs
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
        eps * (1.0 - self.inputs.mean_shape_factor(facet))
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

/// How a class gets its temperature history.
#[derive(Debug, Clone, Copy)]
enum Rep {
    /// Solved with the inputs of this facet.
    Solve(usize),
    /// The previous pass's history of this class.
    Reuse(u32),
}

/// Stage 1 of a pass: the class of every facet (`u32::MAX` for fixed ones)
/// and how each class gets its history (its representative — the first
/// facet of the class in facet order — or the previous pass's history), by
/// the dedup key ([`PassInputs::key`]); every solved facet its own class
/// when `dedup` is `None`.
fn classify(ctx: &PassInputs, dedup: Option<Dedup>) -> (Vec<u32>, Vec<Rep>) {
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
