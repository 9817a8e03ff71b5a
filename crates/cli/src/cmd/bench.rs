//! `glint bench` (not implemented yet).

/// Subcommands of `glint bench`.
#[derive(clap::Subcommand)]
pub enum Command {
    /// Placeholder.
    Todo,
}

/// Runs `glint bench`.
pub fn run(_command: Command) -> anyhow::Result<()> {
    anyhow::bail!("'glint bench' is not implemented yet")
}
