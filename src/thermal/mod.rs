//! The THERM-style thermal model: the temperature of each facet through a
//! weather history, from a 1-D transient slab model.
//!
//! DIRSIG computes facet temperatures with THERM, a 1-D slab model driven
//! by the weather history and by ray-traced per-facet inputs (solar history,
//! sky shape factor, background); see Schott, *Remote Sensing: The Image
//! Chain Approach*, 2nd ed., Oxford UP, 2007 (DIRSIG chapter) and the DIRSIG
//! User Manual ("THERM temperature solver"). irsig's model has the same
//! inputs and the same front-surface energy balance ([`balance`]) with a
//! modern numerical core ([`conduction`]: finite volumes through the
//! thickness, L-stable second-order TR-BDF2 time stepping, Newton on the
//! radiative boundary).
//!
//! # How the types fit together
//! - [`SlabProperties`]: one material's thermal properties and its
//!   [`BackBoundary`] (what the back face of the slab touches), built from a
//!   [`Material`] with [`SlabProperties::from_material`].
//! - [`Forcing`]: the weather history shared by all facets (air temperature,
//!   wind, direct/diffuse solar, sky longwave), from
//!   [`WeatherRecord`]s.
//! - [`FacetInputs`]: what the ray tracer computes per facet — sunlit
//!   fraction and cos of the solar incidence per record, the sky shape factor
//!   `F` and the background temperature.
//! - [`solve`]`(props, forcing, inputs, options)` → [`ThermalSolution`]: the
//!   front-surface temperature at every weather record, with convergence and
//!   energy diagnostics. It is a pure function, cheap (tens of µs), and safe
//!   to call from many threads (`rayon`).
//!
//! - [`linear`]: the tangent-linear model — one facet's Green's matrices
//!   `∂T(t)/∂S_k`, from which facets of the same material follow by a
//!   matrix product.
//! - [`scene`]: the scene-wide solve — every facet of a scene, coupled
//!   through their backgrounds, from plain per-facet inputs
//!   ([`scene::SceneInputs`]); fixed-temperature facets bypass the slab
//!   model there.
//!
//! # What it owns, takes and gives
//! Owns the physics of facet temperatures: the surface energy balance, the
//! conduction through the slab, and the scene solve built on them. Takes
//! material properties, weather records and per-facet inputs as plain
//! numbers; gives temperatures. It must not know how the per-facet inputs
//! are traced (rays, tracers, the exposure module), nor sensors, shading
//! or images: the render's pipeline (`irsig::render::scene_thermal`) feeds
//! it.
//!
//! ```
//! use irsig::thermal::{self, BackBoundary, FacetInputs, Forcing, SlabProperties, SolveOptions};
//! // Two records 15 min apart of a warm sunny calm day.
//! let forcing = Forcing::constant(&[0.0, 900.0], 300.0, 1.0, 800.0, 100.0, 350.0);
//! let props = SlabProperties {
//!     conductivity_w_m_k: 1.4, density_kg_m3: 2300.0, specific_heat_j_kg_k: 880.0,
//!     thickness_m: 0.2, solar_absorptivity: 0.7, thermal_emissivity: 0.9,
//!     self_power_w_m2: 0.0, back: BackBoundary::Insulated, surface: None,
//!     convection: Default::default(), layers: thermal::Layers::NONE,
//! };
//! let sun = [1.0f32, 1.0];
//! let cos = [0.8f32, 0.8];
//! let inputs = FacetInputs::new(&sun, &cos, 1.0);
//! let sol = thermal::solve(&props, &forcing, &inputs, &SolveOptions::default()).unwrap();
//! assert!(sol.surface_temperature_k[1] > 300.0); // sunlit concrete warms above the air
//! ```

pub mod balance;
pub mod conduction;
pub mod construction;
pub mod convection;
pub mod latent;
pub mod linear;
pub mod scene;
pub mod surface;
pub mod two_source;
pub mod wind;

use crate::error::{Error, Result};
use crate::material::{ConvectionSpec, Material};
use crate::weather::WeatherRecord;
pub use balance::{INTERIOR_AIR_K, INTERIOR_FILM_W_M2_K, mcadams_h_w_m2_k};
pub use conduction::{
    Boundary, Grid, LayerCells, STEFAN_BOLTZMANN_W_M2_K4, Slab, StepStats, SurfaceFlux,
};
pub use construction::{InteriorAir, Layer, Layers, MAX_LAYERS, SCHEDULE_HOURS};
pub use linear::{
    Linearization, SourceHistory, SourceModel, background_coefficients, linearize, linearize_with,
    source_history, source_history_into, source_history_with,
};
pub use surface::{Exchange, LandSurface, PassLimits, Passes, ReferencePasses, Skin, WetStore};
pub use two_source::{TwoSourceFluxes, TwoSourceStep};

/// Angular frequency of the diurnal cycle, rad/s.
pub const DIURNAL_OMEGA_RAD_S: f64 = 2.0 * std::f64::consts::PI / 86_400.0;

/// What the back face of a slab exchanges heat with.
///
/// | variant      | typical objects                  | back-face flux into the slab                |
/// |--------------|----------------------------------|---------------------------------------------|
/// | `Insulated`  | roads, lawns, soil, insulated roofs (exposed area 0) | 0                        |
/// | `Exposed`    | leaves, fences, vehicle panels (1); walls with a ventilated cavity (0.5) | `a·[h(u)(T_air−T) + ε F_b E_sky + ε(1−F_b)σT_bg⁴ − εσT⁴]` |
/// | `Ground`     | soil and pavements as a deep column | none: the column extends to `depth_m`, held at `T_deep` |
/// | `Interior`   | building walls and roofs         | `h_i (T_interior(t) − T)`                   |
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BackBoundary {
    /// Adiabatic back face: no heat flows through it.
    Insulated,
    /// The back face is (partly) in the open air: a fraction `fraction` of
    /// its area convects to the air with the same `h(u)` as the front and
    /// exchanges longwave with the sky (shape factor `F_b`,
    /// [`FacetInputs::back_shape_factor`]) and the background. It receives
    /// no sunlight.
    Exposed {
        /// Fraction of the back face exchanging heat with the air, (0, 1].
        fraction: f64,
    },
    /// Ground: the slab is a column of the material down to `depth_m` (None:
    /// the larger of the thickness and five diurnal damping depths
    /// `5·√(2κ/ω)`, where the diurnal wave has decayed to e⁻⁵ < 1 %), whose
    /// bottom is held at `deep_temperature_k` (None: the time-mean air
    /// temperature of the history).
    Ground {
        /// Deep-soil temperature, K (None: mean air temperature).
        deep_temperature_k: Option<f64>,
        /// Depth of the column, m (None: automatic, see above).
        depth_m: Option<f64>,
    },
    /// Building envelope: the back face exchanges heat with interior air
    /// through a film coefficient (convection + radiation to the room):
    /// `q = h_i (T_in(t) − T)`, the interior surface resistance
    /// `R_si = 1/h_i` of EN ISO 6946:2017 Table 7 (0.13 m² K/W for walls,
    /// 0.10 heat flow up, 0.17 heat flow down).
    Interior {
        /// Interior air temperature at each record (constant, hourly
        /// schedule or set points against the outdoor air).
        air: InteriorAir,
        /// Interior film coefficient, W m⁻² K⁻¹.
        film_coefficient_w_m2_k: f64,
    },
}

impl BackBoundary {
    /// A building interior at [`INTERIOR_AIR_K`] with the ISO 6946 film
    /// coefficient [`INTERIOR_FILM_W_M2_K`].
    pub const BUILDING: BackBoundary = BackBoundary::Interior {
        air: InteriorAir::Constant(INTERIOR_AIR_K),
        film_coefficient_w_m2_k: INTERIOR_FILM_W_M2_K,
    };

    /// The ground with automatic depth and deep temperature.
    pub const GROUND: BackBoundary = BackBoundary::Ground {
        deep_temperature_k: None,
        depth_m: None,
    };

    /// Both faces fully in the air (thin objects).
    pub const BOTH_FACES: BackBoundary = BackBoundary::Exposed { fraction: 1.0 };

    /// The back boundary for a material's `exposed_area`, following irsig's
    /// reading of THERM's `EXPOSED_AREA` (documented in [`crate::material`]):
    /// the fraction `a = |exposed_area|` of the back face that exchanges heat
    /// with the air. `a = 0` → [`BackBoundary::Insulated`] (heat leaves only
    /// through the front face: pavements, soil, insulated roofs);
    /// `0 < a ≤ 1` → [`BackBoundary::Exposed`] with that fraction. Ground
    /// columns and building interiors are not expressed by `exposed_area`;
    /// callers that know an object is a building or the terrain choose
    /// [`BackBoundary::BUILDING`] / [`BackBoundary::GROUND`] with
    /// [`SlabProperties::with_back`].
    pub fn from_exposed_area(a: f64) -> BackBoundary {
        let a = a.abs().min(1.0);
        if a > 0.0 {
            BackBoundary::Exposed { fraction: a }
        } else {
            BackBoundary::Insulated
        }
    }
}

impl BackBoundary {
    /// The back boundary a file spells ([`crate::material::BackSpec`]); an
    /// interior without a film coefficient gets the wall's,
    /// [`crate::material::construction::INTERIOR_FILM_WALL_W_M2_K`]. The
    /// spec is taken as checked ([`crate::material::BackSpec::problems`]);
    /// [`SlabProperties::validate`] catches what is out of range.
    pub fn from_spec(spec: &crate::material::BackSpec) -> BackBoundary {
        use crate::material::BackSpec;
        match spec {
            BackSpec::Insulated => BackBoundary::Insulated,
            BackSpec::OutdoorAir { fraction } => BackBoundary::Exposed {
                fraction: *fraction,
            },
            BackSpec::Ground {
                deep_temperature_k,
                depth_m,
            } => BackBoundary::Ground {
                deep_temperature_k: *deep_temperature_k,
                depth_m: *depth_m,
            },
            BackSpec::Interior(i) => BackBoundary::Interior {
                air: match (&i.air_temperature_k, &i.schedule_k) {
                    (Some(t), _) => InteriorAir::Constant(*t),
                    (None, Some(h)) => {
                        let mut a = [f64::NAN; SCHEDULE_HOURS];
                        for (x, t) in a.iter_mut().zip(h) {
                            *x = *t;
                        }
                        InteriorAir::Hourly(a)
                    }
                    (None, None) => InteriorAir::SetPoints {
                        heating_k: i.heating_setpoint_k.unwrap_or(f64::NAN),
                        cooling_k: i.cooling_setpoint_k.unwrap_or(f64::NAN),
                    },
                },
                film_coefficient_w_m2_k: i
                    .film_coefficient_w_m2_k
                    .unwrap_or(crate::material::construction::INTERIOR_FILM_WALL_W_M2_K),
            },
        }
    }
}

/// Thermal properties of one slab material, SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlabProperties {
    /// Thermal conductivity `k`, W m⁻¹ K⁻¹.
    pub conductivity_w_m_k: f64,
    /// Mass density `ρ`, kg m⁻³.
    pub density_kg_m3: f64,
    /// Specific heat `c`, J kg⁻¹ K⁻¹.
    pub specific_heat_j_kg_k: f64,
    /// Slab thickness, m.
    pub thickness_m: f64,
    /// Solar (shortwave) absorptivity `α`, 0–1.
    pub solar_absorptivity: f64,
    /// Broadband **hemispherical** thermal emissivity `ε_h`, 0–1: what the
    /// surface balance emits and absorbs longwave with.
    /// [`SlabProperties::from_material`] converts the material's normal
    /// `thermal_emissivity` once
    /// ([`crate::radiometry::emissivity::thermal_hemispherical_emissivity`]).
    pub thermal_emissivity: f64,
    /// Self-generated power `P` delivered at the front surface, W m⁻².
    pub self_power_w_m2: f64,
    /// What the back face touches.
    pub back: BackBoundary,
    /// How the front surface exchanges heat and vapour with the air (None:
    /// dry, convecting as `convection` says; [`surface`]).
    pub surface: Option<LandSurface>,
    /// How the front convects while it is dry and has no `surface`
    /// ([`convection`]; DOE-2 by default, McAdams for DIRSIG parity).
    pub convection: ConvectionSpec,
    /// The construction's layers from the outer face ([`Layers::NONE`]: a
    /// homogeneous slab of the properties above). With layers, the column
    /// is the layers: `conductivity`, `density` and `specific_heat` above
    /// are the outer layer's (for reports) and `thickness_m` is the layers'
    /// total; the optical properties and `surface` are the outer face's.
    pub layers: Layers,
}

impl SlabProperties {
    /// Thermal diffusivity `κ = k/(ρc)`, m² s⁻¹.
    pub fn diffusivity_m2_s(&self) -> f64 {
        self.conductivity_w_m_k / (self.density_kg_m3 * self.specific_heat_j_kg_k)
    }

    /// Diurnal damping depth `√(2κ/ω)`, m (Carslaw & Jaeger §2.6).
    pub fn diurnal_damping_depth_m(&self) -> f64 {
        (2.0 * self.diffusivity_m2_s() / DIURNAL_OMEGA_RAD_S).sqrt()
    }

    /// The slab's finite-volume column at a uniform `initial_k` (K): the
    /// homogeneous slab of [`Slab::new`] without layers, else
    /// [`Slab::layered`] with [`construction::column_cells`].
    pub fn column(&self, grid: Grid, initial_k: f64) -> Slab {
        let depth = self.column_depth_m();
        if self.layers.is_empty() {
            Slab::new(
                depth,
                self.conductivity_w_m_k,
                self.density_kg_m3 * self.specific_heat_j_kg_k,
                grid,
                initial_k,
            )
        } else {
            Slab::layered(
                &construction::column_cells(&self.layers, depth, grid),
                initial_k,
            )
        }
    }

    /// Depth of the computed column, m: the thickness, or for
    /// [`BackBoundary::Ground`] the column depth described there.
    pub fn column_depth_m(&self) -> f64 {
        match self.back {
            BackBoundary::Ground {
                depth_m: Some(d), ..
            } => d,
            BackBoundary::Ground { depth_m: None, .. } => match self.layers.as_slice() {
                [] => self.thickness_m.max(5.0 * self.diurnal_damping_depth_m()),
                // The last layer continues down to five of its own damping
                // depths below the layers above it.
                l => {
                    let last = l[l.len() - 1];
                    let above = self.layers.thickness_m() - last.thickness_m;
                    self.layers
                        .thickness_m()
                        .max(above + 5.0 * last.diurnal_damping_depth_m())
                }
            },
            _ => self.thickness_m,
        }
    }

    /// Thermal properties of a material, with its normal
    /// `thermal_emissivity` turned into the hemispherical one (see the
    /// field); the back boundary follows
    /// [`BackBoundary::from_exposed_area`] (override with
    /// [`SlabProperties::with_back`]). Errors name the material and the
    /// offending field.
    pub fn from_material(m: &Material) -> Result<SlabProperties> {
        let field = |f: &str| format!("material `{}` (id {}): {f}", m.name, m.id);
        if !m.exposed_area.is_finite() {
            return Err(Error::invalid(
                field("exposed_area"),
                format!("expected a finite number, got {}", m.exposed_area),
            ));
        }
        let p = SlabProperties {
            conductivity_w_m_k: m.conductivity_w_m_k,
            density_kg_m3: m.density_kg_m3,
            specific_heat_j_kg_k: m.specific_heat_j_kg_k,
            thickness_m: m.thickness_m,
            solar_absorptivity: m.solar_absorptivity,
            // The material's value is normal; the balance emits and absorbs
            // with the hemispherical one of the renderer's angular model.
            thermal_emissivity: crate::radiometry::emissivity::thermal_hemispherical_emissivity(m)
                .map_err(|e| Error::invalid(field("emissivity_curve"), e.to_string()))?,
            self_power_w_m2: m.self_power_w_m2,
            back: match &m.back {
                Some(spec) => BackBoundary::from_spec(spec),
                None => BackBoundary::from_exposed_area(m.exposed_area),
            },
            surface: match &m.surface_energy {
                Some(spec) => Some(LandSurface::from_spec(spec).map_err(|e| {
                    Error::invalid(
                        field(&format!("surface_energy.{}", e.field())),
                        e.to_string(),
                    )
                })?),
                None => None,
            },
            convection: m.convection,
            layers: Layers::new(
                &m.layers
                    .iter()
                    .map(|l| Layer {
                        conductivity_w_m_k: l.conductivity_w_m_k,
                        density_kg_m3: l.density_kg_m3,
                        specific_heat_j_kg_k: l.specific_heat_j_kg_k,
                        thickness_m: l.thickness_m,
                        contact_resistance_m2_k_w: l.contact_resistance_m2_k_w,
                    })
                    .collect::<Vec<_>>(),
            )
            .map_err(|e| rename(e, &field))?,
        };
        p.validate_with(&field)?;
        Ok(p)
    }

    /// The same properties with another back boundary.
    pub fn with_back(self, back: BackBoundary) -> SlabProperties {
        SlabProperties { back, ..self }
    }

    /// Check every property is in its physical domain.
    pub fn validate(&self) -> Result<()> {
        self.validate_with(&|f: &str| f.to_string())
    }

    fn validate_with(&self, field: &dyn Fn(&str) -> String) -> Result<()> {
        let positive = [
            ("conductivity_w_m_k", self.conductivity_w_m_k, "W/(m·K)"),
            ("density_kg_m3", self.density_kg_m3, "kg/m³"),
            (
                "specific_heat_j_kg_k",
                self.specific_heat_j_kg_k,
                "J/(kg·K)",
            ),
            ("thickness_m", self.thickness_m, "m"),
        ];
        for (name, v, unit) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(
                    field(name),
                    format!("expected a positive number ({unit}), got {v}"),
                ));
            }
        }
        for (name, v) in [
            ("solar_absorptivity", self.solar_absorptivity),
            ("thermal_emissivity", self.thermal_emissivity),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(Error::invalid(
                    field(name),
                    format!("expected a fraction in [0, 1], got {v}"),
                ));
            }
        }
        if !self.self_power_w_m2.is_finite() {
            return Err(Error::invalid(
                field("self_power_w_m2"),
                format!(
                    "expected a finite power (W/m²), got {}",
                    self.self_power_w_m2
                ),
            ));
        }
        match self.back {
            BackBoundary::Ground {
                deep_temperature_k,
                depth_m,
            } => {
                if let Some(t) = deep_temperature_k
                    && !(t.is_finite() && t > 0.0)
                {
                    return Err(Error::invalid(
                        field("back.deep_temperature_k"),
                        format!("expected a positive temperature (K), got {t}"),
                    ));
                }
                if let Some(d) = depth_m
                    && !(d.is_finite() && d > 0.0)
                {
                    return Err(Error::invalid(
                        field("back.depth_m"),
                        format!("expected a positive depth (m), got {d}"),
                    ));
                }
            }
            BackBoundary::Interior {
                air,
                film_coefficient_w_m2_k,
            } => {
                air.validate("back").map_err(|e| rename(e, field))?;
                if !(film_coefficient_w_m2_k.is_finite() && film_coefficient_w_m2_k >= 0.0) {
                    return Err(Error::invalid(
                        field("back.film_coefficient_w_m2_k"),
                        format!(
                            "expected a non-negative coefficient (W/(m²·K)), got {film_coefficient_w_m2_k}"
                        ),
                    ));
                }
            }
            BackBoundary::Exposed { fraction } => {
                if !(fraction > 0.0 && fraction <= 1.0) {
                    return Err(Error::invalid(
                        field("back.fraction"),
                        format!("expected an exposed fraction in (0, 1], got {fraction}"),
                    ));
                }
            }
            BackBoundary::Insulated => {}
        }
        if let Some(s) = &self.surface {
            s.validate().map_err(|e| rename(e, field))?;
        }
        if !self.layers.is_empty() {
            self.layers.validate().map_err(|e| rename(e, field))?;
            let total = self.layers.thickness_m();
            if (self.thickness_m - total).abs() > 1e-9 * total {
                return Err(Error::invalid(
                    field("thickness_m"),
                    format!(
                        "{} m differs from the layers' total {total} m (a layered slab's thickness is its layers')",
                        self.thickness_m
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// An invalid-field error with its field named through `field`.
fn rename(e: Error, field: &dyn Fn(&str) -> String) -> Error {
    match e {
        Error::Invalid { field: f, message } => Error::invalid(field(&f), message),
        other => other,
    }
}

impl TryFrom<&Material> for SlabProperties {
    type Error = Error;
    fn try_from(m: &Material) -> Result<SlabProperties> {
        SlabProperties::from_material(m)
    }
}

/// The weather history driving every facet, one entry per record, SI units.
/// Between records every quantity varies linearly in time.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Forcing {
    /// Record times, seconds since the first record (strictly increasing).
    pub times_s: Vec<f64>,
    /// Air temperature, K.
    pub air_temperature_k: Vec<f64>,
    /// Wind speed, m/s.
    pub wind_speed_m_s: Vec<f64>,
    /// Direct-normal solar irradiance, W m⁻².
    pub direct_normal_w_m2: Vec<f64>,
    /// Diffuse-horizontal solar irradiance, W m⁻².
    pub diffuse_horizontal_w_m2: Vec<f64>,
    /// Downwelling sky longwave on a horizontal surface, W m⁻².
    pub sky_longwave_w_m2: Vec<f64>,
    /// Actual vapour pressure of the air, Pa.
    pub vapour_pressure_pa: Vec<f64>,
    /// Station pressure, Pa.
    pub pressure_pa: Vec<f64>,
    /// Global-horizontal solar irradiance, W m⁻².
    pub global_horizontal_w_m2: Vec<f64>,
    /// Liquid precipitation over the interval ending at each record, mm
    /// (wets surfaces: [`surface::WetStore`]).
    pub precipitation_mm: Vec<f64>,
    /// Height of the wind measurement above the ground, m (default
    /// [`WIND_HEIGHT_M`]).
    pub wind_height_m: f64,
    /// Height of the air temperature and humidity measurement, m (default
    /// [`AIR_HEIGHT_M`]).
    pub air_height_m: f64,
    /// Local time of day of the first record, s after local midnight (for
    /// interior schedules, [`InteriorAir::Hourly`]; 0 for
    /// [`Forcing::constant`]).
    pub start_second_of_day: f64,
    /// Time of the first record, seconds since 1970-01-01 00:00 UTC (for
    /// a canopy's dated phenology; 0 for [`Forcing::constant`]).
    pub start_unix_s: f64,
}

/// Default height of a weather file's wind, m: the WMO standard anemometer
/// height (WMO-No. 8, *Guide to Instruments and Methods of Observation*,
/// 2018, Vol. I §5.9.2), which EPW and TMY3 airport data follow.
pub const WIND_HEIGHT_M: f64 = 10.0;

/// Default height of a weather file's air temperature and humidity, m: the
/// WMO screen height 1.25–2 m (WMO-No. 8, Vol. I §2.1.4.1); 2 m.
pub const AIR_HEIGHT_M: f64 = 2.0;

impl Forcing {
    /// The forcing of a weather history (validated).
    pub fn from_records(records: &[WeatherRecord]) -> Result<Forcing> {
        let t0 = records.first().map(|r| r.time);
        let f = Forcing {
            times_s: records
                .iter()
                .map(|r| (r.time - t0.expect("non-empty")).num_milliseconds() as f64 * 1e-3)
                .collect(),
            air_temperature_k: records.iter().map(|r| r.air_temperature_k).collect(),
            wind_speed_m_s: records.iter().map(|r| r.wind_speed_m_s).collect(),
            direct_normal_w_m2: records.iter().map(|r| r.direct_normal_w_m2).collect(),
            diffuse_horizontal_w_m2: records.iter().map(|r| r.diffuse_horizontal_w_m2).collect(),
            sky_longwave_w_m2: records.iter().map(|r| r.sky_longwave_w_m2).collect(),
            // FAO-56 eq. 14 from the dew point; eq. 10 from RH where the dew
            // point is not a number.
            vapour_pressure_pa: records
                .iter()
                .map(|r| {
                    if r.dew_point_k.is_finite() {
                        latent::psychrometrics::vapour_pressure_from_dew_point_pa(r.dew_point_k)
                    } else {
                        latent::psychrometrics::vapour_pressure_from_relative_humidity_pa(
                            r.air_temperature_k,
                            r.relative_humidity,
                        )
                    }
                })
                .collect(),
            pressure_pa: records.iter().map(|r| r.pressure_pa).collect(),
            global_horizontal_w_m2: records.iter().map(|r| r.global_horizontal_w_m2).collect(),
            precipitation_mm: records.iter().map(|r| r.precipitation_mm).collect(),
            wind_height_m: WIND_HEIGHT_M,
            air_height_m: AIR_HEIGHT_M,
            start_second_of_day: t0.map_or(0.0, |t| {
                use chrono::Timelike;
                let c = t.time();
                c.num_seconds_from_midnight() as f64 + c.nanosecond() as f64 * 1e-9
            }),
            start_unix_s: t0.map_or(0.0, |t| t.timestamp_millis() as f64 * 1e-3),
        };
        f.validate()?;
        Ok(f)
    }

    /// Constant weather at the given record times (for tests and studies):
    /// relative humidity 50 %, pressure 101 325 Pa, and a global horizontal
    /// irradiance of `direct + diffuse` (the sun at the zenith); change the
    /// fields for other air.
    pub fn constant(
        times_s: &[f64],
        air_temperature_k: f64,
        wind_speed_m_s: f64,
        direct_normal_w_m2: f64,
        diffuse_horizontal_w_m2: f64,
        sky_longwave_w_m2: f64,
    ) -> Forcing {
        let n = times_s.len();
        Forcing {
            times_s: times_s.to_vec(),
            air_temperature_k: vec![air_temperature_k; n],
            wind_speed_m_s: vec![wind_speed_m_s; n],
            direct_normal_w_m2: vec![direct_normal_w_m2; n],
            diffuse_horizontal_w_m2: vec![diffuse_horizontal_w_m2; n],
            sky_longwave_w_m2: vec![sky_longwave_w_m2; n],
            vapour_pressure_pa: vec![
                latent::psychrometrics::vapour_pressure_from_relative_humidity_pa(
                    air_temperature_k,
                    0.5
                );
                n
            ],
            pressure_pa: vec![101_325.0; n],
            global_horizontal_w_m2: vec![direct_normal_w_m2 + diffuse_horizontal_w_m2; n],
            precipitation_mm: vec![0.0; n],
            wind_height_m: WIND_HEIGHT_M,
            air_height_m: AIR_HEIGHT_M,
            start_second_of_day: 0.0,
            start_unix_s: 0.0,
        }
    }

    /// Keep the first `n` records.
    pub fn truncate(&mut self, n: usize) {
        for v in [
            &mut self.times_s,
            &mut self.air_temperature_k,
            &mut self.wind_speed_m_s,
            &mut self.direct_normal_w_m2,
            &mut self.diffuse_horizontal_w_m2,
            &mut self.sky_longwave_w_m2,
            &mut self.vapour_pressure_pa,
            &mut self.pressure_pa,
            &mut self.global_horizontal_w_m2,
            &mut self.precipitation_mm,
        ] {
            v.truncate(n);
        }
    }

    /// Number of records.
    pub fn len(&self) -> usize {
        self.times_s.len()
    }

    /// Whether there are no records.
    pub fn is_empty(&self) -> bool {
        self.times_s.is_empty()
    }

    /// Time-weighted (trapezoidal) mean air temperature, K.
    pub fn mean_air_temperature_k(&self) -> f64 {
        let n = self.len();
        if n == 1 {
            return self.air_temperature_k[0];
        }
        let mut num = 0.0;
        for k in 0..n - 1 {
            let dt = self.times_s[k + 1] - self.times_s[k];
            num += 0.5 * dt * (self.air_temperature_k[k] + self.air_temperature_k[k + 1]);
        }
        num / (self.times_s[n - 1] - self.times_s[0])
    }

    /// Check lengths, time order and physical ranges; errors name the
    /// record (`records[i].field`).
    pub fn validate(&self) -> Result<()> {
        let n = self.len();
        if n == 0 {
            return Err(Error::invalid(
                "records",
                "the weather history is empty; at least one record is needed",
            ));
        }
        let cols: [(&str, &Vec<f64>, f64, &str); 9] = [
            ("air_temperature_k", &self.air_temperature_k, 1.0, "K, > 0"),
            ("wind_speed_m_s", &self.wind_speed_m_s, 0.0, "m/s, ≥ 0"),
            (
                "direct_normal_w_m2",
                &self.direct_normal_w_m2,
                0.0,
                "W/m², ≥ 0",
            ),
            (
                "diffuse_horizontal_w_m2",
                &self.diffuse_horizontal_w_m2,
                0.0,
                "W/m², ≥ 0",
            ),
            (
                "sky_longwave_w_m2",
                &self.sky_longwave_w_m2,
                0.0,
                "W/m², ≥ 0",
            ),
            (
                "vapour_pressure_pa",
                &self.vapour_pressure_pa,
                0.0,
                "Pa, ≥ 0",
            ),
            ("pressure_pa", &self.pressure_pa, 0.0, "Pa, ≥ 0"),
            ("precipitation_mm", &self.precipitation_mm, 0.0, "mm, ≥ 0"),
            (
                "global_horizontal_w_m2",
                &self.global_horizontal_w_m2,
                0.0,
                "W/m², ≥ 0",
            ),
        ];
        for (name, col, min, what) in cols {
            if col.len() != n {
                return Err(Error::invalid(
                    name,
                    format!("has {} values but there are {n} record times", col.len()),
                ));
            }
            if let Some((i, v)) = col
                .iter()
                .enumerate()
                .find(|(_, v)| !(v.is_finite() && **v >= min))
            {
                return Err(Error::invalid(
                    format!("records[{i}].{name}"),
                    format!("expected a finite value ({what}), got {v}"),
                ));
            }
        }
        for (name, z) in [
            ("wind_height_m", self.wind_height_m),
            ("air_height_m", self.air_height_m),
        ] {
            if !(z.is_finite() && z > 0.0) {
                return Err(Error::invalid(
                    name,
                    format!("expected a measurement height > 0 m, got {z}"),
                ));
            }
        }
        for i in 1..n {
            let (a, b) = (self.times_s[i - 1], self.times_s[i]);
            if !(b.is_finite() && b > a) {
                return Err(Error::invalid(
                    format!("records[{i}].time"),
                    format!(
                        "record times must increase strictly; record {i} is {b} s after the first, \
                         record {} is {a} s",
                        i - 1
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Temperature of what a facet sees where it does not see sky.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Background<'a> {
    /// The air temperature of each record (no neighbour information).
    Air,
    /// A constant temperature, K.
    Constant(f64),
    /// One temperature per record, K (e.g. the area-weighted σT⁴-mean of the
    /// neighbours hit by the blocked hemisphere rays, from a previous pass).
    PerRecord(&'a [f32]),
}

/// The per-facet inputs of the thermal model (computed by ray tracing in a
/// scene; by geometry alone in one-facet mode). Slices are borrowed so the
/// caller can keep all facets' histories in flat arrays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FacetInputs<'a> {
    /// Sunlit fraction of the facet at each record, 0–1.
    pub sun_fraction: &'a [f32],
    /// Cosine of the solar incidence angle on the facet at each record
    /// (values ≤ 0: sun behind the facet or below the horizon).
    pub cos_incidence: &'a [f32],
    /// Sky shape factor `F` of the front face, 0–1.
    pub shape_factor: f64,
    /// Sky shape factor of the back face, used only with
    /// [`BackBoundary::Exposed`]; None: `1 − F`, exact for an unobstructed
    /// plane (a plane tilted β sees `(1+cos β)/2` of the sky from the front
    /// and `(1−cos β)/2` from the back).
    pub back_shape_factor: Option<f64>,
    /// Background temperature.
    pub background: Background<'a>,
    /// Shortwave reflected onto the facet by what it sees
    /// ([`Reflected`]; [`Reflected::NONE`] by default).
    pub reflected: Reflected<'a>,
}

/// The shortwave reflected onto a facet by the surfaces it sees, per unit
/// of the weather's irradiances: `E_r(t) = E_dn(t)·direct[t] + E_d(t)·diffuse`
/// (W m⁻²; the model and its coefficients: `irsig::exposure::reflected`).
/// A free-standing facet tilted β over open ground of albedo `ρ_g` has
/// `direct[t] = ρ_g (1 − F) max(sin h(t), 0)` (`h` the sun's elevation) and
/// `diffuse = ρ_g (1 − F)` ([`Reflected::open_ground`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reflected<'a> {
    /// Reflected irradiance per unit direct-normal irradiance at each
    /// record (dimensionless, ≥ 0); empty: none.
    pub direct: &'a [f32],
    /// Reflected irradiance per unit diffuse-horizontal irradiance
    /// (dimensionless, ≥ 0).
    pub diffuse: f64,
}

impl<'a> Reflected<'a> {
    /// No reflected shortwave.
    pub const NONE: Reflected<'static> = Reflected {
        direct: &[],
        diffuse: 0.0,
    };

    /// The coefficient of the direct-normal irradiance at record `k`.
    #[inline]
    pub fn direct_at(&self, k: usize) -> f64 {
        self.direct.get(k).map_or(0.0, |&v| v as f64)
    }

    /// The ground seen by a free-standing facet: view factor `ground_view`
    /// (`1 − F` of an unobstructed plane), albedo `albedo`, the sun's
    /// elevation sine `sin_elevation[t]` at each record (the coefficients
    /// written into `direct`, which is returned borrowed).
    pub fn open_ground(
        ground_view: f64,
        albedo: f64,
        sin_elevation: &[f64],
        direct: &'a mut Vec<f32>,
    ) -> Reflected<'a> {
        let c = (ground_view * albedo).max(0.0);
        direct.clear();
        direct.extend(sin_elevation.iter().map(|&z| (c * z.max(0.0)) as f32));
        Reflected { direct, diffuse: c }
    }
}

impl<'a> FacetInputs<'a> {
    /// Inputs with the background at air temperature and the default back
    /// shape factor.
    pub fn new(sun_fraction: &'a [f32], cos_incidence: &'a [f32], shape_factor: f64) -> Self {
        FacetInputs {
            sun_fraction,
            cos_incidence,
            shape_factor,
            back_shape_factor: None,
            background: Background::Air,
            reflected: Reflected::NONE,
        }
    }

    fn validate(&self, n: usize) -> Result<()> {
        for (name, col) in [
            ("sun_fraction", self.sun_fraction),
            ("cos_incidence", self.cos_incidence),
        ] {
            if col.len() != n {
                return Err(Error::invalid(
                    name,
                    format!(
                        "has {} values; expected one per weather record ({n})",
                        col.len()
                    ),
                ));
            }
        }
        if let Some(i) = self
            .sun_fraction
            .iter()
            .position(|v| !(0.0..=1.0).contains(v))
        {
            return Err(Error::invalid(
                format!("sun_fraction[{i}]"),
                format!(
                    "expected a fraction in [0, 1], got {}",
                    self.sun_fraction[i]
                ),
            ));
        }
        if let Some(i) = self
            .cos_incidence
            .iter()
            .position(|v| !(-1.0..=1.0).contains(v))
        {
            return Err(Error::invalid(
                format!("cos_incidence[{i}]"),
                format!(
                    "expected a cosine in [-1, 1], got {}",
                    self.cos_incidence[i]
                ),
            ));
        }
        for (name, v) in [
            ("shape_factor", Some(self.shape_factor)),
            ("back_shape_factor", self.back_shape_factor),
        ] {
            if let Some(v) = v
                && !(0.0..=1.0).contains(&v)
            {
                return Err(Error::invalid(
                    name,
                    format!("expected a fraction in [0, 1], got {v}"),
                ));
            }
        }
        if !self.reflected.direct.is_empty() && self.reflected.direct.len() != n {
            return Err(Error::invalid(
                "reflected.direct",
                format!(
                    "has {} values; expected one per weather record ({n}) or none",
                    self.reflected.direct.len()
                ),
            ));
        }
        if let Some(i) = self
            .reflected
            .direct
            .iter()
            .position(|v| !(v.is_finite() && *v >= 0.0))
        {
            return Err(Error::invalid(
                format!("reflected.direct[{i}]"),
                format!(
                    "expected a finite coefficient ≥ 0, got {}",
                    self.reflected.direct[i]
                ),
            ));
        }
        if !(self.reflected.diffuse.is_finite() && self.reflected.diffuse >= 0.0) {
            return Err(Error::invalid(
                "reflected.diffuse",
                format!(
                    "expected a finite coefficient ≥ 0, got {}",
                    self.reflected.diffuse
                ),
            ));
        }
        match self.background {
            Background::Air => {}
            Background::Constant(t) => {
                if !(t.is_finite() && t > 0.0) {
                    return Err(Error::invalid(
                        "background",
                        format!("expected a positive temperature (K), got {t}"),
                    ));
                }
            }
            Background::PerRecord(ts) => {
                if ts.len() != n {
                    return Err(Error::invalid(
                        "background",
                        format!(
                            "has {} values; expected one per weather record ({n})",
                            ts.len()
                        ),
                    ));
                }
                if let Some(i) = ts.iter().position(|t| !(t.is_finite() && *t > 0.0)) {
                    return Err(Error::invalid(
                        format!("background[{i}]"),
                        format!("expected a positive temperature (K), got {}", ts[i]),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Spin-up by repeating the first period of the history.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spinup {
    /// Most repetitions of the first period before the real run (0 = none:
    /// the history itself is the spin-up).
    pub max_cycles: u32,
    /// Length of the repeated period, s (a day).
    pub period_s: f64,
    /// Stop repeating once a cycle ends within this of the state it started
    /// from, at every node (the state is then periodic), K.
    pub tolerance_k: f64,
    /// The state the first cycle starts from.
    pub start: SpinupStart,
}

/// The state a spin-up starts from ([`Spinup::start`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SpinupStart {
    /// The steady state of the slab under the period's mean forcing
    /// (default): the front and back laws averaged over the first period
    /// (trapezoidal, as the solver interpolates them), the steady
    /// conduction profile between the two faces solved by Newton's method.
    /// The deep nodes of thick slabs (a pond, a soil column) start near
    /// their periodic mean instead of at the first record's air
    /// temperature, so the spin-up days settle the diurnal wave only. A
    /// mean law without a steady state (no loss that grows with
    /// temperature) falls back to [`SpinupStart::FirstAir`].
    #[default]
    MeanSteady,
    /// Every node at the first record's air temperature (a ground column:
    /// linear from it to the deep temperature).
    FirstAir,
}

impl Default for Spinup {
    /// Up to 3 repetitions of the first 24 h, until a day ends within
    /// 0.05 K of its start state.
    fn default() -> Self {
        Spinup {
            max_cycles: 3,
            period_s: 86_400.0,
            tolerance_k: 0.05,
            start: SpinupStart::MeanSteady,
        }
    }
}

impl Spinup {
    /// No repetition: the history itself is the spin-up.
    pub fn none() -> Self {
        Spinup {
            max_cycles: 0,
            ..Spinup::default()
        }
    }
}

/// Numerical options of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveOptions {
    /// Finite-volume grid through the slab.
    pub grid: Grid,
    /// Longest time step, s; each interval between records is split into
    /// equal sub-steps no longer than this.
    pub max_substep_s: f64,
    /// Spin-up.
    pub spinup: Spinup,
    /// Newton tolerance on the surface temperature within a stage, K.
    pub newton_tolerance_k: f64,
}

impl Default for SolveOptions {
    /// 12 cells (growth 1.3), sub-steps ≤ 900 s (one per 15-min record), up
    /// to 3 spin-up days.
    fn default() -> Self {
        SolveOptions {
            grid: Grid::default(),
            max_substep_s: 900.0,
            spinup: Spinup::default(),
            newton_tolerance_k: 1e-4,
        }
    }
}

impl SolveOptions {
    /// The fast preset for large scenes and parameter sweeps: 8 cells,
    /// sub-steps ≤ 900 s, no spin-up repetitions (the history itself is the
    /// spin-up, which leaves thick slabs and ground up to ~1 K from their
    /// periodic state after one day; see the README).
    pub fn fast() -> Self {
        SolveOptions {
            grid: Grid {
                cells: 8,
                growth: 1.6,
            },
            max_substep_s: 900.0,
            spinup: Spinup::none(),
            newton_tolerance_k: 1e-3,
        }
    }

    /// The accurate preset, for verification: 24 cells (growth 1.15),
    /// sub-steps ≤ 120 s, up to 6 spin-up days to 0.01 K.
    pub fn accurate() -> Self {
        SolveOptions {
            grid: Grid {
                cells: 24,
                growth: 1.15,
            },
            max_substep_s: 120.0,
            spinup: Spinup {
                max_cycles: 6,
                period_s: 86_400.0,
                tolerance_k: 0.01,
                start: SpinupStart::MeanSteady,
            },
            newton_tolerance_k: 1e-6,
        }
    }

    fn validate(&self) -> Result<()> {
        if self.grid.cells == 0 || self.grid.cells > 1000 {
            return Err(Error::invalid(
                "grid.cells",
                format!("expected 1..=1000 cells, got {}", self.grid.cells),
            ));
        }
        if !(self.grid.growth.is_finite() && (1.0..=4.0).contains(&self.grid.growth)) {
            return Err(Error::invalid(
                "grid.growth",
                format!("expected a ratio in [1, 4], got {}", self.grid.growth),
            ));
        }
        if !(self.max_substep_s.is_finite() && self.max_substep_s > 0.0) {
            return Err(Error::invalid(
                "max_substep_s",
                format!("expected a positive time (s), got {}", self.max_substep_s),
            ));
        }
        if !(self.spinup.period_s.is_finite() && self.spinup.period_s > 0.0) {
            return Err(Error::invalid(
                "spinup.period_s",
                format!("expected a positive time (s), got {}", self.spinup.period_s),
            ));
        }
        if !(self.newton_tolerance_k.is_finite() && self.newton_tolerance_k > 0.0) {
            return Err(Error::invalid(
                "newton_tolerance_k",
                format!(
                    "expected a positive tolerance (K), got {}",
                    self.newton_tolerance_k
                ),
            ));
        }
        Ok(())
    }
}

/// Energy budget of the final run (after spin-up), J m⁻², with the time
/// scheme's own quadrature: `front_in + back_in = stored_change` for flux
/// boundaries (for [`BackBoundary::Ground`] the deep boundary is held at a
/// fixed temperature and `back_in` is what crossed it, by difference).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EnergyBudget {
    /// Net energy in through the front surface, J m⁻².
    pub front_in_j_m2: f64,
    /// Net energy in through the back face, J m⁻².
    pub back_in_j_m2: f64,
    /// Change of the heat stored in the slab, J m⁻².
    pub stored_change_j_m2: f64,
}

/// Result of [`solve`].
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalSolution {
    /// Front-surface temperature at each weather record, K.
    pub surface_temperature_k: Vec<f64>,
    /// Back-face (or, for ground, deep-column) temperature at each record, K.
    pub back_temperature_k: Vec<f64>,
    /// Net heat flux into the front surface at each record (sum of the
    /// balance terms at the surface temperature), W m⁻².
    pub net_front_flux_w_m2: Vec<f64>,
    /// Spin-up repetitions of the first period actually run.
    pub spinup_cycles: u32,
    /// Largest change of any node temperature over the last spin-up cycle
    /// (end state − start state), K; None when no spin-up ran. Below the
    /// tolerance, the first period's solution is periodic to within it.
    pub spinup_change_k: Option<f64>,
    /// Change over the last period: largest |T_s(t) − T_s(t − P)| over the
    /// records of the last period `P` of the history, K (None when the
    /// history is shorter than two periods). It mixes incomplete spin-up
    /// with genuine day-to-day weather change.
    pub last_period_change_k: Option<f64>,
    /// A two-source canopy's soil surface temperature at each record, K
    /// (the slab's front node; empty for any other surface, whose
    /// `surface_temperature_k` is its front node).
    pub soil_temperature_k: Vec<f64>,
    /// A two-source canopy's leaf temperature at each record, K (empty for
    /// any other surface).
    pub canopy_temperature_k: Vec<f64>,
    /// Energy budget of the final run.
    pub energy: EnergyBudget,
    /// Work counters of the final run and spin-up.
    pub stats: StepStats,
    /// How the reference passes of the exchange this solve made ended
    /// ([`solve_facing`]; None where it was given one, [`solve_with`], or
    /// none was solved: [`Exchange::passes`]).
    pub exchange_passes: Option<Passes>,
}

/// The flux laws at each record for one facet, and the column to solve.
struct Prepared {
    front: Vec<SurfaceFlux>,
    /// A two-source canopy's absorbed incoming radiation at each record
    /// (the facet's source, W m⁻²) and its model (both empty otherwise).
    incoming: Vec<f64>,
    two_source: Vec<two_source::TwoSourceStep>,
    back: Vec<Boundary>,
    initial_surface_k: f64,
    deep_k: Option<f64>,
}

fn prepare(
    props: &SlabProperties,
    forcing: &Forcing,
    inputs: &FacetInputs,
    exchange: &Exchange,
) -> Prepared {
    let n = forcing.len();
    let mut front = Vec::with_capacity(n);
    let mut back = Vec::with_capacity(n);
    let f_back = inputs
        .back_shape_factor
        .unwrap_or(1.0 - inputs.shape_factor);
    let deep_k = match props.back {
        BackBoundary::Ground {
            deep_temperature_k, ..
        } => Some(deep_temperature_k.unwrap_or_else(|| forcing.mean_air_temperature_k())),
        _ => None,
    };
    let mut incoming = Vec::new();
    for k in 0..n {
        let air = forcing.air_temperature_k[k];
        let ff = front_forcing_at(forcing, exchange, inputs, k);
        let law = balance::front_flux(
            &ff,
            props.solar_absorptivity,
            props.thermal_emissivity,
            props.self_power_w_m2,
        );
        front.push(match exchange.two_source.get(k) {
            Some(step) => {
                incoming.push(law.source_w_m2);
                step.soil_law(law.source_w_m2)
            }
            None => law,
        });
        back.push(match props.back {
            BackBoundary::Insulated => Boundary::Flux(SurfaceFlux::default()),
            BackBoundary::Exposed { fraction } => Boundary::Flux(balance::exposed_back_flux(
                &ff,
                props.thermal_emissivity,
                f_back,
                fraction,
            )),
            BackBoundary::Ground { .. } => Boundary::Temperature(deep_k.unwrap_or(air)),
            BackBoundary::Interior {
                air: interior,
                film_coefficient_w_m2_k,
            } => Boundary::Flux(balance::film_flux(
                interior.temperature_k(forcing.start_second_of_day + forcing.times_s[k], air),
                film_coefficient_w_m2_k,
            )),
        });
    }
    Prepared {
        front,
        incoming,
        two_source: exchange.two_source.clone(),
        back,
        initial_surface_k: forcing.air_temperature_k[0],
        deep_k,
    }
}

/// What the front balance needs at record `k` of a facet.
#[inline]
fn front_forcing_at(
    forcing: &Forcing,
    exchange: &Exchange,
    inputs: &FacetInputs,
    k: usize,
) -> balance::FrontForcing {
    let air = forcing.air_temperature_k[k];
    let bg = match inputs.background {
        Background::Air => air,
        Background::Constant(t) => t,
        Background::PerRecord(ts) => ts[k] as f64,
    };
    balance::FrontForcing {
        air_temperature_k: air,
        convection_w_m2_k: exchange.sensible_w_m2_k[k],
        direct_normal_w_m2: forcing.direct_normal_w_m2[k],
        diffuse_horizontal_w_m2: forcing.diffuse_horizontal_w_m2[k],
        sky_longwave_w_m2: forcing.sky_longwave_w_m2[k],
        sun_fraction: inputs.sun_fraction[k] as f64,
        cos_incidence: inputs.cos_incidence[k] as f64,
        shape_factor: inputs.shape_factor,
        reflected_w_m2: forcing.direct_normal_w_m2[k] * inputs.reflected.direct_at(k)
            + forcing.diffuse_horizontal_w_m2[k] * inputs.reflected.diffuse,
        background_temperature_k: bg,
        vapour_conductance_w_m2_pa: exchange.vapour_conductance_w_m2_pa[k],
        air_vapour_pressure_pa: forcing.vapour_pressure_pa[k],
    }
}

#[inline]
fn lerp_boundary(a: &Boundary, b: &Boundary, f: f64) -> Boundary {
    match (a, b) {
        (Boundary::Flux(x), Boundary::Flux(y)) => Boundary::Flux(x.lerp(y, f)),
        (Boundary::Temperature(x), Boundary::Temperature(y)) => {
            Boundary::Temperature(x + f * (y - x))
        }
        // Mixed kinds do not occur (one back boundary per facet).
        _ => *a,
    }
}

/// Advance the slab from record `k` to record `k + 1` (and the tangent
/// model with it, when given).
fn advance(
    slab: &mut Slab,
    p: &Prepared,
    times: &[f64],
    k: usize,
    max_substep_s: f64,
    mut tangent: Option<&mut linear::Tangent>,
) {
    let span = times[k + 1] - times[k];
    let m = (span / max_substep_s).ceil().max(1.0) as usize;
    let dt = span / m as f64;
    let (fa, fb) = (&p.front[k], &p.front[k + 1]);
    let (ba, bb) = (&p.back[k], &p.back[k + 1]);
    for j in 0..m {
        let base = j as f64 / m as f64;
        let scale = 1.0 / m as f64;
        slab.step(
            dt,
            |f| Boundary::Flux(fa.lerp(fb, base + f * scale)),
            |f| lerp_boundary(ba, bb, base + f * scale),
        );
        if let Some(t) = tangent.as_deref_mut() {
            let phi = [base, base + conduction::GAMMA * scale, base + scale];
            let temps = slab.stage_boundary_k();
            let deriv = |i: usize| {
                let front = fa.lerp(fb, phi[i]).derivative(temps[i].0);
                let back = match lerp_boundary(ba, bb, phi[i]) {
                    Boundary::Flux(law) => law.derivative(temps[i].1),
                    Boundary::Temperature(_) => 0.0,
                };
                (front, back)
            };
            t.step(dt, [deriv(0), deriv(1), deriv(2)], k, phi);
        }
    }
}

/// The steady state of a slab under the mean of its laws over records
/// `0..=k_p` ([`SpinupStart::MeanSteady`]), with its sensitivity to the
/// sources of those records (for the tangent-linear model).
#[derive(Debug, Clone)]
pub(crate) struct MeanSteady {
    /// Node temperatures, K.
    pub temperatures_k: Vec<f64>,
    /// Trapezoidal weight of each record `0..=k_p` in the mean (sum 1).
    pub weights: Vec<f64>,
    /// `∂T_i/∂S̄` of every node per unit mean front source, K per W m⁻²
    /// (a record's source enters with its weight and, for a two-source
    /// canopy, its [`two_source::TwoSourceStep::source_slope`]).
    pub per_front_source: Vec<f64>,
    /// `∂T_i/∂B̄` per unit mean back source (exposed back).
    pub per_back_source: Vec<f64>,
}

fn mean_steady_state(slab: &Slab, p: &Prepared, times: &[f64], k_p: usize) -> Option<MeanSteady> {
    let total = times[k_p] - times[0];
    if total <= 0.0 {
        return None;
    }
    let weights: Vec<f64> = (0..=k_p)
        .map(|k| {
            let before = if k > 0 { times[k] - times[k - 1] } else { 0.0 };
            let after = if k < k_p {
                times[k + 1] - times[k]
            } else {
                0.0
            };
            0.5 * (before + after) / total
        })
        .collect();
    let mean = |t: f64, laws: &mut dyn Iterator<Item = (f64, &SurfaceFlux)>| {
        laws.fold((0.0, 0.0), |(q, d), (w, law)| {
            (q + w * law.flux(t), d + w * law.derivative(t))
        })
    };
    let front = |t: f64| mean(t, &mut weights.iter().copied().zip(&p.front[..=k_p]));
    let fixed_back = match p.back[0] {
        Boundary::Temperature(_) => Some(
            weights
                .iter()
                .zip(&p.back)
                .map(|(w, b)| match b {
                    Boundary::Temperature(t) => w * t,
                    Boundary::Flux(_) => f64::NAN,
                })
                .sum::<f64>(),
        ),
        Boundary::Flux(_) => None,
    };
    let back = |t: f64| {
        weights
            .iter()
            .zip(&p.back)
            .fold((0.0, 0.0), |(q, d), (w, b)| match b {
                Boundary::Flux(law) => (q + w * law.flux(t), d + w * law.derivative(t)),
                Boundary::Temperature(_) => (f64::NAN, f64::NAN),
            })
    };
    // Resistance from the front node to each node, m² K W⁻¹.
    let mut r_to = vec![0.0];
    for k in slab.conductances_w_m2_k() {
        r_to.push(r_to[r_to.len() - 1] + 1.0 / k);
    }
    let r = *r_to.last()?;
    let (mut t0, mut tn) = (
        p.initial_surface_k,
        fixed_back.unwrap_or(p.initial_surface_k),
    );
    let mut jac = [[0.0; 2]; 2];
    let mut converged = false;
    for _ in 0..60 {
        let f = (t0 - tn) / r;
        let (qf, df) = front(t0);
        let r1 = qf - f;
        jac[0] = [df - 1.0 / r, 1.0 / r];
        let r2 = match fixed_back {
            Some(td) => {
                jac[1] = [0.0, 1.0];
                tn - td
            }
            None => {
                let (qb, db) = back(tn);
                jac[1] = [1.0 / r, db - 1.0 / r];
                qb + f
            }
        };
        let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
        if !(det.is_finite() && det.abs() > 1e-12 * (1.0 + jac[0][0].abs()) / r) {
            return None;
        }
        let d0 = (-(r1 * jac[1][1] - jac[0][1] * r2) / det).clamp(-20.0, 20.0);
        let dn = (-(jac[0][0] * r2 - jac[1][0] * r1) / det).clamp(-20.0, 20.0);
        t0 += d0;
        tn += dn;
        if !(t0.is_finite() && tn.is_finite()) {
            return None;
        }
        if d0.abs().max(dn.abs()) < 1e-9 {
            converged = true;
            break;
        }
    }
    if !converged || !(100.0..700.0).contains(&t0) || !(100.0..700.0).contains(&tn) {
        return None;
    }
    let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
    // [dT0, dTn] = −J⁻¹ e₁ per unit mean front source, −J⁻¹ e₂ per back.
    let (u0, u1) = (-jac[1][1] / det, jac[1][0] / det);
    let (v0, v1) = (jac[0][1] / det, -jac[0][0] / det);
    let c: Vec<f64> = r_to.iter().map(|x| x / r).collect();
    Some(MeanSteady {
        temperatures_k: c.iter().map(|&ci| t0 + (tn - t0) * ci).collect(),
        weights,
        per_front_source: c.iter().map(|&ci| (1.0 - ci) * u0 + ci * u1).collect(),
        per_back_source: c.iter().map(|&ci| (1.0 - ci) * v0 + ci * v1).collect(),
    })
}

/// Solve the thermal model of one facet over the whole weather history.
///
/// The slab starts at the air temperature of the first record (a ground
/// column: linear from it to the deep temperature), is optionally spun up by
/// repeating the first period ([`Spinup`]), then is stepped through every
/// record. Returns the front-surface temperature at each record.
///
/// Errors (bad property, input lengths that do not match the history,
/// out-of-range values) name the offending field.
pub fn solve(
    props: &SlabProperties,
    forcing: &Forcing,
    inputs: &FacetInputs,
    opts: &SolveOptions,
) -> Result<ThermalSolution> {
    solve_facing(props, forcing, inputs, opts, 1.0)
}

/// [`solve`] for a facet whose unit normal has z-component `normal_z`
/// (`cos` of its tilt): the orientation sets the natural convection of a
/// dry surface ([`Exchange::facing`]); [`solve`] is a horizontal facet.
///
/// # Errors
/// As [`solve`].
pub fn solve_facing(
    props: &SlabProperties,
    forcing: &Forcing,
    inputs: &FacetInputs,
    opts: &SolveOptions,
    normal_z: f64,
) -> Result<ThermalSolution> {
    props.validate()?;
    forcing.validate()?;
    let exchange = Exchange::facing(props, forcing, normal_z)?;
    let mut sol = solve_with(props, forcing, &exchange, inputs, opts)?;
    sol.exchange_passes = exchange.passes;
    Ok(sol)
}

/// [`solve`] with the material's [`Exchange`] under `forcing` already made
/// ([`Exchange::new`]): for many facets of one material. `props` and
/// `forcing` are taken as validated; the facet inputs and options are
/// checked.
///
/// # Errors
/// Facet inputs or options out of range; an exchange whose length is not
/// the forcing's.
pub fn solve_with(
    props: &SlabProperties,
    forcing: &Forcing,
    exchange: &Exchange,
    inputs: &FacetInputs,
    opts: &SolveOptions,
) -> Result<ThermalSolution> {
    inputs.validate(forcing.len())?;
    opts.validate()?;
    exchange.check_len(forcing.len())?;
    let p = prepare(props, forcing, inputs, exchange);
    Ok(solve_prepared(props, forcing, &p, opts, None))
}

/// [`solve`] on validated, prepared inputs, optionally carrying the
/// tangent-linear model along (see [`linear`]).
fn solve_prepared(
    props: &SlabProperties,
    forcing: &Forcing,
    p: &Prepared,
    opts: &SolveOptions,
    mut tangent: Option<&mut linear::Tangent>,
) -> ThermalSolution {
    let depth = props.column_depth_m();
    let mut slab = props.column(opts.grid, p.initial_surface_k);
    if let Some(skin) = props.surface.and_then(|s| s.skin) {
        slab = slab.with_skin(skin.capacity_j_m2_k, skin.conductance_w_m2_k);
    }
    slab.set_newton(opts.newton_tolerance_k, 30);
    if let Some(deep) = p.deep_k {
        let top = p.initial_surface_k;
        slab.set_temperatures(|x| top + (deep - top) * x / depth);
    }
    if let Some(t) = tangent.as_deref_mut() {
        t.init(&slab);
    }
    let n = forcing.len();
    let times = &forcing.times_s;

    // Spin-up: repeat records 0..=k_p (the first period) while it changes.
    let period = opts.spinup.period_s;
    let k_p = times.partition_point(|&t| t <= times[0] + period + 1e-6) - 1;
    let mut spinup_cycles = 0;
    let mut spinup_change_k = None;
    let spin = opts.spinup.max_cycles > 0 && k_p > 0 && times[k_p] - times[0] >= period - 1e-6;
    if spin
        && opts.spinup.start == SpinupStart::MeanSteady
        && let Some(init) = mean_steady_state(&slab, p, times, k_p)
    {
        slab.set_node_temperatures(&init.temperatures_k);
        if let Some(t) = tangent.as_deref_mut() {
            t.set_initial_sensitivity(&init);
        }
    }
    if spin {
        let mut start_state = slab.temperatures_k().to_vec();
        for _ in 0..opts.spinup.max_cycles {
            for k in 0..k_p {
                advance(
                    &mut slab,
                    p,
                    times,
                    k,
                    opts.max_substep_s,
                    tangent.as_deref_mut(),
                );
            }
            spinup_cycles += 1;
            // Periodicity: how much the state changed over the cycle.
            let change = slab
                .temperatures_k()
                .iter()
                .zip(&start_state)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            spinup_change_k = Some(change);
            if change < opts.spinup.tolerance_k {
                break;
            }
            start_state.copy_from_slice(slab.temperatures_k());
        }
    }

    // The real run.
    slab.reset_energy();
    let e0 = slab.stored_energy_j_m2();
    let mut surface = Vec::with_capacity(n);
    let mut back = Vec::with_capacity(n);
    let mut flux = Vec::with_capacity(n);
    let two = !p.two_source.is_empty();
    let mut soil = Vec::with_capacity(if two { n } else { 0 });
    let mut canopy = Vec::with_capacity(if two { n } else { 0 });
    // The record's output: the front node, or a two-source canopy's
    // radiometric temperature (with its derivatives for the tangent).
    let mut output = |k: usize, t_front: f64| -> (f64, f64, f64) {
        if !two {
            return (t_front, 1.0, 0.0);
        }
        let (step, s) = (&p.two_source[k], p.incoming[k]);
        soil.push(t_front);
        canopy.push(step.canopy_k(s, t_front));
        let (w, feed) = step.radiometric_derivatives(s, t_front);
        (step.radiometric_k(s, t_front), w, feed)
    };
    if let Some(t) = tangent.as_deref_mut() {
        t.set_source_scale(p.two_source.iter().map(|s| s.source_slope()).collect());
    }
    let (t0, w0, feed0) = output(0, slab.front_k());
    surface.push(t0);
    back.push(slab.back_k());
    flux.push(p.front[0].flux(slab.front_k()));
    if let Some(t) = tangent.as_deref_mut() {
        t.record(0, w0, feed0);
    }
    for k in 0..n - 1 {
        advance(
            &mut slab,
            p,
            times,
            k,
            opts.max_substep_s,
            tangent.as_deref_mut(),
        );
        let (tk, wk, feedk) = output(k + 1, slab.front_k());
        if let Some(t) = tangent.as_deref_mut() {
            t.record(k + 1, wk, feedk);
        }
        surface.push(tk);
        back.push(slab.back_k());
        flux.push(p.front[k + 1].flux(slab.front_k()));
    }
    let (front_in, back_in) = slab.boundary_energy_j_m2();
    let stored_change = slab.stored_energy_j_m2() - e0;
    let back_in = if p.deep_k.is_some() {
        stored_change - front_in
    } else {
        back_in
    };

    // Change over the last period.
    let t_end = times[n - 1];
    let last_period_change_k = if t_end - times[0] >= 2.0 * period - 1e-6 {
        let start = times.partition_point(|&t| t < t_end - period);
        let mut worst: f64 = 0.0;
        for k in start..n {
            let t = times[k] - period;
            let j = times.partition_point(|&x| x < t).min(n - 1);
            let then = if j == 0 || (times[j] - t).abs() < 1e-6 {
                surface[j]
            } else {
                let f = (t - times[j - 1]) / (times[j] - times[j - 1]);
                surface[j - 1] + f * (surface[j] - surface[j - 1])
            };
            worst = worst.max((surface[k] - then).abs());
        }
        Some(worst)
    } else {
        None
    };

    ThermalSolution {
        surface_temperature_k: surface,
        back_temperature_k: back,
        net_front_flux_w_m2: flux,
        spinup_cycles,
        spinup_change_k,
        last_period_change_k,
        soil_temperature_k: soil,
        canopy_temperature_k: canopy,
        energy: EnergyBudget {
            front_in_j_m2: front_in,
            back_in_j_m2: back_in,
            stored_change_j_m2: stored_change,
        },
        stats: slab.stats(),
        exchange_passes: None,
    }
}
