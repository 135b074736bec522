//! Aerodynamic resistance to heat and vapour transfer between a surface and
//! the air at the measurement height, with a stability correction.
//!
//! Neutral: FAO-56 eq. 4 (Allen et al. 1998, chapter 2, "Aerodynamic
//! resistance"), the log wind profile,
//!
//! r_a,n = ln((z_m − d)/z_om) · ln((z_h − d)/z_oh) / (k² u_z)  [s m⁻¹],
//!
//! z_m, z_h heights of the wind and of the temperature/humidity measurement,
//! d displacement height, z_om, z_oh roughness lengths for momentum and heat,
//! k = 0.41, u_z wind speed at z_m.
//!
//! Stability: r_a = r_a,n / F_h(Ri_b) with the bulk Richardson number
//!
//! Ri_b = g (z_m − d) (T_a − T_s) / (T_a u_z²)
//!
//! (virtual-temperature effects of humidity neglected) and the heat-transfer
//! stability functions of Louis (1979), "A parametric model of vertical eddy
//! fluxes in the atmosphere", Boundary-Layer Meteorology 17:187–202,
//! doi:10.1007/BF00117978, in the form with b = c = d = 5 of Louis, Tiedtke
//! & Geleyn (1982, ECMWF Workshop on Planetary Boundary Layer
//! Parameterization), and a² = k² / (ln((z_m−d)/z_om) ln((z_h−d)/z_oh)) the
//! neutral transfer coefficient:
//!
//! - unstable (Ri_b < 0, surface warmer than the air):
//!   F_h = 1 − 3b Ri_b / (1 + 3bc a² √(−Ri_b (z_m − d)/z_om));
//! - stable (Ri_b ≥ 0): F_h = 1 / (1 + 3b Ri_b √(1 + d Ri_b)).
//!
//! **Free-convection limit.** Writing s = √(g (z_m−d) (T_s−T_a)/T_a) (so that
//! −Ri_b = s²/u²), the unstable branch is exactly
//! r_a = 1 / (a² (u + 3b s² / (u + K s))), K = 3bc a² √((z_m−d)/z_om),
//! which is evaluated in that form: at calm wind (u = 0) it tends to the
//! finite free-convection value K / (3b a² s), with no division by zero.
//! In stable air at calm wind the exchange vanishes (r_a = +∞), as it does
//! with no wind and no temperature difference; a caller that wants some
//! residual exchange floors the wind speed.
//!
//! Accuracy: the log profile holds above the roughness sublayer; Louis'
//! functions are an analytic fit to Monin–Obukhov similarity (Businger–Dyer
//! profiles), explicit in Ri_b, not an exact solution of it.

use super::{InputError, non_negative, positive};

/// Von Kármán's constant, k = 0.41 (FAO-56 eq. 4).
pub const VON_KARMAN: f64 = 0.41;

/// Gravitational acceleration, m s⁻² (standard gravity).
pub const GRAVITY_M_S2: f64 = 9.806_65;

/// Louis (1979) constants b = c = d = 5.
const LOUIS_B: f64 = 5.0;
const LOUIS_C: f64 = 5.0;
const LOUIS_D: f64 = 5.0;

/// The aerodynamic geometry of a surface and of its measurements. Built by
/// [`Aerodynamic::new`] (which validates) or
/// [`Aerodynamic::from_canopy_height`] (FAO-56's rules of thumb).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aerodynamic {
    wind_height_m: f64,
    air_height_m: f64,
    displacement_height_m: f64,
    roughness_momentum_m: f64,
    roughness_heat_m: f64,
}

impl Aerodynamic {
    /// Heights of the wind (`wind_height_m`, z_m) and the air temperature /
    /// humidity (`air_height_m`, z_h) measurements, the displacement height
    /// d, and the roughness lengths for momentum z_om and heat z_oh, all in m
    /// above the ground.
    ///
    /// # Errors
    /// [`InputError`] naming the field: a height or roughness not finite or
    /// negative, a roughness length that is zero, or a roughness length not
    /// below its measurement height above d
    /// ([`InputError::RoughnessNotBelowHeight`]).
    pub fn new(
        wind_height_m: f64,
        air_height_m: f64,
        displacement_height_m: f64,
        roughness_momentum_m: f64,
        roughness_heat_m: f64,
    ) -> Result<Aerodynamic, InputError> {
        positive("wind_height_m", wind_height_m)?;
        positive("air_height_m", air_height_m)?;
        non_negative("displacement_height_m", displacement_height_m)?;
        positive("roughness_momentum_m", roughness_momentum_m)?;
        positive("roughness_heat_m", roughness_heat_m)?;
        for (field, z) in [
            ("wind_height_m", wind_height_m),
            ("air_height_m", air_height_m),
        ] {
            if z <= displacement_height_m {
                return Err(InputError::OutOfRange {
                    field,
                    value: z,
                    expected: format!("above the displacement height {displacement_height_m} m"),
                });
            }
        }
        for (field, z0, z) in [
            ("roughness_momentum_m", roughness_momentum_m, wind_height_m),
            ("roughness_heat_m", roughness_heat_m, air_height_m),
        ] {
            let above = z - displacement_height_m;
            if z0 >= above {
                return Err(InputError::RoughnessNotBelowHeight {
                    field,
                    roughness_m: z0,
                    height_above_displacement_m: above,
                });
            }
        }
        Ok(Aerodynamic {
            wind_height_m,
            air_height_m,
            displacement_height_m,
            roughness_momentum_m,
            roughness_heat_m,
        })
    }

    /// FAO-56's geometry for a uniform crop of height `canopy_height_m`
    /// (chapter 2, after eq. 4): d = 2/3 h, z_om = 0.123 h, z_oh = 0.1 z_om.
    ///
    /// # Errors
    /// As [`Aerodynamic::new`]; a height ≤ 0 is [`InputError::OutOfRange`]
    /// on `canopy_height_m`.
    pub fn from_canopy_height(
        canopy_height_m: f64,
        wind_height_m: f64,
        air_height_m: f64,
    ) -> Result<Aerodynamic, InputError> {
        positive("canopy_height_m", canopy_height_m)?;
        let z_om = 0.123 * canopy_height_m;
        Aerodynamic::new(
            wind_height_m,
            air_height_m,
            2.0 / 3.0 * canopy_height_m,
            z_om,
            0.1 * z_om,
        )
    }

    /// Height of the wind measurement z_m, m.
    pub fn wind_height_m(&self) -> f64 {
        self.wind_height_m
    }
    /// Height of the air temperature / humidity measurement z_h, m.
    pub fn air_height_m(&self) -> f64 {
        self.air_height_m
    }
    /// Displacement height d, m.
    pub fn displacement_height_m(&self) -> f64 {
        self.displacement_height_m
    }
    /// Roughness length for momentum z_om, m.
    pub fn roughness_momentum_m(&self) -> f64 {
        self.roughness_momentum_m
    }
    /// Roughness length for heat and vapour z_oh, m.
    pub fn roughness_heat_m(&self) -> f64 {
        self.roughness_heat_m
    }

    /// The neutral transfer coefficient a² = k² / (ln((z_m−d)/z_om)
    /// ln((z_h−d)/z_oh)), dimensionless (so r_a,n = 1 / (a² u)).
    pub fn neutral_transfer_coefficient(&self) -> f64 {
        let d = self.displacement_height_m;
        let lm = ((self.wind_height_m - d) / self.roughness_momentum_m).ln();
        let lh = ((self.air_height_m - d) / self.roughness_heat_m).ln();
        VON_KARMAN * VON_KARMAN / (lm * lh)
    }

    /// Neutral aerodynamic resistance at wind speed `wind_speed_m_s` (at
    /// z_m), s m⁻¹ (FAO-56 eq. 4). +∞ at calm wind (u ≤ 0 or not finite).
    pub fn neutral_resistance_s_m(&self, wind_speed_m_s: f64) -> f64 {
        let u = calm_is_zero(wind_speed_m_s);
        if u == 0.0 {
            return f64::INFINITY;
        }
        1.0 / (self.neutral_transfer_coefficient() * u)
    }

    /// Bulk Richardson number Ri_b = g (z_m − d)(T_a − T_s) / (T_a u²) between
    /// the surface at `surface_temperature_k` and the air at
    /// `air_temperature_k`, dimensionless: negative when the surface is
    /// warmer (unstable). ±∞ at calm wind with a temperature difference, 0
    /// with none.
    pub fn bulk_richardson_number(
        &self,
        wind_speed_m_s: f64,
        surface_temperature_k: f64,
        air_temperature_k: f64,
    ) -> f64 {
        let dt = air_temperature_k - surface_temperature_k;
        if dt == 0.0 {
            return 0.0;
        }
        let u = calm_is_zero(wind_speed_m_s);
        GRAVITY_M_S2 * (self.wind_height_m - self.displacement_height_m) * dt
            / (air_temperature_k * u * u)
    }

    /// Louis (1979) stability factor for heat F_h at bulk Richardson number
    /// `ri` (module docs), dimensionless: 1 when neutral, > 1 unstable,
    /// < 1 stable; r_a = r_a,n / F_h.
    pub fn stability_factor_heat(&self, ri: f64) -> f64 {
        if ri < 0.0 {
            let a2 = self.neutral_transfer_coefficient();
            let z_over_z0 =
                (self.wind_height_m - self.displacement_height_m) / self.roughness_momentum_m;
            1.0 - 3.0 * LOUIS_B * ri
                / (1.0 + 3.0 * LOUIS_B * LOUIS_C * a2 * (-ri * z_over_z0).sqrt())
        } else {
            1.0 / (1.0 + 3.0 * LOUIS_B * ri * (1.0 + LOUIS_D * ri).sqrt())
        }
    }

    /// Aerodynamic resistance to heat and vapour, stability-corrected, s m⁻¹:
    /// r_a,n / F_h(Ri_b) (module docs), for wind speed `wind_speed_m_s` at
    /// z_m and the surface and air temperatures, K. Exactly the neutral
    /// [`Aerodynamic::neutral_resistance_s_m`] when the temperatures are
    /// equal. Finite at calm wind over a warmer surface (free convection);
    /// +∞ at calm wind over a colder or equally warm surface.
    pub fn resistance_s_m(
        &self,
        wind_speed_m_s: f64,
        surface_temperature_k: f64,
        air_temperature_k: f64,
    ) -> f64 {
        let u = calm_is_zero(wind_speed_m_s);
        let dt = surface_temperature_k - air_temperature_k;
        if dt > 0.0 {
            // Unstable: r_a = 1 / (a² (u + 3b s² / (u + K s))), division-free at u = 0.
            let a2 = self.neutral_transfer_coefficient();
            let z = self.wind_height_m - self.displacement_height_m;
            let s = (GRAVITY_M_S2 * z * dt / air_temperature_k).sqrt();
            let k = 3.0 * LOUIS_B * LOUIS_C * a2 * (z / self.roughness_momentum_m).sqrt();
            1.0 / (a2 * (u + 3.0 * LOUIS_B * s * s / (u + k * s)))
        } else if u == 0.0 {
            f64::INFINITY
        } else {
            let ri = self.bulk_richardson_number(u, surface_temperature_k, air_temperature_k);
            self.neutral_resistance_s_m(u) / self.stability_factor_heat(ri)
        }
    }
}

/// Wind speed with negative and non-finite values read as calm, m s⁻¹.
#[inline]
fn calm_is_zero(u: f64) -> f64 {
    if u.is_finite() { u.max(0.0) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grass() -> Aerodynamic {
        Aerodynamic::from_canopy_height(0.12, 2.0, 2.0).unwrap()
    }

    #[test]
    fn fao56_reference_grass_is_208_over_u2() {
        // FAO-56, chapter 2 (after eq. 4): for the 0.12 m reference grass with
        // wind and humidity at 2 m, r_a = 208 / u₂ s m⁻¹.
        let a = grass();
        for u in [0.5, 1.0, 2.0, 5.0] {
            assert_eq!((a.neutral_resistance_s_m(u) * u).round(), 208.0, "u = {u}");
        }
    }

    #[test]
    fn richardson_correction_is_neutral_at_zero_temperature_difference() {
        let a = grass();
        for u in [0.3, 1.0, 4.0] {
            for t in [270.0, 300.0, 320.0] {
                assert_eq!(a.bulk_richardson_number(u, t, t), 0.0);
                assert_eq!(a.stability_factor_heat(0.0), 1.0);
                assert_eq!(a.resistance_s_m(u, t, t), a.neutral_resistance_s_m(u));
            }
        }
        // And continuous through it.
        let (u, t) = (2.0, 300.0);
        let n = a.neutral_resistance_s_m(u);
        for dt in [1e-6, -1e-6] {
            let r = a.resistance_s_m(u, t + dt, t);
            assert!((r - n).abs() < 1e-3 * n, "ΔT = {dt}: {r} vs {n}");
        }
    }

    #[test]
    fn unstable_branch_matches_louis_closed_form() {
        // The division-free form equals r_a,n / F_h(Ri_b) wherever both exist.
        let a = grass();
        for (u, ts) in [(0.5, 310.0), (2.0, 305.0), (5.0, 300.5)] {
            let ri = a.bulk_richardson_number(u, ts, 300.0);
            assert!(ri < 0.0);
            let direct = a.neutral_resistance_s_m(u) / a.stability_factor_heat(ri);
            let r = a.resistance_s_m(u, ts, 300.0);
            assert!((r - direct).abs() < 1e-9 * direct, "{r} vs {direct}");
        }
    }

    #[test]
    fn unstable_lowers_and_stable_raises_the_resistance() {
        let a = grass();
        let n = a.neutral_resistance_s_m(2.0);
        assert!(a.resistance_s_m(2.0, 310.0, 300.0) < n);
        assert!(a.resistance_s_m(2.0, 290.0, 300.0) > n);
        // Stronger instability, lower resistance.
        assert!(a.resistance_s_m(2.0, 320.0, 300.0) < a.resistance_s_m(2.0, 310.0, 300.0));
    }

    #[test]
    fn free_convection_limit_is_finite_at_calm_wind() {
        let a = grass();
        let r0 = a.resistance_s_m(0.0, 310.0, 300.0);
        assert!(r0.is_finite() && r0 > 0.0, "r_a(u=0) = {r0}");
        // The limit is approached continuously.
        let r = a.resistance_s_m(1e-6, 310.0, 300.0);
        assert!((r - r0).abs() < 1e-4 * r0, "{r} vs {r0}");
        // Free convection: a 10 K excess gives h = ρ c_p / r_a of a few W m⁻² K⁻¹.
        let h = 1.17 * 1013.0 / r0;
        assert!((1.0..30.0).contains(&h), "h = {h}");
        // Calm and stable or isothermal: no exchange, no NaN.
        assert_eq!(a.resistance_s_m(0.0, 290.0, 300.0), f64::INFINITY);
        assert_eq!(a.resistance_s_m(0.0, 300.0, 300.0), f64::INFINITY);
        assert_eq!(a.resistance_s_m(-1.0, 300.0, 300.0), f64::INFINITY);
        assert_eq!(a.resistance_s_m(f64::NAN, 300.0, 300.0), f64::INFINITY);
    }

    #[test]
    fn bad_geometry_is_an_error_naming_the_field() {
        // Roughness at or above the measurement height above d.
        let e = Aerodynamic::new(2.0, 2.0, 0.0, 2.0, 0.01).unwrap_err();
        assert_eq!(e.field(), "roughness_momentum_m");
        assert!(matches!(e, InputError::RoughnessNotBelowHeight { .. }));
        assert!(e.to_string().contains("roughness_momentum_m"), "{e}");
        let e = Aerodynamic::new(2.0, 2.0, 1.0, 0.1, 1.5).unwrap_err();
        assert_eq!(e.field(), "roughness_heat_m");
        // Negative, zero or NaN values.
        let e = Aerodynamic::new(2.0, 2.0, 0.0, -0.1, 0.01).unwrap_err();
        assert_eq!(
            e,
            InputError::Negative {
                field: "roughness_momentum_m",
                value: -0.1
            }
        );
        let e = Aerodynamic::new(2.0, 2.0, -0.5, 0.1, 0.01).unwrap_err();
        assert_eq!(e.field(), "displacement_height_m");
        let e = Aerodynamic::new(f64::NAN, 2.0, 0.0, 0.1, 0.01).unwrap_err();
        assert_eq!(e.field(), "wind_height_m");
        // Measurement below the displacement height.
        let e = Aerodynamic::new(2.0, 0.5, 1.0, 0.1, 0.01).unwrap_err();
        assert_eq!(e.field(), "air_height_m");
        // A crop taller than the tower.
        let e = Aerodynamic::from_canopy_height(3.5, 2.0, 2.0).unwrap_err();
        assert_eq!(e.field(), "wind_height_m");
        let e = Aerodynamic::from_canopy_height(0.0, 2.0, 2.0).unwrap_err();
        assert_eq!(e.field(), "canopy_height_m");
        // Into the crate's error, keeping the field.
        let e: crate::error::Error = e.into();
        assert!(e.to_string().starts_with("canopy_height_m"), "{e}");
    }
}
