//! The surface energy balance: each term of the net heat flux into a face,
//! written as a [`SurfaceFlux`] law `q(T) = S − H·T − R·T⁴ − g_v(e°(T) − e_a)`
//! (W m⁻²).
//!
//! Front face (the THERM balance of DIRSIG: Schott, *Remote Sensing: The
//! Image Chain Approach*, 2nd ed., Oxford UP, 2007, DIRSIG chapter; DIRSIG
//! User Manual, "THERM temperature solver"), all in W m⁻², positive into the
//! surface:
//!
//! | term                         | expression                         |
//! |------------------------------|------------------------------------|
//! | absorbed direct solar        | `α · E_dn · s(t) · max(cos θ, 0)`  |
//! | absorbed diffuse solar       | `α · F · E_d`                      |
//! | absorbed reflected solar     | `α · E_r`                          |
//! | absorbed sky longwave        | `ε · F · E_sky`                    |
//! | absorbed background longwave | `ε · (1 − F) · σ · T_bg⁴`          |
//! | emission                     | `− ε · σ · T⁴`                     |
//! | convection                   | `h · (T_air − T)`                  |
//! | self-generated power         | `P`                                |
//! | latent heat (evaporation)    | `− g_v · (e°(T) − e_a)`            |
//!
//! The latent row is zero (and skipped) for a surface that does not
//! evaporate (`g_v = 0`, every material today); see [`SurfaceFlux`] for
//! `g_v` and its source.
//!
//! `α` solar absorptivity, `ε` thermal emissivity (Kirchhoff: absorptivity
//! for longwave = `ε`), `E_dn` direct-normal irradiance, `s` sunlit fraction
//! (solar history), `θ` solar incidence angle on the facet, `F` sky shape
//! factor (fraction of the hemisphere seen that is sky), `E_d` diffuse
//! horizontal irradiance (isotropic sky), `E_sky` downwelling sky longwave on
//! a horizontal surface, `T_bg` temperature of what the rest of the
//! hemisphere sees (K), `σ` Stefan–Boltzmann constant, `h` the convection
//! coefficient of the material's exchange ([`super::Exchange`]: DOE-2 or
//! McAdams for a dry surface, [`super::convection`]; `ρc_p/r_a` for one
//! that evaporates),
//! `E_r` the shortwave reflected onto the facet by the surfaces it sees
//! (neighbouring facets, the ground; `irsig::exposure::reflected` for a
//! scene, the ground albedo for a free-standing facet), W m⁻².
//! `ε` is the hemispherical emissivity
//! ([`super::SlabProperties::thermal_emissivity`]).

use super::conduction::{STEFAN_BOLTZMANN_W_M2_K4, SurfaceFlux};

/// Convective heat-transfer coefficient of a surface in wind, W m⁻² K⁻¹:
/// McAdams' correlation `h = 5.7 + 3.8·u`, `u` wind speed in m/s (McAdams,
/// *Heat Transmission*, 3rd ed., 1954; as given by Duffie & Beckman, *Solar
/// Engineering of Thermal Processes*, 4th ed., 2013, §3.15 "Wind convection
/// coefficients", who note it includes some radiation and suits wind up to
/// ~5 m/s). Negative or
/// non-finite speeds are treated as calm.
#[inline]
pub fn mcadams_h_w_m2_k(wind_speed_m_s: f64) -> f64 {
    let u = if wind_speed_m_s.is_finite() {
        wind_speed_m_s.max(0.0)
    } else {
        0.0
    };
    5.7 + 3.8 * u
}

/// Interior surface film coefficient for building walls, W m⁻² K⁻¹:
/// `1/R_si` with `R_si = 0.13 m² K W⁻¹` (ISO 6946 conventional internal
/// surface resistance, horizontal heat flow; combined convection and
/// radiation to the room).
pub const INTERIOR_FILM_W_M2_K: f64 = 1.0 / 0.13;

/// Default interior air temperature of buildings, K (22 °C).
pub const INTERIOR_AIR_K: f64 = 295.15;

/// Everything the front-surface balance needs at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrontForcing {
    /// Air temperature, K.
    pub air_temperature_k: f64,
    /// Convective coefficient, W m⁻² K⁻¹.
    pub convection_w_m2_k: f64,
    /// Direct-normal irradiance, W m⁻².
    pub direct_normal_w_m2: f64,
    /// Diffuse-horizontal irradiance, W m⁻².
    pub diffuse_horizontal_w_m2: f64,
    /// Downwelling sky longwave, W m⁻².
    pub sky_longwave_w_m2: f64,
    /// Sunlit fraction of the facet, 0–1.
    pub sun_fraction: f64,
    /// Cosine of the solar incidence angle (clamped at 0 here).
    pub cos_incidence: f64,
    /// Sky shape factor, 0–1.
    pub shape_factor: f64,
    /// Shortwave reflected onto the facet by what it sees, W m⁻².
    pub reflected_w_m2: f64,
    /// Background (non-sky) temperature, K.
    pub background_temperature_k: f64,
    /// Vapour conductance `ρc_p/(γ(r_a + r_s))` of an evaporating surface,
    /// W m⁻² Pa⁻¹; 0 for a dry one (see [`SurfaceFlux`]).
    pub vapour_conductance_w_m2_pa: f64,
    /// Actual vapour pressure of the air, Pa.
    pub air_vapour_pressure_pa: f64,
}

/// The front-surface balance as a flux law (table in the module docs),
/// for absorptivity `alpha`, emissivity `eps` and self power `p_w_m2`.
#[inline]
pub fn front_flux(f: &FrontForcing, alpha: f64, eps: f64, p_w_m2: f64) -> SurfaceFlux {
    let sigma = STEFAN_BOLTZMANN_W_M2_K4;
    let s = f.sun_fraction.clamp(0.0, 1.0);
    let cos = f.cos_incidence.max(0.0);
    let direct = alpha * f.direct_normal_w_m2 * s * cos;
    let diffuse = alpha * (f.shape_factor * f.diffuse_horizontal_w_m2 + f.reflected_w_m2);
    let sky = eps * f.shape_factor * f.sky_longwave_w_m2;
    let tb2 = f.background_temperature_k * f.background_temperature_k;
    let background = eps * (1.0 - f.shape_factor) * sigma * tb2 * tb2;
    SurfaceFlux {
        source_w_m2: direct
            + diffuse
            + sky
            + background
            + f.convection_w_m2_k * f.air_temperature_k
            + p_w_m2,
        linear_w_m2_k: f.convection_w_m2_k,
        radiative_w_m2_k4: eps * sigma,
        vapour_conductance_w_m2_pa: f.vapour_conductance_w_m2_pa,
        air_vapour_pressure_pa: f.air_vapour_pressure_pa,
    }
}

/// An exposed back face (thin objects: leaves, fences, vehicle panels), a
/// fraction `a` of whose area is in the air: `a` times [convection
/// `h(u)(T_air − T)`, sky longwave `ε F_b E_sky`, background longwave
/// `ε (1 − F_b) σ T_bg⁴`, emission `−εσT⁴`]; no sunlight (the back face is
/// taken to be shaded), W m⁻².
#[inline]
pub fn exposed_back_flux(
    f: &FrontForcing,
    eps: f64,
    back_shape_factor: f64,
    a: f64,
) -> SurfaceFlux {
    let sigma = STEFAN_BOLTZMANN_W_M2_K4;
    let tb2 = f.background_temperature_k * f.background_temperature_k;
    SurfaceFlux {
        source_w_m2: a
            * (eps * back_shape_factor * f.sky_longwave_w_m2
                + eps * (1.0 - back_shape_factor) * sigma * tb2 * tb2
                + f.convection_w_m2_k * f.air_temperature_k),
        linear_w_m2_k: a * f.convection_w_m2_k,
        radiative_w_m2_k4: a * eps * sigma,
        ..SurfaceFlux::default()
    }
}

/// A film to air at `air_k` (K) with coefficient `h` (W m⁻² K⁻¹):
/// `q = h (T_air − T)`.
#[inline]
pub fn film_flux(air_k: f64, h_w_m2_k: f64) -> SurfaceFlux {
    SurfaceFlux {
        source_w_m2: h_w_m2_k * air_k,
        linear_w_m2_k: h_w_m2_k,
        ..SurfaceFlux::default()
    }
}
