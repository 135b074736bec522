//! `irsig compare` (being written).

/// Arguments of `irsig compare`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig compare`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig compare` is not available in this build yet")
}
