//! Surfaces that evaporate: the turbulent exchange of a facet with the air
//! (sensible and latent heat) and the canopy skin of vegetation.
//!
//! A material with a [`LandSurface`] exchanges heat with the air through the
//! aerodynamic resistance `r_a` (log profile with the surface's roughness,
//! stability-corrected; [`crate::thermal::latent::Aerodynamic`]) instead of
//! a dry surface's convection ([`super::convection`]), and loses latent heat through `r_a + r_s`
//! (Penman–Monteith written at the surface temperature, FAO-56 eq. 3;
//! [`crate::thermal::SurfaceFlux`]). Vegetation adds a **skin**: a canopy
//! layer of small heat capacity `C_c` coupled to the soil column below by a
//! conductance `Λ` — the skin-layer scheme of the ECMWF land surface model
//! (Viterbo & Beljaars 1995, "An improved land surface parameterization
//! scheme in the ECMWF model and its validation", J. Climate 8:2716–2748,
//! doi:10.1175/1520-0442(1995)008<2716:AILSPS>2.0.CO;2; ECMWF IFS
//! Documentation Cy47r3 Part IV §8.3, "The skin layer", where Λ is
//! 10 W m⁻² K⁻¹ for low and 20 for high vegetation and the skin has no heat
//! capacity). The skin's temperature is the canopy's radiative temperature,
//! what a radiometer and the renderer see.
//!
//! # The exchange history
//! `r_a` depends on stability, i.e. on the surface–air temperature
//! difference; within a scene that is a property of the surface layer over
//! the site, not of each facet. irsig takes it from the material's **open
//! reference surface**: a horizontal, unshaded facet of the material under
//! the same weather ([`Exchange::new`] solves it, evaluating the stability of
//! each record at its own surface temperature, to a fixed point by the
//! bounded Wegstein passes of [`ReferencePasses`], to
//! [`REFERENCE_TOLERANCE_K`]; where they stop on their cap instead,
//! [`Exchange::passes`] says so and [`Exchange::warning`] words it). Every facet of the material then shares the
//! per-record coefficients `h_k = ρc_p/r_a,k` and `g_v,k = ρc_p/(γ(r_a,k +
//! r_s,k))`; what differs between facets (sun, shape factor, background) is
//! an additive source, which keeps the linearised scene solve exact to first
//! order. The stomata respond to the site's global shortwave, not to a
//! facet's own shading.
//!
//! Wind below [`MIN_WIND_M_S`] is raised to it: cup anemometers stall near
//! 0.5 m s⁻¹, "calm" reports mean below that, and some turbulent exchange
//! remains under a stable night-time surface layer.
//!
//! # What it owns, takes and gives
//! Owns the per-record exchange coefficients of a material and the skin's
//! parameters. Takes the material's properties and the forcing. Gives
//! [`Exchange`], used by the slab solve's front law. Knows nothing of
//! scenes, facets' geometry or files.

use super::latent::aerodynamic::CanopyKb;
use super::latent::{
    Aerodynamic, AirState, InputError, JarvisStewart, RootZone, SurfaceEnergy, SurfaceResistance,
    WaterStep,
};
use super::two_source::{TwoSourceParams, TwoSourceStep};
use super::{FacetInputs, Forcing, SlabProperties, SolveOptions, convection, mcadams_h_w_m2_k};
use crate::error::{Error, Result};
use crate::material::{CanopyModel, HeatRoughness, Phenology, SurfaceEnergySpec, SurfaceKind};

/// Wind speed floor of the turbulent exchange, m s⁻¹ (module docs).
pub const MIN_WIND_M_S: f64 = 0.5;

/// The canopy layer over the soil (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Skin {
    /// Heat capacity of the canopy layer per unit ground area, J m⁻² K⁻¹
    /// (> 0; leaves hold ≈ 0.5–1 kg water per m² of leaf per mm of
    /// thickness, so a few kJ m⁻² K⁻¹ for crops and grass).
    pub capacity_j_m2_k: f64,
    /// Conductance between the canopy and the soil surface, W m⁻² K⁻¹ (> 0;
    /// ECMWF: 10 low vegetation, 20 high vegetation).
    pub conductance_w_m2_k: f64,
}

/// A surface that exchanges heat and water vapour with the air.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandSurface {
    /// Displacement height d, m.
    pub displacement_height_m: f64,
    /// Roughness length for momentum z_om, m (z_oh = z_om/10, FAO-56).
    pub roughness_length_m: f64,
    /// Height of the wind and air measurement to use instead of the
    /// weather's, m (None: the weather's [`Forcing::wind_height_m`] and
    /// [`Forcing::air_height_m`], each raised to at least 2 m above the
    /// canopy top `d/(2/3)`, where the log profile holds).
    pub measurement_height_m: Option<f64>,
    /// The surface resistance.
    pub resistance: SurfaceResistance,
    /// Volumetric water content of the root zone or top soil, m³ m⁻³.
    pub soil_moisture_m3_m3: f64,
    /// The canopy skin of vegetation (None: the slab's front is the surface).
    pub skin: Option<Skin>,
    /// The canopy whose kB⁻¹ sets z_oh at each record (Su et al. 2001;
    /// None: z_oh = z_om/10).
    pub canopy_kb: Option<CanopyKb>,
    /// A canopy that grows (empty: constant); its dated heights and leaf
    /// area indices replace `canopy_height_m` and the LAI at each record
    /// ([`LandSurface::on`]).
    pub phenology: Phenology,
    /// Leaf area per metre of canopy height, m⁻¹: where the phenology
    /// gives no LAI, the LAI at each record is `min(a·h, LAI)` (the
    /// leaves grow with the height up to the full canopy's; None: the LAI
    /// does not follow the height; [`LandSurface::on`]).
    pub leaf_area_per_height_per_m: Option<f64>,
    /// Canopy height h, m (0 without a canopy).
    pub canopy_height_m: f64,
    /// Whether d and z_om follow the canopy height (FAO-56: d = 2/3 h,
    /// z_om = 0.123 h) rather than a given `roughness_length_m`.
    pub roughness_from_height: bool,
    /// Leaves and soil as two sources ([`super::two_source`]; None: one
    /// big leaf, with or without a skin).
    pub two_source: Option<TwoSourceParams>,
    /// The root-zone water budget that `soil_moisture_m3_m3` starts
    /// ([`RootZone`]; None: θ constant through the run).
    pub root_zone: Option<RootZone>,
}

impl LandSurface {
    /// The surface a material's `surface_energy` block describes (the
    /// defaults of [`SurfaceEnergySpec`]).
    ///
    /// # Errors
    /// [`InputError`] naming the field (as the block spells it).
    pub fn from_spec(spec: &SurfaceEnergySpec) -> std::result::Result<LandSurface, InputError> {
        let z0 = spec.roughness_m();
        let d = spec.displacement_m();
        if let Some(z) = spec.measurement_height_m {
            Aerodynamic::new(z, z, d, z0, 0.1 * z0)?;
        }
        let resistance = match spec.kind {
            SurfaceKind::Canopy => SurfaceResistance::Canopy(JarvisStewart {
                min_stomatal_resistance_s_m: spec.min_stomatal_resistance_s_m,
                max_stomatal_resistance_s_m: spec.max_stomatal_resistance_s_m,
                leaf_area_index: spec.leaf_area_index,
                shortwave_limit_w_m2: spec.shortwave_limit(),
                vpd_sensitivity_per_pa: spec.vpd_sensitivity_per_pa,
                optimum_temperature_k: 298.0,
                temperature_sensitivity_per_k2: 0.0016,
                wilting_point_m3_m3: spec.wilting_point_m3_m3,
                field_capacity_m3_m3: spec.field_capacity_m3_m3,
            }),
            SurfaceKind::BareSoil => SurfaceResistance::BareSoil,
            SurfaceKind::Water => SurfaceResistance::Open,
        };
        if let SurfaceResistance::Canopy(js) = &resistance {
            js.validate()?;
        }
        let two_source = (spec.canopy == CanopyModel::TwoSource).then(|| TwoSourceParams {
            clumping_index: spec.clumping(),
            leaf_width_m: spec.leaf_width(),
            saturation_m3_m3: spec.saturation(),
        });
        let skin = (spec.has_skin() && two_source.is_none()).then(|| Skin {
            capacity_j_m2_k: spec.canopy_capacity(),
            conductance_w_m2_k: spec.skin_conductance(),
        });
        let canopy_kb = (spec.heat_roughness == HeatRoughness::Su2001).then(|| CanopyKb {
            leaf_area_index: if spec.kind == SurfaceKind::Canopy {
                spec.leaf_area_index
            } else {
                0.0
            },
            canopy_height_m: spec.canopy_height_m.unwrap_or(0.0),
            leaf_width_m: spec.leaf_width(),
        });
        let root_zone = match spec.root_zone_depth_m {
            Some(d) => {
                let zone = RootZone::new(d, 0.0, spec.field_capacity_m3_m3, spec.saturation())?
                    .with_texture(spec.texture());
                Some(match spec.water_table_depth_m {
                    Some(z) => zone.with_water_table(z, spec.texture())?,
                    None => zone,
                })
            }
            None => None,
        };
        Ok(LandSurface {
            root_zone,
            two_source,
            canopy_kb,
            phenology: spec.phenology,
            leaf_area_per_height_per_m: spec
                .leaf_area_per_height_per_m
                .filter(|_| spec.kind == SurfaceKind::Canopy),
            canopy_height_m: spec.canopy_height_m.unwrap_or(0.0),
            roughness_from_height: spec.kind == SurfaceKind::Canopy
                && spec.roughness_length_m.is_none(),
            displacement_height_m: d,
            roughness_length_m: z0,
            measurement_height_m: spec.measurement_height_m,
            resistance,
            soil_moisture_m3_m3: spec.soil_moisture_m3_m3,
            skin,
        })
    }

    /// The surface's turbulent-exchange parameters under a weather measured
    /// at `wind_height_m` and `air_height_m` (field docs of
    /// [`LandSurface::measurement_height_m`]).
    ///
    /// # Errors
    /// [`InputError`] naming the field when the log profile is undefined.
    pub fn energy(
        &self,
        wind_height_m: f64,
        air_height_m: f64,
    ) -> std::result::Result<SurfaceEnergy, InputError> {
        let d = self.displacement_height_m;
        let z0 = self.roughness_length_m;
        let (zw, za) = self.heights(wind_height_m, air_height_m);
        let aero = Aerodynamic::new(zw, za, d, z0, 0.1 * z0)?;
        let e = SurfaceEnergy::new(aero, self.resistance, self.soil_moisture_m3_m3)?;
        match self.canopy_kb {
            Some(c) => e.with_canopy_kb(c),
            None => Ok(e),
        }
    }

    /// The heights of wind and air (m) under a weather measured at
    /// `wind_height_m` and `air_height_m` (field docs of
    /// [`LandSurface::measurement_height_m`]).
    pub fn heights(&self, wind_height_m: f64, air_height_m: f64) -> (f64, f64) {
        let floor = 1.5 * self.displacement_height_m + 2.0;
        match self.measurement_height_m {
            Some(z) => (z, z),
            None => (wind_height_m.max(floor), air_height_m.max(floor)),
        }
    }

    /// The surface at `unix_s` (seconds since 1970-01-01 UTC): with its
    /// phenology's height and leaf area index then (itself without one).
    /// The height sets d = 2/3 h and z_om = 0.123 h (FAO-56) unless the
    /// material gives its roughness; the LAI sets the stomatal resistance
    /// `r_s,min/LAI` and kB⁻¹. Where the phenology gives no LAI and the
    /// surface has a leaf area per height `a`, the LAI is `min(a·h, LAI)`.
    pub fn on(&self, unix_s: f64) -> LandSurface {
        if !self.grows() {
            return *self;
        }
        let lai0 = match self.resistance {
            SurfaceResistance::Canopy(js) => js.leaf_area_index,
            _ => 0.0,
        };
        let (h, mut lai) = self.phenology.at(unix_s, self.canopy_height_m, lai0);
        if let Some(a) = self.leaf_area_per_height_per_m
            && !self.phenology.gives_leaf_area()
        {
            lai = (a * h).min(lai0);
        }
        let mut s = *self;
        s.canopy_height_m = h;
        if self.roughness_from_height {
            s.displacement_height_m = 2.0 / 3.0 * h;
            s.roughness_length_m = 0.123 * h;
        }
        if let SurfaceResistance::Canopy(js) = &mut s.resistance {
            js.leaf_area_index = lai;
        }
        if let Some(c) = &mut s.canopy_kb {
            c.leaf_area_index = lai;
            c.canopy_height_m = h;
        }
        s
    }

    /// Whether the canopy changes through the run: a phenology, or leaves
    /// that follow the height ([`LandSurface::on`]).
    pub fn grows(&self) -> bool {
        !self.phenology.is_empty() || self.leaf_area_per_height_per_m.is_some()
    }

    /// Checks the skin; errors name the field.
    ///
    /// # Errors
    /// A skin capacity or conductance not finite and positive.
    pub fn validate(&self) -> Result<()> {
        if let Some(s) = self.skin {
            for (field, v) in [
                (
                    "surface_energy.canopy_heat_capacity_j_m2_k",
                    s.capacity_j_m2_k,
                ),
                (
                    "surface_energy.skin_conductance_w_m2_k",
                    s.conductance_w_m2_k,
                ),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(Error::invalid(field, format!("{v}: expected > 0")));
                }
            }
        }
        Ok(())
    }

    /// The exchange at record `k` of `forcing` with the surface at
    /// `surface_k` (K): (sensible coefficient ρc_p/r_a in W m⁻² K⁻¹, vapour
    /// conductance in W m⁻² Pa⁻¹).
    fn exchange_at(
        energy: &SurfaceEnergy,
        forcing: &Forcing,
        k: usize,
        surface_k: f64,
    ) -> Result<(f64, f64)> {
        let air = AirState::new(
            forcing.air_temperature_k[k],
            forcing.vapour_pressure_pa[k],
            forcing.pressure_pa[k],
        )
        .map_err(|e| Error::invalid(format!("records[{k}].{}", e.field()), e.to_string()))?;
        let wind = forcing.wind_speed_m_s[k].max(MIN_WIND_M_S);
        let x = energy
            .exchange_at(air, wind, forcing.global_horizontal_w_m2[k], surface_k)
            .map_err(|e| Error::invalid(format!("records[{k}].{}", e.field()), e.to_string()))?;
        Ok((
            x.sensible_coefficient_w_m2_k(),
            x.vapour_conductance_w_m2_pa(),
        ))
    }
}

/// Rain held on a surface (puddles and films on pavements and roofs, water
/// intercepted by leaves) that evaporates without stomatal or soil
/// resistance — the interception reservoir of Deardorff (1978), "Efficient
/// prediction of ground surface temperature and moisture", J. Geophys. Res.
/// 83(C4):1889–1903, doi:10.1029/JC083iC04p01889, as in Noilhan & Planton
/// (1989) §2c:
///
/// - the store `W` (mm) fills with the rain of each record up to its
///   capacity `W_max` (the rest runs off) and empties by evaporation;
/// - a fraction `δ = (W/W_max)^(2/3)` of the surface is wet and evaporates
///   through the aerodynamic resistance alone: the vapour conductance
///   becomes `(1 − δ)·g_v + δ·ρc_p/(γ r_a) = (1 − δ)·g_v + δ·h/γ`;
/// - the store loses `δ·(h/γ)·max(e°(T_s) − e_a, 0)/λ` (kg m⁻² s⁻¹ = mm s⁻¹)
///   over the interval after each record, at the open reference surface's
///   temperature.
///
/// Capacities: leaves `0.2·LAI` mm (Noilhan & Planton 1989, after Dickinson
/// 1984); bare soil and water 1 mm (water: no effect, it is open already);
/// dry materials 1 mm (depression storage of impervious surfaces, 1.3–2.5 mm
/// in the EPA SWMM 5 Reference Manual Vol. I (Rossman & Huber 2016) Table
/// 3-5; roofs less). With no rain the store stays empty and the exchange is
/// exactly the dry one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WetStore {
    /// Capacity `W_max`, mm.
    pub capacity_mm: f64,
}

impl WetStore {
    /// The store of a material (capacities in the type docs).
    pub fn of(props: &SlabProperties) -> WetStore {
        let capacity_mm = match props.surface.map(|s| s.resistance) {
            Some(SurfaceResistance::Canopy(js)) => (0.2 * js.leaf_area_index).max(0.05),
            _ => 1.0,
        };
        WetStore { capacity_mm }
    }

    /// Wet the exchange `ex` of a surface at `surface_k` under `forcing`'s
    /// rain; returns the wet fraction δ of each record.
    ///
    /// # Errors
    /// Pressure out of the psychrometric range at a record (naming it).
    pub fn wet(&self, forcing: &Forcing, surface_k: &[f64], ex: &mut Exchange) -> Result<Vec<f64>> {
        let n = forcing.len();
        let mut store = 0.0f64;
        let mut wet = Vec::with_capacity(n);
        for (k, &t_surface) in surface_k.iter().enumerate().take(n) {
            let (delta, _overflow) = self.record(
                &mut store,
                forcing,
                k,
                t_surface,
                ex.sensible_w_m2_k[k],
                &mut ex.vapour_conductance_w_m2_pa[k],
            )?;
            wet.push(delta);
        }
        Ok(wet)
    }

    /// One record of [`WetStore::wet`]: fills `store` (mm) with record
    /// `k`'s rain, wets the vapour conductance `g` of the record
    /// (sensible coefficient `h`), and empties the store by the evaporation
    /// of the interval after the record at the surface's `t_surface` (K).
    /// Returns the wet fraction δ and the rain the full store did not hold
    /// (mm), which reaches the soil.
    fn record(
        &self,
        store: &mut f64,
        forcing: &Forcing,
        k: usize,
        t_surface: f64,
        h: f64,
        g: &mut f64,
    ) -> Result<(f64, f64)> {
        use super::latent::psychrometrics::{
            latent_heat_of_vaporisation_j_kg, psychrometric_constant_pa_k,
            saturation_vapour_pressure_pa,
        };
        let n = forcing.len();
        let filled = *store + forcing.precipitation_mm[k].max(0.0);
        *store = filled.min(self.capacity_mm);
        let overflow = filled - *store;
        let delta = (*store / self.capacity_mm).powf(2.0 / 3.0);
        let t_air = forcing.air_temperature_k[k];
        let lambda = latent_heat_of_vaporisation_j_kg(t_air);
        let p = forcing.pressure_pa[k];
        if !(p.is_finite() && p > 0.0) {
            return Err(Error::invalid(
                format!("records[{k}].pressure_pa"),
                format!("{p}: expected a positive pressure"),
            ));
        }
        let gamma = psychrometric_constant_pa_k(p, lambda);
        let g_open = h / gamma;
        *g = (1.0 - delta) * *g + delta * g_open;
        if k + 1 < n && *store > 0.0 {
            let dt = forcing.times_s[k + 1] - forcing.times_s[k];
            let deficit =
                (saturation_vapour_pressure_pa(t_surface) - forcing.vapour_pressure_pa[k]).max(0.0);
            let evaporation_mm = delta * g_open * deficit / lambda * dt;
            *store = (*store - evaporation_mm).max(0.0);
        }
        Ok((delta, overflow))
    }
}

/// Bounded Wegstein iteration, record by record, of an open reference
/// surface's passes `x ← f(x)` (Wegstein 1958, "Accelerating convergence of
/// iterative processes", Commun. ACM 1(6):9–13): with `s` the secant slope
/// of `f` at a record from its last two passes, the record's reference
/// moves by `ω (f(x) − x)`, `ω = 1/(1 − s)` (the secant root of
/// `f(x) − x`), bounded to [1/64, 1] (damping only; ω = 1 where `s ≥ 1` or
/// on the first pass). A record whose pass-to-pass map has a local gain
/// `s < −1` (it turns back every pass: the soil's free convection, the rain
/// stores, stability flipping at dusk) then contracts, where the plain
/// iteration `ω = 1` would cycle; for a scalar linear map one step lands on
/// its fixed point.
#[derive(Debug, Default)]
struct Wegstein {
    /// The last pass's reference and its image, per record.
    last: Vec<(f64, f64)>,
}

impl Wegstein {
    /// Moves `x` towards its image `f` (one per record); returns the
    /// largest `|f − x|`, K.
    fn step(&mut self, x: &mut [f64], f: &[f64]) -> f64 {
        let mut change = 0.0f64;
        let first = self.last.len() != x.len();
        if first {
            self.last = vec![(f64::NAN, f64::NAN); x.len()];
        }
        for ((x, &f), last) in x.iter_mut().zip(f).zip(&mut self.last) {
            let residual = f - *x;
            change = change.max(residual.abs());
            let dx = *x - last.0;
            let omega = if dx.abs() > 1e-12 {
                let s = (f - last.1) / dx;
                if s < 1.0 {
                    (1.0 / (1.0 - s)).clamp(1.0 / 64.0, 1.0)
                } else {
                    1.0
                }
            } else {
                1.0
            };
            *last = (*x, f);
            *x += omega * residual;
        }
        change
    }
}

/// Tolerance of the open reference surface's passes, K: they stop when no
/// record's reference temperature changes by more in a pass that updates
/// the exchange ([`ReferencePasses`]).
pub const REFERENCE_TOLERANCE_K: f64 = 1e-4;

/// Most passes of the open reference surface ([`ReferencePasses`]).
pub const REFERENCE_PASSES: usize = 32;

/// When the open reference surface's passes stop ([`ReferencePasses`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassLimits {
    /// Settled when a pass changes no record's reference by more, K (> 0).
    pub tolerance_k: f64,
    /// Most passes (solves of the reference surface), ≥ 1.
    pub cap: usize,
}

impl PassLimits {
    /// A positive finite tolerance and a cap of at least one pass.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming `passes.tolerance_k` or `passes.cap`.
    pub fn validate(&self) -> Result<()> {
        if !(self.tolerance_k.is_finite() && self.tolerance_k > 0.0) {
            return Err(Error::invalid(
                "passes.tolerance_k",
                format!("{}: expected > 0", self.tolerance_k),
            ));
        }
        if self.cap == 0 {
            return Err(Error::invalid("passes.cap", "0: expected at least 1"));
        }
        Ok(())
    }
}

impl Default for PassLimits {
    /// [`REFERENCE_TOLERANCE_K`] and [`REFERENCE_PASSES`].
    fn default() -> Self {
        PassLimits {
            tolerance_k: REFERENCE_TOLERANCE_K,
            cap: REFERENCE_PASSES,
        }
    }
}

/// How the open reference surface's passes of an [`Exchange`] ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Passes {
    /// Solves of the reference surface run.
    pub count: usize,
    /// Largest change of a record's reference temperature (a two-source
    /// canopy: its leaves' or soil's) in the last pass that updated the
    /// exchange and the rain stores, K.
    pub residual_k: f64,
    /// Whether `residual_k` fell below the tolerance; false: the passes
    /// stopped on their cap, and the exchange is that of a reference not
    /// yet at its fixed point ([`Exchange::warning`]).
    pub settled: bool,
    /// The tolerance they ran to, K.
    pub tolerance_k: f64,
}

/// The one driver of the open reference surface's passes, single source
/// ([`Exchange::facing`]) and two sources ([`Exchange::two_source`]): each
/// pass solves the reference surface under the current exchange (image
/// `f(x)` of the reference temperatures `x`, one per record), then moves
/// each record's reference by a bounded Wegstein step ([`Wegstein`]) and
/// remakes the exchange there. The passes stop when a pass changes no
/// record by more than [`PassLimits::tolerance_k`] (settled) or on
/// [`PassLimits::cap`] (unsettled), and say which ([`Passes`]): never
/// silently.
#[derive(Debug)]
pub struct ReferencePasses {
    limits: PassLimits,
    wegstein: Wegstein,
    count: usize,
    residual_k: f64,
}

impl ReferencePasses {
    /// A driver with `limits`.
    pub fn new(limits: PassLimits) -> ReferencePasses {
        ReferencePasses {
            limits,
            wegstein: Wegstein::default(),
            count: 0,
            residual_k: f64::INFINITY,
        }
    }

    /// One pass: `x` (the references, K) towards its image `f`; returns
    /// whether to stop (settled, or the cap reached). `x` moves in either
    /// case (by at most the tolerance when settled).
    pub fn step(&mut self, x: &mut [f64], f: &[f64]) -> bool {
        let residual = self.wegstein.step(x, f);
        self.record(residual)
    }

    /// Moves `x` towards its image `f` by the bounded Wegstein step
    /// without counting a pass (a two-source canopy counts its passes'
    /// change of leaves and soil together, [`ReferencePasses::record`]).
    pub fn advance(&mut self, x: &mut [f64], f: &[f64]) {
        self.wegstein.step(x, f);
    }

    /// Counts a pass whose largest change was `residual_k` (K) without
    /// moving a reference (a two-source canopy's held passes move it
    /// themselves); returns whether to stop, as [`ReferencePasses::step`].
    pub fn record(&mut self, residual_k: f64) -> bool {
        self.count += 1;
        self.residual_k = residual_k;
        self.settled() || self.count >= self.limits.cap
    }

    /// Counts a pass that does not update the exchange (the residual
    /// stays the last updating pass's).
    pub fn count_held(&mut self) {
        self.count += 1;
    }

    /// Whether the last recorded pass changed no record by more than the
    /// tolerance.
    pub fn settled(&self) -> bool {
        self.residual_k < self.limits.tolerance_k
    }

    /// Passes run so far.
    pub fn count(&self) -> usize {
        self.count
    }

    /// How the passes ended.
    pub fn report(&self) -> Passes {
        Passes {
            count: self.count,
            residual_k: self.residual_k,
            settled: self.settled(),
            tolerance_k: self.limits.tolerance_k,
        }
    }
}

/// The per-record exchange coefficients of one material under one forcing
/// (module docs), shared by every facet of the material.
#[derive(Debug, Clone, PartialEq)]
pub struct Exchange {
    /// Convective (sensible-heat) coefficient, W m⁻² K⁻¹.
    pub sensible_w_m2_k: Vec<f64>,
    /// Vapour conductance `ρc_p/(γ(r_a + r_s))`, W m⁻² Pa⁻¹ (0: dry).
    pub vapour_conductance_w_m2_pa: Vec<f64>,
    /// A two-source canopy's model at each record, linearised about the
    /// open reference surface ([`super::two_source`]; empty otherwise).
    /// With it the two vectors above are 0: a facet's source is its
    /// absorbed incoming radiation, and the soil's law comes from here.
    pub two_source: Vec<TwoSourceStep>,
    /// The root-zone water content at each record, m³ m⁻³, where the
    /// surface has a [`RootZone`] (empty otherwise: θ constant).
    pub soil_moisture_m3_m3: Vec<f64>,
    /// The root zone's water over the interval after each record
    /// ([`WaterStep`]; one fewer than the records; empty without a root
    /// zone).
    pub soil_water: Vec<WaterStep>,
    /// How the open reference surface's passes ended ([`ReferencePasses`];
    /// None where no reference was solved: a dry McAdams material, whose
    /// coefficient is closed-form, or an exchange made at given
    /// temperatures).
    pub passes: Option<Passes>,
}

impl Exchange {
    /// A dry surface with McAdams' coefficient `5.7 + 3.8u`
    /// ([`mcadams_h_w_m2_k`]), the model of every material without a
    /// surface-energy block.
    pub fn mcadams(forcing: &Forcing) -> Exchange {
        Exchange {
            sensible_w_m2_k: forcing
                .wind_speed_m_s
                .iter()
                .map(|&u| mcadams_h_w_m2_k(u))
                .collect(),
            vapour_conductance_w_m2_pa: vec![0.0; forcing.len()],
            two_source: Vec::new(),
            soil_moisture_m3_m3: Vec::new(),
            soil_water: Vec::new(),
            passes: None,
        }
    }

    /// The exchange of `props` under `forcing` for a horizontal surface
    /// facing up ([`Exchange::facing`] with `normal_z = 1`).
    ///
    /// # Errors
    /// As [`Exchange::facing`].
    pub fn new(props: &SlabProperties, forcing: &Forcing) -> Result<Exchange> {
        Exchange::facing(props, forcing, 1.0)
    }

    /// The exchange of `props` under `forcing` (module docs) for facets
    /// whose normal has z-component `normal_z`: McAdams for a dry McAdams
    /// material (no reference solve); for a dry DOE-2 material
    /// ([`super::convection`]), the fixed point of the natural convection
    /// of the open reference surface of the facets' orientation class
    /// ([`super::convection::orientation_class`]; tilted with the class's
    /// `cos Σ`, unshaded, seeing `(1 + cos Σ)/2` of the sky, the sun at
    /// the mean incidence over all azimuths, no reflected shortwave); for
    /// a [`LandSurface`] (whatever `normal_z`), the fixed point of the
    /// horizontal open reference surface's stability and rain store. The
    /// passes run to [`REFERENCE_TOLERANCE_K`], at most
    /// [`REFERENCE_PASSES`] ([`ReferencePasses`]; how they ended in
    /// [`Exchange::passes`]). Deterministic: the spin-up days of the first
    /// pass for every later one, fixed solver options.
    ///
    /// # Errors
    /// Humidity or pressure of a record outside the physical range the
    /// psychrometrics accept (naming `records[k].field`).
    pub fn facing(props: &SlabProperties, forcing: &Forcing, normal_z: f64) -> Result<Exchange> {
        Exchange::facing_limited(props, forcing, normal_z, PassLimits::default())
    }

    /// [`Exchange::facing`] with the reference passes stopping at `limits`
    /// instead of the default ([`PassLimits::default`]).
    ///
    /// # Errors
    /// As [`Exchange::facing`]; `limits` not a positive tolerance and a
    /// cap ≥ 1 (naming the field).
    pub fn facing_limited(
        props: &SlabProperties,
        forcing: &Forcing,
        normal_z: f64,
        limits: PassLimits,
    ) -> Result<Exchange> {
        limits.validate()?;
        if props.surface.is_some_and(|s| s.two_source.is_some()) {
            return Exchange::two_source(props, forcing, limits);
        }
        let rain = forcing.precipitation_mm.iter().any(|&p| p > 0.0);
        let mcadams = props.convection.model == crate::material::ConvectionModel::Mcadams;
        if props.surface.is_none() && mcadams && !rain {
            return Ok(Exchange::mcadams(forcing));
        }
        let cos_tilt = if props.surface.is_some() {
            1.0
        } else {
            convection::class_cos_tilt(convection::orientation_class(normal_z))
        };
        let n = forcing.len();
        let sun = vec![1.0f32; n];
        let sin_tilt = (1.0 - cos_tilt * cos_tilt).max(0.0).sqrt();
        let cos: Vec<f32> = (0..n)
            .map(|k| {
                let dni = forcing.direct_normal_w_m2[k];
                let direct_h = (forcing.global_horizontal_w_m2[k]
                    - forcing.diffuse_horizontal_w_m2[k])
                    .max(0.0);
                if dni <= 1.0 {
                    return 0.0;
                }
                let sin_h = (direct_h / dni).clamp(0.0, 1.0);
                if sin_tilt == 0.0 {
                    return (cos_tilt * sin_h).max(0.0) as f32;
                }
                // Mean over the azimuths of max(cos i, 0).
                let cos_h = (1.0 - sin_h * sin_h).max(0.0).sqrt();
                let m = 72;
                let sum: f64 = (0..m)
                    .map(|j| {
                        let phi = (j as f64 + 0.5) * std::f64::consts::TAU / m as f64;
                        (cos_tilt * sin_h + sin_tilt * cos_h * phi.cos()).max(0.0)
                    })
                    .sum();
                (sum / m as f64) as f32
            })
            .collect();
        let inputs = FacetInputs::new(&sun, &cos, 0.5 * (1.0 + cos_tilt));
        let mut opts = SolveOptions::default();
        let mut surface_k = forcing.air_temperature_k.clone();
        let mut ex = Exchange::at_temperatures_facing(props, forcing, &surface_k, cos_tilt)?;
        let mut passes = ReferencePasses::new(limits);
        loop {
            let p = super::prepare(props, forcing, &inputs, &ex);
            let sol = super::solve_prepared(props, forcing, &p, &opts, None);
            if passes.count() == 0 {
                // The spin-up days of the first pass for every later one:
                // a spin-up that stops on its tolerance may stop a day
                // earlier in one pass than in the next, and the passes
                // would not settle below that tolerance.
                opts.spinup.max_cycles = sol.spinup_cycles;
                opts.spinup.tolerance_k = 0.0;
            }
            let stop = passes.step(&mut surface_k, &sol.surface_temperature_k);
            ex = Exchange::at_temperatures_facing(props, forcing, &surface_k, cos_tilt)?;
            if stop {
                break;
            }
        }
        ex.passes = Some(passes.report());
        Ok(ex)
    }

    /// The exchange of a two-source canopy ([`super::two_source`]): the
    /// model of each record linearised about the open reference surface
    /// (horizontal, unshaded, the whole sky, a fixed three spin-up days),
    /// the reference solved again about its own leaf and soil temperatures
    /// until they change by less than the tolerance of `limits`
    /// ([`ReferencePasses`]), then with the resistances held until they
    /// change by less than 1e-7 K (at most the cap of `limits` passes in
    /// all, the last four held; [`Exchange::passes`]). In each
    /// resistance-updating pass the
    /// leaves are put in balance with the record's wet fractions and
    /// resistances ([`super::two_source::balanced_canopy_k`]) and the soil's
    /// reference moves by a bounded Wegstein step. The weather's
    /// rain wets leaves and soil ([`super::two_source::wet`]), the stores
    /// evolving at each resistance-updating pass's reference temperatures
    /// and held with the resistances. With a root zone ([`RootZone`]) its θ
    /// evolves with the stores ([`super::two_source::water`]): the leaves'
    /// transpiration and the soil's evaporation at each such pass's
    /// reference temperatures dry it, and θ sets the next pass's stomatal
    /// and soil-surface resistances (it starts from the air temperature's
    /// network).
    ///
    /// # Errors
    /// Humidity or pressure of a record out of range (naming it); the
    /// canopy's heights (naming the field).
    pub fn two_source(
        props: &SlabProperties,
        forcing: &Forcing,
        limits: PassLimits,
    ) -> Result<Exchange> {
        use super::two_source;
        limits.validate()?;
        let surface = props
            .surface
            .ok_or_else(|| Error::invalid("surface_energy", "a two-source canopy needs one"))?;
        let n = forcing.len();
        let mut inputs = Vec::with_capacity(n);
        for k in 0..n {
            let x = two_source::inputs_at(
                &surface,
                forcing,
                k,
                props.solar_absorptivity,
                props.thermal_emissivity,
            )?
            .ok_or_else(|| Error::invalid("surface_energy.canopy", "not two_source"))?;
            inputs.push(x);
        }
        let steps = |inputs: &[two_source::TwoSourceInputs], t_c: &[f64], t_s: &[f64]| {
            inputs
                .iter()
                .zip(t_c.iter().zip(t_s))
                .map(|(x, (&c, &s))| TwoSourceStep::new(x, c, s))
                .collect::<Vec<_>>()
        };
        let rain = forcing.precipitation_mm.iter().any(|&p| p > 0.0);
        let sun = vec![1.0f32; n];
        let cos: Vec<f32> = inputs.iter().map(|x| x.cos_zenith as f32).collect();
        let facet = FacetInputs::new(&sun, &cos, 1.0);
        // A fixed number of spin-up days: a spin-up that stops on its
        // tolerance may stop a day earlier in one pass than in the next,
        // and the passes would not converge below that tolerance.
        let mut opts = SolveOptions::default();
        opts.spinup.tolerance_k = 0.0;
        let mut t_c = forcing.air_temperature_k.clone();
        let mut t_s = forcing.air_temperature_k.clone();
        // The root zone's water (with its stores) at the reference
        // temperatures, setting each record's r_st and r_ss from θ.
        let zone = surface.root_zone;
        let theta0 = surface.soil_moisture_m3_m3;
        let water = |inputs: &mut [two_source::TwoSourceInputs], t_c: &[f64], t_s: &[f64]| {
            two_source::water(
                inputs,
                forcing,
                t_c,
                t_s,
                zone.as_ref().map(|z| (z, theta0)),
            )
        };
        let first = zone.is_some().then(|| water(&mut inputs, &t_c, &t_s));
        let mut ex = Exchange {
            sensible_w_m2_k: vec![0.0; n],
            vapour_conductance_w_m2_pa: vec![0.0; n],
            two_source: steps(&inputs, &t_c, &t_s),
            soil_moisture_m3_m3: Vec::new(),
            soil_water: Vec::new(),
            passes: None,
        };
        if let Some(w) = first {
            ex.soil_moisture_m3_m3 = w.soil_moisture_m3_m3;
            ex.soil_water = w.steps;
        }
        // Passes that update the resistances (stability, the soil's free
        // convection) with the linearisation until the reference settles to
        // the tolerance; then Newton passes with the resistances held, which
        // converge quadratically, so the reference closes the leaves'
        // balance.
        let mut hold = false;
        let mut passes = ReferencePasses::new(limits);
        while passes.count() < limits.cap {
            let p = super::prepare(props, forcing, &facet, &ex);
            let sol = super::solve_prepared(props, forcing, &p, &opts, None);
            let change = sol
                .soil_temperature_k
                .iter()
                .zip(&t_s)
                .chain(sol.canopy_temperature_k.iter().zip(&t_c))
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            if hold {
                passes.count_held();
                if change < 1e-7 {
                    break;
                }
                t_s = sol.soil_temperature_k;
            } else {
                passes.record(change);
                hold = passes.settled() || passes.count() + 3 >= limits.cap;
                if hold {
                    t_s = sol.soil_temperature_k;
                } else {
                    // Each record's soil reference by a bounded Wegstein
                    // step.
                    passes.advance(&mut t_s, &sol.soil_temperature_k);
                }
            }
            t_c = sol.canopy_temperature_k;
            ex.two_source = if hold {
                ex.two_source
                    .iter()
                    .zip(t_c.iter().zip(&t_s))
                    .map(|(x, (&c, &s))| x.relinearised(c, s))
                    .collect()
            } else {
                if zone.is_some() {
                    let w = water(&mut inputs, &t_c, &t_s);
                    ex.soil_moisture_m3_m3 = w.soil_moisture_m3_m3;
                    ex.soil_water = w.steps;
                } else if rain {
                    two_source::wet(&mut inputs, forcing, &t_c, &t_s);
                }
                // The leaves in balance with the new wet fractions and
                // resistances, the soil at the reference: the point of the
                // next linearisation.
                for (k, x) in inputs.iter().enumerate() {
                    t_c[k] = two_source::balanced_canopy_k(x, t_c[k], t_s[k]);
                }
                steps(&inputs, &t_c, &t_s)
            };
        }
        ex.passes = Some(passes.report());
        Ok(ex)
    }

    /// [`Exchange::at_temperatures_facing`] of a horizontal surface facing
    /// up.
    ///
    /// # Errors
    /// As [`Exchange::at_temperatures_facing`].
    pub fn at_temperatures(
        props: &SlabProperties,
        forcing: &Forcing,
        surface_k: &[f64],
    ) -> Result<Exchange> {
        Exchange::at_temperatures_facing(props, forcing, surface_k, 1.0)
    }

    /// The exchange of `props` with the surface at `surface_k[k]` (K) at
    /// each record, a dry one tilted with `cos_tilt` (`cos Σ`, 1 facing
    /// up), wetted by the forcing's rain ([`WetStore`]).
    ///
    /// # Errors
    /// Humidity or pressure of a record out of range (naming it).
    pub fn at_temperatures_facing(
        props: &SlabProperties,
        forcing: &Forcing,
        surface_k: &[f64],
        cos_tilt: f64,
    ) -> Result<Exchange> {
        let n = forcing.len();
        let mut ex = match &props.surface {
            None => Exchange {
                sensible_w_m2_k: (0..n)
                    .map(|k| {
                        convection::coefficient_w_m2_k(
                            &props.convection,
                            surface_k[k] - forcing.air_temperature_k[k],
                            cos_tilt,
                            forcing.wind_speed_m_s[k],
                        )
                    })
                    .collect(),
                vapour_conductance_w_m2_pa: vec![0.0; n],
                two_source: Vec::new(),
                soil_moisture_m3_m3: Vec::new(),
                soil_water: Vec::new(),
                passes: None,
            },
            Some(surface) if surface.root_zone.is_some() => {
                return Exchange::with_root_zone(props, forcing, surface, surface_k);
            }
            Some(surface) => {
                let energy_of = |s: &LandSurface| {
                    s.energy(forcing.wind_height_m, forcing.air_height_m)
                        .map_err(|e| {
                            Error::invalid(format!("surface_energy.{}", e.field()), e.to_string())
                        })
                };
                let constant = energy_of(surface)?;
                let mut sensible = Vec::with_capacity(n);
                let mut vapour = Vec::with_capacity(n);
                for (k, &t) in surface_k.iter().enumerate().take(n) {
                    let (h, g) = if !surface.grows() {
                        LandSurface::exchange_at(&constant, forcing, k, t)?
                    } else {
                        let now = surface.on(forcing.start_unix_s + forcing.times_s[k]);
                        LandSurface::exchange_at(&energy_of(&now)?, forcing, k, t)?
                    };
                    sensible.push(h);
                    vapour.push(g);
                }
                Exchange {
                    sensible_w_m2_k: sensible,
                    vapour_conductance_w_m2_pa: vapour,
                    two_source: Vec::new(),
                    soil_moisture_m3_m3: Vec::new(),
                    soil_water: Vec::new(),
                    passes: None,
                }
            }
        };
        if forcing.precipitation_mm.iter().any(|&p| p > 0.0) {
            WetStore::of(props).wet(forcing, surface_k, &mut ex)?;
        }
        Ok(ex)
    }

    /// The exchange of a surface with a root-zone water budget
    /// ([`RootZone`]) at the surface temperatures `surface_k`: record by
    /// record, the exchange at the record's θ, wetted by the rain store
    /// ([`WetStore`]), whose overflow infiltrates; then θ over the interval
    /// after the record from that rain and the dry part's evaporation and
    /// transpiration `E = (1 − δ)·g_v·(e°(T_s) − e_a)/λ` (kg m⁻² s⁻¹; λ of
    /// [`super::latent::psychrometrics::latent_heat_of_vaporisation_j_kg`]
    /// at the air temperature, as the store's), the same step's latent
    /// flux the front law applies.
    fn with_root_zone(
        props: &SlabProperties,
        forcing: &Forcing,
        surface: &LandSurface,
        surface_k: &[f64],
    ) -> Result<Exchange> {
        use super::latent::psychrometrics::{
            latent_heat_of_vaporisation_j_kg, saturation_vapour_pressure_pa,
        };
        let Some(zone) = surface.root_zone else {
            return Err(Error::invalid("surface_energy.root_zone_depth_m", "none"));
        };
        let n = forcing.len();
        let store_model = WetStore::of(props);
        let mut store = 0.0f64;
        let mut theta = surface.soil_moisture_m3_m3;
        let mut sensible = Vec::with_capacity(n);
        let mut vapour = Vec::with_capacity(n);
        let mut thetas = Vec::with_capacity(n);
        let mut water = Vec::with_capacity(n.saturating_sub(1));
        for (k, &t) in surface_k.iter().enumerate().take(n) {
            let mut now = surface.on(forcing.start_unix_s + forcing.times_s[k]);
            now.soil_moisture_m3_m3 = theta;
            let energy = now
                .energy(forcing.wind_height_m, forcing.air_height_m)
                .map_err(|e| {
                    Error::invalid(format!("surface_energy.{}", e.field()), e.to_string())
                })?;
            let (h, g_dry) = LandSurface::exchange_at(&energy, forcing, k, t)?;
            let mut g = g_dry;
            let (delta, infiltration_mm) =
                store_model.record(&mut store, forcing, k, t, h, &mut g)?;
            sensible.push(h);
            vapour.push(g);
            thetas.push(theta);
            if k + 1 < n {
                let dt = forcing.times_s[k + 1] - forcing.times_s[k];
                let lambda = latent_heat_of_vaporisation_j_kg(forcing.air_temperature_k[k]);
                let le_dry = (1.0 - delta)
                    * g_dry
                    * (saturation_vapour_pressure_pa(t) - forcing.vapour_pressure_pa[k]);
                let step = zone.step(theta, infiltration_mm, le_dry / lambda * dt, dt);
                theta = step.theta_m3_m3;
                water.push(step);
            }
        }
        Ok(Exchange {
            sensible_w_m2_k: sensible,
            vapour_conductance_w_m2_pa: vapour,
            two_source: Vec::new(),
            soil_moisture_m3_m3: thetas,
            soil_water: water,
            passes: None,
        })
    }

    /// Error unless there is one entry per record.
    pub(crate) fn check_len(&self, n: usize) -> Result<()> {
        if self.sensible_w_m2_k.len() != n
            || self.vapour_conductance_w_m2_pa.len() != n
            || !(self.two_source.is_empty() || self.two_source.len() == n)
        {
            return Err(Error::invalid(
                "exchange",
                format!(
                    "has {} records but the forcing has {n}",
                    self.sensible_w_m2_k.len()
                ),
            ));
        }
        Ok(())
    }

    /// Whether any record evaporates.
    pub fn has_latent(&self) -> bool {
        self.vapour_conductance_w_m2_pa.iter().any(|&g| g > 0.0)
    }

    /// Where the open reference surface's passes stopped on their cap
    /// ([`Exchange::passes`]): a message naming `material`, the residual
    /// and the passes, for a `warning:` line (None where they settled or
    /// no reference was solved).
    pub fn warning(&self, material: &str) -> Option<String> {
        self.passes.and_then(|p| p.warning(material))
    }
}

impl Passes {
    /// Where the passes stopped on their cap: a message naming `material`,
    /// the residual and the passes, for a `warning:` line (None where they
    /// settled).
    pub fn warning(&self, material: &str) -> Option<String> {
        if self.settled {
            return None;
        }
        Some(format!(
            "material {material}: the exchange's reference passes did not settle: the last \
             of {} passes changed the reference surface by {:.2e} K (tolerance {:.0e} K); \
             its exchange with the air is that of an unsettled reference",
            self.count, self.residual_k, self.tolerance_k
        ))
    }
}
