//! The two-source canopy: leaves and the soil under them, each with its own
//! temperature, net radiation, sensible and latent heat — the series
//! resistance model of Norman, Kustas & Anderson (1995), "Source approach
//! for estimating soil and vegetation energy fluxes in observations of
//! directional radiometric surface temperature", Agric. For. Meteorol.
//! 77:263–293, doi:10.1016/0168-1923(95)02265-Y, with the revisions of
//! Kustas & Norman (1999), Agric. For. Meteorol. 94:13–29,
//! doi:10.1016/S0168-1923(99)00005-2.
//!
//! # The network (W m⁻², K, Pa; positive away from the surface)
//! Heat and vapour leave the leaves (T_c) through the leaf boundary layer
//! `r_x` and the soil surface (T_s) through the soil boundary layer
//! `r_soil` into the canopy air (T_ac, e_ac), which exchanges with the air
//! above (T_a, e_a) through `r_a`:
//!
//! ```text
//! T_ac = (T_a/r_a + T_c/r_x + T_s/r_soil) / (1/r_a + 1/r_x + 1/r_soil)      NKA95 eq. 7
//! H_c = ρc_p (T_c − T_ac)/r_x,  H_s = ρc_p (T_s − T_ac)/r_soil,  H = H_c + H_s
//! LE_c = ρc_p/γ (e°(T_c) − e_ac)/(r_x + r_st),  LE_s = ρc_p/γ (e°(T_s) − e_ac)/(r_soil + r_ss)
//! ```
//!
//! | resistance | model | source |
//! |---|---|---|
//! | `r_a` | log profile with `z_oh = z_om` (the excess resistance is `r_x` and `r_soil`), stability by the bulk Richardson number at the canopy-air temperature | NKA95 eq. 4; Louis (1979) |
//! | `r_x` | `C'/LAI · (s/U_{d+z_om})^½`, `C' = 90 s^½ m⁻¹`, `s` leaf width | NKA95 eq. A.8 |
//! | `r_soil` | `1/(c (T_s − T_ac)^⅓ + b u_s)`, `c = 0.0025`, `b = 0.012` | KN99 (NKA95 eq. A.3 with a free-convection term; KN99 write T_s − T_c, equal within a closed canopy, singular as LAI → 0) |
//! | in-canopy wind | `U(z) = U_c exp(a (z/h − 1))`, `a = 0.28 LAI^⅔ h^⅓ s^−⅓`, `u_s = U(0.05 m)` | NKA95 eqs. A.4–A.5 (Goudriaan 1977) |
//! | `r_st` | the Jarvis–Stewart canopy resistance of the big leaf | [`super::latent::JarvisStewart`] |
//! | `r_ss` | `exp(8.206 − 4.255 θ/θ_sat)` | Sellers, Heiser & Hall (1992) J. Geophys. Res. 97(D17):19033 |
//!
//! The canopy transpires by Penman–Monteith through its stomata (the
//! Jarvis `r_st` of the big leaf) instead of NKA95's Priestley–Taylor first
//! guess: a prognostic model has no measured temperature to invert.
//!
//! **Radiation.** The absorbed shortwave is shared by Beer's law, the beam
//! with `τ_b = exp(−κ Ω LAI/√(2 cos θ_s))` (NKA95 eq. 13, κ = 0.45) and the
//! diffuse with the same at θ_s = 60°; the incoming longwave with
//! `τ_L = exp(−0.95 Ω LAI)` (KN99, Campbell & Norman 1998 §15.6 for
//! diffuse radiation through black leaves). The leaves emit
//! `(1 − τ_L) εσT_c⁴` up and down; the soil `εσT_s⁴`, of which the leaves
//! intercept `1 − τ_L`:
//!
//! ```text
//! Rn_c = A_c + (1 − τ_L)(εσT_s⁴ − 2εσT_c⁴),   Rn_s = A_s + (1 − τ_L)εσT_c⁴ − εσT_s⁴
//! ```
//!
//! with `A_c`, `A_s` the absorbed incoming shortwave and longwave of each.
//! The leaves hold no heat (NKA95): `Rn_c = H_c + LE_c`; the soil surface
//! is the front node of the material's slab: `G = Rn_s − H_s − LE_s`.
//!
//! **Rain.** Leaves and soil each hold a Deardorff (1978) store; a wet
//! fraction δ of a source evaporates through its boundary layer alone, so
//! the vapour conductances become `ρc_p/γ ((1 − δ_c)/(r_x + r_st) + δ_c/r_x)`
//! and `ρc_p/γ ((1 − δ_s)/(r_soil + r_ss) + δ_s/r_soil)` ([`wet`]).
//!
//! **Radiometric temperature** (NKA95 eq. 1–2): at view zenith θ,
//! `T_rad⁴ = f_c(θ) T_c⁴ + (1 − f_c(θ)) T_s⁴` with
//! `f_c(θ) = 1 − exp(−0.5 Ω LAI/cos θ)`. The solver gives it at nadir
//! (θ = 0): the renderer sees the nadir composite at every view angle
//! (a limitation: the cover seen obliquely is larger).
//!
//! # How it fits the slab solver
//! The slab solver has one nonlinear front node. The soil surface is that
//! node, with its own emission and evaporation exactly; the leaves are
//! eliminated. Their balance is linearised, at each record, about the
//! material's **open reference surface** (the same reference that sets the
//! stability of every evaporating material, [`super::Exchange`]): with
//! `F(T_c, T_s, S)` the leaves' net flux,
//!
//! ```text
//! T_c = T̂_c + (F̂ + E (T_s − T̂_s) + φ (S − Ŝ)) / D,   D = −∂F/∂T_c,  E = ∂F/∂T_s
//! ```
//!
//! one Newton step of the leaves' balance per reference pass. `S` is the
//! facet's absorbed incoming radiation (what a dry facet's balance calls
//! its source) and `φ` the leaves' share of it at the open surface; every
//! facet's radiation is shared in that proportion. Each pass that updates
//! the resistances and the rain stores puts the leaves in balance at every
//! record with its wet fractions and resistances, the soil at the
//! reference ([`balanced_canopy_k`]; the leaves hold no heat), and moves
//! each record's soil reference by a bounded Wegstein step (damping where
//! the pass-to-pass map turns back, e.g. the soil's free convection
//! `(T_s − T_ac)^⅓`, whose slope is unbounded at `T_s = T_ac`). The passes
//! repeat until the reference changes by less than
//! [`super::surface::REFERENCE_TOLERANCE_K`] (the one driver of every material's
//! reference passes, [`super::surface::ReferencePasses`]), then with the
//! resistances held (Newton, quadratic) until it changes by < 1e-7 K: the
//! open surface then solves the nonlinear two-source balance (both
//! balances close to < 1e-6 W m⁻², `tests`), and any other facet of the material is
//! exact to first order in its departure from the reference, like the
//! stability of every evaporating material. The soil's law stays of the
//! slab's form `q = S' − L·T_s − εσT_s⁴ − g (e°(T_s) − e')` with `S'`
//! affine in `S`, so the linearised scene solve carries it unchanged.
//!
//! # What it owns, takes and gives
//! Owns the two-source physics at one record. Takes the canopy's parameters,
//! the weather of a record and the reference temperatures; gives a
//! [`TwoSourceStep`]: the soil's flux law, the leaves' temperature and the
//! radiometric temperature as functions of a facet's source and soil
//! temperature, and every flux for diagnostics. Knows nothing of slabs or
//! scenes.

use super::conduction::{STEFAN_BOLTZMANN_W_M2_K4, SurfaceFlux};
use super::latent::psychrometrics::{
    AIR_SPECIFIC_HEAT_J_KG_K, saturation_vapour_pressure_pa as es,
    saturation_vapour_pressure_slope_pa_k as des,
};
use super::latent::{Aerodynamic, AirState, CanopyConditions, JarvisStewart, RootZone, WaterStep};

/// Extinction coefficient of the beam in NKA95 eq. 13 (their 0.3–0.6).
pub const BEAM_EXTINCTION: f64 = 0.45;
/// Extinction coefficient of diffuse longwave, KN99.
pub const LONGWAVE_EXTINCTION: f64 = 0.95;
/// `C'` of the leaf boundary-layer resistance, s^½ m⁻¹ (NKA95 eq. A.8).
pub const LEAF_BOUNDARY_C: f64 = 90.0;
/// `b` of the soil resistance, dimensionless (KN99).
pub const SOIL_RESISTANCE_B: f64 = 0.012;
/// `c` of the soil resistance, m s⁻¹ K^−⅓ (KN99).
pub const SOIL_RESISTANCE_C: f64 = 0.0025;
/// Height of the wind that sets the soil resistance, m (NKA95).
pub const SOIL_WIND_HEIGHT_M: f64 = 0.05;

/// The canopy's two-source parameters (from `surface_energy`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoSourceParams {
    /// Clumping index Ω, (0, 1].
    pub clumping_index: f64,
    /// Leaf width s, m.
    pub leaf_width_m: f64,
    /// Soil water content at saturation, m³ m⁻³.
    pub saturation_m3_m3: f64,
}

/// Everything the network needs at one record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoSourceInputs {
    /// The air above the canopy.
    pub air: AirState,
    /// Wind at `aerodynamic.wind_height_m()`, m s⁻¹ (> 0).
    pub wind_speed_m_s: f64,
    /// Beam shortwave on a horizontal surface, W m⁻².
    pub direct_horizontal_w_m2: f64,
    /// Diffuse shortwave on a horizontal surface, W m⁻².
    pub diffuse_horizontal_w_m2: f64,
    /// Sky longwave, W m⁻².
    pub sky_longwave_w_m2: f64,
    /// Cosine of the solar zenith angle.
    pub cos_zenith: f64,
    /// The log profile over the canopy (z_oh is replaced by z_om).
    pub aerodynamic: Aerodynamic,
    /// Canopy height h, m (> 0 with leaves).
    pub canopy_height_m: f64,
    /// One-sided leaf area index, m² m⁻² (≥ 0).
    pub leaf_area_index: f64,
    /// The canopy's stomatal resistance r_st, s m⁻¹ (+∞: shut).
    pub stomatal_resistance_s_m: f64,
    /// Soil surface's resistance to evaporation r_ss, s m⁻¹ (+∞: dry).
    pub soil_surface_resistance_s_m: f64,
    /// The parameters.
    pub params: TwoSourceParams,
    /// Solar absorptivity α of the surface.
    pub solar_absorptivity: f64,
    /// Hemispherical emissivity ε of leaves and soil.
    pub emissivity: f64,
    /// Wet fraction δ_c of the leaves (rain they hold; 0: dry), [0, 1].
    pub leaf_wet_fraction: f64,
    /// Wet fraction δ_s of the soil surface (0: dry), [0, 1].
    pub soil_wet_fraction: f64,
    /// The leaves' Jarvis–Stewart stomata (None: no leaves), which set
    /// `stomatal_resistance_s_m` from the soil water
    /// ([`TwoSourceInputs::set_soil_moisture`]).
    pub stomata: Option<JarvisStewart>,
    /// Global shortwave on a horizontal surface, W m⁻²: the stomata's light.
    pub global_horizontal_w_m2: f64,
}

impl TwoSourceInputs {
    /// The same record with the soil at water content `theta_m3_m3`: the
    /// stomata's soil-water factor f_soil(θ) (the big leaf's,
    /// [`JarvisStewart`]) in `r_st` and the soil surface's `r_ss(θ)`.
    pub fn set_soil_moisture(&mut self, theta_m3_m3: f64) {
        if let Some(js) = &self.stomata {
            self.stomatal_resistance_s_m =
                stomatal(js, &self.air, self.global_horizontal_w_m2, theta_m3_m3);
        }
        self.soil_surface_resistance_s_m =
            soil_surface_resistance_s_m(theta_m3_m3, self.params.saturation_m3_m3);
    }
}

/// The soil surface's resistance to evaporation of Sellers, Heiser & Hall
/// (1992): `exp(8.206 − 4.255 W)` s m⁻¹, `W = θ/θ_sat` the wetness of the
/// top soil (≈ 3700 s m⁻¹ dry, 52 s m⁻¹ saturated).
pub fn soil_surface_resistance_s_m(theta_m3_m3: f64, saturation_m3_m3: f64) -> f64 {
    let w = (theta_m3_m3 / saturation_m3_m3).clamp(0.0, 1.0);
    (8.206 - 4.255 * w).exp()
}

/// The inputs of record `k` of a land surface with two sources under
/// `forcing` (heights, LAI and height at that time), leaving the
/// stability to the caller's reference temperatures.
///
/// Returns None when the surface has no two-source parameters.
pub(crate) fn inputs_at(
    surface: &super::LandSurface,
    forcing: &super::Forcing,
    k: usize,
    solar_absorptivity: f64,
    emissivity: f64,
) -> crate::error::Result<Option<TwoSourceInputs>> {
    use crate::error::Error;
    let Some(params) = surface.two_source else {
        return Ok(None);
    };
    let s = surface.on(forcing.start_unix_s + forcing.times_s[k]);
    let air = AirState::new(
        forcing.air_temperature_k[k],
        forcing.vapour_pressure_pa[k],
        forcing.pressure_pa[k],
    )
    .map_err(|e| Error::invalid(format!("records[{k}].{}", e.field()), e.to_string()))?;
    let (zw, za) = s.heights(forcing.wind_height_m, forcing.air_height_m);
    let aero = Aerodynamic::new(
        zw,
        za,
        s.displacement_height_m,
        s.roughness_length_m,
        s.roughness_length_m,
    )
    .map_err(|e| Error::invalid(format!("surface_energy.{}", e.field()), e.to_string()))?;
    let (lai, r_st, stomata) = match s.resistance {
        super::latent::SurfaceResistance::Canopy(js) => (
            js.leaf_area_index,
            stomatal(
                &js,
                &air,
                forcing.global_horizontal_w_m2[k],
                s.soil_moisture_m3_m3,
            ),
            Some(js),
        ),
        _ => (0.0, f64::INFINITY, None),
    };
    let dni = forcing.direct_normal_w_m2[k];
    let diffuse = forcing.diffuse_horizontal_w_m2[k];
    let direct_h = (forcing.global_horizontal_w_m2[k] - diffuse).max(0.0);
    let cos_zenith = if dni > 1.0 {
        (direct_h / dni).clamp(0.0, 1.0)
    } else {
        0.0
    };
    Ok(Some(TwoSourceInputs {
        air,
        wind_speed_m_s: forcing.wind_speed_m_s[k].max(super::surface::MIN_WIND_M_S),
        direct_horizontal_w_m2: direct_h,
        diffuse_horizontal_w_m2: diffuse,
        sky_longwave_w_m2: forcing.sky_longwave_w_m2[k],
        cos_zenith,
        aerodynamic: aero,
        canopy_height_m: s.canopy_height_m,
        leaf_area_index: lai,
        stomatal_resistance_s_m: r_st,
        soil_surface_resistance_s_m: soil_surface_resistance_s_m(
            s.soil_moisture_m3_m3,
            params.saturation_m3_m3,
        ),
        params,
        solar_absorptivity,
        emissivity,
        leaf_wet_fraction: 0.0,
        soil_wet_fraction: 0.0,
        stomata,
        global_horizontal_w_m2: forcing.global_horizontal_w_m2[k],
    }))
}

/// Capacity of the soil surface's rain store, mm (the bare soil's of
/// [`super::WetStore`]).
pub const SOIL_STORE_MM: f64 = 1.0;

/// Rain held by the leaves and by the soil surface of a two-source canopy,
/// the interception reservoir of Deardorff (1978, J. Geophys. Res.
/// 83(C4):1889) as Noilhan & Planton (1989, Mon. Weather Rev. 117:536)
/// §2c hold it, one store per source: the leaves catch the nadir cover
/// `f_c = 1 − exp(−0.5 Ω LAI)` of each record's rain up to `0.2·LAI` mm
/// (Dickinson 1984); the rest and their overflow reach the soil surface,
/// which holds [`SOIL_STORE_MM`]; more runs off. A wet fraction
/// `δ = (W/W_max)^⅔` of each source evaporates through its boundary layer
/// alone (`r_x` for leaves, `r_soil` for soil, no stomatal or soil-surface
/// resistance), and each store empties at its wet part's evaporation
/// `δ ρc_p/(γ r)·max(e°(T) − e_ac, 0)/λ` (kg m⁻² s⁻¹ = mm s⁻¹) over the
/// interval after the record, at the reference temperatures `t_c`, `t_s`.
/// Sets the wet fractions of `inputs` (one per record of `forcing`, and
/// of `t_c` and `t_s`; records beyond the shortest are left as they are);
/// returns whether any record is wet. No rain: every fraction 0, exactly
/// the dry network. [`water`] without a root zone.
pub fn wet(
    inputs: &mut [TwoSourceInputs],
    forcing: &super::Forcing,
    t_c: &[f64],
    t_s: &[f64],
) -> bool {
    water(inputs, forcing, t_c, t_s, None).wet
}

/// What [`water`] gives: whether any record is wet, and the root zone's
/// water content at each record and its water over the interval after each
/// (both empty without a root zone).
#[derive(Debug, Clone, PartialEq)]
pub struct SoilWater {
    /// Whether leaves or soil hold rain at any record.
    pub wet: bool,
    /// θ of the root zone at each record, m³ m⁻³.
    pub soil_moisture_m3_m3: Vec<f64>,
    /// The root zone's water over the interval after each record.
    pub steps: Vec<WaterStep>,
}

/// The leaves' temperature that closes their balance `F(T_c) = Rn_c − H_c
/// − LE_c = 0` on the open reference surface of record `x` with the soil
/// at `t_s`, every resistance (stability of `r_a`, the soil's free
/// convection) taken at that `T_c` itself, K; `guess` starts the search.
///
/// The leaves hold no heat (NKA95), so their temperature is a function of
/// the record's wet fraction, resistances and soil temperature alone, not
/// of the previous reference pass. Solving it within the record (instead of
/// one Newton step from the previous pass's leaves) is what makes the
/// passes of [`super::Exchange::two_source`] settle: a wet store's
/// evaporation set by the previous pass's leaves, and leaves set by the
/// previous pass's resistances, fed back with a gain above 1 (the leaves of
/// a drying store flipped between ≈ 292 K wet and ≈ 301 K dry from pass to
/// pass). Newton steps of the linearisation ([`TwoSourceStep::canopy_k`],
/// whose sign is that of F since `D > 0`) kept inside a bracket that
/// bisection shrinks (a safeguarded Newton method, Press et al. 2007,
/// Numerical Recipes 3rd ed. §9.4 `rtsafe`), to 1e-9 K.
pub fn balanced_canopy_k(x: &TwoSourceInputs, guess: f64, t_s: f64) -> f64 {
    let toward = |t: f64| {
        let step = TwoSourceStep::new(x, t, t_s);
        step.canopy_k(step.open_source_w_m2(), t_s)
    };
    let step = TwoSourceStep::new(x, guess, t_s);
    if !step.has_canopy() || !guess.is_finite() {
        return guess;
    }
    // Bracket: F > 0 (Newton moves up) at `lo`, F < 0 at `hi`.
    let (mut lo, mut hi) = (f64::NAN, f64::NAN);
    let mut t = guess;
    for _ in 0..200 {
        let next = toward(t);
        if !next.is_finite() {
            break;
        }
        if (next - t).abs() < 1e-9 {
            return next;
        }
        if next > t {
            lo = t;
        } else {
            hi = t;
        }
        t = if lo.is_nan() {
            // Widen down until F changes sign.
            next.max(hi - 20.0)
        } else if hi.is_nan() {
            next.min(lo + 20.0)
        } else if next > lo && next < hi {
            next
        } else {
            0.5 * (lo + hi)
        };
        if !(lo.is_nan() || hi.is_nan()) && hi - lo < 1e-9 {
            return 0.5 * (lo + hi);
        }
    }
    t
}

/// The rain stores of [`wet`] and, with `root_zone` (the bucket and its
/// starting θ), the root zone's water under a two-source canopy, record by
/// record: θ at the record sets the leaves' stomatal resistance (f_soil(θ),
/// as the big leaf's) and the soil surface's resistance r_ss(θ) of
/// `inputs`; the rain the soil surface's store does not hold infiltrates;
/// over the interval after the record the bucket loses the dry parts'
/// evaporation, the leaves' transpiration `(1 − δ_c) ρc_p/(γ (r_x + r_st))
/// (e°(T_c) − e_ac)` and the soil's `(1 − δ_s) ρc_p/(γ (r_soil + r_ss))
/// (e°(T_s) − e_ac)` (negative: dew), over λ at the air temperature, with
/// the soil at the reference `t_s` and the leaves at their balance for the
/// record's resistances about the reference `t_c`
/// ([`TwoSourceStep::canopy_k`] of the open surface: shut stomata warm the
/// leaves rather than only cut their transpiration, which would make the
/// passes of [`super::Exchange::two_source`] oscillate) ([`RootZone::step`];
/// the wet parts evaporate the stores at the reference temperatures). Without a root zone: exactly [`wet`]'s
/// stores, the resistances untouched.
pub fn water(
    inputs: &mut [TwoSourceInputs],
    forcing: &super::Forcing,
    t_c: &[f64],
    t_s: &[f64],
    root_zone: Option<(&RootZone, f64)>,
) -> SoilWater {
    use super::latent::psychrometrics::latent_heat_of_vaporisation_j_kg;
    let (mut leaves, mut soil) = (0.0f64, 0.0f64);
    let mut any = false;
    let n = forcing.len().min(t_c.len()).min(t_s.len());
    let mut theta = root_zone.map_or(0.0, |(_, t)| t);
    let mut thetas = Vec::new();
    let mut steps = Vec::new();
    let mut leaves_k = t_c.to_vec();
    for (k, x) in inputs.iter_mut().enumerate().take(n) {
        let rain = forcing.precipitation_mm[k].max(0.0);
        let lai = x.leaf_area_index.max(0.0);
        let cover = 1.0 - (-0.5 * x.params.clumping_index * lai).exp();
        let capacity = 0.2 * lai;
        leaves += cover * rain;
        let overflow = (leaves - capacity).max(0.0);
        leaves = leaves.min(capacity);
        let reaching = soil + (1.0 - cover) * rain + overflow;
        let infiltration = (reaching - SOIL_STORE_MM).max(0.0);
        soil = reaching.min(SOIL_STORE_MM);
        x.leaf_wet_fraction = if capacity > 0.0 {
            (leaves / capacity).powf(2.0 / 3.0)
        } else {
            0.0
        };
        x.soil_wet_fraction = (soil / SOIL_STORE_MM).powf(2.0 / 3.0);
        if root_zone.is_some() {
            x.set_soil_moisture(theta);
            thetas.push(theta);
        }
        any |= leaves > 0.0 || soil > 0.0;
        if k + 1 < n {
            let dt = forcing.times_s[k + 1] - forcing.times_s[k];
            let lambda = latent_heat_of_vaporisation_j_kg(x.air.temperature_k());
            let wet_now = leaves > 0.0 || soil > 0.0;
            // The leaves in balance with this record's wet fraction and
            // resistances, the soil at the reference: the stomata that θ
            // closes warm the leaves, a wet store cools them, within the
            // record; at the fixed point this is the reference.
            let step = (wet_now || root_zone.is_some()).then(|| {
                leaves_k[k] = balanced_canopy_k(x, t_c[k], t_s[k]);
                TwoSourceStep::new(x, leaves_k[k], t_s[k])
            });
            if let (true, Some(step)) = (wet_now, &step) {
                let (le_c, le_s) = step.wet_latent_w_m2(leaves_k[k], t_s[k]);
                leaves = (leaves - le_c.max(0.0) / lambda * dt).max(0.0);
                soil = (soil - le_s.max(0.0) / lambda * dt).max(0.0);
            }
            if let (Some((zone, _)), Some(step)) = (root_zone, &step) {
                let (le_c, le_s) = step.dry_latent_w_m2(leaves_k[k], t_s[k]);
                let w = zone.step(theta, infiltration, (le_c + le_s) / lambda * dt, dt);
                theta = w.theta_m3_m3;
                steps.push(w);
            }
        }
    }
    SoilWater {
        wet: any,
        soil_moisture_m3_m3: thetas,
        steps,
    }
}

/// Vapour conductance `ρc_p/γ · ((1 − δ)/(r_b + r_surf) + δ/r_b)`, W m⁻²
/// Pa⁻¹, of a source with boundary-layer resistance `r_b`, surface
/// resistance `r_surf` and wet fraction δ (Deardorff 1978); δ = 0 is the
/// dry `ρc_p/(γ (r_b + r_surf))` exactly.
fn vapour_conductance(rho_cp: f64, gamma: f64, r_b: f64, r_surf: f64, delta: f64) -> f64 {
    let dry = rho_cp / (gamma * (r_b + r_surf));
    if delta > 0.0 {
        (1.0 - delta) * dry + delta * rho_cp / (gamma * r_b)
    } else {
        dry
    }
}

fn stomatal(js: &JarvisStewart, air: &AirState, sw: f64, theta: f64) -> f64 {
    js.surface_resistance_s_m(&CanopyConditions {
        shortwave_down_w_m2: sw.max(0.0),
        vapour_pressure_deficit_pa: air.vapour_pressure_deficit_pa(),
        air_temperature_k: air.temperature_k(),
        soil_moisture_m3_m3: theta,
    })
}

/// The fluxes of both sources at one instant (W m⁻², positive: away from
/// the surface for H and LE, into it for Rn and G).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoSourceFluxes {
    /// Leaf temperature, K.
    pub canopy_k: f64,
    /// Soil surface temperature, K.
    pub soil_k: f64,
    /// Canopy-air temperature, K.
    pub canopy_air_k: f64,
    /// Net radiation of the leaves and of the soil.
    pub net_radiation_canopy_w_m2: f64,
    /// Net radiation of the soil.
    pub net_radiation_soil_w_m2: f64,
    /// Sensible heat of the leaves.
    pub sensible_canopy_w_m2: f64,
    /// Sensible heat of the soil.
    pub sensible_soil_w_m2: f64,
    /// Transpiration of the leaves.
    pub latent_canopy_w_m2: f64,
    /// Evaporation of the soil.
    pub latent_soil_w_m2: f64,
    /// Heat into the soil, `Rn_s − H_s − LE_s`.
    pub ground_w_m2: f64,
}

impl TwoSourceFluxes {
    /// Rn of the surface, W m⁻².
    pub fn net_radiation_w_m2(&self) -> f64 {
        self.net_radiation_canopy_w_m2 + self.net_radiation_soil_w_m2
    }
    /// H of the surface, W m⁻².
    pub fn sensible_w_m2(&self) -> f64 {
        self.sensible_canopy_w_m2 + self.sensible_soil_w_m2
    }
    /// LE of the surface, W m⁻².
    pub fn latent_w_m2(&self) -> f64 {
        self.latent_canopy_w_m2 + self.latent_soil_w_m2
    }
    /// The leaves' imbalance `Rn_c − H_c − LE_c`, W m⁻² (0: closed).
    pub fn canopy_residual_w_m2(&self) -> f64 {
        self.net_radiation_canopy_w_m2 - self.sensible_canopy_w_m2 - self.latent_canopy_w_m2
    }
}

/// The two-source model at one record, linearised about reference
/// temperatures (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoSourceStep {
    air_k: f64,
    air_vapour_pa: f64,
    /// Conductances ρc_p/r (W m⁻² K⁻¹) of r_a, r_x, r_soil.
    g_a: f64,
    g_x: f64,
    g_s: f64,
    /// Vapour conductances ρc_p/(γ r) (W m⁻² Pa⁻¹) of r_a, r_x + r_st,
    /// r_soil + r_ss.
    w_a: f64,
    w_c: f64,
    w_s: f64,
    /// The wet parts of `w_c` and `w_s`: `δ ρc_p/(γ r)` of r_x and r_soil.
    w_c_wet: f64,
    w_s_wet: f64,
    eps_sigma: f64,
    tau_l: f64,
    /// The leaves' share of a facet's absorbed incoming radiation.
    phi: f64,
    /// Nadir cover fraction f_c(0).
    cover_nadir: f64,
    /// The linearisation point: T̂_c, T̂_s (K), Ŝ (W m⁻²).
    t_c: f64,
    t_s: f64,
    s: f64,
    /// F̂, D, E of the leaves' balance (module docs); D = 0 without leaves.
    f_hat: f64,
    d: f64,
    e: f64,
}

impl TwoSourceStep {
    /// The step for `inputs` linearised about leaves at `t_c`, soil at
    /// `t_s` (K) and an open facet's source (computed here). The
    /// stability of `r_a` and the free convection of `r_soil` are taken at
    /// these temperatures.
    pub fn new(x: &TwoSourceInputs, t_c: f64, t_s: f64) -> TwoSourceStep {
        let air = &x.air;
        let rho_cp = air.density_kg_m3() * AIR_SPECIFIC_HEAT_J_KG_K;
        let gamma = air.psychrometric_constant_pa_k();
        let p = &x.params;
        let lai = x.leaf_area_index.max(0.0);
        let omega_lai = p.clumping_index * lai;
        let a = &x.aerodynamic;
        let h = x.canopy_height_m;
        let (d0, z0) = (a.displacement_height_m(), a.roughness_momentum_m());
        let u = x.wind_speed_m_s;
        // Wind at the canopy top (neutral log profile) and inside it.
        let (u_dz, u_s) = if h > 0.0 && h - d0 > z0 {
            let u_c = u * ((h - d0) / z0).ln() / ((a.wind_height_m() - d0) / z0).ln();
            let att = 0.28 * lai.powf(2.0 / 3.0) * h.cbrt() / p.leaf_width_m.cbrt();
            let at = |z: f64| u_c * (att * (z.min(h) / h - 1.0)).exp();
            (at(d0 + z0), at(SOIL_WIND_HEIGHT_M))
        } else {
            (u, u)
        };
        let r_x = if lai > 0.0 {
            LEAF_BOUNDARY_C / lai * (p.leaf_width_m / u_dz).sqrt()
        } else {
            f64::INFINITY
        };
        let g_x = rho_cp / r_x;
        let g_a_neutral = rho_cp / a.neutral_resistance_s_m(u);
        // The soil's free convection is driven by the soil–canopy-air
        // difference (KN99 write T_s − T_c, the same within a closed
        // canopy; with T_c a leafless canopy's limit would be singular).
        let g_forced = rho_cp * SOIL_RESISTANCE_B * u_s;
        let t_ac0 = (g_a_neutral * air.temperature_k() + g_x * t_c + g_forced * t_s)
            / (g_a_neutral + g_x + g_forced);
        let r_soil =
            1.0 / (SOIL_RESISTANCE_C * (t_s - t_ac0).max(0.0).cbrt() + SOIL_RESISTANCE_B * u_s);
        let g_s = rho_cp / r_soil;
        // r_a with the stability of the canopy air at the reference.
        let t_ac =
            (g_a_neutral * air.temperature_k() + g_x * t_c + g_s * t_s) / (g_a_neutral + g_x + g_s);
        let r_a = a.resistance_s_m(u, t_ac, air.temperature_k());
        let g_a = rho_cp / r_a;
        let w_a = g_a / gamma;
        let w_c = vapour_conductance(
            rho_cp,
            gamma,
            r_x,
            x.stomatal_resistance_s_m,
            x.leaf_wet_fraction,
        );
        let w_s = vapour_conductance(
            rho_cp,
            gamma,
            r_soil,
            x.soil_surface_resistance_s_m,
            x.soil_wet_fraction,
        );
        let w_c_wet = x.leaf_wet_fraction * rho_cp / (gamma * r_x);
        let w_s_wet = x.soil_wet_fraction * rho_cp / (gamma * r_soil);
        let tau_b = if x.cos_zenith > 0.0 {
            (-BEAM_EXTINCTION * omega_lai / (2.0 * x.cos_zenith).sqrt()).exp()
        } else {
            0.0
        };
        let tau_d = (-BEAM_EXTINCTION * omega_lai).exp();
        let tau_l = (-LONGWAVE_EXTINCTION * omega_lai).exp();
        let alpha = x.solar_absorptivity;
        let eps = x.emissivity;
        let s_open = alpha * (x.direct_horizontal_w_m2 + x.diffuse_horizontal_w_m2)
            + eps * x.sky_longwave_w_m2;
        let s_canopy = alpha
            * ((1.0 - tau_b) * x.direct_horizontal_w_m2
                + (1.0 - tau_d) * x.diffuse_horizontal_w_m2)
            + eps * (1.0 - tau_l) * x.sky_longwave_w_m2;
        let phi = if s_open > 0.0 {
            (s_canopy / s_open).clamp(0.0, 1.0)
        } else {
            1.0 - tau_l
        };
        let mut step = TwoSourceStep {
            air_k: air.temperature_k(),
            air_vapour_pa: air.vapour_pressure_pa(),
            g_a,
            g_x,
            g_s,
            w_a,
            w_c,
            w_s,
            w_c_wet,
            w_s_wet,
            eps_sigma: eps * STEFAN_BOLTZMANN_W_M2_K4,
            tau_l,
            phi,
            cover_nadir: 1.0 - (-0.5 * omega_lai).exp(),
            t_c,
            t_s,
            s: s_open,
            f_hat: 0.0,
            d: 0.0,
            e: 0.0,
        };
        if lai > 0.0 {
            step = step.relinearised(t_c, t_s);
        }
        step
    }

    /// The same network (resistances, radiation shares) with the leaves'
    /// balance linearised about leaves at `t_c` and soil at `t_s` instead:
    /// one Newton step of the leaves' balance with the resistances held.
    pub fn relinearised(&self, t_c: f64, t_s: f64) -> TwoSourceStep {
        let mut step = *self;
        step.t_c = t_c;
        step.t_s = t_s;
        if self.g_x == 0.0 && self.tau_l == 1.0 {
            // No leaves: nothing to linearise.
            return step;
        }
        let (sg, sw) = (
            self.g_a + self.g_x + self.g_s,
            self.w_a + self.w_c + self.w_s,
        );
        let lw = (1.0 - self.tau_l) * self.eps_sigma;
        step.f_hat = step.canopy_net(t_c, t_s, self.s);
        step.d = 8.0 * lw * t_c.powi(3)
            + self.g_x * (self.g_a + self.g_s) / sg
            + self.w_c * (self.w_a + self.w_s) / sw * des(t_c);
        step.e =
            4.0 * lw * t_s.powi(3) + self.g_x * self.g_s / sg + self.w_c * self.w_s / sw * des(t_s);
        step
    }

    /// The conductances of the network at this record: heat `ρc_p/r`
    /// (W m⁻² K⁻¹) of r_a, r_x, r_soil, and vapour `ρc_p/(γ r)`
    /// (W m⁻² Pa⁻¹) of r_a, r_x + r_st, r_soil + r_ss.
    pub fn conductances(&self) -> [f64; 6] {
        [self.g_a, self.g_x, self.g_s, self.w_a, self.w_c, self.w_s]
    }

    /// Whether the surface has leaves.
    pub fn has_canopy(&self) -> bool {
        self.d > 0.0
    }

    /// The latent heat of the wet parts of leaves and soil (the rain they
    /// hold evaporating, [`wet`]) with leaves at `t_c` and soil at `t_s`,
    /// W m⁻² each.
    pub fn wet_latent_w_m2(&self, t_c: f64, t_s: f64) -> (f64, f64) {
        let sw = self.w_a + self.w_c + self.w_s;
        let e_ac = (self.w_a * self.air_vapour_pa + self.w_c * es(t_c) + self.w_s * es(t_s)) / sw;
        (
            self.w_c_wet * (es(t_c) - e_ac),
            self.w_s_wet * (es(t_s) - e_ac),
        )
    }

    /// The latent heat of the dry parts of leaves and soil (the leaves'
    /// transpiration through their stomata, the soil's evaporation through
    /// r_ss: what the root zone loses, [`water`]) with leaves at `t_c` and
    /// soil at `t_s`, W m⁻² each.
    pub fn dry_latent_w_m2(&self, t_c: f64, t_s: f64) -> (f64, f64) {
        let sw = self.w_a + self.w_c + self.w_s;
        let e_ac = (self.w_a * self.air_vapour_pa + self.w_c * es(t_c) + self.w_s * es(t_s)) / sw;
        (
            (self.w_c - self.w_c_wet) * (es(t_c) - e_ac),
            (self.w_s - self.w_s_wet) * (es(t_s) - e_ac),
        )
    }

    /// The open reference surface's source Ŝ (its absorbed incoming
    /// radiation), W m⁻².
    pub fn open_source_w_m2(&self) -> f64 {
        self.s
    }

    /// Whether leaves or soil hold rain at this record ([`wet`]).
    pub fn is_wet(&self) -> bool {
        self.w_c_wet > 0.0 || self.w_s_wet > 0.0
    }

    /// The leaves' share φ of a facet's absorbed incoming radiation.
    pub fn canopy_share(&self) -> f64 {
        self.phi
    }

    /// The leaves' net flux F(T_c, T_s, S) = Rn_c − H_c − LE_c, W m⁻².
    fn canopy_net(&self, t_c: f64, t_s: f64, s: f64) -> f64 {
        let (sg, sw) = (
            self.g_a + self.g_x + self.g_s,
            self.w_a + self.w_c + self.w_s,
        );
        let rn =
            self.phi * s + (1.0 - self.tau_l) * self.eps_sigma * (t_s.powi(4) - 2.0 * t_c.powi(4));
        let h =
            self.g_x * ((self.g_a + self.g_s) * t_c - self.g_a * self.air_k - self.g_s * t_s) / sg;
        let le = self.w_c
            * ((self.w_a + self.w_s) * es(t_c)
                - self.w_a * self.air_vapour_pa
                - self.w_s * es(t_s))
            / sw;
        rn - h - le
    }

    /// Leaf temperature of a facet with source `s` (W m⁻²) whose soil is at
    /// `t_s` (K): the linearised balance (module docs); `t_s` without
    /// leaves.
    pub fn canopy_k(&self, s: f64, t_s: f64) -> f64 {
        if !self.has_canopy() {
            return t_s;
        }
        self.t_c + (self.f_hat + self.e * (t_s - self.t_s) + self.phi * (s - self.s)) / self.d
    }

    /// `∂T_c/∂T_s` and `∂T_c/∂S` of [`TwoSourceStep::canopy_k`].
    pub fn canopy_derivatives(&self) -> (f64, f64) {
        if !self.has_canopy() {
            return (1.0, 0.0);
        }
        (self.e / self.d, self.phi / self.d)
    }

    /// The radiometric temperature at nadir, K (module docs).
    pub fn radiometric_k(&self, s: f64, t_s: f64) -> f64 {
        let t_c = self.canopy_k(s, t_s);
        let f = self.cover_nadir;
        (f * t_c.powi(4) + (1.0 - f) * t_s.powi(4)).powf(0.25)
    }

    /// The hemispherical radiometric temperature, K: what the upwelling
    /// longwave of a black surface would show, `τ_L T_s⁴ + (1 − τ_L) T_c⁴`.
    pub fn hemispherical_k(&self, s: f64, t_s: f64) -> f64 {
        let t_c = self.canopy_k(s, t_s);
        (self.tau_l * t_s.powi(4) + (1.0 - self.tau_l) * t_c.powi(4)).powf(0.25)
    }

    /// `(∂T_rad/∂T_s, ∂T_rad/∂S)` of [`TwoSourceStep::radiometric_k`] at
    /// (`s`, `t_s`), the leaves through [`TwoSourceStep::canopy_k`].
    pub fn radiometric_derivatives(&self, s: f64, t_s: f64) -> (f64, f64) {
        let t_c = self.canopy_k(s, t_s);
        let t_r = self.radiometric_k(s, t_s);
        let f = self.cover_nadir;
        let w_c = f * (t_c / t_r).powi(3);
        let w_s = (1.0 - f) * (t_s / t_r).powi(3);
        let (b, chi) = self.canopy_derivatives();
        if !self.has_canopy() {
            return (1.0, 0.0);
        }
        (w_s + w_c * b, w_c * chi)
    }

    /// The soil surface's flux law for a facet with source `s` (W m⁻²):
    /// the slab's front law (module docs).
    pub fn soil_law(&self, s: f64) -> SurfaceFlux {
        let (sg, sw) = (
            self.g_a + self.g_x + self.g_s,
            self.w_a + self.w_c + self.w_s,
        );
        // The soil's own exchange with the air through the canopy air.
        let linear_own = self.g_s * (self.g_a + self.g_x) / sg;
        let g = self.w_s * (self.w_a + self.w_c) / sw;
        let e_ref = if self.w_a + self.w_c > 0.0 {
            self.w_a * self.air_vapour_pa / (self.w_a + self.w_c)
        } else {
            0.0
        };
        let mut source = (1.0 - self.phi) * s + self.g_s * self.g_a / sg * self.air_k;
        let mut linear = linear_own;
        if self.has_canopy() {
            // Q(T_c): what the leaves give the soil, linearised.
            let tc = self.t_c;
            let q_hat = (1.0 - self.tau_l) * self.eps_sigma * tc.powi(4)
                + self.g_s * self.g_x / sg * tc
                + self.w_s * self.w_c / sw * es(tc);
            let q_der = 4.0 * (1.0 - self.tau_l) * self.eps_sigma * tc.powi(3)
                + self.g_s * self.g_x / sg
                + self.w_s * self.w_c / sw * des(tc);
            let k = q_der / self.d;
            source += q_hat + k * (self.f_hat - self.e * self.t_s + self.phi * (s - self.s));
            linear -= k * self.e;
        }
        SurfaceFlux {
            source_w_m2: source,
            linear_w_m2_k: linear,
            radiative_w_m2_k4: self.eps_sigma,
            vapour_conductance_w_m2_pa: g,
            air_vapour_pressure_pa: e_ref,
        }
    }

    /// `∂S'/∂S`: how a facet's source enters the soil's law.
    pub fn source_slope(&self) -> f64 {
        if !self.has_canopy() {
            return 1.0 - self.phi;
        }
        let (sg, sw) = (
            self.g_a + self.g_x + self.g_s,
            self.w_a + self.w_c + self.w_s,
        );
        let tc = self.t_c;
        let q_der = 4.0 * (1.0 - self.tau_l) * self.eps_sigma * tc.powi(3)
            + self.g_s * self.g_x / sg
            + self.w_s * self.w_c / sw * des(tc);
        (1.0 - self.phi) + q_der * self.phi / self.d
    }

    /// Every flux of a facet with source `s` and soil at `t_s`, evaluated
    /// with the nonlinear expressions at the leaves' temperature
    /// [`TwoSourceStep::canopy_k`].
    pub fn fluxes(&self, s: f64, t_s: f64) -> TwoSourceFluxes {
        let t_c = self.canopy_k(s, t_s);
        let (sg, sw) = (
            self.g_a + self.g_x + self.g_s,
            self.w_a + self.w_c + self.w_s,
        );
        let t_ac = (self.g_a * self.air_k + self.g_x * t_c + self.g_s * t_s) / sg;
        let e_ac = (self.w_a * self.air_vapour_pa + self.w_c * es(t_c) + self.w_s * es(t_s)) / sw;
        let lw_c = (1.0 - self.tau_l) * self.eps_sigma;
        let rn_c = if self.has_canopy() {
            self.phi * s + lw_c * (t_s.powi(4) - 2.0 * t_c.powi(4))
        } else {
            0.0
        };
        let rn_s = (1.0 - self.phi) * s + lw_c * t_c.powi(4) - self.eps_sigma * t_s.powi(4);
        let h_s = self.g_s * (t_s - t_ac);
        let le_s = self.w_s * (es(t_s) - e_ac);
        TwoSourceFluxes {
            canopy_k: t_c,
            soil_k: t_s,
            canopy_air_k: t_ac,
            net_radiation_canopy_w_m2: rn_c,
            net_radiation_soil_w_m2: rn_s,
            sensible_canopy_w_m2: self.g_x * (t_c - t_ac),
            sensible_soil_w_m2: h_s,
            latent_canopy_w_m2: self.w_c * (es(t_c) - e_ac),
            latent_soil_w_m2: le_s,
            ground_w_m2: rn_s - h_s - le_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::thermal::{Exchange, FacetInputs, Forcing, SlabProperties, SolveOptions};

    fn inputs(lai: f64, r_st: f64, r_ss: f64) -> TwoSourceInputs {
        let h = 1.0;
        TwoSourceInputs {
            air: AirState::from_relative_humidity(300.0, 0.5, 101_325.0).unwrap(),
            wind_speed_m_s: 3.0,
            direct_horizontal_w_m2: 600.0,
            diffuse_horizontal_w_m2: 100.0,
            sky_longwave_w_m2: 380.0,
            cos_zenith: 0.8,
            aerodynamic: Aerodynamic::new(3.5, 3.5, 2.0 / 3.0 * h, 0.123 * h, 0.123 * h).unwrap(),
            canopy_height_m: h,
            leaf_area_index: lai,
            stomatal_resistance_s_m: r_st,
            soil_surface_resistance_s_m: r_ss,
            params: TwoSourceParams {
                clumping_index: 1.0,
                leaf_width_m: 0.04,
                saturation_m3_m3: 0.451,
            },
            solar_absorptivity: 0.8,
            emissivity: 0.97,
            leaf_wet_fraction: 0.0,
            soil_wet_fraction: 0.0,
            stomata: None,
            global_horizontal_w_m2: 700.0,
        }
    }

    /// The source of an open horizontal facet under `inputs`, W m⁻².
    fn open_source(x: &TwoSourceInputs) -> f64 {
        x.solar_absorptivity * (x.direct_horizontal_w_m2 + x.diffuse_horizontal_w_m2)
            + x.emissivity * x.sky_longwave_w_m2
    }

    /// Steady state of leaves over an insulated soil (G = 0): the soil root
    /// of its law by bisection, the leaves by the linearised balance,
    /// repeated about the new temperatures (the reference passes).
    fn steady(x: &TwoSourceInputs) -> (TwoSourceStep, f64) {
        let s = open_source(x);
        let (mut t_c, mut t_s) = (300.0, 300.0);
        for _ in 0..50 {
            let step = TwoSourceStep::new(x, t_c, t_s);
            let law = step.soil_law(s);
            let (mut lo, mut hi) = (200.0, 400.0);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if law.flux(mid) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let ts_new = 0.5 * (lo + hi);
            let tc_new = step.canopy_k(s, ts_new);
            let change = (ts_new - t_s).abs().max((tc_new - t_c).abs());
            t_s = ts_new;
            t_c = tc_new;
            if change < 1e-10 {
                break;
            }
        }
        (TwoSourceStep::new(x, t_c, t_s), t_s)
    }

    /// At the fixed point both sources close their nonlinear balances:
    /// the leaves' Rn_c = H_c + LE_c and the soil's Rn_s − H_s − LE_s = G
    /// (0 here), to 1e-6 W m⁻², and H + LE = Rn − G.
    #[test]
    fn steady_two_source_closes_both_balances() {
        let x = inputs(3.0, 60.0, 260.0);
        let (step, t_s) = steady(&x);
        let f = step.fluxes(open_source(&x), t_s);
        assert!(f.canopy_residual_w_m2().abs() < 1e-6, "{f:?}");
        assert!(f.ground_w_m2.abs() < 1e-6, "{f:?}");
        let total = f.net_radiation_w_m2() - f.sensible_w_m2() - f.latent_w_m2() - f.ground_w_m2;
        assert!(total.abs() < 1e-6, "{total}");
        // A transpiring canopy over warmer soil: the leaves are cooler.
        assert!(f.canopy_k < f.soil_k, "{f:?}");
        assert!(f.latent_canopy_w_m2 > f.latent_soil_w_m2, "{f:?}");
    }

    /// Without leaves the network is the soil alone, in series with r_a:
    /// `q = S − g_a g_s/(g_a + g_s)(T − T_a) − εσT⁴ − w_a w_s/(w_a + w_s)(e°(T) − e_a)`,
    /// and the radiometric temperature is the soil's.
    #[test]
    fn no_leaves_is_the_bare_soil_balance() {
        let x = inputs(0.0, 60.0, 260.0);
        let step = TwoSourceStep::new(&x, 305.0, 310.0);
        let [g_a, g_x, g_s, w_a, w_c, w_s] = step.conductances();
        assert_eq!((g_x, w_c), (0.0, 0.0));
        let s = open_source(&x);
        let law = step.soil_law(s);
        for t in [290.0, 300.0, 315.0] {
            let expected = s
                - g_a * g_s / (g_a + g_s) * (t - 300.0)
                - 0.97 * STEFAN_BOLTZMANN_W_M2_K4 * t.powi(4)
                - w_a * w_s / (w_a + w_s) * (es(t) - x.air.vapour_pressure_pa());
            assert!((law.flux(t) - expected).abs() < 1e-9, "{t}");
            assert_eq!(step.radiometric_k(s, t), t);
        }
        // A vanishing canopy tends to it.
        let (a, t_a) = steady(&x);
        let (b, t_b) = steady(&inputs(1e-6, 60.0, 260.0));
        assert!((t_a - t_b).abs() < 1e-3, "{t_a} {t_b}");
        assert!(
            (a.radiometric_k(open_source(&x), t_a) - b.radiometric_k(open_source(&x), t_b)).abs()
                < 1e-3
        );
    }

    /// A dense canopy is the single-source big leaf: all radiation on the
    /// leaves, heat through r_a + r_x and vapour through r_a + r_x + r_st;
    /// its steady temperature is the root of the big leaf's balance to
    /// 0.01 K (the soil under LAI 50 is decoupled but for e^−47 of the
    /// radiation and a soil resistance of ~10⁶ s/m).
    #[test]
    fn dense_canopy_is_the_big_leaf() {
        let x = inputs(50.0, 2.0, 260.0);
        let (step, t_s) = steady(&x);
        let s = open_source(&x);
        let [g_a, g_x, _, w_a, w_c, _] = step.conductances();
        let (g, w) = (g_a * g_x / (g_a + g_x), w_a * w_c / (w_a + w_c));
        let big_leaf = |t: f64| {
            s - g * (t - 300.0)
                - 0.97 * STEFAN_BOLTZMANN_W_M2_K4 * t.powi(4)
                - w * (es(t) - x.air.vapour_pressure_pa())
        };
        let (mut lo, mut hi) = (250.0, 350.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if big_leaf(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let t_rad = step.radiometric_k(s, t_s);
        assert!((t_rad - 0.5 * (lo + hi)).abs() < 0.01, "{t_rad} vs {lo}");
    }

    /// Shut stomata and a dry soil surface: no latent heat at all, the law
    /// of a dry surface (vapour conductance exactly 0).
    #[test]
    fn infinite_resistances_give_the_dry_model() {
        let x = inputs(3.0, f64::INFINITY, f64::INFINITY);
        let (step, t_s) = steady(&x);
        let f = step.fluxes(open_source(&x), t_s);
        assert_eq!(f.latent_canopy_w_m2, 0.0);
        assert_eq!(f.latent_soil_w_m2, 0.0);
        assert_eq!(
            step.soil_law(open_source(&x)).vapour_conductance_w_m2_pa,
            0.0
        );
        assert!(f.canopy_residual_w_m2().abs() < 1e-6);
        // Dry leaves run warmer than transpiring ones.
        let (wet, t_w) = steady(&inputs(3.0, 60.0, 260.0));
        assert!(f.canopy_k > wet.canopy_k(open_source(&x), t_w) + 1.0);
    }

    /// The leaves in balance ([`balanced_canopy_k`]): with every
    /// resistance taken at the returned temperature their nonlinear
    /// balance closes to 1e-6 W/m², dry and fully wet, from guesses 40 K
    /// either side; wet leaves are cooler than dry ones.
    #[test]
    fn balanced_leaves_close_their_balance() {
        let mut found = Vec::new();
        for wet in [0.0, 1.0] {
            let mut x = inputs(3.0, 60.0, 260.0);
            x.leaf_wet_fraction = wet;
            let t_s = 305.0;
            let mut roots = Vec::new();
            for guess in [260.0, 300.0, 340.0] {
                let t_c = balanced_canopy_k(&x, guess, t_s);
                let step = TwoSourceStep::new(&x, t_c, t_s);
                let f = step.fluxes(open_source(&x), t_s);
                assert!((f.canopy_k - t_c).abs() < 1e-6, "{wet} {guess}: {f:?}");
                assert!(
                    f.canopy_residual_w_m2().abs() < 1e-6,
                    "{wet} {guess}: {f:?}"
                );
                roots.push(t_c);
            }
            assert!(
                roots.iter().all(|r| (r - roots[0]).abs() < 1e-6),
                "{roots:?}"
            );
            found.push(roots[0]);
        }
        assert!(
            found[1] < found[0] - 1.0,
            "wet {} dry {}",
            found[1],
            found[0]
        );
    }

    /// A two-source crop solved through a diurnal cycle, dry and with a
    /// 3 mm shower at 08:00 held by leaves and soil ([`wet`]): on the open
    /// reference surface both sources close at every record (the leaves to
    /// 1e-6 W m⁻², the soil's G equal to the slab's front flux), and the
    /// output is the nadir composite of leaves and soil.
    #[test]
    fn two_source_crop_closes_its_balance_every_record() {
        let db = crate::material::stock::stock().unwrap();
        let mut m = db.get("crop").unwrap().clone();
        m.surface_energy.as_mut().unwrap().canopy = crate::material::CanopyModel::TwoSource;
        let props = SlabProperties::from_material(&m).unwrap();
        let times: Vec<f64> = (0..=96).map(|i| i as f64 * 1800.0).collect();
        let mut forcing = Forcing::constant(&times, 298.0, 2.5, 0.0, 0.0, 360.0);
        for (k, t) in times.iter().enumerate() {
            let sun = (std::f64::consts::TAU * (t / 86_400.0 - 0.25))
                .sin()
                .max(0.0);
            forcing.direct_normal_w_m2[k] = 750.0 * sun;
            forcing.diffuse_horizontal_w_m2[k] = 100.0 * sun;
            forcing.global_horizontal_w_m2[k] = 850.0 * sun;
            forcing.air_temperature_k[k] = 296.0 + 5.0 * sun;
        }
        let n = times.len();
        for rain in [false, true] {
            let mut forcing = forcing.clone();
            if rain {
                forcing.precipitation_mm[16] = 3.0;
            }
            let ex = Exchange::new(&props, &forcing).unwrap();
            assert_eq!(ex.two_source.len(), n);
            assert_eq!(ex.two_source.iter().any(|s| s.is_wet()), rain);
            assert!(!ex.two_source[15].is_wet() && ex.two_source[16].is_wet() == rain);
            let sun = vec![1.0f32; n];
            let cos = vec![1.0f32; n];
            let facet = FacetInputs::new(&sun, &cos, 1.0);
            let mut opts = SolveOptions::default();
            opts.spinup.tolerance_k = 0.0;
            let sol = crate::thermal::solve_with(&props, &forcing, &ex, &facet, &opts).unwrap();
            let sources =
                crate::thermal::source_history_with(&props, &forcing, &ex, &facet).unwrap();
            let mut worst: f64 = 0.0;
            for k in 0..n {
                let f = ex.two_source[k].fluxes(sources.front_w_m2[k], sol.soil_temperature_k[k]);
                worst = worst
                    .max(f.canopy_residual_w_m2().abs())
                    .max((f.ground_w_m2 - sol.net_front_flux_w_m2[k]).abs());
                assert_eq!(f.canopy_k, sol.canopy_temperature_k[k]);
                let t4 = sol.surface_temperature_k[k].powi(4);
                assert!(t4 < f.canopy_k.powi(4).max(f.soil_k.powi(4)) + 1e-3);
                assert!(t4 > f.canopy_k.powi(4).min(f.soil_k.powi(4)) - 1e-3);
            }
            assert!(worst < 1e-6, "rain {rain}: largest imbalance {worst} W/m²");
            // The slab's own budget closes as for any surface.
            let e = sol.energy;
            let rel = (e.front_in_j_m2 + e.back_in_j_m2 - e.stored_change_j_m2).abs()
                / e.stored_change_j_m2.abs().max(1e3);
            assert!(rel < 1e-6, "rain {rain}: {e:?}");
        }
    }

    /// The rain stores of a two-source canopy: the leaves hold at most
    /// 0.2·LAI mm and catch the nadir cover's share of the rain, the soil
    /// the rest up to 1 mm; a wet source evaporates through its boundary
    /// layer alone (fully wet leaves with shut stomata still evaporate),
    /// and no rain leaves the network exactly dry.
    #[test]
    fn rain_wets_leaves_and_soil_and_dries() {
        let db = crate::material::stock::stock().unwrap();
        let mut m = db.get("crop").unwrap().clone();
        m.surface_energy.as_mut().unwrap().canopy = crate::material::CanopyModel::TwoSource;
        let props = SlabProperties::from_material(&m).unwrap();
        let times: Vec<f64> = (0..=48).map(|i| i as f64 * 1800.0).collect();
        let mut forcing = Forcing::constant(&times, 293.0, 2.5, 0.0, 0.0, 360.0);
        let surface = props.surface.unwrap();
        let mut xs: Vec<TwoSourceInputs> = (0..times.len())
            .map(|k| {
                inputs_at(&surface, &forcing, k, 0.8, 0.97)
                    .unwrap()
                    .unwrap()
            })
            .collect();
        let t = vec![293.0; times.len()];
        assert!(!wet(&mut xs, &forcing, &t, &t));
        let dry = xs[3];
        forcing.precipitation_mm[2] = 0.2;
        assert!(wet(&mut xs, &forcing, &t, &t));
        assert_eq!(xs[1].leaf_wet_fraction, 0.0);
        // LAI 3: cover 1 − e^−1.5 = 0.777 of 0.2 mm on leaves holding 0.6
        // mm, the rest on 1 mm of soil.
        let cover = 1.0 - (-1.5f64).exp();
        let expect_c = (cover * 0.2 / 0.6f64).powf(2.0 / 3.0);
        let expect_s = ((1.0 - cover) * 0.2f64).powf(2.0 / 3.0);
        assert!((xs[2].leaf_wet_fraction - expect_c).abs() < 1e-12);
        assert!((xs[2].soil_wet_fraction - expect_s).abs() < 1e-12);
        // Drying: the fractions fall and reach 0 within the day.
        assert!(xs[3].leaf_wet_fraction < xs[2].leaf_wet_fraction);
        assert_eq!(xs.last().unwrap().leaf_wet_fraction, 0.0);
        // A wet leaf evaporates more than a dry one; with shut stomata the
        // wet part alone.
        let mut shut = xs[2];
        shut.stomatal_resistance_s_m = f64::INFINITY;
        let step = TwoSourceStep::new(&shut, 295.0, 295.0);
        let (le_c, _) = step.wet_latent_w_m2(295.0, 295.0);
        assert!(le_c > 0.0);
        assert!(
            TwoSourceStep::new(&xs[2], 295.0, 295.0).conductances()[4]
                > TwoSourceStep::new(&dry, 295.0, 295.0).conductances()[4]
        );
        // Heavy rain fills both stores to their capacities.
        forcing.precipitation_mm[2] = 20.0;
        wet(&mut xs, &forcing, &t, &t);
        assert_eq!(xs[2].leaf_wet_fraction, 1.0);
        assert_eq!(xs[2].soil_wet_fraction, 1.0);
    }

    /// A clumping index out of (0, 1] or a negative leaf area index in a
    /// material file: an error naming the file and the field.
    #[test]
    fn bad_two_source_input_names_file_and_field() {
        let file = |extra: &str| {
            format!(
                r#"{{"materials": [{{"id": 1, "name": "field", "specific_heat_j_kg_k": 1220,
                "conductivity_w_m_k": 0.92, "density_kg_m3": 1800, "thickness_m": 0.3,
                "solar_absorptivity": 0.8, "thermal_emissivity": 0.93,
                "surface_energy": {{"kind": "canopy", "canopy_height_m": 1,
                "canopy": "two_source", {extra}}}}}]}}"#
            )
        };
        let path = std::path::Path::new("fields.json");
        for (extra, field) in [
            (r#""leaf_area_index": -1"#, "surface_energy.leaf_area_index"),
            (
                r#""leaf_area_index": 3, "clumping_index": 0"#,
                "surface_energy.clumping_index",
            ),
            (
                r#""leaf_area_index": 3, "clumping_index": 1.5"#,
                "surface_energy.clumping_index",
            ),
        ] {
            let errors = crate::material::db::load_json_str_all(&file(extra), path).unwrap_err();
            let text = errors
                .iter()
                .map(|e| e.to_string())
                .collect::<Vec<_>>()
                .join("; ");
            assert!(
                text.contains("fields.json") && text.contains(field),
                "{extra}: {text}"
            );
        }
        assert!(
            crate::material::db::load_json_str_all(&file(r#""leaf_area_index": 3"#), path).is_ok()
        );
    }
}
