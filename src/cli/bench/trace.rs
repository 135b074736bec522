//! What `irsig bench trace` measures: the tracing backends on the rays the
//! renderer and the exposure stage make. Returns a report; the printing is
//! in the parent module.
//!
//! [`trace_bench`] builds every [`Backend`] over the same triangles (both
//! Embree's builder and obvhs's parallel build run on rayon's pool, sized
//! by `--threads`), traces the same four ray classes through each and
//! reports build time and throughput, plus how often the backends disagree:
//!
//! * **primary** — a [`FrameCamera`] looking obliquely down on the scene,
//!   its rays made by the renderer's own row generator
//!   ([`FrameCamera::rays_for_row`]) and traced one row per batch as the
//!   renderer does (8×1 runs in 8-wide packets), or re-ordered into pixel
//!   tiles with `--tile WxH`; [`Coherence::Coherent`];
//! * **shadow** — the exposure stage's solar-history rays
//!   ([`exposure::solar_rays`]): from facet sample points toward the sun
//!   over four history steps, batch by batch of 512 facets, with
//!   [`exposure::SOLAR_RAY_COHERENCE`];
//! * **hemisphere** — the exposure stage's sky-view rays
//!   ([`exposure::sky_rays`]): the default sky sampling (stratified, 64
//!   rays per face) from each sample point, with
//!   [`exposure::SKY_RAY_COHERENCE`];
//! * **diffuse** — closest-hit rays from random surface points in
//!   cosine-weighted directions, unrelated ray to ray
//!   ([`Coherence::Scattered`]).
//!
//! Exposure batches are runs of 512 consecutive facets spread evenly over
//! the scene until the class has `--rays` rays (the last batch cut). Each
//! class is traced in `rounds` interleaved rounds (backend after backend)
//! over the global rayon pool, batch by batch (a batch in pieces of at most
//! [`trace::CHUNK_RAYS`] rays from its start, so both threads stay busy);
//! the best round counts.

use std::ops::Range;
use std::time::Instant;

use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use irsig::exposure::{self, ExposureParams, FacetSamples};
use irsig::geometry::SceneGeometry;
use irsig::sensor::camera::{FrameCamera, look_at_axes};
use irsig::trace::embree::RayMode;
use irsig::trace::{self, Backend, Coherence, Hit, Ray, Tracer, Watertight};
use irsig::{Error, Result};

/// Pixel-tile shape of the primary rays: consecutive rays cover one tile.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TileShape {
    /// Tile width, pixels.
    pub width: usize,
    /// Tile height, pixels.
    pub height: usize,
}

impl std::str::FromStr for TileShape {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        let bad = || {
            Error::invalid(
                "tile",
                format!("`{s}` is not a tile shape (expected WxH, e.g. 4x2 or 8x1)"),
            )
        };
        let (w, h) = s.split_once('x').ok_or_else(bad)?;
        let (width, height) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
        if width == 0 || height == 0 || width * height > 64 {
            return Err(bad());
        }
        Ok(TileShape { width, height })
    }
}

/// Options of [`trace_bench`].
#[derive(Debug, Clone)]
pub struct TraceBenchOptions {
    /// Rays per class.
    pub rays: usize,
    /// Timed rounds per class and backend (best counts).
    pub rounds: usize,
    /// Seed of the diffuse rays.
    pub seed: u64,
    /// Pixel tile of the primary rays; `None`: the renderer's rows.
    pub tile: Option<TileShape>,
    /// Triangle tests of the Embree scenes (obvhs is the same either way).
    pub watertight: Watertight,
}

impl Default for TraceBenchOptions {
    fn default() -> Self {
        TraceBenchOptions {
            rays: 1_000_000,
            rounds: 3,
            seed: 1,
            tile: None,
            watertight: Watertight::Yes,
        }
    }
}

/// One class of rays, laid out and batched as its producer does.
#[derive(Debug, Clone)]
pub struct RaySet {
    /// The rays.
    pub rays: Vec<Ray>,
    /// Batches (one tracer call each, in parallel): start of each, then
    /// the end of the last.
    pub bounds: Vec<usize>,
    /// The coherence the producer declares.
    pub coherence: Coherence,
}

impl RaySet {
    fn new(rays: Vec<Ray>, mut starts: Vec<usize>, coherence: Coherence) -> Self {
        // Pieces of at most CHUNK_RAYS from each batch's start.
        starts.retain(|&s| s < rays.len());
        starts.push(rays.len());
        let mut bounds = Vec::new();
        for w in starts.windows(2) {
            bounds.extend((w[0]..w[1]).step_by(trace::CHUNK_RAYS));
        }
        bounds.push(rays.len());
        RaySet {
            rays,
            bounds,
            coherence,
        }
    }

    fn batches(&self) -> impl IndexedParallelIterator<Item = Range<usize>> + '_ {
        self.bounds.par_windows(2).map(|w| w[0]..w[1])
    }

    /// `out` cut into one slice per batch.
    fn batch_slices<'a, T>(&self, mut out: &'a mut [T]) -> Vec<&'a mut [T]> {
        assert_eq!(out.len(), self.rays.len(), "one answer per ray");
        let mut slices = Vec::with_capacity(self.bounds.len());
        for w in self.bounds.windows(2) {
            let (head, rest) = std::mem::take(&mut out).split_at_mut(w[1] - w[0]);
            slices.push(head);
            out = rest;
        }
        slices
    }

    /// Closest hits into `out` (one per ray), batch by batch in parallel,
    /// each batch straight into its own part of `out` (as the renderer's
    /// rows write into their buffers: no allocation or copy is timed).
    pub fn intersect_into(&self, tracer: &dyn Tracer, out: &mut [Option<Hit>]) {
        self.batches()
            .zip(self.batch_slices(out))
            .for_each(|(r, o)| tracer.intersect(&self.rays[r], self.coherence, o));
    }

    /// Occlusion into `out`, as [`RaySet::intersect_into`].
    pub fn occluded_into(&self, tracer: &dyn Tracer, out: &mut [bool]) {
        self.batches()
            .zip(self.batch_slices(out))
            .for_each(|(r, o)| tracer.occluded(&self.rays[r], self.coherence, o));
    }
}

/// The four ray classes.
#[derive(Debug, Clone)]
pub struct RaySets {
    /// Camera rays, row by row (or tile by tile).
    pub primary: RaySet,
    /// Occlusion rays toward the sun from facet sample points.
    pub shadow: RaySet,
    /// DIRSIG-grid hemisphere rays from facet sample points.
    pub hemisphere: RaySet,
    /// Cosine-hemisphere rays from random surface points.
    pub diffuse: RaySet,
    /// Camera size, pixels.
    pub camera: (usize, usize),
}

/// Unit vector toward the sun at elevation and azimuth (degrees, azimuth
/// clockwise from north; x east, y north, z up).
fn sun_at(el_deg: f32, az_deg: f32) -> Vec3 {
    let (el, az) = (el_deg.to_radians(), az_deg.to_radians());
    Vec3::new(az.sin() * el.cos(), az.cos() * el.cos(), el.sin())
}

/// Rays of runs of `batch` consecutive facets spread evenly over
/// `facets` facets, until `n` rays (the last run cut); `make` appends a
/// run's rays. Returns the rays and the start of each run.
fn exposure_batches(
    facets: usize,
    n: usize,
    batch: usize,
    make: impl Fn(Range<usize>, &mut Vec<Ray>),
) -> (Vec<Ray>, Vec<usize>) {
    let mut probe = Vec::new();
    let first = batch.min(facets);
    make(0..first, &mut probe);
    let per_facet = (probe.len() as f64 / first.max(1) as f64).max(1e-3);
    let needed = ((n as f64 / per_facet).ceil() as usize).clamp(1, facets);
    let run = batch.min(needed);
    let runs = needed.div_ceil(run);
    let (mut rays, mut starts) = (Vec::with_capacity(n + probe.len()), Vec::new());
    for i in 0..runs + 1 {
        if rays.len() >= n || i * run >= facets {
            break;
        }
        let f0 = (i * facets / runs).min(facets - run);
        starts.push(rays.len());
        make(f0..f0 + run, &mut rays);
    }
    rays.truncate(n);
    (rays, starts)
}

fn lcm(a: usize, b: usize) -> usize {
    let (mut x, mut y) = (a, b);
    while y != 0 {
        (x, y) = (y, x % y);
    }
    a / x * b
}

/// Builds the four ray classes of about `opts.rays` rays each.
pub fn make_ray_sets(geom: &SceneGeometry, opts: &TraceBenchOptions) -> Result<RaySets> {
    let (lo, hi) = geom
        .bounds()
        .ok_or_else(|| Error::invalid("scene", "the scene has no triangles"))?;
    let n = opts.rays.max(1);
    let centre = 0.5 * (lo + hi);
    let size = (hi - lo).max_element().max(1e-3);

    // Primary: W×H pixels, W:H ≈ 4:3, W a multiple of 8 (whole packets per
    // row), H of the tile height; 50° vertical field of view.
    let th = opts.tile.map_or(1, |t| t.height);
    let tw = opts.tile.map_or(8, |t| lcm(t.width, 8));
    let w = (((n as f64 * 4.0 / 3.0).sqrt() / tw as f64).round() as usize).max(1) * tw;
    let h = (((n / w) as f64 / th as f64).round() as usize).max(1) * th;
    let eye = centre + Vec3::new(-0.35 * size, -0.35 * size, 0.45 * size + (hi.z - centre.z));
    let (eye, centre) = (eye.as_dvec3(), centre.as_dvec3());
    let axes = look_at_axes(eye, centre, DVec3::Z)?;
    let focal_px = 0.5 * h as f64 / 25f64.to_radians().tan();
    let camera = FrameCamera::new(w, h, focal_px, axes, eye, 1)?;
    let mut rows = Vec::with_capacity(w * h);
    for row in 0..h {
        camera.rays_for_row(row, &mut rows);
    }
    let primary = match opts.tile {
        None => RaySet::new(rows, (0..h).map(|r| r * w).collect(), Coherence::Coherent),
        Some(TileShape {
            width: tw,
            height: th,
        }) => {
            let mut tiled = Vec::with_capacity(w * h);
            for ty in (0..h).step_by(th) {
                for tx in (0..w).step_by(tw) {
                    for y in ty..(ty + th).min(h) {
                        tiled.extend_from_slice(&rows[y * w + tx..y * w + (tx + tw).min(w)]);
                    }
                }
            }
            RaySet::new(tiled, vec![0], Coherence::Coherent)
        }
    };

    // Shadow and hemisphere: the exposure stage's rays, its defaults.
    let params = ExposureParams::default();
    let samples = FacetSamples::new(geom, &[], params.samples_per_edge, params.offset_rel);
    let facets = samples.len();
    // Four history steps of a morning sun (elevation 37–40°, azimuth
    // 127.5–142.5°: south-east).
    let suns: Vec<Vec3> = (0..4)
        .map(|k| sun_at(37.0 + k as f32, 127.5 + 5.0 * k as f32))
        .collect();
    let (rays, starts) = exposure_batches(facets, n, params.batch_facets, |r, out| {
        exposure::solar_rays(&samples, r, &suns, out)
    });
    let shadow = RaySet::new(rays, starts, exposure::SOLAR_RAY_COHERENCE);
    let (rays, starts) = exposure_batches(facets, n, params.batch_facets, |r, out| {
        exposure::sky_rays(&samples, r, params.sky, params.seed, out)
    });
    let hemisphere = RaySet::new(rays, starts, exposure::SKY_RAY_COHERENCE);

    let offsets = geom.facet_offsets();
    let eps = 1e-4 * size;
    // A random point on a random facet and the facet's unit normal.
    let surface_point = |rng: &mut ChaCha8Rng| -> (Vec3, Vec3) {
        loop {
            let f = rng.random_range(0..facets);
            let inst = offsets.partition_point(|&o| o <= f) - 1;
            let prim = f - offsets[inst];
            let t = geom.world_triangle(inst, prim);
            let ng = (t[1] - t[0]).cross(t[2] - t[0]);
            if ng.length_squared() == 0.0 {
                continue;
            }
            let (r1, r2): (f32, f32) = (rng.random(), rng.random());
            let s = r1.sqrt();
            let p = t[0] * (1.0 - s) + t[1] * (s * (1.0 - r2)) + t[2] * (s * r2);
            return (p, ng.normalize());
        }
    };
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let diffuse = (0..n)
        .map(|_| {
            let (p, mut nrm) = surface_point(&mut rng);
            if nrm.z < 0.0 {
                nrm = -nrm;
            }
            // Cosine-weighted hemisphere (Malley's method).
            let (u1, u2): (f32, f32) = (rng.random(), rng.random());
            let (r, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
            let (a, b) = nrm.any_orthonormal_pair();
            let d = a * (r * phi.cos()) + b * (r * phi.sin()) + nrm * (1.0 - u1).max(0.0).sqrt();
            Ray::new(p + eps * nrm, d.normalize())
        })
        .collect();
    Ok(RaySets {
        primary,
        shadow,
        hemisphere,
        diffuse: RaySet::new(diffuse, vec![0], Coherence::Scattered),
        camera: (w, h),
    })
}

/// Build time and throughput of one backend.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct BackendResult {
    /// Scene build (acceleration structure), seconds.
    pub build_s: f64,
    /// Primary rays, million rays per second.
    pub primary_mrays_s: f64,
    /// Shadow (occlusion) rays, million rays per second.
    pub shadow_mrays_s: f64,
    /// Hemisphere rays, million rays per second.
    pub hemisphere_mrays_s: f64,
    /// Diffuse rays, million rays per second.
    pub diffuse_mrays_s: f64,
}

impl BackendResult {
    fn mrays_s(&mut self, class: usize) -> &mut f64 {
        match class {
            0 => &mut self.primary_mrays_s,
            1 => &mut self.shadow_mrays_s,
            2 => &mut self.hemisphere_mrays_s,
            _ => &mut self.diffuse_mrays_s,
        }
    }
}

/// Results per backend.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Backends {
    /// Embree, the query chosen per batch from its coherence
    /// ([`RayMode::ByCoherence`], the renderer's default).
    pub embree_packet: BackendResult,
    /// Embree, one ray at a time.
    pub embree_single: BackendResult,
    /// obvhs CWBVH.
    pub obvhs: BackendResult,
}

/// How often the backends disagree.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Agreement {
    /// Rays compared (all classes).
    pub rays: usize,
    /// Rays on which some backend differs from Embree packets on hit/miss,
    /// or on the hit ([`trace::hits_agree`]: the distance, with a floor of
    /// 1e-6 of the scene size, or that floor over the incidence cosine on
    /// the same triangle).
    pub mismatched_rays: usize,
}

/// One ray class: Embree's default query on it against obvhs.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ClassResult {
    /// Rays in the class.
    pub rays: usize,
    /// The coherence its producer declares (`Coherent`, `Incoherent`,
    /// `Scattered`).
    pub coherence: String,
    /// The Embree query [`RayMode::for_batch`] picks for it, e.g.
    /// `Packet(8)`, `Stream`, `Single`.
    pub embree_mode: String,
    /// Embree (`embree_packet`), million rays per second.
    pub embree_mrays_s: f64,
    /// obvhs, million rays per second.
    pub obvhs_mrays_s: f64,
    /// `embree_mrays_s / obvhs_mrays_s`.
    pub ratio: f64,
    /// Rays on which some backend disagrees (as [`Agreement`]).
    pub mismatched: usize,
}

/// Per ray class.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Classes {
    /// Camera rays in the renderer's layout.
    pub primary: ClassResult,
    /// The solar history's occlusion rays.
    pub shadow: ClassResult,
    /// The sky view's hemisphere rays.
    pub hemisphere: ClassResult,
    /// Random cosine-hemisphere rays.
    pub diffuse: ClassResult,
}

/// The report of `irsig bench trace` (its `--json` shape).
#[derive(Debug, Clone, Default, Serialize)]
pub struct TraceBenchReport {
    /// Triangles (facets) in the scene.
    pub triangles: usize,
    /// Threads of both backends' builds and of the tracing (rayon's pool;
    /// Embree's device gets `threads=N` of it).
    pub threads: usize,
    /// Per backend.
    pub backends: Backends,
    /// Cross-check.
    pub agreement: Agreement,
    /// Per ray class.
    pub classes: Classes,
}

/// Extra facts for the human-readable report.
#[derive(Debug, Clone)]
pub struct TraceBenchInfo {
    /// Camera size of the primary rays, pixels.
    pub camera: (usize, usize),
    /// Embree packet width used.
    pub packet_width: usize,
    /// Embree version.
    pub embree_version: String,
}

/// Class names, in the order of [`RaySets`].
pub const CLASSES: [&str; 4] = ["primary", "shadow", "hemisphere", "diffuse"];

enum Answers {
    Hits(Vec<Option<Hit>>),
    Occluded(Vec<bool>),
}

/// Runs the benchmark on `geom`.
pub fn trace_bench(
    geom: &SceneGeometry,
    opts: &TraceBenchOptions,
) -> Result<(TraceBenchReport, TraceBenchInfo)> {
    let sets = make_ray_sets(geom, opts)?;
    let classes = [&sets.primary, &sets.shadow, &sets.hemisphere, &sets.diffuse];
    // Shadow rays are occlusion queries, the rest closest hits; the answer
    // buffers are allocated before the clock starts (`run` fills them).
    let fresh = |c: usize| match c {
        1 => Answers::Occluded(vec![false; classes[c].rays.len()]),
        _ => Answers::Hits(vec![None; classes[c].rays.len()]),
    };
    let run = |t: &dyn Tracer, c: usize, a: &mut Answers| match a {
        Answers::Occluded(o) => classes[c].occluded_into(t, o),
        Answers::Hits(h) => classes[c].intersect_into(t, h),
    };
    let mut tracers: Vec<(Box<dyn Tracer>, BackendResult)> = Vec::new();
    for b in Backend::ALL {
        let t0 = Instant::now();
        let t = trace::build_with(geom, b, opts.watertight)?;
        let res = BackendResult {
            build_s: t0.elapsed().as_secs_f64(),
            ..Default::default()
        };
        tracers.push((t, res));
    }
    let mrays = |n: usize, s: f64| n as f64 / s.max(1e-9) / 1e6;
    let mut last: Vec<Vec<Option<Answers>>> = (0..tracers.len())
        .map(|_| (0..classes.len()).map(|_| None).collect())
        .collect();
    for _ in 0..opts.rounds.max(1) {
        for ((t, res), out) in tracers.iter_mut().zip(last.iter_mut()) {
            for (c, set) in classes.iter().enumerate() {
                let mut a = out[c].take().unwrap_or_else(|| fresh(c));
                let t0 = Instant::now();
                run(t.as_ref(), c, &mut a);
                let m = mrays(set.rays.len(), t0.elapsed().as_secs_f64());
                let best = res.mrays_s(c);
                *best = best.max(m);
                out[c] = Some(a);
            }
        }
    }

    let (lo, hi) = geom.bounds().expect("checked in make_ray_sets");
    let abs_tol = 1e-6 * lo.abs().max(hi.abs()).max_element();
    let hits_agree = |a: &Option<Hit>, b: &Option<Hit>, dir: Vec3| {
        trace::hits_agree(a.as_ref(), b.as_ref(), dir, abs_tol)
    };
    let (reference, others) = last.split_first().expect("three backends");
    let mismatched: Vec<usize> = (0..classes.len())
        .map(|c| {
            let r = reference[c].as_ref().expect("one round");
            (0..classes[c].rays.len())
                .filter(|&i| {
                    others
                        .iter()
                        .any(|o| match (r, o[c].as_ref().expect("one round")) {
                            (Answers::Hits(a), Answers::Hits(b)) => {
                                !hits_agree(&a[i], &b[i], classes[c].rays[i].dir)
                            }
                            (Answers::Occluded(a), Answers::Occluded(b)) => a[i] != b[i],
                            _ => true,
                        })
                })
                .count()
        })
        .collect();

    let embree = trace::embree::Device::new()?;
    let width = embree.native_packet_width();
    let (e, o) = (tracers[0].1, tracers[2].1);
    let class = |c: usize| {
        let (mut e, mut o) = (e, o);
        let (em, om) = (*e.mrays_s(c), *o.mrays_s(c));
        ClassResult {
            rays: classes[c].rays.len(),
            coherence: format!("{:?}", classes[c].coherence),
            embree_mode: format!(
                "{:?}",
                RayMode::ByCoherence(width).for_batch(classes[c].coherence)
            ),
            embree_mrays_s: em,
            obvhs_mrays_s: om,
            ratio: em / om.max(1e-12),
            mismatched: mismatched[c],
        }
    };
    let info = TraceBenchInfo {
        camera: sets.camera,
        packet_width: width,
        embree_version: embree.version(),
    };
    let report = TraceBenchReport {
        triangles: geom.facet_count(),
        threads: rayon::current_num_threads(),
        backends: Backends {
            embree_packet: tracers[0].1,
            embree_single: tracers[1].1,
            obvhs: tracers[2].1,
        },
        agreement: Agreement {
            rays: classes.iter().map(|s| s.rays.len()).sum(),
            mismatched_rays: mismatched.iter().sum(),
        },
        classes: Classes {
            primary: class(0),
            shadow: class(1),
            hemisphere: class(2),
            diffuse: class(3),
        },
    };
    Ok((report, info))
}

/// Writes `geom`'s triangles and the four ray sets of [`make_ray_sets`]
/// into `dir` as raw little-endian files, for an outside harness
/// (`scripts/embree-harness/`; layout in `docs/embree.md`):
///
/// * `triangles.f32`: per triangle its three world vertices, 9 × `f32`;
/// * `CLASS.rays`: per ray origin, direction, `tnear`, `tfar`, 8 × `f32`;
/// * `CLASS.bounds`: the batches (one tracer call each) as `u64` bounds:
///   the start of each, then the end of the last;
/// * `meta.json`: counts, camera size, each class's coherence, watertight.
pub fn dump(geom: &SceneGeometry, opts: &TraceBenchOptions, dir: &std::path::Path) -> Result<()> {
    use irsig::output::atomic::write_atomic;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let sets = make_ray_sets(geom, opts)?;
    let offsets = geom.facet_offsets();
    let write = |name: &str, bytes: &[u8]| {
        write_atomic(dir.join(name), |w| {
            w.write_all(bytes).map_err(|e| Error::io(dir.join(name), e))
        })
    };
    let mut tri = Vec::with_capacity(geom.facet_count() * 36);
    for inst in 0..offsets.len() - 1 {
        for prim in 0..offsets[inst + 1] - offsets[inst] {
            for v in geom.world_triangle(inst, prim) {
                for c in v.to_array() {
                    tri.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
    }
    write("triangles.f32", &tri)?;
    let classes = [&sets.primary, &sets.shadow, &sets.hemisphere, &sets.diffuse];
    let mut meta = serde_json::Map::new();
    for (name, set) in CLASSES.iter().zip(classes) {
        let mut rays = Vec::with_capacity(set.rays.len() * 32);
        for r in &set.rays {
            for c in r.origin.to_array().into_iter().chain(r.dir.to_array()) {
                rays.extend_from_slice(&c.to_le_bytes());
            }
            rays.extend_from_slice(&r.tnear.to_le_bytes());
            rays.extend_from_slice(&r.tfar.to_le_bytes());
        }
        write(&format!("{name}.rays"), &rays)?;
        let bounds: Vec<u8> = set
            .bounds
            .iter()
            .flat_map(|&b| (b as u64).to_le_bytes())
            .collect();
        write(&format!("{name}.bounds"), &bounds)?;
        meta.insert(
            (*name).to_string(),
            serde_json::json!({
                "rays": set.rays.len(),
                "batches": set.bounds.len() - 1,
                "coherence": format!("{:?}", set.coherence),
            }),
        );
    }
    meta.insert("triangles".into(), geom.facet_count().into());
    meta.insert(
        "camera".into(),
        serde_json::json!([sets.camera.0, sets.camera.1]),
    );
    meta.insert(
        "watertight".into(),
        matches!(opts.watertight, Watertight::Yes).into(),
    );
    let text = serde_json::to_string_pretty(&meta)
        .map_err(|e| Error::invalid("meta.json", e.to_string()))?;
    write("meta.json", text.as_bytes())
}
