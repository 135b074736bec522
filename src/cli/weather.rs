//! `irsig weather`: read weather files and print their records in SI units;
//! generate the bundled synthetic history.

use std::io::Write;
use std::path::PathBuf;

use irsig::sun::Site;
use irsig::weather::{self, LoadOptions, WeatherHistory};

/// Arguments of `irsig weather`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Sub,
}

#[derive(Debug, clap::Subcommand)]
enum Sub {
    /// Print every record (RFC 3339 time, all fields in SI, filled fields included).
    Show(ShowArgs),
    /// Write the synthetic clear-sky history of the bundled town scene
    /// (scenes/town/weather.csv) or a variant of it.
    Synth(SynthArgs),
}

/// Arguments of `irsig weather show`.
#[derive(Debug, clap::Args)]
struct ShowArgs {
    /// Weather file: irsig CSV/JSON, EPW, TMY3 CSV or DIRSIG .wth.
    file: PathBuf,
    /// Print JSON: {"records": [{"time", "air_temperature_k", …}]}.
    #[arg(long)]
    json: bool,
    /// Local date and time of hour 0 of a .wth file (RFC 3339, e.g. 2025-06-20T00:00:00-04:00).
    #[arg(long, value_name = "RFC3339")]
    start: Option<String>,
    /// Site latitude, degrees north (for files without a site, where an irradiance split is needed).
    #[arg(
        long,
        value_name = "DEG",
        allow_negative_numbers = true,
        requires = "lon"
    )]
    lat: Option<f64>,
    /// Site longitude, degrees east.
    #[arg(
        long,
        value_name = "DEG",
        allow_negative_numbers = true,
        requires = "lat"
    )]
    lon: Option<f64>,
    /// Site altitude, metres.
    #[arg(
        long,
        value_name = "M",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    alt: f64,
    /// Replace the year of EPW/TMY3 rows (typical-year files mix years).
    #[arg(long)]
    year: Option<i32>,
}

/// Arguments of `irsig weather synth`.
#[derive(Debug, clap::Args)]
struct SynthArgs {
    /// Output CSV (written atomically).
    #[arg(long, short, value_name = "FILE")]
    out: PathBuf,
}

/// Run `irsig weather`.
pub fn run(args: Args) -> anyhow::Result<()> {
    match args.command {
        Sub::Show(a) => show(a),
        Sub::Synth(a) => synth(a),
    }
}

fn show(a: ShowArgs) -> anyhow::Result<()> {
    let mut opts = LoadOptions::default();
    if let Some(s) = &a.start {
        opts = opts.with_start(super::args::parse_time("--start", s)?);
    }
    if let (Some(lat), Some(lon)) = (a.lat, a.lon) {
        opts = opts.with_site(Site::new(lat, lon, a.alt)?);
    }
    if let Some(y) = a.year {
        opts = opts.with_year(y);
    }
    let h = weather::load_with(&a.file, &opts).map_err(|e| {
        let hint = e.to_string().contains("typical-year") && a.year.is_none();
        let e = anyhow::Error::from(e);
        if hint {
            e.context("give the year to apply with --year YEAR")
        } else {
            e
        }
    })?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    if a.json {
        serde_json::to_writer(&mut out, &show_json(&h))?;
        writeln!(out)?;
    } else {
        print_text(&h, &mut out)?;
    }
    out.flush()?;
    Ok(())
}

/// The `--json` document: exactly the fields listed in issue 3.
fn show_json(h: &WeatherHistory) -> serde_json::Value {
    let records: Vec<_> = h
        .records()
        .iter()
        .map(|r| {
            serde_json::json!({
                "time": r.time.to_rfc3339(),
                "air_temperature_k": r.air_temperature_k,
                "dew_point_k": r.dew_point_k,
                "relative_humidity": r.relative_humidity,
                "pressure_pa": r.pressure_pa,
                "wind_speed_m_s": r.wind_speed_m_s,
                "direct_normal_w_m2": r.direct_normal_w_m2,
                "diffuse_horizontal_w_m2": r.diffuse_horizontal_w_m2,
                "global_horizontal_w_m2": r.global_horizontal_w_m2,
                "sky_longwave_w_m2": r.sky_longwave_w_m2,
                "opaque_sky_cover": r.opaque_sky_cover,
            })
        })
        .collect();
    serde_json::json!({ "records": records })
}

fn print_text(h: &WeatherHistory, out: &mut impl Write) -> std::io::Result<()> {
    if let Some(s) = h.site() {
        writeln!(
            out,
            "# site: latitude {}°, longitude {}°, altitude {} m",
            s.latitude_deg, s.longitude_deg, s.altitude_m
        )?;
    }
    writeln!(
        out,
        "# {} records, {} to {}; values marked * were filled, not read",
        h.records().len(),
        h.start().to_rfc3339(),
        h.end().to_rfc3339()
    )?;
    writeln!(
        out,
        "{:<25} {:>9} {:>9} {:>7} {:>9} {:>6} {:>6} {:>8} {:>8} {:>8} {:>8} {:>6} {:>6}",
        "time",
        "T_air_K",
        "T_dew_K",
        "RH",
        "p_Pa",
        "wind",
        "dir",
        "DNI",
        "DHI",
        "GHI",
        "sky_LW",
        "cov_t",
        "cov_o"
    )?;
    for (i, r) in h.records().iter().enumerate() {
        let f = h.filled(i);
        let m = |name: &str| if f.contains(&name) { "*" } else { " " };
        writeln!(
            out,
            "{:<25} {:>8.2}{} {:>8.2}{} {:>6.3}{} {:>8.0}{} {:>5.2}{} {:>5.0}{} {:>7.1}{} {:>7.1}{} {:>7.1}{} {:>7.1}{} {:>5.2}{} {:>5.2}{}",
            r.time.to_rfc3339(),
            r.air_temperature_k,
            m("air_temperature_k"),
            r.dew_point_k,
            m("dew_point_k"),
            r.relative_humidity,
            m("relative_humidity"),
            r.pressure_pa,
            m("pressure_pa"),
            r.wind_speed_m_s,
            m("wind_speed_m_s"),
            r.wind_direction_deg,
            m("wind_direction_deg"),
            r.direct_normal_w_m2,
            m("direct_normal_w_m2"),
            r.diffuse_horizontal_w_m2,
            m("diffuse_horizontal_w_m2"),
            r.global_horizontal_w_m2,
            m("global_horizontal_w_m2"),
            r.sky_longwave_w_m2,
            m("sky_longwave_w_m2"),
            r.total_sky_cover,
            m("total_sky_cover"),
            r.opaque_sky_cover,
            m("opaque_sky_cover"),
        )?;
    }
    Ok(())
}

fn synth(a: SynthArgs) -> anyhow::Result<()> {
    let (history, comments) = weather::synth::town_history()?;
    let mut buf = Vec::new();
    let comment_refs: Vec<&str> = comments.iter().map(String::as_str).collect();
    weather::write_csv(&history, &comment_refs, &mut buf)?;
    irsig::output::write_atomic(&a.out, |w| {
        w.write_all(&buf)
            .map_err(|e| irsig::error::Error::io(&a.out, e))
    })?;
    eprintln!(
        "wrote {} ({} records, {} to {})",
        a.out.display(),
        history.records().len(),
        history.start().to_rfc3339(),
        history.end().to_rfc3339()
    );
    Ok(())
}
