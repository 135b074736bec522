//! `irsig compare`: validate a synthetic image against truth imagery or
//! point measurements, and its geometry against control points.

use std::path::PathBuf;

use anyhow::Context;
use serde::Serialize;

use irsig::analysis::compare::{
    self, CompareOptions, GeometricAccuracy, ImageComparison, MaterialAgreement, PointComparison,
};
use irsig::analysis::image::{Calibration, read_image};
use irsig::analysis::stats::Agreement;
use irsig::analysis::{csv, geo, plot};

use super::args::FlagContext;

/// The layers' names and flags, for errors about them.
const LAYER_FLAGS: &[(&str, &str)] = &[("layer", "--layer"), ("truth_layer", "--truth-layer")];

/// What the values are (`--quantity`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum QuantityArg {
    /// A temperature, K.
    Temperature,
    /// A radiance (or another quantity), in the layer's unit.
    Radiance,
}

impl From<QuantityArg> for compare::Quantity {
    fn from(q: QuantityArg) -> Self {
        match q {
            QuantityArg::Temperature => compare::Quantity::Temperature,
            QuantityArg::Radiance => compare::Quantity::Radiance,
        }
    }
}

/// Arguments of `irsig compare`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = "\
Residuals are synthetic − truth: a positive bias means the synthetic image is
too warm (too bright). Statistics are in kelvin for temperature layers, in the
layer's radiance unit otherwise.

CSV formats (header row; `#` comments):
  truth points    x,y,value[,material][,id]   (pixel x = column, y = row)
                  lat,lon,value[,material][,id] (degrees; with --scene, the scene
                  whose sensor made the image, the point is dropped onto the
                  scene surface, projected through the sensor, and refused when
                  it falls outside the image or is hidden from the sensor;
                  without it, the image's latitude/longitude layers (a sensor's
                  truth_layers) give the nearest pixel)
  control points  synth_x,synth_y,truth_x,truth_y[,id]

Examples:
  irsig compare out/scene.exr truth.tif --truth-gain 0.01 --plot hist.png
  irsig compare out/scene.exr field_points.csv --json
  irsig compare out/scene.exr truth.png --points sites.csv --control gcps.csv --gsd 0.5")]
pub struct Args {
    /// Synthetic image (EXR, ENVI, TIFF or PNG).
    pub synth: PathBuf,
    /// Truth: an image of the same grid (EXR, ENVI, single-band TIFF/PNG),
    /// or a CSV of point measurements `x,y,value[,material]`.
    pub truth: PathBuf,
    /// Validation points (CSV `x,y[,material][,id]`) at which to compare
    /// the synthetic and the truth image (in addition to the whole image).
    #[arg(long, value_name = "POINTS.csv")]
    pub points: Option<PathBuf>,
    /// Synthetic layer to compare (default: apparent_temperature, else the
    /// first value layer).
    #[arg(long, value_name = "NAME")]
    pub layer: Option<String>,
    /// Truth layer (default: the same name as the synthetic one, or the only one).
    #[arg(long, value_name = "NAME")]
    pub truth_layer: Option<String>,
    /// Truth calibration gain: value = gain·DN + offset (for camera DNs).
    #[arg(long, default_value_t = 1.0, value_name = "GAIN")]
    pub truth_gain: f64,
    /// Truth calibration offset: value = gain·DN + offset.
    #[arg(long, default_value_t = 0.0, value_name = "OFFSET")]
    pub truth_offset: f64,
    /// Control points located in both images (CSV
    /// `synth_x,synth_y,truth_x,truth_y`): report geometric accuracy.
    #[arg(long, value_name = "CONTROL.csv")]
    pub control: Option<PathBuf>,
    /// Ground sample distance, metres per pixel (for offsets in metres).
    #[arg(long, value_name = "M")]
    pub gsd: Option<f64>,
    /// What the values are (default: temperature when the layer name says
    /// so, else radiance).
    #[arg(long, value_enum)]
    pub quantity: Option<QuantityArg>,
    /// Histogram bins.
    #[arg(long, default_value_t = 64, value_name = "N")]
    pub bins: usize,
    /// The scene whose sensor made the synthetic image: georeferences
    /// lat/lon points (its site is the origin of its ENU frame).
    #[arg(long, value_name = "SCENE.json")]
    pub scene: Option<PathBuf>,
    /// Sensor of --scene that made the image (default: the first).
    #[arg(long, value_name = "NAME", requires = "scene")]
    pub sensor: Option<String>,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Write a plot: histograms of both images (image truth) or a
    /// synthetic-vs-truth scatter (point truth).
    #[arg(long, value_name = "OUT.png")]
    pub plot: Option<PathBuf>,
}

#[derive(Debug, Serialize)]
struct Report {
    synthetic: String,
    truth: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    image: Option<ImageComparison>,
    #[serde(skip_serializing_if = "Option::is_none")]
    points: Option<PointComparison>,
    #[serde(skip_serializing_if = "Option::is_none")]
    geometry: Option<GeometricAccuracy>,
}

/// Run `irsig compare`.
pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::ensure!(args.bins > 0, "--bins must be at least 1");
    anyhow::ensure!(
        args.truth_gain.is_finite() && args.truth_offset.is_finite(),
        "--truth-gain and --truth-offset must be finite numbers"
    );
    let synth = read_image(&args.synth)?;
    let opts = CompareOptions {
        layer: args.layer.clone(),
        truth_layer: args.truth_layer.clone(),
        bins: Some(args.bins),
        quantity: args.quantity.map(Into::into),
    };
    let truth_is_csv = args
        .truth
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let mut report = Report {
        synthetic: args.synth.display().to_string(),
        truth: args.truth.display().to_string(),
        image: None,
        points: None,
        geometry: None,
    };
    if truth_is_csv {
        anyhow::ensure!(
            args.points.is_none(),
            "--points samples a truth image; with a CSV truth the points are in TRUTH itself"
        );
        let pts = georeference(
            &args,
            &synth,
            csv::read_truth_points(&args.truth)?,
            &args.truth,
        )?;
        report.points =
            Some(compare::compare_points(&synth, &pts, &args.truth, &opts).for_flags(LAYER_FLAGS)?);
    } else {
        let mut truth = read_image(&args.truth)?;
        Calibration {
            gain: args.truth_gain,
            offset: args.truth_offset,
        }
        .apply(&mut truth);
        report.image = Some(
            compare::compare_images(&synth, &truth, &opts)
                .for_flags(LAYER_FLAGS)
                .with_context(|| {
                    format!(
                        "comparing {} with {}",
                        args.synth.display(),
                        args.truth.display()
                    )
                })?,
        );
        if let Some(pp) = &args.points {
            let pts = georeference(&args, &synth, csv::read_truth_points(pp)?, pp)?;
            let pts = compare::sample_points(
                &truth,
                opts.truth_layer
                    .as_deref()
                    .or(report.image.as_ref().map(|i| i.layer.as_str()))
                    .filter(|n| truth.layer(n).is_some()),
                &pts,
                pp,
            )
            .for_flags(LAYER_FLAGS)?;
            report.points =
                Some(compare::compare_points(&synth, &pts, pp, &opts).for_flags(LAYER_FLAGS)?);
        }
    }
    if let Some(cp) = &args.control {
        let pts = csv::read_control_points(cp)?;
        report.geometry =
            Some(compare::geometric_accuracy(&pts, args.gsd).for_flags(&[("gsd_m", "--gsd")])?);
    } else {
        anyhow::ensure!(args.gsd.is_none(), "--gsd needs --control");
    }
    if let Some(out) = &args.plot {
        if let Some(img) = &report.image {
            plot::histograms(
                out,
                &format!("{} histograms", img.layer),
                &format!("{} ({})", img.layer, img.unit),
                &[
                    ("synthetic", &img.synth_histogram),
                    ("truth", &img.truth_histogram),
                ],
            )?;
        } else if let Some(p) = &report.points {
            let t: Vec<f64> = p.points.iter().map(|q| q.truth).collect();
            let s: Vec<f64> = p.points.iter().map(|q| q.synthetic).collect();
            plot::scatter(
                out,
                &format!("{} at validation points", p.layer),
                &p.unit,
                &t,
                &s,
            )?;
        }
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_report(&report)?;
    }
    Ok(())
}

/// Lat/lon points of `file` to pixels through `--scene`'s sensor, or,
/// without `--scene`, through the synthetic image's `latitude`/`longitude`
/// layers (pixel points pass unchanged; without lat/lon points the scene is
/// not opened).
fn georeference(
    args: &Args,
    synth: &irsig::output::ImageStack,
    pts: Vec<csv::TruthPoint>,
    file: &std::path::Path,
) -> anyhow::Result<Vec<csv::TruthPoint>> {
    if !pts
        .iter()
        .any(|p| matches!(p.position, csv::PointPosition::LatLon { .. }))
    {
        return Ok(pts);
    }
    let Some(scene) = &args.scene else {
        if compare::LATLON_LAYERS
            .iter()
            .all(|l| synth.layer(l).is_some())
        {
            return Ok(compare::locate_by_latlon_layers(synth, &pts, file)?);
        }
        anyhow::bail!(
            "{}: lat/lon points need --scene SCENE.json (the scene whose sensor made {}) to georeference the image, or `latitude`/`longitude` layers in it (the sensor's `truth_layers`)",
            file.display(),
            args.synth.display()
        );
    };
    let sa = super::sensitivity::SceneArgs {
        sensor: args.sensor.clone(),
        backend: irsig::Backend::Embree,
    };
    let (session, s) = sa.open(scene)?;
    Ok(geo::points_to_pixels(&session, s, &pts, file)?)
}

fn print_agreement(label: &str, a: &Agreement, unit: &str) -> anyhow::Result<()> {
    outln!(
        "  {label:<16} n={:<8} bias {:+.4} {unit}  RMSE {:.4} {unit}  MAE {:.4} {unit}  Spearman {:.4}  Pearson {:.4}",
        a.n,
        a.bias,
        a.rmse,
        a.mae,
        a.spearman,
        a.pearson
    );
    Ok(())
}

fn print_materials(m: &[MaterialAgreement], unit: &str) -> anyhow::Result<()> {
    if !m.is_empty() {
        outln!("  per material:");
        for g in m {
            print_agreement(&format!("  {}", g.material), &g.agreement, unit)?;
        }
    }
    Ok(())
}

fn print_report(r: &Report) -> anyhow::Result<()> {
    outln!("synthetic {}  vs  truth {}", r.synthetic, r.truth);
    if let Some(i) = &r.image {
        outln!("image, layer `{}` (synthetic − truth):", i.layer);
        print_agreement("all pixels", &i.overall, &i.unit)?;
        print_materials(&i.per_material, &i.unit)?;
    }
    if let Some(p) = &r.points {
        outln!(
            "validation points, layer `{}` (synthetic − truth):",
            p.layer
        );
        print_agreement("all points", &p.overall, &p.unit)?;
        print_materials(&p.per_material, &p.unit)?;
    }
    if let Some(g) = &r.geometry {
        outln!(
            "geometric accuracy from {} control points (truth − synthetic):",
            g.n
        );
        outln!(
            "  bias x {:+.3} px, y {:+.3} px; RMSE x {:.3} px, y {:.3} px, radial {:.3} px",
            g.bias_px[0],
            g.bias_px[1],
            g.rmse_px[0],
            g.rmse_px[1],
            g.rmse_radial_px
        );
        if let (Some(b), Some(e), Some(rr), Some(gsd)) =
            (g.bias_m, g.rmse_m, g.rmse_radial_m, g.gsd_m)
        {
            outln!(
                "  at {gsd} m/px: bias x {:+.3} m, y {:+.3} m; RMSE x {:.3} m, y {:.3} m, radial {:.3} m",
                b[0],
                b[1],
                e[0],
                e[1],
                rr
            );
        }
    }
    Ok(())
}
