//! Convection of dry surfaces (roads, roofs, walls, metal): the sensible
//! heat `h·(T_air − T)` of every material without a `surface_energy` block,
//! convection only — the longwave exchange is the balance's own εσT⁴ and
//! sky/background terms ([`super::balance`]).
//!
//! # The DOE-2 model (default)
//! As in the EnergyPlus Engineering Reference (v9–v24, "Outside Surface
//! Heat Balance → Exterior Convection → DOE-2 model"), W m⁻² K⁻¹:
//!
//! `h = h_n + R_f · (h_glass − h_n)`, `h_glass = √(h_n² + (a·V^b)²)`
//!
//! - **natural** `h_n` (Walton 1983, *Thermal Analysis Research Program
//!   reference manual*, NBSIR 83-2655, the TARP correlations), with
//!   `ΔT = T_s − T_air` (K) and `cos Σ` the cosine of the tilt (1 facing
//!   up, 0 vertical, −1 facing down):
//!   - heat flowing upward (a warm surface facing up, a cold one facing
//!     down), unstable: `h_n = 9.482 |ΔT|^⅓ / (7.238 − |cos Σ|)`;
//!   - heat flowing downward (a warm surface facing down, a cold one facing
//!     up), stable: `h_n = 1.810 |ΔT|^⅓ / (1.382 + |cos Σ|)`;
//!   - vertical (or ΔT = 0): `h_n = 1.31 |ΔT|^⅓` (both of the above give
//!     it at `cos Σ = 0`);
//! - **forced** part from the MoWiTT measurements on a full-scale smooth
//!   (glazed) building surface (Yazdanian & Klems 1994, "Measurement of the
//!   exterior convective film coefficient for windows in low-rise
//!   buildings", ASHRAE Transactions 100(1):1087–1096): windward
//!   `a = 3.26 W m⁻² K⁻¹ (m/s)^−0.89`, `b = 0.89`; leeward `a = 3.55`,
//!   `b = 0.617`; `V` the wind speed at the surface, m/s;
//! - **roughness**: `R_f` from 1.00 (glass) to 2.17 (stucco)
//!   ([`crate::material::SurfaceRoughness`]); concrete, the default, 1.52.
//!
//! Wind direction: EnergyPlus calls a surface windward when the wind comes
//! from within 100° of its outward normal, and a horizontal one always
//! windward. irsig has no per-facet wind direction, so a tilted or
//! vertical surface takes the mean over a wind from any direction with
//! equal odds: `5/9` windward (200° of 360°) and `4/9` leeward, of the
//! combined `h`; a surface within `acos 0.98` of horizontal is windward.
//!
//! Validity: the MoWiTT fit covers winds 0–≈ 8 m/s on a low-rise wall, the
//! TARP natural correlations laminar to turbulent plates (ΔT of a few to
//! tens of K). At calm wind the model tends to the natural convection of
//! the surface (≈ 3.3 W m⁻² K⁻¹ for a horizontal surface 10 K warmer than
//! the air, 1.6 for one 10 K colder), where McAdams gives 5.7.
//!
//! # McAdams (option)
//! `h = 5.7 + 3.8u` ([`super::mcadams_h_w_m2_k`]) is a *combined*
//! coefficient — it contains a radiative part (Duffie & Beckman 2013
//! §3.15), ≈ 4εσT³ ≈ 5 W m⁻² K⁻¹ at 290 K — so with it irsig's balance
//! counts the longwave exchange with the air twice. It is kept
//! (`"convection": {"model": "mcadams"}`) for parity with DIRSIG, whose
//! THERM uses it.
//!
//! # Orientation in the scene solve
//! `h_n` depends on the surface's own ΔT. Like the stability of an
//! evaporating surface ([`super::surface`]), the scene solve takes it from
//! a reference surface per material, wind class and orientation class
//! ([`orientation_class`]: five classes of `cos Σ`), so that the
//! linearised solve keeps its structure; [`super::Exchange::facing`].
//!
//! # What it owns, takes and gives
//! Owns the convection correlations; takes plain numbers (ΔT in K, wind in
//! m/s, `cos Σ`); gives W m⁻² K⁻¹. Knows nothing of facets or scenes.

use crate::material::{ConvectionModel, ConvectionSpec};

/// MoWiTT windward coefficient `a`, W m⁻² K⁻¹ (m/s)^−b.
pub const WINDWARD_A: f64 = 3.26;
/// MoWiTT windward exponent `b`.
pub const WINDWARD_B: f64 = 0.89;
/// MoWiTT leeward coefficient `a`, W m⁻² K⁻¹ (m/s)^−b.
pub const LEEWARD_A: f64 = 3.55;
/// MoWiTT leeward exponent `b`.
pub const LEEWARD_B: f64 = 0.617;
/// Weight of the windward case for a wind from any direction (module docs).
pub const WINDWARD_WEIGHT: f64 = 200.0 / 360.0;
/// `|cos Σ|` from which a surface is horizontal (always windward).
pub const HORIZONTAL_COS: f64 = 0.98;

/// Walton's (1983) natural convection coefficient, W m⁻² K⁻¹, of a surface
/// `delta_k = T_s − T_air` (K) warmer than the air, tilted with
/// `cos_tilt` (1 up, −1 down) (module docs).
pub fn natural_w_m2_k(delta_k: f64, cos_tilt: f64) -> f64 {
    if !(delta_k.is_finite() && cos_tilt.is_finite()) {
        return 0.0;
    }
    let c = cos_tilt.clamp(-1.0, 1.0);
    let cube = delta_k.abs().cbrt();
    if delta_k == 0.0 || c == 0.0 {
        1.31 * cube
    } else if (delta_k > 0.0) == (c > 0.0) {
        // Heat flows upward: unstable.
        9.482 * cube / (7.238 - c.abs())
    } else {
        1.810 * cube / (1.382 + c.abs())
    }
}

/// The DOE-2 coefficient, W m⁻² K⁻¹, for one wind case (`a`, `b`).
fn doe2_case(h_n: f64, wind_m_s: f64, a: f64, b: f64, multiplier: f64) -> f64 {
    let forced = a * wind_m_s.powf(b);
    let glass = (h_n * h_n + forced * forced).sqrt();
    h_n + multiplier * (glass - h_n)
}

/// The DOE-2 convection coefficient, W m⁻² K⁻¹, of a surface `delta_k =
/// T_s − T_air` (K) warmer than the air, tilted with `cos_tilt`, in wind
/// `wind_m_s` (m/s, at the surface; negative or non-finite: calm) with
/// roughness multiplier `multiplier` (module docs).
pub fn doe2_w_m2_k(delta_k: f64, cos_tilt: f64, wind_m_s: f64, multiplier: f64) -> f64 {
    let u = if wind_m_s.is_finite() {
        wind_m_s.max(0.0)
    } else {
        0.0
    };
    let h_n = natural_w_m2_k(delta_k, cos_tilt);
    let windward = doe2_case(h_n, u, WINDWARD_A, WINDWARD_B, multiplier);
    if cos_tilt.abs() >= HORIZONTAL_COS {
        return windward;
    }
    let leeward = doe2_case(h_n, u, LEEWARD_A, LEEWARD_B, multiplier);
    WINDWARD_WEIGHT * windward + (1.0 - WINDWARD_WEIGHT) * leeward
}

/// The convection coefficient of a dry surface under `spec`, W m⁻² K⁻¹
/// (arguments as [`doe2_w_m2_k`]; McAdams takes the wind alone).
pub fn coefficient_w_m2_k(
    spec: &ConvectionSpec,
    delta_k: f64,
    cos_tilt: f64,
    wind_m_s: f64,
) -> f64 {
    match spec.model {
        ConvectionModel::Doe2 => {
            doe2_w_m2_k(delta_k, cos_tilt, wind_m_s, spec.roughness.multiplier())
        }
        ConvectionModel::Mcadams => super::mcadams_h_w_m2_k(wind_m_s),
    }
}

/// Number of orientation classes ([`orientation_class`]).
pub const ORIENTATION_CLASSES: u32 = 5;

/// The orientation class of a surface whose unit normal has z-component
/// `normal_z` (`cos Σ`): `round(2·cos Σ) + 2`, 0 (facing down) … 2
/// (vertical) … 4 (facing up). Classes differ by at most ±0.25 in
/// `cos Σ` from their members, which changes Walton's `h_n` by under 4 %.
pub fn orientation_class(normal_z: f64) -> u32 {
    let c = if normal_z.is_finite() {
        normal_z.clamp(-1.0, 1.0)
    } else {
        1.0
    };
    ((2.0 * c).round() + 2.0) as u32
}

/// The `cos Σ` of an orientation class ([`orientation_class`]).
pub fn class_cos_tilt(class: u32) -> f64 {
    (class.min(ORIENTATION_CLASSES - 1) as f64 - 2.0) / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::SurfaceRoughness;

    /// Walton's correlations at ΔT = ±10 K, computed by hand from the
    /// published constants: 10^⅓ = 2.154435.
    #[test]
    fn natural_convection_follows_walton() {
        let c = 10f64.cbrt();
        let cases = [
            (10.0, 1.0, 9.482 * c / 6.238),   // hot, facing up: 3.2748
            (-10.0, 1.0, 1.810 * c / 2.382),  // cold, facing up: 1.6371
            (10.0, -1.0, 1.810 * c / 2.382),  // hot, facing down
            (-10.0, -1.0, 9.482 * c / 6.238), // cold, facing down
            (10.0, 0.0, 1.31 * c),            // vertical: 2.8223
            (-10.0, 0.0, 1.31 * c),
        ];
        for (dt, cos, want) in cases {
            let got = natural_w_m2_k(dt, cos);
            assert!(
                (got - want).abs() < 1e-12,
                "ΔT {dt} cos {cos}: {got} vs {want}"
            );
        }
        assert!((natural_w_m2_k(10.0, 1.0) - 3.2748).abs() < 1e-4);
        assert!((natural_w_m2_k(-10.0, 1.0) - 1.6371).abs() < 1e-4);
        assert!((natural_w_m2_k(10.0, 0.0) - 2.8223).abs() < 1e-4);
        // Continuous through vertical (9.482/7.238 = 1.3100, 1.810/1.382 = 1.3097).
        for dt in [-5.0, 5.0] {
            let v = natural_w_m2_k(dt, 0.0);
            assert!((natural_w_m2_k(dt, 1e-9) - v).abs() < 1e-3 * v);
            assert!((natural_w_m2_k(dt, -1e-9) - v).abs() < 1e-3 * v);
        }
        assert_eq!(natural_w_m2_k(0.0, 1.0), 0.0);
    }

    /// DOE-2 at 10 K and 3 m/s, by hand: windward forced 3.26·3^0.89 =
    /// 8.6667, leeward 3.55·3^0.617 = 6.9922 W m⁻² K⁻¹.
    #[test]
    fn doe2_combines_natural_and_forced() {
        let f_w = 3.26 * 3f64.powf(0.89);
        let f_l = 3.55 * 3f64.powf(0.617);
        assert!((f_w - 8.6667).abs() < 1e-3, "{f_w}");
        assert!((f_l - 6.9922).abs() < 1e-3, "{f_l}");
        // Horizontal, facing up, hot, concrete (R_f 1.52): windward only.
        let hn = natural_w_m2_k(10.0, 1.0);
        let want = hn + 1.52 * ((hn * hn + f_w * f_w).sqrt() - hn);
        let got = doe2_w_m2_k(10.0, 1.0, 3.0, 1.52);
        assert!((got - want).abs() < 1e-12);
        assert!((got - 12.3796).abs() < 1e-3, "{got}");
        // Vertical: 5/9 windward + 4/9 leeward.
        let hn = natural_w_m2_k(10.0, 0.0);
        let w = hn + (hn.hypot(f_w) - hn);
        let l = hn + (hn.hypot(f_l) - hn);
        let got = doe2_w_m2_k(10.0, 0.0, 3.0, 1.0);
        assert!((got - (5.0 / 9.0 * w + 4.0 / 9.0 * l)).abs() < 1e-12);
        // Calm: natural convection alone, whatever the roughness.
        for r in [1.0, 2.17] {
            assert!((doe2_w_m2_k(10.0, 1.0, 0.0, r) - natural_w_m2_k(10.0, 1.0)).abs() < 1e-12);
        }
        // Glass (R_f = 1) gives MoWiTT's combined coefficient.
        let hn = natural_w_m2_k(-4.0, 1.0);
        let mowitt = (hn * hn + (3.26 * 2f64.powf(0.89)).powi(2)).sqrt();
        assert!((doe2_w_m2_k(-4.0, 1.0, 2.0, 1.0) - mowitt).abs() < 1e-12);
        // Rougher convects more; more wind convects more.
        assert!(doe2_w_m2_k(5.0, 1.0, 2.0, 2.17) > doe2_w_m2_k(5.0, 1.0, 2.0, 1.52));
        assert!(doe2_w_m2_k(5.0, 0.0, 4.0, 1.52) > doe2_w_m2_k(5.0, 0.0, 2.0, 1.52));
        // Convection only: below McAdams' combined 5.7 + 3.8u by about
        // its radiative part at light wind.
        let m = crate::thermal::mcadams_h_w_m2_k(1.0);
        let d = doe2_w_m2_k(5.0, 1.0, 1.0, 1.52);
        assert!(m - d > 3.0 && m - d < 7.0, "McAdams {m} DOE-2 {d}");
        let spec = ConvectionSpec {
            model: ConvectionModel::Doe2,
            roughness: SurfaceRoughness::VerySmooth,
        };
        assert_eq!(
            coefficient_w_m2_k(&spec, 3.0, 0.5, 2.0),
            doe2_w_m2_k(3.0, 0.5, 2.0, 1.0)
        );
        assert_eq!(
            coefficient_w_m2_k(&ConvectionSpec::MCADAMS, 3.0, 0.5, 2.0),
            5.7 + 7.6
        );
    }

    #[test]
    fn orientation_classes_cover_up_vertical_down() {
        assert_eq!(orientation_class(1.0), 4);
        assert_eq!(orientation_class(0.0), 2);
        assert_eq!(orientation_class(-1.0), 0);
        assert_eq!(orientation_class(0.8), 4);
        assert_eq!(orientation_class(0.6), 3);
        for c in 0..ORIENTATION_CLASSES {
            assert_eq!(orientation_class(class_cos_tilt(c)), c);
        }
    }
}
