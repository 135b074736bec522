//! Atmosphere: path transmittance τ₂ and path radiance L_u between a surface
//! and the sensor, sky downwelling radiance, and solar transmittance τ₁ —
//! spectral, on the caller's [`SpectralGrid`].
//!
//! - [`Atmosphere`] is the closed set of models the render integrator calls:
//!   `None` (vacuum), [`BuiltinAtmosphere`] (needs nothing external; see
//!   [`builtin`] for the model and its sources, on the analytic profile or
//!   one of the six AFGL model atmospheres of [`profile`], with LOWTRAN 7's
//!   aerosol of [`aerosol`]) and [`Tape7Lut`]
//!   (a table of MODTRAN runs, see [`lut`]).
//! - The sky depends on direction: [`Atmosphere::sky_radiance_toward`]
//!   (what a ray leaving the scene sees), [`Atmosphere::sky_radiance`] (the
//!   isotropic equivalent a diffuse surface reflects), and
//!   [`Atmosphere::look_up`] (τ to space with the sky radiance, as
//!   `irsig atmosphere --look up` prints it).
//! - [`tape7`]: the MODTRAN tape7 reader (radiance and transmittance modes).
//! - [`PathTable`]: path spectra tabulated over view zenith and range for one
//!   sensor position — what a renderer should look up per hit (the built-in
//!   model integrates tens of layers per call, ~0.5 ms for 600 wavelengths).
//!
//! - Scattered sunlight ([`scatter`]): the built-in model's single
//!   scattering of the direct solar beam by aerosols and molecules into a
//!   line of sight, for a [`Sun`]: [`Atmosphere::scattered_solar`],
//!   [`Atmosphere::scattered_solar_up`], [`PreparedPaths::path_sunlit`]
//!   (the thermal-only functions above are unchanged).
//!
//! Geometry is flat-earth: a straight path from the sensor to the target,
//! view zenith at the target cos θ = (h_sensor − h_target)/range.
//!
//! Takes the surface weather and a spectral grid; gives path and sky
//! spectra. It must not know scenes, facets or sensors beyond a position and
//! a view direction.

pub mod aerosol;
pub mod builtin;
pub mod lines;
pub mod lowtran;
pub mod lut;
pub mod profile;
pub mod scatter;
pub mod table;
pub mod tape7;

pub use aerosol::{Aerosol, AerosolModel};
pub use builtin::{BuiltinAtmosphere, BuiltinParams, SurfaceMet};
pub use lut::{Tape7Lut, Tape7Run};
pub use profile::{Profile, ProfileLevel};
pub use scatter::{ANGLE_NODES, Sun, SunColumn, angle_node, angle_node_cos};
pub use table::PathTable;
pub use tape7::{Tape7, Tape7Column, Tape7Mode};

use crate::radiometry::{Constants, Planck, SpectralGrid};
use crate::{Error, Result};

/// Transmittance and path radiance of one path, on a spectral grid.
#[derive(Debug, Clone, PartialEq)]
pub struct PathSpectra {
    /// Path transmittance τ(λ), 0–1.
    pub transmittance: Vec<f64>,
    /// Path radiance L_u(λ) toward the sensor, W·m⁻²·sr⁻¹·µm⁻¹.
    pub path_radiance: Vec<f64>,
}

/// A sensor-to-target path. Altitudes above sea level, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathGeometry {
    /// Sensor altitude, m.
    pub sensor_altitude_m: f64,
    /// Target (hit point) altitude, m.
    pub target_altitude_m: f64,
    /// Straight-line distance, m (≥ |altitude difference|).
    pub range_m: f64,
}

impl PathGeometry {
    /// Zenith angle of the line of sight from the sensor toward the target,
    /// degrees (0 = looking straight up, 180 = straight down):
    /// 180° − [`PathGeometry::view_zenith_deg`].
    pub fn line_of_sight_zenith_deg(&self) -> f64 {
        180.0 - self.view_zenith_deg()
    }

    /// View zenith angle at the target, degrees (0 = sensor straight above).
    pub fn view_zenith_deg(&self) -> f64 {
        if self.range_m <= 0.0 {
            return 0.0;
        }
        ((self.sensor_altitude_m - self.target_altitude_m) / self.range_m)
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
    }
}

/// Conditions for the sky radiance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkyConditions {
    /// Air temperature at the ground, K.
    pub air_temperature_k: f64,
    /// Broadband downwelling sky longwave on a horizontal surface, W/m².
    pub sky_longwave_w_m2: f64,
}

/// The atmosphere between the scene and the sensor.
#[derive(Debug, Clone, PartialEq)]
pub enum Atmosphere {
    /// No atmosphere: τ = 1, L_u = 0, τ₁ = 1; the sky is a grey body at the
    /// air temperature with the weather's broadband sky longwave.
    None,
    /// The built-in model.
    Builtin(BuiltinAtmosphere),
    /// A table of MODTRAN tape7 runs.
    Tape7Lut(Tape7Lut),
}

fn grey_sky(sky: &SkyConditions, grid: &SpectralGrid) -> Result<Vec<f64>> {
    let t = sky.air_temperature_k;
    if !(t.is_finite() && t > 0.0) {
        return Err(Error::invalid(
            "air_temperature_k",
            format!("expected a positive temperature, got {t}"),
        ));
    }
    let sigma = Constants::CODATA_2018.stefan_boltzmann_w_m2_k4();
    let eps = if sky.sky_longwave_w_m2.is_finite() && sky.sky_longwave_w_m2 > 0.0 {
        sky.sky_longwave_w_m2 / (sigma * t.powi(4))
    } else {
        1.0
    };
    Ok(grid
        .blackbody(&Planck::default(), t)
        .into_iter()
        .map(|b| eps * b)
        .collect())
}

/// Most view zenith of a look up through the flat-earth model, degrees: the
/// horizon itself has an infinite path (a round earth would give ~38 air
/// masses; 89° gives 57).
pub const MAX_SKY_ZENITH_DEG: f64 = 89.0;

/// The spectral range the built-in model covers, µm (its LOWTRAN 7 band
/// models and continuum tables, 3–16 µm).
pub const BUILTIN_RANGE_UM: (f64, f64) = (3.0, 16.0);

impl Atmosphere {
    /// The built-in model on the AFGL `profile` for a weather record at a
    /// site altitude (the record's surface conditions blended into the
    /// profile's lowest layers, see [`BuiltinAtmosphere::state`]).
    pub fn builtin_profile(
        profile: Profile,
        weather: &crate::weather::WeatherRecord,
        ground_altitude_m: f64,
    ) -> Result<Self> {
        Ok(Atmosphere::Builtin(BuiltinAtmosphere::with_params(
            SurfaceMet::from_weather(weather, ground_altitude_m),
            BuiltinParams {
                profile: Some(profile),
                ..BuiltinParams::default()
            },
        )?))
    }

    /// The built-in model on the AFGL `profile` as tabulated (no weather),
    /// for a ground at `ground_altitude_m`.
    pub fn standard(profile: Profile, ground_altitude_m: f64) -> Result<Self> {
        Ok(Atmosphere::Builtin(BuiltinAtmosphere::with_params(
            SurfaceMet::of_profile(profile, ground_altitude_m),
            BuiltinParams {
                profile: Some(profile),
                ..BuiltinParams::default()
            },
        )?))
    }

    /// The wavelengths the model covers, µm: the built-in model's
    /// absorbers are modelled over 3–16 µm (beyond, the sky is a blackbody
    /// at the air temperature); the vacuum and tape7 tables (whose runs say
    /// their own coverage when resampled) have no fixed range.
    pub fn spectral_range_um(&self) -> Option<(f64, f64)> {
        match self {
            Atmosphere::Builtin(_) => Some(BUILTIN_RANGE_UM),
            _ => None,
        }
    }

    /// Looking up from the ground at `zenith_deg` (0 ≤ zenith < 90°,
    /// clamped to [`MAX_SKY_ZENITH_DEG`]): the transmittance to space and
    /// the sky radiance arriving from that direction
    /// ([`Atmosphere::sky_radiance_toward`]).
    pub fn look_up(
        &self,
        sky: &SkyConditions,
        zenith_deg: f64,
        grid: &SpectralGrid,
    ) -> Result<PathSpectra> {
        if !(0.0..90.0).contains(&zenith_deg) {
            return Err(Error::invalid(
                "zenith_deg",
                format!("looking up needs 0 ≤ zenith < 90°, got {zenith_deg}"),
            ));
        }
        let z = zenith_deg.min(MAX_SKY_ZENITH_DEG);
        let transmittance = match self {
            Atmosphere::None => vec![1.0; grid.len()],
            Atmosphere::Builtin(b) => b.path_to_space(z, grid)?.transmittance,
            Atmosphere::Tape7Lut(l) if !l.sky_runs.is_empty() => l.sky(z, grid)?.transmittance,
            Atmosphere::Tape7Lut(_) => vec![1.0; grid.len()],
        };
        Ok(PathSpectra {
            transmittance,
            path_radiance: self.sky_radiance_toward(sky, z, grid)?,
        })
    }

    /// Sky radiance arriving at the ground from zenith angle `zenith_deg`
    /// (0 ≤ zenith < 90°, clamped to [`MAX_SKY_ZENITH_DEG`]),
    /// W·m⁻²·sr⁻¹·µm⁻¹: the built-in model's path radiance from the ground
    /// to space in that direction (a blackbody at the air temperature beyond
    /// 16 µm), with the same broadband scale to the weather's sky longwave
    /// as [`Atmosphere::sky_radiance`]; the tape7 table's sky runs
    /// interpolated in zenith; the grey sky (isotropic) with no atmosphere
    /// or no sky runs.
    pub fn sky_radiance_toward(
        &self,
        sky: &SkyConditions,
        zenith_deg: f64,
        grid: &SpectralGrid,
    ) -> Result<Vec<f64>> {
        if !(zenith_deg.is_finite() && zenith_deg >= 0.0) {
            return Err(Error::invalid(
                "zenith_deg",
                format!("expected a zenith ≥ 0°, got {zenith_deg}"),
            ));
        }
        let z = zenith_deg.min(MAX_SKY_ZENITH_DEG);
        match self {
            Atmosphere::None => grey_sky(sky, grid),
            Atmosphere::Builtin(b) => b.sky_radiance_toward(sky.sky_longwave_w_m2, z, grid),
            Atmosphere::Tape7Lut(l) if !l.sky_runs.is_empty() => Ok(l.sky(z, grid)?.path_radiance),
            Atmosphere::Tape7Lut(_) => grey_sky(sky, grid),
        }
    }

    /// [`Atmosphere::sky_radiance_toward`] for each of `zeniths_deg` (the
    /// built-in model's broadband scale computed once).
    pub fn sky_radiances_toward(
        &self,
        sky: &SkyConditions,
        zeniths_deg: &[f64],
        grid: &SpectralGrid,
    ) -> Result<Vec<Vec<f64>>> {
        match self {
            Atmosphere::Builtin(b) => {
                let scale = b.sky_scale(sky.sky_longwave_w_m2)?;
                zeniths_deg
                    .iter()
                    .map(|&z| {
                        let mut v =
                            b.sky_radiance_toward(f64::NAN, z.min(MAX_SKY_ZENITH_DEG), grid)?;
                        v.iter_mut().for_each(|x| *x *= scale);
                        Ok(v)
                    })
                    .collect()
            }
            _ => zeniths_deg
                .iter()
                .map(|&z| self.sky_radiance_toward(sky, z, grid))
                .collect(),
        }
    }

    /// The built-in model for a weather record at a site altitude.
    pub fn builtin(
        weather: &crate::weather::WeatherRecord,
        ground_altitude_m: f64,
    ) -> Result<Self> {
        Ok(Atmosphere::Builtin(BuiltinAtmosphere::new(
            SurfaceMet::from_weather(weather, ground_altitude_m),
        )?))
    }

    /// A tape7 lookup table from its JSON index file.
    pub fn tape7_index(path: impl AsRef<std::path::Path>) -> Result<Self> {
        Ok(Atmosphere::Tape7Lut(Tape7Lut::read_index(path)?))
    }

    /// Single-scattered sunlight L_ss(λ) along `geom` toward the sensor,
    /// W·m⁻²·sr⁻¹·µm⁻¹ ([`scatter`]; not part of [`Atmosphere::path`]'s
    /// thermal path radiance): zero with no atmosphere or the sun at or
    /// below the horizon.
    ///
    /// # Errors
    /// A tape7 table: its runs' path radiance already holds their own
    /// scattered sunlight (SOL_SCAT) and cannot be split by sun position.
    pub fn scattered_solar(
        &self,
        geom: &PathGeometry,
        sun: &Sun,
        grid: &SpectralGrid,
    ) -> Result<Vec<f64>> {
        let p = self.prepare(grid);
        let column = p.sun_column(sun)?;
        p.scattered(geom, column.as_ref())
    }

    /// [`Atmosphere::scattered_solar`] looking up from the ground at
    /// `zenith_deg` (0 ≤ zenith < 90°, clamped to [`MAX_SKY_ZENITH_DEG`])
    /// to the top of the model atmosphere: the sky's scattered sunlight
    /// from that direction.
    pub fn scattered_solar_up(
        &self,
        zenith_deg: f64,
        sun: &Sun,
        grid: &SpectralGrid,
    ) -> Result<Vec<f64>> {
        if !(0.0..90.0).contains(&zenith_deg) {
            return Err(Error::invalid(
                "zenith_deg",
                format!("looking up needs 0 ≤ zenith < 90°, got {zenith_deg}"),
            ));
        }
        let z = zenith_deg.min(MAX_SKY_ZENITH_DEG);
        let ground = match self {
            Atmosphere::Builtin(b) => b.met().ground_altitude_m,
            _ => 0.0,
        };
        let geom = PathGeometry {
            sensor_altitude_m: ground,
            target_altitude_m: builtin::TOP_OF_ATMOSPHERE_M,
            range_m: (builtin::TOP_OF_ATMOSPHERE_M - ground) / z.to_radians().cos(),
        };
        self.scattered_solar(&geom, sun, grid)
    }

    /// The sky's single-scattered sunlight ([`scatter`]) arriving at the
    /// ground from each of `zeniths_deg` (0 ≤ zenith < 90°, clamped to
    /// [`MAX_SKY_ZENITH_DEG`]), at each scattering angle of `cos_thetas`
    /// (cosines): `[zenith][angle]` spectra L_ss(λ), W·m⁻²·sr⁻¹·µm⁻¹, along
    /// the path from the ground to the top of the model atmosphere
    /// ([`Atmosphere::scattered_solar_up`]'s, one march per zenith for all
    /// angles). `None` where there is none: no atmosphere, a tape7 table
    /// (its sky runs hold their own), the sun at or below the horizon.
    pub fn scattered_sky(
        &self,
        zeniths_deg: &[f64],
        sun: &Sun,
        cos_thetas: &[f64],
        grid: &SpectralGrid,
    ) -> Result<Option<Vec<Vec<Vec<f64>>>>> {
        let Atmosphere::Builtin(b) = self else {
            return Ok(None);
        };
        if let Some(z) = zeniths_deg
            .iter()
            .find(|z| !(z.is_finite() && (0.0..90.0).contains(*z)))
        {
            return Err(Error::invalid(
                "zenith_deg",
                format!("looking up needs 0 ≤ zenith < 90°, got {z}"),
            ));
        }
        let p = self.prepare(grid);
        let Some(column) = p.sun_column(sun)? else {
            return Ok(None);
        };
        let ground = b.met().ground_altitude_m;
        // The zeniths in parallel (the same values as in turn).
        use rayon::prelude::*;
        zeniths_deg
            .par_iter()
            .map(|&z| {
                let z = z.min(MAX_SKY_ZENITH_DEG);
                let geom = PathGeometry {
                    sensor_altitude_m: ground,
                    target_altitude_m: builtin::TOP_OF_ATMOSPHERE_M,
                    range_m: (builtin::TOP_OF_ATMOSPHERE_M - ground) / z.to_radians().cos(),
                };
                let (_, ss) = p.path_sunlit_angles(&geom, Some(&column), cos_thetas)?;
                Ok(ss.unwrap_or_else(|| vec![vec![0.0; grid.len()]; cos_thetas.len()]))
            })
            .collect::<Result<Vec<_>>>()
            .map(Some)
    }

    /// τ₂(λ) and L_u(λ) along `geom` on `grid`.
    pub fn path(&self, geom: &PathGeometry, grid: &SpectralGrid) -> Result<PathSpectra> {
        self.prepare(grid).path(geom)
    }

    /// [`Atmosphere::path`] for many geometries on one `grid`: what the
    /// model needs of the grid computed once.
    pub fn prepare<'a>(&'a self, grid: &'a SpectralGrid) -> PreparedPaths<'a> {
        PreparedPaths {
            atmosphere: self,
            grid,
            builtin: match self {
                Atmosphere::Builtin(b) => Some(b.prepare(grid)),
                _ => None,
            },
        }
    }
}

/// Paths on one spectral grid ([`Atmosphere::prepare`]).
#[derive(Debug, Clone)]
pub struct PreparedPaths<'a> {
    atmosphere: &'a Atmosphere,
    grid: &'a SpectralGrid,
    builtin: Option<builtin::PreparedGrid>,
}

impl PreparedPaths<'_> {
    /// The sun's beam on this grid for [`PreparedPaths::path_sunlit`]
    /// ([`BuiltinAtmosphere::sun_column`]): `None` with no atmosphere, a
    /// tape7 table, or the sun at or below the horizon.
    pub fn sun_column(&self, sun: &Sun) -> Result<Option<SunColumn>> {
        match (self.atmosphere, &self.builtin) {
            (Atmosphere::Builtin(b), Some(p)) => b.sun_column(p, sun),
            _ => Ok(None),
        }
    }

    /// [`PreparedPaths::path`] with the single-scattered sunlight of
    /// `column` (from [`PreparedPaths::sun_column`] of this grid) added to
    /// the path radiance, at the scattering angle of `geom`'s line of sight
    /// and `column`'s sun; `None`: the thermal path alone.
    pub fn path_sunlit(
        &self,
        geom: &PathGeometry,
        column: Option<&SunColumn>,
    ) -> Result<PathSpectra> {
        let (Some(col), Atmosphere::Builtin(b), Some(p)) = (column, self.atmosphere, &self.builtin)
        else {
            return self.path(geom);
        };
        if !(geom.range_m.is_finite() && geom.range_m >= 0.0) {
            return self.path(geom);
        }
        // One march for both (the same values as `path` and `scattered`).
        let cos_theta = col
            .sun
            .cos_scattering_angle(geom.line_of_sight_zenith_deg());
        let (mut p, ss) = b.path_sunlit(
            p,
            geom.sensor_altitude_m,
            geom.target_altitude_m,
            geom.range_m,
            col,
            cos_theta,
        )?;
        p.path_radiance
            .iter_mut()
            .zip(ss)
            .for_each(|(l, s)| *l += s);
        Ok(p)
    }

    /// The thermal path along `geom` ([`PreparedPaths::path`]) and, apart,
    /// the single-scattered sunlight of `column` at each scattering angle
    /// of `cos_thetas` (cosines; one march for all): `None` without a
    /// column, or with no atmosphere or a tape7 table.
    pub fn path_sunlit_angles(
        &self,
        geom: &PathGeometry,
        column: Option<&SunColumn>,
        cos_thetas: &[f64],
    ) -> Result<(PathSpectra, Option<Vec<Vec<f64>>>)> {
        let (Some(col), Atmosphere::Builtin(b), Some(p)) = (column, self.atmosphere, &self.builtin)
        else {
            return Ok((self.path(geom)?, None));
        };
        if !(geom.range_m.is_finite() && geom.range_m >= 0.0) {
            return Ok((self.path(geom)?, None));
        }
        let (p, ss) = b.path_sunlit_angles(
            p,
            geom.sensor_altitude_m,
            geom.target_altitude_m,
            geom.range_m,
            col,
            cos_thetas,
        )?;
        Ok((p, Some(ss)))
    }

    /// The single-scattered sunlight alone along `geom` (zeros without a
    /// column). A tape7 table is an error ([`Atmosphere::scattered_solar`]).
    pub fn scattered(&self, geom: &PathGeometry, column: Option<&SunColumn>) -> Result<Vec<f64>> {
        if let Atmosphere::Tape7Lut(_) = self.atmosphere {
            return Err(Error::invalid(
                "atmosphere",
                "a tape7 table's path radiance already holds its runs' scattered sunlight \
                 (SOL_SCAT); the sun position cannot change it",
            ));
        }
        let (Some(col), Atmosphere::Builtin(b), Some(p)) = (column, self.atmosphere, &self.builtin)
        else {
            return Ok(vec![0.0; self.grid.len()]);
        };
        let cos_theta = col
            .sun
            .cos_scattering_angle(geom.line_of_sight_zenith_deg());
        Ok(b.path_sunlit(
            p,
            geom.sensor_altitude_m,
            geom.target_altitude_m,
            geom.range_m,
            col,
            cos_theta,
        )?
        .1)
    }

    /// τ₂(λ) and L_u(λ) along `geom` ([`Atmosphere::path`]).
    pub fn path(&self, geom: &PathGeometry) -> Result<PathSpectra> {
        let grid = self.grid;
        if !(geom.range_m.is_finite() && geom.range_m >= 0.0) {
            return Err(Error::invalid(
                "range_m",
                format!("expected a range ≥ 0 m, got {}", geom.range_m),
            ));
        }
        match (self.atmosphere, &self.builtin) {
            (Atmosphere::None, _) => Ok(PathSpectra {
                transmittance: vec![1.0; grid.len()],
                path_radiance: vec![0.0; grid.len()],
            }),
            (Atmosphere::Builtin(b), Some(p)) => b.path_prepared(
                p,
                geom.sensor_altitude_m,
                geom.target_altitude_m,
                geom.range_m,
            ),
            (Atmosphere::Builtin(b), None) => b.path(
                geom.sensor_altitude_m,
                geom.target_altitude_m,
                geom.range_m,
                grid,
            ),
            (Atmosphere::Tape7Lut(l), _) => l.path(geom.view_zenith_deg(), geom.range_m, grid),
        }
    }
}

impl Atmosphere {
    /// Sky radiance (E_ds + E_de)/π, W·m⁻²·sr⁻¹·µm⁻¹, on `grid`. The tape7
    /// table uses its sky runs at the diffusivity zenith (52.96°) as given
    /// (their band coverage does not allow broadband scaling), or the grey
    /// sky where it has none.
    pub fn sky_radiance(&self, sky: &SkyConditions, grid: &SpectralGrid) -> Result<Vec<f64>> {
        match self {
            Atmosphere::None => grey_sky(sky, grid),
            Atmosphere::Builtin(b) => b.sky_radiance(sky.sky_longwave_w_m2, grid),
            Atmosphere::Tape7Lut(l) if !l.sky_runs.is_empty() => {
                Ok(l.sky(builtin::DIFFUSIVITY_ZENITH_DEG, grid)?.path_radiance)
            }
            Atmosphere::Tape7Lut(_) => grey_sky(sky, grid),
        }
    }

    /// Solar transmittance τ₁(λ) from the top of the atmosphere to the
    /// ground for the sun at `sun_zenith_deg` (0 for the sun at or below the
    /// horizon).
    pub fn solar_transmittance(
        &self,
        sun_zenith_deg: f64,
        grid: &SpectralGrid,
    ) -> Result<Vec<f64>> {
        if !(sun_zenith_deg.is_finite()) {
            return Err(Error::invalid("sun_zenith_deg", "not a number"));
        }
        if sun_zenith_deg >= 90.0 {
            return Ok(vec![0.0; grid.len()]);
        }
        let z = sun_zenith_deg.max(0.0);
        match self {
            Atmosphere::None => Ok(vec![1.0; grid.len()]),
            Atmosphere::Builtin(b) => Ok(b.path_to_space(z.min(89.0), grid)?.transmittance),
            Atmosphere::Tape7Lut(l) => Ok(l.sky(z, grid)?.transmittance),
        }
    }
}
