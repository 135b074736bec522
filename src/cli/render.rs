//! `irsig render SCENE.json -o DIR`: the whole imaging chain to image files.

use std::path::PathBuf;

use anyhow::Context;
use irsig::{Backend, RunOptions, Session};

use super::args::{FlagContext, parse_tile, parse_times};
use super::progress::Bar;

/// Arguments of `irsig render`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene file (JSON), or a DIRSIG `.scene`/`.jsim`/`.sim` (imported first).
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,
    /// Output folder (created if needed): per sensor `NAME.exr`, `NAME.img` +
    /// `NAME.hdr` (ENVI) and `NAME.png`, or `NAME.tileK-of-N.exr` with --tile.
    #[arg(short, long, value_name = "DIR")]
    pub out: PathBuf,
    /// Ray-tracing backend: embree, embree-single or obvhs.
    #[arg(long, default_value = "embree", value_name = "NAME")]
    pub backend: Backend,
    /// Image times: a comma-separated list of RFC 3339 times, or
    /// START/END/STEP (STEP like 30s, 15min, 1h). Default: the scene's time.
    /// With several times, files are named `NAME_YYYYMMDDTHHMMSS.*`.
    #[arg(long, value_name = "LIST|START/END/STEP")]
    pub times: Option<String>,
    /// Render only the K-th of N bands of rows into `NAME.tileK-of-N.exr`
    /// (skipped if that tile is already complete); assemble with `irsig merge`.
    #[arg(long, value_name = "K/N")]
    pub tile: Option<String>,
    /// Noise seed (overrides the sensors' `seed`).
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// Render only this sensor (repeatable). Default: all.
    #[arg(long = "sensor", value_name = "NAME")]
    pub sensors: Vec<String>,
    /// Sample points per facet edge for the per-facet sun and sky rays (n²
    /// points per facet, 1 to 16); overrides the scene's
    /// `render.facet_samples` [default: the scene's, else 1].
    #[arg(long, value_name = "N")]
    pub facet_samples: Option<u32>,
    /// Hemisphere sampling of each facet's sky view: `stratified:N` (N
    /// rays per face), `dirsig` (DIRSIG's 15°×30° grid, 72 rays) or
    /// `grid:DZxDA` (degrees); overrides the scene's `render.sky_sampling`
    /// [default: the scene's, else stratified:64].
    #[arg(long, value_name = "SPEC")]
    pub sky_sampling: Option<irsig::exposure::SkySampling>,
    /// Also write each georeferenced image (a nadir-looking one, see
    /// docs/georeferencing.md) as a GeoTIFF `STEM.tif` with every layer;
    /// the same as the scene's `render.geotiff: true`.
    #[arg(long)]
    pub geotiff: bool,
    /// Read every facet's state from this folder (made by `irsig
    /// thermal-scene --state DIR` for this scene, these times and
    /// settings) instead of solving it; the images are the same bit for bit.
    #[arg(long, value_name = "DIR")]
    pub state: Option<PathBuf>,
    /// Per-hit temperatures: `on` (a hit on a facet whose exposure is not
    /// uniform, or that is large against the pixel footprint, gets the
    /// temperature of its own solar history) or `off` (one temperature per
    /// facet); overrides the scene's `render.per_hit` [default: the
    /// scene's, else on].
    #[arg(long, value_name = "on|off", value_parser = parse_on_off)]
    pub per_hit: Option<bool>,
    /// No progress bar and no summary.
    #[arg(short, long)]
    pub quiet: bool,
    /// For a DIRSIG scene or simulation: a folder to look in for files not found where
    /// the DIRSIG files say (see `irsig import dirsig`); repeat for more.
    #[arg(long, value_name = "DIR")]
    pub search: Vec<std::path::PathBuf>,
}

/// `on`/`off` (also `true`/`false`).
fn parse_on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" | "true" => Ok(true),
        "off" | "false" => Ok(false),
        _ => Err(format!("`{s}`: expected on or off")),
    }
}

/// Run `irsig render`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let times = match &args.times {
        Some(t) => parse_times(t)?,
        None => Vec::new(),
    };
    let tile = args.tile.as_deref().map(parse_tile).transpose()?;
    if let Some(n) = args.facet_samples {
        anyhow::ensure!(
            (1..=16).contains(&n),
            "--facet-samples: {n} is out of range (expected 1 to 16)"
        );
    }
    let t0 = std::time::Instant::now();
    let bar = (!args.quiet).then(Bar::on_terminal);
    let progress: &dyn irsig::Progress = match &bar {
        Some(b) => b.as_ref(),
        None => &irsig::progress::NoProgress,
    };
    anyhow::ensure!(
        args.search.is_empty() || irsig::scene::dirsig::is_dirsig_scene(&args.scene),
        "--search: {} is not a DIRSIG scene or simulation (.scene, .jsim, .sim)",
        args.scene.display()
    );
    let scene = if args.search.is_empty() {
        Session::load_scene_observed(&args.scene, progress)
    } else {
        let opts = irsig::scene::dirsig::ImportOptions {
            search_dirs: args.search.clone(),
            time: None,
        };
        irsig::scene::Scene::load_dirsig(&args.scene, &opts)
    }
    .with_context(|| format!("loading {}", args.scene.display()))?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    // Before anything is allocated: an image that cannot fit in memory.
    if let Some(e) = irsig::scene::image_memory_errors(
        &scene,
        irsig::render::TRUTH_LAYERS.len(),
        tile.map_or(1, |(_, n)| n),
        irsig::scene::available_memory_bytes(),
    )
    .into_iter()
    .next()
    {
        return Err(anyhow::Error::new(e))
            .with_context(|| format!("loading {}", args.scene.display()));
    }
    let mut session = Session::from_scene_observed(scene, args.backend, t0, progress)
        .with_context(|| format!("loading {}", args.scene.display()))?;
    for w in irsig::render::checks::view_warnings(
        &session.scene,
        &session.sensors,
        session.tracer.as_ref(),
    ) {
        eprintln!("warning: {w}");
    }
    for w in irsig::render::session::visibility_warnings(&session, &times) {
        eprintln!("warning: {w}");
    }
    if let Some(n) = args.facet_samples {
        session.config.facet_samples = n;
    }
    if let Some(s) = args.sky_sampling {
        session.config.sky_sampling = s;
    }
    if args.geotiff {
        session.config.geotiff = true;
    }
    if let Some(p) = args.per_hit {
        session.config.per_hit = p;
    }
    if args.state.is_some() && session.config.per_hit {
        eprintln!(
            "warning: a state folder holds one temperature per facet: hits take their facet's \
             (as --per-hit off), which can differ from a render that solves"
        );
    }
    let options = RunOptions {
        backend: args.backend,
        times,
        tile,
        seed: args.seed,
        progress: bar.map(|b| b as _),
        sensors: args.sensors.clone(),
        state: args.state.clone(),
    };
    let stems = session
        .run(&args.out, &options)
        .for_flags(&[("sensor", "--sensor"), ("state", "--state")])
        .with_context(|| format!("rendering {}", args.scene.display()))?;
    for w in &session.warnings {
        eprintln!("warning: {w}");
    }
    if !args.quiet {
        let t = &session.timings;
        for s in &stems {
            match tile {
                Some((k, n)) => eprintln!(
                    "wrote {}",
                    args.out.join(format!("{s}.tile{k}-of-{n}.exr")).display()
                ),
                None => {
                    let tif = session.config.geotiff && args.out.join(format!("{s}.tif")).exists();
                    eprintln!(
                        "wrote {}",
                        args.out
                            .join(format!(
                                "{s}.{{exr,img,hdr,png{}}}",
                                if tif { ",tif" } else { "" }
                            ))
                            .display()
                    )
                }
            }
        }
        eprintln!(
            "{} facets, {} primary rays; time {:.2} s: load {:.2}, BVH {:.2}, rays+thermal {:.2}, \
             radiometry setup {:.2}, ray generation {:.2}, primary trace {:.2}, radiometry {:.2}, \
             secondary rays ({} hits) {:.2}, sensor {:.2}, output {:.2}",
            session.scene.geometry.facet_count(),
            t.primary_rays,
            t.total().as_secs_f64(),
            t.load.as_secs_f64(),
            t.bvh_build.as_secs_f64(),
            t.thermal.as_secs_f64(),
            t.radiometry_setup.as_secs_f64(),
            t.ray_generation.as_secs_f64(),
            t.primary_trace.as_secs_f64(),
            t.radiometry.as_secs_f64(),
            t.secondary_hits,
            t.secondary.as_secs_f64(),
            t.sensor.as_secs_f64(),
            t.output.as_secs_f64(),
        );
    }
    Ok(())
}
