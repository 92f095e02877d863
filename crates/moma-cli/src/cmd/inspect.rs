//! PLACEHOLDER: replaced by the work that implements this subcommand.

/// Arguments (to be defined).
#[derive(clap::Args)]
pub struct Args {}

/// Runs the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("this subcommand is not implemented yet")
}
