//! Spectral grids, sensor bands, band integrals and their inverse
//! (band radiance → brightness temperature).
//!
//! A [`SpectralGrid`] is a set of increasing wavelengths (µm) with trapezoid
//! quadrature weights (µm), so that ∫ f(λ) dλ ≈ Σ wᵢ f(λᵢ). A [`Band`] is a
//! grid plus a relative spectral response R(λ) (peak-normalised to 1); its
//! band integral is
//!
//! ```text
//! L_band = ∫ R(λ) L(λ) dλ          W·m⁻²·sr⁻¹  (for L in W·m⁻²·sr⁻¹·µm⁻¹)
//! ```
//!
//! i.e. the in-band radiance (for a flat response it is ∫_lo^hi L dλ). This
//! is what `irsig radiance` prints as `radiance_w_m2_sr` and what the sensor
//! model calls "band radiance". [`Band::mean`] gives the response-weighted
//! mean spectral radiance ∫RL dλ / ∫R dλ (W·m⁻²·sr⁻¹·µm⁻¹) where that is
//! wanted instead.
//!
//! Owns grids, bands and band integrals. Takes wavelengths and a response
//! ([`super::response`]); gives quadrature weights, band radiances and their
//! inverse. Must not know sensors or scenes.

use super::planck::Planck;
use super::response::SpectralResponse;
use crate::math::interp1d;
use crate::{Error, Result};

/// Default spectral step for band grids, µm. Planck curves are smooth on this
/// scale: the trapezoid rule on an 8–14 µm band is then accurate to ~3·10⁻⁷ at 8–14 µm and ~10⁻⁵ at 3–5 µm (trapezoid
/// rule, error ∝ step²).
pub const DEFAULT_STEP_UM: f64 = 0.01;

/// The wavelengths a sensor band or a response file may span, µm: from the
/// near ultraviolet to the far infrared. Beyond them a value was most likely
/// given in nanometres.
pub const BAND_LIMITS_UM: (f64, f64) = (0.2, 100.0);

/// Increasing wavelengths (µm) with trapezoid quadrature weights (µm).
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralGrid {
    wavelengths_um: Vec<f64>,
    weights_um: Vec<f64>,
}

impl SpectralGrid {
    /// A grid on the given wavelengths, which must be finite, positive and
    /// strictly increasing (at least one; a single wavelength has weight 1 µm,
    /// i.e. the "integral" is the value itself — a monochromatic band).
    pub fn new(wavelengths_um: Vec<f64>) -> Result<Self> {
        if wavelengths_um.is_empty() {
            return Err(Error::invalid(
                "wavelengths_um",
                "a spectral grid needs at least one wavelength",
            ));
        }
        for (i, &l) in wavelengths_um.iter().enumerate() {
            if !(l.is_finite() && l > 0.0) {
                return Err(Error::invalid(
                    format!("wavelengths_um[{i}]"),
                    format!("expected a positive wavelength in µm, got {l}"),
                ));
            }
            if i > 0 && l <= wavelengths_um[i - 1] {
                return Err(Error::invalid(
                    format!("wavelengths_um[{i}]"),
                    format!(
                        "wavelengths must increase strictly, got {} after {}",
                        l,
                        wavelengths_um[i - 1]
                    ),
                ));
            }
        }
        let n = wavelengths_um.len();
        let mut weights_um = vec![0.0; n];
        if n == 1 {
            weights_um[0] = 1.0;
        } else {
            for i in 0..n - 1 {
                let h = 0.5 * (wavelengths_um[i + 1] - wavelengths_um[i]);
                weights_um[i] += h;
                weights_um[i + 1] += h;
            }
        }
        Ok(SpectralGrid {
            wavelengths_um,
            weights_um,
        })
    }

    /// A uniform grid from `lo_um` to `hi_um` inclusive with spacing at most
    /// `step_um`.
    pub fn uniform(lo_um: f64, hi_um: f64, step_um: f64) -> Result<Self> {
        check_range(lo_um, hi_um)?;
        if !(step_um.is_finite() && step_um > 0.0) {
            return Err(Error::invalid(
                "step_um",
                format!("expected a positive spectral step in µm, got {step_um}"),
            ));
        }
        let n = ((hi_um - lo_um) / step_um).ceil().max(1.0) as usize;
        let h = (hi_um - lo_um) / n as f64;
        let wl = (0..=n)
            .map(|i| if i == n { hi_um } else { lo_um + h * i as f64 })
            .collect();
        SpectralGrid::new(wl)
    }

    /// The wavelengths, µm.
    pub fn wavelengths_um(&self) -> &[f64] {
        &self.wavelengths_um
    }
    /// The trapezoid weights, µm (sum = hi − lo).
    pub fn weights_um(&self) -> &[f64] {
        &self.weights_um
    }
    /// Number of wavelengths.
    pub fn len(&self) -> usize {
        self.wavelengths_um.len()
    }
    /// Whether the grid is empty (never true for a constructed grid).
    pub fn is_empty(&self) -> bool {
        self.wavelengths_um.is_empty()
    }
    /// ∫ f dλ by the trapezoid rule, for `values` on this grid.
    pub fn integrate(&self, values: &[f64]) -> f64 {
        debug_assert_eq!(values.len(), self.len());
        self.weights_um.iter().zip(values).map(|(w, v)| w * v).sum()
    }
    /// Resample a tabulated spectrum onto this grid, conserving integrals:
    /// the source is taken as piecewise linear between its points
    /// (`src_wl_um` increasing), and each grid point gets the source's mean
    /// over its dual cell (from the midpoint to its left neighbour to the
    /// midpoint to its right one; the trapezoid weight is that cell's width),
    /// so `self.integrate(&out)` equals the exact integral of the source
    /// over the grid's range. A single-point grid takes the value at its
    /// wavelength. Errors where the grid extends beyond the source by more
    /// than `tolerance_um`; within it the source is held constant.
    pub fn resample_mean(
        &self,
        src_wl_um: &[f64],
        src: &[f64],
        tolerance_um: f64,
    ) -> Result<Vec<f64>> {
        let n = src_wl_um.len();
        if n < 2 || src.len() != n {
            return Err(Error::invalid(
                "spectrum",
                "expected at least two (wavelength, value) points",
            ));
        }
        let (lo, hi) = (self.wavelengths_um[0], self.wavelengths_um[self.len() - 1]);
        if lo < src_wl_um[0] - tolerance_um || hi > src_wl_um[n - 1] + tolerance_um {
            return Err(Error::invalid(
                "spectrum",
                format!(
                    "data cover {:.4}–{:.4} µm but the spectral grid spans {lo:.4}–{hi:.4} µm",
                    src_wl_um[0],
                    src_wl_um[n - 1]
                ),
            ));
        }
        // Cumulative integral at the source points.
        let mut cum = vec![0.0; n];
        for j in 1..n {
            cum[j] = cum[j - 1] + 0.5 * (src[j] + src[j - 1]) * (src_wl_um[j] - src_wl_um[j - 1]);
        }
        let value = |x: f64| interp1d(src_wl_um, src, x);
        // ∫ from src_wl_um[0] to x (constant extension outside).
        let cumulative = |x: f64| -> f64 {
            if x <= src_wl_um[0] {
                return (x - src_wl_um[0]) * src[0];
            }
            if x >= src_wl_um[n - 1] {
                return cum[n - 1] + (x - src_wl_um[n - 1]) * src[n - 1];
            }
            let j = src_wl_um.partition_point(|&w| w <= x).clamp(1, n - 1);
            let x0 = src_wl_um[j - 1];
            cum[j - 1] + 0.5 * (src[j - 1] + value(x)) * (x - x0)
        };
        let m = self.len();
        if m == 1 {
            return Ok(vec![value(lo)]);
        }
        let w = &self.wavelengths_um;
        Ok((0..m)
            .map(|i| {
                let a = if i == 0 {
                    w[0]
                } else {
                    0.5 * (w[i - 1] + w[i])
                };
                let b = if i == m - 1 {
                    w[m - 1]
                } else {
                    0.5 * (w[i] + w[i + 1])
                };
                (cumulative(b) - cumulative(a)) / (b - a)
            })
            .collect())
    }

    /// Blackbody spectral radiance B(λ, T) on this grid, W·m⁻²·sr⁻¹·µm⁻¹.
    pub fn blackbody(&self, planck: &Planck, temperature_k: f64) -> Vec<f64> {
        self.wavelengths_um
            .iter()
            .map(|&l| planck.radiance(l, temperature_k))
            .collect()
    }
}

fn check_range(lo_um: f64, hi_um: f64) -> Result<()> {
    if !(lo_um.is_finite() && hi_um.is_finite() && lo_um > 0.0 && hi_um > lo_um) {
        return Err(Error::invalid(
            "band",
            format!("expected 0 < lo < hi in µm, got {lo_um}–{hi_um}"),
        ));
    }
    Ok(())
}

/// A spectral band: a grid plus a relative response R(λ) ∈ [0, 1] (peak 1).
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    grid: SpectralGrid,
    response: Vec<f64>,
    /// Quadrature weights × response, µm.
    weights_um: Vec<f64>,
    planck: Planck,
}

impl Band {
    /// A flat (R = 1) band from `lo_um` to `hi_um`, sampled every ≤ `step_um`.
    pub fn flat(lo_um: f64, hi_um: f64, step_um: f64) -> Result<Self> {
        let grid = SpectralGrid::uniform(lo_um, hi_um, step_um)?;
        let response = vec![1.0; grid.len()];
        Band::new(grid, response)
    }

    /// A band from a measured response: the grid is the response's own
    /// wavelengths refined so no step exceeds `step_um`; R is interpolated
    /// linearly between the given points and normalised to a peak of 1.
    pub fn from_response(resp: &SpectralResponse, step_um: f64) -> Result<Self> {
        if !(step_um.is_finite() && step_um > 0.0) {
            return Err(Error::invalid(
                "step_um",
                format!("expected a positive spectral step in µm, got {step_um}"),
            ));
        }
        let wl = resp.wavelengths_um();
        let mut grid_wl = Vec::with_capacity(wl.len());
        for i in 0..wl.len() {
            grid_wl.push(wl[i]);
            if i + 1 < wl.len() {
                let n = ((wl[i + 1] - wl[i]) / step_um).ceil() as usize;
                for k in 1..n {
                    grid_wl.push(wl[i] + (wl[i + 1] - wl[i]) * k as f64 / n as f64);
                }
            }
        }
        let response = grid_wl.iter().map(|&l| resp.at(l)).collect();
        Band::new(SpectralGrid::new(grid_wl)?, response)
    }

    /// A band on `grid` with the response values `response` (one per grid
    /// wavelength, ≥ 0, not all zero); the response is normalised to peak 1.
    pub fn new(grid: SpectralGrid, mut response: Vec<f64>) -> Result<Self> {
        if response.len() != grid.len() {
            return Err(Error::invalid(
                "response",
                format!(
                    "expected {} response values (one per wavelength), got {}",
                    grid.len(),
                    response.len()
                ),
            ));
        }
        let mut peak: f64 = 0.0;
        for (i, &r) in response.iter().enumerate() {
            if !(r.is_finite() && r >= 0.0) {
                return Err(Error::invalid(
                    format!("response[{i}]"),
                    format!("expected a finite relative response ≥ 0, got {r}"),
                ));
            }
            peak = peak.max(r);
        }
        if peak <= 0.0 {
            return Err(Error::invalid(
                "response",
                "the spectral response is zero everywhere",
            ));
        }
        response.iter_mut().for_each(|r| *r /= peak);
        let weights_um = grid
            .weights_um()
            .iter()
            .zip(&response)
            .map(|(w, r)| w * r)
            .collect();
        Ok(Band {
            grid,
            response,
            weights_um,
            planck: Planck::default(),
        })
    }

    /// The same band using Planck's law with other constants.
    pub fn with_planck(mut self, planck: Planck) -> Self {
        self.planck = planck;
        self
    }

    /// The spectral grid.
    pub fn grid(&self) -> &SpectralGrid {
        &self.grid
    }
    /// The wavelengths, µm.
    pub fn wavelengths_um(&self) -> &[f64] {
        self.grid.wavelengths_um()
    }
    /// The relative response on the grid (peak 1).
    pub fn response(&self) -> &[f64] {
        &self.response
    }
    /// Quadrature weights including the response, µm: Σ wᵢ Lᵢ = ∫ R L dλ.
    pub fn weights_um(&self) -> &[f64] {
        &self.weights_um
    }
    /// The Planck function the band uses.
    pub fn planck(&self) -> &Planck {
        &self.planck
    }
    /// Number of wavelengths.
    pub fn len(&self) -> usize {
        self.grid.len()
    }
    /// Whether the band has no wavelengths (never true once constructed).
    pub fn is_empty(&self) -> bool {
        self.grid.is_empty()
    }
    /// ∫ R dλ, µm (the equivalent width).
    pub fn equivalent_width_um(&self) -> f64 {
        self.weights_um.iter().sum()
    }

    /// Band integral ∫ R(λ) L(λ) dλ of a spectrum on the band's grid
    /// (W·m⁻²·sr⁻¹ for L in W·m⁻²·sr⁻¹·µm⁻¹).
    #[inline]
    pub fn integrate(&self, spectrum: &[f64]) -> f64 {
        debug_assert_eq!(spectrum.len(), self.len());
        self.weights_um
            .iter()
            .zip(spectrum)
            .map(|(w, v)| w * v)
            .sum()
    }

    /// Response-weighted mean ∫ R L dλ / ∫ R dλ (W·m⁻²·sr⁻¹·µm⁻¹).
    pub fn mean(&self, spectrum: &[f64]) -> f64 {
        self.integrate(spectrum) / self.equivalent_width_um()
    }

    /// Blackbody band radiance ∫ R B(λ, T) dλ, W·m⁻²·sr⁻¹.
    pub fn blackbody_radiance(&self, temperature_k: f64) -> f64 {
        self.grid
            .wavelengths_um()
            .iter()
            .zip(&self.weights_um)
            .map(|(&l, w)| w * self.planck.radiance(l, temperature_k))
            .sum()
    }

    /// ∂/∂T of [`Band::blackbody_radiance`], W·m⁻²·sr⁻¹·K⁻¹.
    pub fn blackbody_radiance_derivative(&self, temperature_k: f64) -> f64 {
        self.grid
            .wavelengths_um()
            .iter()
            .zip(&self.weights_um)
            .map(|(&l, w)| w * self.planck.radiance_derivative(l, temperature_k))
            .sum()
    }

    /// Brightness temperature: the T (K) whose blackbody band radiance equals
    /// `radiance_w_m2_sr`. The band radiance is strictly increasing in T, so
    /// the root is unique; it is found by Newton steps safeguarded by a
    /// bisection bracket, to 10⁻¹⁰ relative. Errors for a radiance that is not
    /// finite and positive or lies outside the bracket 1 K – 100 000 K.
    pub fn brightness_temperature(&self, radiance_w_m2_sr: f64) -> Result<f64> {
        let target = radiance_w_m2_sr;
        if !(target.is_finite() && target > 0.0) {
            return Err(Error::invalid(
                "radiance",
                format!("expected a positive band radiance in W/m²/sr, got {target}"),
            ));
        }
        let (mut lo, mut hi) = (1.0_f64, 1.0e5_f64);
        let f_lo = self.blackbody_radiance(lo) - target;
        let f_hi = self.blackbody_radiance(hi) - target;
        if f_lo > 0.0 || f_hi < 0.0 {
            return Err(Error::invalid(
                "radiance",
                format!(
                    "band radiance {target} W/m²/sr corresponds to no temperature between \
                     {lo} K and {hi} K for this band"
                ),
            ));
        }
        // Start from a sensible guess: 300 K, or the bracket's midpoint.
        let mut t = 300.0_f64;
        for _ in 0..200 {
            let f = self.blackbody_radiance(t) - target;
            if f == 0.0 {
                return Ok(t);
            }
            if f > 0.0 {
                hi = t;
            } else {
                lo = t;
            }
            let d = self.blackbody_radiance_derivative(t);
            let mut next = if d > 0.0 { t - f / d } else { f64::NAN };
            if !(next.is_finite() && next > lo && next < hi) {
                // Bisect in log T: the bracket spans orders of magnitude.
                next = (lo * hi).sqrt();
            }
            if (next - t).abs() <= 1e-10 * t {
                return Ok(next);
            }
            t = next;
        }
        Ok(t)
    }
}
