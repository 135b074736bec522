//! `irsig diurnal`: target and background temperatures and radiance
//! through a period, the time of greatest contrast and thermal crossovers;
//! one thermal run (one spin-up) per material on the one-facet path.

use std::path::PathBuf;

use anyhow::Context;
use chrono::{DateTime, Duration, FixedOffset};
use serde::Serialize;

use irsig::analysis::diurnal::{self, ContrastSeries};
use irsig::analysis::plot;

use super::args::{FlagContext, parse_time};
use super::sensitivity::SceneArgs;

/// Arguments of `irsig diurnal`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = "\
The scene's thermal state is computed at every sample time in one run (per-facet
inputs traced once, one spin-up for the whole period), and up to --samples
pixels of the sensor image that see the target (and the background) are shaded
through the render's radiometry at each time: surface temperature of the facets
under them, apparent temperature and band radiance at the sensor, averaged.
The target is an object name or a material name; so is the background (the
target object's own facets are left out of it).

Example:
  irsig diurnal scenes/town/scene.json --target building_1 --background grass --plot contrast.png")]
pub struct Args {
    /// Scene file.
    pub scene: PathBuf,
    /// Target object (or material) name.
    #[arg(long, value_name = "OBJECT")]
    pub target: String,
    /// Background object or material name.
    #[arg(long, value_name = "OBJECT|MATERIAL")]
    pub background: String,
    /// Start (RFC 3339; default: midnight before the image time).
    #[arg(long, value_name = "T")]
    pub from: Option<String>,
    /// End (RFC 3339; default: 24 h after --from).
    #[arg(long, value_name = "T")]
    pub to: Option<String>,
    /// Sampling step in minutes.
    #[arg(long, value_name = "MIN", default_value_t = 15)]
    pub step: i64,
    /// Pixels sampled per side (target, background).
    #[arg(long, value_name = "N", default_value_t = 16)]
    pub samples: usize,
    #[command(flatten)]
    pub scene_args: SceneArgs,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Plot the curves (apparent temperatures and their contrast).
    #[arg(long, value_name = "OUT.png")]
    pub plot: Option<PathBuf>,
}

#[derive(Serialize)]
struct Report {
    target: String,
    background: String,
    sensor: String,
    target_pixels: Vec<[f64; 2]>,
    background_pixels: Vec<[f64; 2]>,
    times: Vec<String>,
    surface_temperature: ContrastSeries,
    apparent_temperature: ContrastSeries,
    band_radiance: ContrastSeries,
}

/// Run `irsig diurnal`.
pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::ensure!(args.step > 0, "--step must be a positive number of minutes");
    let (mut session, s) = args.scene_args.open(&args.scene)?;
    let scene = &session.scene;
    let from: DateTime<FixedOffset> = match &args.from {
        Some(s) => parse_time("--from", s)?,
        None => {
            let d = scene
                .time
                .date_naive()
                .and_hms_opt(0, 0, 0)
                .context("midnight")?;
            d.and_local_timezone(*scene.time.offset())
                .single()
                .context("midnight")?
        }
    };
    let to = match &args.to {
        Some(s) => parse_time("--to", s)?,
        None => from + Duration::hours(24),
    };
    anyhow::ensure!(to > from, "--to must be after --from");
    let sensor = session.sensors[s].name.clone();
    let report_sensor = sensor.clone();
    let band_name = session.sensors[s].bands[0].name.clone();
    let mut times = Vec::new();
    let mut t = from;
    while t <= to {
        times.push(t);
        t += Duration::minutes(args.step);
    }
    anyhow::ensure!(
        times.len() <= 2000,
        "{} sample times: choose a longer --step or a shorter period",
        times.len()
    );
    anyhow::ensure!(args.samples > 0, "--samples must be at least 1");
    let contrast = diurnal::scene_contrast(
        &mut session,
        s,
        &args.target,
        &args.background,
        args.samples,
        &times,
    )
    .for_flags(&[("target", "--target"), ("background", "--background")])?;
    let diurnal::SceneContrast {
        target_pixels: tp,
        background_pixels: bp,
        surface_temperature: surface,
        band_radiance: radiance,
        apparent_temperature: apparent,
    } = contrast;
    if let Some(p) = &args.plot {
        let hours: Vec<f64> = times
            .iter()
            .map(|t| (*t - from).num_minutes() as f64 / 60.0)
            .collect();
        let mut marks: Vec<(String, f64)> = apparent
            .crossovers
            .iter()
            .map(|c| {
                (
                    format!("crossover {}", c.format("%H:%M")),
                    (*c - from).num_minutes() as f64 / 60.0,
                )
            })
            .collect();
        marks.push((
            format!("max |ΔT| {}", apparent.time_of_max.format("%H:%M")),
            (apparent.time_of_max - from).num_minutes() as f64 / 60.0,
        ));
        plot::curves(
            p,
            &format!(
                "{} vs {}: apparent temperature, {} band {}",
                args.target, args.background, report_sensor, band_name
            ),
            &format!("hours after {}", from.format("%Y-%m-%d %H:%M %:z")),
            "K",
            &hours,
            &[
                (args.target.as_str(), &apparent.target),
                (args.background.as_str(), &apparent.background),
            ],
            &marks,
        )?;
    }
    let report = Report {
        target: args.target.clone(),
        background: args.background.clone(),
        sensor,
        target_pixels: tp.iter().map(|p| [p.x, p.y]).collect(),
        background_pixels: bp.iter().map(|p| [p.x, p.y]).collect(),
        times: times.iter().map(|t| t.to_rfc3339()).collect(),
        surface_temperature: surface,
        apparent_temperature: apparent,
        band_radiance: radiance,
    };
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    outln!(
        "{} ({} pixels) vs {} ({} pixels) in sensor `{}`, {} to {}",
        report.target,
        report.target_pixels.len(),
        report.background,
        report.background_pixels.len(),
        report.sensor,
        from,
        to
    );
    for s in [
        &report.apparent_temperature,
        &report.surface_temperature,
        &report.band_radiance,
    ] {
        let cross: Vec<String> = s
            .crossovers
            .iter()
            .map(|c| c.format("%H:%M").to_string())
            .collect();
        outln!(
            "  {:<22} greatest contrast {:+.4} {} at {}; crossovers: {}",
            s.quantity,
            s.max_contrast_signed,
            s.unit,
            s.time_of_max.format("%H:%M"),
            if cross.is_empty() {
                "none".to_string()
            } else {
                cross.join(", ")
            }
        );
    }
    Ok(())
}
