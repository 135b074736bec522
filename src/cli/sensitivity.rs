//! `irsig sensitivity` (being written).

/// Arguments of `irsig sensitivity`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig sensitivity`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig sensitivity` is not available in this build yet")
}
