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
    /// Also write each georeferenced image as a GeoTIFF `NAME.tif` (as the
    /// scene's `render.geotiff: true`).
    #[arg(long)]
    pub geotiff: bool,
    /// Print nothing on success.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Run `irsig merge`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let stems = irsig::render::tile::merge_tiles_with(&args.parts, &args.out, args.geotiff)
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
