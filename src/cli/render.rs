//! `irsig render` (being written).

/// Arguments of `irsig render`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig render`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig render` is not available in this build yet")
}
