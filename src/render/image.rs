//! Rendering a sensor's image: rows of primary rays → hits → radiance →
//! PSF reduction ([`render_rows`], giving a [`RowBand`]), then the
//! image-wide sensor effects and the output layers ([`finish`]).
//!
//! A [`RowBand`] holds, for a range of image rows, each band's radiance after
//! the oversampling reduction but *before* MTF, noise and quantisation, and
//! the truth layers. Row bands are what tiles store: the MTF acts on the
//! whole image, so it is applied once the bands are assembled. Every value
//! of a row band depends only on the rows it covers (and, for a Gaussian
//! PSF, the halo rows traced with it), never on the thread count or on how
//! the image is split, so tiles merge bit for bit into the single render.

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::shade::Shader;
use crate::output::ImageStack;
use crate::radiometry::Band;
use crate::sensor::{Psf, Sensor, effects};
use crate::trace::{Coherence, Hit, Ray};
use crate::{Error, Result};

/// Names of the truth layers, in output order.
pub const TRUTH_LAYERS: [&str; 6] = [
    "surface_temperature",
    "material_id",
    "object_id",
    "shape_factor",
    "sun_fraction",
    "depth",
];

/// Values written to the truth layers of pixels whose centre ray leaves the
/// scene (sky or ground beyond), in [`TRUTH_LAYERS`] order:
/// temperature 0 K, material and object id −1, shape factor 0, sun
/// fraction 0, depth 0 m. (No NaN or infinity appears in any layer.)
pub const MISS_TRUTH: [f32; 6] = [0.0, -1.0, -1.0, 0.0, 0.0, 0.0];

/// Rows of an image before the image-wide sensor effects.
#[derive(Debug, Clone, PartialEq)]
pub struct RowBand {
    /// Image width, pixels.
    pub width: usize,
    /// Full image height, pixels.
    pub height: usize,
    /// The rows held.
    pub rows: Range<usize>,
    /// Per band: radiance after the PSF reduction, W·m⁻²·sr⁻¹,
    /// `rows.len() × width`.
    pub radiance: Vec<Vec<f32>>,
    /// Truth layers ([`TRUTH_LAYERS`] order) of each pixel's centre ray.
    pub truth: Vec<Vec<f32>>,
}

impl RowBand {
    /// An empty band of rows, to be filled.
    pub fn empty(width: usize, height: usize, rows: Range<usize>, bands: usize) -> Self {
        let n = rows.len() * width;
        RowBand {
            width,
            height,
            rows,
            radiance: vec![vec![0.0; n]; bands],
            truth: vec![vec![0.0; n]; TRUTH_LAYERS.len()],
        }
    }

    /// Copy `other`'s rows into this band (which must cover them).
    pub fn paste(&mut self, other: &RowBand) -> Result<()> {
        if other.width != self.width
            || other.radiance.len() != self.radiance.len()
            || other.rows.start < self.rows.start
            || other.rows.end > self.rows.end
        {
            return Err(Error::invalid(
                "row band",
                format!(
                    "rows {:?} of width {} with {} bands do not fit rows {:?} of width {} with {} bands",
                    other.rows,
                    other.width,
                    other.radiance.len(),
                    self.rows,
                    self.width,
                    self.radiance.len()
                ),
            ));
        }
        let at = (other.rows.start - self.rows.start) * self.width;
        let n = other.rows.len() * self.width;
        for (d, s) in self
            .radiance
            .iter_mut()
            .chain(self.truth.iter_mut())
            .zip(other.radiance.iter().chain(&other.truth))
        {
            d[at..at + n].copy_from_slice(&s[..n]);
        }
        Ok(())
    }
}

/// Time spent in each stage, summed over threads.
#[derive(Debug, Default)]
pub struct StageTimes {
    ray_generation: AtomicU64,
    primary_trace: AtomicU64,
    shading: AtomicU64,
    secondary: AtomicU64,
    psf: AtomicU64,
    /// Primary rays traced.
    pub primary_rays: AtomicU64,
    /// Primary hits shaded by the spectral reference (specular or
    /// transmissive materials: secondary rays).
    pub secondary_hits: AtomicU64,
}

impl StageTimes {
    fn add(counter: &AtomicU64, d: Duration) {
        counter.fetch_add(d.as_nanos() as u64, Ordering::Relaxed);
    }
    /// Primary-ray generation, thread-seconds.
    pub fn ray_generation(&self) -> Duration {
        Duration::from_nanos(self.ray_generation.load(Ordering::Relaxed))
    }
    /// Tracing primary rays (packets), thread-seconds.
    pub fn primary_trace(&self) -> Duration {
        Duration::from_nanos(self.primary_trace.load(Ordering::Relaxed))
    }
    /// Radiometry of the primary hits and misses that spawn no secondary
    /// rays (band radiances, truth values), thread-seconds.
    pub fn shading(&self) -> Duration {
        Duration::from_nanos(self.shading.load(Ordering::Relaxed))
    }
    /// Primary hits on specular or transmissive materials: secondary-ray
    /// tracing and the spectral radiometry of those hits and of the
    /// secondary ones, thread-seconds.
    pub fn secondary(&self) -> Duration {
        Duration::from_nanos(self.secondary.load(Ordering::Relaxed))
    }
    /// PSF reduction, wall-clock.
    pub fn psf(&self) -> Duration {
        Duration::from_nanos(self.psf.load(Ordering::Relaxed))
    }
}

/// Per-thread working memory of [`trace_row`], reused from row to row.
#[derive(Default)]
struct Scratch {
    rays: Vec<Ray>,
    hits: Vec<Option<Hit>>,
    /// Indices of the hits left to the spectral reference.
    slow: Vec<usize>,
    slow_rays: Vec<Ray>,
    slow_hits: Vec<Option<Hit>>,
    spectra: Vec<f64>,
    bands: Vec<f32>,
}

/// Trace and shade image row `row`: per band the band radiance of every
/// sub-pixel ray into `radiance` (`bands × rays_per_row`, band-major), the
/// truth values of the row's pixels into `truth`.
fn trace_row(
    shader: &Shader,
    sensor: &Sensor,
    row: usize,
    times: &StageTimes,
    sc: &mut Scratch,
    radiance: &mut [f32],
    truth: &mut [[f32; 6]],
) {
    let t0 = Instant::now();
    sc.rays.clear();
    sensor.rays_for_row(row, &mut sc.rays);
    let nr = sc.rays.len();
    let t1 = Instant::now();
    sc.hits.clear();
    sc.hits.resize(nr, None);
    shader
        .tracer()
        .intersect(&sc.rays, Coherence::Coherent, &mut sc.hits);
    let t2 = Instant::now();
    let nb = shader.band_count();
    sc.bands.resize(nb, 0.0);
    sc.slow.clear();
    for (i, (ray, hit)) in sc.rays.iter().zip(&sc.hits).enumerate() {
        match hit {
            None => shader.fast_miss(ray, &mut sc.bands),
            Some(h) => {
                if shader.fast_primary(ray, h, &mut sc.bands).is_err() {
                    sc.slow.push(i);
                    continue;
                }
            }
        }
        for (b, &v) in sc.bands.iter().enumerate() {
            radiance[b * nr + i] = v;
        }
    }
    // Truth of each pixel's centre sub-ray (sub-row and sub-column ⌊N/2⌋).
    let n = sensor.oversample();
    let ws = sensor.width() * n;
    let s = &shader.conditions().surface;
    let optics = shader.optics();
    for (col, t) in truth.iter_mut().enumerate() {
        let k = (n / 2) * ws + col * n + n / 2;
        *t = match &sc.hits[k] {
            None => MISS_TRUTH,
            Some(h) => {
                let f = shader.facet_of(h);
                let m = &optics.materials[optics.facet_material[f] as usize];
                let depth = h.t * sc.rays[k].dir.length();
                [
                    s.temperature_k[f],
                    m.id as f32,
                    optics.facet_object[f] as f32,
                    s.shape_factor[f],
                    s.sun_fraction[f],
                    if depth.is_finite() { depth } else { 0.0 },
                ]
            }
        };
    }
    let t3 = Instant::now();
    // Hits with secondary rays (or off the Planck table): the spectral
    // reference.
    if !sc.slow.is_empty() {
        sc.slow_rays.clear();
        sc.slow_hits.clear();
        for &i in &sc.slow {
            sc.slow_rays.push(sc.rays[i]);
            sc.slow_hits.push(sc.hits[i]);
        }
        let nl = shader.spectrum_len();
        sc.spectra.clear();
        sc.spectra.resize(sc.slow.len() * nl, 0.0);
        shader.shade_primary(&sc.slow_rays, &sc.slow_hits, &mut sc.spectra);
        for (&i, spectrum) in sc.slow.iter().zip(sc.spectra.chunks_exact(nl)) {
            for b in 0..nb {
                radiance[b * nr + i] = shader.band_radiance(b, spectrum) as f32;
            }
        }
    }
    let t4 = Instant::now();
    StageTimes::add(&times.ray_generation, t1 - t0);
    StageTimes::add(&times.primary_trace, t2 - t1);
    StageTimes::add(&times.shading, t3 - t2);
    StageTimes::add(&times.secondary, t4 - t3);
    times.primary_rays.fetch_add(nr as u64, Ordering::Relaxed);
    times
        .secondary_hits
        .fetch_add(sc.slow.len() as u64, Ordering::Relaxed);
}

/// Render image rows `rows` of `sensor`: trace and shade the primary rays of
/// those rows (plus the PSF's halo rows), band-integrate, and reduce the
/// oversampled radiance with the PSF. `progress` is called with the number
/// of rows finished (from worker threads).
pub fn render_rows(
    shader: &Shader,
    sensor: &Sensor,
    rows: Range<usize>,
    times: &StageTimes,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RowBand> {
    let (w, h, n) = (sensor.width(), sensor.height(), sensor.oversample());
    if rows.start >= rows.end || rows.end > h {
        return Err(Error::invalid(
            "rows",
            format!("{rows:?}: expected a non-empty range within 0..{h}"),
        ));
    }
    let nb = shader.band_count();
    if nb != sensor.bands.len() {
        return Err(Error::invalid(
            "bands",
            format!(
                "{} bands shaded for a sensor with {}",
                shader.band_count(),
                sensor.bands.len()
            ),
        ));
    }
    let psf = sensor.effects.psf;
    let halo = psf.halo_px();
    let traced = rows.start.saturating_sub(halo)..(rows.end + halo).min(h);
    let ws = w * n;
    // One image row: n sub-rows of ws sub-pixels, per band.
    let per_row = n * ws;
    let mut over = vec![0.0f32; traced.len() * nb * per_row];
    let mut truth = vec![[0.0f32; 6]; traced.len() * w];
    over.par_chunks_mut(nb * per_row)
        .zip(truth.par_chunks_mut(w))
        .enumerate()
        .for_each_init(Scratch::default, |sc, (i, (radiance, truth))| {
            trace_row(shader, sensor, traced.start + i, times, sc, radiance, truth);
            progress(1);
        });
    let t0 = Instant::now();
    let mut band = RowBand::empty(w, h, rows.clone(), nb);
    let band_rows = |b: usize| {
        over.chunks_exact(nb * per_row)
            .map(move |r| &r[b * per_row..(b + 1) * per_row])
    };
    for b in 0..nb {
        let reduced = match psf {
            // Box weights do not depend on the position in the image:
            // reduce each row in place, with the sums of
            // `effects::reduce_oversampled` in its order (along x, then
            // along y, weights 1/n, in f64), so the values are the same.
            Psf::Box => {
                let wgt = 1.0 / n as f64;
                let skip = rows.start - traced.start;
                band.radiance[b]
                    .par_chunks_mut(w)
                    .zip(over.par_chunks(nb * per_row).skip(skip))
                    .for_each(|(out, src)| {
                        let src = &src[b * per_row..(b + 1) * per_row];
                        for (x, o) in out.iter_mut().enumerate() {
                            let mut y_sum = 0.0f64;
                            for sub in src.chunks_exact(ws) {
                                let px = &sub[x * n..(x + 1) * n];
                                let x_sum: f64 = px.iter().map(|&v| wgt * v as f64).sum();
                                y_sum += wgt * x_sum;
                            }
                            *o = y_sum as f32;
                        }
                    });
                continue;
            }
            // Other PSFs: place the traced rows in a full-height image so
            // every weight is computed exactly as in a full render.
            _ => {
                let mut img = vec![0.0f32; h * per_row];
                for (src, r) in band_rows(b).zip(traced.clone()) {
                    img[r * per_row..(r + 1) * per_row].copy_from_slice(src);
                }
                let full = effects::reduce_oversampled(&img, w, h, n, psf)?;
                full[traced.start * w..traced.end * w].to_vec()
            }
        };
        let skip = (rows.start - traced.start) * w;
        band.radiance[b].copy_from_slice(&reduced[skip..skip + rows.len() * w]);
    }
    let skip = (rows.start - traced.start) * w;
    for (i, t) in truth[skip..skip + rows.len() * w].iter().enumerate() {
        for (l, v) in t.iter().enumerate() {
            band.truth[l][i] = *v;
        }
    }
    StageTimes::add(&times.psf, t0.elapsed());
    Ok(band)
}

/// A finished image: the layers and the ENVI wavelengths of its band
/// radiance layers.
#[derive(Debug, Clone, PartialEq)]
pub struct Finished {
    /// All layers: per band `NAME_radiance` (and `NAME_counts` when
    /// quantised), `apparent_temperature` (band 0) and
    /// `NAME_apparent_temperature` (other bands), then the truth layers.
    pub stack: ImageStack,
    /// The band radiance layers alone (for ENVI).
    pub radiance: ImageStack,
    /// Response-weighted centre wavelength of each band, µm.
    pub wavelengths_um: Vec<f64>,
}

/// Brightness temperature of band radiance `l`, K; 0 for a non-positive or
/// non-finite radiance (documented sentinel; no NaN in outputs).
pub fn apparent_temperature(band: &Band, l: f32) -> f32 {
    if !(l.is_finite() && l > 0.0) {
        return 0.0;
    }
    band.brightness_temperature(l as f64)
        .map(|t| t as f32)
        .unwrap_or(0.0)
}

/// Temperature step of the inversion table of [`apparent_temperatures`], K.
const INVERSION_STEP_K: f64 = 0.05;

/// Brightness temperatures of many band radiances: exact inversion at the
/// extremes, then a table of the band's blackbody radiance every
/// [`INVERSION_STEP_K`] between them, inverted by linear interpolation
/// (error ≤ h²/8 · L''(T)/L'(T) < 3·10⁻⁵ K for h = 0.05 K at 3–14 µm and
/// 200–400 K: the curvature of T(L) over one step). Non-positive or
/// non-finite radiances give 0 (as [`apparent_temperature`]).
pub fn apparent_temperatures(band: &Band, radiance: &[f32]) -> Vec<f32> {
    let (lo, hi) = radiance
        .iter()
        .filter(|v| v.is_finite() && **v > 0.0)
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return vec![0.0; radiance.len()];
    }
    let (t_lo, t_hi) = (
        apparent_temperature(band, lo),
        apparent_temperature(band, hi),
    );
    let nodes = ((t_hi - t_lo) as f64 / INVERSION_STEP_K).ceil() as usize + 3;
    if t_lo <= 0.0 || nodes > 200_000 {
        return radiance
            .par_iter()
            .map(|&v| apparent_temperature(band, v))
            .collect();
    }
    let t0 = t_lo as f64 - INVERSION_STEP_K;
    let temps: Vec<f64> = (0..nodes)
        .map(|k| t0 + k as f64 * INVERSION_STEP_K)
        .collect();
    let table: Vec<f64> = temps
        .par_iter()
        .map(|&t| band.blackbody_radiance(t))
        .collect();
    // Where to start looking: for `nodes` equal steps of radiance from
    // table[0], the partition point of the step's radiance (a short scan
    // from there finds the same node as a binary search over the table).
    let (l0, l_end) = (table[0], table[nodes - 1]);
    let dl = (l_end - l0) / nodes as f64;
    let start: Vec<usize> = (0..=nodes)
        .map(|j| table.partition_point(|&x| x <= l0 + j as f64 * dl))
        .collect();
    radiance
        .par_iter()
        .map(|&v| {
            if !(v.is_finite() && v > 0.0) {
                return 0.0;
            }
            let v = v as f64;
            let j = if dl > 0.0 {
                (((v - l0) / dl).max(0.0) as usize).min(nodes)
            } else {
                0
            };
            let i = if l0 + j as f64 * dl <= v {
                // start[j] is the partition point of a radiance ≤ v: scan up.
                let mut i = start[j];
                while i < nodes && table[i] <= v {
                    i += 1;
                }
                i
            } else {
                table.partition_point(|&x| x <= v)
            };
            let i = i.clamp(1, nodes - 1);
            let f = (v - table[i - 1]) / (table[i] - table[i - 1]);
            (temps[i - 1] + f * INVERSION_STEP_K) as f32
        })
        .collect()
}

/// Apply the image-wide sensor effects to a complete [`RowBand`] (MTF, then
/// NEdT noise with `seed`, then quantisation) and build the output layers.
pub fn finish(full: &RowBand, sensor: &Sensor, bands: &[Band], seed: u64) -> Result<Finished> {
    let (w, h) = (full.width, full.height);
    if full.rows != (0..h) || bands.len() != full.radiance.len() {
        return Err(Error::invalid(
            "image",
            format!(
                "rows {:?} of {h} with {} bands: expected all rows and {} bands",
                full.rows,
                full.radiance.len(),
                bands.len()
            ),
        ));
    }
    let fx = &sensor.effects;
    let mut stack = ImageStack::new(w, h);
    let mut radiance_stack = ImageStack::new(w, h);
    let mut temps = Vec::new();
    for (b, (band, cfg)) in bands.iter().zip(&sensor.bands).enumerate() {
        let mut l = full.radiance[b].clone();
        if let Some(m) = &fx.mtf {
            effects::apply_mtf(&mut l, w, h, &m.at(effects::band_centre_um(band)))?;
        }
        if fx.nedt_k.is_some() {
            effects::add_noise(&mut l, w, 0, fx.noise_sigma(band), seed, b as u64);
        }
        let t = apparent_temperatures(band, &l);
        let counts = fx
            .bits
            .map(|bits| effects::quantise(&l, bits, fx.gain, fx.offset));
        radiance_stack.push(format!("{}_radiance", cfg.name), l.clone())?;
        stack.push(format!("{}_radiance", cfg.name), l)?;
        if let Some(c) = counts {
            stack.push(format!("{}_counts", cfg.name), c)?;
        }
        temps.push((cfg.name.clone(), t));
    }
    for (b, (name, t)) in temps.into_iter().enumerate() {
        let layer = if b == 0 {
            "apparent_temperature".to_string()
        } else {
            format!("{name}_apparent_temperature")
        };
        stack.push(layer, t)?;
    }
    for (name, v) in TRUTH_LAYERS.iter().zip(&full.truth) {
        stack.push(*name, v.clone())?;
    }
    for l in &stack.layers {
        // A branch-free scan in parallel; the value is looked up only when
        // there is one.
        let bad = l
            .data
            .par_chunks(1 << 16)
            .any(|c| c.iter().fold(false, |acc, v| acc | !v.is_finite()));
        if let Some(v) = l.data.iter().find(|v| bad && !v.is_finite()) {
            return Err(Error::Other(format!(
                "layer `{}` of sensor `{}` has a non-finite value ({v}): refusing to write it",
                l.name, sensor.name
            )));
        }
    }
    Ok(Finished {
        stack,
        radiance: radiance_stack,
        wavelengths_um: bands.iter().map(effects::band_centre_um).collect(),
    })
}
