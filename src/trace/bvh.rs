//! The obvhs backend: a pure-Rust compressed wide BVH (CWBVH, obvhs 0.4).
//!
//! obvhs has no instancing, so the instances are *flattened*: every instance's
//! triangles are transformed to world space and put in one BVH. Each BVH slot
//! remembers its `(instance, prim)`, so hits use the same numbering as the
//! Embree backend. Memory therefore grows with the facet count, not the stored
//! triangle count — fine for a reference backend.
//!
//! There is no packet traversal; rays are traced one at a time.

use glam::{Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray as BvhRay, RayHit};
use obvhs::triangle::Triangle;

use super::{Coherence, Hit, Ray, Tracer};
use crate::error::{Error, Result};
use crate::geometry::SceneGeometry;

/// obvhs tracer over a flattened [`SceneGeometry`].
pub struct ObvhsTracer {
    bvh: CwBvh,
    /// Triangles in BVH primitive order.
    tris: Vec<Triangle>,
    /// `(instance, prim)` of each BVH primitive.
    ids: Vec<(u32, u32)>,
}

impl ObvhsTracer {
    /// Builds the BVH (obvhs `medium_build` preset, multi-threaded through
    /// rayon).
    pub fn new(geom: &SceneGeometry) -> Result<Self> {
        let n = geom.facet_count();
        let mut tris = Vec::with_capacity(n);
        let mut ids = Vec::with_capacity(n);
        for (i, inst) in geom.instances.iter().enumerate() {
            let mesh = geom.meshes.get(inst.mesh).ok_or_else(|| {
                Error::invalid(
                    format!("instances[{i}].mesh"),
                    format!(
                        "mesh index {} out of range ({} meshes)",
                        inst.mesh,
                        geom.meshes.len()
                    ),
                )
            })?;
            let nv = mesh.positions.len();
            for (p, t) in mesh.indices.iter().enumerate() {
                if t.iter().any(|&k| k as usize >= nv) {
                    return Err(Error::invalid(
                        format!("mesh `{}` triangle {p}", mesh.name),
                        format!("vertex index in {t:?} out of range (mesh has {nv} vertices)"),
                    ));
                }
                let [a, b, c] = t.map(|k| {
                    Vec3A::from(
                        inst.world_from_object
                            .transform_point3(mesh.positions[k as usize]),
                    )
                });
                tris.push(Triangle {
                    v0: a,
                    v1: b,
                    v2: c,
                });
                ids.push((i as u32, p as u32));
            }
        }
        if tris.is_empty() {
            return Ok(ObvhsTracer {
                bvh: CwBvh::default(),
                tris,
                ids,
            });
        }
        let mut core = std::time::Duration::ZERO;
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &tris,
            BvhBuildParams::medium_build(),
            &mut core,
        );
        // The traversal reports BVH-ordered primitive indices: reorder.
        let tris_bvh = bvh
            .primitive_indices
            .iter()
            .map(|&k| tris[k as usize])
            .collect();
        let ids_bvh = bvh
            .primitive_indices
            .iter()
            .map(|&k| ids[k as usize])
            .collect();
        Ok(ObvhsTracer {
            bvh,
            tris: tris_bvh,
            ids: ids_bvh,
        })
    }

    fn bvh_ray(r: &Ray) -> BvhRay {
        BvhRay::new(r.origin.into(), r.dir.into(), r.tnear, r.tfar)
    }
}

impl Tracer for ObvhsTracer {
    fn name(&self) -> &str {
        "obvhs"
    }

    fn intersect(&self, rays: &[Ray], _coherence: Coherence, out: &mut [Option<Hit>]) {
        assert_eq!(
            rays.len(),
            out.len(),
            "intersect: rays and out differ in length"
        );
        if self.tris.is_empty() {
            out.fill(None);
            return;
        }
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            let ray = Self::bvh_ray(r);
            let mut hit = RayHit::none();
            *o = if self
                .bvh
                .ray_traverse(ray, &mut hit, |ray, id| self.tris[id].intersect(ray))
            {
                let tri = &self.tris[hit.primitive_id as usize];
                let (instance, prim) = self.ids[hit.primitive_id as usize];
                // Barycentrics as in Embree's Möller–Trumbore kernel:
                // u weighs v1, v weighs v2.
                let e1 = tri.v0 - tri.v1;
                let e2 = tri.v2 - tri.v0;
                let n = e1.cross(e2);
                let c = tri.v0 - ray.origin;
                let rr = ray.direction.cross(c);
                let inv_det = 1.0 / n.dot(ray.direction);
                Some(Hit {
                    t: hit.t,
                    instance,
                    prim,
                    u: rr.dot(e2) * inv_det,
                    v: rr.dot(e1) * inv_det,
                    ng: Vec3::from((tri.v1 - tri.v0).cross(tri.v2 - tri.v0)),
                })
            } else {
                None
            };
        }
    }

    fn occluded(&self, rays: &[Ray], _coherence: Coherence, out: &mut [bool]) {
        assert_eq!(
            rays.len(),
            out.len(),
            "occluded: rays and out differ in length"
        );
        if self.tris.is_empty() {
            out.fill(false);
            return;
        }
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = !self
                .bvh
                .ray_traverse_miss(Self::bvh_ray(r), |ray, id| self.tris[id].intersect(ray));
        }
    }
}
