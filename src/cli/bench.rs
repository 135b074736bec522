//! `irsig bench` (being written).

/// Arguments of `irsig bench`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig bench`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig bench` is not available in this build yet")
}
