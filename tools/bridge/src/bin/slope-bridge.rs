//! `slope-bridge`: forwards estimates and health reports to Zenoh.

use std::process::ExitCode;

use clap::Parser;
use slope_bridge::bridge::{run, BridgeArgs};
use slope_tools::cli::{exit_status, stop_on_signals};

fn main() -> ExitCode {
    let args = BridgeArgs::parse();
    args.common.init_logging();
    exit_status(stop_on_signals().and_then(|stop| run(&args, &stop).map(drop)))
}
