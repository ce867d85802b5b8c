//! `slope-record OUT_DIR`: records the cloud topic (or the Kinect v2) into a
//! recording that `slope-replay` can play.

use std::process::ExitCode;

use slope_tools::cli::{exit_status, stop_on_signals, OutputArgs};
use slope_tools::record::{run, RecordArgs};

fn main() -> ExitCode {
    let args = RecordArgs::parse_checked();
    args.common.init_logging();
    exit_status(stop_on_signals().and_then(|stop| run(&args, &stop).map(drop)))
}
