//! `slope-capture`: the Kinect v2 daemon (needs the `kinect2` feature).

use std::process::ExitCode;

use clap::Parser;
use slope_tools::capture::{run, CaptureArgs};
use slope_tools::cli::{exit_status, stop_on_signals};

fn main() -> ExitCode {
    let args = CaptureArgs::parse();
    args.common.init_logging();
    exit_status(stop_on_signals().and_then(|stop| run(&args, &stop).map(drop)))
}
