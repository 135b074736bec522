//! `irsig thermal`: solve the thermal model for one free-standing facet
//! (THERM alone): no ray tracing, the sun unshadowed, the sky shape factor
//! of an unobstructed tilted plane, the background at air temperature.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use irsig::analysis::facet;
use irsig::analysis::params::ParamSet;
use irsig::thermal::SlabProperties;
use irsig::weather;

use super::args::{FlagContext, parse_time};
use super::sensitivity::{FACET_FLAGS as FLAGS, FacetArgs};

/// Arguments of `irsig thermal`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Material: a name in the material database (--materials), or a material
    /// file (irsig JSON or DIRSIG .mat) holding one material, or
    /// FILE#NAME for one material of a file.
    #[arg(long, value_name = "NAME|FILE")]
    pub material: String,
    /// Material database for --material NAME (default: the stock library,
    /// built into irsig).
    #[arg(long, value_name = "FILE")]
    pub materials: Option<PathBuf>,
    /// Weather file: irsig CSV/JSON, EPW, TMY3 CSV or DIRSIG .wth.
    #[arg(long, value_name = "FILE")]
    pub weather: PathBuf,
    /// Image time (RFC 3339 with offset): the history is solved from its
    /// first record up to this time.
    #[arg(long, value_name = "RFC3339")]
    pub time: String,
    #[command(flatten)]
    pub facet: FacetArgs,
    /// Parameter values to apply (a PARAMS file: each entry's `value` set on
    /// the material or the weather), e.g. the fitted parameters that
    /// `irsig calibrate --thermal --params-out` writes.
    #[arg(long, value_name = "PARAMS.json")]
    pub params: Option<PathBuf>,
    /// Print JSON: {"records": [{"time", "surface_temperature_k"}, …]}.
    #[arg(long, conflicts_with = "csv")]
    pub json: bool,
    /// Print CSV: time,surface_temperature_k.
    #[arg(long)]
    pub csv: bool,
}

/// `--material NAME|FILE|FILE#NAME` with `--materials FILE`, or, without it, a NAME from
/// the stock library built into irsig (not a path relative to the working directory).
pub(crate) fn find_material(
    spec: &str,
    db: Option<&std::path::Path>,
) -> irsig::Result<irsig::material::Material> {
    match db {
        Some(db) => facet::find_material(spec, db),
        None if spec.contains('#') || std::path::Path::new(spec).is_file() => {
            facet::find_material(spec, std::path::Path::new(""))
        }
        None => {
            let stock = irsig::material::stock::stock()?;
            stock.get(spec).cloned().ok_or_else(|| {
                irsig::Error::invalid(
                    "material",
                    format!(
                        "no material named `{spec}` in the stock library (or no such file); it has: {}",
                        stock
                            .materials()
                            .iter()
                            .map(|m| m.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })
        }
    }
}

/// Run `irsig thermal`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let time = parse_time("--time", &args.time)?;
    let f = &args.facet;
    let site = f.site()?;
    let mut material = find_material(&args.material, args.materials.as_deref()).for_flags(FLAGS)?;
    let history = weather::load_with(&args.weather, &f.load_options(time)?)?;
    let site = site.or(history.site().copied()).ok_or_else(|| {
        anyhow::anyhow!(
            "{}: the weather file names no site; give one with --site LAT,LON,ALT",
            args.weather.display()
        )
    })?;
    let mut records = facet::records_until(&history, time)
        .with_context(|| format!("{}: --time", args.weather.display()))?;
    if let Some(p) = &args.params {
        let ps = ParamSet::load(p, std::slice::from_ref(&material))
            .with_context(|| format!("--params {}", p.display()))?;
        let x = ps.nominal();
        material = ps.apply_material(&x, &material)?;
        records = ps.apply_weather_at(&x, &records, Some(&site))?;
    }
    let mut props = SlabProperties::from_material(&material)?;
    if let Some(back) = f.back()? {
        props = props.with_back(back);
    }
    f.warn_unused_back_shape_factor(&props.back);
    let options = f.options();
    let (sol, shape_factor) =
        facet::solve_free_facet(&props, &records, &site, &f.spec(), &options).for_flags(FLAGS)?;
    if let Some(w) = sol.exchange_passes.and_then(|p| p.warning(&material.name)) {
        eprintln!("warning: {w}");
    }

    let mut out = std::io::stdout().lock();
    let times = records.iter().map(|r| r.time);
    if args.json {
        let records: Vec<JsonRecord> = times
            .zip(&sol.surface_temperature_k)
            .map(|(t, &k)| JsonRecord {
                time: t.to_rfc3339(),
                surface_temperature_k: k,
            })
            .collect();
        serde_json::to_writer(&mut out, &JsonOutput { records })?;
        writeln!(out)?;
    } else if args.csv {
        writeln!(out, "time,surface_temperature_k")?;
        for (t, k) in times.zip(&sol.surface_temperature_k) {
            writeln!(out, "{},{k:.4}", t.to_rfc3339())?;
        }
    } else {
        writeln!(
            out,
            "material {} ({:?}), tilt {:.1}°, azimuth {:.1}°, shape factor {shape_factor:.4}",
            material.name, props.back, f.tilt, f.azimuth
        )?;
        match sol.spinup_change_k {
            Some(c) => writeln!(
                out,
                "spin-up: {} day(s), last day changed the state by {c:.3} K",
                sol.spinup_cycles
            )?,
            None => writeln!(
                out,
                "spin-up: none (history shorter than a day or disabled)"
            )?,
        }
        writeln!(out, "{:<26} {:>10} {:>8}", "time", "T_s (K)", "T_s (°C)")?;
        for (t, k) in times.zip(&sol.surface_temperature_k) {
            writeln!(out, "{:<26} {k:>10.2} {:>8.2}", t.to_rfc3339(), k - 273.15)?;
        }
    }
    Ok(())
}

/// `--json` output: `{"records": [{"time", "surface_temperature_k"}, …]}`.
#[derive(serde::Serialize)]
struct JsonOutput {
    records: Vec<JsonRecord>,
}

#[derive(serde::Serialize)]
struct JsonRecord {
    time: String,
    surface_temperature_k: f64,
}
