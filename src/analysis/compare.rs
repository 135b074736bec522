//! Validation of a synthetic image against truth: a truth image of the same
//! grid, or truth point measurements; per-material statistics through the
//! synthetic image's `material_id` layer; and geometric accuracy from
//! control points located in both images.
//!
//! Takes image stacks and point tables, gives statistics ([`Agreement`]s)
//! to report; knows nothing of how they are printed, plotted or asked for
//! (errors name the options' fields, `layer`, `truth_layer`, `gsd_m`).

use std::collections::BTreeMap;

use serde::Serialize;

use super::csv::{ControlPoint, PointPosition, TruthPoint};
use super::stats::{Agreement, Histogram, common_range, mean};
use crate::output::{ImageStack, Layer};
use crate::{Error, Location, Result};

/// Name of the per-pixel material-id layer of a synthetic image.
pub const MATERIAL_ID_LAYER: &str = "material_id";

/// What a layer holds, judged from its name: temperatures are compared in
/// kelvin, everything else in the layer's own (radiance) unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// A temperature, K.
    Temperature,
    /// A radiance (or another quantity), in the layer's unit.
    Radiance,
}

impl Quantity {
    /// The quantity of a layer called `name`.
    pub fn of_layer(name: &str) -> Quantity {
        if name.to_ascii_lowercase().contains("temperature") {
            Quantity::Temperature
        } else {
            Quantity::Radiance
        }
    }
    /// Unit label for reports.
    pub fn unit(&self) -> &'static str {
        match self {
            Quantity::Temperature => "K",
            Quantity::Radiance => "radiance units",
        }
    }
}

/// Layers that hold labels, not measurements.
fn is_label_layer(name: &str) -> bool {
    matches!(name, MATERIAL_ID_LAYER | "object_id" | "facet_id" | "mask")
}

/// The layer of `synth` to compare: `name` if given, else the first of
/// `apparent_temperature`, `surface_temperature`, `temperature`, else the
/// first layer that is not a label layer.
pub fn pick_layer<'a>(stack: &'a ImageStack, name: Option<&str>, what: &str) -> Result<&'a Layer> {
    let names = || {
        stack
            .layers
            .iter()
            .map(|l| l.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Some(n) = name {
        return stack.layer(n).ok_or_else(|| {
            Error::invalid(what, format!("no layer `{n}`; the image has: {}", names()))
        });
    }
    for n in ["apparent_temperature", "surface_temperature", "temperature"] {
        if let Some(l) = stack.layer(n) {
            return Ok(l);
        }
    }
    stack
        .layers
        .iter()
        .find(|l| !is_label_layer(&l.name))
        .ok_or_else(|| Error::invalid(what, format!("no value layer; the image has: {}", names())))
}

/// Agreement for one material.
#[derive(Debug, Clone, Serialize)]
pub struct MaterialAgreement {
    /// Material id (from `material_id`) or label (from the points file).
    pub material: String,
    /// Statistics over that material's pixels/points.
    pub agreement: Agreement,
}

/// Result of comparing a synthetic image with a truth image.
#[derive(Debug, Clone, Serialize)]
pub struct ImageComparison {
    /// Synthetic layer compared.
    pub layer: String,
    /// What it holds.
    pub quantity: Quantity,
    /// Unit of the statistics.
    pub unit: String,
    /// Statistics over all pixels finite in both images.
    pub overall: Agreement,
    /// Statistics per material id (when the synthetic image has `material_id`).
    pub per_material: Vec<MaterialAgreement>,
    /// Histogram of the synthetic values.
    pub synth_histogram: Histogram,
    /// Histogram of the truth values (same bins).
    pub truth_histogram: Histogram,
}

/// Options of [`compare_images`] and [`compare_points`].
#[derive(Debug, Clone, Default)]
pub struct CompareOptions {
    /// Synthetic layer (default: see [`pick_layer`]).
    pub layer: Option<String>,
    /// Truth layer (default: the same name, or the only layer).
    pub truth_layer: Option<String>,
    /// Histogram bins (default 64).
    pub bins: Option<usize>,
    /// What the compared values are (default: judged from the layer name).
    pub quantity: Option<Quantity>,
}

fn material_ids(stack: &ImageStack) -> Option<&[f32]> {
    stack.layer(MATERIAL_ID_LAYER).map(|l| l.data.as_slice())
}

/// A material id is valid when finite and non-negative (background pixels
/// carry NaN or a negative id).
fn material_key(id: f32) -> Option<u32> {
    (id.is_finite() && id >= 0.0).then_some(id.round() as u32)
}

fn per_group(groups: BTreeMap<String, (Vec<f64>, Vec<f64>)>) -> Vec<MaterialAgreement> {
    groups
        .into_iter()
        .filter_map(|(material, (p, t))| {
            Agreement::of(&p, &t)
                .ok()
                .map(|agreement| MaterialAgreement {
                    material,
                    agreement,
                })
        })
        .collect()
}

/// Compare `synth` with `truth`, pixel by pixel (same width and height).
pub fn compare_images(
    synth: &ImageStack,
    truth: &ImageStack,
    opts: &CompareOptions,
) -> Result<ImageComparison> {
    if (synth.width, synth.height) != (truth.width, truth.height) {
        return Err(Error::invalid(
            "truth image",
            format!(
                "size {}×{} differs from the synthetic image's {}×{}; resample one to the other's grid first",
                truth.width, truth.height, synth.width, synth.height
            ),
        ));
    }
    let sl = pick_layer(synth, opts.layer.as_deref(), "layer")?;
    let tl = match &opts.truth_layer {
        Some(n) => pick_layer(truth, Some(n), "truth_layer")?,
        None => match truth.layer(&sl.name) {
            Some(l) => l,
            None if truth.layers.len() == 1 => &truth.layers[0],
            None => pick_layer(truth, None, "truth_layer")?,
        },
    };
    let p: Vec<f64> = sl.data.iter().map(|&v| v as f64).collect();
    let t: Vec<f64> = tl.data.iter().map(|&v| v as f64).collect();
    let overall = Agreement::of(&p, &t)?;
    let mut groups: BTreeMap<String, (Vec<f64>, Vec<f64>)> = BTreeMap::new();
    if let Some(ids) = material_ids(synth) {
        for ((&id, &a), &b) in ids.iter().zip(&p).zip(&t) {
            if let Some(k) = material_key(id) {
                let g = groups.entry(format!("{k}")).or_default();
                g.0.push(a);
                g.1.push(b);
            }
        }
    }
    let bins = opts.bins.unwrap_or(64);
    let (lo, hi) = common_range([p.as_slice(), t.as_slice()])
        .ok_or_else(|| Error::invalid("comparison", "no finite value"))?;
    let quantity = opts.quantity.unwrap_or(Quantity::of_layer(&sl.name));
    Ok(ImageComparison {
        layer: sl.name.clone(),
        quantity,
        unit: quantity.unit().into(),
        overall,
        per_material: per_group(groups),
        synth_histogram: Histogram::new(p.iter().copied(), lo, hi, bins)?,
        truth_histogram: Histogram::new(t.iter().copied(), lo, hi, bins)?,
    })
}

/// One validation point with the synthetic value found there.
#[derive(Debug, Clone, Serialize)]
pub struct PointResidual {
    /// Point identifier.
    pub id: String,
    /// Pixel column and row sampled.
    pub pixel: [usize; 2],
    /// Material (label from the file, else the pixel's material id).
    pub material: Option<String>,
    /// Truth value.
    pub truth: f64,
    /// Synthetic value at the pixel.
    pub synthetic: f64,
    /// synthetic − truth.
    pub residual: f64,
}

/// Result of comparing a synthetic image with truth points.
#[derive(Debug, Clone, Serialize)]
pub struct PointComparison {
    /// Synthetic layer compared.
    pub layer: String,
    /// What it holds.
    pub quantity: Quantity,
    /// Unit of the statistics.
    pub unit: String,
    /// Statistics over all points.
    pub overall: Agreement,
    /// Statistics per material.
    pub per_material: Vec<MaterialAgreement>,
    /// Every point.
    pub points: Vec<PointResidual>,
}

/// Compare the synthetic image with truth points from `points_file`
/// (used in error messages). Points use pixel coordinates: the pixel
/// containing `(x, y)` is sampled.
pub fn compare_points(
    synth: &ImageStack,
    points: &[TruthPoint],
    points_file: &std::path::Path,
    opts: &CompareOptions,
) -> Result<PointComparison> {
    let sl = pick_layer(synth, opts.layer.as_deref(), "layer")?;
    let ids = material_ids(synth);
    let mut out = Vec::with_capacity(points.len());
    for pt in points {
        let (x, y) = match pt.position {
            PointPosition::Pixel { x, y } => (x, y),
            PointPosition::LatLon { .. } => {
                return Err(Error::parse(
                    Location::file(points_file)
                        .at_line(pt.line)
                        .with_field("lat"),
                    "lat/lon points must be georeferenced first (with the scene whose sensor made the image: `analysis::geo`), or given as pixel x,y columns",
                ));
            }
        };
        if x < 0.0 || y < 0.0 || x >= synth.width as f64 || y >= synth.height as f64 {
            return Err(Error::parse(
                Location::file(points_file).at_line(pt.line).with_field("x"),
                format!(
                    "point ({x}, {y}) lies outside the {}×{} synthetic image",
                    synth.width, synth.height
                ),
            ));
        }
        let Some(truth) = pt.value else {
            return Err(Error::parse(
                Location::file(points_file).at_line(pt.line),
                "no truth value: the file needs a `value` column (or compare against a truth image)",
            ));
        };
        let (c, r) = (x.floor() as usize, y.floor() as usize);
        let k = r * synth.width + c;
        let s = sl.data[k] as f64;
        let material = pt.material.clone().or_else(|| {
            ids.and_then(|ids| material_key(ids[k]))
                .map(|m| m.to_string())
        });
        out.push(PointResidual {
            id: pt.id.clone(),
            pixel: [c, r],
            material,
            truth,
            synthetic: s,
            residual: s - truth,
        });
    }
    let p: Vec<f64> = out.iter().map(|q| q.synthetic).collect();
    let t: Vec<f64> = out.iter().map(|q| q.truth).collect();
    let overall = Agreement::of(&p, &t)?;
    let mut groups: BTreeMap<String, (Vec<f64>, Vec<f64>)> = BTreeMap::new();
    for q in &out {
        if let Some(m) = &q.material {
            let g = groups.entry(m.clone()).or_default();
            g.0.push(q.synthetic);
            g.1.push(q.truth);
        }
    }
    let quantity = opts.quantity.unwrap_or(Quantity::of_layer(&sl.name));
    Ok(PointComparison {
        layer: sl.name.clone(),
        quantity,
        unit: quantity.unit().into(),
        overall,
        per_material: per_group(groups),
        points: out,
    })
}

/// The points with their values taken from the pixel of `truth` (layer
/// `layer`, or the only/first value layer) that contains each point.
pub fn sample_points(
    truth: &ImageStack,
    layer: Option<&str>,
    points: &[TruthPoint],
    points_file: &std::path::Path,
) -> Result<Vec<TruthPoint>> {
    let tl = pick_layer(truth, layer, "truth_layer")?;
    points
        .iter()
        .map(|pt| {
            let PointPosition::Pixel { x, y } = pt.position else {
                return Err(Error::parse(
                    Location::file(points_file).at_line(pt.line).with_field("lat"),
                    "lat/lon points must be georeferenced first (with the scene whose sensor made the image: `analysis::geo`), or given as pixel x,y columns",
                ));
            };
            if x < 0.0 || y < 0.0 || x >= truth.width as f64 || y >= truth.height as f64 {
                return Err(Error::parse(
                    Location::file(points_file).at_line(pt.line).with_field("x"),
                    format!(
                        "point ({x}, {y}) lies outside the {}×{} truth image",
                        truth.width, truth.height
                    ),
                ));
            }
            let k = y.floor() as usize * truth.width + x.floor() as usize;
            Ok(TruthPoint {
                value: Some(tl.data[k] as f64),
                ..pt.clone()
            })
        })
        .collect()
}

/// Names of the geolocation layers [`locate_by_latlon_layers`] reads.
pub const LATLON_LAYERS: [&str; 2] = ["latitude", "longitude"];

/// `points` with lat/lon positions replaced by the pixel of `synth` whose
/// `latitude`/`longitude` layers (a sensor's `truth_layers`) are nearest,
/// at its centre; pixel points pass unchanged. Distances are on the local
/// sphere (east scaled by cos latitude). A point is refused (naming
/// `points_file` and its line) when the nearest pixel is farther from it
/// than that pixel's distance to its farthest neighbour: it lies off the
/// image or in a gap (sky).
pub fn locate_by_latlon_layers(
    synth: &ImageStack,
    points: &[TruthPoint],
    points_file: &std::path::Path,
) -> Result<Vec<TruthPoint>> {
    let (Some(lat), Some(lon)) = (synth.layer(LATLON_LAYERS[0]), synth.layer(LATLON_LAYERS[1]))
    else {
        return Err(Error::invalid(
            "layer",
            "the synthetic image has no `latitude` and `longitude` layers (a sensor's `truth_layers`)",
        ));
    };
    let (w, h) = (synth.width, synth.height);
    // Squared distance in degrees of latitude between pixel k and (la, lo).
    let d2 = |k: usize, la: f64, lo: f64, c: f64| -> f64 {
        let (a, b) = (lat.data[k] as f64, lon.data[k] as f64);
        if a.is_nan() || b.is_nan() {
            return f64::INFINITY;
        }
        let dlon = (b - lo + 540.0).rem_euclid(360.0) - 180.0;
        (a - la).powi(2) + (dlon * c).powi(2)
    };
    points
        .iter()
        .map(|p| {
            let PointPosition::LatLon { lat: la, lon: lo } = p.position else {
                return Ok(p.clone());
            };
            let c = la.to_radians().cos();
            let (k, best) = (0..w * h)
                .map(|k| (k, d2(k, la, lo, c)))
                .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
            let (col, row) = (k % w.max(1), k / w.max(1));
            let neighbours = [
                (col > 0).then(|| k - 1),
                (col + 1 < w).then(|| k + 1),
                (row > 0).then(|| k - w),
                (row + 1 < h).then(|| k + w),
            ];
            let (a, b) = (lat.data[k] as f64, lon.data[k] as f64);
            let spacing = neighbours
                .iter()
                .flatten()
                .map(|&n| d2(n, a, b, c))
                .filter(|d| d.is_finite())
                .fold(0.0f64, f64::max);
            if !best.is_finite() || best > spacing {
                return Err(Error::parse(
                    Location::file(points_file)
                        .at_line(p.line)
                        .with_field("lat"),
                    format!(
                        "({la}, {lo}) is not on the synthetic image: the nearest pixel with a \
                         latitude/longitude is ({col}, {row}), {:.1} m away",
                        best.sqrt() * 111_195.0
                    ),
                ));
            }
            Ok(TruthPoint {
                position: PointPosition::Pixel {
                    x: col as f64 + 0.5,
                    y: row as f64 + 0.5,
                },
                ..p.clone()
            })
        })
        .collect()
}

/// Geometric accuracy from control points: offsets `truth − synthetic`.
#[derive(Debug, Clone, Serialize)]
pub struct GeometricAccuracy {
    /// Number of control points.
    pub n: usize,
    /// Mean offset (x, y), pixels.
    pub bias_px: [f64; 2],
    /// RMS offset per axis (x, y), pixels.
    pub rmse_px: [f64; 2],
    /// RMS of the offset length, pixels (`sqrt(rmse_x² + rmse_y²)`).
    pub rmse_radial_px: f64,
    /// Ground sample distance used for metres, m/pixel.
    pub gsd_m: Option<f64>,
    /// Mean offset, metres (x east-ward along columns, y along rows).
    pub bias_m: Option<[f64; 2]>,
    /// RMS offset per axis, metres.
    pub rmse_m: Option<[f64; 2]>,
    /// RMS offset length, metres.
    pub rmse_radial_m: Option<f64>,
}

/// Offsets' bias and RMSE of control points, in pixels and (with the ground
/// sample distance `gsd_m`, m/pixel) in metres.
pub fn geometric_accuracy(
    points: &[ControlPoint],
    gsd_m: Option<f64>,
) -> Result<GeometricAccuracy> {
    if points.is_empty() {
        return Err(Error::invalid("control points", "none given"));
    }
    if let Some(g) = gsd_m {
        if !(g.is_finite() && g > 0.0) {
            return Err(Error::invalid(
                "gsd_m",
                format!("expected a positive ground sample distance in metres, got {g}"),
            ));
        }
    }
    let dx: Vec<f64> = points.iter().map(|p| p.truth[0] - p.synth[0]).collect();
    let dy: Vec<f64> = points.iter().map(|p| p.truth[1] - p.synth[1]).collect();
    let rms = |d: &[f64]| (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt();
    let bias_px = [mean(&dx), mean(&dy)];
    let rmse_px = [rms(&dx), rms(&dy)];
    let rmse_radial_px = (rmse_px[0].powi(2) + rmse_px[1].powi(2)).sqrt();
    Ok(GeometricAccuracy {
        n: points.len(),
        bias_px,
        rmse_px,
        rmse_radial_px,
        gsd_m,
        bias_m: gsd_m.map(|g| [bias_px[0] * g, bias_px[1] * g]),
        rmse_m: gsd_m.map(|g| [rmse_px[0] * g, rmse_px[1] * g]),
        rmse_radial_m: gsd_m.map(|g| rmse_radial_px * g),
    })
}
