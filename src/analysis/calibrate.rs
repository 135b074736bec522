//! Calibration: fit chosen input parameters, within their bounds, so that a
//! model's predictions match truth measurements in the least-squares sense
//! (minimum RMSE), and give confidence intervals for the fitted values.
//!
//! * Search, [`Method::LevenbergMarquardt`] (the default): Levenberg (1944)
//!   and Marquardt (1963, J. SIAM 11, 431–441) damped Gauss–Newton steps
//!   `(JᵀJ + λ diag JᵀJ) δ = −Jᵀr` on the parameters scaled to their bounds
//!   (`s = (x − low)/(high − low)`), the Jacobian `J` by finite differences
//!   (evaluated in parallel), λ updated from the ratio of actual to
//!   predicted reduction after a step that lowers the sum of squares and
//!   multiplied by 2, 4, 8, … after one that does not (Nielsen 1999;
//!   Madsen, Nielsen & Tingleff 2004, *Methods for Non-Linear Least Squares
//!   Problems*, §3.2). Bounds by
//!   projection: a step is clipped into the box, and a parameter at a bound
//!   whose gradient points out of the box is held there (an active set,
//!   Kanzow, Yamashita & Fukushima 2004, J. Comput. Appl. Math. 172,
//!   375–397, in its simplest form). It needs far fewer model evaluations
//!   than a simplex on smooth least-squares problems (the thermal model is
//!   smooth in its parameters: [`super::facet::OneFacet`]).
//! * Search, [`Method::NelderMead`]: the Nelder–Mead simplex (crate
//!   `argmin`; Nelder & Mead 1965, Comput. J. 7, 308–313) on unconstrained
//!   variables `u`, mapped into the bounds by
//!   `x = low + (high − low)(1 + sin u)/2` (the MINUIT bound transform,
//!   James & Roos 1975), restarted from the best point until the RMSE stops
//!   improving. Derivative-free: for models that are not smooth.
//! * Uncertainty: linearised least squares at the optimum — Jacobian `J`
//!   by central finite differences, `cov = s² (JᵀJ)⁻¹` with
//!   `s² = SSR/(n − q)`, and intervals `x̂ ± t_{(1+c)/2, n−q} √cov_ii`
//!   (Seber & Wild, *Nonlinear Regression*, 1989, §5.1), over the `q`
//!   parameters not at a bound. A parameter that ends at a bound is
//!   reported as at that bound, with no interval (the linearised interval
//!   does not apply to a constrained optimum; Seber & Wild §5.8), and is
//!   held fixed for the others' intervals. A parameter the data do not
//!   constrain (a zero Jacobian column, or `JᵀJ` singular) gets an infinite
//!   standard error.
//!
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, StudentsT};

use super::sensitivity::{Factor, evaluate_all, jacobian_with_steps};
use super::stats::{self, Agreement};
use crate::{Error, Result};

/// The search method of [`calibrate`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Levenberg–Marquardt with bounds (Jacobian-based; see the module docs).
    LevenbergMarquardt,
    /// Bounded Nelder–Mead simplex with restarts (derivative-free).
    NelderMead,
}

/// Options of [`calibrate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationOptions {
    /// Search method.
    pub method: Method,
    /// Iterations (Levenberg–Marquardt: Jacobians; Nelder–Mead: per run).
    pub max_iters: u64,
    /// Nelder–Mead restarts from the best point (after the first run).
    pub restarts: usize,
    /// Confidence level of the intervals (0–1).
    pub confidence: f64,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        CalibrationOptions {
            method: Method::LevenbergMarquardt,
            max_iters: 400,
            restarts: 3,
            confidence: 0.95,
        }
    }
}

/// Which bound a fitted parameter ended at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Bound {
    /// The lower bound.
    Low,
    /// The upper bound.
    High,
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
    /// Standard error (linearised), parameter unit; infinite if the data do
    /// not constrain it; `None` when it ended at a bound.
    pub std_error: Option<f64>,
    /// Lower end of the confidence interval (`None` at a bound).
    pub ci_low: Option<f64>,
    /// Upper end of the confidence interval (`None` at a bound).
    pub ci_high: Option<f64>,
    /// Bounds searched.
    pub bounds: [f64; 2],
    /// The bound the fit ended at (within 10⁻⁴ of the range), if any: the
    /// data want the parameter beyond it.
    pub at_bound: Option<Bound>,
}

/// Result of a calibration.
#[derive(Debug, Clone, Serialize)]
pub struct Calibration {
    /// Search method used.
    pub method: Method,
    /// Fitted parameters, in order.
    pub params: Vec<FittedParameter>,
    /// Number of truth values.
    pub n_obs: usize,
    /// Degrees of freedom n − q (q: the parameters not at a bound).
    pub dof: usize,
    /// Confidence level of the intervals.
    pub confidence: f64,
    /// Agreement at the starting values.
    pub initial: Agreement,
    /// Agreement at the fitted values.
    pub fitted: Agreement,
    /// Parameter covariance (parameter units), row-major p × p; rows and
    /// columns of parameters at a bound are 0 (held fixed).
    pub covariance: Vec<Vec<f64>>,
    /// Predictions at the fitted values.
    pub predicted: Vec<f64>,
    /// Model evaluations made.
    pub evaluations: usize,
    /// Iterations (Levenberg–Marquardt: Jacobians; Nelder–Mead: all runs).
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

/// Sum of squared residuals of `y` against `truth`; infinite when not finite.
fn sum_of_squares(y: &[f64], truth: &[f64]) -> f64 {
    let s: f64 = y.iter().zip(truth).map(|(a, b)| (a - b).powi(2)).sum();
    if s.is_finite() { s } else { f64::INFINITY }
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
        Ok(sum_of_squares(&y, self.truth) / y.len() as f64)
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

/// Solve `a x = b` (a symmetric positive definite, small) by Cholesky;
/// `None` when `a` is not positive definite to working precision.
fn solve_spd(a: &[Vec<f64>], b: &[f64]) -> Option<Vec<f64>> {
    let n = a.len();
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if i == j {
                if s <= 0.0 || !s.is_finite() {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        y[i] = (b[i] - (0..i).map(|k| l[i][k] * y[k]).sum::<f64>()) / l[i][i];
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        x[i] = (y[i] - (i + 1..n).map(|k| l[k][i] * x[k]).sum::<f64>()) / l[i][i];
    }
    Some(x)
}

/// Finite-difference steps at `x`: 10⁻⁴ of the value's magnitude, at least
/// 10⁻⁶ of the range (so offsets near 0 get a step too).
fn fd_steps(factors: &[Factor], x: &[f64]) -> Vec<f64> {
    factors
        .iter()
        .zip(x)
        .map(|(f, &v)| 1e-4 * v.abs().max(1e-2 * (f.high - f.low)))
        .collect()
}

/// What a search returns: the best point, evaluations and iterations.
struct Search {
    x: Vec<f64>,
    evaluations: usize,
    iterations: u64,
}

/// Bounded Levenberg–Marquardt from `x0` (see the module docs).
fn levenberg_marquardt<M>(
    factors: &[Factor],
    truth: &[f64],
    model: &M,
    x0: &[f64],
    y0: &[f64],
    max_iters: u64,
) -> Result<Search>
where
    M: Fn(&[f64]) -> Result<Vec<f64>> + Sync,
{
    let p = factors.len();
    let range: Vec<f64> = factors.iter().map(|f| f.high - f.low).collect();
    let mut x = x0.to_vec();
    let mut r: Vec<f64> = y0.iter().zip(truth).map(|(y, t)| y - t).collect();
    let mut cost = sum_of_squares(y0, truth);
    let mut lambda = 1e-3;
    let mut nu = 2.0;
    let mut evaluations = 0usize;
    let mut iterations = 0u64;
    'outer: while iterations < max_iters && cost > 0.0 {
        iterations += 1;
        // Jacobian in scaled units: ∂y/∂s = ∂y/∂x · range.
        let jac = jacobian_with_steps(factors, &x, &fd_steps(factors, &x), model)?;
        evaluations += 2 * p;
        let mut a = vec![vec![0.0; p]; p];
        let mut g = vec![0.0; p];
        for (row, ro) in jac.iter().zip(&r) {
            for i in 0..p {
                let ji = row[i] * range[i];
                g[i] += ji * ro;
                for (k, aik) in a[i].iter_mut().enumerate() {
                    *aik += ji * row[k] * range[k];
                }
            }
        }
        // Active set: at a bound with the descent direction (−g) pointing out.
        let free: Vec<usize> = (0..p)
            .filter(|&i| {
                let s = (x[i] - factors[i].low) / range[i];
                !((s <= 0.0 && g[i] > 0.0) || (s >= 1.0 && g[i] < 0.0))
            })
            .collect();
        if free.is_empty() || free.iter().all(|&i| g[i] == 0.0) {
            break;
        }
        let max_diag = free.iter().map(|&i| a[i][i]).fold(0.0f64, f64::max);
        loop {
            let m: Vec<Vec<f64>> = free
                .iter()
                .map(|&i| {
                    free.iter()
                        .map(|&k| {
                            let d = if i == k {
                                lambda * a[i][i].max(1e-12 * max_diag).max(1e-300)
                            } else {
                                0.0
                            };
                            a[i][k] + d
                        })
                        .collect()
                })
                .collect();
            let rhs: Vec<f64> = free.iter().map(|&i| -g[i]).collect();
            let step = solve_spd(&m, &rhs);
            let mut xn = x.clone();
            let mut moved = 0.0f64;
            if let Some(d) = &step {
                for (&i, di) in free.iter().zip(d) {
                    let s = ((x[i] - factors[i].low) / range[i] + di).clamp(0.0, 1.0);
                    xn[i] = (factors[i].low + s * range[i]).clamp(factors[i].low, factors[i].high);
                    moved = moved.max(((xn[i] - x[i]) / range[i]).abs());
                }
            }
            let mut predicted = 0.0;
            if let Some(d) = &step {
                // Reduction of Σr² the Gauss–Newton model predicts for the
                // (unclipped) step: −2gᵀδ − δᵀAδ. Below 10⁻¹² of Σr² (or a
                // step that no longer moves) the fit has converged.
                let gd: f64 = free.iter().zip(d).map(|(&i, di)| g[i] * di).sum();
                let dad: f64 = free
                    .iter()
                    .zip(d)
                    .map(|(&i, di)| {
                        di * free.iter().zip(d).map(|(&k, dk)| a[i][k] * dk).sum::<f64>()
                    })
                    .sum();
                predicted = -2.0 * gd - dad;
                if predicted <= 1e-12 * cost || moved < 1e-12 {
                    break 'outer;
                }
            }
            let trial = if step.is_some() {
                evaluations += 1;
                model(&xn).ok().filter(|y| y.len() == truth.len())
            } else {
                None
            };
            let cn = trial
                .as_ref()
                .map_or(f64::INFINITY, |y| sum_of_squares(y, truth));
            if cn < cost {
                let y = trial.expect("a finite cost has a prediction");
                let gain = (cost - cn) / cost;
                let cost_before = cost;
                r = y.iter().zip(truth).map(|(y, t)| y - t).collect();
                x = xn;
                cost = cn;
                // Nielsen's (1999) update from the gain ratio ρ = actual /
                // predicted reduction (Madsen, Nielsen & Tingleff 2004,
                // *Methods for Non-Linear Least Squares Problems*, eq. 3.16).
                let rho = if predicted > 0.0 {
                    (cost_before - cn) / predicted
                } else {
                    0.0
                };
                lambda = (lambda * (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3))).max(1e-9);
                nu = 2.0;
                if gain < 1e-10 {
                    break 'outer;
                }
                break;
            }
            lambda *= nu;
            nu *= 2.0;
            if lambda > 1e12 {
                break 'outer; // no step lowers the sum of squares
            }
        }
    }
    Ok(Search {
        x,
        evaluations,
        iterations,
    })
}

/// Bounded Nelder–Mead with restarts from `x0` (see the module docs).
fn nelder_mead<M>(
    factors: &[Factor],
    truth: &[f64],
    model: &M,
    x0: &[f64],
    cost0: f64,
    opts: &CalibrationOptions,
) -> Result<Search>
where
    M: Fn(&[f64]) -> Result<Vec<f64>> + Sync,
{
    let p = factors.len();
    let evaluations = std::sync::atomic::AtomicUsize::new(0);
    let mut best_u = to_unbounded(x0, factors);
    let mut best_cost = cost0;
    let mut iterations = 0u64;
    let mut step = 0.5;
    for run in 0..=opts.restarts {
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
        if !improved && run > 0 {
            break;
        }
        step *= 0.5;
    }
    Ok(Search {
        x: to_bounded(&best_u, factors),
        evaluations: evaluations.load(std::sync::atomic::Ordering::Relaxed),
        iterations,
    })
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
    let search = match opts.method {
        Method::LevenbergMarquardt => {
            levenberg_marquardt(factors, truth, model, &x0, &y0, opts.max_iters)?
        }
        Method::NelderMead => nelder_mead(factors, truth, model, &x0, initial.rmse.powi(2), &opts)?,
    };
    let xf = search.x;
    let yf = evaluate_all(model, std::slice::from_ref(&xf), Some(n))?.remove(0);
    let fitted = Agreement::of(&yf, truth)?;
    let at_bound: Vec<Option<Bound>> = factors
        .iter()
        .zip(&xf)
        .map(|(f, &x)| {
            let tol = 1e-4 * (f.high - f.low);
            if x - f.low <= tol {
                Some(Bound::Low)
            } else if f.high - x <= tol {
                Some(Bound::High)
            } else {
                None
            }
        })
        .collect();
    // Linearised covariance at the optimum, over the parameters not at a
    // bound and with a non-zero Jacobian column.
    let free: Vec<usize> = (0..p).filter(|&i| at_bound[i].is_none()).collect();
    let jac = jacobian_with_steps(factors, &xf, &fd_steps(factors, &xf), model)?; // [obs][param]
    let col_norm: Vec<f64> = (0..p)
        .map(|i| jac.iter().map(|r| r[i] * r[i]).sum::<f64>().sqrt())
        .collect();
    let scale = free.iter().map(|&i| col_norm[i]).fold(0.0f64, f64::max);
    let (identifiable, flat): (Vec<usize>, Vec<usize>) = free
        .iter()
        .partition(|&&i| col_norm[i] > 1e-10 * scale && col_norm[i] > 0.0);
    let dof = n - free.len();
    let ssr: f64 = yf.iter().zip(truth).map(|(a, b)| (a - b).powi(2)).sum();
    let s2 = ssr / dof as f64;
    let t = StudentsT::new(0.0, 1.0, dof as f64)
        .map_err(|e| Error::Other(format!("Student t: {e}")))?
        .inverse_cdf(0.5 * (1.0 + opts.confidence));
    let mut covariance = vec![vec![0.0; p]; p];
    for &i in &flat {
        covariance[i][i] = f64::INFINITY;
    }
    let q = identifiable.len();
    let mut jtj = vec![vec![0.0; q]; q];
    for row in &jac {
        for (a, &i) in identifiable.iter().enumerate() {
            for (b, &k) in identifiable.iter().enumerate() {
                jtj[a][b] += row[i] * row[k];
            }
        }
    }
    match invert(&jtj) {
        Some(inv) => {
            for (a, &i) in identifiable.iter().enumerate() {
                for (b, &k) in identifiable.iter().enumerate() {
                    covariance[i][k] = inv[a][b] * s2;
                }
            }
        }
        None => {
            for &i in &identifiable {
                covariance[i][i] = f64::INFINITY;
            }
        }
    }
    let params = factors
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let (std_error, ci_low, ci_high) = if at_bound[i].is_some() {
                (None, None, None)
            } else {
                let se = covariance[i][i].max(0.0).sqrt();
                (Some(se), Some(xf[i] - t * se), Some(xf[i] + t * se))
            };
            FittedParameter {
                name: f.name.clone(),
                initial: f.nominal,
                fitted: xf[i],
                std_error,
                ci_low,
                ci_high,
                bounds: [f.low, f.high],
                at_bound: at_bound[i],
            }
        })
        .collect();
    Ok(Calibration {
        method: opts.method,
        params,
        n_obs: n,
        dof,
        confidence: opts.confidence,
        initial,
        fitted,
        covariance,
        predicted: yf,
        evaluations: search.evaluations + 2 + 2 * p,
        iterations: search.iterations,
    })
}

/// RMSE and Spearman of `predicted` against `truth` (convenience).
pub fn fit_quality(predicted: &[f64], truth: &[f64]) -> Result<(f64, f64)> {
    Ok((
        stats::rmse(predicted, truth)?,
        stats::spearman(predicted, truth)?,
    ))
}
