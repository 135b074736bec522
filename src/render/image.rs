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

use super::shade::{FastScratch, Shader, TruthOut};
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
/// fraction 0, depth 0 m. (No NaN or infinity appears in these layers; the
/// opt-in geolocation layers, [`crate::sensor::GeoLayer`], are NaN there.)
pub const MISS_TRUTH: [f32; 6] = [0.0, -1.0, -1.0, 0.0, 0.0, 0.0];

/// Rows of an image before the image-wide sensor effects.
///
/// Every value is finite: the constructors check it ([`RowBand::new`]
/// names the layer, row and column of the first that is not;
/// [`render_rows`] checks each row as it is shaded), and the fields are
/// read-only outside this module, so [`finish`] need not scan the layers
/// again.
#[derive(Debug, Clone, PartialEq)]
pub struct RowBand {
    /// Image width, pixels.
    width: usize,
    /// Full image height, pixels.
    height: usize,
    /// The rows held.
    rows: Range<usize>,
    /// Per band: radiance after the PSF reduction, W·m⁻²·sr⁻¹,
    /// `rows.len() × width`.
    radiance: Vec<Vec<f32>>,
    /// Truth layers ([`TRUTH_LAYERS`] order) of each pixel's centre ray.
    truth: Vec<Vec<f32>>,
    /// Scene x, y, z (m) of each pixel's centre-ray hit, NaN where it
    /// misses ([`POINT_LAYERS`]); empty unless the sensor asks for
    /// geolocation layers.
    points: Vec<Vec<f32>>,
}

/// Names of the hit-point layers of a [`RowBand`] (scene x, y, z, m) as
/// tiles store them.
pub const POINT_LAYERS: [&str; 3] = ["hit_x", "hit_y", "hit_z"];

/// The first non-finite value of `data` (rows of `width`, the first being
/// image row `row0`) as (row, column, value); a branch-free scan first.
fn first_non_finite(data: &[f32], width: usize, row0: usize) -> Option<(usize, usize, f32)> {
    if !data.iter().fold(false, |acc, v| acc | !v.is_finite()) {
        return None;
    }
    let i = data.iter().position(|v| !v.is_finite())?;
    let w = width.max(1);
    Some((row0 + i / w, i % w, data[i]))
}

/// The error for a non-finite value of layer `layer` at (`row`, `col`).
fn non_finite_error(what: &str, layer: &str, (row, col, v): (usize, usize, f32)) -> Error {
    Error::Other(format!(
        "{what}: layer `{layer}` has a non-finite value ({v}) at row {row}, column {col}"
    ))
}

impl RowBand {
    /// Rows `rows` of a `width × height` image from their layers: per band
    /// the radiance (W·m⁻²·sr⁻¹) and the [`TRUTH_LAYERS`], each
    /// `rows.len() × width` values. `what` names the source in errors (a
    /// file, say). Errors on a wrong layer count or size and on any
    /// non-finite value (naming the layer, row and column).
    pub fn new(
        what: &str,
        width: usize,
        height: usize,
        rows: Range<usize>,
        radiance: Vec<Vec<f32>>,
        truth: Vec<Vec<f32>>,
    ) -> Result<Self> {
        if rows.start > rows.end || rows.end > height {
            return Err(Error::invalid(
                what,
                format!("rows {rows:?}: expected a range within 0..{height}"),
            ));
        }
        if truth.len() != TRUTH_LAYERS.len() {
            return Err(Error::invalid(
                what,
                format!(
                    "{} truth layers: expected {} ({})",
                    truth.len(),
                    TRUTH_LAYERS.len(),
                    TRUTH_LAYERS.join(", ")
                ),
            ));
        }
        let n = rows.len() * width;
        let names = (0..radiance.len())
            .map(|b| format!("band {b} radiance"))
            .chain(TRUTH_LAYERS.iter().map(|s| s.to_string()));
        for (name, l) in names.zip(radiance.iter().chain(&truth)) {
            if l.len() != n {
                return Err(Error::invalid(
                    what,
                    format!(
                        "layer `{name}` has {} values: expected {n} ({} rows of {width})",
                        l.len(),
                        rows.len()
                    ),
                ));
            }
            if let Some(bad) = first_non_finite(l, width, rows.start) {
                return Err(non_finite_error(what, &name, bad));
            }
        }
        Ok(RowBand {
            width,
            height,
            rows,
            radiance,
            truth,
            points: Vec::new(),
        })
    }

    /// This band with the hit points of its pixels ([`POINT_LAYERS`]: x,
    /// y, z in m, NaN where the centre ray misses), `rows().len() × width()`
    /// values each.
    pub fn with_points(mut self, points: Vec<Vec<f32>>) -> Result<Self> {
        let n = self.rows.len() * self.width;
        if points.len() != POINT_LAYERS.len() || points.iter().any(|l| l.len() != n) {
            return Err(Error::invalid(
                "hit points",
                format!(
                    "{} layers: expected {} ({}) of {n} values",
                    points.len(),
                    POINT_LAYERS.len(),
                    POINT_LAYERS.join(", ")
                ),
            ));
        }
        self.points = points;
        Ok(self)
    }

    /// Hit points ([`POINT_LAYERS`]) of each pixel's centre ray, if kept.
    pub fn points(&self) -> &[Vec<f32>] {
        &self.points
    }

    /// Image width, pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Full image height, pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The image rows held.
    pub fn rows(&self) -> Range<usize> {
        self.rows.clone()
    }

    /// Per band: radiance after the PSF reduction, W·m⁻²·sr⁻¹,
    /// `rows().len() × width()` values.
    pub fn radiance(&self) -> &[Vec<f32>] {
        &self.radiance
    }

    /// Truth layers ([`TRUTH_LAYERS`] order) of each pixel's centre ray.
    pub fn truth(&self) -> &[Vec<f32>] {
        &self.truth
    }

    /// An empty band of rows, to be filled.
    pub fn empty(width: usize, height: usize, rows: Range<usize>, bands: usize) -> Self {
        Self::empty_with(width, height, rows, bands, false)
    }

    /// An empty band of rows, with hit-point layers if `points`.
    pub fn empty_with(
        width: usize,
        height: usize,
        rows: Range<usize>,
        bands: usize,
        points: bool,
    ) -> Self {
        let n = rows.len() * width;
        let layers = |k: usize| (0..k).map(|_| zeros(n)).collect();
        RowBand {
            width,
            height,
            rows,
            radiance: layers(bands),
            truth: layers(TRUTH_LAYERS.len()),
            points: if points {
                layers(POINT_LAYERS.len())
            } else {
                Vec::new()
            },
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
        if other.points.is_empty() != self.points.is_empty() {
            return Err(Error::invalid(
                "row band",
                format!(
                    "rows {:?} {} hit points, rows {:?} {}",
                    other.rows,
                    if other.points.is_empty() {
                        "lack"
                    } else {
                        "have"
                    },
                    self.rows,
                    if self.points.is_empty() {
                        "do not"
                    } else {
                        "do"
                    },
                ),
            ));
        }
        let at = (other.rows.start - self.rows.start) * self.width;
        let n = other.rows.len() * self.width;
        for (d, s) in self
            .radiance
            .iter_mut()
            .chain(self.truth.iter_mut())
            .chain(self.points.iter_mut())
            .zip(
                other
                    .radiance
                    .iter()
                    .chain(&other.truth)
                    .chain(&other.points),
            )
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
    reduction: AtomicU64,
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
    /// The box PSF's reduction of the oversampling, done row by row as the
    /// rows are shaded, thread-seconds.
    pub fn reduction(&self) -> Duration {
        Duration::from_nanos(self.reduction.load(Ordering::Relaxed))
    }
    /// PSF reduction after the row loop (PSFs reaching into neighbouring
    /// rows), wall-clock.
    pub fn psf(&self) -> Duration {
        Duration::from_nanos(self.psf.load(Ordering::Relaxed))
    }
}

/// Per-thread working memory of [`trace_row`], reused from row to row.
#[derive(Default)]
struct Scratch {
    rays: Vec<Ray>,
    hits: Vec<Option<Hit>>,
    /// Band radiance of every sub-pixel ray of the row, band-major.
    radiance: Vec<f32>,
    /// Indices of the hits left to the spectral reference.
    slow: Vec<usize>,
    slow_rays: Vec<Ray>,
    slow_hits: Vec<Option<Hit>>,
    spectra: Vec<f64>,
    fast: FastScratch,
}

/// Trace and shade image row `row`: per band the band radiance of every
/// sub-pixel ray into `sc.radiance` (`bands × rays_per_row`, band-major),
/// the truth values of the row's pixels into `truth` (one row slice per
/// layer, [`TRUTH_LAYERS`] order), and, if `points` is not empty, the hit
/// point of each pixel's centre ray ([`POINT_LAYERS`]).
fn trace_row(
    shader: &Shader,
    sensor: &Sensor,
    row: usize,
    times: &StageTimes,
    sc: &mut Scratch,
    truth: &mut [&mut [f32]],
    points: &mut [&mut [f32]],
) {
    let t0 = Instant::now();
    sc.rays.clear();
    sensor.rays_for_row(row, &mut sc.rays);
    let nr = sc.rays.len();
    let t1 = Instant::now();
    // Every element is written by the tracer (`Tracer::intersect`): no
    // clearing between rows.
    sc.hits.resize(nr, None);
    shader
        .tracer()
        .intersect(&sc.rays, Coherence::Coherent, &mut sc.hits);
    let t2 = Instant::now();
    let nb = shader.band_count();
    sc.radiance.resize(nb * nr, 0.0);
    sc.slow.clear();
    let radiance = &mut sc.radiance;
    // Truth of each pixel's centre sub-ray (sub-row and sub-column ⌊N/2⌋),
    // written as the hits are shaded.
    let n = sensor.oversample();
    let ws = sensor.width() * n;
    if let [px, py, pz] = points {
        let first = (n / 2) * ws + n / 2;
        for col in 0..sensor.width() {
            let i = first + col * n;
            let p = match sc.hits[i] {
                Some(h) => {
                    let r = &sc.rays[i];
                    let p = r.origin.as_dvec3() + r.dir.as_dvec3() * h.t as f64;
                    [p.x as f32, p.y as f32, p.z as f32]
                }
                None => [f32::NAN; 3],
            };
            (px[col], py[col], pz[col]) = (p[0], p[1], p[2]);
        }
    }
    let truth = TruthOut {
        first: (n / 2) * ws + n / 2,
        stride: n,
        layers: truth,
    };
    shader.shade_fast(
        &sc.rays,
        &sc.hits,
        radiance,
        &mut sc.slow,
        &mut sc.fast,
        Some(truth),
    );
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

/// The box PSF's reduction of one image row: pixel `x` of `out` is the
/// mean of its `n × n` sub-samples in `src` (`n` sub-rows of `out.len()·n`
/// values), summed along x then along y with weights `1/n` in f64 — the
/// sums of `effects::reduce_oversampled` in its order, so the values are
/// the same.
fn box_reduce_row(src: &[f32], n: usize, out: &mut [f32]) {
    let ws = out.len() * n;
    let wgt = 1.0 / n as f64;
    if n == 1 {
        // wgt = 1: each sum is the value itself.
        out.copy_from_slice(&src[..ws]);
        return;
    }
    if n == 2 {
        // The same sums, written out for the common 2×2 oversampling.
        let (r0, r1) = (&src[..ws], &src[ws..2 * ws]);
        for ((o, a), b) in out
            .iter_mut()
            .zip(r0.chunks_exact(2))
            .zip(r1.chunks_exact(2))
        {
            let xa = wgt * a[0] as f64 + wgt * a[1] as f64;
            let xb = wgt * b[0] as f64 + wgt * b[1] as f64;
            *o = (wgt * xa + wgt * xb) as f32;
        }
        return;
    }
    for (x, o) in out.iter_mut().enumerate() {
        let mut y_sum = 0.0f64;
        for sub in src.chunks_exact(ws) {
            let px = &sub[x * n..(x + 1) * n];
            let x_sum: f64 = px.iter().map(|&v| wgt * v as f64).sum();
            y_sum += wgt * x_sum;
        }
        *o = y_sum as f32;
    }
}

/// `n` zeros, written by every thread: filled on one thread, an image's
/// layers (tens of MB) would hold up the row loop that follows them
/// (about 1 ms for 1 M pixels).
fn zeros(n: usize) -> Vec<f32> {
    let mut v = Vec::with_capacity(n);
    v.par_extend(rayon::iter::repeat_n(0.0f32, n));
    v
}

/// Check that the row just shaded is finite: per band the radiance
/// (`width` values per sub-row), and the truth values of its pixels; the
/// error names the sensor, layer, row and column. The values are in cache:
/// this is what lets [`finish`] skip a scan of the whole image.
fn check_row<'a>(
    sensor: &Sensor,
    row: usize,
    width: usize,
    radiance: impl Iterator<Item = &'a [f32]>,
    truth: &[&mut [f32]],
) -> Result<()> {
    for (b, l) in radiance.enumerate() {
        if let Some((_, col, v)) = first_non_finite(l, width, 0) {
            let name = format!("{}_radiance", sensor.bands[b].name);
            let what = format!("sensor `{}`", sensor.name);
            return Err(non_finite_error(&what, &name, (row, col, v)));
        }
    }
    for (name, l) in TRUTH_LAYERS.iter().zip(truth) {
        if let Some((_, col, v)) = first_non_finite(l, l.len(), 0) {
            let what = format!("sensor `{}`", sensor.name);
            return Err(non_finite_error(&what, name, (row, col, v)));
        }
    }
    Ok(())
}

/// [`rows_of`] for the hit-point layers, which may be absent: then `rows`
/// empty rows.
fn point_rows(layers: &mut [Vec<f32>], width: usize, rows: usize) -> Vec<Vec<&mut [f32]>> {
    if layers.is_empty() {
        (0..rows).map(|_| Vec::new()).collect()
    } else {
        rows_of(layers, width)
    }
}

/// Split each layer of `layers` into rows of `width` and regroup them per
/// row: element `r` holds row `r` of every layer, in layer order.
fn rows_of(layers: &mut [Vec<f32>], width: usize) -> Vec<Vec<&mut [f32]>> {
    let rows = layers.first().map_or(0, |l| l.len() / width.max(1));
    let mut out: Vec<Vec<&mut [f32]>> = (0..rows)
        .map(|_| Vec::with_capacity(layers.len()))
        .collect();
    for layer in layers.iter_mut() {
        for (o, r) in out.iter_mut().zip(layer.chunks_exact_mut(width)) {
            o.push(r);
        }
    }
    out
}

/// Render image rows `rows` of `sensor`: trace and shade the primary rays of
/// those rows (plus the PSF's halo rows), band-integrate, and reduce the
/// oversampled radiance with the PSF. `progress` is called with the number
/// of rows finished (from worker threads).
///
/// With the box PSF (no halo) each row is reduced by the thread that shaded
/// it, straight into the output; other PSFs keep the oversampled rows and
/// reduce the image after the loop.
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
    let with_points = !sensor.geo_layers.is_empty();
    let ws = w * n;
    // One image row: n sub-rows of ws sub-pixels, per band.
    let per_row = n * ws;
    if let Psf::Box = psf {
        let mut band = RowBand::empty_with(w, h, rows.clone(), nb, with_points);
        let radiance_rows = rows_of(&mut band.radiance, w);
        let truth_rows = rows_of(&mut band.truth, w);
        let point_rows = point_rows(&mut band.points, w, rows.len());
        radiance_rows
            .into_par_iter()
            .zip(truth_rows)
            .zip(point_rows)
            .enumerate()
            .try_for_each_init(
                Scratch::default,
                |sc, (i, ((mut out, mut truth), mut pts))| {
                    let row = rows.start + i;
                    trace_row(shader, sensor, row, times, sc, &mut truth, &mut pts);
                    let t0 = Instant::now();
                    for (b, o) in out.iter_mut().enumerate() {
                        box_reduce_row(&sc.radiance[b * per_row..(b + 1) * per_row], n, o);
                    }
                    let checked = check_row(sensor, row, w, out.iter().map(|o| &**o), &truth);
                    StageTimes::add(&times.reduction, t0.elapsed());
                    progress(1);
                    checked
                },
            )?;
        return Ok(band);
    }
    let traced = rows.start.saturating_sub(halo)..(rows.end + halo).min(h);
    let mut over = zeros(traced.len() * nb * per_row);
    let mut truth: Vec<Vec<f32>> = (0..TRUTH_LAYERS.len())
        .map(|_| zeros(traced.len() * w))
        .collect();
    let mut points: Vec<Vec<f32>> = if with_points {
        (0..POINT_LAYERS.len())
            .map(|_| zeros(traced.len() * w))
            .collect()
    } else {
        Vec::new()
    };
    over.par_chunks_mut(nb * per_row)
        .zip(rows_of(&mut truth, w))
        .zip(point_rows(&mut points, w, traced.len()))
        .enumerate()
        .try_for_each_init(
            Scratch::default,
            |sc, (i, ((radiance, mut truth), mut pts))| {
                let row = traced.start + i;
                trace_row(shader, sensor, row, times, sc, &mut truth, &mut pts);
                radiance.copy_from_slice(&sc.radiance);
                progress(1);
                // The oversampled radiance (n sub-rows of w·n per band): the
                // PSF's weighted sums of finite values are finite.
                check_row(sensor, row, w * n, radiance.chunks_exact(per_row), &truth)
            },
        )?;
    let t0 = Instant::now();
    let mut band = RowBand::empty_with(w, h, rows.clone(), nb, with_points);
    let skip = (rows.start - traced.start) * w;
    for b in 0..nb {
        // Place the traced rows in a full-height image so every weight is
        // computed exactly as in a full render.
        let mut img = vec![0.0f32; h * per_row];
        for (src, r) in over.chunks_exact(nb * per_row).zip(traced.clone()) {
            img[r * per_row..(r + 1) * per_row]
                .copy_from_slice(&src[b * per_row..(b + 1) * per_row]);
        }
        let full = effects::reduce_oversampled(&img, w, h, n, psf)?;
        let reduced = &full[traced.start * w..traced.end * w];
        band.radiance[b].copy_from_slice(&reduced[skip..skip + rows.len() * w]);
    }
    for (d, s) in band
        .truth
        .iter_mut()
        .zip(&truth)
        .chain(band.points.iter_mut().zip(&points))
    {
        d.copy_from_slice(&s[skip..skip + rows.len() * w]);
    }
    StageTimes::add(&times.psf, t0.elapsed());
    Ok(band)
}

/// A finished image: the layers and, for ENVI, which of them are the band
/// radiances and their wavelengths.
#[derive(Debug, Clone, PartialEq)]
pub struct Finished {
    /// All layers: per band `NAME_radiance` (and `NAME_counts` when
    /// quantised), `apparent_temperature` (band 0) and
    /// `NAME_apparent_temperature` (other bands), then the truth layers and
    /// the sensor's geolocation layers, laid out in its orientation.
    pub stack: ImageStack,
    /// Names of the band radiance layers of `stack`, in band order (the
    /// ENVI bands).
    pub radiance_layers: Vec<String>,
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
const INVERSION_STEP_K: f64 = 1.0;

/// Brightness temperatures of many band radiances: exact inversion at the
/// extremes, then a table of the band's blackbody radiance `L_k` and its
/// derivative `dL/dT` every [`INVERSION_STEP_K`] between them, inverted by
/// cubic Hermite interpolation of T(L) (slopes `dT/dL = 1/(dL/dT)` at the
/// nodes; error O(h⁴): < 10⁻⁶ K at 3–14 µm and 200–400 K, checked against
/// the exact inversion in `tests/render.rs`). Non-positive or non-finite
/// radiances give 0 (as [`apparent_temperature`]).
pub fn apparent_temperatures(band: &Band, radiance: &[f32]) -> Vec<f32> {
    // Extremes of the positive finite radiances, branch-free on the bits:
    // a positive finite f32 is a bit pattern in (0, 0x7f80_0000) read as
    // i32, and those order as the values do (vectorises).
    let (lo, hi) = radiance
        .par_chunks(1 << 14)
        .map(|c| {
            let mut lo = [i32::MAX; 8];
            let mut hi = [0i32; 8];
            let mut lanes = c.chunks_exact(8);
            let mut take = |k: usize, v: f32| {
                let b = v.to_bits() as i32;
                let ok = (b > 0) & (b < 0x7f80_0000);
                lo[k] = lo[k].min(if ok { b } else { i32::MAX });
                hi[k] = hi[k].max(if ok { b } else { 0 });
            };
            for x in &mut lanes {
                for (k, &v) in x.iter().enumerate() {
                    take(k, v);
                }
            }
            for (k, &v) in lanes.remainder().iter().enumerate() {
                take(k, v);
            }
            (
                lo.iter().fold(i32::MAX, |a, &v| a.min(v)),
                hi.iter().fold(0, |a, &v| a.max(v)),
            )
        })
        .reduce(|| (i32::MAX, 0), |(a, b), (c, d)| (a.min(c), b.max(d)));
    let (lo, hi) = if lo == i32::MAX {
        (f32::INFINITY, f32::NEG_INFINITY)
    } else {
        (f32::from_bits(lo as u32), f32::from_bits(hi as u32))
    };
    if !lo.is_finite() {
        return vec![0.0; radiance.len()];
    }
    let (t_lo, t_hi) = (
        apparent_temperature(band, lo),
        apparent_temperature(band, hi),
    );
    let nodes = ((t_hi - t_lo) as f64 / INVERSION_STEP_K).ceil() as usize + 3;
    if t_lo <= 2.0 * INVERSION_STEP_K as f32 || nodes > 200_000 {
        return radiance
            .par_iter()
            .map(|&v| apparent_temperature(band, v))
            .collect();
    }
    let t0 = t_lo as f64 - INVERSION_STEP_K;
    let temps: Vec<f64> = (0..nodes)
        .map(|k| t0 + k as f64 * INVERSION_STEP_K)
        .collect();
    let (table, slope): (Vec<f64>, Vec<f64>) = temps
        .par_iter()
        .map(|&t| {
            (
                band.blackbody_radiance(t),
                1.0 / band.blackbody_radiance_derivative(t),
            )
        })
        .unzip();
    // The node interval of a radiance: from the partition point of the
    // lower edge of its step among `m` equal steps of radiance from
    // table[0] (steps much finer than the nodes: the scan rarely moves;
    // where nodes crowd a step it still finds the node a binary search
    // would).
    let (l0, l_end) = (table[0], table[nodes - 1]);
    let steps = |m: usize| {
        let dl = (l_end - l0) / m as f64;
        (dl, if dl > 0.0 { 1.0 / dl } else { 0.0 })
    };
    let m = (nodes * 64).clamp(4096, 1 << 18);
    let (dl, inv_dl) = steps(m);
    let start: Vec<u32> = (0..=m)
        .map(|j| table.partition_point(|&x| x <= l0 + j as f64 * dl) as u32)
        .collect();
    let inv_d: Vec<f64> = (0..nodes)
        .map(|i| {
            if i == 0 {
                0.0
            } else {
                1.0 / (table[i] - table[i - 1])
            }
        })
        .collect();
    // T(v) by cubic Hermite over the node interval of v.
    let hermite = |v: f64| -> f64 {
        let j = (((v - l0) * inv_dl).max(0.0) as usize).min(m);
        let mut i = start[j] as usize;
        while i < nodes && table[i] <= v {
            i += 1;
        }
        let i = i.clamp(1, nodes - 1);
        let d = table[i] - table[i - 1];
        let s = (v - table[i - 1]) * inv_d[i];
        let (s2, s3) = (s * s, s * s * s);
        (2.0 * s3 - 3.0 * s2 + 1.0) * temps[i - 1]
            + (s3 - 2.0 * s2 + s) * d * slope[i - 1]
            + (3.0 * s2 - 2.0 * s3) * temps[i]
            + (s3 - s2) * d * slope[i]
    };
    // Where T(L) is flat enough, a table of T on equal radiance steps,
    // interpolated linearly: no search per pixel. Its error, |T''|·ΔL²/8,
    // is largest mid-step; the steps are refined until the Hermite value
    // there differs from the linear one by < 10⁻⁵ K, else (radiances over
    // decades) the Hermite interpolation is used for every pixel.
    // Each step is stored as its first value and its rise, so a pixel
    // reads one entry.
    let uniform = [1usize << 12, 1 << 14, 1 << 16].into_iter().find_map(|m| {
        let (dl, inv_dl) = steps(m);
        let t: Vec<f64> = (0..=m)
            .into_par_iter()
            .map(|j| hermite(l0 + j as f64 * dl))
            .collect();
        let flat = (0..m)
            .into_par_iter()
            .all(|j| (hermite(l0 + (j as f64 + 0.5) * dl) - 0.5 * (t[j] + t[j + 1])).abs() < 1e-5);
        flat.then(|| {
            let segs: Vec<[f64; 2]> = t.windows(2).map(|w| [w[0], w[1] - w[0]]).collect();
            (inv_dl, segs)
        })
    });
    // Chunks with the choice of interpolation made once per chunk, so the
    // inner loops are plain (no per-value dispatch or collection).
    let mut out = zeros(radiance.len());
    out.par_chunks_mut(1 << 14)
        .zip(radiance.par_chunks(1 << 14))
        .for_each(|(o, r)| match &uniform {
            Some((inv_dl, segs)) => {
                let last = (segs.len() - 1) as f64;
                for (o, &v) in o.iter_mut().zip(r) {
                    // In [0, last] (NaN: 0): the index is in bounds.
                    let x = ((v as f64 - l0) * inv_dl).max(0.0);
                    let j = x.min(last) as usize;
                    let [t0, dt] = segs[j];
                    let tv = (t0 + (x - j as f64) * dt) as f32;
                    *o = if v.is_finite() && v > 0.0 { tv } else { 0.0 };
                }
            }
            None => {
                for (o, &v) in o.iter_mut().zip(r) {
                    if v.is_finite() && v > 0.0 {
                        *o = hermite(v as f64) as f32;
                    }
                }
            }
        });
    out
}

/// Append the sensor's geolocation layers, in [`crate::sensor::GeoLayer`]
/// order, from the hit points (x, y, z, m; NaN where the ray missed).
fn push_geo_layers(
    stack: &mut ImageStack,
    sensor: &Sensor,
    points: Vec<Vec<f32>>,
    site: Option<&crate::sun::Site>,
) -> Result<()> {
    use crate::sensor::GeoLayer;
    if sensor.geo_layers.is_empty() {
        return Ok(());
    }
    let Ok([x, y, z]) = <[Vec<f32>; 3]>::try_from(points) else {
        return Err(Error::invalid(
            "truth_layers",
            format!(
                "sensor `{}` asks for geolocation layers but the rendered rows carry no hit points",
                sensor.name
            ),
        ));
    };
    let wants = |l: GeoLayer| sensor.geo_layers.contains(&l);
    if wants(GeoLayer::Latitude) || wants(GeoLayer::Longitude) {
        let Some(site) = site else {
            return Err(Error::invalid(
                "truth_layers",
                format!(
                    "sensor `{}`: latitude and longitude need the scene's site",
                    sensor.name
                ),
            ));
        };
        let (lat, lon): (Vec<f32>, Vec<f32>) = x
            .par_iter()
            .zip(&y)
            .zip(&z)
            .map(|((&x, &y), &z)| {
                if x.is_nan() {
                    (f32::NAN, f32::NAN)
                } else {
                    let p = glam::DVec3::new(x as f64, y as f64, z as f64);
                    let (lat, lon, _) = crate::geodesy::geodetic_from_enu(site, p);
                    (lat as f32, lon as f32)
                }
            })
            .unzip();
        if wants(GeoLayer::Latitude) {
            stack.push(GeoLayer::Latitude.name(), lat)?;
        }
        if wants(GeoLayer::Longitude) {
            stack.push(GeoLayer::Longitude.name(), lon)?;
        }
    }
    for (l, v) in [(GeoLayer::X, x), (GeoLayer::Y, y), (GeoLayer::Z, z)] {
        if wants(l) {
            stack.push(l.name(), v)?;
        }
    }
    Ok(())
}

/// Apply the image-wide sensor effects to a complete [`RowBand`] (MTF, then
/// NEdT noise with `seed`, then quantisation) and build the output layers.
/// The band's buffers become the layers (no copies). Every output value is
/// finite: the band's are ([`RowBand`]), the apparent temperatures and
/// counts are by construction, and the radiance after MTF or noise is
/// checked (an error names the layer, row and column). The geolocation
/// layers, which are NaN where a ray misses, are the exception; for
/// `latitude`/`longitude` use [`finish_at`].
pub fn finish(full: RowBand, sensor: &Sensor, bands: &[Band], seed: u64) -> Result<Finished> {
    finish_at(full, sensor, bands, seed, None)
}

/// [`finish`] for a scene at `site`, which the `latitude` and `longitude`
/// layers need (an error if the sensor asks for them without a site). The
/// sensor's geolocation layers ([`crate::sensor::GeoLayer`]) follow the
/// truth layers; then every layer is laid out in the sensor's
/// [`crate::sensor::Orientation`]. Latitude and longitude are f32 degrees:
/// steps of 4–8 × 10⁻⁶° (under a metre) at longitudes of 64–128°; the
/// `x`, `y`, `z` layers hold the hit points to a millimetre within 16 km.
pub fn finish_at(
    full: RowBand,
    sensor: &Sensor,
    bands: &[Band],
    seed: u64,
    site: Option<&crate::sun::Site>,
) -> Result<Finished> {
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
    let mut radiance_layers = Vec::with_capacity(bands.len());
    let mut temps = Vec::new();
    for (b, ((band, cfg), mut l)) in bands
        .iter()
        .zip(&sensor.bands)
        .zip(full.radiance)
        .enumerate()
    {
        if let Some(m) = &fx.mtf {
            effects::apply_mtf(&mut l, w, h, &m.at(effects::band_centre_um(band)))?;
        }
        if fx.nedt_k.is_some() {
            effects::add_noise(&mut l, w, 0, fx.noise_sigma(band), seed, b as u64);
        }
        if fx.mtf.is_some() || fx.nedt_k.is_some() {
            // The effects' sums of finite values are finite; checked (at
            // a fraction of their cost) rather than assumed.
            let bad = l
                .par_chunks(1 << 16)
                .any(|c| c.iter().fold(false, |acc, v| acc | !v.is_finite()));
            if let Some(at) = bad.then(|| first_non_finite(&l, w, 0)).flatten() {
                let what = format!("sensor `{}` after MTF and noise", sensor.name);
                return Err(non_finite_error(
                    &what,
                    &format!("{}_radiance", cfg.name),
                    at,
                ));
            }
        }
        let t = apparent_temperatures(band, &l);
        let counts = fx
            .bits
            .map(|bits| effects::quantise(&l, bits, fx.gain, fx.offset));
        let name = format!("{}_radiance", cfg.name);
        radiance_layers.push(name.clone());
        stack.push(name, l)?;
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
    for (name, v) in TRUTH_LAYERS.iter().zip(full.truth) {
        stack.push(*name, v)?;
    }
    push_geo_layers(&mut stack, sensor, full.points, site)?;
    if !sensor.orientation.is_identity() {
        stack
            .layers
            .par_iter_mut()
            .for_each(|l| sensor.orientation.flip_layer(&mut l.data, w));
    }
    Ok(Finished {
        stack,
        radiance_layers,
        wavelengths_um: bands.iter().map(effects::band_centre_um).collect(),
    })
}
