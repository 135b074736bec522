//! Scene geometry as the ray tracer sees it: triangle meshes, stored once, and
//! instances of them placed in the world by an affine transform.
//!
//! # Conventions
//! World space is a local east-north-up frame in metres: `x` east, `y` north,
//! `z` up, origin at the scene's site. A *facet* is one triangle of one
//! instance: the same mesh placed twice gives two sets of facets (they see
//! different sun and sky). Facets are numbered globally, instance by instance,
//! in instance order then primitive order ([`SceneGeometry::facet_id`]).
//!
//! Takes triangles and transforms; gives facets, their normals, areas and
//! sample points. It must not know materials, files or ray-tracing backends.

use glam::{Affine3A, Vec3};

pub mod procedural;

/// One entry of a facet's background: another facet seen from it, with the
/// share of the facet's cosine-weighted hemisphere it fills (a view factor).
/// The exposure traces these ([`crate::exposure::SkyView`]); the scene
/// thermal solve reads them ([`crate::thermal::scene::SceneInputs`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BackgroundEntry {
    /// Global facet id of the facet seen ([`SceneGeometry::facet_id`]).
    pub facet: u32,
    /// Its view factor from this facet (share of `∫cosθ dω/π`).
    pub weight: f32,
}

/// A triangle mesh in its own (object) space.
#[derive(Debug, Clone, Default)]
pub struct TriangleMesh {
    /// Name, for messages and summaries.
    pub name: String,
    /// Vertex positions, metres (object space).
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`, counter-clockwise seen from the
    /// front (the geometric normal is `(p1 - p0) × (p2 - p0)`).
    pub indices: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }
    /// The three vertices of triangle `prim` in object space.
    pub fn triangle(&self, prim: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[prim];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }
}

/// One placement of a mesh in the world.
#[derive(Debug, Clone)]
pub struct Instance {
    /// Index into [`SceneGeometry::meshes`].
    pub mesh: usize,
    /// Object space → world space.
    pub world_from_object: Affine3A,
}

/// All geometry of a scene: meshes stored once, placed by instances.
#[derive(Debug, Clone, Default)]
pub struct SceneGeometry {
    /// The meshes.
    pub meshes: Vec<TriangleMesh>,
    /// The placements. A mesh used once still has one instance.
    pub instances: Vec<Instance>,
}

impl SceneGeometry {
    /// Geometry with a single mesh placed once at the identity.
    pub fn single(mesh: TriangleMesh) -> Self {
        SceneGeometry {
            meshes: vec![mesh],
            instances: vec![Instance {
                mesh: 0,
                world_from_object: Affine3A::IDENTITY,
            }],
        }
    }

    /// Offsets of each instance's first facet in the global facet numbering;
    /// one more entry than instances (the last is the facet count).
    pub fn facet_offsets(&self) -> Vec<usize> {
        let mut off = Vec::with_capacity(self.instances.len() + 1);
        let mut n = 0;
        off.push(0);
        for inst in &self.instances {
            n += self.meshes[inst.mesh].triangle_count();
            off.push(n);
        }
        off
    }

    /// Total number of facets (triangles over all instances).
    pub fn facet_count(&self) -> usize {
        self.instances
            .iter()
            .map(|i| self.meshes[i.mesh].triangle_count())
            .sum()
    }

    /// Number of distinct triangles stored (each mesh once).
    pub fn stored_triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.triangle_count()).sum()
    }

    /// Global facet id of primitive `prim` of instance `instance`, given
    /// offsets from [`Self::facet_offsets`].
    pub fn facet_id(offsets: &[usize], instance: u32, prim: u32) -> usize {
        offsets[instance as usize] + prim as usize
    }

    /// World-space vertices of primitive `prim` of instance `instance`.
    pub fn world_triangle(&self, instance: usize, prim: usize) -> [Vec3; 3] {
        let inst = &self.instances[instance];
        let t = self.meshes[inst.mesh].triangle(prim);
        t.map(|p| inst.world_from_object.transform_point3(p))
    }

    /// Axis-aligned world bounding box `(min, max)`; `None` when empty.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        let mut any = false;
        for inst in &self.instances {
            for p in &self.meshes[inst.mesh].positions {
                let w = inst.world_from_object.transform_point3(*p);
                lo = lo.min(w);
                hi = hi.max(w);
                any = true;
            }
        }
        any.then_some((lo, hi))
    }

    /// The geometry flattened into one world-space mesh (instances expanded),
    /// in global facet order. Used by backends without instancing and by tests.
    pub fn flatten(&self) -> TriangleMesh {
        let mut out = TriangleMesh {
            name: "flattened".into(),
            ..Default::default()
        };
        for inst in &self.instances {
            let m = &self.meshes[inst.mesh];
            let base = out.positions.len() as u32;
            out.positions.extend(
                m.positions
                    .iter()
                    .map(|p| inst.world_from_object.transform_point3(*p)),
            );
            out.indices.extend(
                m.indices
                    .iter()
                    .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
            );
        }
        out
    }
}

/// Cosine of the solar incidence angle on a facet with unit front normal
/// `normal` for the unit vector toward the sun `sun`: `n·s`, or `|n·s|` for
/// a double-sided facet (the face toward the sun is lit); 0 with the sun at
/// or below the horizon (`z ≤ 0`) or behind a single-sided facet; at most 1.
/// The one rule of the solar history ([`crate::exposure::SolarHistory`]),
/// which recomputes it rather than storing it.
#[inline]
pub fn sun_cosine(normal: Vec3, double_sided: bool, sun: Vec3) -> f32 {
    if sun.z <= 0.0 {
        return 0.0;
    }
    let c = normal.dot(sun);
    if double_sided || c > 0.0 {
        c.abs().min(1.0)
    } else {
        0.0
    }
}

/// Geometric (unnormalised-area) quantities of a world triangle.
pub fn triangle_normal_area(t: &[Vec3; 3]) -> (Vec3, f32) {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let len = n.length();
    if len > 0.0 {
        (n / len, 0.5 * len)
    } else {
        (Vec3::Z, 0.0)
    }
}
