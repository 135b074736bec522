//! Calibration: fit chosen input parameters, within their bounds, so that a
//! model's predictions match truth measurements in the least-squares sense
//! (minimum RMSE), and give confidence intervals for the fitted values.
//!
//! * Search: Nelder–Mead simplex (crate `argmin`; Nelder & Mead 1965,
//!   Comput. J. 7, 308–313) on unconstrained variables `u`, mapped into
//!   the bounds by `x = low + (high − low)(1 + sin u)/2` (the MINUIT bound
//!   transform, James & Roos 1975), restarted from the best point until the
//!   RMSE stops improving.
//! * Uncertainty: linearised least squares at the optimum — Jacobian `J`
//!   by central finite differences, `cov = s² (JᵀJ)⁻¹` with
//!   `s² = SSR/(n − p)`, and intervals `x̂ ± t_{(1+c)/2, n−p} √cov_ii`
//!   (Seber & Wild, *Nonlinear Regression*, 1989, §5.1). A parameter the
//!   data do not constrain (singular `JᵀJ`) gets infinite intervals.

use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, StudentsT};

use super::sensitivity::{Factor, evaluate_all, finite_difference_jacobian};
use super::stats::{self, Agreement};
use crate::{Error, Result};

/// Options of [`calibrate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationOptions {
    /// Iterations per Nelder–Mead run.
    pub max_iters: u64,
    /// Restarts from the best point (after the first run).
    pub restarts: usize,
    /// Confidence level of the intervals (0–1).
    pub confidence: f64,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        CalibrationOptions {
            max_iters: 400,
            restarts: 3,
            confidence: 0.95,
        }
    }
}

/// A fitted parameter.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FittedParameter {
    /// Name.
    pub name: String,
    /// Starting (nominal) value.
    pub initial: f64,
    /// Fitted value.
    pub fitted: f64,
    /// Standard error (linearised), parameter unit; ∞ if not identifiable.
    pub std_error: f64,
    /// Lower end of the confidence interval.
    pub ci_low: f64,
    /// Upper end of the confidence interval.
    pub ci_high: f64,
    /// Bounds searched.
    pub bounds: [f64; 2],
    /// The fit ended within 0.1 % of the range from a bound (the interval
    /// is then only indicative).
    pub at_bound: bool,
}

/// Result of a calibration.
#[derive(Debug, Clone, Serialize)]
pub struct Calibration {
    /// Fitted parameters, in order.
    pub params: Vec<FittedParameter>,
    /// Number of truth values.
    pub n_obs: usize,
    /// Degrees of freedom n − p.
    pub dof: usize,
    /// Confidence level of the intervals.
    pub confidence: f64,
    /// Agreement at the starting values.
    pub initial: Agreement,
    /// Agreement at the fitted values.
    pub fitted: Agreement,
    /// Parameter covariance (parameter units), row-major p × p.
    pub covariance: Vec<Vec<f64>>,
    /// Predictions at the fitted values.
    pub predicted: Vec<f64>,
    /// Model evaluations made.
    pub evaluations: usize,
    /// Nelder–Mead iterations (all runs).
    pub iterations: u64,
}

/// `x = low + (high − low)(1 + sin u)/2`.
fn to_bounded(u: &[f64], f: &[Factor]) -> Vec<f64> {
    u.iter()
        .zip(f)
        .map(|(&u, f)| f.low + (f.high - f.low) * 0.5 * (1.0 + u.sin()))
        .collect()
}

fn to_unbounded(x: &[f64], f: &[Factor]) -> Vec<f64> {
    x.iter()
        .zip(f)
        .map(|(&x, f)| {
            (2.0 * (x - f.low) / (f.high - f.low) - 1.0)
                .clamp(-1.0, 1.0)
                .asin()
        })
        .collect()
}

struct Problem<'a, M> {
    factors: &'a [Factor],
    truth: &'a [f64],
    model: &'a M,
    evaluations: &'a std::sync::atomic::AtomicUsize,
}

impl<M> CostFunction for Problem<'_, M>
where
    M: Fn(&[f64]) -> Result<Vec<f64>> + Sync,
{
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, u: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
        self.evaluations
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let x = to_bounded(u, self.factors);
        // A model failure (e.g. an unstable corner) counts as a very poor fit.
        let Ok(y) = (self.model)(&x) else {
            return Ok(f64::INFINITY);
        };
        if y.len() != self.truth.len() {
            return Err(argmin::core::Error::msg(format!(
                "the model returned {} values for {} truth values",
                y.len(),
                self.truth.len()
            )));
        }
        let mse = y
            .iter()
            .zip(self.truth)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            / y.len() as f64;
        Ok(if mse.is_finite() { mse } else { f64::INFINITY })
    }
}

/// Invert a symmetric positive-definite matrix (Gauss–Jordan with partial
/// pivoting); `None` when singular to working precision.
fn invert(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    let scale = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    if scale == 0.0 {
        return None;
    }
    let mut m: Vec<Vec<f64>> = a
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let mut row = r.clone();
            row.extend((0..n).map(|j| if i == j { 1.0 } else { 0.0 }));
            row
        })
        .collect();
    for c in 0..n {
        let p = (c..n).max_by(|&i, &j| m[i][c].abs().total_cmp(&m[j][c].abs()))?;
        if m[p][c].abs() <= 1e-12 * scale {
            return None;
        }
        m.swap(c, p);
        let d = m[c][c];
        for v in &mut m[c] {
            *v /= d;
        }
        for r in 0..n {
            if r != c {
                let f = m[r][c];
                if f != 0.0 {
                    let pivot = m[c].clone();
                    for (v, pv) in m[r].iter_mut().zip(&pivot) {
                        *v -= f * pv;
                    }
                }
            }
        }
    }
    Some(m.into_iter().map(|r| r[n..].to_vec()).collect())
}

/// Fit `factors` (starting from their nominal values, within their bounds)
/// so that `model(x)` matches `truth` in the least-squares sense.
pub fn calibrate<M>(
    factors: &[Factor],
    truth: &[f64],
    model: &M,
    opts: CalibrationOptions,
) -> Result<Calibration>
where
    M: Fn(&[f64]) -> Result<Vec<f64>> + Sync,
{
    let p = factors.len();
    let n = truth.len();
    if p == 0 {
        return Err(Error::invalid("parameters", "no parameter to fit"));
    }
    if n <= p {
        return Err(Error::invalid(
            "truth",
            format!(
                "{n} truth values cannot determine {p} parameters (need more values than parameters)"
            ),
        ));
    }
    if truth.iter().any(|v| !v.is_finite()) {
        return Err(Error::invalid("truth", "truth values must be finite"));
    }
    if !(opts.confidence > 0.0 && opts.confidence < 1.0) {
        return Err(Error::invalid(
            "confidence",
            format!("expected 0 < c < 1, got {}", opts.confidence),
        ));
    }
    for f in factors {
        if !(f.low < f.high && f.nominal >= f.low && f.nominal <= f.high) {
            return Err(Error::invalid(
                &f.name,
                "need low < high and the nominal value within them",
            ));
        }
    }
    let x0: Vec<f64> = factors.iter().map(|f| f.nominal).collect();
    let y0 = evaluate_all(model, std::slice::from_ref(&x0), Some(n))?.remove(0);
    let initial = Agreement::of(&y0, truth)?;
    let evaluations = std::sync::atomic::AtomicUsize::new(1);
    let mut best_u = to_unbounded(&x0, factors);
    let mut best_cost = initial.rmse.powi(2);
    let mut iterations = 0u64;
    let mut step = 0.5;
    for _run in 0..=opts.restarts {
        let mut simplex = vec![best_u.clone()];
        for i in 0..p {
            let mut v = best_u.clone();
            // Step away from the turning points of sin (bounds) inwards.
            v[i] += if v[i] > 0.0 { -step } else { step };
            simplex.push(v);
        }
        let tol = (best_cost * 1e-10).max(1e-300);
        let solver = NelderMead::new(simplex)
            .with_sd_tolerance(tol)
            .map_err(|e| Error::Other(format!("Nelder–Mead: {e}")))?;
        let problem = Problem {
            factors,
            truth,
            model,
            evaluations: &evaluations,
        };
        let res = Executor::new(problem, solver)
            .configure(|s| s.max_iters(opts.max_iters))
            .run()
            .map_err(|e| Error::Other(format!("calibration: {e}")))?;
        let state = res.state();
        iterations += state.get_iter();
        let cost = state.get_best_cost();
        let improved = cost < best_cost * (1.0 - 1e-9);
        if let Some(u) = state.get_best_param() {
            if cost <= best_cost {
                best_u = u.clone();
                best_cost = cost;
            }
        }
        if !improved && _run > 0 {
            break;
        }
        step *= 0.5;
    }
    let xf = to_bounded(&best_u, factors);
    let yf = evaluate_all(model, std::slice::from_ref(&xf), Some(n))?.remove(0);
    let fitted = Agreement::of(&yf, truth)?;
    // Linearised covariance at the optimum.
    let jac = finite_difference_jacobian(factors, &xf, 1e-4, model)?; // [obs][param]
    let mut jtj = vec![vec![0.0; p]; p];
    for row in &jac {
        for a in 0..p {
            for b in 0..p {
                jtj[a][b] += row[a] * row[b];
            }
        }
    }
    let dof = n - p;
    let ssr: f64 = yf.iter().zip(truth).map(|(a, b)| (a - b).powi(2)).sum();
    let s2 = ssr / dof as f64;
    let t = StudentsT::new(0.0, 1.0, dof as f64)
        .map_err(|e| Error::Other(format!("Student t: {e}")))?
        .inverse_cdf(0.5 * (1.0 + opts.confidence));
    let covariance = match invert(&jtj) {
        Some(inv) => inv
            .into_iter()
            .map(|r| r.into_iter().map(|v| v * s2).collect())
            .collect(),
        None => vec![vec![f64::INFINITY; p]; p],
    };
    let params = factors
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let se = covariance[i][i].max(0.0).sqrt();
            let tol = 1e-3 * (f.high - f.low);
            FittedParameter {
                name: f.name.clone(),
                initial: f.nominal,
                fitted: xf[i],
                std_error: se,
                ci_low: xf[i] - t * se,
                ci_high: xf[i] + t * se,
                bounds: [f.low, f.high],
                at_bound: xf[i] - f.low < tol || f.high - xf[i] < tol,
            }
        })
        .collect();
    let evaluations = evaluations.load(std::sync::atomic::Ordering::Relaxed) + 1 + 2 * p;
    Ok(Calibration {
        params,
        n_obs: n,
        dof,
        confidence: opts.confidence,
        initial,
        fitted,
        covariance,
        predicted: yf,
        evaluations,
        iterations,
    })
}

/// RMSE and Spearman of `predicted` against `truth` (convenience).
pub fn fit_quality(predicted: &[f64], truth: &[f64]) -> Result<(f64, f64)> {
    Ok((
        stats::rmse(predicted, truth)?,
        stats::spearman(predicted, truth)?,
    ))
}
