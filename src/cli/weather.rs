//! `irsig weather` (being written).

/// Arguments of `irsig weather`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig weather`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig weather` is not available in this build yet")
}
