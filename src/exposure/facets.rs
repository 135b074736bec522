//! Facet frames and sample points: where exposure rays start.

use glam::Vec3;

use super::sampling::{orthonormal_basis, triangle_strata};
use crate::geometry::{SceneGeometry, triangle_normal_area};

/// Per-facet frames and stratified sample points, in global facet order
/// ([`SceneGeometry::facet_id`]).
///
/// Each facet carries `n²` points (`n` = `samples_per_edge`), the centroids
/// of its `n²` congruent sub-triangles, each standing for an equal share of
/// the area. Rays start at a point lifted by [`Self::offset_m`] along the
/// normal on the side they leave from, so that the facet never hits itself
/// and coplanar neighbours are not hit by grazing rays.
#[derive(Debug, Clone)]
pub struct FacetSamples {
    /// Unit front normal per facet, `(p1−p0)×(p2−p0)` normalised (`+z` for a
    /// degenerate facet).
    pub normal: Vec<Vec3>,
    /// Tangent per facet, completing `(tangent, bitangent, normal)`.
    pub tangent: Vec<Vec3>,
    /// Bitangent per facet.
    pub bitangent: Vec<Vec3>,
    /// Area per facet, m².
    pub area: Vec<f32>,
    /// Whether both faces of the facet are front faces (thin objects).
    pub double_sided: Vec<bool>,
    /// Sample points, `per_facet` consecutive entries per facet, on the
    /// facet's plane (not offset).
    pub points: Vec<Vec3>,
    /// Points per facet (`n²`).
    pub per_facet: usize,
    /// Distance, m, by which ray origins are lifted off the facet's plane.
    pub offset_m: f32,
    /// First global facet id of each instance (see
    /// [`SceneGeometry::facet_offsets`]), to turn hits into facet ids.
    pub instance_offsets: Vec<usize>,
}

impl FacetSamples {
    /// Frames and `samples_per_edge²` points per facet. `double_sided` has
    /// one entry per facet, or is empty (all single-sided). The origin
    /// offset is `offset_rel · (largest |coordinate| + scene diagonal)` —
    /// proportional to the scene's floating-point resolution — at least
    /// 1 µm.
    ///
    /// # Panics
    /// Never for valid geometry; `double_sided` of the wrong length is
    /// reported by [`super::compute_exposure`] before this is called.
    pub fn new(
        geometry: &SceneGeometry,
        double_sided: &[bool],
        samples_per_edge: u32,
        offset_rel: f32,
    ) -> Self {
        let n = geometry.facet_count();
        let strata = triangle_strata(samples_per_edge);
        let per = strata.len();
        let mut normal = Vec::with_capacity(n);
        let mut tangent = Vec::with_capacity(n);
        let mut bitangent = Vec::with_capacity(n);
        let mut area = Vec::with_capacity(n);
        let mut points = Vec::with_capacity(n * per);
        for (ii, inst) in geometry.instances.iter().enumerate() {
            let mesh = &geometry.meshes[inst.mesh];
            for prim in 0..mesh.triangle_count() {
                let t = geometry.world_triangle(ii, prim);
                let (nrm, a) = triangle_normal_area(&t);
                let (tg, bt) = orthonormal_basis(nrm);
                normal.push(nrm);
                tangent.push(tg);
                bitangent.push(bt);
                area.push(a);
                let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
                points.extend(strata.iter().map(|&(b1, b2)| t[0] + b1 * e1 + b2 * e2));
            }
        }
        let scale = geometry
            .bounds()
            .map(|(lo, hi)| lo.abs().max(hi.abs()).max_element() + (hi - lo).length())
            .unwrap_or(1.0);
        FacetSamples {
            normal,
            tangent,
            bitangent,
            area,
            double_sided: if double_sided.is_empty() {
                vec![false; n]
            } else {
                double_sided.to_vec()
            },
            points,
            per_facet: per,
            offset_m: (offset_rel * scale).max(1e-6),
            instance_offsets: geometry.facet_offsets(),
        }
    }

    /// Number of facets.
    pub fn len(&self) -> usize {
        self.normal.len()
    }

    /// Whether there are no facets.
    pub fn is_empty(&self) -> bool {
        self.normal.is_empty()
    }

    /// The sample points of `facet` (on its plane).
    pub fn facet_points(&self, facet: usize) -> &[Vec3] {
        &self.points[facet * self.per_facet..(facet + 1) * self.per_facet]
    }

    /// A local-frame direction (`z` along the normal) in world space, on the
    /// front (`side = 1`) or back (`side = −1`) of `facet`.
    pub fn to_world(&self, facet: usize, local: Vec3, side: f32) -> Vec3 {
        self.tangent[facet] * local.x
            + self.bitangent[facet] * (side * local.y)
            + self.normal[facet] * (side * local.z)
    }
}
