//! `slope-estimator`: clouds in, slope estimates out.

use std::process::ExitCode;

use slope_tools::cli::{daemon_exit_status, stop_on_signals};
use slope_tools::estimator::{run, EstimatorArgs};
use slope_tools::service_manager::parse_daemon_args;

fn main() -> ExitCode {
    // A usage error is also the unit's status line (it is not restarted).
    let args: EstimatorArgs = parse_daemon_args();
    args.common.init_logging();
    // A config-file error exits with EX_CONFIG (78).
    daemon_exit_status(stop_on_signals().and_then(|stop| run(&args, &stop).map(drop)))
}
