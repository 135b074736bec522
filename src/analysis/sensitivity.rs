//! Sensitivity analysis, generic over a model `f(x) → y` that maps
//! parameter values to named outputs (temperatures or radiances per
//! material or validation point).
//!
//! * One-at-a-time ([`one_at_a_time`]): each parameter at its low and high
//!   bound, the others nominal. Gives signed output changes (the tornado
//!   plot) and a secant sensitivity `(y_high − y_low)/(high − low)`.
//! * Morris elementary effects ([`morris`]): `r` random one-factor-at-a-time
//!   trajectories on a `p`-level grid of the unit hypercube, step
//!   `Δ = p / (2(p − 1))`; per parameter and output the mean effect μ, the
//!   mean absolute effect μ* (Campolongo, Cariboni & Saltelli 2007,
//!   Environ. Model. Softw. 22, 1509–1518) and the standard deviation σ
//!   (non-linearity / interaction), after Morris (1991), Technometrics 33,
//!   161–174. Effects are reported per full parameter range (output unit)
//!   and per parameter unit. Seeded (ChaCha8), so runs repeat exactly.
//! * Error budget ([`error_budget`]): each parameter's standard uncertainty
//!   times the output's sensitivity to it, combined root-sum-square (first-
//!   order propagation, JCGM 100:2008 "GUM" eq. 10, uncorrelated inputs).
//!
//! Model evaluations run in parallel (rayon); the model must be `Sync`.

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use super::params::ParamSet;
use crate::{Error, Result};

/// One uncertain input of a model, as the engines see it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Factor {
    /// Name.
    pub name: String,
    /// Nominal value.
    pub nominal: f64,
    /// Lower bound.
    pub low: f64,
    /// Upper bound.
    pub high: f64,
    /// One standard uncertainty (parameter unit).
    pub uncertainty: f64,
}

impl ParamSet {
    /// The parameters as engine factors.
    pub fn factors(&self) -> Vec<Factor> {
        self.params
            .iter()
            .map(|p| Factor {
                name: p.name.clone(),
                nominal: p.nominal,
                low: p.low,
                high: p.high,
                uncertainty: p.uncertainty,
            })
            .collect()
    }
}

fn check_factors(factors: &[Factor]) -> Result<()> {
    if factors.is_empty() {
        return Err(Error::invalid("parameters", "no parameter to vary"));
    }
    for f in factors {
        if !(f.low < f.high && f.nominal >= f.low && f.nominal <= f.high) {
            return Err(Error::invalid(
                &f.name,
                format!(
                    "need low < high and nominal within them, got nominal {} in [{}, {}]",
                    f.nominal, f.low, f.high
                ),
            ));
        }
    }
    Ok(())
}

/// Evaluate `model` at every point (in parallel), checking that each
/// returns `n_out` finite outputs (`n_out = None`: take the first's count).
pub(crate) fn evaluate_all<M>(
    model: &M,
    points: &[Vec<f64>],
    n_out: Option<usize>,
) -> Result<Vec<Vec<f64>>>
where
    M: Fn(&[f64]) -> Result<Vec<f64>> + Sync,
{
    let ys: Vec<Vec<f64>> = points.par_iter().map(|x| model(x)).collect::<Result<_>>()?;
    let n = n_out.unwrap_or_else(|| ys.first().map_or(0, |y| y.len()));
    for (x, y) in points.iter().zip(&ys) {
        if y.len() != n {
            return Err(Error::Other(format!(
                "the model returned {} outputs at {x:?}, expected {n}",
                y.len()
            )));
        }
        if y.iter().any(|v| !v.is_finite()) {
            return Err(Error::Other(format!(
                "the model returned a non-finite output at {x:?}: {y:?}"
            )));
        }
    }
    Ok(ys)
}

/// One parameter's one-at-a-time effect on one output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OatEffect {
    /// Output with the parameter at its low bound, minus the nominal output.
    pub at_low: f64,
    /// Output with the parameter at its high bound, minus the nominal output.
    pub at_high: f64,
    /// Secant sensitivity `(y_high − y_low)/(high − low)`, output per parameter unit.
    pub per_unit: f64,
}

impl OatEffect {
    /// The swing `|y_high − y_low|` (ranking key).
    pub fn swing(&self) -> f64 {
        (self.at_high - self.at_low).abs()
    }
}

/// Result of a one-at-a-time study.
#[derive(Debug, Clone, Serialize)]
pub struct Oat {
    /// The factors, in order.
    pub factors: Vec<Factor>,
    /// Output names.
    pub outputs: Vec<String>,
    /// Outputs at the nominal point.
    pub nominal_outputs: Vec<f64>,
    /// `effects[output][factor]`.
    pub effects: Vec<Vec<OatEffect>>,
    /// Model evaluations made.
    pub evaluations: usize,
}

impl Oat {
    /// Factor indices for `output`, largest swing first.
    pub fn ranking(&self, output: usize) -> Vec<usize> {
        let e = &self.effects[output];
        let mut idx: Vec<usize> = (0..e.len()).collect();
        idx.sort_by(|&a, &b| e[b].swing().total_cmp(&e[a].swing()));
        idx
    }
}

/// One-at-a-time study: `2k + 1` evaluations for `k` factors.
pub fn one_at_a_time<M>(factors: &[Factor], outputs: &[String], model: &M) -> Result<Oat>
where
    M: Fn(&[f64]) -> Result<Vec<f64>> + Sync,
{
    check_factors(factors)?;
    let x0: Vec<f64> = factors.iter().map(|f| f.nominal).collect();
    let mut points = vec![x0.clone()];
    for (i, f) in factors.iter().enumerate() {
        for v in [f.low, f.high] {
            let mut x = x0.clone();
            x[i] = v;
            points.push(x);
        }
    }
    let ys = evaluate_all(model, &points, Some(outputs.len()))?;
    let y0 = ys[0].clone();
    let effects = (0..outputs.len())
        .map(|o| {
            factors
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    let (yl, yh) = (ys[1 + 2 * i][o], ys[2 + 2 * i][o]);
                    OatEffect {
                        at_low: yl - y0[o],
                        at_high: yh - y0[o],
                        per_unit: (yh - yl) / (f.high - f.low),
                    }
                })
                .collect()
        })
        .collect();
    Ok(Oat {
        factors: factors.to_vec(),
        outputs: outputs.to_vec(),
        nominal_outputs: y0,
        effects,
        evaluations: points.len(),
    })
}

/// Options of [`morris`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MorrisOptions {
    /// Number of trajectories r (each `k + 1` evaluations).
    pub trajectories: usize,
    /// Grid levels p (even, ≥ 2).
    pub levels: usize,
    /// Random seed.
    pub seed: u64,
}

impl Default for MorrisOptions {
    fn default() -> Self {
        MorrisOptions {
            trajectories: 20,
            levels: 4,
            seed: 1,
        }
    }
}

/// Morris statistics of one factor on one output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MorrisEffect {
    /// Mean elementary effect μ, output change per full parameter range.
    pub mu: f64,
    /// Mean absolute elementary effect μ*, per full range (ranking key).
    pub mu_star: f64,
    /// Standard deviation σ of the elementary effects, per full range.
    pub sigma: f64,
    /// μ* per parameter unit.
    pub mu_star_per_unit: f64,
    /// μ per parameter unit.
    pub mu_per_unit: f64,
}

/// Result of a Morris study.
#[derive(Debug, Clone, Serialize)]
pub struct Morris {
    /// The factors, in order.
    pub factors: Vec<Factor>,
    /// Output names.
    pub outputs: Vec<String>,
    /// `effects[output][factor]`.
    pub effects: Vec<Vec<MorrisEffect>>,
    /// Trajectories r.
    pub trajectories: usize,
    /// Grid levels p.
    pub levels: usize,
    /// Step Δ in unit-hypercube coordinates.
    pub delta: f64,
    /// Seed.
    pub seed: u64,
    /// Model evaluations made.
    pub evaluations: usize,
}

impl Morris {
    /// Factor indices for `output`, largest μ* first.
    pub fn ranking(&self, output: usize) -> Vec<usize> {
        let e = &self.effects[output];
        let mut idx: Vec<usize> = (0..e.len()).collect();
        idx.sort_by(|&a, &b| e[b].mu_star.total_cmp(&e[a].mu_star));
        idx
    }
}

/// One Morris trajectory in unit coordinates: `k + 1` points, each
/// differing from the previous in one factor by ±Δ; `order[j]` is the
/// factor changed between points j and j + 1.
fn trajectory(
    k: usize,
    levels: usize,
    delta: f64,
    rng: &mut ChaCha8Rng,
) -> (Vec<Vec<f64>>, Vec<usize>) {
    let step = 1.0 / (levels - 1) as f64;
    let mut x: Vec<f64> = (0..k)
        .map(|_| rng.random_range(0..levels) as f64 * step)
        .collect();
    let mut order: Vec<usize> = (0..k).collect();
    order.shuffle(rng);
    let mut pts = vec![x.clone()];
    for &i in &order {
        let up_ok = x[i] + delta <= 1.0 + 1e-12;
        let down_ok = x[i] - delta >= -1e-12;
        let up = match (up_ok, down_ok) {
            (true, true) => rng.random_bool(0.5),
            (u, _) => u,
        };
        x[i] = if up { x[i] + delta } else { x[i] - delta };
        x[i] = x[i].clamp(0.0, 1.0);
        pts.push(x.clone());
    }
    (pts, order)
}

/// Morris elementary-effects screening: `r (k + 1)` evaluations.
pub fn morris<M>(
    factors: &[Factor],
    outputs: &[String],
    model: &M,
    opts: MorrisOptions,
) -> Result<Morris>
where
    M: Fn(&[f64]) -> Result<Vec<f64>> + Sync,
{
    check_factors(factors)?;
    if opts.levels < 2 || !opts.levels.is_multiple_of(2) {
        return Err(Error::invalid(
            "levels",
            format!("expected an even number ≥ 2, got {}", opts.levels),
        ));
    }
    if opts.trajectories < 2 {
        return Err(Error::invalid(
            "trajectories",
            format!("expected at least 2, got {}", opts.trajectories),
        ));
    }
    let k = factors.len();
    let delta = opts.levels as f64 / (2.0 * (opts.levels - 1) as f64);
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let trajs: Vec<(Vec<Vec<f64>>, Vec<usize>)> = (0..opts.trajectories)
        .map(|_| trajectory(k, opts.levels, delta, &mut rng))
        .collect();
    let to_phys = |u: &[f64]| -> Vec<f64> {
        u.iter()
            .zip(factors)
            .map(|(&u, f)| f.low + u * (f.high - f.low))
            .collect()
    };
    let points: Vec<Vec<f64>> = trajs
        .iter()
        .flat_map(|(p, _)| p.iter().map(|u| to_phys(u)))
        .collect();
    let ys = evaluate_all(model, &points, Some(outputs.len()))?;
    // ee[output][factor] = elementary effects per full range.
    let mut ee = vec![vec![Vec::with_capacity(opts.trajectories); k]; outputs.len()];
    for (t, (pts, order)) in trajs.iter().enumerate() {
        let base = t * (k + 1);
        for (j, &i) in order.iter().enumerate() {
            let du = pts[j + 1][i] - pts[j][i];
            for (o, e) in ee.iter_mut().enumerate() {
                e[i].push((ys[base + j + 1][o] - ys[base + j][o]) / du);
            }
        }
    }
    let effects = ee
        .iter()
        .map(|per_factor| {
            per_factor
                .iter()
                .zip(factors)
                .map(|(e, f)| {
                    let n = e.len() as f64;
                    let mu = e.iter().sum::<f64>() / n;
                    let mu_star = e.iter().map(|v| v.abs()).sum::<f64>() / n;
                    let sigma =
                        (e.iter().map(|v| (v - mu).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
                    let range = f.high - f.low;
                    MorrisEffect {
                        mu,
                        mu_star,
                        sigma,
                        mu_star_per_unit: mu_star / range,
                        mu_per_unit: mu / range,
                    }
                })
                .collect()
        })
        .collect();
    Ok(Morris {
        factors: factors.to_vec(),
        outputs: outputs.to_vec(),
        effects,
        trajectories: opts.trajectories,
        levels: opts.levels,
        delta,
        seed: opts.seed,
        evaluations: points.len(),
    })
}

/// One parameter's share of an output's uncertainty.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BudgetLine {
    /// Parameter name.
    pub name: String,
    /// Its standard uncertainty (parameter unit).
    pub uncertainty: f64,
    /// Output sensitivity to it (output per parameter unit, magnitude).
    pub sensitivity: f64,
    /// `uncertainty × sensitivity`, output unit.
    pub contribution: f64,
    /// Share of the combined variance, 0–1.
    pub variance_fraction: f64,
}

/// An output's estimated-error budget.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorBudget {
    /// Output name.
    pub output: String,
    /// Lines, largest contribution first.
    pub lines: Vec<BudgetLine>,
    /// Root-sum-square of the contributions, output unit.
    pub combined: f64,
}

/// Error budget of each output from per-unit sensitivities
/// `sensitivity[output][factor]` (e.g. [`OatEffect::per_unit`] or
/// [`MorrisEffect::mu_star_per_unit`]) and the factors' uncertainties.
pub fn error_budget(
    factors: &[Factor],
    outputs: &[String],
    sensitivity: &[Vec<f64>],
) -> Vec<ErrorBudget> {
    outputs
        .iter()
        .zip(sensitivity)
        .map(|(name, s)| {
            let mut lines: Vec<BudgetLine> = factors
                .iter()
                .zip(s)
                .map(|(f, &d)| BudgetLine {
                    name: f.name.clone(),
                    uncertainty: f.uncertainty,
                    sensitivity: d.abs(),
                    contribution: f.uncertainty * d.abs(),
                    variance_fraction: 0.0,
                })
                .collect();
            let var: f64 = lines.iter().map(|l| l.contribution.powi(2)).sum();
            for l in &mut lines {
                l.variance_fraction = if var > 0.0 {
                    l.contribution.powi(2) / var
                } else {
                    0.0
                };
            }
            lines.sort_by(|a, b| b.contribution.total_cmp(&a.contribution));
            ErrorBudget {
                output: name.clone(),
                lines,
                combined: var.sqrt(),
            }
        })
        .collect()
}

/// Central finite-difference derivatives `∂y_o/∂x_i` at `x` (steps
/// `rel_step × (high − low)`, one-sided at a bound): `[output][factor]`.
pub fn finite_difference_jacobian<M>(
    factors: &[Factor],
    x: &[f64],
    rel_step: f64,
    model: &M,
) -> Result<Vec<Vec<f64>>>
where
    M: Fn(&[f64]) -> Result<Vec<f64>> + Sync,
{
    let steps: Vec<f64> = factors
        .iter()
        .map(|f| rel_step * (f.high - f.low))
        .collect();
    jacobian_with_steps(factors, x, &steps, model)
}

/// Central finite-difference derivatives `∂y_o/∂x_i` at `x` with step
/// `steps[i]` for factor `i` (one-sided where a step would leave the
/// bounds): `[output][factor]`. The `2p` evaluations run in parallel.
pub fn jacobian_with_steps<M>(
    factors: &[Factor],
    x: &[f64],
    steps: &[f64],
    model: &M,
) -> Result<Vec<Vec<f64>>>
where
    M: Fn(&[f64]) -> Result<Vec<f64>> + Sync,
{
    let mut points = Vec::with_capacity(2 * factors.len());
    let mut widths = Vec::with_capacity(factors.len());
    for (i, (f, &h)) in factors.iter().zip(steps).enumerate() {
        let lo = (x[i] - h).max(f.low);
        let hi = (x[i] + h).min(f.high);
        let mut a = x.to_vec();
        a[i] = lo;
        let mut b = x.to_vec();
        b[i] = hi;
        points.push(a);
        points.push(b);
        widths.push(hi - lo);
    }
    let ys = evaluate_all(model, &points, None)?;
    let n_out = ys.first().map_or(0, |y| y.len());
    Ok((0..n_out)
        .map(|o| {
            (0..factors.len())
                .map(|i| (ys[2 * i + 1][o] - ys[2 * i][o]) / widths[i])
                .collect()
        })
        .collect())
}
