//! `irsig thermal`: solve the thermal model for one free-standing facet
//! (THERM alone): no ray tracing, the sun unshadowed, the sky shape factor
//! of an unobstructed tilted plane, the background at air temperature.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use irsig::analysis::facet::{self, FacetSpec};
use irsig::thermal::{BackBoundary, SlabProperties, SolveOptions, Spinup};
use irsig::weather::{self, LoadOptions};

use super::args::{FlagContext, parse_site, parse_time};
use super::sensitivity::FACET_FLAGS as FLAGS;

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
    /// Local date and time of hour 0 of a DIRSIG .wth file (RFC 3339).
    #[arg(long, value_name = "RFC3339")]
    pub start: Option<String>,
    /// Replace the year of every EPW/TMY3 row. A typical-year file (months
    /// from different years) takes --time's year without it.
    #[arg(long, value_name = "YEAR")]
    pub year: Option<i32>,
    /// Image time (RFC 3339 with offset): the history is solved from its
    /// first record up to this time.
    #[arg(long, value_name = "RFC3339")]
    pub time: String,
    /// Facet tilt from horizontal, degrees (0 = facing up, 90 = vertical).
    #[arg(long, value_name = "DEG", default_value_t = 0.0)]
    pub tilt: f64,
    /// Direction the facet faces, degrees clockwise from north (180 = south).
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 180.0,
        allow_negative_numbers = true
    )]
    pub azimuth: f64,
    /// Sky shape factor of the front face, 0–1 (default: (1 + cos tilt)/2,
    /// an unobstructed plane).
    #[arg(long, value_name = "F")]
    pub shape_factor: Option<f64>,
    /// Site as LAT,LON,ALT (degrees north, degrees east, metres); default:
    /// the weather file's site.
    #[arg(long, value_name = "LAT,LON,ALT", allow_hyphen_values = true)]
    pub site: Option<String>,
    /// Back boundary, overriding the material's exposed area:
    /// insulated | exposed | ground | building.
    #[arg(long, value_name = "KIND")]
    pub back: Option<String>,
    /// Repeat the first day up to N times before the run (spin-up).
    #[arg(long, value_name = "N", default_value_t = Spinup::default().max_cycles)]
    pub spinup_days: u32,
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
    let site = args.site.as_deref().map(parse_site).transpose()?;
    let material = find_material(&args.material, args.materials.as_deref()).for_flags(FLAGS)?;
    let mut props = SlabProperties::from_material(&material)?;
    if let Some(kind) = &args.back {
        props = props.with_back(parse_back(kind)?);
    }
    let spec = FacetSpec {
        tilt_deg: args.tilt,
        azimuth_deg: args.azimuth,
        shape_factor: args.shape_factor,
    };

    let mut opts = LoadOptions::default();
    if let Some(s) = site {
        opts = opts.with_site(s);
    }
    if let Some(s) = &args.start {
        opts = opts.with_start(parse_time("--start", s)?);
    }
    opts = opts.with_typical_year(chrono::Datelike::year(&time));
    if let Some(y) = args.year {
        opts = opts.with_year(y);
    }
    let history = weather::load_with(&args.weather, &opts)?;
    let site = site.or(history.site().copied()).ok_or_else(|| {
        anyhow::anyhow!(
            "{}: the weather file names no site; give one with --site LAT,LON,ALT",
            args.weather.display()
        )
    })?;
    let records = facet::records_until(&history, time)
        .with_context(|| format!("{}: --time", args.weather.display()))?;
    let options = SolveOptions {
        spinup: Spinup {
            max_cycles: args.spinup_days,
            ..Spinup::default()
        },
        ..SolveOptions::default()
    };
    let (sol, shape_factor) =
        facet::solve_free_facet(&props, &records, &site, &spec, &options).for_flags(FLAGS)?;

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
            material.name, props.back, args.tilt, args.azimuth
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

fn parse_back(kind: &str) -> anyhow::Result<BackBoundary> {
    Ok(match kind {
        "insulated" => BackBoundary::Insulated,
        "exposed" => BackBoundary::BOTH_FACES,
        "ground" => BackBoundary::GROUND,
        "building" => BackBoundary::BUILDING,
        _ => anyhow::bail!("--back: `{kind}` is not one of insulated, exposed, ground, building"),
    })
}
