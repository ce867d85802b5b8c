//! `slope-echo`: prints slope estimates.

use std::process::ExitCode;

use clap::Parser;
use slope_tools::cli::{exit_status, stop_on_signals};
use slope_tools::echo::{run, EchoArgs};

fn main() -> ExitCode {
    let args = EchoArgs::parse();
    args.common.init_logging();
    exit_status(stop_on_signals().and_then(|stop| run(&args, &stop).map(drop)))
}
