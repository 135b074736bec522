//! Transient 1-D heat conduction through a slab: vertex-centred finite
//! volumes in space, TR-BDF2 in time, a Thomas (tridiagonal) solve per stage
//! and a Newton iteration on the (nonlinear, radiative) boundary nodes.
//!
//! # Discretisation
//! Nodes `x_0 = 0` (the front surface) `< x_1 < … < x_n = L` (the back
//! surface). Cell widths grow geometrically away from the front surface
//! (`Δ_j = Δ_0·r^j`), so the thin layers where the diurnal wave is steepest
//! are resolved. Each node owns the control volume between the midpoints of
//! its neighbouring cells (half cells at both surfaces), so the front node's
//! temperature *is* the surface temperature. Heat capacity per unit area
//! `C_i = ρ·c·V_i` (J m⁻² K⁻¹), conductance between nodes `K_j = k/Δ_j`
//! (W m⁻² K⁻¹). The semi-discrete system
//!
//! ```text
//! C_i dT_i/dt = K_{i−1}(T_{i−1} − T_i) + K_i(T_{i+1} − T_i) + q_i(T_i, t)
//! ```
//!
//! (`q_0` = net heat flux into the front surface, `q_n` = into the back,
//! W m⁻²) is the classical finite-volume form (Patankar, *Numerical Heat
//! Transfer and Fluid Flow*, 1980, §4.2–4.3). It conserves energy exactly:
//! the conduction terms cancel in `Σ C_i T_i`.
//!
//! # Time integration
//! TR-BDF2 (Bank et al., "Transient simulation of silicon devices and
//! circuits", IEEE Trans. CAD 4(4), 1985, doi:10.1109/TCAD.1985.1270142;
//! Hosea & Shampine, Appl. Numer. Math. 20, 1996): a trapezoidal stage to
//! `t + γΔt`, then a BDF2 stage to `t + Δt`, `γ = 2 − √2`. It is second-order
//! accurate (no phase lag of backward Euler) and L-stable (no ringing of
//! Crank–Nicolson on the stiff modes of thin, highly conductive slabs), so any
//! step is stable. The boundary fluxes contain `εσT⁴`; each stage is solved by
//! Newton's method on the two boundary nodes only: the rest of the system is
//! linear, so the interior is eliminated with a tridiagonal factorisation
//! that is computed once per step size (static condensation), and each
//! Newton iteration is a 2×2 solve.

use super::latent::psychrometrics::{
    saturation_vapour_pressure_pa, saturation_vapour_pressure_slope_pa_k,
};

/// Stefan–Boltzmann constant, W m⁻² K⁻⁴ (CODATA 2018, exact).
pub const STEFAN_BOLTZMANN_W_M2_K4: f64 = 5.670_374_419e-8;

/// TR-BDF2 stage fraction γ = 2 − √2.
pub(crate) const GAMMA: f64 = 2.0 - std::f64::consts::SQRT_2;

/// A boundary heat-flux law, linear plus radiative plus latent in the
/// boundary temperature `T` (K):
///
/// ```text
/// q(T) = source_w_m2 − linear_w_m2_k·T − radiative_w_m2_k4·T⁴
///        − vapour_conductance_w_m2_pa·(e°(T) − air_vapour_pressure_pa)   [W m⁻²]
/// ```
///
/// positive *into* the slab. Every boundary in the model has this form: the
/// front-surface balance (`source` = absorbed solar + absorbed sky and
/// background longwave + `h·T_air` + self power, `linear` = `h`,
/// `radiative` = `εσ`), an exposed back face, a film coefficient to interior
/// air (`radiative` = 0), an insulated face (all zero) and a prescribed flux
/// (`source` only).
///
/// The last term is the latent heat flux of a surface that evaporates: with
/// the vapour conductance `g_v = ρ c_p / (γ (r_a + r_s))` (W m⁻² Pa⁻¹; air
/// density ρ, specific heat c_p, psychrometric constant γ, aerodynamic and
/// surface resistances r_a, r_s) it is `λE = g_v (e°(T_s) − e_a)`, the
/// Penman–Monteith latent flux written at the surface temperature instead of
/// linearised about the air temperature (FAO-56, Allen et al. 1998, eq. 3
/// before the Δ-linearisation; e° by FAO-56 eq. 11, see
/// [`crate::thermal::latent::psychrometrics::saturation_vapour_pressure_pa`]).
/// With `g_v = 0` (every dry surface, and the limit `r_s → ∞`) the term is
/// skipped and the law is the linear-plus-radiative one, bit for bit.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SurfaceFlux {
    /// Temperature-independent part, W m⁻².
    pub source_w_m2: f64,
    /// Coefficient of `−T`, W m⁻² K⁻¹ (≥ 0; a convective/film coefficient).
    pub linear_w_m2_k: f64,
    /// Coefficient of `−T⁴`, W m⁻² K⁻⁴ (≥ 0; `ε·σ` for an emitting face).
    pub radiative_w_m2_k4: f64,
    /// Vapour conductance `g_v = ρc_p/(γ(r_a + r_s))`, W m⁻² Pa⁻¹ (≥ 0; 0 for
    /// a surface that does not evaporate).
    pub vapour_conductance_w_m2_pa: f64,
    /// Actual vapour pressure of the air `e_a`, Pa (used only when
    /// `vapour_conductance_w_m2_pa > 0`).
    pub air_vapour_pressure_pa: f64,
}

impl SurfaceFlux {
    /// A prescribed, temperature-independent flux into the slab, W m⁻².
    pub fn constant(q_w_m2: f64) -> Self {
        SurfaceFlux {
            source_w_m2: q_w_m2,
            ..Default::default()
        }
    }

    /// Net flux into the slab at boundary temperature `t_k` (K), W m⁻².
    #[inline]
    pub fn flux(&self, t_k: f64) -> f64 {
        let t2 = t_k * t_k;
        let q = self.source_w_m2 - self.linear_w_m2_k * t_k - self.radiative_w_m2_k4 * t2 * t2;
        if self.vapour_conductance_w_m2_pa == 0.0 {
            q
        } else {
            q - self.latent_w_m2(t_k)
        }
    }

    /// `dq/dT` at `t_k`, W m⁻² K⁻¹ (≤ 0).
    #[inline]
    pub fn derivative(&self, t_k: f64) -> f64 {
        let d = -self.linear_w_m2_k - 4.0 * self.radiative_w_m2_k4 * t_k * t_k * t_k;
        if self.vapour_conductance_w_m2_pa == 0.0 {
            d
        } else {
            d - self.vapour_conductance_w_m2_pa * saturation_vapour_pressure_slope_pa_k(t_k)
        }
    }

    /// The latent heat flux away from the surface at `t_k`,
    /// `g_v (e°(T) − e_a)`, W m⁻² (negative = dew forming; 0 when
    /// `g_v = 0`).
    #[inline]
    pub fn latent_w_m2(&self, t_k: f64) -> f64 {
        if self.vapour_conductance_w_m2_pa == 0.0 {
            0.0
        } else {
            self.vapour_conductance_w_m2_pa
                * (saturation_vapour_pressure_pa(t_k) - self.air_vapour_pressure_pa)
        }
    }

    /// Whether the law has a latent term (`g_v > 0`).
    #[inline]
    pub fn has_latent(&self) -> bool {
        self.vapour_conductance_w_m2_pa != 0.0
    }

    /// Linear interpolation between two flux laws, `f ∈ [0, 1]`.
    #[inline]
    pub fn lerp(&self, other: &SurfaceFlux, f: f64) -> SurfaceFlux {
        SurfaceFlux {
            source_w_m2: self.source_w_m2 + f * (other.source_w_m2 - self.source_w_m2),
            linear_w_m2_k: self.linear_w_m2_k + f * (other.linear_w_m2_k - self.linear_w_m2_k),
            radiative_w_m2_k4: self.radiative_w_m2_k4
                + f * (other.radiative_w_m2_k4 - self.radiative_w_m2_k4),
            vapour_conductance_w_m2_pa: self.vapour_conductance_w_m2_pa
                + f * (other.vapour_conductance_w_m2_pa - self.vapour_conductance_w_m2_pa),
            air_vapour_pressure_pa: self.air_vapour_pressure_pa
                + f * (other.air_vapour_pressure_pa - self.air_vapour_pressure_pa),
        }
    }
}

/// A boundary condition at one face of the slab at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Boundary {
    /// The face is held at this temperature, K (Dirichlet).
    Temperature(f64),
    /// A heat flux law into the face (Neumann / Robin / radiative).
    Flux(SurfaceFlux),
}

/// How the slab is divided into finite volumes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// Number of cells (nodes = cells + 1), ≥ 1.
    pub cells: usize,
    /// Ratio of successive cell widths away from the front surface (≥ 1;
    /// 1 = uniform).
    pub growth: f64,
}

impl Default for Grid {
    /// 12 cells growing by 1.3: the first cell is 0.3 % of the thickness
    /// (e.g. 1.5 mm of a 0.5 m ground column).
    fn default() -> Self {
        Grid {
            cells: 12,
            growth: 1.3,
        }
    }
}

/// One layer of a [`Slab::layered`] column.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerCells {
    /// Thickness, m (> 0).
    pub thickness_m: f64,
    /// Conductivity `k`, W m⁻¹ K⁻¹ (> 0).
    pub conductivity_w_m_k: f64,
    /// Volumetric heat capacity `ρc`, J m⁻³ K⁻¹ (> 0).
    pub rho_c: f64,
    /// Contact resistance between this layer and the next, m² K W⁻¹ (≥ 0;
    /// ignored behind the last layer).
    pub contact_resistance_m2_k_w: f64,
    /// Cells in the layer (≥ 1).
    pub cells: usize,
    /// Ratio of successive cell widths away from the layer's front face (≥ 1).
    pub growth: f64,
}

/// Counters of the work done, for diagnostics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StepStats {
    /// Time steps taken.
    pub steps: u64,
    /// Newton iterations, summed over stages (each one 2×2 solve on the
    /// condensed boundary system).
    pub solves: u64,
    /// Stages whose Newton iteration hit the iteration limit.
    pub unconverged_stages: u64,
}

/// A homogeneous slab discretised in depth, with its temperature state.
///
/// Build it with [`Slab::new`], set the initial temperatures, then call
/// [`Slab::step`] with the boundary conditions as functions of the fraction
/// of the step (0 = start, 1 = end).
#[derive(Debug, Clone)]
pub struct Slab {
    depth_m: Vec<f64>,
    /// Heat capacity of each node's control volume, J m⁻² K⁻¹.
    capacity: Vec<f64>,
    /// Conductance between node j and j+1, W m⁻² K⁻¹.
    conductance: Vec<f64>,
    temp: Vec<f64>,
    // Work arrays (reused; no allocation per step).
    t_start: Vec<f64>,
    rhs: Vec<f64>,
    /// Scratch: forward-substitution values of the interior solve.
    diag: Vec<f64>,
    /// Scratch: the particular interior solution P.
    cprime: Vec<f64>,
    /// Energy that entered through the front face, J m⁻² (scheme quadrature).
    front_energy_j_m2: f64,
    /// Energy that entered through the back face, J m⁻².
    back_energy_j_m2: f64,
    newton_tolerance_k: f64,
    max_newton: u32,
    stats: StepStats,
    /// Interior factorisations for the two stage coefficients.
    factors: [Factor; 2],
    /// Boundary-node temperatures (front, back) of the last step at its
    /// start, after stage 1 and at its end, K (for the tangent model).
    stage_boundary_k: [(f64, f64); 3],
}

/// Boundary-node flux values used by a stage: (front, back), W m⁻².
type StageFluxes = (f64, f64);

impl Slab {
    /// A slab of `thickness_m` (m), conductivity `k` (W m⁻¹ K⁻¹) and volumetric
    /// heat capacity `rho_c` (J m⁻³ K⁻¹), divided per `grid`, at a uniform
    /// `initial_k` (K).
    ///
    /// Panics in debug builds on non-positive inputs; the public solver
    /// validates them first.
    pub fn new(thickness_m: f64, k: f64, rho_c: f64, grid: Grid, initial_k: f64) -> Slab {
        debug_assert!(thickness_m > 0.0 && k > 0.0 && rho_c > 0.0);
        let n = grid.cells.max(1);
        let r = grid.growth.max(1.0);
        // Δ_0 (1 + r + … + r^{n−1}) = L.
        let series = if (r - 1.0).abs() < 1e-12 {
            n as f64
        } else {
            (r.powi(n as i32) - 1.0) / (r - 1.0)
        };
        let d0 = thickness_m / series;
        let mut depth = Vec::with_capacity(n + 1);
        let mut widths = Vec::with_capacity(n);
        depth.push(0.0);
        let mut w = d0;
        for j in 0..n {
            widths.push(w);
            let next = if j + 1 == n {
                thickness_m
            } else {
                depth[j] + w
            };
            depth.push(next);
            w *= r;
        }
        // Recompute the last width so that the nodes end exactly at L.
        widths[n - 1] = depth[n] - depth[n - 1];
        let mut capacity = vec![0.0; n + 1];
        for (j, &wj) in widths.iter().enumerate() {
            capacity[j] += 0.5 * rho_c * wj;
            capacity[j + 1] += 0.5 * rho_c * wj;
        }
        let conductance = widths.iter().map(|&wj| k / wj).collect();
        Slab {
            depth_m: depth,
            capacity,
            conductance,
            temp: vec![initial_k; n + 1],
            t_start: vec![0.0; n + 1],
            rhs: vec![0.0; n + 1],
            diag: vec![0.0; n + 1],
            cprime: vec![0.0; n + 1],
            front_energy_j_m2: 0.0,
            back_energy_j_m2: 0.0,
            newton_tolerance_k: 1e-5,
            max_newton: 30,
            stats: StepStats::default(),
            factors: [
                Factor {
                    c: f64::NAN,
                    ..Default::default()
                },
                Factor {
                    c: f64::NAN,
                    ..Default::default()
                },
            ],
            stage_boundary_k: [(initial_k, initial_k); 3],
        }
    }

    /// A slab of layers from the front face: each [`LayerCells`] is a layer
    /// of its own conductivity and volumetric heat capacity split into
    /// `cells` cells growing by `growth` away from the layer's front face,
    /// with a node on every interface. Every cell lies within one layer, so
    /// the conductance between two nodes is that layer's `k/Δ` (the
    /// harmonic mean of the two half-cells' conductances, Patankar 1980
    /// §4.2-3, reduces to it); a contact resistance `R` (m² K W⁻¹) behind a
    /// layer adds in series to the next layer's first cell,
    /// `K = 1/(Δ/k + R)`. The interface node's capacity is the sum of its
    /// two half cells, as for any node, so energy is conserved exactly.
    ///
    /// Panics in debug builds on an empty list or non-positive inputs; the
    /// public solver validates them first.
    pub fn layered(layers: &[LayerCells], initial_k: f64) -> Slab {
        debug_assert!(!layers.is_empty());
        let mut widths = Vec::new();
        let mut conductance = Vec::new();
        let mut rho_c = Vec::new();
        let mut extra_r = 0.0;
        for l in layers {
            debug_assert!(l.thickness_m > 0.0 && l.conductivity_w_m_k > 0.0 && l.rho_c > 0.0);
            let n = l.cells.max(1);
            let r = l.growth.max(1.0);
            let series = if (r - 1.0).abs() < 1e-12 {
                n as f64
            } else {
                (r.powi(n as i32) - 1.0) / (r - 1.0)
            };
            let mut w = l.thickness_m / series;
            let mut used = 0.0;
            for j in 0..n {
                // The last cell closes the layer exactly.
                let wj = if j + 1 == n { l.thickness_m - used } else { w };
                used += wj;
                widths.push(wj);
                rho_c.push(l.rho_c);
                conductance.push(1.0 / (wj / l.conductivity_w_m_k + extra_r));
                extra_r = 0.0;
                w *= r;
            }
            extra_r = l.contact_resistance_m2_k_w;
        }
        let n = widths.len();
        let mut depth = Vec::with_capacity(n + 1);
        depth.push(0.0);
        for (j, w) in widths.iter().enumerate() {
            depth.push(depth[j] + w);
        }
        let mut capacity = vec![0.0; n + 1];
        for (j, (&wj, &rc)) in widths.iter().zip(&rho_c).enumerate() {
            capacity[j] += 0.5 * rc * wj;
            capacity[j + 1] += 0.5 * rc * wj;
        }
        let mut s = Slab::new(
            depth[n],
            1.0,
            1.0,
            Grid {
                cells: n,
                growth: 1.0,
            },
            initial_k,
        );
        s.depth_m = depth;
        s.capacity = capacity;
        s.conductance = conductance;
        s
    }

    /// The slab with a **skin** node in front of its front surface: a node
    /// of heat capacity `capacity_j_m2_k` (J m⁻² K⁻¹) joined to the old front
    /// node by the conductance `conductance_w_m2_k` (W m⁻² K⁻¹), at depth 0.
    /// The front boundary then acts on the skin: a vegetation canopy over
    /// the soil column (`crate::thermal::surface`). Energy is conserved as
    /// for any node.
    pub fn with_skin(mut self, capacity_j_m2_k: f64, conductance_w_m2_k: f64) -> Slab {
        debug_assert!(capacity_j_m2_k > 0.0 && conductance_w_m2_k > 0.0);
        let t0 = self.temp[0];
        self.depth_m.insert(0, 0.0);
        self.capacity.insert(0, capacity_j_m2_k);
        self.conductance.insert(0, conductance_w_m2_k);
        self.temp.insert(0, t0);
        let n = self.temp.len();
        self.t_start = vec![0.0; n];
        self.rhs = vec![0.0; n];
        self.diag = vec![0.0; n];
        self.cprime = vec![0.0; n];
        for f in &mut self.factors {
            f.c = f64::NAN;
        }
        self
    }

    /// Newton convergence tolerance on the boundary temperatures, K, and the
    /// iteration limit per stage.
    pub fn set_newton(&mut self, tolerance_k: f64, max_iterations: u32) {
        self.newton_tolerance_k = tolerance_k;
        self.max_newton = max_iterations.max(1);
    }

    /// Node depths below the front surface, m (first 0, last = thickness).
    pub fn depths_m(&self) -> &[f64] {
        &self.depth_m
    }

    /// Node temperatures, K (front surface first).
    pub fn temperatures_k(&self) -> &[f64] {
        &self.temp
    }

    /// Set the node temperatures from a function of depth (m) → K.
    pub fn set_temperatures(&mut self, f: impl Fn(f64) -> f64) {
        for (t, &x) in self.temp.iter_mut().zip(&self.depth_m) {
            *t = f(x);
        }
    }

    /// Set every node's temperature, K (one per node, front first; extra
    /// values are ignored).
    pub fn set_node_temperatures(&mut self, t_k: &[f64]) {
        for (t, &v) in self.temp.iter_mut().zip(t_k) {
            *t = v;
        }
    }

    /// Front-surface temperature, K.
    pub fn front_k(&self) -> f64 {
        self.temp[0]
    }

    /// Back-surface temperature, K.
    pub fn back_k(&self) -> f64 {
        self.temp[self.temp.len() - 1]
    }

    /// Temperature at depth `x_m` (m), linearly interpolated between nodes
    /// (clamped to the slab).
    pub fn temperature_at(&self, x_m: f64) -> f64 {
        let d = &self.depth_m;
        if x_m <= 0.0 {
            return self.temp[0];
        }
        let j = d.partition_point(|&xi| xi < x_m);
        if j >= d.len() {
            return self.back_k();
        }
        let (x0, x1) = (d[j - 1], d[j]);
        let f = (x_m - x0) / (x1 - x0);
        self.temp[j - 1] + f * (self.temp[j] - self.temp[j - 1])
    }

    /// Heat stored per unit area relative to 0 K, `Σ C_i T_i`, J m⁻².
    pub fn stored_energy_j_m2(&self) -> f64 {
        self.capacity
            .iter()
            .zip(&self.temp)
            .map(|(c, t)| c * t)
            .sum()
    }

    /// Total heat capacity per unit area, J m⁻² K⁻¹.
    pub fn heat_capacity_j_m2_k(&self) -> f64 {
        self.capacity.iter().sum()
    }

    /// Energy that has entered through the (front, back) faces since the
    /// last [`Slab::reset_energy`], J m⁻², integrated with the time scheme's
    /// own quadrature (exactly consistent with [`Slab::stored_energy_j_m2`]
    /// for flux boundaries; a face held at a fixed temperature contributes 0
    /// here).
    pub fn boundary_energy_j_m2(&self) -> (f64, f64) {
        (self.front_energy_j_m2, self.back_energy_j_m2)
    }

    /// Zero the boundary energy counters.
    pub fn reset_energy(&mut self) {
        self.front_energy_j_m2 = 0.0;
        self.back_energy_j_m2 = 0.0;
    }

    /// Work counters.
    pub fn stats(&self) -> StepStats {
        self.stats
    }

    /// Heat capacity of each node's control volume, J m⁻² K⁻¹.
    pub fn capacities_j_m2_k(&self) -> &[f64] {
        &self.capacity
    }

    /// Conductance between node `j` and `j + 1`, W m⁻² K⁻¹.
    pub fn conductances_w_m2_k(&self) -> &[f64] {
        &self.conductance
    }

    /// Boundary-node temperatures (front, back) of the last [`Slab::step`]
    /// at its start, after the trapezoidal stage (at `t + γΔt`) and at its
    /// end, K: the points the tangent-linear model linearises about.
    pub fn stage_boundary_k(&self) -> [(f64, f64); 3] {
        self.stage_boundary_k
    }

    /// Advance by `dt_s` seconds with TR-BDF2. `front(f)` and `back(f)` give
    /// the boundary conditions at the fraction `f ∈ {0, γ, 1}` of the step.
    pub fn step(
        &mut self,
        dt_s: f64,
        front: impl Fn(f64) -> Boundary,
        back: impl Fn(f64) -> Boundary,
    ) {
        debug_assert!(dt_s > 0.0 && dt_s.is_finite());
        let n = self.temp.len() - 1;
        self.stats.steps += 1;
        // Boundary fluxes at the start of the step, from the current state.
        let q0_start = boundary_flux(&front(0.0), self.temp[0]);
        let qn_start = boundary_flux(&back(0.0), self.temp[n]);

        // Stage 1 (trapezoidal rule to t + γΔt):
        //   C U* − c1 (A U* + g*) = C Uⁿ + c1 (A Uⁿ + gⁿ),  c1 = γΔt/2.
        let c1 = 0.5 * GAMMA * dt_s;
        self.t_start.copy_from_slice(&self.temp);
        for i in 0..=n {
            let mut au = 0.0;
            if i > 0 {
                au += self.conductance[i - 1] * (self.t_start[i - 1] - self.t_start[i]);
            }
            if i < n {
                au += self.conductance[i] * (self.t_start[i + 1] - self.t_start[i]);
            }
            self.rhs[i] = self.capacity[i] * self.t_start[i] + c1 * au;
        }
        self.rhs[0] += c1 * q0_start;
        self.rhs[n] += c1 * qn_start;
        let (q0_mid, qn_mid) = self.stage(0, c1, front(GAMMA), back(GAMMA));
        // The stage-1 result is now in `temp`.
        self.stage_boundary_k[0] = (self.t_start[0], self.t_start[n]);
        self.stage_boundary_k[1] = (self.temp[0], self.temp[n]);

        // Stage 2 (BDF2 through tⁿ, t + γΔt to t + Δt):
        //   C U − w Δt (A U + g) = C [a U* − b Uⁿ],  a − b = 1.
        let a = 1.0 / (GAMMA * (2.0 - GAMMA));
        let b = (1.0 - GAMMA) * (1.0 - GAMMA) / (GAMMA * (2.0 - GAMMA));
        let c2 = (1.0 - GAMMA) / (2.0 - GAMMA) * dt_s;
        for i in 0..=n {
            self.rhs[i] = self.capacity[i] * (a * self.temp[i] - b * self.t_start[i]);
        }
        let (q0_end, qn_end) = self.stage(1, c2, front(1.0), back(1.0));
        self.stage_boundary_k[2] = (self.temp[0], self.temp[n]);

        // Energy through each face with the scheme's quadrature: summing the
        // stages over all nodes, the conduction terms cancel and
        //   ΔE = (1 + b) c1 (qⁿ + q*) + c2 qⁿ⁺¹.
        let w01 = (1.0 + b) * c1;
        if matches!(front(0.0), Boundary::Flux(_)) {
            self.front_energy_j_m2 += w01 * (q0_start + q0_mid) + c2 * q0_end;
        }
        if matches!(back(0.0), Boundary::Flux(_)) {
            self.back_energy_j_m2 += w01 * (qn_start + qn_mid) + c2 * qn_end;
        }
    }

    /// Solve `C U − c (A U + g(U)) = rhs` for `U` (stored in `temp`, whose
    /// current boundary values are the Newton starting point). Returns the
    /// boundary fluxes `g` actually used in the final linear system (front,
    /// back), so that the energy bookkeeping is exact.
    ///
    /// Only the two boundary nodes are nonlinear, so the interior unknowns
    /// are eliminated: with `A_int` the interior tridiagonal matrix (which
    /// depends on `c` only and is factorised once per step size),
    /// `U_int = P + U_0·X + U_n·Y` where `P = A_int⁻¹ rhs_int` (one
    /// substitution per stage) and `X`, `Y` are the responses to the two
    /// boundary temperatures. Newton then runs on a 2×2 system.
    fn stage(&mut self, slot: usize, c: f64, front: Boundary, back: Boundary) -> StageFluxes {
        let n = self.temp.len() - 1;
        self.ensure_factor(slot, c);
        let f = &self.factors[slot];
        let k0 = self.conductance[0];
        let kn = self.conductance[n - 1];
        // Reduced boundary equations
        //   a00 U0 + a0n Un − c g0(U0) = b0,   an0 U0 + ann Un − c gn(Un) = bn.
        let (a00, a0n, an0, ann, b0, bn);
        if n == 1 {
            a00 = self.capacity[0] + c * k0;
            a0n = -c * k0;
            an0 = -c * k0;
            ann = self.capacity[1] + c * k0;
            b0 = self.rhs[0];
            bn = self.rhs[1];
        } else {
            // P = A_int⁻¹ rhs_int (forward and back substitution).
            let m = n - 1; // interior unknowns 1..=m
            let mut prev = 0.0;
            for i in 0..m {
                let d = (self.rhs[i + 1] - f.lower[i] * prev) * f.inv[i];
                self.diag[i] = d;
                prev = d;
            }
            let mut next = self.diag[m - 1];
            self.cprime[m - 1] = next;
            for i in (0..m - 1).rev() {
                next = self.diag[i] - f.cp[i] * next;
                self.cprime[i] = next;
            }
            let p = &self.cprime;
            a00 = self.capacity[0] + c * k0 - c * k0 * f.x[0];
            a0n = -c * k0 * f.y[0];
            b0 = self.rhs[0] + c * k0 * p[0];
            an0 = -c * kn * f.x[m - 1];
            ann = self.capacity[n] + c * kn - c * kn * f.y[m - 1];
            bn = self.rhs[n] + c * kn * p[m - 1];
        }
        // Newton on (U0, Un).
        let (mut u0, mut un) = (self.temp[0], self.temp[n]);
        let mut used = (0.0, 0.0);
        let mut converged = false;
        for _ in 0..self.max_newton {
            self.stats.solves += 1;
            let (g0, d0, fix0) = linearise(&front, u0);
            let (gn, dn, fixn) = linearise(&back, un);
            // Row 0 and row n of the Newton system J Δ = −F.
            let (j00, j0n, r0) = match fix0 {
                Some(t) => (1.0, 0.0, t - u0),
                None => (a00 - c * d0, a0n, b0 - (a00 * u0 + a0n * un - c * g0)),
            };
            let (jn0, jnn, rn) = match fixn {
                Some(t) => (0.0, 1.0, t - un),
                None => (an0, ann - c * dn, bn - (an0 * u0 + ann * un - c * gn)),
            };
            let det = j00 * jnn - j0n * jn0;
            let du0 = (r0 * jnn - j0n * rn) / det;
            let dun = (j00 * rn - jn0 * r0) / det;
            u0 += du0;
            un += dun;
            used = (
                if fix0.is_some() { 0.0 } else { g0 + d0 * du0 },
                if fixn.is_some() { 0.0 } else { gn + dn * dun },
            );
            if du0.abs().max(dun.abs()) < self.newton_tolerance_k {
                converged = true;
                break;
            }
        }
        if !converged {
            self.stats.unconverged_stages += 1;
        }
        // Recover the interior.
        self.temp[0] = u0;
        self.temp[n] = un;
        if n > 1 {
            let f = &self.factors[slot];
            for i in 0..n - 1 {
                self.temp[i + 1] = self.cprime[i] + u0 * f.x[i] + un * f.y[i];
            }
        }
        used
    }

    /// Factorise the interior matrix for stage coefficient `c` into `slot`
    /// (kept until `c` changes) and compute the boundary responses X, Y.
    fn ensure_factor(&mut self, slot: usize, c: f64) {
        let n = self.temp.len() - 1;
        if self.factors[slot].c == c || n < 2 {
            return;
        }
        let m = n - 1;
        let k = &self.conductance;
        let f = &mut self.factors[slot];
        f.c = c;
        f.lower.clear();
        f.cp.clear();
        f.inv.clear();
        // Interior row j (node i = j + 1): lower −c K_{i−1}, diag
        // C_i + c(K_{i−1} + K_i), upper −c K_i (Thomas algorithm, Press et
        // al., Numerical Recipes, 3rd ed., §2.4).
        let mut prev_cp = 0.0;
        for j in 0..m {
            let i = j + 1;
            let lower = if j > 0 { -c * k[i - 1] } else { 0.0 };
            let upper = if j + 1 < m { -c * k[i] } else { 0.0 };
            let diag = self.capacity[i] + c * (k[i - 1] + k[i]);
            let inv = 1.0 / (diag - lower * prev_cp);
            let cp = upper * inv;
            f.lower.push(lower);
            f.inv.push(inv);
            f.cp.push(cp);
            prev_cp = cp;
        }
        // X = A⁻¹ (c K_0 e_1), Y = A⁻¹ (c K_{n−1} e_m).
        let solve = |rhs_at: &dyn Fn(usize) -> f64,
                     out: &mut Vec<f64>,
                     f_lower: &[f64],
                     f_inv: &[f64],
                     f_cp: &[f64]| {
            out.clear();
            let mut prev = 0.0;
            for j in 0..m {
                let d = (rhs_at(j) - f_lower[j] * prev) * f_inv[j];
                out.push(d);
                prev = d;
            }
            for j in (0..m - 1).rev() {
                out[j] -= f_cp[j] * out[j + 1];
            }
        };
        let (k0, kn) = (k[0], k[n - 1]);
        let mut x = std::mem::take(&mut f.x);
        let mut y = std::mem::take(&mut f.y);
        solve(
            &|j| if j == 0 { c * k0 } else { 0.0 },
            &mut x,
            &f.lower,
            &f.inv,
            &f.cp,
        );
        solve(
            &|j| if j + 1 == m { c * kn } else { 0.0 },
            &mut y,
            &f.lower,
            &f.inv,
            &f.cp,
        );
        f.x = x;
        f.y = y;
    }
}

/// A factorised interior matrix for one stage coefficient.
#[derive(Debug, Clone, Default)]
struct Factor {
    c: f64,
    lower: Vec<f64>,
    cp: Vec<f64>,
    inv: Vec<f64>,
    x: Vec<f64>,
    y: Vec<f64>,
}

#[inline]
fn boundary_flux(b: &Boundary, t_k: f64) -> f64 {
    match b {
        Boundary::Temperature(_) => 0.0,
        Boundary::Flux(f) => f.flux(t_k),
    }
}

#[inline]
fn linearise(b: &Boundary, t_k: f64) -> (f64, f64, Option<f64>) {
    match b {
        Boundary::Temperature(t) => (0.0, 0.0, Some(*t)),
        Boundary::Flux(f) => (f.flux(t_k), f.derivative(t_k), None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_spans_thickness_and_capacity_sums() {
        let s = Slab::new(0.5, 1.0, 2.0e6, Grid::default(), 300.0);
        let d = s.depths_m();
        assert_eq!(d[0], 0.0);
        assert!((d[d.len() - 1] - 0.5).abs() < 1e-15);
        assert!(d.windows(2).all(|w| w[1] > w[0]));
        assert!((s.heat_capacity_j_m2_k() - 0.5 * 2.0e6).abs() < 1e-6);
    }

    #[test]
    fn insulated_slab_stays_uniform() {
        let mut s = Slab::new(0.1, 1.0, 2.0e6, Grid::default(), 290.0);
        let ins = Boundary::Flux(SurfaceFlux::default());
        for _ in 0..50 {
            s.step(600.0, |_| ins, |_| ins);
        }
        assert!(s.temperatures_k().iter().all(|t| (t - 290.0).abs() < 1e-9));
    }
}
