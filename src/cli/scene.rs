//! `irsig scene` (being written).

/// Arguments of `irsig scene`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run `irsig scene`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`irsig scene` is not available in this build yet")
}
