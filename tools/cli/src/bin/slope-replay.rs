//! `slope-replay RECORDING`: publishes a recording in place of the camera.

use clap::Parser;
use slope_tools::cli::stop_on_signals;
use slope_tools::replay::{run, ReplayArgs};

fn main() -> anyhow::Result<()> {
    let args = ReplayArgs::parse();
    args.common.init_logging();
    let stop = stop_on_signals()?;
    run(&args, &stop)?;
    Ok(())
}
