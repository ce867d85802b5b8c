//! `slope-echo`: prints slope estimates.

use clap::Parser;
use slope_tools::cli::stop_on_signals;
use slope_tools::echo::{run, EchoArgs};

fn main() -> anyhow::Result<()> {
    let args = EchoArgs::parse();
    args.common.init_logging();
    let stop = stop_on_signals()?;
    run(&args, &stop)?;
    Ok(())
}
