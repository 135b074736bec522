//! `irsig merge` (being written).

/// Arguments of `irsig merge`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig merge`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig merge` is not available in this build yet")
}
