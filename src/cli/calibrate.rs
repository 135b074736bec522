//! `irsig calibrate`: fit input parameters within their bounds to truth
//! temperatures (bounded Levenberg–Marquardt, or Nelder–Mead), with
//! confidence intervals; `--list-params` prints every fittable parameter of
//! a material with its physical bounds.

use std::path::PathBuf;

use anyhow::Context;

use irsig::analysis::calibrate::{self, Bound, Calibration, CalibrationOptions, Method};
use irsig::analysis::csv;
use irsig::analysis::facet;
use irsig::analysis::params::ParamSet;
use irsig::analysis::registry;

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
`time,surface_temperature_k` for one facet, modelled as `irsig thermal` with
the same facet options (--tilt, --azimuth, --shape-factor, --site, --start,
--back, --spinup-days, --accurate). The fitted material is written with -o
as a material JSON file that `irsig thermal --material FITTED.json` reads;
--params-out writes every fitted parameter (weather ones included) as a
PARAMS file that `irsig thermal --params` applies. A fit with weather
parameters refuses -o without --params-out (a material file cannot carry
them).

--list-params (with --thermal --material M): every parameter of the
material's thermal model and the weather scalings, with value, unit and
physical bounds; with --json the list is itself a PARAMS file.

Example:
  irsig calibrate --thermal --material asphalt --list-params --json > params.json
  irsig calibrate --thermal --material asphalt --weather w.csv --truth series.csv \\
      --params params.json -o fitted.json --params-out fitted_params.json
  irsig thermal --material fitted.json --params fitted_params.json --weather w.csv --time …")]
pub struct Args {
    /// Scene file (omit with --thermal).
    pub scene: Option<PathBuf>,
    /// Truth: POINTS.csv (scene) or SERIES.csv (--thermal).
    #[arg(long, value_name = "CSV", required_unless_present = "list_params")]
    pub truth: Option<PathBuf>,
    /// Parameters to fit, with bounds (JSON).
    #[arg(
        long,
        value_name = "PARAMS.json",
        required_unless_present = "list_params"
    )]
    pub params: Option<PathBuf>,
    /// Print every fittable parameter of --material (and the weather
    /// scalings) with its physical bounds, and exit.
    #[arg(long, requires = "thermal")]
    pub list_params: bool,
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
    /// Search method.
    #[arg(long, value_enum, default_value = "lm")]
    pub method: SearchMethod,
    /// Confidence level of the intervals.
    #[arg(long, default_value_t = 0.95)]
    pub confidence: f64,
    /// Iterations (Levenberg–Marquardt: Jacobians; Nelder–Mead: per run).
    #[arg(long, default_value_t = 400, value_name = "N")]
    pub max_iters: u64,
    /// Nelder–Mead restarts from the best point.
    #[arg(long, default_value_t = 3, value_name = "N")]
    pub restarts: usize,
    /// Write the fitted material (one-facet form) as material JSON.
    #[arg(short = 'o', long, value_name = "FITTED.json")]
    pub output: Option<PathBuf>,
    /// Write every fitted parameter (value = fitted) as a PARAMS file.
    #[arg(long, value_name = "PARAMS.json")]
    pub params_out: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// The search method (`--method`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SearchMethod {
    /// Levenberg–Marquardt with bounds (Jacobian by finite differences).
    Lm,
    /// Bounded Nelder–Mead simplex with restarts (derivative-free).
    NelderMead,
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
    if args.list_params {
        return list_params(&args);
    }
    let truth_path = args.truth.as_ref().context("--truth CSV is required")?;
    let params_path = args
        .params
        .as_ref()
        .context("--params PARAMS.json is required")?;
    let opts = CalibrationOptions {
        method: match args.method {
            SearchMethod::Lm => Method::LevenbergMarquardt,
            SearchMethod::NelderMead => Method::NelderMead,
        },
        confidence: args.confidence,
        max_iters: args.max_iters,
        restarts: args.restarts,
    };
    if !args.one.thermal && (args.output.is_some() || args.params_out.is_some()) {
        anyhow::bail!(
            "-o and --params-out write the fit of the one-facet form (--thermal); the scene form prints its fit"
        );
    }
    let (result, fitted) = if args.one.thermal {
        anyhow::ensure!(
            args.scene.is_none(),
            "give either SCENE.json or --thermal, not both"
        );
        let series = csv::read_temperature_series(truth_path)?;
        let last = series.last().map(|s| s.0).context("empty series")?;
        let last_s = last.to_rfc3339();
        let study = match build_study(
            None,
            &args.one,
            &args.facet,
            &args.scene_args,
            Samples::PerMaterial(0),
            Some(&last_s),
            params_path,
        )? {
            Study::Facet(s) => s,
            Study::Scene(_) => unreachable!("--thermal builds a one-facet study"),
        };
        check_outputs(&args, &study.params)?;
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
                truth_path.display(),
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
        let listing = study.params.listing(&x)?;
        (c, Some((m, listing)))
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
            Samples::Points(truth_path),
            args.time.as_deref(),
            params_path,
        )?;
        let pts = csv::read_truth_points(truth_path)?;
        let truth = pts
            .iter()
            .map(|p| {
                p.value.with_context(|| {
                    format!(
                        "{}: line {}: no value (expected a `value` column)",
                        truth_path.display(),
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
    if let Some((m, listing)) = &fitted {
        if let Some(out) = &args.output {
            facet::write_material_json(
                out,
                m,
                &format!(
                    "{} fitted by irsig calibrate to {} (RMSE {:.3} K)",
                    m.name,
                    truth_path.display(),
                    result.fitted.rmse
                ),
            )?;
        }
        if let Some(out) = &args.params_out {
            let text = registry::ParamsFile { params: listing }.to_json();
            irsig::analysis::write_file_atomic(out, text.as_bytes())?;
        }
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&result)?);
    } else {
        print_result(&result)?;
    }
    Ok(())
}

/// Refuse, before fitting, an output that cannot carry every fitted
/// parameter: a material file holds no weather parameter.
fn check_outputs(args: &Args, params: &ParamSet) -> anyhow::Result<()> {
    if args.output.is_some() && args.params_out.is_none() && params.has_weather() {
        let names: Vec<&str> = params
            .params
            .iter()
            .filter(|p| matches!(p.target, irsig::analysis::params::Target::Weather(_)))
            .map(|p| p.name.as_str())
            .collect();
        anyhow::bail!(
            "-o writes a material file, which cannot carry the fitted weather parameter(s) {}; \
             add --params-out FILE to write every fitted parameter (then run \
             `irsig thermal --material FITTED.json --params FILE`), or leave them out of --params",
            names.join(", ")
        );
    }
    Ok(())
}

/// `--list-params`: every registered parameter of --material and the
/// weather scalings.
fn list_params(args: &Args) -> anyhow::Result<()> {
    let material = args.one.material()?;
    let list = registry::list(&material);
    if args.json {
        outln!(
            "{}",
            registry::ParamsFile { params: &list }.to_json().trim_end()
        );
        return Ok(());
    }
    let w = list
        .iter()
        .map(|p| p.property.len())
        .max()
        .unwrap_or(8)
        .max(8);
    outln!(
        "{:<9} {:<w$} {:>12} {:<10} {:>12} {:>12}",
        "kind",
        "property",
        "value",
        "unit",
        "low",
        "high"
    );
    for p in &list {
        outln!(
            "{:<9} {:<w$} {:>12.6} {:<10} {:>12} {:>12}",
            p.kind,
            p.property,
            p.value,
            p.unit,
            p.low,
            p.high
        );
    }
    Ok(())
}

fn print_result(c: &Calibration) -> anyhow::Result<()> {
    outln!(
        "fit to {} values ({} degrees of freedom), {} model evaluations ({})",
        c.n_obs,
        c.dof,
        c.evaluations,
        match c.method {
            Method::LevenbergMarquardt => "Levenberg–Marquardt",
            Method::NelderMead => "Nelder–Mead",
        }
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
        let rest = match (p.at_bound, p.std_error, p.ci_low, p.ci_high) {
            (Some(Bound::Low), ..) => format!("{:>12}  at its lower bound {}", "-", p.bounds[0]),
            (Some(Bound::High), ..) => format!("{:>12}  at its upper bound {}", "-", p.bounds[1]),
            (None, Some(se), Some(lo), Some(hi)) if se.is_finite() => {
                format!("{se:>12.5}  [{lo:.5}, {hi:.5}]")
            }
            _ => format!("{:>12}  not constrained by the data", "inf"),
        };
        outln!(
            "{:<40} {:>12.5} {:>12.5} {rest}",
            p.name,
            p.initial,
            p.fitted
        );
    }
    Ok(())
}
