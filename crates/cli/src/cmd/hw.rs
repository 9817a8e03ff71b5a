//! `glint hw` (not implemented yet).

/// Subcommands of `glint hw`.
#[derive(clap::Subcommand)]
pub enum Command {
    /// Placeholder.
    Todo,
}

/// Runs `glint hw`.
pub fn run(_command: Command) -> anyhow::Result<()> {
    anyhow::bail!("'glint hw' is not implemented yet")
}
