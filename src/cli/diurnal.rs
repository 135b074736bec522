//! `irsig diurnal` (being written).

/// Arguments of `irsig diurnal`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig diurnal`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig diurnal` is not available in this build yet")
}
