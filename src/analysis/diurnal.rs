//! Target/background contrast through a period: the time of greatest
//! contrast and the thermal crossovers (times where the contrast changes
//! sign, located by linear interpolation between samples).
//!
//! The series come from one thermal run with a shared spin-up (see
//! `irsig diurnal`); this module only analyses them.

use chrono::{DateTime, Duration, FixedOffset};
use serde::Serialize;

use crate::{Error, Result};

/// One quantity of the target and the background at the sample times.
#[derive(Debug, Clone, Serialize)]
pub struct ContrastSeries {
    /// What is compared (`apparent_temperature_k`, `band_radiance`, ...).
    pub quantity: String,
    /// Unit.
    pub unit: String,
    /// Target values.
    pub target: Vec<f64>,
    /// Background values.
    pub background: Vec<f64>,
    /// Contrast target − background.
    pub contrast: Vec<f64>,
    /// Greatest |contrast|.
    pub max_abs_contrast: f64,
    /// Signed contrast at that time.
    pub max_contrast_signed: f64,
    /// When it occurs (the sample time; refined by a parabola through the
    /// neighbouring samples, when inside the period).
    pub time_of_max: DateTime<FixedOffset>,
    /// Crossover times (contrast = 0), interpolated.
    pub crossovers: Vec<DateTime<FixedOffset>>,
}

/// Analyse `target` against `background` sampled at `times` (increasing).
pub fn contrast_series(
    quantity: &str,
    unit: &str,
    times: &[DateTime<FixedOffset>],
    target: &[f64],
    background: &[f64],
) -> Result<ContrastSeries> {
    if times.len() != target.len() || times.len() != background.len() {
        return Err(Error::invalid(
            "contrast",
            format!(
                "{} times, {} target and {} background values",
                times.len(),
                target.len(),
                background.len()
            ),
        ));
    }
    if times.is_empty() {
        return Err(Error::invalid("contrast", "no sample times"));
    }
    if times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(Error::invalid("contrast", "sample times must increase"));
    }
    let contrast: Vec<f64> = target.iter().zip(background).map(|(t, b)| t - b).collect();
    if contrast.iter().any(|c| !c.is_finite()) {
        return Err(Error::invalid(
            "contrast",
            "non-finite target or background value",
        ));
    }
    let k = (0..contrast.len())
        .max_by(|&a, &b| contrast[a].abs().total_cmp(&contrast[b].abs()))
        .unwrap_or(0);
    let mut time_of_max = times[k];
    let mut max_signed = contrast[k];
    // Parabolic refinement through (k−1, k, k+1) when equally spaced.
    if k > 0 && k + 1 < contrast.len() && times[k] - times[k - 1] == times[k + 1] - times[k] {
        let (a, b, c) = (
            contrast[k - 1].abs(),
            contrast[k].abs(),
            contrast[k + 1].abs(),
        );
        let den = a - 2.0 * b + c;
        if den < 0.0 {
            let off = 0.5 * (a - c) / den; // in steps, within ±0.5
            let dt = (times[k] - times[k - 1]).num_milliseconds() as f64;
            time_of_max = times[k] + Duration::milliseconds((off * dt).round() as i64);
            let peak = b - 0.25 * (a - c) * off;
            max_signed = peak.copysign(contrast[k]);
        }
    }
    let mut crossovers = Vec::new();
    for i in 1..contrast.len() {
        let (c0, c1) = (contrast[i - 1], contrast[i]);
        if c0 == 0.0 && i == 1 {
            crossovers.push(times[0]);
        }
        if c1 == 0.0 {
            crossovers.push(times[i]);
        } else if c0 != 0.0 && (c0 < 0.0) != (c1 < 0.0) {
            let f = c0 / (c0 - c1);
            let dt = (times[i] - times[i - 1]).num_milliseconds() as f64;
            crossovers.push(times[i - 1] + Duration::milliseconds((f * dt).round() as i64));
        }
    }
    Ok(ContrastSeries {
        quantity: quantity.into(),
        unit: unit.into(),
        target: target.to_vec(),
        background: background.to_vec(),
        max_abs_contrast: max_signed.abs(),
        max_contrast_signed: max_signed,
        contrast,
        time_of_max,
        crossovers,
    })
}
