//! `irsig calibrate` (being written).

/// Arguments of `irsig calibrate`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig calibrate`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig calibrate` is not available in this build yet")
}
