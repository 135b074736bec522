//! `irsig thermal-scene SCENE.json --state DIR`: every facet's state (the
//! per-facet rays and the thermal passes) into a state folder that
//! `irsig render --state DIR` reads, in one process or split across many
//! (`--pass 1|2 --shard K/N`; see `irsig::render::state`).

use std::path::PathBuf;

use anyhow::Context;
use irsig::render::state::{self, Outcome};
use irsig::{Backend, Session};

use super::args::{FlagContext, parse_k_of_n, parse_times};
use super::progress::Bar;

/// Arguments of `irsig thermal-scene`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene file (JSON).
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,
    /// State folder (created if needed): `manifest.json`, pass 1's
    /// `rays-K-of-N.arrow` and the facet states `state-K-of-N.arrow`
    /// (Arrow IPC / Feather v2).
    #[arg(long, value_name = "DIR")]
    pub state: PathBuf,
    /// Image times: a comma-separated list of RFC 3339 times, or
    /// START/END/STEP. Default: the scene's time. The render must ask for
    /// the same times.
    #[arg(long, value_name = "LIST|START/END/STEP")]
    pub times: Option<String>,
    /// Run one pass of the split stage: 1 traces the rays of the facets of
    /// --shard; 2 reads every pass-1 shard, runs the thermal passes and
    /// writes the facet states of --shard. Without it: everything in this
    /// process.
    #[arg(long, value_name = "1|2", value_parser = clap::value_parser!(u8).range(1..=2))]
    pub pass: Option<u8>,
    /// With --pass: this process's share, the K-th of N runs of the pass
    /// (whole batches of facets) [default: 1/1]. A shard already complete
    /// is skipped.
    #[arg(long, value_name = "K/N", requires = "pass")]
    pub shard: Option<String>,
    /// Ray-tracing backend: embree, embree-single or obvhs (the render must
    /// use the same).
    #[arg(long, default_value = "embree", value_name = "NAME")]
    pub backend: Backend,
    /// Sample points per facet edge (as `irsig render --facet-samples`).
    #[arg(long, value_name = "N")]
    pub facet_samples: Option<u32>,
    /// Hemisphere sampling of the sky view (as `irsig render
    /// --sky-sampling`).
    #[arg(long, value_name = "SPEC")]
    pub sky_sampling: Option<irsig::exposure::SkySampling>,
    /// No progress bar and no summary.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Run `irsig thermal-scene`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let times = match &args.times {
        Some(t) => parse_times(t)?,
        None => Vec::new(),
    };
    let shard = match &args.shard {
        Some(s) => parse_k_of_n("--shard", s)?,
        None => (1, 1),
    };
    if let Some(n) = args.facet_samples {
        anyhow::ensure!(
            (1..=16).contains(&n),
            "--facet-samples: {n} is out of range (expected 1 to 16)"
        );
    }
    let bar = (!args.quiet).then(Bar::on_terminal);
    let progress: &dyn irsig::Progress = match &bar {
        Some(b) => b.as_ref(),
        None => &irsig::progress::NoProgress,
    };
    let t0 = std::time::Instant::now();
    let mut session = Session::open_observed(&args.scene, args.backend, progress)
        .with_context(|| format!("loading {}", args.scene.display()))?;
    if !args.quiet {
        for w in &session.scene.warnings {
            eprintln!("warning: {w}");
        }
    }
    if let Some(n) = args.facet_samples {
        session.config.facet_samples = n;
    }
    if let Some(s) = args.sky_sampling {
        session.config.sky_sampling = s;
    }
    let outcome = match args.pass {
        None => state::run_all(&mut session, &args.state, &times, progress),
        Some(1) => state::run_pass1(&mut session, &args.state, &times, shard, progress),
        Some(_) => state::run_pass2(&mut session, &args.state, &times, shard, progress),
    }
    .for_flags(&[
        ("shard", "--shard"),
        ("state", "--state"),
        ("times", "--times"),
    ])
    .with_context(|| format!("thermal-scene {}", args.scene.display()))?;
    for w in &session.warnings {
        eprintln!("warning: {w}");
    }
    if !args.quiet {
        match outcome {
            Outcome::Wrote(p) => eprintln!(
                "wrote {} ({} facets, {:.2} s)",
                p.display(),
                session.scene.geometry.facet_count(),
                t0.elapsed().as_secs_f64()
            ),
            Outcome::Skipped(p) => eprintln!("{} is already complete", p.display()),
        }
    }
    Ok(())
}
