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

/// Prandtl number of air (Su et al. 2001; Massman 1999), dimensionless.
pub const PRANDTL_AIR: f64 = 0.71;

/// The canopy of [`kb_inverse_su2001`]: what sets the excess resistance to
/// heat of a partly vegetated surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CanopyKb {
    /// One-sided leaf area index, m² m⁻² (0: bare soil).
    pub leaf_area_index: f64,
    /// Canopy height h, m (> 0 with leaves).
    pub canopy_height_m: f64,
    /// Characteristic leaf dimension D_l, m (> 0), for the leaf Reynolds
    /// number of the leaf heat-transfer coefficient.
    pub leaf_width_m: f64,
}

/// Foliage drag coefficient C_d (Su et al. 2001; Massman 1997), dimensionless.
pub const FOLIAGE_DRAG: f64 = 0.2;
/// Roughness height of the soil under the canopy h_s, m (Su et al. 2001,
/// after Su et al. 1997: 0.009–0.024 m).
pub const SOIL_ROUGHNESS_HEIGHT_M: f64 = 0.009;

/// Kinematic viscosity of air ν, m² s⁻¹, at `temperature_k` and
/// `pressure_pa`: ν = 1.327·10⁻⁵ (p₀/p)(T/T₀)^1.81, p₀ = 101 325 Pa,
/// T₀ = 273.15 K (Massman 1999b, as used by Su et al. 2001).
pub fn kinematic_viscosity_m2_s(temperature_k: f64, pressure_pa: f64) -> f64 {
    1.327e-5 * (101_325.0 / pressure_pa) * (temperature_k / 273.15).powf(1.81)
}

/// Fractional vegetation cover seen from nadir, f_c = 1 − exp(−0.5 Ω LAI)
/// with a random leaf distribution (clumping Ω = 1, spherical leaf angles:
/// extinction 0.5/cos θ at θ = 0; Norman, Kustas & Humes 1995, Agric. For.
/// Meteorol. 77:263, eq. 3), dimensionless.
pub fn nadir_cover_fraction(leaf_area_index: f64) -> f64 {
    1.0 - (-0.5 * leaf_area_index.max(0.0)).exp()
}

/// The excess resistance parameter kB⁻¹ = ln(z_om/z_oh) of a partly
/// vegetated surface, dimensionless: the model of Su, Schmugge, Kustas &
/// Massman (2001), "An evaluation of two models for estimation of the
/// roughness height for heat transfer between the land surface and the
/// atmosphere", J. Appl. Meteorol. 40:1933–1951 (as used in SEBS, Su 2002,
/// Hydrol. Earth Syst. Sci. 6:85, eq. 15), a surrogate of Massman's (1999)
/// localized near-field model weighting a full-canopy, a mixed and a
/// bare-soil part by the cover fraction f_c ([`nadir_cover_fraction`]),
/// f_s = 1 − f_c:
///
/// ```text
/// kB⁻¹ = f_c² · k C_d / (4 C_t (u*/u_h) (1 − e^(−n_ec/2)))      (Choudhury & Monteith 1988)
///      + 2 f_c f_s · k (u*/u_h) (z_om/h) / C_t*
///      + f_s² · (2.46 Re_s^¼ − ln 7.4)                            (Brutsaert 1982, bare soil)
/// u*/u_h = 0.32 − 0.264 exp(−15.1 C_d LAI)                       (Massman 1997)
/// n_ec   = C_d LAI / (2 (u*/u_h)²)                                (within-canopy wind extinction)
/// C_t    = N Pr^(−2/3) Re_l^(−1/2),  Re_l = D_l u_h / ν, N = 2    (leaf; Massman 1999)
/// C_t*   = Pr^(−2/3) Re_m^(−1/2),    Re_m = u* h / ν              (SEBS reference code)
/// Re_s   = h_s u*_s / ν,  u*_s = k u / ln(z_m / h_s)              (soil, h_s = 0.009 m)
/// ```
///
/// with C_d = 0.2, Pr = 0.71, k = 0.41, the wind `wind_speed_m_s` at
/// `wind_height_m` over a surface of displacement `displacement_height_m`
/// and momentum roughness `roughness_momentum_m`, u_h the neutral log
/// profile's wind at the canopy top and u* = (u*/u_h)·u_h; ν from
/// [`kinematic_viscosity_m2_s`]. Clamped to ≥ 0. A closed canopy
/// (LAI → ∞) tends to the first term (≈ 1.5 for a 1 m crop of 4 cm leaves
/// at 3 m/s: with Massman's leaf coefficient C_t ≈ 0.06, at the low end of
/// the homogeneous-canopy ≈ 2; SEBS's fixed C_t = 0.01 would give ≈ 8);
/// bare soil (LAI = 0) is Brutsaert's, 4–7 at field wind speeds; between
/// them kB⁻¹ falls as the cover closes.
#[allow(clippy::too_many_arguments)]
pub fn kb_inverse_su2001(
    canopy: &CanopyKb,
    wind_speed_m_s: f64,
    wind_height_m: f64,
    displacement_height_m: f64,
    roughness_momentum_m: f64,
    air_temperature_k: f64,
    pressure_pa: f64,
) -> f64 {
    let k = VON_KARMAN;
    let u = calm_is_zero(wind_speed_m_s).max(0.1);
    let nu = kinematic_viscosity_m2_s(air_temperature_k, pressure_pa);
    let pr = PRANDTL_AIR.powf(-2.0 / 3.0);
    let lai = canopy.leaf_area_index.max(0.0);
    let fc = nadir_cover_fraction(lai);
    let fs = 1.0 - fc;
    // Bare soil (Brutsaert 1982).
    let u_star_s = k * u / (wind_height_m / SOIL_ROUGHNESS_HEIGHT_M).ln();
    let re_s = SOIL_ROUGHNESS_HEIGHT_M * u_star_s / nu;
    let kb_s = 2.46 * re_s.powf(0.25) - 7.4f64.ln();
    if lai == 0.0 {
        return kb_s.max(0.0);
    }
    let h = canopy.canopy_height_m;
    let ratio = 0.32 - 0.264 * (-15.1 * FOLIAGE_DRAG * lai).exp();
    let n_ec = FOLIAGE_DRAG * lai / (2.0 * ratio * ratio);
    // Neutral log-profile wind at the canopy top.
    let d = displacement_height_m;
    let z0 = roughness_momentum_m;
    let u_h = (u * ((h - d) / z0).ln() / ((wind_height_m - d) / z0).ln()).max(0.01);
    let u_star = ratio * u_h;
    let re_l = canopy.leaf_width_m * u_h / nu;
    let c_t = 2.0 * pr / re_l.sqrt();
    let kb_c = k * FOLIAGE_DRAG / (4.0 * c_t * ratio * (1.0 - (-0.5 * n_ec).exp()));
    let re_m = u_star * h / nu;
    let c_t_star = pr / re_m.sqrt();
    let kb_m = k * ratio * (z0 / h) / c_t_star;
    (fc * fc * kb_c + 2.0 * fc * fs * kb_m + fs * fs * kb_s).max(0.0)
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

    /// Air at 300 K and 1 atm: ν = 15.89·10⁻⁶ m²/s (Incropera et al.,
    /// Fundamentals of Heat and Mass Transfer, 6th ed., Table A.4);
    /// Massman's fit is within 1.1 %.
    #[test]
    fn kinematic_viscosity_matches_the_air_table() {
        let nu = kinematic_viscosity_m2_s(300.0, 101_325.0);
        assert!((nu / 15.89e-6 - 1.0).abs() < 0.015, "{nu}");
        // Half the pressure, twice the viscosity.
        assert!((kinematic_viscosity_m2_s(300.0, 50_662.5) / nu - 2.0).abs() < 1e-12);
    }

    fn crop(lai: f64) -> CanopyKb {
        CanopyKb {
            leaf_area_index: lai,
            canopy_height_m: 1.0,
            leaf_width_m: 0.04,
        }
    }

    /// kB⁻¹ of Su et al. (2001) at wind `u` (10 m) over a 1 m crop with
    /// FAO-56's geometry (d = 2/3 h, z_om = 0.123 h), air 300 K, 1 atm.
    fn kb(lai: f64, u: f64) -> f64 {
        kb_inverse_su2001(&crop(lai), u, 10.0, 2.0 / 3.0, 0.123, 300.0, 101_325.0)
    }

    /// The limits of the model are its three published parts: bare soil
    /// (LAI = 0) is Brutsaert's (1982) 2.46 Re_s^¼ − ln 7.4; a closed
    /// canopy (LAI → ∞, f_c → 1) is Choudhury & Monteith's canopy term
    /// with u*/u_h → 0.32 and n_ec → ∞.
    #[test]
    fn su2001_kb_inverse_has_the_bare_soil_and_closed_canopy_limits() {
        let (u, nu) = (3.0, kinematic_viscosity_m2_s(300.0, 101_325.0));
        // Bare soil, computed from the formula's definitions.
        let u_star_s = VON_KARMAN * u / (10.0f64 / 0.009).ln();
        let re_s = 0.009 * u_star_s / nu;
        let brutsaert = 2.46 * re_s.powf(0.25) - 7.4f64.ln();
        assert!((kb(0.0, u) - brutsaert).abs() < 1e-12, "{}", kb(0.0, u));
        assert!((4.0..8.0).contains(&brutsaert), "{brutsaert}");
        // Closed canopy: f_c = 1 − e^(−LAI/2) → 1, the canopy term alone.
        let u_h = u * ((1.0f64 / 3.0) / 0.123).ln() / ((10.0 - 2.0 / 3.0) / 0.123f64).ln();
        let c_t = 2.0 * PRANDTL_AIR.powf(-2.0 / 3.0) / (0.04 * u_h / nu).sqrt();
        let closed = VON_KARMAN * FOLIAGE_DRAG / (4.0 * c_t * 0.32);
        let k60 = kb(60.0, u);
        assert!((k60 - closed).abs() < 1e-6 * closed, "{k60} vs {closed}");
        // A closed crop's kB⁻¹ is of the order of the homogeneous-canopy
        // value ≈ 2 (Garratt & Hicks 1973, QJRMS 99:680).
        assert!((1.0..3.5).contains(&kb(6.0, u)), "{}", kb(6.0, u));
        // Leaves make a rougher heat sink than the soil: kB⁻¹ falls as
        // the cover closes, from the bare-soil value.
        let mut last = kb(0.0, u);
        for lai in [0.5, 1.0, 2.0, 3.0, 5.0, 8.0] {
            let v = kb(lai, u);
            assert!(v < last, "LAI {lai}: {v} !< {last}");
            last = v;
        }
    }

    /// Finite and non-negative for any wind, calm included.
    #[test]
    fn su2001_kb_inverse_is_finite_at_any_wind() {
        for u in [0.0, 0.1, 0.5, 2.0, 10.0, 30.0, f64::NAN] {
            for lai in [0.0, 0.3, 3.0, 10.0] {
                let v = kb(lai, u);
                assert!(v.is_finite() && v >= 0.0, "u {u} LAI {lai}: {v}");
            }
        }
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
