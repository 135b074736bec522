//! The tangent-linear slab model: how a facet's surface-temperature history
//! responds to its surface heat sources, for the scene-wide solve of many
//! facets that share one material.
//!
//! # Why
//! In the slab model only the emission `εσT⁴` is nonlinear: conduction,
//! convection `h(u)(T_air − T)` and film coefficients are linear in the
//! temperatures, and every facet-specific input — absorbed direct solar
//! `α E_dn s cos θ`, diffuse `α F E_d`, sky longwave `ε F E_sky`, background
//! `ε(1−F)σT_bg⁴`, self power — enters only through the temperature-free
//! part `S` of the boundary flux law `q = S − H·T − R·T⁴`
//! ([`super::SurfaceFlux::source_w_m2`]). Facets with the same properties
//! therefore share one discrete operator and differ only in their source
//! histories `S_k` (front) and `B_k` (the back face, when it is exposed).
//!
//! # What
//! [`linearize`] solves one facet (the *reference*) with the full nonlinear
//! model and carries the tangent-linear model of every TR-BDF2 step along
//! (the derivative of the discrete scheme itself: stage equations
//! linearised about the reference's stage temperatures, the same
//! tridiagonal operators, Thomas solves with one right-hand side per
//! source record). The result, [`Linearization`], holds the Green's
//! matrices `G[t][k] = ∂T(t)/∂S_k` (K per W m⁻²) of the front (and back)
//! node temperature at every record `t` with respect to the front (and back)
//! source at every record `k` — spin-up included: with `c` spin-up cycles
//! of the first period, `∂x₀/∂S = Σ_{j<c} Φʲ Ψ` where `Φ = ∂x(P)/∂x(0)`,
//! `Ψ = ∂x(P)/∂S` are the one-period maps, taken from the real run's first
//! period (the reference is periodic to within the spin-up tolerance there).
//!
//! A facet with sources `S' = S + ΔS` then has, to first order,
//! `T'(t) = T(t) + Σ_k G[t][k] ΔS_k` ([`Linearization::predict`]). The
//! neglected term is the curvature of the emission,
//! `r = −εσ[(T+Δ)⁴ − T⁴ − 4T³Δ] = −εσΔ²(6T² + 4TΔ + Δ²)` (W m⁻²); the
//! second-order correction adds `G r(Δ)` with `Δ` the first-order change
//! (one fixed-point iteration of `Δ = G(ΔS + r(Δ))`), leaving an error
//! of third order in `Δ`.
//!
//! The tangent-linear and adjoint views give the same matrix (one forward
//! sweep with one column per source, or one backward sweep per output
//! record); the forward sweep is used because every output record is needed
//! (the neighbours' temperature histories drive the background term of the
//! second pass). Reference: the tangent-linear model of a discrete scheme,
//! e.g. Errico, "What is an adjoint model?", Bull. Amer. Meteor. Soc.
//! 78(11), 1997, doi:10.1175/1520-0477(1997)078<2577:WIAAM>2.0.CO;2.

use super::conduction::{GAMMA, Slab};
use super::{
    BackBoundary, Exchange, FacetInputs, Forcing, SlabProperties, SolveOptions, ThermalSolution,
    prepare, solve_prepared,
};
use crate::error::Result;
use crate::thermal::Boundary;

/// The surface-source histories of one facet (the temperature-free part of
/// its boundary flux laws at each record), W m⁻².
#[derive(Debug, Clone, PartialEq)]
pub struct SourceHistory {
    /// Front surface: absorbed solar and longwave, `h·T_air`, self power.
    pub front_w_m2: Vec<f64>,
    /// Back face, for [`BackBoundary::Exposed`] only (None otherwise: the
    /// back law is then the same for every facet of the material).
    pub back_w_m2: Option<Vec<f64>>,
}

/// The source histories of a facet (validated like [`super::solve`]).
pub fn source_history(
    props: &SlabProperties,
    forcing: &Forcing,
    inputs: &FacetInputs,
) -> Result<SourceHistory> {
    props.validate()?;
    forcing.validate()?;
    inputs.validate(forcing.len())?;
    let exchange = Exchange::new(props, forcing)?;
    source_history_with(props, forcing, &exchange, inputs)
}

/// [`source_history`] with the material's exchange made
/// ([`Exchange::new`]); properties and forcing taken as validated.
pub fn source_history_with(
    props: &SlabProperties,
    forcing: &Forcing,
    exchange: &Exchange,
    inputs: &FacetInputs,
) -> Result<SourceHistory> {
    inputs.validate(forcing.len())?;
    exchange.check_len(forcing.len())?;
    let p = prepare(props, forcing, inputs, exchange);
    Ok(SourceHistory {
        // A two-source canopy's source is the absorbed incoming radiation
        // (its soil law's source is affine in it, `super::two_source`).
        front_w_m2: if p.incoming.is_empty() {
            p.front.iter().map(|f| f.source_w_m2).collect()
        } else {
            p.incoming.clone()
        },
        back_w_m2: matches!(props.back, BackBoundary::Exposed { .. }).then(|| {
            p.back
                .iter()
                .map(|b| match b {
                    Boundary::Flux(f) => f.source_w_m2,
                    Boundary::Temperature(_) => 0.0,
                })
                .collect()
        }),
    })
}

/// [`source_history`] into caller buffers (one value per record; `back` is
/// filled only for an exposed back), without allocating: for scene solves
/// over many facets. The properties and forcing are not validated here
/// (the caller has); the facet inputs are.
pub fn source_history_into(
    props: &SlabProperties,
    forcing: &Forcing,
    exchange: &Exchange,
    inputs: &FacetInputs,
    front: &mut [f64],
    back: &mut [f64],
) -> Result<()> {
    let n = forcing.len();
    inputs.validate(n)?;
    let f_back = inputs
        .back_shape_factor
        .unwrap_or(1.0 - inputs.shape_factor);
    let exposed = match props.back {
        BackBoundary::Exposed { fraction } => Some(fraction),
        _ => None,
    };
    for k in 0..n {
        let ff = super::front_forcing_at(forcing, exchange, inputs, k);
        front[k] = super::balance::front_flux(
            &ff,
            props.solar_absorptivity,
            props.thermal_emissivity,
            props.self_power_w_m2,
        )
        .source_w_m2;
        if let Some(a) = exposed {
            back[k] = super::balance::exposed_back_flux(&ff, props.thermal_emissivity, f_back, a)
                .source_w_m2;
        }
    }
    Ok(())
}

/// The source histories of every facet of one property set under one
/// weather history, with the air as background, as affine functions of the
/// facet's inputs: front `S_k = base_k + F·shape_k + (s_k·max(cos θ_k, 0) +
/// a_k)·sun_k + b·reflected_diffuse_k`, exposed back `B_k = back_base_k +
/// F_b·back_shape_k` (W m⁻²), with `a_k`, `b` the facet's reflected-shortwave
/// coefficients ([`super::Reflected`]: the reflected direct sunlight
/// weighs like the facet's own, `α E_dn`). The coefficients are evaluated
/// from the balance itself ([`super::balance::front_flux`],
/// [`super::balance::exposed_back_flux`]), which is affine in `F`, `F_b`,
/// `s·cos θ`, `a` and `b`; this makes a facet's source history a few
/// operations per record, for scenes of many facets.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceModel {
    base: Vec<f64>,
    shape: Vec<f64>,
    sun: Vec<f64>,
    reflected_diffuse: Vec<f64>,
    back_base: Vec<f64>,
    back_shape: Vec<f64>,
}

impl SourceModel {
    /// The model of `props` under `forcing` with the material's exchange
    /// ([`Exchange::new`]); not validated here.
    pub fn new(props: &SlabProperties, forcing: &Forcing, exchange: &Exchange) -> SourceModel {
        let n = forcing.len();
        let one = vec![1.0f32; n];
        let zero = vec![0.0f32; n];
        let eval = |sun: &[f32], cos: &[f32], f: f64, f_back: f64, b: f64| {
            let inputs = FacetInputs {
                back_shape_factor: Some(f_back),
                reflected: super::Reflected {
                    direct: &[],
                    diffuse: b,
                },
                ..FacetInputs::new(sun, cos, f)
            };
            let mut front = vec![0.0; n];
            let mut back = vec![0.0; n];
            for k in 0..n {
                let ff = super::front_forcing_at(forcing, exchange, &inputs, k);
                front[k] = super::balance::front_flux(
                    &ff,
                    props.solar_absorptivity,
                    props.thermal_emissivity,
                    props.self_power_w_m2,
                )
                .source_w_m2;
                if let BackBoundary::Exposed { fraction } = props.back {
                    back[k] = super::balance::exposed_back_flux(
                        &ff,
                        props.thermal_emissivity,
                        f_back,
                        fraction,
                    )
                    .source_w_m2;
                }
            }
            (front, back)
        };
        let (s0, b0) = eval(&zero, &zero, 0.0, 0.0, 0.0);
        let (s1, b1) = eval(&zero, &zero, 1.0, 1.0, 0.0);
        let (s2, _) = eval(&one, &one, 0.0, 0.0, 0.0);
        let (s3, _) = eval(&zero, &zero, 0.0, 0.0, 1.0);
        let sub = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x - y).collect::<Vec<_>>();
        let exposed = matches!(props.back, BackBoundary::Exposed { .. });
        SourceModel {
            shape: sub(&s1, &s0),
            sun: sub(&s2, &s0),
            reflected_diffuse: sub(&s3, &s0),
            base: s0,
            back_shape: if exposed { sub(&b1, &b0) } else { Vec::new() },
            back_base: if exposed { b0 } else { Vec::new() },
        }
    }

    /// Whether the back face has a source (exposed back).
    pub fn has_back(&self) -> bool {
        !self.back_base.is_empty()
    }

    /// `∂S_k/∂F` per record, W m⁻².
    pub fn front_per_shape_factor(&self) -> &[f64] {
        &self.shape
    }

    /// `∂S_k/∂(s·max(cos θ, 0))` per record (the absorbed direct-normal
    /// irradiance `α E_dn`), W m⁻².
    pub fn front_per_sunlit_cos(&self) -> &[f64] {
        &self.sun
    }

    /// `∂S_k/∂b` per record (the absorbed diffuse-horizontal irradiance
    /// `α E_d`), W m⁻².
    pub fn front_per_reflected_diffuse(&self) -> &[f64] {
        &self.reflected_diffuse
    }

    /// `∂B_k/∂F_b` per record (empty without an exposed back), W m⁻².
    pub fn back_per_shape_factor(&self) -> &[f64] {
        &self.back_shape
    }

    /// Front source history of a facet (sun fraction, cos θ, shape factor
    /// `f`, no reflected shortwave) into `out`, W m⁻².
    pub fn front_into(&self, sun_fraction: &[f32], cos_incidence: &[f32], f: f64, out: &mut [f32]) {
        self.front_reflected_into(sun_fraction, cos_incidence, f, super::Reflected::NONE, out);
    }

    /// [`SourceModel::front_into`] with the reflected shortwave `refl`.
    pub fn front_reflected_into(
        &self,
        sun_fraction: &[f32],
        cos_incidence: &[f32],
        f: f64,
        refl: super::Reflected,
        out: &mut [f32],
    ) {
        for k in 0..out.len() {
            let sc = (sun_fraction[k].clamp(0.0, 1.0) * cos_incidence[k].max(0.0)) as f64
                + refl.direct_at(k);
            out[k] = (self.base[k]
                + f * self.shape[k]
                + sc * self.sun[k]
                + refl.diffuse * self.reflected_diffuse[k]) as f32;
        }
    }

    /// Back source history (back shape factor `f_back`) into `out`, W m⁻²
    /// (zeros without an exposed back).
    pub fn back_into(&self, f_back: f64, out: &mut [f32]) {
        if !self.has_back() {
            out.iter_mut().for_each(|v| *v = 0.0);
            return;
        }
        for (k, o) in out.iter_mut().enumerate() {
            *o = (self.back_base[k] + f_back * self.back_shape[k]) as f32;
        }
    }
}

/// How a facet's sources depend on its background: `∂S/∂(σT_bg⁴)` of the
/// front (`ε(1 − F)`) and of an exposed back (`a·ε(1 − F_b)`, 0 otherwise),
/// dimensionless (the background term of [`super::balance::front_flux`] and
/// [`super::balance::exposed_back_flux`]). A change of the background from
/// `T₁` to `T₂` at a record changes the sources there by these times
/// `σ(T₂⁴ − T₁⁴)`.
pub fn background_coefficients(
    props: &SlabProperties,
    shape_factor: f64,
    back_shape_factor: Option<f64>,
) -> (f64, f64) {
    let eps = props.thermal_emissivity;
    let front = eps * (1.0 - shape_factor);
    let back = match props.back {
        BackBoundary::Exposed { fraction } => {
            fraction * eps * (1.0 - back_shape_factor.unwrap_or(1.0 - shape_factor))
        }
        _ => 0.0,
    };
    (front, back)
}

/// A reference facet's nonlinear solution and its Green's matrices.
#[derive(Debug, Clone)]
pub struct Linearization {
    /// Records of the history.
    pub records: usize,
    /// The nonlinear solution of the reference facet.
    pub solution: ThermalSolution,
    /// The reference's source histories.
    pub sources: SourceHistory,
    /// `εσ` of the front face, W m⁻² K⁻⁴.
    pub front_radiative_w_m2_k4: f64,
    /// Vapour conductance of the front law at each record, W m⁻² Pa⁻¹
    /// (empty for a dry surface): the latent term whose `e°(T)` curvature
    /// the second order adds ([`latent_curvature`]).
    pub front_vapour_conductance_w_m2_pa: Vec<f64>,
    /// `a·εσ` of an exposed back face (0 otherwise), W m⁻² K⁻⁴.
    pub back_radiative_w_m2_k4: f64,
    /// `∂T_front(t)/∂S_k`, row-major `[t][k]`, K per W m⁻².
    pub front_from_front: Vec<f64>,
    /// `∂T_front(t)/∂B_k` (exposed back only, else empty).
    pub front_from_back: Vec<f64>,
    /// `∂T_back(t)/∂S_k` (exposed back only, else empty).
    pub back_from_front: Vec<f64>,
    /// `∂T_back(t)/∂B_k` (exposed back only, else empty).
    pub back_from_back: Vec<f64>,
}

impl Linearization {
    /// Whether the back face has its own source (exposed back).
    pub fn has_back(&self) -> bool {
        !self.front_from_back.is_empty()
    }

    /// Front-surface temperature history of a facet with the same
    /// properties and weather and source histories `front` (and `back`,
    /// required when [`Linearization::has_back`]), K: the reference's plus
    /// the Green's matrices times the source differences, plus (when
    /// `second_order`) the correction for the curvature of the emission
    /// (module docs).
    pub fn predict(&self, front: &[f64], back: Option<&[f64]>, second_order: bool) -> Vec<f64> {
        let n = self.records;
        assert_eq!(front.len(), n, "one front source per record");
        let ds: Vec<f64> = front
            .iter()
            .zip(&self.sources.front_w_m2)
            .map(|(a, b)| a - b)
            .collect();
        let db: Option<Vec<f64>> = if self.has_back() {
            let back = back.expect("an exposed back needs its source history");
            let r = self.sources.back_w_m2.as_ref().expect("exposed back");
            Some(back.iter().zip(r).map(|(a, b)| a - b).collect())
        } else {
            None
        };
        let apply = |g_front: &[f64], g_back: &[f64], x: &[f64], y: Option<&[f64]>| {
            let mut out = vec![0.0; n];
            for (t, o) in out.iter_mut().enumerate() {
                let row = &g_front[t * n..(t + 1) * n];
                let mut s: f64 = row.iter().zip(x).map(|(g, v)| g * v).sum();
                if let Some(y) = y {
                    let row = &g_back[t * n..(t + 1) * n];
                    s += row.iter().zip(y).map(|(g, v)| g * v).sum::<f64>();
                }
                *o = s;
            }
            out
        };
        let mut d = apply(
            &self.front_from_front,
            &self.front_from_back,
            &ds,
            db.as_deref(),
        );
        if second_order {
            let t_ref = &self.solution.surface_temperature_k;
            let rf: Vec<f64> = d
                .iter()
                .zip(t_ref)
                .enumerate()
                .map(|(k, (&dt, &t))| {
                    emission_curvature(self.front_radiative_w_m2_k4, t, dt)
                        + self
                            .front_vapour_conductance_w_m2_pa
                            .get(k)
                            .map_or(0.0, |&g| latent_curvature(g, t, dt))
                })
                .collect();
            let rb = if self.has_back() {
                let db = db.as_deref().expect("exposed back");
                let dback = apply(&self.back_from_front, &self.back_from_back, &ds, Some(db));
                Some(
                    dback
                        .iter()
                        .zip(&self.solution.back_temperature_k)
                        .map(|(&dt, &t)| emission_curvature(self.back_radiative_w_m2_k4, t, dt))
                        .collect::<Vec<f64>>(),
                )
            } else {
                None
            };
            let c = apply(
                &self.front_from_front,
                &self.front_from_back,
                &rf,
                rb.as_deref(),
            );
            d.iter_mut().zip(c).for_each(|(a, b)| *a += b);
        }
        d.iter()
            .zip(&self.solution.surface_temperature_k)
            .map(|(a, b)| a + b)
            .collect()
    }
}

/// The neglected curvature of the emission `−R T⁴` about `t_k` for a change
/// `dt_k`: `−R[(T+Δ)⁴ − T⁴ − 4T³Δ] = −RΔ²(6T² + 4TΔ + Δ²)`, W m⁻².
#[inline]
pub fn emission_curvature(radiative_w_m2_k4: f64, t_k: f64, dt_k: f64) -> f64 {
    -radiative_w_m2_k4 * dt_k * dt_k * (6.0 * t_k * t_k + 4.0 * t_k * dt_k + dt_k * dt_k)
}

/// The neglected curvature of the latent loss `−g_v e°(T)` about `t_k` for
/// a change `dt_k`: `−g_v[e°(T+Δ) − e°(T) − e°′(T)Δ]`, W m⁻² (e° by FAO-56
/// eq. 11, its slope by eq. 13).
#[inline]
pub fn latent_curvature(vapour_conductance_w_m2_pa: f64, t_k: f64, dt_k: f64) -> f64 {
    if vapour_conductance_w_m2_pa == 0.0 {
        return 0.0;
    }
    latent_curvature_about(vapour_conductance_w_m2_pa, saturation_about(t_k), t_k, dt_k)
}

/// `(e°(T), e°′(T))` at `t_k`, Pa and Pa K⁻¹ (FAO-56 eqs. 11, 13): what
/// [`latent_curvature_about`] takes of the point it expands about.
#[inline]
pub fn saturation_about(t_k: f64) -> (f64, f64) {
    use super::latent::psychrometrics::{
        saturation_vapour_pressure_pa as es, saturation_vapour_pressure_slope_pa_k as des,
    };
    (es(t_k), des(t_k))
}

/// [`latent_curvature`] with `(e°(T), e°′(T))` of `t_k` given
/// ([`saturation_about`]; precomputed for a reference's records), W m⁻²:
/// the same value, one exponential instead of three.
#[inline]
pub fn latent_curvature_about(
    vapour_conductance_w_m2_pa: f64,
    (es_t, des_t): (f64, f64),
    t_k: f64,
    dt_k: f64,
) -> f64 {
    use super::latent::psychrometrics::saturation_vapour_pressure_pa as es;
    if vapour_conductance_w_m2_pa == 0.0 {
        return 0.0;
    }
    -vapour_conductance_w_m2_pa * (es(t_k + dt_k) - es_t - des_t * dt_k)
}

/// Solves the reference facet with the nonlinear model and returns its
/// Green's matrices (module docs). Errors as [`super::solve`].
pub fn linearize(
    props: &SlabProperties,
    forcing: &Forcing,
    inputs: &FacetInputs,
    opts: &SolveOptions,
) -> Result<Linearization> {
    props.validate()?;
    forcing.validate()?;
    let exchange = Exchange::new(props, forcing)?;
    linearize_with(props, forcing, &exchange, inputs, opts)
}

/// [`linearize`] with the material's exchange made ([`Exchange::new`]);
/// properties and forcing taken as validated. The Green's functions carry
/// the latent term's derivative `g_v·de°/dT` of the reference; the
/// curvature of `e°(T)` away from the reference is neglected like the
/// emission's (first order).
pub fn linearize_with(
    props: &SlabProperties,
    forcing: &Forcing,
    exchange: &Exchange,
    inputs: &FacetInputs,
    opts: &SolveOptions,
) -> Result<Linearization> {
    let sources = source_history_with(props, forcing, exchange, inputs)?;
    opts.validate()?;
    let p = prepare(props, forcing, inputs, exchange);
    let n = forcing.len();
    let has_back = sources.back_w_m2.is_some();
    let fixed_back = matches!(props.back, BackBoundary::Ground { .. });
    // The end of the first period (spin-up cycle) within the real run.
    let times = &forcing.times_s;
    let period = opts.spinup.period_s;
    let k_p = times.partition_point(|&t| t <= times[0] + period + 1e-6) - 1;
    let mut tangent = Tangent::new(n, has_back, fixed_back, k_p);
    let solution = solve_prepared(props, forcing, &p, opts, Some(&mut tangent));
    let cycles = solution.spinup_cycles as usize;
    let (front_from_front, front_from_back, back_from_front, back_from_back) =
        tangent.green(cycles);
    let (front_radiative, back_radiative) = match props.back {
        BackBoundary::Exposed { fraction } => {
            let r = props.thermal_emissivity * super::STEFAN_BOLTZMANN_W_M2_K4;
            (r, fraction * r)
        }
        _ => (
            props.thermal_emissivity * super::STEFAN_BOLTZMANN_W_M2_K4,
            0.0,
        ),
    };
    Ok(Linearization {
        records: n,
        solution,
        sources,
        front_radiative_w_m2_k4: front_radiative,
        front_vapour_conductance_w_m2_pa: if p.front.iter().any(|f| f.has_latent()) {
            p.front
                .iter()
                .map(|f| f.vapour_conductance_w_m2_pa)
                .collect()
        } else {
            Vec::new()
        },
        back_radiative_w_m2_k4: back_radiative,
        front_from_front,
        front_from_back,
        back_from_front,
        back_from_back,
    })
}

/// The tangent-linear state carried along a nonlinear solve: the
/// sensitivity `P` of every node temperature to every source record and to
/// the state at the start of the real run.
///
/// Columns: front sources `0..R`, back sources `R..2R` (exposed back
/// only), then one column per node (the initial state). `P` is stored
/// node-major (`P[node][column]`), so every operation is a vector operation
/// over the columns.
#[derive(Debug, Clone)]
pub(crate) struct Tangent {
    records: usize,
    has_back: bool,
    fixed_back: bool,
    /// Record at the end of the first period (0: no spin-up period).
    k_p: usize,
    nodes: usize,
    cols: usize,
    capacity: Vec<f64>,
    conductance: Vec<f64>,
    p: Vec<f64>,
    star: Vec<f64>,
    rhs: Vec<f64>,
    cp: Vec<f64>,
    /// Rows 0 (front) and `nodes − 1` (back) of `P` at each record.
    out_front: Vec<f64>,
    out_back: Vec<f64>,
    /// `P` at record `k_p`.
    period: Vec<f64>,
    active: bool,
    /// How a unit source at each record enters the front law (empty: 1;
    /// a two-source canopy's `∂S'/∂S`, [`super::two_source`]).
    source_scale: Vec<f64>,
    /// The spin-up's start state and its sensitivity to the first period's
    /// sources ([`super::SpinupStart::MeanSteady`]; None: a fixed start).
    initial: Option<super::MeanSteady>,
}

impl Tangent {
    fn new(records: usize, has_back: bool, fixed_back: bool, k_p: usize) -> Tangent {
        Tangent {
            records,
            has_back,
            fixed_back,
            k_p,
            nodes: 0,
            cols: 0,
            capacity: Vec::new(),
            conductance: Vec::new(),
            p: Vec::new(),
            star: Vec::new(),
            rhs: Vec::new(),
            cp: Vec::new(),
            out_front: Vec::new(),
            out_back: Vec::new(),
            period: Vec::new(),
            active: false,
            source_scale: Vec::new(),
            initial: None,
        }
    }

    /// The spin-up starts from `init`, which depends on the first period's
    /// sources.
    pub(crate) fn set_initial_sensitivity(&mut self, init: &super::MeanSteady) {
        self.initial = Some(super::MeanSteady {
            temperatures_k: Vec::new(),
            weights: init.weights.clone(),
            per_front_source: init.per_front_source.clone(),
            per_back_source: init.per_back_source.clone(),
        });
    }

    /// How a unit source at each record enters the front law (module docs
    /// of [`super::two_source`]; empty: as itself).
    pub(crate) fn set_source_scale(&mut self, scale: Vec<f64>) {
        self.source_scale = scale;
    }

    /// Called when the slab is built: remember its operators. The tangent
    /// becomes active at the start of the real run ([`Tangent::record`]
    /// with record 0).
    pub(crate) fn init(&mut self, slab: &Slab) {
        self.capacity = slab.capacities_j_m2_k().to_vec();
        self.conductance = slab.conductances_w_m2_k().to_vec();
        self.nodes = self.capacity.len();
        let src = if self.has_back { 2 } else { 1 } * self.records;
        self.cols = src + self.nodes;
        let size = self.nodes * self.cols;
        self.p = vec![0.0; size];
        self.star = vec![0.0; size];
        self.rhs = vec![0.0; size];
        self.cp = vec![0.0; self.nodes];
        self.out_front = vec![0.0; self.records * self.cols];
        self.out_back = if self.has_back {
            vec![0.0; self.records * self.cols]
        } else {
            Vec::new()
        };
        self.active = false;
    }

    /// The real run is at record `t`: store the sensitivities (record 0
    /// starts the tangent with `P = [0 | I]`) of the output, `weight` times
    /// the front node plus `feed` times the record's own front source (a
    /// two-source canopy's radiometric temperature; 1 and 0 otherwise).
    pub(crate) fn record(&mut self, t: usize, weight: f64, feed: f64) {
        let (nodes, cols) = (self.nodes, self.cols);
        if t == 0 {
            self.p.iter_mut().for_each(|v| *v = 0.0);
            let src = cols - nodes;
            for i in 0..nodes {
                self.p[i * cols + src + i] = 1.0;
            }
            if self.fixed_back {
                let last = nodes - 1;
                self.p[last * cols + src + last] = 0.0;
            }
            self.active = true;
        }
        let out = &mut self.out_front[t * cols..(t + 1) * cols];
        out.copy_from_slice(&self.p[..cols]);
        if weight != 1.0 {
            out.iter_mut().for_each(|v| *v *= weight);
        }
        out[t] += feed;
        if self.has_back {
            let last = (nodes - 1) * cols;
            self.out_back[t * cols..(t + 1) * cols].copy_from_slice(&self.p[last..last + cols]);
        }
        if t == self.k_p && t > 0 {
            self.period = self.p.clone();
        }
    }

    /// One TR-BDF2 step of the tangent model: `dt` s, boundary-flux
    /// derivatives `dq/dT` (front, back) at the step's start, stage 1 and
    /// end, the record interval `k` and the interval fractions `phi` of those
    /// three instants.
    ///
    /// Runs compiled for the widest vector instructions the CPU has
    /// ([`crate::simd::vectorized`]); every column's operations are the
    /// same in the same order on every path, so the result does not depend
    /// on it.
    pub(crate) fn step(&mut self, dt: f64, deriv: [(f64, f64); 3], k: usize, phi: [f64; 3]) {
        if !self.active {
            return;
        }
        crate::simd::vectorized(TangentStep {
            tangent: self,
            dt,
            deriv,
            k,
            phi,
        });
    }

    /// [`Tangent::step`] of an active tangent, inlined into the dispatched
    /// copy.
    #[inline(always)]
    fn step_impl(&mut self, dt: f64, deriv: [(f64, f64); 3], k: usize, phi: [f64; 3]) {
        let (nodes, cols) = (self.nodes, self.cols);
        let n = nodes - 1;
        let act = self.active_columns(k);
        let c1 = 0.5 * GAMMA * dt;
        let a = 1.0 / (GAMMA * (2.0 - GAMMA));
        let b = (1.0 - GAMMA) * (1.0 - GAMMA) / (GAMMA * (2.0 - GAMMA));
        let c2 = (1.0 - GAMMA) / (2.0 - GAMMA) * dt;
        // Stage 1 right-hand side: C P + c1 (A P + D_start P + σ(0)) + c1 σ(γ).
        for i in 0..nodes {
            let row = i * cols;
            let cap = self.capacity[i];
            let kl = if i > 0 { self.conductance[i - 1] } else { 0.0 };
            let kr = if i < n { self.conductance[i] } else { 0.0 };
            let mut diag = cap - c1 * (kl + kr);
            if i == 0 {
                diag += c1 * deriv[0].0;
            }
            if i == n && !self.fixed_back {
                diag += c1 * deriv[0].1;
            }
            let (wl, wr) = (
                if i > 0 { c1 * kl } else { 0.0 },
                if i < n { c1 * kr } else { 0.0 },
            );
            for &(lo, hi) in &act {
                let out = &mut self.rhs[row + lo..row + hi];
                let here = &self.p[row + lo..row + hi];
                // Rows outside the slab have zero weight; clamp to any row.
                let up = row.saturating_sub(cols);
                let down = if i < n { row + cols } else { row };
                let above = &self.p[up + lo..up + hi];
                let below = &self.p[down + lo..down + hi];
                for (((o, &h), &u), &d) in out.iter_mut().zip(here).zip(above).zip(below) {
                    *o = diag * h + wl * u + wr * d;
                }
            }
        }
        let w_k = c1 * ((1.0 - phi[0]) + (1.0 - phi[1]));
        let w_k1 = c1 * (phi[0] + phi[1]);
        self.add_sources(k, w_k, w_k1);
        if self.fixed_back {
            let row = n * cols;
            self.rhs[row..row + cols].iter_mut().for_each(|v| *v = 0.0);
        }
        solve_tridiagonal(
            &self.capacity,
            &self.conductance,
            c1,
            deriv[1],
            self.fixed_back,
            &mut self.cp,
            &self.rhs,
            &mut self.star,
            cols,
            &act,
        );
        // Stage 2: C (a P* − b P) + c2 σ(1).
        for i in 0..nodes {
            let cap = self.capacity[i];
            let row = i * cols;
            let (o, st, pp) = (
                &mut self.rhs[row..row + cols],
                &self.star[row..row + cols],
                &self.p[row..row + cols],
            );
            for &(lo, hi) in &act {
                for j in lo..hi {
                    o[j] = cap * (a * st[j] - b * pp[j]);
                }
            }
        }
        self.add_sources(k, c2 * (1.0 - phi[2]), c2 * phi[2]);
        if self.fixed_back {
            let row = n * cols;
            self.rhs[row..row + cols].iter_mut().for_each(|v| *v = 0.0);
        }
        solve_tridiagonal(
            &self.capacity,
            &self.conductance,
            c2,
            deriv[2],
            self.fixed_back,
            &mut self.cp,
            &self.rhs,
            &mut self.p,
            cols,
            &act,
        );
    }

    /// The column ranges of `P` that can be non-zero during the step over
    /// record interval `k` of the real run: the sources of records
    /// `0..=k + 1` (a source acts only from its record on: causality) and
    /// the initial state; the other columns are zero and stay so.
    #[inline(always)]
    fn active_columns(&self, k: usize) -> [(usize, usize); 3] {
        let r = self.records;
        let a = (k + 2).min(r);
        let src = self.cols - self.nodes;
        let back = if self.has_back { (r, r + a) } else { (0, 0) };
        [(0, a), back, (src, self.cols)]
    }

    /// Add the unit source perturbations of records `k` and `k + 1` with
    /// weights `w_k`, `w_k1` to the boundary rows of `rhs`.
    #[inline(always)]
    fn add_sources(&mut self, k: usize, w_k: f64, w_k1: f64) {
        let cols = self.cols;
        let r = self.records;
        let scale = |j: usize| self.source_scale.get(j).copied().unwrap_or(1.0);
        let (s_k, s_k1) = (scale(k), scale(k + 1));
        self.rhs[k] += w_k * s_k;
        self.rhs[k + 1] += w_k1 * s_k1;
        if self.has_back {
            let row = (self.nodes - 1) * cols;
            self.rhs[row + r + k] += w_k;
            self.rhs[row + r + k + 1] += w_k1;
        }
    }

    /// The Green's matrices `[t][k]` (front←front, front←back, back←front,
    /// back←back) with `cycles` spin-up cycles folded in.
    /// Vectorised like [`Tangent::step`].
    fn green(&self, cycles: usize) -> GreenMatrices {
        crate::simd::vectorized(TangentGreen {
            tangent: self,
            cycles,
        })
    }

    /// [`Tangent::green`], inlined into the dispatched copy.
    #[inline(always)]
    fn green_impl(&self, cycles: usize) -> GreenMatrices {
        let (nodes, cols, r) = (self.nodes, self.cols, self.records);
        let src = cols - nodes;
        // X = Σ_{j<c} Φʲ Ψ: sensitivity of the real run's start state to the
        // sources, nodes × src.
        let mut x = vec![0.0; nodes * src];
        // One period's map of a node-by-source matrix: `Φ·term`.
        let period_step = |term: &[f64]| -> Vec<f64> {
            let phi = |i: usize, l: usize| self.period[i * cols + src + l];
            let mut next = vec![0.0; nodes * src];
            for i in 0..nodes {
                for l in 0..nodes {
                    let f = phi(i, l);
                    if f == 0.0 {
                        continue;
                    }
                    for j in 0..src {
                        next[i * src + j] += f * term[l * src + j];
                    }
                }
            }
            next
        };
        if cycles > 0 && !self.period.is_empty() {
            let psi = |i: usize, j: usize| self.period[i * cols + j];
            let mut term: Vec<f64> = (0..nodes * src).map(|q| psi(q / src, q % src)).collect();
            x.copy_from_slice(&term);
            for _ in 1..cycles {
                term = period_step(&term);
                x.iter_mut().zip(&term).for_each(|(a, b)| *a += b);
            }
        }
        // A start state that depends on the sources adds Φᶜ ∂x_init/∂S.
        if let Some(init) = &self.initial
            && cycles > 0
            && !self.period.is_empty()
        {
            let mut term = vec![0.0; nodes * src];
            for i in 0..nodes {
                for (k, &w) in init.weights.iter().enumerate().take(r) {
                    let scale = self.source_scale.get(k).copied().unwrap_or(1.0);
                    term[i * src + k] = init.per_front_source[i] * w * scale;
                    if self.has_back {
                        term[i * src + r + k] = init.per_back_source[i] * w;
                    }
                }
            }
            for _ in 0..cycles {
                term = period_step(&term);
            }
            x.iter_mut().zip(&term).for_each(|(a, b)| *a += b);
        }
        let fold = |out: &[f64]| -> Vec<f64> {
            let mut g = vec![0.0; r * src];
            for t in 0..r {
                let row = &out[t * cols..(t + 1) * cols];
                let gt = &mut g[t * src..(t + 1) * src];
                gt.copy_from_slice(&row[..src]);
                for l in 0..nodes {
                    let f = row[src + l];
                    if f != 0.0 {
                        gt.iter_mut()
                            .zip(&x[l * src..(l + 1) * src])
                            .for_each(|(a, b)| *a += f * b);
                    }
                }
            }
            g
        };
        let split = |g: Vec<f64>| -> (Vec<f64>, Vec<f64>) {
            if !self.has_back {
                return (g, Vec::new());
            }
            let mut a = Vec::with_capacity(r * r);
            let mut b = Vec::with_capacity(r * r);
            for t in 0..r {
                a.extend_from_slice(&g[t * src..t * src + r]);
                b.extend_from_slice(&g[t * src + r..(t + 1) * src]);
            }
            (a, b)
        };
        let (ff, fb) = split(fold(&self.out_front));
        let (bf, bb) = if self.has_back {
            split(fold(&self.out_back))
        } else {
            (Vec::new(), Vec::new())
        };
        (ff, fb, bf, bb)
    }
}

/// [`Tangent::step_impl`] for [`crate::simd::vectorized`].
#[inline(always)]
fn tangent_step(tangent: &mut Tangent, dt: f64, deriv: [(f64, f64); 3], k: usize, phi: [f64; 3]) {
    tangent.step_impl(dt, deriv, k, phi)
}

crate::simd::simd_kernel!(TangentStep<'a> { tangent: &'a mut Tangent, dt: f64, deriv: [(f64, f64); 3], k: usize, phi: [f64; 3] } -> () => tangent_step);

/// The Green's matrices `[t][k]`: front←front, front←back, back←front,
/// back←back.
type GreenMatrices = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);

/// [`Tangent::green_impl`] for [`crate::simd::vectorized`].
#[inline(always)]
fn tangent_green(tangent: &Tangent, cycles: usize) -> GreenMatrices {
    tangent.green_impl(cycles)
}

crate::simd::simd_kernel!(TangentGreen<'a> { tangent: &'a Tangent, cycles: usize } -> GreenMatrices => tangent_green);

/// Solve `(C − c A − c D) X = rhs` for the `active` column ranges of
/// `cols` right-hand sides (node-major; the other columns are untouched),
/// `A` the conduction operator, `D = diag(d_front, 0, …, d_back)`; with a
/// fixed back the last row is `X_n = rhs_n` (Thomas algorithm, Press et al.,
/// *Numerical Recipes*, 3rd ed., §2.4).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn solve_tridiagonal(
    capacity: &[f64],
    conductance: &[f64],
    c: f64,
    d: (f64, f64),
    fixed_back: bool,
    cp: &mut [f64],
    rhs: &[f64],
    x: &mut [f64],
    cols: usize,
    active: &[(usize, usize)],
) {
    let nodes = capacity.len();
    let n = nodes - 1;
    let mut prev_cp = 0.0;
    for i in 0..nodes {
        let kl = if i > 0 { conductance[i - 1] } else { 0.0 };
        let kr = if i < n { conductance[i] } else { 0.0 };
        let (lower, upper, diag) = if i == n && fixed_back {
            (0.0, 0.0, 1.0)
        } else {
            let mut diag = capacity[i] + c * (kl + kr);
            if i == 0 {
                diag -= c * d.0;
            }
            if i == n {
                diag -= c * d.1;
            }
            (-c * kl, -c * kr, diag)
        };
        let inv = 1.0 / (diag - lower * prev_cp);
        cp[i] = upper * inv;
        prev_cp = cp[i];
        let row = i * cols;
        if i == 0 {
            for &(lo, hi) in active {
                for j in lo..hi {
                    x[j] = rhs[j] * inv;
                }
            }
        } else {
            let (done, cur) = x.split_at_mut(row);
            let prev = &done[row - cols..];
            for &(lo, hi) in active {
                for j in lo..hi {
                    cur[j] = (rhs[row + j] - lower * prev[j]) * inv;
                }
            }
        }
    }
    for i in (0..n).rev() {
        let row = i * cols;
        let (cur, next) = x.split_at_mut(row + cols);
        let cur = &mut cur[row..];
        let f = cp[i];
        for &(lo, hi) in active {
            for j in lo..hi {
                cur[j] -= f * next[j];
            }
        }
    }
}
