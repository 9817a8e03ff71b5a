//! `glint render` (not implemented yet).

/// Arguments of `glint render`.
#[derive(clap::Args)]
pub struct Args {}

/// Runs `glint render`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("'glint render' is not implemented yet")
}
