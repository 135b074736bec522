//! `irsig merge`: assemble tiles rendered with `irsig render --tile K/N`.

use std::path::PathBuf;

use anyhow::Context;

/// Arguments of `irsig merge`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Tile files (`NAME.tileK-of-N.exr`), all tiles of one or more images.
    #[arg(required = true, value_name = "PARTS")]
    pub parts: Vec<PathBuf>,
    /// Output folder for the merged `NAME.exr`, `NAME.img`/`.hdr`, `NAME.png`.
    #[arg(short, long, value_name = "DIR")]
    pub out: PathBuf,
    /// Print nothing on success.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Run `irsig merge`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let stems = irsig::render::tile::merge_tiles(&args.parts, &args.out)
        .with_context(|| format!("merging {} tile file(s)", args.parts.len()))?;
    if !args.quiet {
        for s in stems {
            eprintln!(
                "merged {}",
                args.out.join(format!("{s}.{{exr,img,hdr,png}}")).display()
            );
        }
    }
    Ok(())
}
