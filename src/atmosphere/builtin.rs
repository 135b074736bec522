//! The built-in atmosphere: needs nothing external.
//!
//! **Profile.** Either one of the six AFGL model atmospheres
//! ([`super::profile`], [`BuiltinParams::profile`]) with the surface weather
//! blended into its lowest [`SURFACE_BLEND_DEPTH_M`]
//! (see [`BuiltinAtmosphere::state`]), or the analytic profile:
//! temperature the US Standard Atmosphere 1976 (NOAA/NASA/USAF,
//! NOAA-S/T 76-1562, table I) shifted by ΔT = T_air − T_US76(z_ground); the
//! shift applies in full up to 11 km and tapers linearly to zero at 20 km.
//! Pressure: p(z) = p_s·exp(−(z − z_g)/H), H = 8 km. Water vapour: surface
//! partial pressure e = RH·e_sat(T_air) (Magnus form, Alduchov & Eskridge
//! 1996, J. Appl. Meteor. 35, 601), density falling exponentially with a
//! 2 km scale height (a tropical column of ~4 g/cm² at 300 K, 80 % RH).
//! CO₂ well mixed at 420 ppmv.
//!
//! **Absorption.** Spectral on the caller's grid, 3–16 µm:
//! 1. LOWTRAN 7's band models of H₂O, CO₂ (outside the 4.3 µm lines of
//!    item 2), O₃, N₂O, CO and CH₄ and its CKD water-vapour continuum
//!    ([`super::lowtran`], Kneizys et al. 1988, AFGL-TR-88-0177), with CH₄
//!    1.7, CO 0.15 and N₂O 0.32 ppmv well mixed.
//! 2. The CO₂ 4.3 µm band (¹²CO₂ ν₃, its first hot band and ¹³CO₂ ν₃) from
//!    its lines ([`super::lines`]): positions and intensities from the
//!    molecular constants at each layer's temperature, Malkmus parameters
//!    from the lines in each wavelength's window (Curtis–Godson path sums),
//!    and the far wings of the other lines, sub-Lorentzian after Perrin &
//!    Hartmann (1989), as a continuum.
//! 3. The N₂ collision-induced fundamental band near 4.3 µm (Lafferty et
//!    al. 1996), optical depth ∝ n_N₂² (see [`N2_CIA_INTEGRAL`]).
//! 4. LOWTRAN 7's aerosol ([`super::aerosol`], [`BuiltinParams::aerosol`]):
//!    rural (default, 23 km visibility), urban or maritime in the boundary
//!    layer over its tropospheric and stratospheric background, its
//!    extinction added to the optical depth and emitting with it (LOWTRAN 7
//!    without multiple scattering). Sunlight scattered once into the path
//!    is [`BuiltinAtmosphere::path_sunlit`] ([`super::scatter`]). On the
//!    six AFGL profiles the zenith path is within 4 % in τ̄ and 7 % in L of
//!    LOWTRAN 7, with and without aerosol, in 8–12, 8–14, 3–5 and
//!    3.5–4.5 µm, on the tropical one within 7 % of MODTRAN in τ̄, and the
//!    mid-latitude summer window and 3–5 µm clear-sky fluxes within 1.3 % of
//!    RRTMG (docs/physics/atmosphere.md has the comparisons).
//!
//! **Radiative transfer.** Along the slant path from the sensor, in segments
//! of at most 1 km and 250 m of altitude: cumulative transmittance τ(s) from
//! the continua's optical depth and the band models, and path radiance
//! L_u = Σ B(λ, T_i)·(τ(s_i) − τ(s_{i+1})) (Schwarzschild's equation without
//! a scattering source; the aerosol's extinction emits like absorption). τ → 1 and L_u → 0 as the range → 0; τ falls and L_u rises
//! with range and water vapour.
//!
//! **Sky.** The downwelling radiance of an isotropic equivalent sky is the
//! path radiance from the ground to 50 km at the diffusivity angle
//! (sec θ = 1.66, θ = 52.96°; Elsasser 1942), taken as a blackbody at the
//! air temperature beyond 16 µm (the water rotational band, opaque but in
//! dry air: 8 % too bright broadband on the sub-arctic winter), then
//! scaled so that its integral over 3–∞ µm equals the weather's broadband sky
//! longwave E_sky/π.

use super::PathSpectra;
use super::aerosol::{self, Aerosol, AerosolGrid, Season};
use super::lines;
use super::lowtran;
use super::profile::Profile;
use super::scatter::{self, Sun, SunColumn};
use crate::radiometry::solar;
use crate::radiometry::{Planck, SpectralGrid};
use crate::weather::WeatherRecord;
use crate::{Error, Result};

/// US Standard Atmosphere 1976 temperature, K, at geometric altitude `z_m`
/// (treated as geopotential; < 0.5 % error below 30 km).
pub fn us76_temperature_k(z_m: f64) -> f64 {
    let z = z_m / 1000.0;
    // (base altitude km, base temperature K, lapse K/km)
    const LAYERS: [(f64, f64, f64); 7] = [
        (0.0, 288.15, -6.5),
        (11.0, 216.65, 0.0),
        (20.0, 216.65, 1.0),
        (32.0, 228.65, 2.8),
        (47.0, 270.65, 0.0),
        (51.0, 270.65, -2.8),
        (71.0, 214.65, -2.0),
    ];
    let z = z.clamp(-1.0, 86.0);
    let mut t = LAYERS[0].1 + LAYERS[0].2 * z;
    for &(zb, tb, lapse) in LAYERS.iter() {
        if z >= zb {
            t = tb + lapse * (z - zb);
        }
    }
    t
}

/// Saturation vapour pressure over water, Pa (Magnus form, Alduchov &
/// Eskridge 1996), T in K.
pub fn saturation_vapour_pressure_pa(t_k: f64) -> f64 {
    let c = t_k - 273.15;
    610.94 * (17.625 * c / (c + 243.04)).exp()
}

const R_GAS: f64 = 8.314_462_618; // J/(mol K)
const M_H2O_G_MOL: f64 = 18.015;
const M_CO2_G_MOL: f64 = 44.01;
const M_O3_G_MOL: f64 = 48.00;
const M_N2O_G_MOL: f64 = 44.01;
/// N₂O volume mixing ratio, ppmv (well mixed; the AFGL profiles' 0.32 in
/// the troposphere).
const N2O_PPMV: f64 = 0.32;
/// CH₄ and CO volume mixing ratios, ppmv, well mixed: the tropospheric
/// values of the AFGL model atmospheres (Anderson et al. 1986, tables
/// 1a–1f: CH₄ 1.7; CO 0.15 near the ground, falling with height — the
/// ground value is used throughout).
const CH4_PPMV: f64 = 1.7;
const CO_PPMV: f64 = 0.15;
const AVOGADRO: f64 = 6.022_140_76e23;
/// N₂ volume mixing ratio of dry air.
const N2_FRACTION: f64 = 0.7808;
/// Integrated absorption of the N₂ collision-induced fundamental band,
/// cm⁻² amagat⁻² (Lafferty, Solodov, Weber, Olson & Hartmann 1996, Appl.
/// Opt. 35, 5911: 3.467·10⁻⁴ at 293 K, nearly independent of temperature).
const N2_CIA_INTEGRAL: f64 = 3.467e-4;
/// Centre of the N₂ fundamental, cm⁻¹.
const N2_CIA_CENTRE_CM: f64 = 2330.0;
/// Width ω of the exponential profile `(S/ω)·exp(−2|ν − ν₀|/ω)` of the N₂
/// band, cm⁻¹: a peak of 1.5·10⁻⁶ cm⁻¹ amagat⁻² (Lafferty et al. 1996,
/// fig. 3), so that the band spans ~2150–2600 cm⁻¹ as measured.
const N2_CIA_WIDTH_CM: f64 = 231.0;
/// Depth over which the weather's surface conditions fade into the model
/// profile, m (the order of a daytime boundary layer).
pub const SURFACE_BLEND_DEPTH_M: f64 = 2000.0;
const ATM_PA: f64 = 101_325.0;
const PRESSURE_SCALE_HEIGHT_M: f64 = 8000.0;
/// Top of the model atmosphere, m.
pub const TOP_OF_ATMOSPHERE_M: f64 = 50_000.0;
/// Zenith angle of the diffusivity approximation, degrees (sec θ = 1.66).
pub const DIFFUSIVITY_ZENITH_DEG: f64 = 52.96;

/// Surface meteorology that drives the built-in atmosphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceMet {
    /// Air temperature at the ground, K.
    pub air_temperature_k: f64,
    /// Relative humidity, 0–1.
    pub relative_humidity: f64,
    /// Station pressure, Pa.
    pub pressure_pa: f64,
    /// Ground altitude above sea level, m.
    pub ground_altitude_m: f64,
}

impl SurfaceMet {
    /// From a weather record and the site's altitude.
    pub fn from_weather(w: &WeatherRecord, ground_altitude_m: f64) -> Self {
        SurfaceMet {
            air_temperature_k: w.air_temperature_k,
            relative_humidity: w.relative_humidity,
            pressure_pa: w.pressure_pa,
            ground_altitude_m,
        }
    }

    /// The surface air of `profile` itself at `ground_altitude_m` (no
    /// weather: the profile unscaled).
    pub fn of_profile(profile: Profile, ground_altitude_m: f64) -> Self {
        let l = profile.level(ground_altitude_m);
        let e = l.h2o_ppmv * 1e-6 * l.pressure_pa;
        SurfaceMet {
            air_temperature_k: l.temperature_k,
            relative_humidity: (e / saturation_vapour_pressure_pa(l.temperature_k)).min(1.0),
            pressure_pa: l.pressure_pa,
            ground_altitude_m,
        }
    }
}

/// Tunable parameters of the built-in model (defaults as documented above).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BuiltinParams {
    /// Water-vapour density scale height, m.
    pub water_scale_height_m: f64,
    /// CO₂ volume mixing ratio, ppmv.
    pub co2_ppmv: f64,
    /// Longest path segment, m.
    pub max_segment_m: f64,
    /// Largest altitude change of a segment, m.
    pub max_segment_rise_m: f64,
    /// The AFGL model atmosphere above the surface ([`Profile`]); `None`:
    /// the analytic profile (US 1976 temperatures, exponential water
    /// vapour with [`BuiltinParams::water_scale_height_m`], no ozone).
    pub profile: Option<Profile>,
    /// LOWTRAN 7's aerosol ([`super::aerosol`]); `None`: clear air
    /// (gases only). Default: rural, 23 km visibility.
    pub aerosol: Option<Aerosol>,
    /// The aerosol's asymmetry parameter for the Henyey–Greenstein phase
    /// function of the scattered sunlight ([`super::scatter`]): `None`,
    /// LOWTRAN 7's tabulated g of each region (default); `Some(g)`, one g
    /// everywhere (MODTRAN's IPH = 0 with its card 3A2 G).
    pub aerosol_asymmetry: Option<f64>,
}

impl Default for BuiltinParams {
    fn default() -> Self {
        BuiltinParams {
            water_scale_height_m: 2000.0,
            co2_ppmv: 420.0,
            max_segment_m: 1000.0,
            max_segment_rise_m: 250.0,
            profile: None,
            aerosol: Some(Aerosol::default()),
            aerosol_asymmetry: None,
        }
    }
}

/// The built-in atmosphere (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct BuiltinAtmosphere {
    met: SurfaceMet,
    params: BuiltinParams,
    planck: Planck,
    /// The broadband integral of the unscaled sky shape
    /// ([`BuiltinAtmosphere::sky_scale`]), computed once: it depends only on
    /// the fields above, which do not change after construction.
    broadband: Broadband,
}

/// What the built-in model's paths need of one spectral grid
/// ([`BuiltinAtmosphere::prepare`]).
#[derive(Debug, Clone)]
pub struct PreparedGrid {
    wl: Vec<f64>,
    nu: Vec<f64>,
    windows: lines::LineWindows,
    band_model: lowtran::BandModelGrid,
    h2o_cont: Vec<[f64; 3]>,
    aerosol: Option<AerosolGrid>,
    /// Rayleigh cross-section per molecule on the grid, m².
    rayleigh_m2: Vec<f64>,
}

/// A once-computed broadband sky integral, W m⁻² sr⁻¹. Not part of the
/// atmosphere's identity: two atmospheres are equal whether or not either
/// has computed it.
#[derive(Debug, Clone, Default)]
struct Broadband(std::sync::OnceLock<f64>);

impl PartialEq for Broadband {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// Thermodynamic state at one altitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirState {
    /// Temperature, K.
    pub temperature_k: f64,
    /// Pressure, Pa.
    pub pressure_pa: f64,
    /// Water-vapour density, g/m³.
    pub water_g_m3: f64,
    /// Water-vapour partial pressure, Pa.
    pub water_pa: f64,
    /// CO₂ density, g/m³.
    pub co2_g_m3: f64,
    /// Ozone density, g/m³.
    pub o3_g_m3: f64,
    /// Nitrous oxide density, g/m³.
    pub n2o_g_m3: f64,
}

/// Malkmus narrow-band transmittance for X = Σ k̄u and overlap β.
#[inline]
fn malkmus(x: f64, beta: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let beta = beta.max(1e-12);
    (-(0.5 * beta) * ((1.0 + 4.0 * x / beta).sqrt() - 1.0)).exp()
}

/// N₂ collision-induced absorption coefficient, cm⁻¹ amagat⁻², at
/// wavenumber `nu` (cm⁻¹): the fundamental band as an exponential profile
/// of the measured integral (see [`N2_CIA_INTEGRAL`]).
#[inline]
fn n2_cia(nu: f64) -> f64 {
    let x = 2.0 * (nu - N2_CIA_CENTRE_CM).abs() / N2_CIA_WIDTH_CM;
    if x > 40.0 {
        0.0
    } else {
        N2_CIA_INTEGRAL / N2_CIA_WIDTH_CM * (-x).exp()
    }
}

impl BuiltinAtmosphere {
    /// A built-in atmosphere for the given surface conditions; validates them.
    pub fn new(met: SurfaceMet) -> Result<Self> {
        BuiltinAtmosphere::with_params(met, BuiltinParams::default())
    }

    /// With explicit parameters.
    pub fn with_params(met: SurfaceMet, params: BuiltinParams) -> Result<Self> {
        let check = |ok: bool, field: &str, msg: String| {
            if ok {
                Ok(())
            } else {
                Err(Error::invalid(field, msg))
            }
        };
        check(
            met.air_temperature_k.is_finite() && (150.0..=350.0).contains(&met.air_temperature_k),
            "air_temperature_k",
            format!("expected 150–350 K, got {}", met.air_temperature_k),
        )?;
        check(
            (0.0..=1.0).contains(&met.relative_humidity),
            "relative_humidity",
            format!("expected a fraction 0–1, got {}", met.relative_humidity),
        )?;
        check(
            met.pressure_pa.is_finite() && (30_000.0..=110_000.0).contains(&met.pressure_pa),
            "pressure_pa",
            format!("expected 30 000–110 000 Pa, got {}", met.pressure_pa),
        )?;
        check(
            met.ground_altitude_m.is_finite() && met.ground_altitude_m < 9000.0,
            "ground_altitude_m",
            format!("expected below 9000 m, got {}", met.ground_altitude_m),
        )?;
        check(
            params.water_scale_height_m > 0.0
                && params.co2_ppmv >= 0.0
                && params.max_segment_m > 0.0
                && params.max_segment_rise_m > 0.0,
            "params",
            "scale height and segment sizes must be positive".into(),
        )?;
        if let Some(a) = params.aerosol {
            Aerosol::new(a.model, a.visibility_km)?;
        }
        if let Some(g) = params.aerosol_asymmetry {
            check(
                g.is_finite() && g > -1.0 && g < 1.0,
                "aerosol_asymmetry",
                format!("expected −1 < g < 1, got {g}"),
            )?;
        }
        Ok(BuiltinAtmosphere {
            met,
            params,
            planck: Planck::default(),
            broadband: Broadband::default(),
        })
    }

    /// The surface conditions.
    pub fn met(&self) -> &SurfaceMet {
        &self.met
    }

    /// Precipitable water of the vertical column above the ground, g/cm².
    pub fn water_column_g_cm2(&self) -> f64 {
        if self.params.profile.is_none() {
            return self.state(self.met.ground_altitude_m).water_g_m3
                * self.params.water_scale_height_m
                * 1e-4;
        }
        // Midpoint rule over 10 m layers to the top of the model.
        let z0 = self.met.ground_altitude_m;
        let n = ((TOP_OF_ATMOSPHERE_M - z0) / 10.0).ceil() as usize;
        let dz = (TOP_OF_ATMOSPHERE_M - z0) / n as f64;
        (0..n)
            .map(|i| self.state(z0 + (i as f64 + 0.5) * dz).water_g_m3 * dz)
            .sum::<f64>()
            * 1e-4
    }

    /// The parameters.
    pub fn params(&self) -> &BuiltinParams {
        &self.params
    }

    /// The season of the aerosol's tropospheric and stratospheric profiles:
    /// LOWTRAN 7's choice for its model atmospheres (fall–winter for the
    /// two winter profiles), spring–summer on the analytic profile.
    pub fn aerosol_season(&self) -> Season {
        match self.params.profile {
            Some(Profile::MidLatitudeWinter | Profile::SubArcticWinter) => Season::FallWinter,
            _ => Season::SpringSummer,
        }
    }

    /// The air at altitude `z_m` (m above sea level).
    pub fn state(&self, z_m: f64) -> AirState {
        if let Some(profile) = self.params.profile {
            return self.profile_state(profile, z_m);
        }
        let m = &self.met;
        let dz = z_m - m.ground_altitude_m;
        let shift = m.air_temperature_k - us76_temperature_k(m.ground_altitude_m);
        let w = ((20_000.0 - z_m) / 9000.0).clamp(0.0, 1.0);
        let t = us76_temperature_k(z_m) + shift * w;
        let p = m.pressure_pa * (-dz / PRESSURE_SCALE_HEIGHT_M).exp();
        let e0 = m.relative_humidity * saturation_vapour_pressure_pa(m.air_temperature_k);
        let rho0 = e0 * M_H2O_G_MOL / (R_GAS * m.air_temperature_k);
        let rho = rho0 * (-dz / self.params.water_scale_height_m).exp();
        let e = (rho * R_GAS * t / M_H2O_G_MOL).min(0.5 * p);
        let co2 = self.params.co2_ppmv * 1e-6 * p * M_CO2_G_MOL / (R_GAS * t);
        AirState {
            temperature_k: t,
            pressure_pa: p,
            water_g_m3: rho,
            water_pa: e,
            co2_g_m3: co2,
            o3_g_m3: 0.0,
            n2o_g_m3: N2O_PPMV * 1e-6 * p * M_N2O_G_MOL / (R_GAS * t),
        }
    }

    /// [`BuiltinAtmosphere::state`] on an AFGL profile: the profile's air
    /// with the surface conditions blended in over the lowest
    /// [`SURFACE_BLEND_DEPTH_M`] — temperature shifted by
    /// ΔT = T_air − T_profile(z_g) and the water-vapour mixing ratio scaled
    /// by x_w(weather)/x_w(profile at z_g), both by a weight falling
    /// linearly from 1 at the ground to 0 at the blend depth; pressure
    /// scaled everywhere by p_s/p_profile(z_g) (the column hydrostatically
    /// heavier or lighter).
    fn profile_state(&self, profile: Profile, z_m: f64) -> AirState {
        let m = &self.met;
        let g = profile.level(m.ground_altitude_m);
        let l = profile.level(z_m);
        let w = (1.0 - (z_m - m.ground_altitude_m) / SURFACE_BLEND_DEPTH_M).clamp(0.0, 1.0);
        let t = l.temperature_k + (m.air_temperature_k - g.temperature_k) * w;
        let p = l.pressure_pa * m.pressure_pa / g.pressure_pa;
        let x_met = m.relative_humidity * saturation_vapour_pressure_pa(m.air_temperature_k)
            / m.pressure_pa;
        let x_prof = g.h2o_ppmv * 1e-6;
        let scale = if x_prof > 0.0 { x_met / x_prof } else { 1.0 };
        let x_w = l.h2o_ppmv * 1e-6 * (1.0 + (scale - 1.0) * w);
        let e = (x_w * p).min(0.5 * p);
        let mol_m3 = p / (R_GAS * t);
        AirState {
            temperature_k: t,
            pressure_pa: p,
            water_g_m3: e / (R_GAS * t) * M_H2O_G_MOL,
            water_pa: e,
            co2_g_m3: self.params.co2_ppmv * 1e-6 * mol_m3 * M_CO2_G_MOL,
            o3_g_m3: l.o3_ppmv * 1e-6 * mol_m3 * M_O3_G_MOL,
            n2o_g_m3: N2O_PPMV * 1e-6 * mol_m3 * M_N2O_G_MOL,
        }
    }

    /// Transmittance and path radiance along a straight path from a sensor
    /// at altitude `sensor_altitude_m` to a point at `target_altitude_m`,
    /// `range_m` apart, on `grid`.
    pub fn path(
        &self,
        sensor_altitude_m: f64,
        target_altitude_m: f64,
        range_m: f64,
        grid: &SpectralGrid,
    ) -> Result<PathSpectra> {
        self.path_prepared(
            &self.prepare(grid),
            sensor_altitude_m,
            target_altitude_m,
            range_m,
        )
    }

    /// What [`BuiltinAtmosphere::path`] needs of `grid` whatever the path
    /// (line windows, band-model samples, continuum and aerosol
    /// coefficients), for many paths on one grid
    /// ([`BuiltinAtmosphere::path_prepared`]).
    pub fn prepare(&self, grid: &SpectralGrid) -> PreparedGrid {
        let wl = grid.wavelengths_um().to_vec();
        let nu: Vec<f64> = wl.iter().map(|l| 1e4 / l).collect();
        let windows = lines::LineWindows::new(lines::co2_bands(), &nu);
        let band_model = lowtran::BandModelGrid::new(&nu, &lines::window_widths(&nu));
        let h2o_cont: Vec<[f64; 3]> = nu.iter().map(|&v| lowtran::continuum(v)).collect();
        let aerosol = self
            .params
            .aerosol
            .map(|a| AerosolGrid::new(a, self.aerosol_season(), &wl));
        let rayleigh_m2 = wl
            .iter()
            .map(|&l| scatter::rayleigh_cross_section_m2(l))
            .collect();
        PreparedGrid {
            wl,
            nu,
            windows,
            band_model,
            h2o_cont,
            aerosol,
            rayleigh_m2,
        }
    }

    /// [`BuiltinAtmosphere::path`] on a grid prepared by this atmosphere's
    /// [`BuiltinAtmosphere::prepare`] (the same values).
    pub fn path_prepared(
        &self,
        prepared: &PreparedGrid,
        sensor_altitude_m: f64,
        target_altitude_m: f64,
        range_m: f64,
    ) -> Result<PathSpectra> {
        self.march(
            prepared,
            sensor_altitude_m,
            target_altitude_m,
            range_m,
            None,
            None,
        )
    }

    /// [`BuiltinAtmosphere::path_prepared`] with the single-scattered
    /// sunlight along the same path ([`super::scatter`]): the path spectra
    /// (thermal) and L_ss(λ), W·m⁻²·sr⁻¹·µm⁻¹, for the sun of `column`
    /// ([`BuiltinAtmosphere::sun_column`] on the same grid) at
    /// `cos_theta`, the cosine of the scattering angle.
    pub fn path_sunlit(
        &self,
        prepared: &PreparedGrid,
        sensor_altitude_m: f64,
        target_altitude_m: f64,
        range_m: f64,
        column: &SunColumn,
        cos_theta: f64,
    ) -> Result<(PathSpectra, Vec<f64>)> {
        let (p, mut out) = self.path_sunlit_angles(
            prepared,
            sensor_altitude_m,
            target_altitude_m,
            range_m,
            column,
            &[cos_theta],
        )?;
        Ok((p, out.pop().unwrap_or_default()))
    }

    /// [`BuiltinAtmosphere::path_sunlit`] at several scattering angles in
    /// one march (the same values as one call per angle): L_ss(λ) for each
    /// of `cos_thetas`, the cosines of the scattering angles.
    pub fn path_sunlit_angles(
        &self,
        prepared: &PreparedGrid,
        sensor_altitude_m: f64,
        target_altitude_m: f64,
        range_m: f64,
        column: &SunColumn,
        cos_thetas: &[f64],
    ) -> Result<(PathSpectra, Vec<Vec<f64>>)> {
        let n = prepared.wl.len();
        let k = cos_thetas.len();
        // Wavelength-major while marching (the angles of one wavelength
        // adjacent), angle-major out.
        let mut flat = vec![0.0; n * k];
        let p = self.march(
            prepared,
            sensor_altitude_m,
            target_altitude_m,
            range_m,
            Some((column, cos_thetas, &mut flat)),
            None,
        )?;
        let out = (0..k)
            .map(|j| (0..n).map(|i| flat[i * k + j]).collect())
            .collect();
        Ok((p, out))
    }

    /// The sun's beam on `prepared`'s grid: E₀/d² and τ_sun against
    /// altitude, from one slant path from the top of the model atmosphere
    /// down to the ground at the sun's zenith (clamped to 89°, as
    /// [`super::Atmosphere::solar_transmittance`]); `None` for the sun at or
    /// below the horizon.
    pub fn sun_column(&self, prepared: &PreparedGrid, sun: &Sun) -> Result<Option<SunColumn>> {
        if !sun.is_up() {
            return Ok(None);
        }
        let z0 = self.met.ground_altitude_m;
        let range = (TOP_OF_ATMOSPHERE_M - z0) / sun.zenith_deg.min(89.0).to_radians().cos();
        let mut nodes = vec![(TOP_OF_ATMOSPHERE_M, vec![1.0; prepared.wl.len()])];
        self.march(
            prepared,
            TOP_OF_ATMOSPHERE_M,
            z0,
            range,
            None,
            Some(&mut nodes),
        )?;
        nodes.reverse();
        let e0: Vec<f64> = prepared
            .wl
            .iter()
            .map(|&l| {
                solar::solar_irradiance_toa_at(l) * sun.attenuation
                    / (sun.distance_au * sun.distance_au)
            })
            .collect();
        Ok(Some(SunColumn {
            sun: *sun,
            irradiance_toa: e0,
            altitudes_m: nodes.iter().map(|n| n.0).collect(),
            transmittance: nodes.into_iter().map(|n| n.1).collect(),
        }))
    }

    /// The path march: τ and the thermal L_u, with the single-scattered
    /// sunlight at each scattering angle of `scatter.1` (cosines) added to
    /// `scatter.2` (wavelength-major: `[i · angles + k]`) when given, and
    /// the altitude and
    /// cumulative τ at the end of every segment pushed to `record`.
    fn march(
        &self,
        prepared: &PreparedGrid,
        sensor_altitude_m: f64,
        target_altitude_m: f64,
        range_m: f64,
        mut scatter: Option<(&SunColumn, &[f64], &mut Vec<f64>)>,
        mut record: Option<&mut Vec<(f64, Vec<f64>)>>,
    ) -> Result<PathSpectra> {
        if !(range_m.is_finite() && range_m >= 0.0) {
            return Err(Error::invalid(
                "range_m",
                format!("expected a range ≥ 0 m, got {range_m}"),
            ));
        }
        let rise = target_altitude_m - sensor_altitude_m;
        if !(rise.is_finite() && rise.abs() <= range_m * (1.0 + 1e-9) + 1e-6) {
            return Err(Error::invalid(
                "range_m",
                format!(
                    "a {range_m} m path cannot span the altitudes {sensor_altitude_m} m to \
                     {target_altitude_m} m"
                ),
            ));
        }
        let PreparedGrid {
            wl,
            nu,
            windows,
            band_model,
            h2o_cont,
            aerosol,
            rayleigh_m2,
        } = prepared;
        let n = wl.len();
        let mut tau = vec![1.0; n];
        let mut lu = vec![0.0; n];
        if range_m == 0.0 {
            return Ok(PathSpectra {
                transmittance: tau,
                path_radiance: lu,
            });
        }
        let cos = (rise / range_m).clamp(-1.0, 1.0);
        let step = if cos.abs() > 0.0 {
            self.params
                .max_segment_m
                .min(self.params.max_segment_rise_m / cos.abs())
        } else {
            self.params.max_segment_m
        };
        let mut cont = vec![0.0; n];
        let line_bands = lines::co2_bands();
        let mut w_bm = [0.0f64; lowtran::REGIONS.len()];
        let mut xl = vec![vec![0.0f64; line_bands.len()]; n];
        let mut xlb = vec![vec![0.0f64; line_bands.len()]; n];
        // Per segment, for the scattered sunlight: aerosol scattering
        // optical depth, the same weighted by g, Rayleigh optical depth.
        let mut sca = vec![0.0; if scatter.is_some() { n } else { 0 }];
        let mut g_sca = sca.clone();
        let mut ray = sca.clone();
        // The Rayleigh phase function of each angle, and the
        // Henyey–Greenstein one's cos Θ.
        let p_ray: Vec<f64> = scatter.as_ref().map_or(Vec::new(), |s| {
            s.1.iter().map(|&c| scatter::rayleigh_phase(c)).collect()
        });
        let fixed_g = self.params.aerosol_asymmetry;
        // Fixed segment boundaries k·step from the sensor, so a longer path
        // shares all the segments of a shorter one (exact monotonicity).
        let mut s0 = 0.0;
        while s0 < range_m {
            let s1 = (s0 + step).min(range_m);
            let ds = s1 - s0;
            let z = sensor_altitude_m + cos * 0.5 * (s0 + s1);
            let st = self.state(z.max(self.met.ground_altitude_m - 500.0));
            let t = st.temperature_k;
            let u_w_cm2 = st.water_g_m3 * ds * 1e-4;
            let p_atm = st.pressure_pa / ATM_PA;
            let line_layers: Vec<(lines::LayerBand, f64)> = (0..line_bands.len())
                .filter(|&b| windows.active(b))
                .map(|b| {
                    (
                        lines::layer_parameters(line_bands, windows, b, t, p_atm),
                        st.co2_g_m3 * ds,
                    )
                })
                .collect();
            // N₂ density in amagat (number density / Loschmidt's at 273.15 K, 1 atm).
            let n2 = N2_FRACTION * (st.pressure_pa - st.water_pa) / ATM_PA * 273.15 / t;
            let n2_path = n2 * n2 * ds * 100.0;
            // LOWTRAN 7: the layer's amounts, g/cm² of water and atm·cm of
            // the other gases, and its water continuum factors (module docs
            // of `lowtran`).
            let n_air = st.pressure_pa * AVOGADRO / (R_GAS * t);
            let atm_cm = |n_m3: f64| n_m3 * ds / (lowtran::LOSCHMIDT_M3 * 0.01);
            let per_m3 = |g_m3: f64, m: f64| g_m3 / m * AVOGADRO;
            let lt_amounts = [
                u_w_cm2,
                atm_cm(per_m3(st.co2_g_m3, M_CO2_G_MOL)),
                atm_cm(per_m3(st.o3_g_m3, M_O3_G_MOL)),
                atm_cm(per_m3(st.n2o_g_m3, M_N2O_G_MOL)),
                atm_cm(CO_PPMV * 1e-6 * n_air),
                atm_cm(CH4_PPMV * 1e-6 * n_air),
            ];
            if band_model.active() {
                lowtran::scaled_amounts(&mut w_bm, &lt_amounts, p_atm, t);
            }
            let w_a_bm = lowtran::powered_amounts(&w_bm);
            let n_w = per_m3(st.water_g_m3, M_H2O_G_MOL);
            let rho0 = 273.15 / 296.0;
            let col_w = n_w * ds * 1e-4 * 1e-20 / rho0;
            let self_w = col_w * n_w / lowtran::LOSCHMIDT_M3;
            let foreign_w = col_w * (n_air - n_w).max(0.0) / lowtran::LOSCHMIDT_M3;
            let w260 = ((296.0 - t) / 36.0).clamp(0.0, 1.0);
            if let Some(aer) = aerosol {
                // LOWTRAN 7's aerosol extinction at the segment's own
                // humidity, emitting like the gases (IMULT = 0).
                let rh = 100.0 * st.water_pa / saturation_vapour_pressure_pa(t);
                let z_aer = aerosol::profile_altitude_km(
                    z.max(self.met.ground_altitude_m),
                    self.met.ground_altitude_m,
                );
                aer.add_optical_depth(z_aer, rh.clamp(0.0, 100.0), ds, &mut cont);
                if scatter.is_some() {
                    sca.iter_mut().for_each(|x| *x = 0.0);
                    g_sca.iter_mut().for_each(|x| *x = 0.0);
                    aer.add_scattering(z_aer, rh.clamp(0.0, 100.0), ds, &mut sca, &mut g_sca);
                }
            }
            if scatter.is_some() {
                // σ_R(λ)·N·ds ([`scatter::rayleigh_scattering_per_m`]).
                let n_ds = scatter::air_number_density_m3(st.pressure_pa, t) * ds;
                for (r, &sigma) in ray.iter_mut().zip(rayleigh_m2) {
                    *r = sigma * n_ds;
                }
            }
            let sun_at = scatter.as_ref().map(|s| s.0.locate(z));
            for i in 0..n {
                let [c296, c260, cf] = h2o_cont[i];
                cont[i] += n2_cia(nu[i]) * n2_path + (c296 + w260 * c260) * self_w + cf * foreign_w;
                let mut t_lines = band_model.transmittance(i, &w_a_bm);
                for (b, (lb, amount)) in line_layers.iter().enumerate() {
                    cont[i] += lb.wing[i] * amount;
                    let ku = lb.kbar[i] * amount;
                    xl[i][b] += ku;
                    xlb[i][b] += ku * lb.beta[i];
                    if xl[i][b] > 0.0 {
                        t_lines *= malkmus(xl[i][b], xlb[i][b] / xl[i][b]);
                    }
                }
                let new_tau = ((-cont[i]).exp() * t_lines).min(tau[i]);
                lu[i] += self.planck.radiance(wl[i], t) * (tau[i] - new_tau);
                if let (Some((col, cos_thetas, out)), Some(at)) = (scatter.as_mut(), sun_at) {
                    // Single scattering (module docs of `scatter`): the
                    // segment's scattering optical depth, phase-weighted,
                    // times the mean view transmittance over it.
                    let source = col.irradiance_toa[i] * col.transmittance_at(at, i)
                        / (4.0 * std::f64::consts::PI)
                        * scatter::log_mean(tau[i], new_tau);
                    let k = cos_thetas.len();
                    let out = &mut out[i * k..(i + 1) * k];
                    let r = source * ray[i];
                    if sca[i] > 0.0 {
                        let g = fixed_g.unwrap_or(g_sca[i] / sca[i]);
                        let a = source * sca[i];
                        for ((o, &c), &pr) in out.iter_mut().zip(*cos_thetas).zip(&p_ray) {
                            *o += a * scatter::henyey_greenstein(g, c) + r * pr;
                        }
                    } else {
                        for (o, &pr) in out.iter_mut().zip(&p_ray) {
                            *o += r * pr;
                        }
                    }
                }
                tau[i] = new_tau;
            }
            if let Some(r) = record.as_mut() {
                r.push((sensor_altitude_m + cos * s1, tau.clone()));
            }
            s0 = s1;
        }
        Ok(PathSpectra {
            transmittance: tau,
            path_radiance: lu,
        })
    }

    /// Path from the ground up to the top of the model atmosphere at zenith
    /// angle `zenith_deg` (< 90°).
    pub fn path_to_space(&self, zenith_deg: f64, grid: &SpectralGrid) -> Result<PathSpectra> {
        if !(0.0..90.0).contains(&zenith_deg) {
            return Err(Error::invalid(
                "zenith_deg",
                format!("expected 0 ≤ zenith < 90°, got {zenith_deg}"),
            ));
        }
        let z0 = self.met.ground_altitude_m;
        let range = (TOP_OF_ATMOSPHERE_M - z0) / zenith_deg.to_radians().cos();
        self.path(z0, TOP_OF_ATMOSPHERE_M, range, grid)
    }

    /// Sky radiance (E_ds + E_de)/π on `grid`, W·m⁻²·sr⁻¹·µm⁻¹, scaled to
    /// the broadband sky longwave `sky_longwave_w_m2` (unscaled where that is
    /// not finite and positive): the sky toward the diffusivity zenith
    /// ([`BuiltinAtmosphere::sky_radiance_toward`]). See the module docs.
    pub fn sky_radiance(&self, sky_longwave_w_m2: f64, grid: &SpectralGrid) -> Result<Vec<f64>> {
        self.sky_radiance_toward(sky_longwave_w_m2, DIFFUSIVITY_ZENITH_DEG, grid)
    }

    /// The sky radiance arriving from zenith angle `zenith_deg` (< 90°):
    /// the path radiance from the ground to space in that direction, a
    /// blackbody at the air temperature beyond 16 µm, times the broadband
    /// scale of [`BuiltinAtmosphere::sky_scale`] (one factor for every
    /// direction, so the angular shape is the model's).
    pub fn sky_radiance_toward(
        &self,
        sky_longwave_w_m2: f64,
        zenith_deg: f64,
        grid: &SpectralGrid,
    ) -> Result<Vec<f64>> {
        let mut out = self.sky_shape(zenith_deg, grid)?;
        let scale = self.sky_scale(sky_longwave_w_m2)?;
        out.iter_mut().for_each(|v| *v *= scale);
        Ok(out)
    }

    /// The unscaled sky radiance toward `zenith_deg` on `grid`.
    fn sky_shape(&self, zenith_deg: f64, g: &SpectralGrid) -> Result<Vec<f64>> {
        let p = self.path_to_space(zenith_deg, g)?;
        Ok(g.wavelengths_um()
            .iter()
            .zip(p.path_radiance)
            .map(|(&l, lu)| {
                if l > 16.0 {
                    self.planck.radiance(l, self.met.air_temperature_k)
                } else {
                    lu
                }
            })
            .collect())
    }

    /// The factor that makes the model's isotropic-equivalent sky (the sky
    /// at the diffusivity zenith, 52.96°) integrate over 3–∞ µm to the
    /// weather's E_sky/π; 1 where `sky_longwave_w_m2` is not finite and
    /// positive.
    pub fn sky_scale(&self, sky_longwave_w_m2: f64) -> Result<f64> {
        if !(sky_longwave_w_m2.is_finite() && sky_longwave_w_m2 > 0.0) {
            return Ok(1.0);
        }
        let total = match self.broadband.0.get() {
            Some(&v) => v,
            None => {
                let v = self.broadband_sky()?;
                *self.broadband.0.get_or_init(|| v)
            }
        };
        Ok(sky_longwave_w_m2 / std::f64::consts::PI / total)
    }

    /// The broadband integral of the unscaled sky shape at the diffusivity
    /// zenith, W m⁻² sr⁻¹: 3–16 µm from the model at 0.02 µm, 16 µm–∞ a
    /// blackbody at the air temperature.
    fn broadband_sky(&self) -> Result<f64> {
        let g = SpectralGrid::uniform(3.0, 16.0, 0.02)?;
        let model = g.integrate(&self.sky_shape(DIFFUSIVITY_ZENITH_DEG, &g)?);
        let t = self.met.air_temperature_k;
        let sigma_t4_pi = crate::radiometry::Constants::CODATA_2018.stefan_boltzmann_w_m2_k4()
            * t.powi(4)
            / std::f64::consts::PI;
        let below16 = SpectralGrid::uniform(0.5, 16.0, 0.005)?;
        let bb_below = below16.integrate(&below16.blackbody(&self.planck, t));
        Ok(model + (sigma_t4_pi - bb_below))
    }
}
