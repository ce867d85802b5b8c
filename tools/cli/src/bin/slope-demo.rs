//! `slope-demo`: replay -> estimator -> this process, on a bundled recording.

use std::process::ExitCode;

use clap::Parser;
use slope_tools::cli::{exit_status, stop_on_signals};
use slope_tools::demo::{run, DemoArgs};

fn main() -> ExitCode {
    let args = DemoArgs::parse();
    args.common.init_logging();
    exit_status(stop_on_signals().and_then(|stop| run(&args, &stop).map(drop)))
}
