//! `irsig thermal` (being written).

/// Arguments of `irsig thermal`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig thermal`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig thermal` is not available in this build yet")
}
