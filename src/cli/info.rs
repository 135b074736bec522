//! `irsig info` (being written).

/// Arguments of `irsig info`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig info`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig info` is not available in this build yet")
}
