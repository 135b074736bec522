//! Studies on a scene with its geometry held fixed: the per-facet
//! ray-traced thermal inputs (solar history, shape factor, background) are
//! traced once, and each parameter evaluation re-solves the slab model only
//! for the facets that matter, then shades the sample pixels through the
//! render's own radiometry (sensor band, atmosphere path, reflected sky,
//! sun and neighbours).
//!
//! # Model of one evaluation
//! 1. The weather history of the render's window and the materials of the
//!    scene's parts are perturbed by the parameters
//!    ([`ParamSet::apply_weather_at`], [`ParamSet::apply_material`]).
//! 2. The *neighbours* — the facets that the sampled facets' blocked
//!    hemisphere rays hit — are solved with the air as background (the
//!    scene solve's pass 1), each with its own traced inputs
//!    ([`crate::thermal::solve`] with [`FacetInputs`]).
//! 3. The *sampled facets* — those hit by the sample pixels' primary rays —
//!    are solved again with the radiative mean of the neighbours' pass-1
//!    histories and the air beyond the scene as background (pass 2).
//! 4. The render's conditions at the image time (every facet's temperature
//!    from the scene-wide solve, [`Session::thermal`]) are updated by the
//!    *changes* from the nominal parameters: each sampled facet by its
//!    pass-2 change, each neighbour by its pass-1 change, the sampled
//!    facets' background temperatures recomputed, and the sky, sun, ground
//!    and (built-in) atmosphere taken from the perturbed weather record.
//!    At the nominal parameters the conditions are exactly the render's.
//! 5. The sample pixels' primary sub-rays (traced once) are shaded with a
//!    [`Shader`] of those conditions and the perturbed materials' optics;
//!    a pixel's band radiance is the mean over its `N×N` sub-rays (a box
//!    PSF; the render's other PSFs also weight neighbouring pixels) and its
//!    apparent temperature the band brightness temperature of that mean.
//!
//! A material parameter applies to every part of that material and replaces
//! a part's own override of the same property (the part's other overrides
//! stay). Facets farther away keep their rendered temperatures, so what a sampled
//! facet reflects of them does not follow the parameters. The reflected
//! shortwave follows the materials' albedos (1 − α − transmissivity): where
//! a parameter changes one, the solve at those parameters takes the
//! reflected shortwave recomputed over every facet's hemisphere hits
//! ([`crate::exposure::reflected::reflected_shortwave`], as the render's),
//! so a brighter road sends more sunlight onto its neighbours. No parameter of
//! [`super::params`] changes the geometry, so none needs a full render;
//! emissivity acts both on the slab model and on the optics of the shading
//! (emission and every reflected term).

use std::collections::HashMap;

use chrono::{DateTime, FixedOffset};
use rayon::prelude::*;

use super::params::ParamSet;
use crate::exposure::{
    Exposure, ExposureParams, HistoryWindow, ReflectedShortwave, compute_exposure, history_times,
    sun_directions,
};
use crate::render::path::PathTables;
use crate::render::scene_thermal::{FacetThermalSetup, SceneThermalParams};
use crate::render::session::Session;
use crate::render::{Conditions, ShadeOptions, Shader, Sky};
use crate::thermal::scene::{
    FacetThermal, FacetWind, ThermalParams, forcing_with_wind_class, wind_class,
};
use crate::thermal::{
    self, BackBoundary, Background, Exchange, FacetInputs, Forcing, Reflected, SlabProperties,
    SolveOptions,
};
use crate::trace::{Coherence, Hit, Ray};
use crate::weather::WeatherRecord;
use crate::{Error, Result};

/// A pixel to sample: continuous image coordinates of a sensor image
/// (`x` the column, `y` the row; pixel `(i, j)` covers `[i,i+1)×[j,j+1)`).
#[derive(Debug, Clone, PartialEq)]
pub struct PixelPoint {
    /// Label (a truth point's id, or `material#k`).
    pub label: String,
    /// Column coordinate, pixels.
    pub x: f64,
    /// Row coordinate, pixels.
    pub y: f64,
}

/// A sample pixel with its primary sub-rays traced.
#[derive(Debug, Clone)]
struct Tracked {
    rays: Vec<Ray>,
    hits: Vec<Option<Hit>>,
    centre_facet: usize,
}

/// The values of one sample pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelValues {
    /// Surface temperature of the facet under the pixel centre, K.
    pub surface_temperature_k: f64,
    /// Band radiance at the sensor (band 0), W·m⁻²·sr⁻¹.
    pub band_radiance_w_m2_sr: f64,
    /// Band brightness temperature of that radiance, K.
    pub apparent_temperature_k: f64,
}

/// Primary sub-rays of the pixel containing `(x, y)` of sensor `s`, the
/// hits, and the facet under its centre sub-ray.
fn track(session: &Session, s: usize, p: &PixelPoint) -> Result<Tracked> {
    let sensor = &session.sensors[s];
    let (w, h, n) = (sensor.width(), sensor.height(), sensor.oversample());
    if !(p.x.is_finite() && p.y.is_finite() && p.x >= 0.0 && p.y >= 0.0)
        || p.x >= w as f64
        || p.y >= h as f64
    {
        return Err(Error::invalid(
            format!("point `{}`", p.label),
            format!(
                "pixel ({}, {}) is outside the {w}×{h} image of sensor `{}`",
                p.x, p.y, sensor.name
            ),
        ));
    }
    let (col, row) = (p.x as usize, p.y as usize);
    let mut all = Vec::with_capacity(sensor.rays_per_row());
    sensor.rays_for_row(row, &mut all);
    let mut rays = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            rays.push(all[j * w * n + col * n + i]);
        }
    }
    let mut hits = vec![None; rays.len()];
    session
        .tracer
        .intersect(&rays, Coherence::Incoherent, &mut hits);
    let centre = (n / 2) * n + n / 2;
    let offsets = &session.scene.facet_offsets;
    let centre_facet = hits[centre]
        .as_ref()
        .map(|h| crate::geometry::SceneGeometry::facet_id(offsets, h.instance, h.prim))
        .ok_or_else(|| {
            Error::invalid(
                format!("point `{}`", p.label),
                format!(
                    "pixel ({}, {}) of sensor `{}` sees no scene surface (sky)",
                    p.x, p.y, sensor.name
                ),
            )
        })?;
    Ok(Tracked {
        rays,
        hits,
        centre_facet,
    })
}

/// Shading options of the render (as [`Session::render_rows`] sets them).
fn shade_options(session: &Session) -> (ShadeOptions, f32) {
    let size = session
        .scene
        .geometry
        .bounds()
        .map(|(lo, hi)| (hi - lo).length())
        .unwrap_or(1.0);
    (
        ShadeOptions {
            max_bounces: session.config.max_bounces,
            offset_m: (1e-5 * size).max(1e-4),
        },
        size,
    )
}

/// Shade `points` of sensor `s` under `cond` with `optics` (the render's
/// radiometry, band 0).
fn shade(
    session: &Session,
    s: usize,
    optics: &crate::render::SceneOptics,
    cond: &Conditions,
    points: &[&Tracked],
) -> Result<Vec<PixelValues>> {
    let (opts, size) = shade_options(session);
    let sensor = &session.sensors[s];
    let bands = &session.bands[s];
    let path = PathTables::new(
        &cond.atmosphere,
        sensor,
        bands,
        session.scene.site.altitude_m,
        size as f64,
        crate::render::path::scene_heights(&session.scene.geometry),
        crate::render::path::PathSun::for_scene(cond.sun.as_ref()).as_ref(),
    )?;
    let shader = Shader::new(
        session.tracer.as_ref(),
        &session.scene.geometry,
        optics,
        cond,
        bands,
        opts,
    )?
    .with_path(path);
    let rays: Vec<Ray> = points.iter().flat_map(|p| p.rays.iter().copied()).collect();
    let hits: Vec<Option<Hit>> = points.iter().flat_map(|p| p.hits.iter().cloned()).collect();
    let nl = shader.spectrum_len();
    let mut spectra = vec![0.0f64; rays.len() * nl];
    shader.shade_primary(&rays, &hits, &mut spectra);
    let mut out = Vec::with_capacity(points.len());
    let mut k = 0;
    for p in points {
        let m = p.rays.len();
        let l = (k..k + m)
            .map(|i| shader.band_radiance(0, &spectra[i * nl..(i + 1) * nl]))
            .sum::<f64>()
            / m as f64;
        k += m;
        out.push(PixelValues {
            surface_temperature_k: cond.surface.temperature_k[p.centre_facet] as f64,
            band_radiance_w_m2_sr: l,
            apparent_temperature_k: shader.band(0).brightness_temperature(l).unwrap_or(0.0),
        });
    }
    Ok(out)
}

/// Pixel centres of sensor `s` on a grid of about 64×64, with the facet
/// under each (misses left out).
fn grid_facets(session: &Session, s: usize) -> Vec<((usize, usize), usize)> {
    let sensor = &session.sensors[s];
    let (w, h, n) = (sensor.width(), sensor.height(), sensor.oversample());
    let step = ((w * h) as f64 / 4096.0).sqrt().max(1.0) as usize;
    let mut cand = Vec::new();
    let mut rays = Vec::new();
    let mut row_rays = Vec::new();
    for row in (step / 2..h).step_by(step) {
        row_rays.clear();
        sensor.rays_for_row(row, &mut row_rays);
        for col in (step / 2..w).step_by(step) {
            cand.push((col, row));
            rays.push(row_rays[(n / 2) * w * n + col * n + n / 2]);
        }
    }
    let hits = crate::trace::intersect_all(session.tracer.as_ref(), &rays, Coherence::Coherent);
    let offsets = &session.scene.facet_offsets;
    cand.into_iter()
        .zip(hits)
        .filter_map(|(c, hit)| {
            let hit = hit?;
            Some((
                c,
                crate::geometry::SceneGeometry::facet_id(offsets, hit.instance, hit.prim),
            ))
        })
        .collect()
}

/// `k` of `px` evenly spread, labelled `name#i`.
fn thin(px: &[(usize, usize)], k: usize, name: &str) -> Vec<PixelPoint> {
    let k = k.min(px.len());
    (0..k)
        .map(|i| {
            let (col, row) = px[(2 * i + 1) * px.len() / (2 * k)];
            PixelPoint {
                label: format!("{name}#{i}"),
                x: col as f64 + 0.5,
                y: row as f64 + 0.5,
            }
        })
        .collect()
}

/// Up to `per_material` pixels per material of the scene, spread over the
/// image of sensor `s`: pixel centres on a grid of about 64×64 grouped by
/// the material under them (fixed-temperature parts left out), each group
/// thinned evenly. Returns the pixels and the groups (material name, pixel
/// indices), materials in order of first appearance.
pub fn material_samples(
    session: &Session,
    s: usize,
    per_material: usize,
) -> (Vec<PixelPoint>, Vec<(String, Vec<usize>)>) {
    let parts = session.scene.facet_parts();
    let mut groups: Vec<(String, Vec<(usize, usize)>)> = Vec::new();
    for (c, f) in grid_facets(session, s) {
        let part = &session.scene.parts[parts[f] as usize];
        if part.fixed_temperature_k.is_some() {
            continue;
        }
        let name = session.scene.materials.materials()[part.material]
            .name
            .clone();
        match groups.iter_mut().find(|(n, _)| *n == name) {
            Some((_, v)) => v.push(c),
            None => groups.push((name, vec![c])),
        }
    }
    let mut points = Vec::new();
    let mut out = Vec::new();
    for (name, px) in groups {
        let start = points.len();
        points.extend(thin(&px, per_material.max(1), &name));
        out.push((name, (start..points.len()).collect()));
    }
    (points, out)
}

/// A scene study: sample pixels of one sensor at one time, with
/// parameters applied to the weather and the materials.
pub struct SceneStudy {
    /// The render session (scene, sensors, tracer).
    pub session: Session,
    /// Sensor index.
    pub sensor: usize,
    /// Image time.
    pub time: DateTime<FixedOffset>,
    /// The parameters.
    pub params: ParamSet,
    /// The sample pixels.
    pub points: Vec<PixelPoint>,
    /// Output groups: a name and the sample pixels averaged into it.
    pub groups: Vec<(String, Vec<usize>)>,
    tracked: Vec<Tracked>,
    base: Conditions,
    record: WeatherRecord,
    history: Vec<WeatherRecord>,
    image_record: usize,
    exposure: Exposure,
    /// The traced shape factor of each exposed back, as the render's
    /// ([`FacetThermalSetup::exposed_back_shape_factor`]).
    exposed_back: Vec<Option<f32>>,
    /// The wind at each facet, as the render's (empty: the weather's).
    wind: Vec<FacetWind>,
    kinds: Vec<FacetThermal>,
    /// Facets on the ground (the render's rule,
    /// [`FacetThermalSetup::ground_facets`]): an insulated back becomes the
    /// deep-ground boundary, as in the scene-wide solve.
    ground: Vec<bool>,
    facet_part: Vec<u32>,
    /// Each part's albedo at the nominal parameters (as the render's
    /// [`FacetThermalSetup`]).
    part_albedo: Vec<f32>,
    /// The history's sun directions, the ground's albedo and the bounces
    /// of the reflected shortwave (0: none).
    sun_dirs: Vec<glam::Vec3>,
    ground_albedo: f32,
    reflected_bounces: u32,
    sampled: Vec<usize>,
    neighbours: Vec<usize>,
    nominal_pass1: Vec<f32>,
    nominal_pass2: Vec<f32>,
    options: SolveOptions,
}

impl std::fmt::Debug for SceneStudy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneStudy")
            .field("scene", &self.session.scene.path)
            .field("points", &self.points.len())
            .field("sampled_facets", &self.sampled.len())
            .field("neighbour_facets", &self.neighbours.len())
            .finish()
    }
}

impl SceneStudy {
    /// Set up the study: the render's thermal state at `time`, the per-facet
    /// exposure of the render's history window, the sample pixels traced,
    /// and the nominal re-solve of their facets. `groups` name output
    /// groups of `points` (indices); empty: one group per point.
    ///
    /// # Errors
    /// A point outside the image or seeing only sky; the render's and the
    /// thermal model's errors.
    pub fn new(
        mut session: Session,
        sensor: usize,
        time: DateTime<FixedOffset>,
        params: ParamSet,
        points: Vec<PixelPoint>,
        groups: Vec<(String, Vec<usize>)>,
    ) -> Result<SceneStudy> {
        if sensor >= session.sensors.len() {
            return Err(Error::invalid("sensor", "no such sensor"));
        }
        if points.is_empty() {
            return Err(Error::invalid(
                "points",
                "no sample pixels: give validation points, or a scene whose sensor sees thermal facets",
            ));
        }
        let groups = if groups.is_empty() {
            points
                .iter()
                .enumerate()
                .map(|(i, p)| (p.label.clone(), vec![i]))
                .collect()
        } else {
            groups
        };
        let tracked = points
            .iter()
            .map(|p| track(&session, sensor, p))
            .collect::<Result<Vec<_>>>()?;
        let mut states = session.thermal(&[time])?;
        let base = states.conditions.remove(0);
        let record = states.records.remove(0);
        let scene = &session.scene;
        // The render's history window and per-facet exposure.
        let window = HistoryWindow::default();
        let times = history_times(&session.weather, &[time], &window)?;
        let history = times
            .iter()
            .map(|&t| session.weather.at(t))
            .collect::<Result<Vec<_>>>()?;
        let image_record = times
            .iter()
            .position(|t| *t == time)
            .ok_or_else(|| Error::Other("image time not on the history grid".into()))?;
        let dirs = sun_directions(&scene.site, &times)?;
        let physics = session.config.thermal;
        let setup = FacetThermalSetup::from_scene_with(scene, &physics)?;
        // The same kind of scene as the render's exposure (and, as there,
        // the watertight one for the ground test).
        let own = session.exposure_tracer()?;
        let tracer = own.as_deref().unwrap_or(session.tracer.as_ref());
        let scene = &session.scene;
        let exposure_params = ExposureParams {
            samples_per_edge: session.config.facet_samples,
            sky: session.config.sky_sampling,
            ..ExposureParams::default()
        };
        let mut exposure = compute_exposure(
            tracer,
            &scene.geometry,
            &setup.double_sided,
            &dirs,
            &exposure_params,
        )?;
        for (f, o) in setup.shape_factor_override.iter().enumerate() {
            if let Some(v) = *o {
                exposure.sky.shape_factor[f] = v;
            }
        }
        let (exposed_back, _) = setup.exposed_back_shape_factor(
            tracer,
            &exposure.facets,
            &exposure_params,
            0..exposure.facets.len(),
        );
        // As the render: the reflected shortwave and the wind at each facet.
        let exposure = if physics.reflected_bounces > 0 {
            exposure.with_reflected(
                &setup.facet_albedo(),
                physics.ground_albedo,
                &dirs,
                physics.reflected_bounces,
            )?
        } else {
            exposure
        };
        let wind = if physics.facet_wind {
            let forcing = Forcing::from_records(&history)?;
            crate::render::scene_thermal::facet_wind(&exposure, &forcing, physics.roughness_m)
        } else {
            Vec::new()
        };
        let ground = if SceneThermalParams::default().ground {
            setup.ground_facets(session.tracer.as_ref(), &exposure.facets)
        } else {
            vec![false; exposure.facets.len()]
        };
        let kinds = setup.kinds;
        let solved = |f: &usize| matches!(kinds[*f], FacetThermal::Solve(_));
        let mut sampled: Vec<usize> = tracked
            .iter()
            .flat_map(|t| {
                t.hits.iter().flatten().map(|h| {
                    crate::geometry::SceneGeometry::facet_id(
                        &scene.facet_offsets,
                        h.instance,
                        h.prim,
                    )
                })
            })
            .filter(solved)
            .collect();
        sampled.sort_unstable();
        sampled.dedup();
        let mut neighbours: Vec<usize> = sampled
            .iter()
            .flat_map(|&f| exposure.sky.background(f).iter().map(|e| e.facet as usize))
            .filter(solved)
            .collect();
        neighbours.sort_unstable();
        neighbours.dedup();
        let mut options = ThermalParams::scene_options();
        options.spinup.tolerance_k = 0.0;
        options.newton_tolerance_k = options.newton_tolerance_k.min(1e-7);
        let facet_part = scene.facet_parts();
        let part_albedo = (0..scene.parts.len())
            .map(|p| albedo_of(&scene.part_material(p)))
            .collect();
        let mut study = SceneStudy {
            session,
            sensor,
            time,
            params,
            points,
            groups,
            tracked,
            base,
            record,
            history,
            image_record,
            exposure,
            exposed_back,
            wind,
            kinds,
            ground,
            facet_part,
            part_albedo,
            sun_dirs: dirs,
            ground_albedo: physics.ground_albedo,
            reflected_bounces: physics.reflected_bounces,
            sampled,
            neighbours,
            nominal_pass1: Vec::new(),
            nominal_pass2: Vec::new(),
            options,
        };
        let (p1, p2) = study.solve(&study.params.nominal())?;
        study.nominal_pass1 = p1.iter().map(|h| h[image_record]).collect();
        study.nominal_pass2 = p2;
        Ok(study)
    }

    /// Facets re-solved per evaluation: (sampled, neighbours).
    pub fn facet_counts(&self) -> (usize, usize) {
        (self.sampled.len(), self.neighbours.len())
    }

    /// Per sampled facet: its nominal re-solved temperature minus the
    /// scene-wide solve's at the image time, K (the scene solve merges
    /// facets with nearly equal inputs, so this is its dedup error; a
    /// check that the re-solve sees the scene's inputs).
    pub fn resolve_residuals_k(&self) -> Vec<f32> {
        self.sampled
            .iter()
            .zip(&self.nominal_pass2)
            .map(|(&f, t)| t - self.base.surface.temperature_k[f])
            .collect()
    }

    /// Output names: per group, surface temperature (K), apparent
    /// temperature (K) and band radiance at the sensor (W·m⁻²·sr⁻¹).
    pub fn output_names(&self) -> Vec<String> {
        self.groups
            .iter()
            .flat_map(|(g, _)| {
                [
                    format!("{g}.surface_temperature_k"),
                    format!("{g}.apparent_temperature_k"),
                    format!("{g}.band_radiance_w_m2_sr"),
                ]
            })
            .collect()
    }

    /// Slab properties of every part with the parameters `x` (`None` for
    /// fixed-temperature parts).
    fn part_props(&self, x: &[f64]) -> Result<Vec<Option<SlabProperties>>> {
        let scene = &self.session.scene;
        (0..scene.parts.len())
            .map(|p| {
                if scene.parts[p].fixed_temperature_k.is_some() {
                    return Ok(None);
                }
                let m = self.params.apply_material(x, &scene.part_material(p))?;
                SlabProperties::from_material(&m).map(Some)
            })
            .collect()
    }

    /// `sun`: the facet's sunlit fraction and cosine of incidence per record
    /// (decoded from the compact solar history: [`Self::solar_of`]).
    /// The solar history of facet `f`: sunlit fraction and cosine of
    /// incidence per record, and its reflected direct coefficient per
    /// record (decoded from the day records; empty without reflected
    /// shortwave).
    fn solar_of(&self, f: usize, r: &ReflectedShortwave) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
        let s = &self.exposure.solar;
        let refl = if r.facet_count() == 0 {
            Vec::new()
        } else {
            r.direct(f)
        };
        (s.sun_fraction(f), s.cos_incidence(f), refl)
    }

    /// The reflected shortwave at `x`: recomputed where a parameter
    /// changes a part's albedo, else `None` (the nominal one in
    /// [`Exposure::reflected`]).
    fn reflected_at(&self, x: &[f64]) -> Result<Option<ReflectedShortwave>> {
        if self.reflected_bounces == 0 {
            return Ok(None);
        }
        let scene = &self.session.scene;
        let part_albedo = (0..scene.parts.len())
            .map(|p| {
                Ok(albedo_of(
                    &self.params.apply_material(x, &scene.part_material(p))?,
                ))
            })
            .collect::<Result<Vec<f32>>>()?;
        if part_albedo == self.part_albedo {
            return Ok(None);
        }
        let albedo: Vec<f32> = self
            .facet_part
            .iter()
            .map(|&p| part_albedo[p as usize])
            .collect();
        crate::exposure::reflected::reflected_shortwave(
            &self.exposure.sky,
            &self.exposure.solar,
            &albedo,
            self.ground_albedo,
            &self.sun_dirs,
            self.reflected_bounces,
        )
        .map(Some)
    }

    fn inputs<'a>(
        &'a self,
        f: usize,
        sun: &'a (Vec<f32>, Vec<f32>, Vec<f32>),
        background: Background<'a>,
        reflected: &'a ReflectedShortwave,
    ) -> FacetInputs<'a> {
        let s = &self.exposure;
        FacetInputs {
            sun_fraction: &sun.0,
            cos_incidence: &sun.1,
            shape_factor: s.sky.shape_factor[f] as f64,
            back_shape_factor: s
                .sky
                .back_shape_factor(f)
                .or(self.exposed_back[f])
                .map(f64::from),
            background,
            reflected: if reflected.facet_count() == 0 {
                Reflected::NONE
            } else {
                Reflected {
                    direct: &sun.2,
                    diffuse: reflected.diffuse[f] as f64,
                }
            },
        }
    }

    /// Pass-1 histories of the neighbours and pass-2 temperatures at the
    /// image record of the sampled facets, at `x`.
    fn solve(&self, x: &[f64]) -> Result<(Vec<Vec<f32>>, Vec<f32>)> {
        let site = self.session.scene.site;
        let w = self
            .params
            .apply_weather_at(x, &self.history, Some(&site))?;
        let forcing = Forcing::from_records(&w)?;
        let props = self.part_props(x)?;
        let reflected_x = self.reflected_at(x)?;
        let reflected = reflected_x.as_ref().unwrap_or(&self.exposure.reflected);
        // The ground twin of each part's properties (deep-ground back
        // boundary where the back is insulated), as the scene solve's
        // `FacetThermalSetup::with_ground`.
        let ground_props: Vec<Option<SlabProperties>> = props
            .iter()
            .map(|p| {
                p.filter(|p| p.back == BackBoundary::Insulated)
                    .map(|p| p.with_back(BackBoundary::GROUND))
            })
            .collect();
        // Each property set's exchange with the air, made once (as the
        // scene solve does), not once per facet.
        let exchanges = |ps: &[Option<SlabProperties>]| -> Result<Vec<Option<Exchange>>> {
            ps.iter()
                .map(|p| {
                    p.as_ref()
                        .map(|p| {
                            p.validate()?;
                            Exchange::new(p, &forcing)
                        })
                        .transpose()
                })
                .collect()
        };
        let (own_ex, ground_ex) = (exchanges(&props)?, exchanges(&ground_props)?);
        // With the wind at each facet: one exchange per (part, ground twin,
        // wind class) of the solved facets, as the scene solve's classes.
        let key = |f: usize| -> Option<(usize, bool, u32)> {
            let part = self.facet_part[f] as usize;
            let ground = self.ground[f] && ground_props[part].is_some();
            let p = if ground {
                ground_props[part].as_ref()
            } else {
                props[part].as_ref()
            }?;
            Some((part, ground, wind_class(self.wind.get(f)?, p)))
        };
        let mut keys: Vec<(usize, bool, u32)> = self
            .neighbours
            .iter()
            .chain(&self.sampled)
            .filter_map(|&f| key(f))
            .collect();
        keys.sort_unstable();
        keys.dedup();
        let wind_ex: HashMap<(usize, bool, u32), Exchange> = keys
            .par_iter()
            .map(|&(part, ground, q)| {
                let p = if ground {
                    ground_props[part].as_ref()
                } else {
                    props[part].as_ref()
                }
                .expect("solved facets have properties");
                Exchange::new(p, &forcing_with_wind_class(&forcing, q))
                    .map(|e| ((part, ground, q), e))
            })
            .collect::<Result<_>>()?;
        let prop = |f: usize| -> Result<(&SlabProperties, &Exchange)> {
            let part = self.facet_part[f] as usize;
            let own = props[part].as_ref().zip(own_ex[part].as_ref());
            let p = if self.ground[f] {
                ground_props[part]
                    .as_ref()
                    .zip(ground_ex[part].as_ref())
                    .or(own)
            } else {
                own
            };
            let p = p.ok_or_else(|| Error::Other(format!("facet {f} has a fixed temperature")))?;
            match key(f).and_then(|k| wind_ex.get(&k)) {
                Some(ex) => Ok((p.0, ex)),
                None => Ok(p),
            }
        };
        let pass1: Vec<Vec<f32>> = self
            .neighbours
            .par_iter()
            .map(|&f| {
                let (p, ex) = prop(f)?;
                let sol = thermal::solve_with(
                    p,
                    &forcing,
                    ex,
                    &self.inputs(f, &self.solar_of(f, reflected), Background::Air, reflected),
                    &self.options,
                )?;
                Ok(sol
                    .surface_temperature_k
                    .iter()
                    .map(|&t| t as f32)
                    .collect())
            })
            .collect::<Result<_>>()?;
        let index: HashMap<usize, usize> = self
            .neighbours
            .iter()
            .enumerate()
            .map(|(i, &f)| (f, i))
            .collect();
        let air4: Vec<f32> = w
            .iter()
            .map(|r| (r.air_temperature_k as f32).powi(4))
            .collect();
        let pass2: Vec<f32> = self
            .sampled
            .par_iter()
            .map(|&f| {
                let sky = &self.exposure.sky;
                let g = sky.ground_weight[f];
                let entries = sky.background(f);
                let den: f32 = g + entries.iter().map(|e| e.weight).sum::<f32>();
                let mut bg: Vec<f32> = Vec::new();
                if den > 0.0 {
                    let mut acc: Vec<f32> = air4.iter().map(|a| g * a).collect();
                    for e in entries {
                        let j = e.facet as usize;
                        match self.kinds[j] {
                            FacetThermal::Fixed(t) => {
                                acc.iter_mut().for_each(|o| *o += e.weight * t.powi(4))
                            }
                            FacetThermal::Solve(_) => {
                                let h = &pass1[index[&j]];
                                acc.iter_mut()
                                    .zip(h)
                                    .for_each(|(o, t)| *o += e.weight * t.powi(4));
                            }
                        }
                    }
                    bg = acc.iter().map(|a| (a / den).powf(0.25)).collect();
                }
                let background = if bg.is_empty() {
                    Background::Air
                } else {
                    Background::PerRecord(&bg)
                };
                let (p, ex) = prop(f)?;
                let sol = thermal::solve_with(
                    p,
                    &forcing,
                    ex,
                    &self.inputs(f, &self.solar_of(f, reflected), background, reflected),
                    &self.options,
                )?;
                Ok(sol.surface_temperature_k[self.image_record] as f32)
            })
            .collect::<Result<_>>()?;
        Ok((pass1, pass2))
    }

    /// The render's conditions and optics at the image time with the
    /// parameters `x` (see the module docs).
    pub fn conditions(&self, x: &[f64]) -> Result<(Conditions, crate::render::SceneOptics)> {
        let (p1, p2) = self.solve(x)?;
        let mut cond = self.base.clone();
        let temps = &mut cond.surface.temperature_k;
        for (k, &f) in self.neighbours.iter().enumerate() {
            temps[f] += p1[k][self.image_record] - self.nominal_pass1[k];
        }
        for (k, &f) in self.sampled.iter().enumerate() {
            temps[f] = self.base.surface.temperature_k[f] + p2[k] - self.nominal_pass2[k];
        }
        let site = self.session.scene.site;
        let rec = self
            .params
            .apply_weather_at(x, &[self.record], Some(&site))?[0];
        for &f in &self.sampled {
            cond.surface.background_k[f] = self.exposure.sky.background_temperature(
                f,
                &cond.surface.temperature_k,
                rec.air_temperature_k as f32,
            );
        }
        if self.params.has_weather() {
            if let Sky::Atmosphere(c) = &mut cond.sky {
                c.air_temperature_k = rec.air_temperature_k;
                c.sky_longwave_w_m2 = rec.sky_longwave_w_m2;
            }
            if let Some(s) = &mut cond.sun {
                s.direct_normal_w_m2 = rec.direct_normal_w_m2;
            }
            cond.ground_temperature_k = rec.air_temperature_k;
            // The atmosphere from the perturbed record, as the render makes it.
            cond.atmosphere = self.session.atmosphere_at(&rec)?;
        }
        let mut optics = self.session.optics.clone();
        for m in &mut optics.materials {
            *m = self.params.apply_material(x, m)?;
        }
        Ok((cond, optics))
    }

    /// Values of every sample pixel at `x`.
    pub fn pixels(&self, x: &[f64]) -> Result<Vec<PixelValues>> {
        let (cond, optics) = self.conditions(x)?;
        let refs: Vec<&Tracked> = self.tracked.iter().collect();
        shade(&self.session, self.sensor, &optics, &cond, &refs)
    }

    /// The outputs (see [`SceneStudy::output_names`]) at `x`: group means.
    pub fn evaluate(&self, x: &[f64]) -> Result<Vec<f64>> {
        let px = self.pixels(x)?;
        let mut out = Vec::with_capacity(3 * self.groups.len());
        for (_, idx) in &self.groups {
            let n = idx.len().max(1) as f64;
            let mean =
                |g: &dyn Fn(&PixelValues) -> f64| idx.iter().map(|&i| g(&px[i])).sum::<f64>() / n;
            out.push(mean(&|p| p.surface_temperature_k));
            out.push(mean(&|p| p.apparent_temperature_k));
            out.push(mean(&|p| p.band_radiance_w_m2_sr));
        }
        Ok(out)
    }
}

/// Pixels of sensor `s` that see `select`ed facets (by the facet under the
/// centre of pixels on a grid of about 64×64), thinned evenly to at most
/// `max`; labels `name#k`.
pub fn pixels_seeing(
    session: &Session,
    s: usize,
    name: &str,
    max: usize,
    select: &dyn Fn(usize) -> bool,
) -> Vec<PixelPoint> {
    let px: Vec<(usize, usize)> = grid_facets(session, s)
        .into_iter()
        .filter(|(_, f)| select(*f))
        .map(|(c, _)| c)
        .collect();
    thin(&px, max, name)
}

/// Values of `points` of sensor `s` under each of `conditions` (one per
/// time) with the render's optics: for diurnal curves from one
/// [`Session::thermal`] call over all times.
///
/// # Errors
/// A point outside the image or seeing only sky; shading errors.
pub fn pixel_series(
    session: &Session,
    s: usize,
    points: &[PixelPoint],
    conditions: &[Conditions],
) -> Result<Vec<Vec<PixelValues>>> {
    let tracked = points
        .iter()
        .map(|p| track(session, s, p))
        .collect::<Result<Vec<_>>>()?;
    let refs: Vec<&Tracked> = tracked.iter().collect();
    conditions
        .iter()
        .map(|c| shade(session, s, &session.optics, c, &refs))
        .collect()
}

/// A material's albedo for the reflected shortwave, as the render's
/// [`FacetThermalSetup`]: 1 − α − transmissivity, in 0..1.
fn albedo_of(m: &crate::material::Material) -> f32 {
    (1.0 - m.solar_absorptivity - m.transmissivity).clamp(0.0, 1.0) as f32
}
