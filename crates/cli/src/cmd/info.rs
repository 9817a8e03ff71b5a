//! `glint info` (not implemented yet).

/// Arguments of `glint info`.
#[derive(clap::Args)]
pub struct Args {}

/// Runs `glint info`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("'glint info' is not implemented yet")
}
