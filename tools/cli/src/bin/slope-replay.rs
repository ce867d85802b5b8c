//! `slope-replay RECORDING`: publishes a recording in place of the camera.

use std::process::ExitCode;

use clap::Parser;
use slope_tools::cli::{daemon_exit_status, stop_on_signals};
use slope_tools::replay::{run, ReplayArgs};

fn main() -> ExitCode {
    let args = ReplayArgs::parse();
    args.common.init_logging();
    // A config-file error exits with EX_CONFIG (78).
    daemon_exit_status(stop_on_signals().and_then(|stop| run(&args, &stop).map(drop)))
}
