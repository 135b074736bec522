//! Command-line interface: clap definitions and dispatch. Each subcommand
//! lives in its own file and turns its arguments into library calls.
//!
//! Owns everything about the command line the library must not know:
//! argument parsing (clap), the progress bar (indicatif, [`progress`]),
//! time lists, durations and tiles ([`args`]), the flag names in error
//! messages ([`args::FlagContext`]), and what is printed, benchmark tables
//! included. Goes through the library's front (`irsig::Session`,
//! `irsig::analysis`); commands that view one module (`sun`, `weather`,
//! `radiance`, `info`, `scene`) call that module.

use clap::{Parser, Subcommand};

/// `println!` that returns the write error instead of panicking, so that a
/// closed stdout (`irsig … | head`) ends the command quietly (`main` treats
/// a broken pipe as success).
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)?
    }};
}

mod args;
mod atmosphere;
mod bench;
mod calibrate;
mod compare;
mod diurnal;
mod import;
mod info;
mod merge;
mod progress;
mod radiance;
mod render;
mod scene;
mod sensitivity;
mod sun;
mod thermal;
mod thermal_scene;
mod weather;

/// irsig — physics-based thermal-infrared synthetic image generator.
///
/// Models the whole imaging chain the way DIRSIG does: scene geometry and
/// materials, weather history and sun, ray-traced solar history and shape
/// factors, a THERM-style 1-D thermal model per facet, the radiometric "big
/// equation" through an atmosphere, and a frame camera or airborne line
/// scanner. Internal units are SI.
#[derive(Debug, Parser)]
#[command(name = "irsig", version = concat!(env!("CARGO_PKG_VERSION"), " (Embree ", env!("IRSIG_EMBREE_VERSION"), ")"), propagate_version = true)]
pub struct Cli {
    /// Worker threads (default: all cores).
    #[arg(long, global = true, value_name = "N")]
    pub threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render a scene to EXR, ENVI and PNG images.
    Render(render::Args),
    /// Print statistics of the layers of an image file.
    Info(info::Args),
    /// Benchmarks: ray-tracing backends, the render pipeline.
    Bench(bench::Args),
    /// Check a scene file and print a summary.
    Scene(scene::Args),
    /// Read a weather file and print its records in SI units.
    Weather(weather::Args),
    /// Solar position (NREL SPA) for a place and time.
    Sun(sun::Args),
    /// Solve the thermal model for one free-standing facet.
    Thermal(thermal::Args),
    /// Every facet's state (rays and thermal passes) into a state folder
    /// for `render --state`, in one process or split across many.
    ThermalScene(thermal_scene::Args),
    /// Planck band radiance and its inverse (brightness temperature).
    Radiance(radiance::Args),
    /// Atmospheric transmittance and path (or sky) radiance of one path.
    Atmosphere(atmosphere::Args),
    /// Compare a synthetic image with truth imagery or point measurements.
    Compare(compare::Args),
    /// Sensitivity of temperatures and radiances to input parameters.
    Sensitivity(sensitivity::Args),
    /// Fit input parameters to truth measurements.
    Calibrate(calibrate::Args),
    /// Target/background contrast through the day; thermal crossover times.
    Diurnal(diurnal::Args),
    /// Merge tiles rendered with `render --tile K/N` into one image set.
    Merge(merge::Args),
    /// Import a scene from another tool (DIRSIG) as an irsig scene file.
    Import(import::Args),
}

/// Parse the command line and run the chosen subcommand.
pub fn run() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = cli.threads {
        anyhow::ensure!(n > 0, "--threads must be at least 1");
        pool = pool.num_threads(n);
    }
    pool.build_global()?;
    match cli.command {
        Command::Render(a) => render::run(a),
        Command::Info(a) => info::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Scene(a) => scene::run(a),
        Command::Weather(a) => weather::run(a),
        Command::Sun(a) => sun::run(a),
        Command::Thermal(a) => thermal::run(a),
        Command::ThermalScene(a) => thermal_scene::run(a),
        Command::Radiance(a) => radiance::run(a),
        Command::Atmosphere(a) => atmosphere::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Sensitivity(a) => sensitivity::run(a),
        Command::Calibrate(a) => calibrate::run(a),
        Command::Diurnal(a) => diurnal::run(a),
        Command::Merge(a) => merge::run(a),
        Command::Import(a) => import::run(a),
    }
}
