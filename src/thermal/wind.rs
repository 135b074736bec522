//! The wind at each facet: the weather's wind (measured at
//! [`super::Forcing::wind_height_m`], 10 m by default) reduced to the
//! facet's height by a logarithmic profile and, in street canyons, by the
//! canyon's sheltering — what the convection of a dry surface
//! ([`super::convection`]) and the aerodynamic resistance of an
//! evaporating one ([`super::surface`]) see.
//!
//! # Model
//! `u_f = u_ref · L(z_f) · C(a_f)`:
//! - **Height** (neutral logarithmic profile over the site's roughness
//!   length `z₀`; e.g. Stull, *An Introduction to Boundary Layer
//!   Meteorology*, 1988, §9.7.5; Wieringa, Davenport, Grimmond & Oke,
//!   "New revision of Davenport roughness classification", 3rd EACWE,
//!   2001, for `z₀`): `L(z) = ln(max(z, z_min)/z₀) / ln(z_ref/z₀)`, with
//!   `z_f` the facet centre's height above the scene's ground and `z_min`
//!   the air-temperature height (2 m: the convective film pairs the air
//!   temperature with the wind at that height). Default `z₀ = 0.5 m`,
//!   Davenport–Wieringa class 6 "very rough" (low buildings three to seven
//!   heights apart). Above `z_ref` the wind grows (roofs of tall buildings).
//! - **Canyon** (Masson 2000, "A physically-based scheme for the urban
//!   energy budget in atmospheric models", Boundary-Layer Meteorol. 94,
//!   357–397, doi:10.1023/A:1002463829265 (TEB), canyon wind: the
//!   direction-averaged wind in a canyon of aspect `a = H/W` is
//!   `(2/π)·exp(−a/4)` times the wind at roof level): `C(a) = exp(−a/4)·
//!   (1 − (1 − 2/π)·min(a/a₀, 1))`, i.e. Masson's factor for `a ≥ a₀ = 0.5`
//!   and a linear blend to 1 on open ground (`a = 0`), where the `2/π` of
//!   the along-canyon channelling does not apply (the blend is irsig's
//!   choice, so that a facet's wind does not jump with the noise of its
//!   sky view). A facet's aspect is that of the infinite canyon whose road
//!   (facets facing up, `n_z ≥ cos 45°`) or wall (the others) has its sky
//!   view relative to an open plane of its tilt, `Ψ = F / ((1 + cos β)/2)`
//!   (Masson's eqs. 8–9 inverted): road `a = (1 − Ψ²)/(2Ψ)`, wall (with
//!   `Ψ_w = Ψ/2`) `a = (1 − 2Ψ_w)/(2Ψ_w(1 − Ψ_w))`.
//!
//! Evaporating surfaces compute their aerodynamic resistance from the wind
//! at the measurement height with their own log profile, so they take the
//! canyon factor alone ([`FacetWind::factor_for`]): the height reduction
//! is in their `r_a` already.
//!
//! # What it owns, takes and gives
//! Owns the wind-reduction rules. Takes a facet's height, tilt and sky view
//! (plain numbers); gives [`FacetWind`]. Knows nothing of rays or scenes.

use crate::{Error, Result};

/// Default site roughness length, m (module docs).
pub const ROUGHNESS_M: f64 = 0.5;

/// Aspect above which Masson's canyon factor applies unblended.
pub const FULL_CANYON_ASPECT: f64 = 0.5;

/// The site's wind profile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindProfile {
    /// Roughness length `z₀` of the site, m (> 0, below the measurement
    /// and lowest heights).
    pub roughness_m: f64,
}

impl Default for WindProfile {
    fn default() -> Self {
        WindProfile {
            roughness_m: ROUGHNESS_M,
        }
    }
}

impl WindProfile {
    /// Checks `z₀` against the measurement height `z_ref` and the lowest
    /// height `z_min`, m.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming `roughness_m`.
    pub fn validate(&self, z_ref: f64, z_min: f64) -> Result<()> {
        let z0 = self.roughness_m;
        if !(z0.is_finite() && z0 > 0.0 && z0 < z_ref.min(z_min)) {
            return Err(Error::invalid(
                "roughness_m",
                format!(
                    "expected a roughness length > 0 and below the lowest height ({} m), got {z0}",
                    z_ref.min(z_min)
                ),
            ));
        }
        Ok(())
    }

    /// `L(z)`: the wind at height `z` (m, raised to `z_min`) over the wind
    /// at the measurement height `z_ref` (module docs).
    pub fn height_factor(&self, z_m: f64, z_ref_m: f64, z_min_m: f64) -> f64 {
        let z0 = self.roughness_m;
        let z = if z_m.is_finite() {
            z_m.max(z_min_m)
        } else {
            z_min_m
        };
        (z / z0).ln() / (z_ref_m / z0).ln()
    }
}

/// `C(a)`: the canyon's wind over the roof-level wind for aspect `a = H/W`
/// (module docs; Masson 2000 for `a ≥ 0.5`).
pub fn canyon_factor(aspect: f64) -> f64 {
    let a = if aspect.is_finite() {
        aspect.max(0.0)
    } else {
        0.0
    };
    let channel = 1.0 - (1.0 - 2.0 / std::f64::consts::PI) * (a / FULL_CANYON_ASPECT).min(1.0);
    (-a / 4.0).exp() * channel
}

/// The aspect `H/W` of the infinite canyon in which a facet of unit
/// normal z-component `normal_z` (cos of its tilt) has sky view `F`
/// (module docs; 0 for a facet that sees its open-plane sky, large for
/// one that sees almost none).
pub fn equivalent_aspect(normal_z: f64, shape_factor: f64) -> f64 {
    let open = (1.0 + normal_z.clamp(-1.0, 1.0)) / 2.0;
    if open <= 1e-6 {
        return 0.0;
    }
    let psi = (shape_factor / open).clamp(1e-3, 1.0);
    if normal_z >= std::f64::consts::FRAC_1_SQRT_2 {
        (1.0 - psi * psi) / (2.0 * psi)
    } else {
        let pw = (psi / 2.0).min(0.5);
        (1.0 - 2.0 * pw) / (2.0 * pw * (1.0 - pw))
    }
}

/// The reduction of the weather's wind at one facet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FacetWind {
    /// `L(z_f)`: height factor.
    pub height: f32,
    /// `C(a_f)`: canyon factor.
    pub canyon: f32,
}

impl FacetWind {
    /// The weather's wind unchanged.
    pub const NONE: FacetWind = FacetWind {
        height: 1.0,
        canyon: 1.0,
    };

    /// The facet's wind for a facet of height `z_m` above the ground (m),
    /// normal z-component `normal_z` and sky view `shape_factor`, under
    /// `profile` with the measurement height `z_ref_m` and the lowest
    /// height `z_min_m`.
    pub fn new(
        profile: &WindProfile,
        z_m: f64,
        normal_z: f64,
        shape_factor: f64,
        z_ref_m: f64,
        z_min_m: f64,
    ) -> FacetWind {
        FacetWind {
            height: profile.height_factor(z_m, z_ref_m, z_min_m) as f32,
            canyon: canyon_factor(equivalent_aspect(normal_z, shape_factor)) as f32,
        }
    }

    /// The factor on the weather's wind for a surface: `L·C` for a dry one
    /// (its convection takes the wind at the facet), `C` alone for an
    /// `evaporating` one (its aerodynamic resistance reduces the
    /// measurement-height wind with its own log profile).
    pub fn factor_for(&self, evaporating: bool) -> f64 {
        if evaporating {
            self.canyon as f64
        } else {
            (self.height * self.canyon) as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The height factor is the log law: 1 at the measurement height, the
    /// ratio of logarithms below it, raised to `z_min`.
    #[test]
    fn height_factor_is_the_log_law() {
        let p = WindProfile::default();
        assert!((p.height_factor(10.0, 10.0, 2.0) - 1.0).abs() < 1e-12);
        let l5 = p.height_factor(5.0, 10.0, 2.0);
        assert!((l5 - (10f64).ln() / (20f64).ln()).abs() < 1e-12, "{l5}");
        assert_eq!(
            p.height_factor(0.0, 10.0, 2.0),
            p.height_factor(2.0, 10.0, 2.0)
        );
        // Profile check: u(z₂)/u(z₁) = ln(z₂/z₀)/ln(z₁/z₀) for any pair.
        let (a, b) = (
            p.height_factor(3.0, 10.0, 2.0),
            p.height_factor(30.0, 10.0, 2.0),
        );
        assert!((b / a - (60f64).ln() / (6f64).ln()).abs() < 1e-12);
        assert!(p.validate(10.0, 2.0).is_ok());
        assert!(
            WindProfile { roughness_m: 3.0 }
                .validate(10.0, 2.0)
                .is_err()
        );
        assert!(
            WindProfile { roughness_m: 0.0 }
                .validate(10.0, 2.0)
                .is_err()
        );
    }

    /// Masson's canyon factor `(2/π) exp(−a/4)` from aspect 0.5 on; 1 on
    /// open ground; the aspect recovered from Masson's sky views (eqs. 8–9).
    #[test]
    fn canyon_factor_follows_masson() {
        for a in [0.5f64, 1.0, 2.0, 3.0] {
            let masson = 2.0 / std::f64::consts::PI * (-a / 4.0).exp();
            assert!((canyon_factor(a) - masson).abs() < 1e-12, "a = {a}");
            let road = (a * a + 1.0).sqrt() - a;
            let wall = (a + 1.0 - (a * a + 1.0).sqrt()) / (2.0 * a);
            assert!(
                (equivalent_aspect(1.0, road) - a).abs() < 1e-9,
                "road a = {a}"
            );
            assert!(
                (equivalent_aspect(0.0, wall) - a).abs() < 1e-9,
                "wall a = {a}"
            );
        }
        assert_eq!(canyon_factor(0.0), 1.0);
        assert_eq!(equivalent_aspect(1.0, 1.0), 0.0);
        assert_eq!(equivalent_aspect(0.0, 0.5), 0.0);
        // Monotone: deeper canyons shelter more.
        let mut prev = 1.0;
        for i in 1..50 {
            let c = canyon_factor(i as f64 * 0.1);
            assert!(c < prev);
            prev = c;
        }
        let w = FacetWind::new(&WindProfile::default(), 0.0, 1.0, 0.414_213_56, 10.0, 2.0);
        assert!((w.canyon as f64 - 2.0 / std::f64::consts::PI * (-0.25f64).exp()).abs() < 1e-5);
        assert_eq!(w.factor_for(true), w.canyon as f64);
        assert!((w.factor_for(false) - (w.height * w.canyon) as f64).abs() < 1e-7);
    }
}
