//! `slope-estimator`: clouds in, slope estimates out.

use std::process::ExitCode;

use clap::Parser;
use slope_tools::cli::{exit_status, stop_on_signals};
use slope_tools::estimator::{run, EstimatorArgs};

fn main() -> ExitCode {
    let args = EstimatorArgs::parse();
    args.common.init_logging();
    exit_status(stop_on_signals().and_then(|stop| run(&args, &stop).map(drop)))
}
