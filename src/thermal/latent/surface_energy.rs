//! The per-record coupling of a surface that evaporates: from its
//! aerodynamic and canopy parameters and the weather at one record, the
//! [`TurbulentExchange`] whose sensible coefficient `ρc_p/r_a` replaces the
//! McAdams convection coefficient and whose vapour conductance
//! `ρc_p/(γ(r_a + r_s))` is the latent term of the slab model's front law
//! (issue 16, step 2 of the plan; the thermal solve calls
//! [`SurfaceEnergy::exchange_at`] once per record).
//!
//! Stability is evaluated at a surface temperature the caller gives (the
//! plan: the previous record's surface temperature, lagged), so the
//! exchange stays a fixed law within a step and the slab's Newton solve
//! sees only `e°(T)` as new nonlinearity.

use super::aerodynamic::{CanopyKb, kb_inverse_su2001};
use super::{
    Aerodynamic, AirState, CanopyConditions, InputError, JarvisStewart, TurbulentExchange,
    in_range, positive,
};

/// What resists vapour leaving the surface (the r_s of Penman–Monteith).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SurfaceResistance {
    /// A transpiring canopy: the Jarvis–Stewart stomatal resistance.
    Canopy(JarvisStewart),
    /// Bare soil drying from the top: r_s = 10·exp(0.3563·(15 − θ)) s m⁻¹
    /// for θ < 15 % (volumetric, in percent), 10 s m⁻¹ above (van de Griend
    /// & Owe 1994, "Bare soil surface resistance to evaporation by vapor
    /// diffusion under semiarid conditions", Water Resour. Res. 30(2):181–188,
    /// doi:10.1029/93WR02747, eq. 9 with θ_min = 15 %), θ the water content
    /// of the top 1–5 cm.
    BareSoil,
    /// An open water surface (a pond, or a surface wetted by rain): r_s = 0.
    Open,
}

impl SurfaceResistance {
    /// r_s under the conditions `c`, s m⁻¹ (+∞: no evaporation).
    pub fn resistance_s_m(&self, c: &CanopyConditions) -> f64 {
        match self {
            SurfaceResistance::Canopy(js) => js.surface_resistance_s_m(c),
            SurfaceResistance::BareSoil => bare_soil_resistance_s_m(c.soil_moisture_m3_m3),
            SurfaceResistance::Open => 0.0,
        }
    }
}

/// Bare-soil surface resistance of van de Griend & Owe (1994), s m⁻¹
/// ([`SurfaceResistance::BareSoil`]), at volumetric water content `theta`
/// (m³ m⁻³).
pub fn bare_soil_resistance_s_m(theta_m3_m3: f64) -> f64 {
    let pct = 100.0 * theta_m3_m3;
    if pct >= 15.0 {
        10.0
    } else {
        10.0 * (0.3563 * (15.0 - pct)).exp()
    }
}

/// A surface's turbulent-exchange parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceEnergy {
    /// Heights and roughness of the aerodynamic resistance.
    pub aerodynamic: Aerodynamic,
    /// The surface resistance.
    pub resistance: SurfaceResistance,
    /// Volumetric water content of the root zone θ, m³ m⁻³ (constant: no
    /// soil water budget).
    pub soil_moisture_m3_m3: f64,
    /// The canopy whose kB⁻¹ sets the roughness length for heat at each
    /// record ([`kb_inverse_su2001`]); None: the aerodynamic geometry's
    /// fixed z_oh (FAO-56: z_om/10, kB⁻¹ = 2.3).
    pub canopy_kb: Option<CanopyKb>,
}

impl SurfaceEnergy {
    /// Checks the parts; errors name the field.
    ///
    /// # Errors
    /// [`InputError`] from [`JarvisStewart::validate`] or a soil moisture
    /// outside 0..=1.
    pub fn new(
        aerodynamic: Aerodynamic,
        resistance: SurfaceResistance,
        soil_moisture_m3_m3: f64,
    ) -> Result<SurfaceEnergy, InputError> {
        if let SurfaceResistance::Canopy(js) = &resistance {
            js.validate()?;
        }
        in_range("soil_moisture_m3_m3", soil_moisture_m3_m3, 0.0, 1.0)?;
        Ok(SurfaceEnergy {
            aerodynamic,
            resistance,
            soil_moisture_m3_m3,
            canopy_kb: None,
        })
    }

    /// The same surface with the roughness length for heat of each record
    /// from the canopy's kB⁻¹ (Su et al. 2001, [`kb_inverse_su2001`])
    /// instead of the fixed z_oh of its geometry.
    ///
    /// # Errors
    /// [`InputError`] naming the field: a leaf area index < 0, a leaf width
    /// ≤ 0, or a canopy height ≤ 0 with leaves.
    pub fn with_canopy_kb(mut self, canopy: CanopyKb) -> Result<SurfaceEnergy, InputError> {
        super::non_negative("leaf_area_index", canopy.leaf_area_index)?;
        positive("leaf_width_m", canopy.leaf_width_m)?;
        if canopy.leaf_area_index > 0.0 {
            positive("canopy_height_m", canopy.canopy_height_m)?;
        }
        self.canopy_kb = Some(canopy);
        Ok(self)
    }

    /// The aerodynamic geometry at one record: the fixed one, or with
    /// z_oh = z_om·exp(−kB⁻¹) from the canopy ([`SurfaceEnergy::with_canopy_kb`]).
    pub fn aerodynamic_at(&self, air: &AirState, wind_speed_m_s: f64) -> Aerodynamic {
        let a = self.aerodynamic;
        let Some(canopy) = &self.canopy_kb else {
            return a;
        };
        let kb = kb_inverse_su2001(
            canopy,
            wind_speed_m_s,
            a.wind_height_m(),
            a.displacement_height_m(),
            a.roughness_momentum_m(),
            air.temperature_k(),
            air.pressure_pa(),
        );
        // z_oh ≤ z_om < z − d: the geometry stays valid.
        Aerodynamic::new(
            a.wind_height_m(),
            a.air_height_m(),
            a.displacement_height_m(),
            a.roughness_momentum_m(),
            a.roughness_momentum_m() * (-kb).exp(),
        )
        .unwrap_or(a)
    }

    /// The exchange with `air` at wind speed `wind_speed_m_s` and global
    /// shortwave `shortwave_down_w_m2` (W m⁻²), with the stability of a
    /// surface at `surface_temperature_k`: r_a from
    /// [`Aerodynamic::resistance_s_m`] (FAO-56 eq. 4, Louis 1979), r_s from
    /// [`SurfaceResistance::resistance_s_m`].
    ///
    /// # Errors
    /// [`InputError`] when the resistances are not usable (a NaN input).
    pub fn exchange_at(
        &self,
        air: AirState,
        wind_speed_m_s: f64,
        shortwave_down_w_m2: f64,
        surface_temperature_k: f64,
    ) -> Result<TurbulentExchange, InputError> {
        let r_a = self.aerodynamic_at(&air, wind_speed_m_s).resistance_s_m(
            wind_speed_m_s,
            surface_temperature_k,
            air.temperature_k(),
        );
        let r_s = self.resistance.resistance_s_m(&CanopyConditions {
            shortwave_down_w_m2: shortwave_down_w_m2.max(0.0),
            vapour_pressure_deficit_pa: air.vapour_pressure_deficit_pa(),
            air_temperature_k: air.temperature_k(),
            soil_moisture_m3_m3: self.soil_moisture_m3_m3,
        });
        TurbulentExchange::new(air, r_a, r_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grass() -> SurfaceEnergy {
        SurfaceEnergy::new(
            Aerodynamic::from_canopy_height(0.12, 2.0, 2.0).unwrap(),
            SurfaceResistance::Canopy(JarvisStewart {
                min_stomatal_resistance_s_m: 40.0,
                max_stomatal_resistance_s_m: 5000.0,
                leaf_area_index: 2.88,
                shortwave_limit_w_m2: 30.0,
                vpd_sensitivity_per_pa: 0.0,
                optimum_temperature_k: 298.0,
                temperature_sensitivity_per_k2: 0.0016,
                wilting_point_m3_m3: 0.1,
                field_capacity_m3_m3: 0.3,
            }),
            0.3,
        )
        .unwrap()
    }

    /// Midday sun opens the stomata: the latent conductance is larger than
    /// at night, and the sensible coefficient of a neutral surface is the
    /// FAO-56 grass value ρc_p·u/208 at 2 m.
    #[test]
    fn sun_opens_the_canopy_and_neutral_r_a_is_fao56() {
        let g = grass();
        let air = AirState::from_relative_humidity(298.0, 0.5, 101_325.0).unwrap();
        let day = g.exchange_at(air, 2.0, 800.0, 298.0).unwrap();
        let night = g.exchange_at(air, 2.0, 0.0, 298.0).unwrap();
        assert!(day.vapour_conductance_w_m2_pa() > 5.0 * night.vapour_conductance_w_m2_pa());
        assert!((day.aerodynamic_resistance_s_m() - 104.0).abs() < 1.0);
        // An unstable (warm) surface exchanges more than a neutral one.
        let warm = g.exchange_at(air, 2.0, 800.0, 308.0).unwrap();
        assert!(warm.sensible_coefficient_w_m2_k() > day.sensible_coefficient_w_m2_k());
    }

    /// van de Griend & Owe (1994): 10 s/m at and above 15 % water, rising
    /// by e^0.3563 per percent below (≈ 350 s/m at 5 %).
    #[test]
    fn bare_soil_resistance_follows_van_de_griend_and_owe() {
        assert_eq!(bare_soil_resistance_s_m(0.20), 10.0);
        assert_eq!(bare_soil_resistance_s_m(0.15), 10.0);
        let r5 = bare_soil_resistance_s_m(0.05);
        assert!((r5 - 10.0 * (3.563f64).exp()).abs() < 1e-9, "{r5}");
        assert!(bare_soil_resistance_s_m(0.10) < r5);
    }

    #[test]
    fn soil_moisture_out_of_range_names_the_field() {
        let g = grass();
        let e = SurfaceEnergy::new(g.aerodynamic, g.resistance, 1.5).unwrap_err();
        assert_eq!(e.field(), "soil_moisture_m3_m3");
    }
}
