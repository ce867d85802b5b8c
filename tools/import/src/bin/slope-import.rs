//! `slope-import`: a ROS 1 or ROS 2 bag of a depth camera as a recording.

use std::process::ExitCode;

use clap::Parser;
use slope_import::{run, ImportArgs};
use slope_tools::cli::{exit_status, stop_on_signals};

fn main() -> ExitCode {
    let args = ImportArgs::parse();
    args.log.init_logging();
    exit_status(stop_on_signals().and_then(|stop| run(&args, &stop)))
}
