//! Stage 4, the sensor path: the transmittance τ₂ and path radiance L_u of
//! [`crate::render::path::PathTables`] folded into each band's quadrature
//! weights per path node ([`FastPath`]), so that the band stage reads
//! `Σ w·τ₂·X` and `Σ w·L_u` directly.

use rayon::prelude::*;

use super::Shader;
use super::band::{GreyTables, Integrals, LANES};
use crate::render::path::PathTables;

/// The sensor path folded into the band weights, per range node of the
/// [`PathTables`]: `w·τ₂(λ)` per band and the band path radiance `Σ w·L_u`.
#[derive(Debug, Clone)]
pub(super) struct FastPath {
    /// Per band, per node: `w·τ₂` on the band's grid.
    pub(super) weighted_tau: Vec<Vec<Vec<f32>>>,
    /// Per band, per node: `Σ w·L_u`, W·m⁻²·sr⁻¹.
    pub(super) path_radiance: Vec<Vec<f64>>,
    /// Per band, per node: the band integrals weighted by `w·τ₂`.
    pub(super) integrals: Vec<Vec<Integrals>>,
    /// By day: per band, per node, per scattering-angle node the band
    /// scattered sunlight `Σ w·L_ss(Θ_k)`, W·m⁻²·sr⁻¹ (empty at night).
    pub(super) scatter: Vec<Vec<Vec<f64>>>,
    /// Unit vector toward the sun for the scattering angle (by day).
    pub(super) sun: Option<glam::Vec3>,
}

impl Shader<'_> {
    /// The same shader applying the sensor path's τ₂ and L_u to primary
    /// hits ([`Shader::shade_primary`], [`Shader::fast_primary`]); `None`:
    /// no atmosphere.
    pub fn with_path(mut self, path: Option<PathTables>) -> Self {
        self.fast_path = path.as_ref().map(|p| FastPath {
            weighted_tau: self
                .bands
                .iter()
                .enumerate()
                .map(|(b, t)| {
                    p.bands[b]
                        .iter()
                        .map(|(tau, _)| {
                            let len = t.band.len().div_ceil(LANES) * LANES;
                            let mut v: Vec<f32> = t
                                .band
                                .weights_um()
                                .iter()
                                .zip(tau)
                                .map(|(w, x)| (w * x) as f32)
                                .collect();
                            v.resize(len, 0.0);
                            v
                        })
                        .collect()
                })
                .collect(),
            path_radiance: self
                .bands
                .iter()
                .enumerate()
                .map(|(b, t)| {
                    p.bands[b]
                        .iter()
                        .map(|(_, lu)| t.band.integrate(lu))
                        .collect()
                })
                .collect(),
            integrals: self
                .bands
                .iter()
                .enumerate()
                .map(|(b, t)| {
                    // Per node: nodes × temperature nodes × wavelengths
                    // products, in parallel.
                    p.bands[b]
                        .par_iter()
                        .map(|(tau, _)| {
                            let q: Vec<f64> = t
                                .band
                                .weights_um()
                                .iter()
                                .zip(tau)
                                .map(|(w, x)| w * x)
                                .collect();
                            Integrals::new(&q, t, &self.table, self.total)
                        })
                        .collect()
                })
                .collect(),
            scatter: p.scatter.as_ref().map_or(Vec::new(), |sc| {
                self.bands
                    .iter()
                    .zip(&sc.bands)
                    .map(|(t, nodes)| {
                        nodes
                            .iter()
                            .map(|angles| angles.iter().map(|l| t.band.integrate(l)).collect())
                            .collect()
                    })
                    .collect()
            }),
            sun: p
                .scatter
                .as_ref()
                .map(|sc| glam::DVec3::from_array(sc.sun_direction).as_vec3()),
        });
        if let (Some(p), Some(fp)) = (&path, &self.fast_path) {
            let nodes: Vec<Vec<(&Integrals, f64)>> = fp
                .integrals
                .iter()
                .zip(&fp.path_radiance)
                .map(|(ig, lu)| ig.iter().zip(lu.iter().copied()).collect())
                .collect();
            self.grey_tables = GreyTables::new(
                &self.fast,
                &nodes,
                &p.ranges_m,
                &p.heights_m,
                &self.optics.materials,
            )
            .with_scatter(&fp.scatter, fp.sun);
            // The per-facet terms hold for the plain weights only.
            self.grey_terms = Vec::new();
        }
        self.path = path;
        self
    }
}
