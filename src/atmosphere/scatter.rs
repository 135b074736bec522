//! Single scattering of the direct solar beam into a line of sight.
//!
//! ```text
//! L_ss(λ) = ∫ E₀(λ)·τ_sun(λ, s)·τ_view(λ, s)
//!             · [β_sca,aer(λ, s)·P_HG(Θ; g(λ, s)) + β_sca,R(λ, s)·P_R(Θ)] / (4π) ds
//! ```
//!
//! along the same straight path and segments as the thermal path radiance
//! ([`super::builtin`]); W·m⁻²·sr⁻¹·µm⁻¹. E₀ is the top-of-atmosphere solar
//! spectral irradiance ([`crate::radiometry::solar`], ASTM E490, scaled by
//! 1/d² for the sun–earth distance d in AU), τ_sun the transmittance from
//! the scattering point to the top of the atmosphere toward the sun
//! ([`SunColumn`]), τ_view from the point to the sensor, and Θ the
//! scattering angle, cos Θ = ŝ·l̂ (ŝ toward the sun, l̂ the line of sight
//! from the sensor toward the target), constant along a straight path.
//! Each phase function is normalised so that (1/4π)∫P dΩ = 1.
//!
//! - Aerosol: LOWTRAN 7's scattering (extinction − absorption) and
//!   asymmetry parameter of each region ([`super::aerosol`]), with the
//!   Henyey–Greenstein phase function (Henyey & Greenstein 1941, ApJ 93, 70)
//!   of the segment's scattering-weighted g — LOWTRAN 7's own IPH = 0
//!   option (its subroutine PFHG); MODTRAN's default (IPH = 2) uses Mie
//!   phase functions instead.
//! - Molecules: Rayleigh scattering, the cross-section and depolarisation
//!   of A. Bucholtz, *Rayleigh-scattering calculations for the terrestrial
//!   atmosphere*, Appl. Opt. 34, 2765 (1995), eq. 8–9 and table 3. Its
//!   extinction (optical depth < 10⁻⁴ in 3–16 µm) is not added to τ.
//!
//! Within a segment both τ's are taken as exponential: the segment's
//! scattering optical depth times the logarithmic mean of τ_view at its ends
//! (exact for a homogeneous segment), τ_sun at its midpoint altitude.
//!
//! Approximations: single scattering only (multiple scattering neglected:
//! MODTRAN's SOL_SCAT/SING_SCAT, the measure of what is missed, is 1.008
//! in 3.5–4.5 µm on the tropical zenith path, docs/physics/atmosphere.md);
//! τ_sun·τ_view as a product of two band-model transmittances; flat earth
//! (the sun's path clamped to 89° zenith); sun below the horizon → exactly
//! zero.

use crate::{Error, Result};

/// King-factor depolarisation ratio of air, ρ_n (Bucholtz 1995, table 1:
/// 0.0279 from the visible into the infrared).
pub const AIR_DEPOLARISATION: f64 = 0.0279;

/// The sun as the source of single-scattered radiance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sun {
    /// Solar zenith angle at the ground, degrees, 0–180 (≥ 90: below the
    /// horizon, no scattered sunlight).
    pub zenith_deg: f64,
    /// The sun's azimuth less the azimuth of the line of sight (from the
    /// sensor toward the target), degrees.
    pub relative_azimuth_deg: f64,
    /// Sun–earth distance, AU (the irradiance scales as 1/d²).
    pub distance_au: f64,
    /// The weather's attenuation of the direct beam beyond the clear sky
    /// (clouds, haze), 0–1: the beam that is scattered is the clear-sky
    /// beam times this factor (1 by [`Sun::new`]; see
    /// [`Sun::with_attenuation`]).
    pub attenuation: f64,
}

impl Sun {
    /// A sun; the zenith must be 0–180°, the azimuth finite, the distance
    /// 0.9–1.1 AU.
    pub fn new(zenith_deg: f64, relative_azimuth_deg: f64, distance_au: f64) -> Result<Self> {
        if !(zenith_deg.is_finite() && (0.0..=180.0).contains(&zenith_deg)) {
            return Err(Error::invalid(
                "sun_zenith_deg",
                format!("expected 0–180°, got {zenith_deg}"),
            ));
        }
        if !relative_azimuth_deg.is_finite() {
            return Err(Error::invalid(
                "sun_azimuth_deg",
                format!("expected a finite azimuth, got {relative_azimuth_deg}"),
            ));
        }
        if !(distance_au.is_finite() && (0.9..=1.1).contains(&distance_au)) {
            return Err(Error::invalid(
                "distance_au",
                format!("expected a sun–earth distance of 0.9–1.1 AU, got {distance_au}"),
            ));
        }
        Ok(Sun {
            zenith_deg,
            relative_azimuth_deg,
            distance_au,
            attenuation: 1.0,
        })
    }

    /// This sun with its beam attenuated beyond the clear sky by
    /// `attenuation` (0–1; e.g. a weather record's measured over the
    /// modelled clear-sky direct normal irradiance).
    pub fn with_attenuation(self, attenuation: f64) -> Result<Self> {
        if !(attenuation.is_finite() && (0.0..=1.0).contains(&attenuation)) {
            return Err(Error::invalid(
                "attenuation",
                format!("expected a beam attenuation of 0–1, got {attenuation}"),
            ));
        }
        Ok(Sun {
            attenuation,
            ..self
        })
    }

    /// Whether the sun is above the horizon.
    pub fn is_up(&self) -> bool {
        self.zenith_deg < 90.0
    }

    /// cos Θ, the cosine of the scattering angle for a line of sight (from
    /// the sensor) at zenith angle `los_zenith_deg` (0: looking straight
    /// up, 180: straight down): ŝ·l̂.
    pub fn cos_scattering_angle(&self, los_zenith_deg: f64) -> f64 {
        let (ts, tl) = (self.zenith_deg.to_radians(), los_zenith_deg.to_radians());
        let dphi = self.relative_azimuth_deg.to_radians();
        (ts.cos() * tl.cos() + ts.sin() * tl.sin() * dphi.cos()).clamp(-1.0, 1.0)
    }
}

/// Nodes of the scattering-angle tables of the renderer (the path tables'
/// and the sky's scattered sunlight): uniform in `u = sin(Θ/2) =
/// √((1 − cos Θ)/2)`, from Θ = 0 (toward the sun) to 180°, so that they
/// are densest in angle around the forward peak of the aerosol's phase
/// function (spacing ≈ 2/(N − 1) rad there, 3.6°) and a hit finds its
/// node with one square root. Henyey–Greenstein in `u` is
/// `(1 − g²)/((1 − g)² + 4g·u²)^{3/2}`: the forward peak is
/// `(1 − g)/(2√g)` wide in `u`, 0.15 for g = 0.74.
pub const ANGLE_NODES: usize = 33;

/// cos Θ of scattering-angle node `k` ([`ANGLE_NODES`]): `1 − 2u²`,
/// `u = k/(N − 1)`.
#[inline]
pub fn angle_node_cos(k: usize) -> f64 {
    let u = k as f64 / (ANGLE_NODES - 1) as f64;
    1.0 - 2.0 * u * u
}

/// The scattering-angle nodes bracketing cos Θ = `cos_theta`: `(k, f)`,
/// the angle at fraction `f` (in `u`) from node `k` to node `k + 1`
/// (cos Θ clamped to [−1, 1]; NaN: node 0).
#[inline]
pub fn angle_node(cos_theta: f64) -> (usize, f64) {
    let u = ((1.0 - cos_theta) * 0.5).clamp(0.0, 1.0).sqrt();
    let s = u * (ANGLE_NODES - 1) as f64;
    let k = (s as usize).min(ANGLE_NODES - 2);
    (k, (s - k as f64).clamp(0.0, 1.0))
}

/// [`angle_node`] in single precision (the fast paths'), the same node
/// and the fraction to ~10⁻⁷.
#[inline(always)]
pub fn angle_node_f32(cos_theta: f32) -> (usize, f32) {
    let u = ((1.0 - cos_theta) * 0.5).clamp(0.0, 1.0).sqrt();
    let s = u * (ANGLE_NODES - 1) as f32;
    let k = (s as usize).min(ANGLE_NODES - 2);
    (k, (s - k as f32).clamp(0.0, 1.0))
}

/// Henyey–Greenstein phase function of asymmetry parameter `g` (−1 < g < 1)
/// at cos Θ, normalised to (1/4π)∫P dΩ = 1:
/// `P = (1 − g²) / (1 + g² − 2g·cos Θ)^{3/2}`.
#[inline]
pub fn henyey_greenstein(g: f64, cos_theta: f64) -> f64 {
    let g = g.clamp(-0.9999, 0.9999);
    let d = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (d * d.sqrt())
}

/// Rayleigh phase function with depolarisation (Bucholtz 1995, eq. 12–13),
/// normalised to (1/4π)∫P dΩ = 1:
/// `P = 3/(4(1 + 2γ))·[(1 + 3γ) + (1 − γ)cos²Θ]`, γ = ρ_n/(2 − ρ_n).
#[inline]
pub fn rayleigh_phase(cos_theta: f64) -> f64 {
    let gamma = AIR_DEPOLARISATION / (2.0 - AIR_DEPOLARISATION);
    0.75 / (1.0 + 2.0 * gamma) * ((1.0 + 3.0 * gamma) + (1.0 - gamma) * cos_theta * cos_theta)
}

/// Rayleigh scattering cross-section of air per molecule at `wl_um`, m²:
/// Bucholtz's (1995, eq. 8 and table 3) fit `σ = A·λ^−(B + Cλ + D/λ)` cm²
/// (λ in µm), accurate to 0.2 % against his full calculation.
pub fn rayleigh_cross_section_m2(wl_um: f64) -> f64 {
    let (a, b, c, d) = if wl_um < 0.5 {
        (3.01577e-28, 3.55212, 1.35579, 0.11563)
    } else {
        (4.01061e-28, 3.99668, 1.10298e-3, 2.71393e-2)
    };
    a * wl_um.powf(-(b + c * wl_um + d / wl_um)) * 1e-4
}

/// Rayleigh volume scattering coefficient, m⁻¹, at `wl_um` in air of
/// pressure `p_pa` and temperature `t_k` (σ times the number density
/// p/(k_B·T)).
pub fn rayleigh_scattering_per_m(wl_um: f64, p_pa: f64, t_k: f64) -> f64 {
    rayleigh_cross_section_m2(wl_um) * air_number_density_m3(p_pa, t_k)
}

/// Number density of air molecules, m⁻³, at pressure `p_pa` and
/// temperature `t_k` (ideal gas, p/(k_B·T)).
#[inline]
pub fn air_number_density_m3(p_pa: f64, t_k: f64) -> f64 {
    const K_B: f64 = 1.380_649e-23;
    p_pa / (K_B * t_k)
}

/// The logarithmic mean of the transmittances at a segment's two ends,
/// `(a − b)/ln(a/b)`: the segment's mean transmittance for exponential
/// attenuation within it.
#[inline]
pub fn log_mean(a: f64, b: f64) -> f64 {
    if a <= 0.0 || b <= 0.0 {
        return 0.0;
    }
    let r = b / a;
    if (r - 1.0).abs() < 1e-6 {
        0.5 * (a + b)
    } else {
        (a - b) / (a / b).ln()
    }
}

/// The sun's beam through the atmosphere on one spectral grid: E₀(λ)/d²
/// at the top, and the transmittance from each altitude to the top toward
/// the sun (from one slant path from the top of the atmosphere down to the
/// ground, whose cumulative transmittance at each segment boundary is that
/// altitude's τ_sun).
#[derive(Debug, Clone, PartialEq)]
pub struct SunColumn {
    /// The sun.
    pub sun: Sun,
    /// E₀(λ)/d², W·m⁻²·µm⁻¹, on the grid.
    pub irradiance_toa: Vec<f64>,
    /// Altitudes of the τ_sun nodes, m above sea level, increasing (the
    /// last the top of the model atmosphere).
    pub altitudes_m: Vec<f64>,
    /// τ_sun(λ) at each node.
    pub transmittance: Vec<Vec<f64>>,
}

impl SunColumn {
    /// The node `k` and fraction `f` of altitude `z_m` between nodes `k`
    /// and `k + 1` (clamped to the column).
    pub fn locate(&self, z_m: f64) -> (usize, f64) {
        let x = &self.altitudes_m;
        if x.len() < 2 {
            return (0, 0.0);
        }
        let k = x
            .partition_point(|&v| v <= z_m)
            .saturating_sub(1)
            .min(x.len() - 2);
        (k, ((z_m - x[k]) / (x[k + 1] - x[k])).clamp(0.0, 1.0))
    }

    /// τ_sun at wavelength index `i` at the node and fraction of
    /// [`SunColumn::locate`].
    #[inline]
    pub fn transmittance_at(&self, (k, f): (usize, f64), i: usize) -> f64 {
        let t0 = self.transmittance[k][i];
        match self.transmittance.get(k + 1) {
            Some(t1) => t0 + (t1[i] - t0) * f,
            None => t0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_mean_limits() {
        assert_eq!(log_mean(0.5, 0.5), 0.5);
        assert_eq!(log_mean(0.5, 0.0), 0.0);
        let (a, b) = (0.9f64, 0.3f64);
        // ∫₀¹ a·(b/a)^x dx
        let n = 100_000;
        let num: f64 = (0..n)
            .map(|k| a * (b / a).powf((k as f64 + 0.5) / n as f64))
            .sum::<f64>()
            / n as f64;
        assert!((log_mean(a, b) - num).abs() < 1e-9);
    }
}
