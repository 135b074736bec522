//! `irsig calibrate`: fit input parameters within their bounds to truth
//! temperatures (bounded Nelder–Mead), with confidence intervals.

use std::path::PathBuf;

use anyhow::Context;

use irsig::analysis::calibrate::{self, Calibration, CalibrationOptions};
use irsig::analysis::csv;
use irsig::analysis::facet;

use super::sensitivity::{FacetArgs, Samples, SceneArgs, Study, ThermalArgs, build_study};

/// Arguments of `irsig calibrate`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = "\
Scene form: POINTS.csv holds `x,y,value` or `lat,lon,value` rows (pixel or
geographic position in the sensor image, value at the image time: apparent
temperature in K by default, see --quantity); each point is predicted at its
pixel with the scene's per-facet inputs traced once, the facets under it
re-solved and the pixel shaded through the render's radiometry.
One-facet form (--thermal): SERIES.csv holds
`time,surface_temperature_k` for one facet (as `irsig thermal`); the fitted
material is written with -o as a material JSON file that
`irsig thermal --material FITTED.json` reads.

Example:
  irsig calibrate --thermal --material asphalt --weather w.csv --truth series.csv \\
      --params params.json -o fitted.json")]
pub struct Args {
    /// Scene file (omit with --thermal).
    pub scene: Option<PathBuf>,
    /// Truth: POINTS.csv (scene) or SERIES.csv (--thermal).
    #[arg(long, value_name = "CSV")]
    pub truth: PathBuf,
    /// Parameters to fit, with bounds (JSON).
    #[arg(long, value_name = "PARAMS.json")]
    pub params: PathBuf,
    /// Image time (scene form; default the scene's).
    #[arg(long, value_name = "RFC3339")]
    pub time: Option<String>,
    #[command(flatten)]
    pub one: ThermalArgs,
    #[command(flatten)]
    pub facet: FacetArgs,
    #[command(flatten)]
    pub scene_args: SceneArgs,
    /// What the scene-form truth values are.
    #[arg(long, value_enum, default_value = "apparent-temperature")]
    pub quantity: Quantity,
    /// Confidence level of the intervals.
    #[arg(long, default_value_t = 0.95)]
    pub confidence: f64,
    /// Nelder–Mead iterations per run.
    #[arg(long, default_value_t = 400, value_name = "N")]
    pub max_iters: u64,
    /// Nelder–Mead restarts from the best point.
    #[arg(long, default_value_t = 3, value_name = "N")]
    pub restarts: usize,
    /// Write the fitted material (one-facet form) as material JSON.
    #[arg(short = 'o', long, value_name = "FITTED.json")]
    pub output: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// The quantity of scene-form truth values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Quantity {
    /// Surface temperature of the facet under the pixel centre, K.
    SurfaceTemperature,
    /// Apparent (band brightness) temperature at the sensor, K.
    ApparentTemperature,
    /// Band radiance at the sensor, W/m²/sr.
    Radiance,
}

impl Quantity {
    /// Index among a scene study's three outputs per point.
    fn index(self) -> usize {
        match self {
            Quantity::SurfaceTemperature => 0,
            Quantity::ApparentTemperature => 1,
            Quantity::Radiance => 2,
        }
    }
}

/// Run `irsig calibrate`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let opts = CalibrationOptions {
        confidence: args.confidence,
        max_iters: args.max_iters,
        restarts: args.restarts,
    };
    let (result, fitted_material) = if args.one.thermal {
        anyhow::ensure!(
            args.scene.is_none(),
            "give either SCENE.json or --thermal, not both"
        );
        let series = csv::read_temperature_series(&args.truth)?;
        let last = series.last().map(|s| s.0).context("empty series")?;
        let last_s = last.to_rfc3339();
        let study = match build_study(
            None,
            &args.one,
            &args.facet,
            &args.scene_args,
            Samples::PerMaterial(0),
            Some(&last_s),
            &args.params,
        )? {
            Study::Facet(s) => s,
            Study::Scene(_) => unreachable!("--thermal builds a one-facet study"),
        };
        let times: Vec<f64> = study
            .facet
            .records
            .iter()
            .map(|r| (r.time - study.facet.records[0].time).num_milliseconds() as f64 * 1e-3)
            .collect();
        let at: Vec<f64> = series
            .iter()
            .map(|(t, _)| (*t - study.facet.records[0].time).num_milliseconds() as f64 * 1e-3)
            .collect();
        if let Some((k, (t, _))) = series.iter().enumerate().find(|(k, _)| at[*k] < 0.0) {
            anyhow::bail!(
                "{}: line {}: {t} is before the first weather record",
                args.truth.display(),
                k + 2
            );
        }
        let truth: Vec<f64> = series.iter().map(|s| s.1).collect();
        let model = |x: &[f64]| -> irsig::Result<Vec<f64>> {
            let ts = study.temperature_series(x, 0)?;
            Ok(at
                .iter()
                .map(|&t| irsig::math::interp1d(&times, &ts, t))
                .collect())
        };
        let c = calibrate::calibrate(&study.params.factors(), &truth, &model, opts)?;
        let x: Vec<f64> = c.params.iter().map(|p| p.fitted).collect();
        let m = study.params.apply_material(&x, &study.materials[0])?;
        (c, Some(m))
    } else {
        let scene = args
            .scene
            .as_ref()
            .context("give a SCENE.json, or --thermal …")?;
        let study = build_study(
            Some(scene),
            &args.one,
            &args.facet,
            &args.scene_args,
            Samples::Points(&args.truth),
            args.time.as_deref(),
            &args.params,
        )?;
        let pts = csv::read_truth_points(&args.truth)?;
        let truth = pts
            .iter()
            .map(|p| {
                p.value.with_context(|| {
                    format!(
                        "{}: line {}: no value (expected a `value` column)",
                        args.truth.display(),
                        p.line
                    )
                })
            })
            .collect::<anyhow::Result<Vec<f64>>>()?;
        let q = args.quantity.index();
        let model = |x: &[f64]| -> irsig::Result<Vec<f64>> {
            let y = study.evaluate(x)?;
            Ok((0..truth.len()).map(|k| y[3 * k + q]).collect())
        };
        (
            calibrate::calibrate(&study.params().factors(), &truth, &model, opts)?,
            None,
        )
    };
    if let (Some(out), Some(m)) = (&args.output, &fitted_material) {
        facet::write_material_json(
            out,
            m,
            &format!(
                "{} fitted by irsig calibrate to {} (RMSE {:.3} K)",
                m.name,
                args.truth.display(),
                result.fitted.rmse
            ),
        )?;
    } else if args.output.is_some() {
        anyhow::bail!("-o writes the fitted material of the one-facet form (--thermal)");
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&result)?);
    } else {
        print_result(&result)?;
    }
    Ok(())
}

fn print_result(c: &Calibration) -> anyhow::Result<()> {
    outln!(
        "fit to {} values ({} degrees of freedom), {} model evaluations",
        c.n_obs,
        c.dof,
        c.evaluations
    );
    outln!(
        "RMSE {:.4} → {:.4}   bias {:+.4} → {:+.4}   Spearman {:.4} → {:.4}",
        c.initial.rmse,
        c.fitted.rmse,
        c.initial.bias,
        c.fitted.bias,
        c.initial.spearman,
        c.fitted.spearman
    );
    outln!(
        "{:<40} {:>12} {:>12} {:>12}  {:.0}% interval",
        "parameter",
        "initial",
        "fitted",
        "std error",
        c.confidence * 100.0
    );
    for p in &c.params {
        outln!(
            "{:<40} {:>12.5} {:>12.5} {:>12.5}  [{:.5}, {:.5}]{}",
            p.name,
            p.initial,
            p.fitted,
            p.std_error,
            p.ci_low,
            p.ci_high,
            if p.at_bound { "  (at a bound)" } else { "" }
        );
    }
    Ok(())
}
