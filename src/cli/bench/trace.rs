//! What `irsig bench trace` measures: the tracing backends on the same rays.
//! Returns a report; the printing is in the parent module.
//!
//! [`trace_bench`] builds every [`Backend`] over the same triangles, traces
//! the same three ray sets through each and reports build time and
//! throughput, plus how often the backends disagree:
//!
//! * **primary** — a pinhole camera looking obliquely down on the scene,
//!   rays ordered in small pixel tiles ([`TileShape`]) so that consecutive
//!   rays form coherent packets; traced with [`Coherence::Coherent`];
//! * **shadow** — occlusion rays from random points on random facets toward
//!   a sun at 40° elevation, azimuth 135° (south-east);
//! * **diffuse** — closest-hit rays from random surface points in
//!   cosine-weighted directions about the facet normal.
//!
//! Each set is traced in `rounds` interleaved rounds (backend after backend)
//! over the global rayon pool; the best round counts.

use std::time::Instant;

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use irsig::geometry::SceneGeometry;
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

impl TileShape {
    /// 4×2 pixels: one 8-wide packet per tile.
    pub const T4X2: TileShape = TileShape {
        width: 4,
        height: 2,
    };
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
    /// Rays per set.
    pub rays: usize,
    /// Timed rounds per set and backend (best counts).
    pub rounds: usize,
    /// Seed of the shadow/diffuse ray origins and directions.
    pub seed: u64,
    /// Pixel tile of the primary rays.
    pub tile: TileShape,
    /// Triangle tests of the Embree scenes (obvhs is the same either way).
    pub watertight: Watertight,
}

impl Default for TraceBenchOptions {
    fn default() -> Self {
        TraceBenchOptions {
            rays: 1_000_000,
            rounds: 3,
            seed: 1,
            tile: TileShape::T4X2,
            watertight: Watertight::Yes,
        }
    }
}

/// The three ray sets.
#[derive(Debug, Clone)]
pub struct RaySets {
    /// Camera rays, tile by tile.
    pub primary: Vec<Ray>,
    /// Occlusion rays toward the sun.
    pub shadow: Vec<Ray>,
    /// Cosine-hemisphere rays from surface points.
    pub diffuse: Vec<Ray>,
}

/// Unit vector toward the sun: elevation 40°, azimuth 135° (clockwise from
/// north; x east, y north, z up).
pub fn bench_sun_direction() -> Vec3 {
    let (el, az) = (40f32.to_radians(), 135f32.to_radians());
    Vec3::new(az.sin() * el.cos(), az.cos() * el.cos(), el.sin())
}

/// Builds the three ray sets of about `opts.rays` rays each.
pub fn make_ray_sets(geom: &SceneGeometry, opts: &TraceBenchOptions) -> Result<RaySets> {
    let (lo, hi) = geom
        .bounds()
        .ok_or_else(|| Error::invalid("scene", "the scene has no triangles"))?;
    let n = opts.rays.max(1);
    let centre = 0.5 * (lo + hi);
    let size = (hi - lo).max_element().max(1e-3);

    // Primary: W×H pixels in whole tiles, W:H ≈ 4:3.
    let TileShape {
        width: tw,
        height: th,
    } = opts.tile;
    let w = (((n as f64 * 4.0 / 3.0).sqrt() / tw as f64).round() as usize).max(1) * tw;
    let h = (((n / w) as f64 / th as f64).round() as usize).max(1) * th;
    let eye = centre + Vec3::new(-0.35 * size, -0.35 * size, 0.45 * size + (hi.z - centre.z));
    let fwd = (centre - eye).normalize();
    let right = fwd.cross(Vec3::Z).normalize();
    let up = right.cross(fwd);
    let tan_half = (25f32).to_radians().tan(); // 50° vertical field of view
    let aspect = w as f32 / h as f32;
    let mut primary = Vec::with_capacity(w * h);
    for ty in (0..h).step_by(th) {
        for tx in (0..w).step_by(tw) {
            for y in ty..ty + th {
                for x in tx..tx + tw {
                    let sx = (2.0 * (x as f32 + 0.5) / w as f32 - 1.0) * tan_half * aspect;
                    let sy = (1.0 - 2.0 * (y as f32 + 0.5) / h as f32) * tan_half;
                    primary.push(Ray::new(eye, (fwd + sx * right + sy * up).normalize()));
                }
            }
        }
    }

    let offsets = geom.facet_offsets();
    let facets = geom.facet_count();
    let eps = 1e-4 * size;
    let sun = bench_sun_direction();
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
    let shadow = (0..n)
        .map(|_| {
            let (p, mut nrm) = surface_point(&mut rng);
            if nrm.dot(sun) < 0.0 {
                nrm = -nrm;
            }
            Ray::new(p + eps * nrm, sun)
        })
        .collect();
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
        diffuse,
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
    /// Diffuse rays, million rays per second.
    pub diffuse_mrays_s: f64,
}

/// Results per backend.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Backends {
    /// Embree, packets at the native width.
    pub embree_packet: BackendResult,
    /// Embree, one ray at a time.
    pub embree_single: BackendResult,
    /// obvhs CWBVH.
    pub obvhs: BackendResult,
}

/// How often the backends disagree.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Agreement {
    /// Rays compared (all three sets).
    pub rays: usize,
    /// Rays on which some backend differs from Embree packets on hit/miss,
    /// or on the hit distance ([`trace::distances_agree`] with a floor of
    /// 1e-6 of the scene size).
    pub mismatched_rays: usize,
}

/// The report of `irsig bench trace` (its `--json` shape).
#[derive(Debug, Clone, Default, Serialize)]
pub struct TraceBenchReport {
    /// Triangles (facets) in the scene.
    pub triangles: usize,
    /// Per backend.
    pub backends: Backends,
    /// Cross-check.
    pub agreement: Agreement,
}

/// Extra facts for the human-readable report.
#[derive(Debug, Clone)]
pub struct TraceBenchInfo {
    /// Rays per set (primary may differ slightly: whole tiles).
    pub rays: [usize; 3],
    /// Worker threads.
    pub threads: usize,
    /// Embree packet width used.
    pub packet_width: usize,
    /// Embree version.
    pub embree_version: String,
}

struct Outputs {
    primary: Vec<Option<Hit>>,
    shadow: Vec<bool>,
    diffuse: Vec<Option<Hit>>,
}

/// Runs the benchmark on `geom`.
pub fn trace_bench(
    geom: &SceneGeometry,
    opts: &TraceBenchOptions,
) -> Result<(TraceBenchReport, TraceBenchInfo)> {
    let sets = make_ray_sets(geom, opts)?;
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
    let mut last: Vec<Option<Outputs>> = (0..tracers.len()).map(|_| None).collect();
    for _ in 0..opts.rounds.max(1) {
        for ((t, res), out) in tracers.iter_mut().zip(last.iter_mut()) {
            let t0 = Instant::now();
            let primary = trace::intersect_all(t.as_ref(), &sets.primary, Coherence::Coherent);
            let t1 = Instant::now();
            let shadow = trace::occluded_all(t.as_ref(), &sets.shadow, Coherence::Scattered);
            let t2 = Instant::now();
            let diffuse = trace::intersect_all(t.as_ref(), &sets.diffuse, Coherence::Scattered);
            let t3 = Instant::now();
            let p = mrays(sets.primary.len(), (t1 - t0).as_secs_f64());
            let s = mrays(sets.shadow.len(), (t2 - t1).as_secs_f64());
            let d = mrays(sets.diffuse.len(), (t3 - t2).as_secs_f64());
            res.primary_mrays_s = res.primary_mrays_s.max(p);
            res.shadow_mrays_s = res.shadow_mrays_s.max(s);
            res.diffuse_mrays_s = res.diffuse_mrays_s.max(d);
            *out = Some(Outputs {
                primary,
                shadow,
                diffuse,
            });
        }
    }

    let (lo, hi) = geom.bounds().expect("checked in make_ray_sets");
    let abs_tol = 1e-6 * lo.abs().max(hi.abs()).max_element();
    let hits_agree = |a: &Option<Hit>, b: &Option<Hit>| match (a, b) {
        (None, None) => true,
        (Some(x), Some(y)) => trace::distances_agree(x.t, y.t, abs_tol),
        _ => false,
    };
    let outs: Vec<Outputs> = last.into_iter().map(|o| o.expect("one round")).collect();
    let (reference, others) = outs.split_first().expect("three backends");
    let mut mismatched = 0;
    for i in 0..sets.primary.len() {
        mismatched += others
            .iter()
            .any(|o| !hits_agree(&reference.primary[i], &o.primary[i]))
            as usize;
    }
    for i in 0..sets.shadow.len() {
        mismatched += others.iter().any(|o| reference.shadow[i] != o.shadow[i]) as usize;
    }
    for i in 0..sets.diffuse.len() {
        mismatched += others
            .iter()
            .any(|o| !hits_agree(&reference.diffuse[i], &o.diffuse[i]))
            as usize;
    }

    let embree = trace::embree::Device::new()?;
    let info = TraceBenchInfo {
        rays: [sets.primary.len(), sets.shadow.len(), sets.diffuse.len()],
        threads: rayon::current_num_threads(),
        packet_width: embree.native_packet_width(),
        embree_version: embree.version(),
    };
    let report = TraceBenchReport {
        triangles: geom.facet_count(),
        backends: Backends {
            embree_packet: tracers[0].1,
            embree_single: tracers[1].1,
            obvhs: tracers[2].1,
        },
        agreement: Agreement {
            rays: sets.primary.len() + sets.shadow.len() + sets.diffuse.len(),
            mismatched_rays: mismatched,
        },
    };
    Ok((report, info))
}
