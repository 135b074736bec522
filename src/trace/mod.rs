//! Ray queries: the [`Tracer`] interface and its two backends.
//!
//! Embree ([`embree`]) is the default; obvhs ([`bvh`]) is the pure-Rust twin
//! used for cross-checks and benchmarks. Both answer the same two batched
//! queries — closest hit and occlusion — over a [`SceneGeometry`], and agree
//! hit for hit (tests/backends.rs).
//!
//! Build one with [`build`] and a [`Backend`]; trace large batches with
//! [`intersect_all`] / [`occluded_all`], which split them over rayon in
//! fixed-size chunks (results do not depend on the thread count).
//!
//! Takes geometry and rays; gives hits. It must not know what the rays are
//! for (sun, sky, sensor) beyond their [`Coherence`], nor materials or
//! temperatures. Only [`embree`] may use `unsafe` code.
//!
//! ```no_run
//! use irsig::geometry::procedural::{self, TerrainParams};
//! use irsig::trace::{self, Backend, Coherence, Ray};
//! use glam::Vec3;
//!
//! let geom = procedural::generate(&TerrainParams::with_triangles(100_000, 1));
//! let tracer = trace::build(&geom, Backend::Embree)?;
//! let rays = vec![Ray::new(Vec3::new(0.0, 0.0, 500.0), Vec3::NEG_Z)];
//! let hits = trace::intersect_all(tracer.as_ref(), &rays, Coherence::Incoherent);
//! assert!(hits[0].is_some());
//! # Ok::<(), irsig::Error>(())
//! ```

use std::fmt;
use std::str::FromStr;

use glam::Vec3;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::geometry::SceneGeometry;

pub mod bvh;
// The only module with `unsafe` code (the crate denies it everywhere else):
// the safe wrappers over `embree-sys`.
#[allow(unsafe_code)]
pub mod embree;

/// A ray: `origin + t·dir` for `t` in `[tnear, tfar]`. `dir` need not be
/// normalised; hit distances are in units of `|dir|`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Origin, world metres.
    pub origin: Vec3,
    /// Direction.
    pub dir: Vec3,
    /// Smallest accepted `t`.
    pub tnear: f32,
    /// Largest accepted `t` (`f32::INFINITY` for unbounded).
    pub tfar: f32,
}

impl Ray {
    /// An unbounded ray starting at `tnear = 0`.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Ray {
            origin,
            dir,
            tnear: 0.0,
            tfar: f32::INFINITY,
        }
    }
}

/// The closest hit of a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance along the ray (in units of `|dir|`).
    pub t: f32,
    /// Instance index ([`crate::geometry::SceneGeometry::instances`]).
    pub instance: u32,
    /// Primitive (triangle) index within the instance's mesh.
    pub prim: u32,
    /// Barycentric `u` (weight of vertex 1).
    pub u: f32,
    /// Barycentric `v` (weight of vertex 2).
    pub v: f32,
    /// Geometric normal in world space, unnormalised, `(p1-p0)×(p2-p0)`.
    pub ng: Vec3,
}

/// Hints about a batch of rays; the Embree backend picks its query from it
/// ([`embree::RayMode::ByCoherence`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Coherence {
    /// Rays of a scanline / tile from one camera, or parallel rays from
    /// neighbouring points: packet tracing pays off. Embree traces them as
    /// packets at the native width with its coherent flag.
    Coherent,
    /// Rays that share a neighbourhood but not a direction: a facet's
    /// hemisphere rays laid out together (consecutive rays from one sample
    /// point), secondary rays of neighbouring pixels. Embree traces them as
    /// packets at the native width without the coherent flag: on the
    /// bundled town's sky rays that is ~6 % faster than the stream API
    /// (`irsig bench render`, per-facet rays 1.75 s against 1.85 s).
    #[default]
    Incoherent,
    /// Rays with unrelated origins and directions (random surface points,
    /// as `irsig bench trace`'s shadow and diffuse sets). Embree traces
    /// them through its stream API (Embree 3) or one at a time (Embree 4),
    /// which measured faster than packets for such rays (`irsig bench
    /// modes`).
    Scattered,
}

/// Batched ray queries over a built scene. Implementations are `Sync`: callers
/// split large batches over threads (rayon) and call these per chunk.
pub trait Tracer: Send + Sync {
    /// Short name for reports (`"embree"`, `"embree_single"`, `"obvhs"`, ...).
    fn name(&self) -> &str;
    /// Closest hit of every ray; `out.len() == rays.len()`. Every element
    /// of `out` is written (`None` for a miss): callers may reuse it.
    fn intersect(&self, rays: &[Ray], coherence: Coherence, out: &mut [Option<Hit>]);
    /// For every ray, whether anything is hit within `[tnear, tfar]`.
    fn occluded(&self, rays: &[Ray], coherence: Coherence, out: &mut [bool]);
}

/// The ray-tracing backends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Backend {
    /// Embree, the query chosen per batch (the default): packets at the
    /// native width for [`Coherence::Coherent`] (with Embree's coherent
    /// flag) and [`Coherence::Incoherent`] batches, the stream API (Embree
    /// 3) or single rays (Embree 4) for [`Coherence::Scattered`] ones.
    #[default]
    Embree,
    /// Embree, one ray at a time (`rtcIntersect1`), for comparison.
    EmbreeSingle,
    /// obvhs (pure-Rust CWBVH), instances flattened.
    Obvhs,
}

impl Backend {
    /// All backends, in report order.
    pub const ALL: [Backend; 3] = [Backend::Embree, Backend::EmbreeSingle, Backend::Obvhs];

    /// The command-line name (`embree`, `embree-single`, `obvhs`).
    pub fn as_str(self) -> &'static str {
        match self {
            Backend::Embree => "embree",
            Backend::EmbreeSingle => "embree-single",
            Backend::Obvhs => "obvhs",
        }
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for Backend {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Backend::ALL
            .into_iter()
            .find(|b| b.as_str() == s)
            .ok_or_else(|| {
                Error::invalid(
                    "backend",
                    format!("unknown backend `{s}` (expected embree, embree-single or obvhs)"),
                )
            })
    }
}

/// Whether a tracer's ray–triangle tests must be watertight.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Watertight {
    /// No ray slips between two triangles sharing an edge, even one running
    /// in the edge's plane, as sensor rays over a regular heightmap do
    /// (Embree: `RTC_SCENE_FLAG_ROBUST`). The default.
    #[default]
    Yes,
    /// Embree's faster default tests, which can miss a ray meeting a shared
    /// edge exactly. Rays from interior sample points in generic directions
    /// — the exposure's shadow and sky rays — meet an edge only on a set of
    /// measure zero, so they lose nothing. obvhs is the same either way.
    No,
}

impl FromStr for Watertight {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "yes" => Ok(Watertight::Yes),
            "no" => Ok(Watertight::No),
            _ => Err(Error::invalid(
                "watertight",
                format!("`{s}`: expected yes or no"),
            )),
        }
    }
}

/// Builds a watertight tracer over `geom` with `backend`. Returned boxed so
/// callers can pick the backend at run time; the concrete types are
/// [`embree::EmbreeTracer`] and [`bvh::ObvhsTracer`].
pub fn build(geom: &SceneGeometry, backend: Backend) -> Result<Box<dyn Tracer>> {
    build_with(geom, backend, Watertight::Yes)
}

/// [`build`] with the triangle tests chosen by `watertight`.
pub fn build_with(
    geom: &SceneGeometry,
    backend: Backend,
    watertight: Watertight,
) -> Result<Box<dyn Tracer>> {
    Ok(match backend {
        Backend::Embree => Box::new(embree::EmbreeTracer::with_options(geom, true, watertight)?),
        Backend::EmbreeSingle => {
            Box::new(embree::EmbreeTracer::with_options(geom, false, watertight)?)
        }
        Backend::Obvhs => Box::new(bvh::ObvhsTracer::new(geom)?),
    })
}

/// Whether two hit distances agree: within 1e-4 relative, or within
/// `abs_tol` (the float resolution of the scene's coordinates, e.g. 1e-6 of
/// its size over `|dir|`, which matters for hits very close to the origin).
pub fn distances_agree(a: f32, b: f32, abs_tol: f32) -> bool {
    (a - b).abs() <= (1e-4 * a.abs().max(b.abs())).max(abs_tol)
}

/// Whether two backends' closest hits of the ray along `dir` agree: both
/// miss; or they hit at distances that [`distances_agree`]; or they hit the
/// same triangle at distances within `abs_tol / |cos θ|` (θ between the ray
/// and the triangle's normal). The last rule is the float precision of a
/// grazing hit: a plane whose position is known to `abs_tol` (the
/// resolution of the scene's f32 coordinates) places the hit of a ray at
/// incidence cosine `cos θ` only to `abs_tol / cos θ` along it — at
/// cos θ = 0.03 on a terrain 450 m from the origin, ≈ 1 mm, over the 1e-4
/// relative rule for hits closer than 10 m (measured with `irsig bench
/// trace`: every hemisphere and diffuse ray the distance rule alone flags
/// hits the same triangle in both backends, at cos θ of 0.01–0.08).
pub fn hits_agree(a: Option<&Hit>, b: Option<&Hit>, dir: Vec3, abs_tol: f32) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(x), Some(y)) => {
            if distances_agree(x.t, y.t, abs_tol) {
                return true;
            }
            if (x.instance, x.prim) != (y.instance, y.prim) {
                return false;
            }
            let cos = x.ng.normalize_or_zero().dot(dir.normalize_or_zero()).abs();
            (x.t - y.t).abs() <= abs_tol / cos.max(1e-3)
        }
        _ => false,
    }
}

/// Rays per parallel work item in [`intersect_all`] / [`occluded_all`]; a
/// multiple of every packet width, so packets never straddle chunks.
pub const CHUNK_RAYS: usize = 1024;

/// Closest hits of all `rays`, traced in parallel (rayon) over chunks of
/// [`CHUNK_RAYS`]. The result is identical for any thread count.
pub fn intersect_all(tracer: &dyn Tracer, rays: &[Ray], coherence: Coherence) -> Vec<Option<Hit>> {
    let mut out = vec![None; rays.len()];
    rays.par_chunks(CHUNK_RAYS)
        .zip(out.par_chunks_mut(CHUNK_RAYS))
        .for_each(|(r, o)| tracer.intersect(r, coherence, o));
    out
}

/// Occlusion of all `rays` (anything hit within `[tnear, tfar]`), in
/// parallel over chunks of [`CHUNK_RAYS`]; identical for any thread count.
pub fn occluded_all(tracer: &dyn Tracer, rays: &[Ray], coherence: Coherence) -> Vec<bool> {
    let mut out = vec![false; rays.len()];
    rays.par_chunks(CHUNK_RAYS)
        .zip(out.par_chunks_mut(CHUNK_RAYS))
        .for_each(|(r, o)| tracer.occluded(r, coherence, o));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(t: f32, prim: u32, ng: Vec3) -> Hit {
        Hit {
            t,
            instance: 0,
            prim,
            u: 0.2,
            v: 0.2,
            ng,
        }
    }

    #[test]
    fn grazing_hits_on_the_same_triangle_agree_within_the_precision_of_their_plane() {
        let tol = 4.5e-4; // 1e-6 of a 450 m scene
        // A ray at incidence cosine 0.03 on an upward triangle.
        let dir = Vec3::new(0.99955, 0.0, -0.03).normalize();
        let up = Vec3::Z * 2.0;
        // 1 mm apart at t = 0.7 m: over the distance rule, within tol/cos.
        assert!(!distances_agree(0.7007, 0.6997, tol));
        assert!(hits_agree(
            Some(&hit(0.7007, 8, up)),
            Some(&hit(0.6997, 8, up)),
            dir,
            tol
        ));
        // The same gap on different triangles is a disagreement...
        assert!(!hits_agree(
            Some(&hit(0.7007, 8, up)),
            Some(&hit(0.6997, 9, up)),
            dir,
            tol
        ));
        // ...as is a gap beyond tol/cos on the same one (here 2 cm ≫ 15 mm).
        assert!(!hits_agree(
            Some(&hit(0.72, 8, up)),
            Some(&hit(0.70, 8, up)),
            dir,
            tol
        ));
        // Head-on, the same triangle gets no extra room.
        assert!(!hits_agree(
            Some(&hit(0.7007, 8, up)),
            Some(&hit(0.6997, 8, up)),
            -Vec3::Z,
            tol
        ));
        // Hit against miss.
        assert!(!hits_agree(Some(&hit(1.0, 8, up)), None, dir, tol));
        assert!(hits_agree(None, None, dir, tol));
    }
}
