//! `irsig diurnal`: target and background temperatures and radiance
//! through a period, the time of greatest contrast and thermal crossovers;
//! one thermal run (one spin-up) per material on the one-facet path.

use std::path::PathBuf;

use anyhow::Context;
use chrono::{DateTime, Duration, FixedOffset};
use serde::Serialize;

use irsig::analysis::diurnal::{self, ContrastSeries};
use irsig::analysis::plot;
use irsig::material::Material;
use irsig::scene::Scene;

use super::sensitivity::{FacetArgs, parse_time, setup_scene};

/// Arguments of `irsig diurnal`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = "\
Objects stand for their dominant material (most facets); each material is
solved once as a free-standing facet (--tilt/--azimuth/--shape-factor) over
the weather history up to --to, and sampled every --step from --from.

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
    #[command(flatten)]
    pub facet: FacetArgs,
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
    target_material: String,
    background: String,
    background_material: String,
    times: Vec<String>,
    surface_temperature: ContrastSeries,
    apparent_temperature: ContrastSeries,
    band_radiance: ContrastSeries,
}

/// The material an object stands for (its most common part's), or the
/// material of that name.
fn resolve(scene: &Scene, name: &str, materials: &[Material]) -> anyhow::Result<Material> {
    if let Some(o) = scene.objects.iter().position(|o| o.name == name) {
        let mut count = vec![0usize; scene.parts.len()];
        for (i, inst) in scene.geometry.instances.iter().enumerate() {
            if scene.instance_object[i] == o {
                for &p in &scene.mesh_parts[inst.mesh] {
                    count[p as usize] += 1;
                }
            }
        }
        let p = (0..count.len())
            .max_by_key(|&p| count[p])
            .filter(|&p| count[p] > 0);
        return Ok(
            scene.part_material(p.with_context(|| format!("object `{name}` has no facets"))?)
        );
    }
    if let Some(m) = materials.iter().find(|m| m.name == name) {
        return Ok(m.clone());
    }
    scene.materials.get(name).cloned().with_context(|| {
        format!(
            "{}: `{name}` is neither an object ({}) nor a material of the scene",
            scene.path.display(),
            scene
                .objects
                .iter()
                .take(8)
                .map(|o| o.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )
    })
}

/// Run `irsig diurnal`.
pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::ensure!(args.step > 0, "--step must be a positive number of minutes");
    let scene = Scene::load(&args.scene)?;
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
    let setup = setup_scene(&scene, &args.facet, Some(to))?;
    let target = resolve(&scene, &args.target, &setup.materials)?;
    let background = resolve(&scene, &args.background, &setup.materials)?;
    let f = &setup.facet;
    anyhow::ensure!(
        f.records[0].time <= from,
        "{}: the weather starts at {}, after --from {from}",
        args.scene.display(),
        f.records[0].time
    );
    let t_s = |m: &Material| f.surface_temperatures(m, &f.records);
    let (tt, tb) = (t_s(&target)?, t_s(&background)?);
    let secs = |t: DateTime<FixedOffset>| (t - f.records[0].time).num_milliseconds() as f64 * 1e-3;
    let xs: Vec<f64> = f.records.iter().map(|r| secs(r.time)).collect();
    let mut times = Vec::new();
    let mut t = from;
    while t <= to {
        times.push(t);
        t += Duration::minutes(args.step);
    }
    let lerp = |ys: &[f64], x: f64| {
        let i = xs.partition_point(|&v| v <= x).clamp(1, xs.len() - 1);
        let w = ((x - xs[i - 1]) / (xs[i] - xs[i - 1])).clamp(0.0, 1.0);
        ys[i - 1] + w * (ys[i] - ys[i - 1])
    };
    let mut cols: [Vec<f64>; 6] = Default::default();
    for &t in &times {
        let x = secs(t);
        let rec = f.records[f.index_at(t)?];
        for (k, (m, ts)) in [(&target, &tt), (&background, &tb)].into_iter().enumerate() {
            let temp = lerp(ts, x);
            let l = f.band_radiance(m, &rec, temp);
            cols[k].push(temp);
            cols[2 + k].push(l);
            cols[4 + k].push(f.apparent_temperature(l)?);
        }
    }
    let surface = diurnal::contrast_series("surface_temperature", "K", &times, &cols[0], &cols[1])?;
    let radiance =
        diurnal::contrast_series("band_radiance", "W/m2/sr", &times, &cols[2], &cols[3])?;
    let apparent =
        diurnal::contrast_series("apparent_temperature", "K", &times, &cols[4], &cols[5])?;
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
                "{} vs {}: apparent temperature (8–14 µm)",
                args.target, args.background
            ),
            &format!("hours after {}", from.format("%Y-%m-%d %H:%M %:z")),
            "K",
            &hours,
            &[
                (args.target.as_str(), &cols[4]),
                (args.background.as_str(), &cols[5]),
            ],
            &marks,
        )?;
    }
    let report = Report {
        target: args.target.clone(),
        target_material: target.name.clone(),
        background: args.background.clone(),
        background_material: background.name.clone(),
        times: times.iter().map(|t| t.to_rfc3339()).collect(),
        surface_temperature: surface,
        apparent_temperature: apparent,
        band_radiance: radiance,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    println!(
        "{} ({}) vs {} ({}), {} to {}",
        report.target,
        report.target_material,
        report.background,
        report.background_material,
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
        println!(
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
