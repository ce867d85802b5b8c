//! `slope-demo`: replay -> estimator -> this process, on a bundled recording.

use clap::Parser;
use slope_tools::cli::stop_on_signals;
use slope_tools::demo::{run, DemoArgs};

fn main() -> anyhow::Result<()> {
    let args = DemoArgs::parse();
    args.common.init_logging();
    let stop = stop_on_signals()?;
    run(&args, &stop)?;
    Ok(())
}
