//! `irsig radiance` (being written).

/// Arguments of `irsig radiance`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig radiance`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig radiance` is not available in this build yet")
}
