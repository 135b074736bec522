//! Ray queries: the [`Tracer`] interface and its two backends.
//!
//! Embree ([`embree`]) is the default; obvhs ([`bvh`]) is the pure-Rust twin
//! used for cross-checks and benchmarks. Both answer the same two batched
//! queries — closest hit and occlusion — over a [`SceneGeometry`], and agree
//! hit for hit (tests/backends.rs).

use glam::Vec3;

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

/// Hints about a batch of rays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Coherence {
    /// Rays of a scanline / tile from one camera: packet tracing pays off.
    Coherent,
    /// Scattered rays (diffuse, hemisphere, shadow from many facets).
    #[default]
    Incoherent,
}

/// Batched ray queries over a built scene. Implementations are `Sync`: callers
/// split large batches over threads (rayon) and call these per chunk.
pub trait Tracer: Send + Sync {
    /// Short name for reports (`"embree_packet"`, `"obvhs"`, ...).
    fn name(&self) -> &str;
    /// Closest hit of every ray; `out.len() == rays.len()`.
    fn intersect(&self, rays: &[Ray], coherence: Coherence, out: &mut [Option<Hit>]);
    /// For every ray, whether anything is hit within `[tnear, tfar]`.
    fn occluded(&self, rays: &[Ray], coherence: Coherence, out: &mut [bool]);
}
