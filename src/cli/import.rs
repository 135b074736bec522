//! `irsig import dirsig`: turn a DIRSIG scene or simulation into an irsig scene file
//! (with its materials beside it), printing what could not be mapped.

use std::path::PathBuf;

use anyhow::Context as _;
use irsig::scene::dirsig::{ImportOptions, import};

/// Arguments of `irsig import`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: ImportCommand,
}

#[derive(Debug, clap::Subcommand)]
enum ImportCommand {
    /// Import a DIRSIG scene (`.scene`) or simulation (`.jsim`, `.sim`): writes the
    /// irsig scene, its materials (`STEM.materials.json`) and any converted geometry
    /// (`STEM.geometry/`), and prints a `warning:` for everything not mapped.
    Dirsig {
        /// The DIRSIG `.scene`, `.jsim` or `.sim` file.
        file: PathBuf,
        /// The irsig scene file to write (JSON).
        #[arg(short, long, value_name = "FILE")]
        out: PathBuf,
        /// A folder to look in for files not found where the DIRSIG files say
        /// (absolute paths from another machine, a scene split over folders); repeat
        /// for more.
        #[arg(long, value_name = "DIR")]
        search: Vec<PathBuf>,
        /// The image time (RFC 3339), replacing the `.tasks` time (a bare `.scene` has
        /// none).
        #[arg(long, value_name = "TIME")]
        time: Option<String>,
    },
}

/// Run `irsig import`.
pub fn run(args: Args) -> anyhow::Result<()> {
    match args.command {
        ImportCommand::Dirsig {
            file,
            out,
            search,
            time,
        } => {
            for d in &search {
                anyhow::ensure!(d.is_dir(), "--search: {} is not a folder", d.display());
            }
            if let Some(t) = &time {
                irsig::sun::parse_time(t).map_err(|e| anyhow::anyhow!("--time: {e}"))?;
            }
            let opts = ImportOptions {
                search_dirs: search,
                time,
            };
            let imported = import(&file, &out, &opts)
                .with_context(|| format!("importing {}", file.display()))?;
            for w in &imported.warnings {
                eprintln!("warning: {w}");
            }
            let written = imported.write(&out)?;
            let s = &imported.scene;
            let instances: usize = s
                .objects
                .iter()
                .map(|o| o.instances.as_ref().map_or(1, Vec::len))
                .sum();
            outln!(
                "{}: {} object(s), {} instance(s), {} material(s), {} sensor(s), time {}",
                out.display(),
                s.objects.len(),
                instances,
                imported.materials.materials.len(),
                s.sensors.len(),
                s.time
            );
            outln!(
                "wrote {} file(s); {} warning(s)",
                written.len(),
                imported.warnings.len()
            );
            Ok(())
        }
    }
}
