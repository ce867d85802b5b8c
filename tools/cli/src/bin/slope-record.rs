//! `slope-record OUT_DIR`: records the cloud topic (or the Kinect v2) into a
//! recording that `slope-replay` can play.

use clap::Parser;
use slope_tools::cli::stop_on_signals;
use slope_tools::record::{run, RecordArgs};

fn main() -> anyhow::Result<()> {
    let args = RecordArgs::parse();
    args.common.init_logging();
    let stop = stop_on_signals()?;
    run(&args, &stop)?;
    Ok(())
}
