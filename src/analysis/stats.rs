//! Agreement statistics between predicted (synthetic) and measured (truth)
//! values: bias, mean absolute error, RMSE, Pearson's r, Spearman's ρ with
//! tied values given their average rank, and histograms.
//!
//! Conventions: residuals are `predicted − truth`, so a positive bias means
//! the synthetic image is too warm (too bright). All functions take paired
//! slices of equal length; pairs where either value is not finite are the
//! caller's to remove (see [`finite_pairs`]).
//!
//! References: Spearman's ρ as Pearson's r of the ranks, ties receiving the
//! mean of the ranks they span — Siegel & Castellan, *Nonparametric
//! Statistics for the Behavioral Sciences*, 2nd ed. (1988), §9.3 (the
//! tie-corrected coefficient equals Pearson's r on average ranks).

use serde::Serialize;

use crate::{Error, Result};

fn check_pairs(predicted: &[f64], truth: &[f64], what: &str) -> Result<()> {
    if predicted.len() != truth.len() {
        return Err(Error::invalid(
            what,
            format!(
                "the two samples differ in length ({} vs {})",
                predicted.len(),
                truth.len()
            ),
        ));
    }
    if predicted.is_empty() {
        return Err(Error::invalid(what, "no values to compare"));
    }
    Ok(())
}

/// The pairs `(p, t)` where both values are finite.
pub fn finite_pairs(predicted: &[f64], truth: &[f64]) -> (Vec<f64>, Vec<f64>) {
    predicted
        .iter()
        .zip(truth)
        .filter(|(p, t)| p.is_finite() && t.is_finite())
        .map(|(&p, &t)| (p, t))
        .unzip()
}

/// Mean of `x` (NaN for an empty slice).
pub fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

/// Sample standard deviation of `x` (divisor n − 1; NaN when n < 2).
pub fn std_dev(x: &[f64]) -> f64 {
    if x.len() < 2 {
        return f64::NAN;
    }
    let m = mean(x);
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() - 1) as f64).sqrt()
}

/// Bias (mean error) `mean(predicted − truth)`, in the values' unit.
pub fn bias(predicted: &[f64], truth: &[f64]) -> Result<f64> {
    check_pairs(predicted, truth, "bias")?;
    Ok(predicted.iter().zip(truth).map(|(p, t)| p - t).sum::<f64>() / predicted.len() as f64)
}

/// Mean absolute error `mean(|predicted − truth|)`, in the values' unit.
pub fn mae(predicted: &[f64], truth: &[f64]) -> Result<f64> {
    check_pairs(predicted, truth, "mean absolute error")?;
    Ok(predicted
        .iter()
        .zip(truth)
        .map(|(p, t)| (p - t).abs())
        .sum::<f64>()
        / predicted.len() as f64)
}

/// Root-mean-square error `sqrt(mean((predicted − truth)²))`, in the values' unit.
pub fn rmse(predicted: &[f64], truth: &[f64]) -> Result<f64> {
    check_pairs(predicted, truth, "RMSE")?;
    Ok((predicted
        .iter()
        .zip(truth)
        .map(|(p, t)| (p - t).powi(2))
        .sum::<f64>()
        / predicted.len() as f64)
        .sqrt())
}

/// Pearson's product-moment correlation coefficient r. NaN when either
/// sample has zero variance (correlation undefined).
pub fn pearson(x: &[f64], y: &[f64]) -> Result<f64> {
    check_pairs(x, y, "Pearson correlation")?;
    let (mx, my) = (mean(x), mean(y));
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        let (dx, dy) = (a - mx, b - my);
        sxy += dx * dy;
        sxx += dx * dx;
        syy += dy * dy;
    }
    if sxx == 0.0 || syy == 0.0 {
        return Ok(f64::NAN);
    }
    Ok(sxy / (sxx * syy).sqrt())
}

/// Ranks 1..=n of `x` (ascending), tied values receiving the mean of the
/// ranks they span ("fractional" ranking). NaN sorts as an error: the
/// caller must pass finite values.
pub fn average_ranks(x: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..x.len()).collect();
    order.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    let mut ranks = vec![0.0; x.len()];
    let mut i = 0;
    while i < order.len() {
        let mut j = i + 1;
        while j < order.len() && x[order[j]] == x[order[i]] {
            j += 1;
        }
        // Positions i..j (0-based) hold equal values: ranks i+1..=j, mean (i+1+j)/2.
        let r = (i + 1 + j) as f64 / 2.0;
        for &k in &order[i..j] {
            ranks[k] = r;
        }
        i = j;
    }
    ranks
}

/// Spearman's rank-order correlation ρ: Pearson's r of the average ranks
/// (exact with ties; Siegel & Castellan 1988 §9.3). NaN when either sample
/// is constant.
pub fn spearman(x: &[f64], y: &[f64]) -> Result<f64> {
    check_pairs(x, y, "Spearman correlation")?;
    if x.iter().chain(y).any(|v| !v.is_finite()) {
        return Err(Error::invalid(
            "Spearman correlation",
            "values must be finite (remove NaN/∞ pairs first)",
        ));
    }
    pearson(&average_ranks(x), &average_ranks(y))
}

/// Agreement of predicted with truth values (residual = predicted − truth).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Agreement {
    /// Number of pairs used.
    pub n: usize,
    /// Mean error (predicted − truth), values' unit.
    pub bias: f64,
    /// Mean absolute error, values' unit.
    pub mae: f64,
    /// Root-mean-square error, values' unit.
    pub rmse: f64,
    /// Standard deviation of the residuals (n − 1), values' unit.
    pub residual_std: f64,
    /// Pearson's r (NaN if undefined).
    pub pearson: f64,
    /// Spearman's ρ with average ranks for ties (NaN if undefined).
    pub spearman: f64,
    /// Mean of the predicted values.
    pub mean_predicted: f64,
    /// Mean of the truth values.
    pub mean_truth: f64,
}

impl Agreement {
    /// All statistics of `predicted` against `truth` over the pairs where
    /// both are finite. Errors when no such pair exists.
    pub fn of(predicted: &[f64], truth: &[f64]) -> Result<Agreement> {
        if predicted.len() != truth.len() {
            return Err(Error::invalid(
                "comparison",
                format!(
                    "the two samples differ in length ({} vs {})",
                    predicted.len(),
                    truth.len()
                ),
            ));
        }
        let (p, t) = finite_pairs(predicted, truth);
        if p.is_empty() {
            return Err(Error::invalid(
                "comparison",
                "no pair of finite values to compare",
            ));
        }
        let resid: Vec<f64> = p.iter().zip(&t).map(|(a, b)| a - b).collect();
        Ok(Agreement {
            n: p.len(),
            bias: bias(&p, &t)?,
            mae: mae(&p, &t)?,
            rmse: rmse(&p, &t)?,
            residual_std: std_dev(&resid),
            pearson: pearson(&p, &t)?,
            spearman: spearman(&p, &t)?,
            mean_predicted: mean(&p),
            mean_truth: mean(&t),
        })
    }
}

/// A histogram with equal-width bins over `[min, max]`; values outside are
/// counted in `below`/`above`, non-finite values are ignored.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Histogram {
    /// Lower edge of the first bin.
    pub min: f64,
    /// Upper edge of the last bin (the last bin includes it).
    pub max: f64,
    /// Counts per bin.
    pub counts: Vec<u64>,
    /// Values below `min`.
    pub below: u64,
    /// Values above `max`.
    pub above: u64,
}

impl Histogram {
    /// Count the finite values of `x` into `bins` equal bins over `[min, max]`.
    pub fn new(x: impl IntoIterator<Item = f64>, min: f64, max: f64, bins: usize) -> Result<Self> {
        if bins == 0 {
            return Err(Error::invalid("histogram bins", "need at least one bin"));
        }
        if !(min.is_finite() && max.is_finite() && max > min) {
            return Err(Error::invalid(
                "histogram range",
                format!("need finite min < max, got [{min}, {max}]"),
            ));
        }
        let mut h = Histogram {
            min,
            max,
            counts: vec![0; bins],
            below: 0,
            above: 0,
        };
        let w = (max - min) / bins as f64;
        for v in x {
            if !v.is_finite() {
                continue;
            }
            if v < min {
                h.below += 1;
            } else if v > max {
                h.above += 1;
            } else {
                let k = (((v - min) / w) as usize).min(bins - 1);
                h.counts[k] += 1;
            }
        }
        Ok(h)
    }

    /// Width of one bin.
    pub fn bin_width(&self) -> f64 {
        (self.max - self.min) / self.counts.len() as f64
    }

    /// Centre of bin `k`.
    pub fn bin_centre(&self, k: usize) -> f64 {
        self.min + (k as f64 + 0.5) * self.bin_width()
    }

    /// Total count inside the range.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum()
    }
}

/// The common `[min, max]` of the finite values of several samples, widened
/// slightly when all values are equal. `None` when there is no finite value.
pub fn common_range<'a>(samples: impl IntoIterator<Item = &'a [f64]>) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for s in samples {
        for &v in s.iter().filter(|v| v.is_finite()) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if lo > hi {
        return None;
    }
    if lo == hi {
        let d = if lo == 0.0 { 0.5 } else { lo.abs() * 1e-3 };
        return Some((lo - d, hi + d));
    }
    Some((lo, hi))
}
