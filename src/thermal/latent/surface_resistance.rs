//! Jarvis–Stewart surface (canopy) resistance: the stomata's resistance to
//! vapour leaving a big-leaf canopy, opening with sunlight and closing with
//! dry air, dry soil and temperatures away from an optimum.
//!
//! r_s = r_s,min / LAI × f_sun⁻¹ × f_vpd⁻¹ × f_soil⁻¹ × f_T⁻¹  [s m⁻¹]
//!
//! after Jarvis (1976), Phil. Trans. R. Soc. B 273:593–610,
//! doi:10.1098/rstb.1976.0035, and Stewart (1988), Agric. For. Meteorol.
//! 43:19–35, doi:10.1016/0168-1923(88)90003-2, with the stress functions of
//! Noilhan & Planton (1989), "A simple parameterization of land surface
//! processes for meteorological models", Mon. Wea. Rev. 117:536–549,
//! doi:10.1175/1520-0493(1989)117<0536:ASPOLS>2.0.CO;2 (NP89):
//!
//! - sunlight: f_sun = (f + r_s,min/r_s,max) / (1 + f),
//!   f = 0.55 (S↓ / S_L) (2 / LAI), S↓ the global shortwave irradiance and
//!   S_L a limit (30 W m⁻² for crops, 100 W m⁻² for forest in NP89); in the
//!   dark r_s = r_s,max / LAI;
//! - soil moisture: f_soil = (θ − θ_wilt) / (θ_fc − θ_wilt) clamped to 0..1,
//!   θ the volumetric water content of the root zone;
//! - vapour-pressure deficit: f_vpd = 1 − g_D D clamped to 0..1 (NP89 write it
//!   with the specific-humidity deficit; D here is the vapour-pressure deficit
//!   in Pa, so g_D is per Pa);
//! - temperature: f_T = 1 − a_T (T_opt − T_a)² clamped to 0..1 (NP89:
//!   a_T = 0.0016 K⁻², T_opt = 298 K, after Dickinson 1984).
//!
//! A factor at 0 (stomata shut, or no leaves) gives r_s = +∞, and the
//! Penman–Monteith latent flux then goes to 0 smoothly.

use super::{InputError, in_range, non_negative, positive};

/// The parameters of a Jarvis–Stewart canopy. Check them with
/// [`JarvisStewart::validate`] (the material loader does) before use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JarvisStewart {
    /// Minimum stomatal (leaf) resistance r_s,min, s m⁻¹ (NP89: about 40 for
    /// crops and grass, 150 for forest).
    pub min_stomatal_resistance_s_m: f64,
    /// Maximum (cuticular) resistance r_s,max, s m⁻¹ (NP89: 5000).
    pub max_stomatal_resistance_s_m: f64,
    /// Leaf area index taking part in transpiration, m² m⁻² (≥ 0; 0: no
    /// leaves, r_s = +∞).
    pub leaf_area_index: f64,
    /// Shortwave limit S_L of the sunlight response, W m⁻² (NP89: 30 crops,
    /// 100 forest).
    pub shortwave_limit_w_m2: f64,
    /// Sensitivity g_D to the vapour-pressure deficit, Pa⁻¹ (0: none).
    pub vpd_sensitivity_per_pa: f64,
    /// Optimum air temperature T_opt, K (NP89: 298).
    pub optimum_temperature_k: f64,
    /// Curvature a_T of the temperature response, K⁻² (NP89: 0.0016).
    pub temperature_sensitivity_per_k2: f64,
    /// Volumetric water content at the wilting point θ_wilt, m³ m⁻³.
    pub wilting_point_m3_m3: f64,
    /// Volumetric water content at field capacity θ_fc, m³ m⁻³ (> θ_wilt).
    pub field_capacity_m3_m3: f64,
}

/// The conditions the canopy responds to at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CanopyConditions {
    /// Global shortwave irradiance on the canopy S↓, W m⁻².
    pub shortwave_down_w_m2: f64,
    /// Vapour-pressure deficit of the air D, Pa.
    pub vapour_pressure_deficit_pa: f64,
    /// Air temperature T_a, K.
    pub air_temperature_k: f64,
    /// Volumetric water content of the root zone θ, m³ m⁻³.
    pub soil_moisture_m3_m3: f64,
}

/// The four stress factors, each 0 (shut) to 1 (no stress).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StressFactors {
    /// f_sun.
    pub sunlight: f64,
    /// f_vpd.
    pub vapour_pressure_deficit: f64,
    /// f_soil.
    pub soil_moisture: f64,
    /// f_T.
    pub temperature: f64,
}

impl StressFactors {
    /// The product f_sun f_vpd f_soil f_T.
    pub fn product(&self) -> f64 {
        self.sunlight * self.vapour_pressure_deficit * self.soil_moisture * self.temperature
    }
}

impl JarvisStewart {
    /// Check every parameter.
    ///
    /// # Errors
    /// [`InputError`] naming the field: a negative resistance or LAI, a
    /// maximum resistance not above the minimum, a non-positive shortwave
    /// limit, a negative sensitivity, water contents outside 0..1 or a field
    /// capacity not above the wilting point, anything not finite.
    pub fn validate(&self) -> Result<(), InputError> {
        non_negative(
            "min_stomatal_resistance_s_m",
            self.min_stomatal_resistance_s_m,
        )?;
        positive(
            "max_stomatal_resistance_s_m",
            self.max_stomatal_resistance_s_m,
        )?;
        if self.max_stomatal_resistance_s_m <= self.min_stomatal_resistance_s_m {
            return Err(InputError::OutOfRange {
                field: "max_stomatal_resistance_s_m",
                value: self.max_stomatal_resistance_s_m,
                expected: format!(
                    "above min_stomatal_resistance_s_m = {}",
                    self.min_stomatal_resistance_s_m
                ),
            });
        }
        non_negative("leaf_area_index", self.leaf_area_index)?;
        positive("shortwave_limit_w_m2", self.shortwave_limit_w_m2)?;
        non_negative("vpd_sensitivity_per_pa", self.vpd_sensitivity_per_pa)?;
        in_range(
            "optimum_temperature_k",
            self.optimum_temperature_k,
            250.0,
            330.0,
        )?;
        non_negative(
            "temperature_sensitivity_per_k2",
            self.temperature_sensitivity_per_k2,
        )?;
        in_range("wilting_point_m3_m3", self.wilting_point_m3_m3, 0.0, 1.0)?;
        in_range("field_capacity_m3_m3", self.field_capacity_m3_m3, 0.0, 1.0)?;
        if self.field_capacity_m3_m3 <= self.wilting_point_m3_m3 {
            return Err(InputError::OutOfRange {
                field: "field_capacity_m3_m3",
                value: self.field_capacity_m3_m3,
                expected: format!("above wilting_point_m3_m3 = {}", self.wilting_point_m3_m3),
            });
        }
        Ok(())
    }

    /// The stress factors under `c` (module docs), each in 0..1.
    pub fn stress_factors(&self, c: &CanopyConditions) -> StressFactors {
        let lai = self.leaf_area_index;
        let ratio = self.min_stomatal_resistance_s_m / self.max_stomatal_resistance_s_m;
        let sunlight = if lai > 0.0 {
            let f =
                0.55 * (c.shortwave_down_w_m2.max(0.0) / self.shortwave_limit_w_m2) * (2.0 / lai);
            (f + ratio) / (1.0 + f)
        } else {
            0.0
        };
        let soil_moisture = ((c.soil_moisture_m3_m3 - self.wilting_point_m3_m3)
            / (self.field_capacity_m3_m3 - self.wilting_point_m3_m3))
            .clamp(0.0, 1.0);
        let vapour_pressure_deficit = (1.0
            - self.vpd_sensitivity_per_pa * c.vapour_pressure_deficit_pa.max(0.0))
        .clamp(0.0, 1.0);
        let dt = self.optimum_temperature_k - c.air_temperature_k;
        let temperature = (1.0 - self.temperature_sensitivity_per_k2 * dt * dt).clamp(0.0, 1.0);
        StressFactors {
            sunlight,
            vapour_pressure_deficit,
            soil_moisture,
            temperature,
        }
    }

    /// Surface resistance r_s under `c`, s m⁻¹ (module docs): +∞ when a
    /// stress factor is 0 or there are no leaves.
    pub fn surface_resistance_s_m(&self, c: &CanopyConditions) -> f64 {
        debug_assert!(self.validate().is_ok(), "{:?}", self.validate());
        let f = self.stress_factors(c).product();
        if f <= 0.0 || self.leaf_area_index <= 0.0 {
            return f64::INFINITY;
        }
        self.min_stomatal_resistance_s_m / (self.leaf_area_index * f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn crop() -> JarvisStewart {
        JarvisStewart {
            min_stomatal_resistance_s_m: 40.0,
            max_stomatal_resistance_s_m: 5000.0,
            leaf_area_index: 3.0,
            shortwave_limit_w_m2: 30.0,
            vpd_sensitivity_per_pa: 1.5e-4,
            optimum_temperature_k: 298.0,
            temperature_sensitivity_per_k2: 0.0016,
            wilting_point_m3_m3: 0.1,
            field_capacity_m3_m3: 0.35,
        }
    }

    fn noon() -> CanopyConditions {
        CanopyConditions {
            shortwave_down_w_m2: 800.0,
            vapour_pressure_deficit_pa: 1000.0,
            air_temperature_k: 298.0,
            soil_moisture_m3_m3: 0.35,
        }
    }

    #[test]
    fn an_unstressed_sunlit_canopy_approaches_the_minimum() {
        let mut j = crop();
        j.vpd_sensitivity_per_pa = 0.0;
        let floor = j.min_stomatal_resistance_s_m / j.leaf_area_index;
        // At noon, NP89's sunlight factor: r_s = (r_min/LAI)(1 + f)/(f + r_min/r_max).
        let r = j.surface_resistance_s_m(&noon());
        let f = 0.55 * (800.0 / 30.0) * (2.0 / 3.0);
        let expect = floor * (1.0 + f) / (f + 40.0 / 5000.0);
        assert!(
            (r - expect).abs() < 1e-9 * expect,
            "r_s = {r}, expected {expect}"
        );
        // Ever brighter light: r_s → r_min / LAI from above.
        let bright = CanopyConditions {
            shortwave_down_w_m2: 1e6,
            ..noon()
        };
        let r = j.surface_resistance_s_m(&bright);
        assert!(r > floor && r < 1.001 * floor, "r_s = {r}, floor {floor}");
    }

    #[test]
    fn the_canopy_closes_in_the_dark_in_dry_air_dry_soil_and_heat() {
        let j = crop();
        let base = j.surface_resistance_s_m(&noon());
        // Night: r_s,max / LAI.
        let dark = CanopyConditions {
            shortwave_down_w_m2: 0.0,
            ..noon()
        };
        let r = j.surface_resistance_s_m(&dark);
        let f = j.stress_factors(&dark);
        let expect = j.max_stomatal_resistance_s_m
            / j.leaf_area_index
            / (f.vapour_pressure_deficit * f.soil_moisture * f.temperature);
        assert!((r - expect).abs() < 1e-9 * expect, "{r} vs {expect}");
        // Each stress raises r_s monotonically.
        let dry_air = CanopyConditions {
            vapour_pressure_deficit_pa: 3000.0,
            ..noon()
        };
        assert!(j.surface_resistance_s_m(&dry_air) > base);
        let drier = CanopyConditions {
            soil_moisture_m3_m3: 0.2,
            ..noon()
        };
        assert!(j.surface_resistance_s_m(&drier) > base);
        let hot = CanopyConditions {
            air_temperature_k: 310.0,
            ..noon()
        };
        assert!(j.surface_resistance_s_m(&hot) > base);
        // Wilted soil, or no leaves: shut.
        let wilted = CanopyConditions {
            soil_moisture_m3_m3: 0.05,
            ..noon()
        };
        assert_eq!(j.surface_resistance_s_m(&wilted), f64::INFINITY);
        let bare = JarvisStewart {
            leaf_area_index: 0.0,
            ..j
        };
        assert_eq!(bare.surface_resistance_s_m(&noon()), f64::INFINITY);
    }

    #[test]
    fn bad_parameters_are_errors_naming_the_field() {
        let e = JarvisStewart {
            leaf_area_index: -1.0,
            ..crop()
        }
        .validate()
        .unwrap_err();
        assert_eq!(
            e,
            InputError::Negative {
                field: "leaf_area_index",
                value: -1.0
            }
        );
        let e = JarvisStewart {
            min_stomatal_resistance_s_m: -5.0,
            ..crop()
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.field(), "min_stomatal_resistance_s_m");
        let e = JarvisStewart {
            max_stomatal_resistance_s_m: 10.0,
            ..crop()
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.field(), "max_stomatal_resistance_s_m");
        let e = JarvisStewart {
            field_capacity_m3_m3: 0.05,
            ..crop()
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.field(), "field_capacity_m3_m3");
        let e = JarvisStewart {
            shortwave_limit_w_m2: 0.0,
            ..crop()
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.field(), "shortwave_limit_w_m2");
        let e = JarvisStewart {
            vpd_sensitivity_per_pa: f64::NAN,
            ..crop()
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.field(), "vpd_sensitivity_per_pa");
        assert!(crop().validate().is_ok());
    }
}
