//! `slope-synth`: parse the command line, set up logging, call [`slope_synth::run`].

use clap::Parser;
use tracing_subscriber::EnvFilter;

fn main() -> anyhow::Result<()> {
    let args = slope_synth::Args::parse();
    tracing_subscriber::fmt()
        .with_env_filter(
            EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("info")),
        )
        .with_writer(std::io::stderr)
        .init();
    let summary = slope_synth::run(&args)?;
    tracing::info!(
        dir = %summary.dir.display(),
        frames = summary.frames,
        "done"
    );
    Ok(())
}
