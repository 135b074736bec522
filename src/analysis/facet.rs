//! The one-facet thermal path: a free-standing facet (tilt, azimuth, sky
//! shape factor, the sun unshadowed) solved with [`crate::thermal::solve`].
//! [`solve_free_facet`] solves it once; [`OneFacet`] serves sensitivity,
//! calibration and diurnal studies, computing the facet geometry — sunlit
//! fraction and solar incidence per record — once and holding it fixed
//! while materials and weather are perturbed. Takes materials (by name or
//! file, [`find_material`]), weather records and a site; gives surface
//! temperatures and band radiances. Knows nothing of scenes, ray tracing or
//! the command line.
//!
//! Surface-leaving band radiance (no atmospheric path, a sensor at the
//! surface), per wavelength of the band grid:
//! `L = ε B(T_s) + (1 − ε) [F B(T_sky) + (1 − F) B(T_air)]`, with
//! `T_sky = (E_sky/σ)^{1/4}` the effective sky temperature of the record's
//! downwelling longwave irradiance (an isotropic-sky approximation), `F`
//! the sky shape factor and `ε` the material's spectral emissivity at
//! normal view (Schott 2007, *Remote Sensing*, eq. 4.61 without path
//! terms). The apparent temperature is the band brightness temperature of L.

use std::path::Path;

use chrono::{DateTime, FixedOffset};

use crate::material::{Material, MaterialDb};
use crate::radiometry::band::Band;
use crate::sun::{self, Site};
use crate::thermal::{
    self, BackBoundary, FacetInputs, Forcing, STEFAN_BOLTZMANN_W_M2_K4, SlabProperties,
    SolveOptions,
};
use crate::weather::{WeatherHistory, WeatherRecord};
use crate::{Error, Result};

/// Orientation and sky view of a free-standing facet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FacetSpec {
    /// Tilt from horizontal, degrees (0 = facing up).
    pub tilt_deg: f64,
    /// Direction faced, degrees clockwise from north (180 = south).
    pub azimuth_deg: f64,
    /// Sky shape factor; `None` = `(1 + cos tilt)/2` (an unobstructed plane).
    pub shape_factor: Option<f64>,
    /// Sky shape factor of the back face, used only with an exposed back
    /// ([`BackBoundary::Exposed`]); `None` = `1 − F`, exact for an
    /// unobstructed plane (`(1 − cos tilt)/2`). A scene solve traces it
    /// (`exposure::exposed_back_shape_factors`); give it here to study a
    /// wall whose back is obstructed differently from its front (a canyon
    /// wall's back in the next street).
    pub back_shape_factor: Option<f64>,
    /// Albedo of the open ground the facet sees over `1 − F` of its
    /// hemisphere, which reflects the sun and sky onto it (isotropically,
    /// the ground fully sunlit: [`crate::thermal::Reflected::open_ground`]);
    /// default [`crate::exposure::reflected::GROUND_ALBEDO`], the value of
    /// the ground beyond a scene. 0 switches it off. A horizontal facet
    /// (`F = 1`) sees no ground.
    pub ground_albedo: f64,
}

impl Default for FacetSpec {
    fn default() -> Self {
        FacetSpec {
            tilt_deg: 0.0,
            azimuth_deg: 180.0,
            shape_factor: None,
            back_shape_factor: None,
            ground_albedo: crate::exposure::reflected::GROUND_ALBEDO as f64,
        }
    }
}

/// The default study band: 8–14 µm, flat response.
pub fn lwir_band() -> Result<Band> {
    Band::flat(8.0, 14.0, 0.05)
}

/// A facet with its fixed geometry over a weather history.
#[derive(Debug, Clone)]
pub struct OneFacet {
    /// The nominal weather records (the solve runs over all of them).
    pub records: Vec<WeatherRecord>,
    sun_fraction: Vec<f32>,
    cos_incidence: Vec<f32>,
    /// Ground-reflected shortwave per unit direct-normal irradiance.
    reflected_direct: Vec<f32>,
    /// Ground-reflected shortwave per unit diffuse-horizontal irradiance.
    reflected_diffuse: f64,
    /// Sky shape factor used.
    pub shape_factor: f64,
    /// Sky shape factor of an exposed back (`None`: `1 − F`).
    pub back_shape_factor: Option<f64>,
    /// Thermal solver options (spin-up always runs its full cycle count and
    /// Newton is tightened to 1e-7 K, so outputs are smooth in parameters).
    pub options: SolveOptions,
    /// Band of the radiance outputs.
    pub band: Band,
    /// The site (solar positions of perturbed weather).
    pub site: Site,
    /// Back boundary overriding the one the material's exposed area gives
    /// (as `irsig thermal --back`); `None`: the material's.
    pub back: Option<BackBoundary>,
}

/// The records of `history` up to `until`, ending with the weather
/// interpolated at `until` when it falls between records.
pub fn records_until(
    history: &WeatherHistory,
    until: DateTime<FixedOffset>,
) -> Result<Vec<WeatherRecord>> {
    let mut out: Vec<WeatherRecord> = history
        .records()
        .iter()
        .take_while(|r| r.time <= until)
        .copied()
        .collect();
    if out.last().is_none_or(|r| r.time < until) {
        out.push(history.at(until)?);
    }
    Ok(out)
}

/// The geometry of a free-standing facet over the records.
struct FreeGeometry {
    sun_fraction: Vec<f32>,
    cos_incidence: Vec<f32>,
    shape_factor: f64,
    /// Sky shape factor of an exposed back (`None`: `1 − F`).
    back_shape_factor: Option<f64>,
    /// Ground-reflected shortwave per unit `E_dn`, per record.
    reflected_direct: Vec<f32>,
    /// Ground-reflected shortwave per unit `E_d`.
    reflected_diffuse: f64,
}

impl FreeGeometry {
    fn inputs(&self) -> FacetInputs<'_> {
        FacetInputs {
            reflected: thermal::Reflected {
                direct: &self.reflected_direct,
                diffuse: self.reflected_diffuse,
            },
            back_shape_factor: self.back_shape_factor,
            ..FacetInputs::new(&self.sun_fraction, &self.cos_incidence, self.shape_factor)
        }
    }
}

/// Sunlit fraction and cosine of the solar incidence per record of a
/// free-standing facet (the sun unshadowed), its sky shape factor and the
/// shortwave reflected onto it by the open ground; the facet's tilt,
/// azimuth, shape factor and ground albedo checked.
fn free_facet_geometry(
    records: &[WeatherRecord],
    site: &Site,
    facet: &FacetSpec,
) -> Result<FreeGeometry> {
    if !(0.0..=1.0).contains(&facet.ground_albedo) {
        return Err(Error::invalid(
            "ground_albedo",
            format!("{} is not a fraction in 0..=1", facet.ground_albedo),
        ));
    }
    if !(facet.tilt_deg.is_finite() && (0.0..=180.0).contains(&facet.tilt_deg)) {
        return Err(Error::invalid(
            "tilt_deg",
            format!("{} is not a tilt in 0..=180 degrees", facet.tilt_deg),
        ));
    }
    if !facet.azimuth_deg.is_finite() {
        return Err(Error::invalid(
            "azimuth_deg",
            format!("{} is not a finite direction in degrees", facet.azimuth_deg),
        ));
    }
    let tilt = facet.tilt_deg.to_radians();
    let shape_factor = facet.shape_factor.unwrap_or((1.0 + tilt.cos()) / 2.0);
    if !(0.0..=1.0).contains(&shape_factor) {
        return Err(Error::invalid(
            "shape_factor",
            format!("{shape_factor} is not a fraction in 0..=1"),
        ));
    }
    if let Some(fb) = facet.back_shape_factor
        && !(0.0..=1.0).contains(&fb)
    {
        return Err(Error::invalid(
            "back_shape_factor",
            format!("{fb} is not a fraction in 0..=1"),
        ));
    }
    if records.is_empty() {
        return Err(Error::invalid("weather", "no weather records"));
    }
    let az = facet.azimuth_deg.to_radians();
    let normal = glam::DVec3::new(tilt.sin() * az.sin(), tilt.sin() * az.cos(), tilt.cos());
    let mut sun_fraction = Vec::with_capacity(records.len());
    let mut cos_incidence = Vec::with_capacity(records.len());
    let mut sin_elevation = Vec::with_capacity(records.len());
    for r in records {
        let p = sun::position_standard(site, r.time)?;
        let d = p.direction_enu();
        let cos = normal.dot(d).clamp(-1.0, 1.0);
        sun_fraction.push(if p.is_up() && cos > 0.0 { 1.0f32 } else { 0.0 });
        cos_incidence.push(cos as f32);
        sin_elevation.push(if p.is_up() { d.z } else { 0.0 });
    }
    let mut reflected_direct = Vec::new();
    let refl = thermal::Reflected::open_ground(
        1.0 - shape_factor,
        facet.ground_albedo,
        &sin_elevation,
        &mut reflected_direct,
    );
    let reflected_diffuse = refl.diffuse;
    Ok(FreeGeometry {
        sun_fraction,
        cos_incidence,
        shape_factor,
        back_shape_factor: facet.back_shape_factor,
        reflected_direct,
        reflected_diffuse,
    })
}

/// A free-standing facet of slab `props` at `site` solved over `records`
/// (the thermal model alone: no ray tracing, the sun unshadowed, the sky
/// shape factor of `facet`, the background at air temperature), with the
/// solver `options` as given. Returns the solution and the shape factor
/// used.
pub fn solve_free_facet(
    props: &SlabProperties,
    records: &[WeatherRecord],
    site: &Site,
    facet: &FacetSpec,
    options: &SolveOptions,
) -> Result<(thermal::ThermalSolution, f64)> {
    let g = free_facet_geometry(records, site, facet)?;
    let forcing = Forcing::from_records(records)?;
    Ok((
        thermal::solve_facing(
            props,
            &forcing,
            &g.inputs(),
            options,
            facet.tilt_deg.to_radians().cos(),
        )?,
        g.shape_factor,
    ))
}

impl OneFacet {
    /// Geometry of `facet` at `site` for every record.
    pub fn new(
        records: Vec<WeatherRecord>,
        site: &Site,
        facet: &FacetSpec,
        options: SolveOptions,
        band: Band,
    ) -> Result<Self> {
        let g = free_facet_geometry(&records, site, facet)?;
        // Studies difference outputs across parameter values, so the outputs
        // must be smooth in them: a spin-up that stops on a tolerance (a
        // whole day more or less) or a loose Newton tolerance would add
        // steps and noise. Fixed cycle count, tight Newton.
        let mut options = options;
        options.spinup.tolerance_k = 0.0;
        options.newton_tolerance_k = options.newton_tolerance_k.min(1e-7);
        Ok(OneFacet {
            records,
            sun_fraction: g.sun_fraction,
            cos_incidence: g.cos_incidence,
            reflected_direct: g.reflected_direct,
            reflected_diffuse: g.reflected_diffuse,
            shape_factor: g.shape_factor,
            back_shape_factor: g.back_shape_factor,
            options,
            band,
            site: *site,
            back: None,
        })
    }

    /// The same facet with the back boundary `back` for every material
    /// (`None`: each material's own).
    pub fn with_back(mut self, back: Option<BackBoundary>) -> Self {
        self.back = back;
        self
    }

    /// The slab properties of `material` on this facet (its back boundary
    /// overridden where [`OneFacet::back`] says so).
    pub fn slab(&self, material: &Material) -> Result<SlabProperties> {
        let props = SlabProperties::from_material(material)?;
        Ok(match self.back {
            Some(b) => props.with_back(b),
            None => props,
        })
    }

    /// Index of the record at `time` (the last record at or before it).
    pub fn index_at(&self, time: DateTime<FixedOffset>) -> Result<usize> {
        let n = self.records.iter().take_while(|r| r.time <= time).count();
        if n == 0 {
            return Err(Error::invalid(
                "time",
                format!("{time} is before the first weather record"),
            ));
        }
        Ok(n - 1)
    }

    /// Surface temperature (K) at every record for `material` under
    /// `weather` (same record times as [`OneFacet::records`]).
    pub fn surface_temperatures(
        &self,
        material: &Material,
        weather: &[WeatherRecord],
    ) -> Result<Vec<f64>> {
        if weather.len() != self.records.len() {
            return Err(Error::invalid(
                "weather",
                "the perturbed history must keep the record times",
            ));
        }
        let props = self.slab(material)?;
        let forcing = Forcing::from_records(weather)?;
        let inputs = FacetInputs {
            reflected: thermal::Reflected {
                direct: &self.reflected_direct,
                diffuse: self.reflected_diffuse,
            },
            back_shape_factor: self.back_shape_factor,
            ..FacetInputs::new(&self.sun_fraction, &self.cos_incidence, self.shape_factor)
        };
        Ok(thermal::solve(&props, &forcing, &inputs, &self.options)?.surface_temperature_k)
    }

    /// Surface-leaving band radiance (W·m⁻²·sr⁻¹) of `material` at surface
    /// temperature `t_k` under weather record `w` (see the module docs).
    pub fn band_radiance(&self, material: &Material, w: &WeatherRecord, t_k: f64) -> f64 {
        let t_sky = (w.sky_longwave_w_m2.max(0.0) / STEFAN_BOLTZMANN_W_M2_K4).powf(0.25);
        let f = self.shape_factor;
        let planck = self.band.planck();
        self.band
            .wavelengths_um()
            .iter()
            .zip(self.band.weights_um())
            .map(|(&l, wgt)| {
                let e = material.emissivity_at(l, 0.0).clamp(0.0, 1.0);
                let down = f * planck.radiance(l, t_sky)
                    + (1.0 - f) * planck.radiance(l, w.air_temperature_k);
                wgt * (e * planck.radiance(l, t_k) + (1.0 - e) * down)
            })
            .sum()
    }

    /// Band brightness temperature (K) of a band radiance.
    pub fn apparent_temperature(&self, radiance_w_m2_sr: f64) -> Result<f64> {
        self.band.brightness_temperature(radiance_w_m2_sr)
    }
}

/// A material by name in the database `db`, or from a material file
/// (`FILE` holding one material, or `FILE#NAME`).
pub fn find_material(spec: &str, db: &Path) -> Result<Material> {
    let (file, name) = match spec.split_once('#') {
        Some((f, n)) => (std::path::PathBuf::from(f), Some(n)),
        None if Path::new(spec).is_file() => (std::path::PathBuf::from(spec), None),
        None => (db.to_path_buf(), Some(spec)),
    };
    let mdb = MaterialDb::load(&file)?;
    match name {
        Some(n) => mdb.get(n).cloned().ok_or_else(|| {
            Error::invalid(
                "material",
                format!(
                    "{}: no material named `{n}`{}; it has: {}",
                    file.display(),
                    crate::suggest::hint(n, mdb.materials().iter().map(|m| m.name.as_str())),
                    mdb.materials()
                        .iter()
                        .map(|m| m.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        }),
        None => match mdb.materials() {
            [m] => Ok(m.clone()),
            ms => Err(Error::invalid(
                "material",
                format!(
                    "{} holds {} materials; choose one with {}#NAME (names: {})",
                    file.display(),
                    ms.len(),
                    file.display(),
                    ms.iter()
                        .map(|m| m.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )),
        },
    }
}

/// Write `material` as an irsig material JSON file (`{"materials": [...]}`)
/// that `irsig thermal --material FILE` reads back; atomically.
pub fn write_material_json(path: &Path, material: &Material, description: &str) -> Result<()> {
    let mut entry = serde_json::to_value(material).map_err(|e| Error::Other(e.to_string()))?;
    if let Some(o) = entry.as_object_mut() {
        if o.get("emissivity_curve").is_some_and(|v| v.is_null()) {
            o.remove("emissivity_curve");
        }
        o.insert(
            "description".into(),
            serde_json::Value::String(description.into()),
        );
    }
    let doc = serde_json::json!({ "materials": [entry] });
    let text = serde_json::to_string_pretty(&doc).map_err(|e| Error::Other(e.to_string()))? + "\n";
    super::write_file_atomic(path, text.as_bytes())
}
