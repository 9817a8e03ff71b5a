//! `glint analyze` (not implemented yet).

/// Arguments of `glint analyze`.
#[derive(clap::Args)]
pub struct Args {}

/// Runs `glint analyze`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("'glint analyze' is not implemented yet")
}
