//! `slope-capture`: the Kinect v2 daemon (needs the `kinect2` feature).

use clap::Parser;
use slope_tools::capture::{run, CaptureArgs};
use slope_tools::cli::stop_on_signals;

fn main() -> anyhow::Result<()> {
    let args = CaptureArgs::parse();
    args.common.init_logging();
    let stop = stop_on_signals()?;
    run(&args, &stop)?;
    Ok(())
}
