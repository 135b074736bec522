//! A root-zone soil water budget: the volumetric water content θ(t) of a
//! bucket of depth `d_root` that rain wets and evapotranspiration dries, the
//! θ that the surface resistance sees (f_soil of the Jarvis–Stewart canopy,
//! the bare-soil resistance).
//!
//! The root-zone reservoir w₂ of ISBA (Noilhan & Planton 1989, "A simple
//! parameterization of land surface processes for meteorological models",
//! Mon. Wea. Rev. 117:536–549, the w₂ equation, without the force-restore surface
//! layer w_g) with the gravitational drainage of Mahfouf & Noilhan (1996),
//! "Inclusion of gravitational drainage in a land surface scheme based on
//! the force-restore method", J. Appl. Meteor. 35:987–992:
//!
//! ρ_w d_root dθ/dt = P_inf − E − ρ_w d_root (C₃/τ) max(0, θ − θ_fc)
//!
//! in kg m⁻² s⁻¹ (1 kg m⁻² of water = 1 mm), with ρ_w = 1000 kg m⁻³,
//! P_inf the rain that the surface store does not hold, E = LE/λ the
//! evaporation and transpiration of the step (negative: dew), τ = 1 day and
//! C₃ the drainage coefficient (Noilhan & Mahfouf 1996, "The ISBA land
//! surface parameterisation scheme", Global Planet. Change 13:145–159,
//! C₃ = 5.327·X_clay^−1.043, X_clay in %; loam, 18 % clay: C₃ = 0.261).
//!
//! Each step is split: infiltration and evaporation first (evaporation
//! limited to the water above the residual content), then the drainage
//! integrated exactly over the step (the excess above field capacity decays
//! as exp(−C₃ Δt/τ)), then any water above saturation runs off. Every term
//! is returned, so storage change = P_inf − E − D − R holds to rounding.

use super::{InputError, in_range, positive};

/// Density of liquid water, kg m⁻³ (1 mm of water per m² is 1 kg).
pub const WATER_DENSITY_KG_M3: f64 = 1000.0;

/// ISBA's drainage time scale τ, s (one day; Mahfouf & Noilhan 1996).
pub const DRAINAGE_TAU_S: f64 = 86_400.0;

/// ISBA's drainage coefficient C₃ of a loam (18 % clay; Noilhan & Mahfouf
/// 1996: C₃ = 5.327·X_clay^−1.043), dimensionless.
pub fn drainage_coefficient_c3(clay_pct: f64) -> f64 {
    5.327 * clay_pct.powf(-1.043)
}

/// Clay content of the loam the stock soils are, % (Clapp & Hornberger
/// 1978, Water Resour. Res. 14:601, Table 2 texture class, as ISBA's loam).
pub const LOAM_CLAY_PCT: f64 = 18.0;

/// The root-zone bucket (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RootZone {
    /// Depth d_root, m (> 0).
    pub depth_m: f64,
    /// Residual water content θ_r that evaporation cannot take, m³ m⁻³.
    pub residual_m3_m3: f64,
    /// Field capacity θ_fc, m³ m⁻³: drainage above it.
    pub field_capacity_m3_m3: f64,
    /// Saturation (porosity) θ_sat, m³ m⁻³: runoff above it.
    pub saturation_m3_m3: f64,
    /// Drainage coefficient C₃ (dimensionless; module docs).
    pub drainage_c3: f64,
}

/// One step of the bucket: the new θ and each flux of water over the step,
/// mm (kg m⁻²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaterStep {
    /// θ at the end of the step, m³ m⁻³.
    pub theta_m3_m3: f64,
    /// Rain that entered the bucket, mm.
    pub infiltration_mm: f64,
    /// Evaporation and transpiration taken (negative: dew), mm.
    pub evaporation_mm: f64,
    /// Gravitational drainage below the root zone, mm.
    pub drainage_mm: f64,
    /// Water above saturation that ran off, mm.
    pub runoff_mm: f64,
}

impl RootZone {
    /// A checked bucket; errors name the field.
    ///
    /// # Errors
    /// [`InputError`] naming `root_zone_depth_m` (not finite and > 0), or
    /// a water content out of 0..=1 or out of order
    /// (θ_r ≤ θ_fc ≤ θ_sat).
    pub fn new(
        depth_m: f64,
        residual_m3_m3: f64,
        field_capacity_m3_m3: f64,
        saturation_m3_m3: f64,
    ) -> Result<RootZone, InputError> {
        positive("root_zone_depth_m", depth_m)?;
        in_range("field_capacity_m3_m3", field_capacity_m3_m3, 0.0, 1.0)?;
        in_range(
            "saturation_m3_m3",
            saturation_m3_m3,
            field_capacity_m3_m3,
            1.0,
        )?;
        in_range("residual_m3_m3", residual_m3_m3, 0.0, field_capacity_m3_m3)?;
        Ok(RootZone {
            depth_m,
            residual_m3_m3,
            field_capacity_m3_m3,
            saturation_m3_m3,
            drainage_c3: drainage_coefficient_c3(LOAM_CLAY_PCT),
        })
    }

    /// Water held at `theta`, mm (kg m⁻²).
    pub fn storage_mm(&self, theta_m3_m3: f64) -> f64 {
        WATER_DENSITY_KG_M3 * self.depth_m * theta_m3_m3
    }

    /// θ after `dt_s` seconds from `theta_m3_m3` with `infiltration_mm` of
    /// rain in and `evaporation_mm` out (module docs).
    pub fn step(
        &self,
        theta_m3_m3: f64,
        infiltration_mm: f64,
        evaporation_mm: f64,
        dt_s: f64,
    ) -> WaterStep {
        let w = self.storage_mm(theta_m3_m3);
        let w_res = self.storage_mm(self.residual_m3_m3);
        let w_fc = self.storage_mm(self.field_capacity_m3_m3);
        let w_sat = self.storage_mm(self.saturation_m3_m3);
        let inf = infiltration_mm.max(0.0);
        // Evaporation cannot take water below the residual content.
        let e = evaporation_mm.min((w + inf - w_res).max(0.0));
        let w1 = w + inf - e;
        let drainage =
            (w1 - w_fc).max(0.0) * -(-self.drainage_c3 * dt_s.max(0.0) / DRAINAGE_TAU_S).exp_m1();
        let w2 = w1 - drainage;
        let runoff = (w2 - w_sat).max(0.0);
        // θ moves by the net flux (exactly unchanged when nothing flows).
        let net = inf - e - drainage - runoff;
        WaterStep {
            theta_m3_m3: theta_m3_m3 + net / (WATER_DENSITY_KG_M3 * self.depth_m),
            infiltration_mm: inf,
            evaporation_mm: e,
            drainage_mm: drainage,
            runoff_mm: runoff,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn loam() -> RootZone {
        RootZone::new(1.0, 0.0, 0.32, 0.451).unwrap()
    }

    /// Noilhan & Mahfouf (1996): C₃ of a loam ≈ 0.26.
    #[test]
    fn loam_drainage_coefficient() {
        let c3 = drainage_coefficient_c3(18.0);
        assert!((c3 - 0.261).abs() < 0.002, "{c3}");
    }

    /// Above field capacity with nothing in or out, the excess decays as
    /// exp(−C₃ t/τ) (the exact solution of the drainage equation), and
    /// the drained water is what the bucket lost.
    #[test]
    fn drainage_is_the_exact_exponential_decay() {
        let b = loam();
        let theta0 = 0.40;
        let mut theta = theta0;
        let mut drained = 0.0;
        for _ in 0..48 {
            let s = b.step(theta, 0.0, 0.0, 1800.0);
            drained += s.drainage_mm;
            theta = s.theta_m3_m3;
        }
        let expect = 0.32 + (theta0 - 0.32) * (-b.drainage_c3).exp();
        assert!((theta - expect).abs() < 1e-12, "{theta} vs {expect}");
        assert!((b.storage_mm(theta0) - b.storage_mm(theta) - drained).abs() < 1e-9);
        // Below field capacity nothing drains.
        let s = b.step(0.2, 0.0, 0.0, 86_400.0);
        assert_eq!(s.theta_m3_m3, 0.2);
        assert_eq!(s.drainage_mm, 0.0);
    }

    /// Evaporation stops at the residual content; rain above saturation
    /// runs off.
    #[test]
    fn bounds_hold() {
        let b = RootZone::new(0.1, 0.05, 0.32, 0.451).unwrap();
        let s = b.step(0.06, 0.0, 50.0, 3600.0);
        assert!((s.theta_m3_m3 - 0.05).abs() < 1e-15);
        assert!((s.evaporation_mm - 1.0).abs() < 1e-9);
        let s = b.step(0.44, 100.0, 0.0, 1.0);
        assert!((s.theta_m3_m3 - 0.451).abs() < 1e-12, "{}", s.theta_m3_m3);
        assert!(s.runoff_mm > 80.0);
    }

    #[test]
    fn bad_depth_names_the_field() {
        for d in [0.0, -1.0, f64::NAN] {
            let e = RootZone::new(d, 0.0, 0.32, 0.45).unwrap_err();
            assert_eq!(e.field(), "root_zone_depth_m");
        }
        let e = RootZone::new(1.0, 0.0, 0.32, 0.30).unwrap_err();
        assert_eq!(e.field(), "saturation_m3_m3");
    }
}
