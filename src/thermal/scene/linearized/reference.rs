//! A reference facet of the linearised solve: its nonlinear solution and
//! Green's matrices ([`crate::thermal::Linearization`]) laid out for the
//! per-facet products.
//!
//! Owns [`Reference`] and its parts: the reference facet's own inputs
//! ([`RefFacet`]), the Green's matrices of each node with their products
//! with the source model ([`NodeGreen`]), and the probes that predict a
//! facet's change at a few records ([`Probes`]). Takes a
//! [`Linearization`], the probed records and the property set's
//! [`SourceModel`]; knows nothing of passes, bins or backgrounds.

use super::kernels::{GREEN_PADDING, dot};
use super::nodes::CurvatureNodes;
use crate::thermal::{Linearization, SourceModel};

/// What a facet's sources are made of besides its `s·max(cos θ, 0) + a`
/// history (see [`SourceModel`]): its shape factors and its reflected
/// diffuse coefficient.
#[derive(Clone, Copy)]
pub(super) struct FacetState {
    /// Shape factor of the front face.
    pub f: f32,
    /// Shape factor of the back face (`1 − F` for a single-sided facet).
    pub f_back: f32,
    /// Reflected shortwave per unit diffuse-horizontal irradiance (`b`).
    pub b: f32,
}

/// The reference facet's own inputs, from which a facet's differences are
/// taken.
pub(super) struct RefFacet {
    /// Shape factor of the front face.
    pub f: f32,
    /// Shape factor of the back face.
    pub f_back: f32,
    /// Reflected diffuse coefficient `b`.
    pub b: f32,
    /// `s·max(cos θ, 0) + a` history.
    pub sc: Vec<f32>,
}

/// One node (front surface or back face) of a reference: its Green's
/// matrices in `f32`, column-major (`g[k·R + t] = ∂T(t)/∂S_k`), their
/// products with the parts of the affine source model, and the
/// reference's own history of the node.
pub(super) struct NodeGreen {
    /// `∂T(t)/∂S_k`: the response to the front sources.
    pub from_front: Vec<f32>,
    /// `∂T(t)/∂B_k`: the response to the back sources (empty without an
    /// exposed back).
    pub from_back: Vec<f32>,
    /// `G·∂S/∂F`, K per unit of shape factor.
    pub shape: Vec<f32>,
    /// `G_b·∂B/∂F_b`, K per unit of back shape factor.
    pub back_shape: Vec<f32>,
    /// `G·(s cos θ_ref·αE_dn)`, K: the reference's own sun term.
    pub reference_sun: Vec<f32>,
    /// `G·∂S/∂b` (`G·αE_d`), K per unit of the reflected diffuse coefficient.
    pub reflected_diffuse: Vec<f32>,
    /// The reference's temperature of this node at each record, K.
    pub temperature_k: Vec<f32>,
    /// Radiative coefficient of this node's emission: `εσ` of the front,
    /// `a·εσ` of an exposed back (0 otherwise), W m⁻² K⁻⁴.
    pub radiative: f32,
    /// Vapour conductance of this node's latent loss at each record,
    /// W m⁻² Pa⁻¹ (empty: none; only the front of an evaporating surface).
    pub latent: Vec<f64>,
    /// `(e°, e°′)` at the reference's temperature at each record where
    /// `latent` is not empty ([`crate::thermal::linear::saturation_about`]).
    pub saturation: Vec<(f64, f64)>,
}

/// Probes of the front temperature: the rows of the image records (then
/// the first and last), and the column means `(1/R) Σ_t G[t][k]`, so that
/// a facet's first-order change at a probed record is one dot product over
/// its `s·max(cos θ, 0)` history plus a few scalars.
pub(super) struct Probes {
    /// Rows `[i][k]` of `∂T_front(rows[i])/∂S_k`.
    pub rows_front: Vec<f32>,
    /// Rows `[i][k]` of `∂T_front(rows[i])/∂B_k`.
    pub rows_back: Vec<f32>,
    /// `P_j[k]·αE_dn[k]`, `[j][k]`.
    pub sun: Vec<f32>,
    /// `P_j·∂S/∂F`, K per unit.
    pub shape: Vec<f32>,
    /// `P_fb,j·∂B/∂F_b`, K per unit.
    pub back_shape: Vec<f32>,
    /// `P_j·(s cos θ_ref·αE_dn)`, K.
    pub reference_sun: Vec<f32>,
    /// `P_j·∂S/∂b`, K per unit.
    pub reflected_diffuse: Vec<f32>,
}

/// A reference facet's linearisation in the layout the per-facet products
/// use: `T' = T_ref + G·ΔS` with
/// `ΔS = ΔF·∂S/∂F + (s cos θ − s cos θ_ref)·αE_dn (+ ΔF_b·∂B/∂F_b)`.
pub(super) struct Reference {
    /// Whether the back face is exposed (back sources exist).
    pub has_back: bool,
    /// The reference facet's inputs.
    pub facet: RefFacet,
    /// The front node.
    pub front: NodeGreen,
    /// The back node (its matrices empty without an exposed back).
    pub back: NodeGreen,
    /// Probes of the front node.
    pub probes: Probes,
    /// The front and back nodes at the curvature nodes only, for the
    /// second order ([`super::nodes`]; `None`: at every record).
    pub coarse: Option<Coarse>,
    /// The reference solve's last spin-up change, K.
    pub spinup_change_k: f64,
}

/// A reference at the curvature nodes ([`super::nodes`]): the rows of its
/// Green's matrices at the node records (`g[k·N + n]`, `N` nodes, so that
/// the history products run over `N` rows instead of `R`), and the weights
/// of the node curvatures in the image records.
pub(super) struct Coarse {
    /// The node records.
    pub records: Vec<u32>,
    /// The front node at the node records.
    pub front: NodeGreen,
    /// The back node at the node records (empty without an exposed back).
    pub back: NodeGreen,
    /// `[image][n]`: `Σ_k ∂T_front(image)/∂S_k φ_n(k)`, K per W m⁻².
    pub weights_front: Vec<f32>,
    /// `[image][n]`: `Σ_k ∂T_front(image)/∂B_k φ_n(k)`, K per W m⁻².
    pub weights_back: Vec<f32>,
}

impl Reference {
    /// Lays out `lin` (the linearisation about the facet `st` with
    /// `s·max(cos θ, 0) + a` history `sc`) for the probed `rows` and the
    /// property set's source `model`.
    pub fn new(
        lin: Linearization,
        rows: &[usize],
        images: usize,
        model: &SourceModel,
        st: FacetState,
        sc: Vec<f32>,
        nodes: Option<&CurvatureNodes>,
    ) -> Reference {
        let r = lin.records;
        let sun = model.front_per_sunlit_cos();
        let ref_sun: Vec<f64> = sc.iter().zip(sun).map(|(&c, w)| c as f64 * w).collect();
        let times = |g: &[f64], v: &[f64]| -> Vec<f32> {
            if g.is_empty() || v.is_empty() {
                return Vec::new();
            }
            (0..r)
                .map(|t| {
                    to_f32(
                        g[t * r..(t + 1) * r]
                            .iter()
                            .zip(v)
                            .map(|(a, b)| a * b)
                            .sum::<f64>(),
                    )
                })
                .collect()
        };
        let shape = model.front_per_shape_factor();
        let refl_diffuse = model.front_per_reflected_diffuse();
        let back_shape = model.back_per_shape_factor();
        let transpose = |g: &[f64]| -> Vec<f32> {
            if g.is_empty() {
                return Vec::new();
            }
            let mut out = vec![0.0f32; r * r + GREEN_PADDING];
            for t in 0..r {
                for k in 0..r {
                    out[k * r + t] = to_f32(g[t * r + k]);
                }
            }
            out
        };
        // Probe vectors (f64): the rows, then the column means.
        let probes = |g: &[f64]| -> Vec<Vec<f64>> {
            if g.is_empty() {
                return Vec::new();
            }
            let mut p: Vec<Vec<f64>> = rows
                .iter()
                .map(|&t| g[t * r..(t + 1) * r].to_vec())
                .collect();
            p.push(
                (0..r)
                    .map(|k| (0..r).map(|t| g[t * r + k]).sum::<f64>() / r as f64)
                    .collect(),
            );
            p
        };
        let (pf, pb) = (probes(&lin.front_from_front), probes(&lin.front_from_back));
        let dot64 = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let rows_of = |p: &[Vec<f64>]| -> Vec<f32> {
            p.iter()
                .take(rows.len())
                .flat_map(|v| v.iter().map(|&x| to_f32(x)))
                .collect()
        };
        let f32s = |v: &[f64]| v.iter().map(|&x| to_f32(x)).collect::<Vec<f32>>();
        let mut reference = Reference {
            has_back: lin.has_back(),
            front: NodeGreen {
                from_front: transpose(&lin.front_from_front),
                from_back: transpose(&lin.front_from_back),
                shape: times(&lin.front_from_front, shape),
                back_shape: times(&lin.front_from_back, back_shape),
                reference_sun: times(&lin.front_from_front, &ref_sun),
                reflected_diffuse: times(&lin.front_from_front, refl_diffuse),
                temperature_k: f32s(&lin.solution.surface_temperature_k),
                radiative: lin.front_radiative_w_m2_k4 as f32,
                latent: lin.front_vapour_conductance_w_m2_pa.clone(),
                saturation: Vec::new(),
            },
            back: NodeGreen {
                from_front: transpose(&lin.back_from_front),
                from_back: transpose(&lin.back_from_back),
                shape: times(&lin.back_from_front, shape),
                back_shape: times(&lin.back_from_back, back_shape),
                reference_sun: times(&lin.back_from_front, &ref_sun),
                reflected_diffuse: times(&lin.back_from_front, refl_diffuse),
                temperature_k: f32s(&lin.solution.back_temperature_k),
                radiative: lin.back_radiative_w_m2_k4 as f32,
                latent: Vec::new(),
                saturation: Vec::new(),
            },
            probes: Probes {
                rows_front: rows_of(&pf),
                rows_back: rows_of(&pb),
                sun: pf
                    .iter()
                    .flat_map(|p| p.iter().zip(sun).map(|(a, b)| to_f32(a * b)))
                    .collect(),
                shape: pf.iter().map(|p| to_f32(dot64(p, shape))).collect(),
                back_shape: pb.iter().map(|p| to_f32(dot64(p, back_shape))).collect(),
                reference_sun: pf.iter().map(|p| to_f32(dot64(p, &ref_sun))).collect(),
                reflected_diffuse: pf.iter().map(|p| to_f32(dot64(p, refl_diffuse))).collect(),
            },
            coarse: None,
            spinup_change_k: lin.solution.spinup_change_k.unwrap_or(0.0),
            facet: RefFacet {
                f: st.f,
                f_back: st.f_back,
                b: st.b,
                sc,
            },
        };
        reference.front.saturation = saturation_of(&reference.front);
        if let Some(nodes) = nodes {
            let c = Coarse::new(&lin, &reference, nodes, &pf, &pb, images);
            reference.coarse = Some(c);
        }
        reference
    }

    /// First-order change of the front temperature at probe `j` (K) of a
    /// facet with `s·max(cos θ, 0) + a` history `sc`, shape factors `df`,
    /// `dfb` and reflected diffuse coefficient `db` from the reference's,
    /// with the air as background.
    #[inline]
    pub fn probe(&self, j: usize, sc: &[f32], d: Diff) -> f32 {
        let p = &self.probes;
        let r = sc.len();
        let Diff { df, dfb, db } = d;
        let mut v = dot(&p.sun[j * r..(j + 1) * r], sc) - p.reference_sun[j]
            + df * p.shape[j]
            + db * p.reflected_diffuse[j];
        if self.has_back {
            v += dfb * p.back_shape[j];
        }
        v
    }

    /// Row `i` (an image record) of the front node's response to the front
    /// sources.
    #[inline]
    pub fn row_front(&self, i: usize) -> &[f32] {
        let r = self.facet.sc.len();
        &self.probes.rows_front[i * r..(i + 1) * r]
    }

    /// Row `i` (an image record) of the front node's response to the back
    /// sources.
    #[inline]
    pub fn row_back(&self, i: usize) -> &[f32] {
        let r = self.facet.sc.len();
        &self.probes.rows_back[i * r..(i + 1) * r]
    }
}

impl Coarse {
    /// `rep` (laid out from `lin`) at the curvature `nodes`; `pf`, `pb` the
    /// probe rows of the front node's response to the front and back
    /// sources (the first `images` are the image records).
    fn new(
        lin: &Linearization,
        rep: &Reference,
        nodes: &CurvatureNodes,
        pf: &[Vec<f64>],
        pb: &[Vec<f64>],
        images: usize,
    ) -> Coarse {
        let r = lin.records;
        let nn = nodes.len();
        // Rows of `g` (row-major `[t][k]`) at the nodes, column-major.
        let node_rows = |g: &[f64]| -> Vec<f32> {
            if g.is_empty() {
                return Vec::new();
            }
            let mut out = vec![0.0f32; r * nn + GREEN_PADDING];
            for (n, &t) in nodes.records.iter().enumerate() {
                for k in 0..r {
                    out[k * nn + n] = to_f32(g[t * r + k]);
                }
            }
            out
        };
        let node = |from_front: &[f64], from_back: &[f64], full: &NodeGreen| NodeGreen {
            from_front: node_rows(from_front),
            from_back: node_rows(from_back),
            shape: pick(&full.shape, nodes),
            back_shape: pick(&full.back_shape, nodes),
            reference_sun: pick(&full.reference_sun, nodes),
            reflected_diffuse: pick(&full.reflected_diffuse, nodes),
            temperature_k: pick(&full.temperature_k, nodes),
            radiative: full.radiative,
            latent: if full.latent.is_empty() {
                Vec::new()
            } else {
                nodes.records.iter().map(|&t| full.latent[t]).collect()
            },
            saturation: if full.saturation.is_empty() {
                Vec::new()
            } else {
                nodes.records.iter().map(|&t| full.saturation[t]).collect()
            },
        };
        let weights = |p: &[Vec<f64>]| -> Vec<f32> {
            p.iter()
                .take(images)
                .flat_map(|row| nodes.weights(row).into_iter().map(to_f32))
                .collect()
        };
        Coarse {
            records: nodes.records.iter().map(|&t| t as u32).collect(),
            front: node(&lin.front_from_front, &lin.front_from_back, &rep.front),
            back: node(&lin.back_from_front, &lin.back_from_back, &rep.back),
            weights_front: weights(pf),
            weights_back: weights(pb),
        }
    }
}

/// `(e°, e°′)` at `node`'s temperature at each record, where it has a latent
/// loss (empty otherwise), as the second order takes it (`f64` of the
/// `f32` temperature).
fn saturation_of(node: &NodeGreen) -> Vec<(f64, f64)> {
    if node.latent.is_empty() {
        return Vec::new();
    }
    node.temperature_k
        .iter()
        .map(|&t| crate::thermal::linear::saturation_about(f64::from(t)))
        .collect()
}

/// The entries of `v` (one per record; empty stays empty) at the nodes.
fn pick(v: &[f32], nodes: &CurvatureNodes) -> Vec<f32> {
    if v.is_empty() {
        return Vec::new();
    }
    nodes.records.iter().map(|&t| v[t]).collect()
}

/// A facet's differences from its reference in the scalar inputs: shape
/// factors of the front and back, reflected diffuse coefficient.
#[derive(Clone, Copy)]
pub(super) struct Diff {
    pub df: f32,
    pub dfb: f32,
    pub db: f32,
}

impl Diff {
    /// `st`'s differences from the reference `rep`.
    #[inline]
    pub fn of(st: &FacetState, rep: &RefFacet) -> Diff {
        Diff {
            df: st.f - rep.f,
            dfb: st.f_back - rep.f_back,
            db: st.b - rep.b,
        }
    }
}

/// `x` in single precision, with magnitudes below [`NEGLIGIBLE`] flushed to
/// a signed zero. The Green's functions decay by tens of orders of magnitude
/// over a history; their far tails carry nothing the `f32` sums can keep
/// (a response of 10⁻³⁰ K per W m⁻² is 25 orders below a temperature's
/// `f32` resolution), but products with them land in the subnormal range,
/// where every operation takes the CPU's slow path (the town's thermal
/// solve ran 0.31 s instead of 0.22 s). Flushing them leaves the images
/// bit-identical.
#[inline]
fn to_f32(x: f64) -> f32 {
    let y = x as f32;
    if y.abs() < NEGLIGIBLE {
        0.0f32.copysign(y)
    } else {
        y
    }
}

/// Below this magnitude a Green's-function entry, K per W m⁻² (or its
/// products with the forcing), is dropped: see [`to_f32`].
const NEGLIGIBLE: f32 = 1e-30;
