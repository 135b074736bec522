//! Sensor effects on a band's radiance image, in the order they act:
//!
//! 1. [`reduce_oversampled`]: `N×N` sub-pixel radiances → one pixel, weighted
//!    by the point-spread function ([`Psf`]: box = the detector footprint
//!    average; Gaussian of σ pixels). Weights are normalised per pixel, so a
//!    flat field keeps its value and radiant energy is conserved.
//! 2. [`apply_mtf`]: optics and detector modulation transfer ([`Mtf`]),
//!    multiplied in the frequency domain (FFT, `rustfft`) over a mirrored
//!    (even-symmetric) extension of the image, which avoids wrap-around edges.
//! 3. [`add_noise`]: zero-mean Gaussian noise of σ = NEdT·dL/dT at the
//!    NEdT's reference temperature ([`radiance_sigma_from_nedt`]); seeded
//!    ChaCha8 with one stream per (band, row), so results are bit-identical
//!    for any thread count and any tiling into row bands.
//! 4. [`quantise`]: digital counts `clamp(round(gain·L + offset), 0, 2ᵇ − 1)`.
//!
//! Units: radiance in whatever unit the caller uses consistently (irsig:
//! band radiance W·m⁻²·sr⁻¹), frequencies in cycles per pixel.

use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rustfft::{FftPlanner, num_complex::Complex};
use serde::Deserialize;

use super::MtfConfig;
use crate::radiometry::Band;
use crate::{Error, Result};

/// Point-spread function used to reduce oversampled sub-pixels.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Default, schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Psf {
    /// Equal weights over the pixel's own `N×N` sub-samples.
    #[default]
    Box,
    /// Gaussian of standard deviation `sigma_px` pixels centred on the
    /// pixel, over sub-samples within 4σ (reaching into neighbours).
    Gaussian {
        /// Standard deviation, pixels.
        sigma_px: f64,
    },
}

impl Psf {
    /// Rows of neighbouring pixels a pixel's value depends on (halo needed
    /// when rendering in row bands).
    pub fn halo_px(&self) -> usize {
        match *self {
            Psf::Box => 0,
            Psf::Gaussian { sigma_px } => (4.0 * sigma_px).ceil() as usize,
        }
    }
}

/// Normalised 1-D weights of output index `o` over sub-sample indices.
fn weights_1d(psf: Psf, n: usize, len_sub: usize, o: usize) -> (usize, Vec<f64>) {
    match psf {
        Psf::Box => (o * n, vec![1.0 / n as f64; n]),
        Psf::Gaussian { sigma_px } => {
            let centre = o as f64 + 0.5; // pixel units
            // At least the nearest sub-sample, however narrow the PSF.
            let reach = (4.0 * sigma_px).max(1.0 / n as f64);
            let lo = (((centre - reach) * n as f64 - 0.5).ceil().max(0.0)) as usize;
            let hi = (((centre + reach) * n as f64 - 0.5).floor() as usize).min(len_sub - 1);
            let w: Vec<f64> = (lo..=hi)
                .map(|k| {
                    let d = (k as f64 + 0.5) / n as f64 - centre;
                    (-0.5 * d * d / (sigma_px * sigma_px)).exp()
                })
                .collect();
            let s: f64 = w.iter().sum();
            (lo, w.into_iter().map(|v| v / s).collect())
        }
    }
}

/// Reduce a `(width·n) × (height·n)` oversampled image (row-major) to
/// `width × height` with `psf`. The 2-D weights are the product of 1-D
/// weights (both PSFs are separable), normalised over the sub-samples inside
/// the image, so edges keep a flat field flat.
pub fn reduce_oversampled(
    data: &[f32],
    width: usize,
    height: usize,
    n: usize,
    psf: Psf,
) -> Result<Vec<f32>> {
    let (ws, hs) = (width * n, height * n);
    if n == 0 || data.len() != ws * hs {
        return Err(Error::invalid(
            "oversampled image",
            format!(
                "{} values: expected ({width}·{n}) × ({height}·{n}) = {}",
                data.len(),
                ws * hs
            ),
        ));
    }
    if let Psf::Gaussian { sigma_px } = psf {
        if !(sigma_px.is_finite() && sigma_px > 0.0) {
            return Err(Error::invalid(
                "psf.sigma_px",
                format!("{sigma_px}: expected a positive width in pixels"),
            ));
        }
    }
    let wx: Vec<_> = (0..width).map(|o| weights_1d(psf, n, ws, o)).collect();
    let wy: Vec<_> = (0..height).map(|o| weights_1d(psf, n, hs, o)).collect();
    // Along x: hs sub-rows of width values.
    let mut tmp = vec![0f64; hs * width];
    tmp.par_chunks_mut(width)
        .zip(data.par_chunks(ws))
        .for_each(|(out, row)| {
            for (o, (lo, w)) in out.iter_mut().zip(&wx) {
                *o = w.iter().zip(&row[*lo..]).map(|(a, &b)| a * b as f64).sum();
            }
        });
    // Along y.
    let mut out = vec![0f32; width * height];
    out.par_chunks_mut(width)
        .zip(wy.par_iter())
        .for_each(|(orow, (lo, w))| {
            for (x, o) in orow.iter_mut().enumerate() {
                let s: f64 = w
                    .iter()
                    .enumerate()
                    .map(|(k, a)| a * tmp[(lo + k) * width + x])
                    .sum();
                *o = s as f32;
            }
        });
    Ok(out)
}

/// Diffraction-limited MTF of an aberration-free circular pupil at
/// normalised frequency `x = ν/ν_c` (`ν_c = D/(λ·f)`):
/// `(2/π)·(acos x − x·√(1 − x²))` for `x < 1`, else 0 (Goodman,
/// *Introduction to Fourier Optics*, 3rd ed., eq. 6-32).
pub fn diffraction_mtf(x: f64) -> f64 {
    let x = x.abs();
    if x >= 1.0 {
        0.0
    } else {
        std::f64::consts::FRAC_2_PI * (x.acos() - x * (1.0 - x * x).sqrt())
    }
}

/// `sin(πx)/(πx)`.
pub fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-12 {
        1.0
    } else {
        let px = std::f64::consts::PI * x;
        px.sin() / px
    }
}

/// Optics and detector transfer functions, frequencies in cycles/pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mtf {
    /// Diffraction cutoff `D·(pixel angle)/λ`, cycles per pixel (`None`: no
    /// optics MTF).
    pub optics_cutoff_cycles_per_px: Option<f64>,
    /// Detector fill factor: transfer `sinc(ff·fx)·sinc(ff·fy)` (the OTF of
    /// a square detector of side `ff·pitch`; Boreman, *Modulation Transfer
    /// Function in Optical and Electro-Optical Systems*, §2.1). A box PSF
    /// reduction of oversampled pixels already integrates over the full
    /// pixel, so use this with `oversample: 1`.
    pub fill_factor: Option<f64>,
}

impl Mtf {
    /// The transfer at frequency `(fx, fy)`, cycles/pixel.
    pub fn value(&self, fx: f64, fy: f64) -> f64 {
        let mut v = 1.0;
        if let Some(c) = self.optics_cutoff_cycles_per_px {
            v *= diffraction_mtf(fx.hypot(fy) / c);
        }
        if let Some(ff) = self.fill_factor {
            v *= sinc(ff * fx) * sinc(ff * fy);
        }
        v
    }
}

/// Multiply the image's spectrum by `mtf` (in place). The image is extended
/// to `2W × 2H` by mirroring, transformed, filtered, transformed back and
/// cropped: a cosine `cos(2πk(x+½)/2W)` comes out scaled by exactly
/// `mtf(k/2W, 0)`.
pub fn apply_mtf(data: &mut [f32], width: usize, height: usize, mtf: &Mtf) -> Result<()> {
    if data.len() != width * height || width == 0 || height == 0 {
        return Err(Error::invalid(
            "image",
            format!("{} values for {width}×{height}", data.len()),
        ));
    }
    let (w2, h2) = (2 * width, 2 * height);
    let mut planner = FftPlanner::<f64>::new();
    let fx_fwd = planner.plan_fft_forward(w2);
    let fx_inv = planner.plan_fft_inverse(w2);
    let fy_fwd = planner.plan_fft_forward(h2);
    let fy_inv = planner.plan_fft_inverse(h2);
    let mirror = |i: usize, n: usize| if i < n { i } else { 2 * n - 1 - i };
    // Rows of the extended image (only the first `height` distinct rows are
    // needed for the x transform; rows mirror in y afterwards).
    let mut rows: Vec<Complex<f64>> = vec![Complex::default(); height * w2];
    rows.par_chunks_mut(w2).enumerate().for_each(|(y, r)| {
        for (x, c) in r.iter_mut().enumerate() {
            *c = Complex::new(data[y * width + mirror(x, width)] as f64, 0.0);
        }
        fx_fwd.process(r);
    });
    // Columns: for each x frequency, a column of length 2H, mirrored in y.
    let mut cols: Vec<Complex<f64>> = vec![Complex::default(); w2 * h2];
    let freq = |k: usize, n: usize| {
        let k = k as f64;
        let n = n as f64;
        if k <= n / 2.0 { k / n } else { k / n - 1.0 }
    };
    cols.par_chunks_mut(h2).enumerate().for_each(|(kx, c)| {
        for (y, v) in c.iter_mut().enumerate() {
            *v = rows[mirror(y, height) * w2 + kx];
        }
        fy_fwd.process(c);
        let fx = freq(kx, w2);
        for (ky, v) in c.iter_mut().enumerate() {
            *v *= mtf.value(fx, freq(ky, h2));
        }
        fy_inv.process(c);
    });
    // Back along x for the rows we keep.
    let scale = 1.0 / (w2 * h2) as f64;
    data.par_chunks_mut(width).enumerate().for_each(|(y, out)| {
        let mut r: Vec<Complex<f64>> = (0..w2).map(|kx| cols[kx * h2 + y]).collect();
        fx_inv.process(&mut r);
        for (o, v) in out.iter_mut().zip(&r) {
            *o = (v.re * scale) as f32;
        }
    });
    Ok(())
}

/// Radiance noise σ for an NEdT: `NEdT · dL/dT` at `reference_k`, with
/// `dL/dT` from a central difference (±0.01 K) of `band_radiance(T)` (the
/// radiometry module's band-integrated Planck radiance). Units: those of
/// `band_radiance`.
pub fn radiance_sigma_from_nedt(
    nedt_k: f64,
    reference_k: f64,
    band_radiance: impl Fn(f64) -> f64,
) -> f64 {
    let h = 0.01;
    nedt_k * (band_radiance(reference_k + h) - band_radiance(reference_k - h)) / (2.0 * h)
}

/// Standard normal deviate by the Box–Muller transform (one per pair of
/// uniforms).
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u = |r: &mut ChaCha8Rng| (r.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    let u1 = 1.0 - u(rng); // (0, 1]
    let u2 = u(rng);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Add zero-mean Gaussian noise of standard deviation `sigma` to the rows of
/// `data` (`width` wide), whose first row is image row `first_row`. The
/// stream of image row `r` is keyed by `(seed, stream, r)` alone (ChaCha8),
/// so a band (`stream`) gets the same noise however it is split into
/// threads or row bands.
pub fn add_noise(
    data: &mut [f32],
    width: usize,
    first_row: usize,
    sigma: f64,
    seed: u64,
    stream: u64,
) {
    if sigma == 0.0 || width == 0 {
        return;
    }
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    key[8..16].copy_from_slice(&stream.to_le_bytes());
    data.par_chunks_mut(width).enumerate().for_each(|(i, row)| {
        let mut rng = ChaCha8Rng::from_seed(key);
        rng.set_stream((first_row + i) as u64);
        for v in row {
            *v = (*v as f64 + sigma * normal(&mut rng)) as f32;
        }
    });
}

/// Digital counts: `clamp(round(gain·L + offset), 0, 2^bits − 1)`, as f32
/// (exact for `bits ≤ 24`). NaN radiance stays NaN (visible in `irsig
/// info`'s NaN count rather than hidden as a count).
pub fn quantise(data: &[f32], bits: u32, gain: f64, offset: f64) -> Vec<f32> {
    let max = ((1u64 << bits.min(32)) - 1) as f64;
    data.iter()
        .map(|&l| {
            if l.is_nan() {
                f32::NAN
            } else {
                (gain * l as f64 + offset).round().clamp(0.0, max) as f32
            }
        })
        .collect()
}

/// A sensor's MTF settings; the optics cutoff depends on the band's
/// wavelength, so the [`Mtf`] itself is made per band by [`MtfModel::at`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MtfModel {
    /// Entrance-pupil diameter, m (`None`: no optics MTF).
    pub aperture_diameter_m: Option<f64>,
    /// Fixed wavelength for the optics MTF, µm (`None`: each band's centre).
    pub wavelength_um: Option<f64>,
    /// Detector fill factor (`None`: no detector MTF).
    pub fill_factor: Option<f64>,
    /// Angle one pixel subtends (pitch/f, or a scanner's sample step), rad.
    pub pixel_angle_rad: f64,
}

impl MtfModel {
    /// The MTF for a band centred at `band_centre_um`: diffraction cutoff
    /// `ν_c = D/λ` cycles/rad, i.e. `D·(pixel angle)/λ` cycles/pixel.
    pub fn at(&self, band_centre_um: f64) -> Mtf {
        let lambda_m = self.wavelength_um.unwrap_or(band_centre_um) * 1e-6;
        Mtf {
            optics_cutoff_cycles_per_px: self
                .aperture_diameter_m
                .map(|d| d / lambda_m * self.pixel_angle_rad),
            fill_factor: self.fill_factor,
        }
    }
}

/// Response-weighted centre wavelength of a band, `∫R λ dλ / ∫R dλ`, µm.
pub fn band_centre_um(band: &Band) -> f64 {
    band.wavelengths_um()
        .iter()
        .zip(band.weights_um())
        .map(|(l, w)| l * w)
        .sum::<f64>()
        / band.equivalent_width_um()
}

/// A sensor's effects chain (see the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct Effects {
    /// Oversampling reduction PSF.
    pub psf: Psf,
    /// Optics/detector MTF, if any.
    pub mtf: Option<MtfModel>,
    /// NEdT, K, if noise is on.
    pub nedt_k: Option<f64>,
    /// Scene temperature at which the NEdT holds, K.
    pub nedt_reference_k: f64,
    /// Quantisation bits, if a counts layer is wanted.
    pub bits: Option<u32>,
    /// Counts per radiance unit.
    pub gain: f64,
    /// Counts offset.
    pub offset: f64,
    /// Noise seed.
    pub seed: u64,
}

/// The processed image of one band.
#[derive(Debug, Clone, PartialEq)]
pub struct BandImage {
    /// Radiance after PSF, MTF and noise.
    pub radiance: Vec<f32>,
    /// Digital counts, when quantisation is on.
    pub counts: Option<Vec<f32>>,
}

impl Effects {
    /// No effects: box reduction only.
    pub fn none() -> Self {
        Effects {
            psf: Psf::Box,
            mtf: None,
            nedt_k: None,
            nedt_reference_k: 300.0,
            bits: None,
            gain: 1.0,
            offset: 0.0,
            seed: 0,
        }
    }

    /// Build from scene-file values; `pixel_angle_rad` is the angle one
    /// pixel subtends (pitch/f, or a scanner's sample step).
    pub(crate) fn from_parts(
        psf: Psf,
        mtf: Option<&MtfConfig>,
        pixel_angle_rad: f64,
        (nedt_k, nedt_reference_k, bits, gain, offset, seed): (
            Option<f64>,
            f64,
            Option<u32>,
            f64,
            f64,
            u64,
        ),
    ) -> Result<Self> {
        if let Psf::Gaussian { sigma_px } = psf {
            if !(sigma_px.is_finite() && sigma_px > 0.0) {
                return Err(Error::invalid(
                    "psf.sigma_px",
                    format!("{sigma_px}: expected a positive width in pixels"),
                ));
            }
        }
        let mtf = match mtf {
            None => None,
            Some(m) => {
                for (name, v) in [
                    ("mtf.aperture_diameter_m", m.aperture_diameter_m),
                    ("mtf.wavelength_um", m.wavelength_um),
                ] {
                    if let Some(v) = v {
                        if !(v.is_finite() && v > 0.0) {
                            return Err(Error::invalid(
                                name,
                                format!("{v}: expected a positive value"),
                            ));
                        }
                    }
                }
                if let Some(ff) = m.fill_factor {
                    if !(ff > 0.0 && ff <= 1.0) {
                        return Err(Error::invalid(
                            "mtf.fill_factor",
                            format!("{ff}: expected a value in (0, 1]"),
                        ));
                    }
                }
                Some(MtfModel {
                    aperture_diameter_m: m.aperture_diameter_m,
                    wavelength_um: m.wavelength_um,
                    fill_factor: m.fill_factor,
                    pixel_angle_rad,
                })
            }
        };
        if let Some(n) = nedt_k {
            if !(n.is_finite() && n >= 0.0) {
                return Err(Error::invalid(
                    "nedt_k",
                    format!("{n}: expected NEdT ≥ 0 K"),
                ));
            }
        }
        if !(nedt_reference_k.is_finite() && nedt_reference_k > 0.0) {
            return Err(Error::invalid(
                "nedt_reference_k",
                format!("{nedt_reference_k}: expected a positive temperature in K"),
            ));
        }
        if let Some(b) = bits {
            if !(1..=24).contains(&b) {
                return Err(Error::invalid(
                    "bits",
                    format!("{b}: expected 1 to 24 bits"),
                ));
            }
        }
        if !(gain.is_finite() && gain > 0.0 && offset.is_finite()) {
            return Err(Error::invalid(
                "gain",
                format!("gain {gain}, offset {offset}: expected a positive gain and finite offset"),
            ));
        }
        Ok(Effects {
            psf,
            mtf,
            nedt_k,
            nedt_reference_k,
            bits,
            gain,
            offset,
            seed,
        })
    }

    /// Radiance noise σ of `band` (W·m⁻²·sr⁻¹): `NEdT · dL/dT` at the
    /// reference temperature, with the band's analytic Planck derivative;
    /// 0 without an NEdT.
    pub fn noise_sigma(&self, band: &Band) -> f64 {
        self.nedt_k.map_or(0.0, |n| {
            n * band.blackbody_radiance_derivative(self.nedt_reference_k)
        })
    }

    /// Run the chain on band number `band_index` (its noise stream) of
    /// spectral band `band`, given its oversampled radiance image
    /// (`(width·n) × (height·n)`, W·m⁻²·sr⁻¹).
    pub fn apply(
        &self,
        oversampled: &[f32],
        width: usize,
        height: usize,
        n: usize,
        band_index: usize,
        band: &Band,
    ) -> Result<BandImage> {
        let mtf = self.mtf.map(|m| m.at(band_centre_um(band)));
        self.apply_with(
            oversampled,
            width,
            height,
            n,
            band_index,
            mtf.as_ref(),
            self.noise_sigma(band),
        )
    }

    /// [`Effects::apply`] with the band's MTF and noise σ given directly.
    #[allow(clippy::too_many_arguments)]
    pub fn apply_with(
        &self,
        oversampled: &[f32],
        width: usize,
        height: usize,
        n: usize,
        band_index: usize,
        mtf: Option<&Mtf>,
        noise_sigma: f64,
    ) -> Result<BandImage> {
        let mut radiance = reduce_oversampled(oversampled, width, height, n, self.psf)?;
        if let Some(m) = mtf {
            apply_mtf(&mut radiance, width, height, m)?;
        }
        if self.nedt_k.is_some() {
            add_noise(
                &mut radiance,
                width,
                0,
                noise_sigma,
                self.seed,
                band_index as u64,
            );
        }
        let counts = self
            .bits
            .map(|b| quantise(&radiance, b, self.gain, self.offset));
        Ok(BandImage { radiance, counts })
    }
}
