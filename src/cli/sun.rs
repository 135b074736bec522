//! `irsig sun` (being written).

/// Arguments of `irsig sun`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig sun`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig sun` is not available in this build yet")
}
