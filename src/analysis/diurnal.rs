//! Target/background contrast through a period: the time of greatest
//! contrast and the thermal crossovers (times where the contrast changes
//! sign, located by linear interpolation between samples).
//!
//! [`scene_contrast`] samples a target and a background of a scene (an
//! object or a material each) in one sensor's image from one thermal run
//! with a shared spin-up ([`Session::thermal`] over all the times);
//! [`contrast_series`] analyses any pair of series. Takes a [`Session`]
//! and times, gives [`ContrastSeries`]. Knows nothing of the command line
//! or of plotting.

use chrono::{DateTime, Duration, FixedOffset};
use serde::Serialize;

use super::scene::{self as scene_study, PixelPoint};
use crate::render::session::Session;
use crate::{Error, Result};

/// A target and a background of a scene through a period, as one sensor
/// sees them (see [`scene_contrast`]).
#[derive(Debug, Clone)]
pub struct SceneContrast {
    /// The pixels sampled on the target.
    pub target_pixels: Vec<PixelPoint>,
    /// The pixels sampled on the background.
    pub background_pixels: Vec<PixelPoint>,
    /// Surface temperature of the facets under the pixels, K (mean).
    pub surface_temperature: ContrastSeries,
    /// Band radiance at the sensor, W·m⁻²·sr⁻¹ (mean; the sensor's first
    /// band).
    pub band_radiance: ContrastSeries,
    /// Apparent temperature at the sensor, K (mean).
    pub apparent_temperature: ContrastSeries,
}

/// Up to `samples` pixels of sensor `s` seeing `target` and as many seeing
/// `background` (each an object or a material name of the scene; the
/// target object's own facets are left out of the background), shaded
/// through the render's radiometry at every one of `times` from one
/// [`Session::thermal`] run, averaged per side and analysed with
/// [`contrast_series`].
///
/// # Errors
/// [`Error::Invalid`] for field `target` or `background` when the name is
/// neither an object nor a material of the scene, or sensor `s` does not
/// see it; the thermal solve's and shading's errors.
pub fn scene_contrast(
    session: &mut Session,
    s: usize,
    target: &str,
    background: &str,
    samples: usize,
    times: &[DateTime<FixedOffset>],
) -> Result<SceneContrast> {
    let (tp, tobj) = pixels_of(session, s, "target", target, samples, None)?;
    let (bp, _) = pixels_of(session, s, "background", background, samples, tobj)?;
    let states = session.thermal(times)?;
    let mut cols: [Vec<f64>; 6] = Default::default();
    for (k, px) in [&tp, &bp].into_iter().enumerate() {
        let series = scene_study::pixel_series(session, s, px, &states.conditions)?;
        for vals in series {
            let n = vals.len() as f64;
            cols[k].push(vals.iter().map(|v| v.surface_temperature_k).sum::<f64>() / n);
            cols[2 + k].push(vals.iter().map(|v| v.band_radiance_w_m2_sr).sum::<f64>() / n);
            cols[4 + k].push(vals.iter().map(|v| v.apparent_temperature_k).sum::<f64>() / n);
        }
    }
    Ok(SceneContrast {
        target_pixels: tp,
        background_pixels: bp,
        surface_temperature: contrast_series(
            "surface_temperature",
            "K",
            times,
            &cols[0],
            &cols[1],
        )?,
        band_radiance: contrast_series("band_radiance", "W/m2/sr", times, &cols[2], &cols[3])?,
        apparent_temperature: contrast_series(
            "apparent_temperature",
            "K",
            times,
            &cols[4],
            &cols[5],
        )?,
    })
}

/// Pixels of sensor `s` seeing object or material `name` (not object
/// `exclude`), and the object's index when `name` is an object; errors
/// name `field`.
fn pixels_of(
    session: &Session,
    s: usize,
    field: &str,
    name: &str,
    max: usize,
    exclude: Option<usize>,
) -> Result<(Vec<PixelPoint>, Option<usize>)> {
    let scene = &session.scene;
    let object = scene.objects.iter().position(|o| o.name == name);
    let material = scene
        .materials
        .materials()
        .iter()
        .position(|m| m.name == name);
    if object.is_none() && material.is_none() {
        return Err(Error::invalid(
            field,
            format!(
                "{}: `{name}` is neither an object ({}, …) nor a material of the scene",
                scene.path.display(),
                scene
                    .objects
                    .iter()
                    .take(8)
                    .map(|o| o.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    }
    let parts = scene.facet_parts();
    let fobj = &session.optics.facet_object;
    let select = |f: usize| {
        let o = fobj[f] as usize;
        if Some(o) == exclude {
            return false;
        }
        match object {
            Some(want) => o == want,
            None => Some(scene.parts[parts[f] as usize].material) == material,
        }
    };
    let px = scene_study::pixels_seeing(session, s, name, max, &select);
    if px.is_empty() {
        return Err(Error::invalid(
            field,
            format!(
                "`{name}` is not seen by sensor `{}` of {}: choose another object or sensor",
                session.sensors[s].name,
                scene.path.display()
            ),
        ));
    }
    Ok((px, object))
}

/// One quantity of the target and the background at the sample times.
#[derive(Debug, Clone, Serialize)]
pub struct ContrastSeries {
    /// What is compared (`apparent_temperature_k`, `band_radiance`, ...).
    pub quantity: String,
    /// Unit.
    pub unit: String,
    /// Target values.
    pub target: Vec<f64>,
    /// Background values.
    pub background: Vec<f64>,
    /// Contrast target − background.
    pub contrast: Vec<f64>,
    /// Greatest |contrast|.
    pub max_abs_contrast: f64,
    /// Signed contrast at that time.
    pub max_contrast_signed: f64,
    /// When it occurs (the sample time; refined by a parabola through the
    /// neighbouring samples, when inside the period).
    pub time_of_max: DateTime<FixedOffset>,
    /// Crossover times (contrast = 0), interpolated.
    pub crossovers: Vec<DateTime<FixedOffset>>,
}

/// Analyse `target` against `background` sampled at `times` (increasing).
pub fn contrast_series(
    quantity: &str,
    unit: &str,
    times: &[DateTime<FixedOffset>],
    target: &[f64],
    background: &[f64],
) -> Result<ContrastSeries> {
    if times.len() != target.len() || times.len() != background.len() {
        return Err(Error::invalid(
            "contrast",
            format!(
                "{} times, {} target and {} background values",
                times.len(),
                target.len(),
                background.len()
            ),
        ));
    }
    if times.is_empty() {
        return Err(Error::invalid("contrast", "no sample times"));
    }
    if times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(Error::invalid("contrast", "sample times must increase"));
    }
    let contrast: Vec<f64> = target.iter().zip(background).map(|(t, b)| t - b).collect();
    if contrast.iter().any(|c| !c.is_finite()) {
        return Err(Error::invalid(
            "contrast",
            "non-finite target or background value",
        ));
    }
    let k = (0..contrast.len())
        .max_by(|&a, &b| contrast[a].abs().total_cmp(&contrast[b].abs()))
        .unwrap_or(0);
    let mut time_of_max = times[k];
    let mut max_signed = contrast[k];
    // Parabolic refinement through (k−1, k, k+1) when equally spaced.
    if k > 0 && k + 1 < contrast.len() && times[k] - times[k - 1] == times[k + 1] - times[k] {
        let (a, b, c) = (
            contrast[k - 1].abs(),
            contrast[k].abs(),
            contrast[k + 1].abs(),
        );
        let den = a - 2.0 * b + c;
        if den < 0.0 {
            let off = 0.5 * (a - c) / den; // in steps, within ±0.5
            let dt = (times[k] - times[k - 1]).num_milliseconds() as f64;
            time_of_max = times[k] + Duration::milliseconds((off * dt).round() as i64);
            let peak = b - 0.25 * (a - c) * off;
            max_signed = peak.copysign(contrast[k]);
        }
    }
    let mut crossovers = Vec::new();
    for i in 1..contrast.len() {
        let (c0, c1) = (contrast[i - 1], contrast[i]);
        if c0 == 0.0 && i == 1 {
            crossovers.push(times[0]);
        }
        if c1 == 0.0 {
            crossovers.push(times[i]);
        } else if c0 != 0.0 && (c0 < 0.0) != (c1 < 0.0) {
            let f = c0 / (c0 - c1);
            let dt = (times[i] - times[i - 1]).num_milliseconds() as f64;
            crossovers.push(times[i - 1] + Duration::milliseconds((f * dt).round() as i64));
        }
    }
    Ok(ContrastSeries {
        quantity: quantity.into(),
        unit: unit.into(),
        target: target.to_vec(),
        background: background.to_vec(),
        max_abs_contrast: max_signed.abs(),
        max_contrast_signed: max_signed,
        contrast,
        time_of_max,
        crossovers,
    })
}
