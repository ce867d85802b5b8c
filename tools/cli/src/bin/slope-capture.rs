//! `slope-capture`: the Kinect v2 daemon (needs the `kinect2` feature).

use std::process::ExitCode;

use slope_tools::capture::{config_exit_code, run, CaptureArgs};
use slope_tools::cli::{exit_status, stop_on_signals};
use slope_tools::service_manager::parse_daemon_args;

fn main() -> ExitCode {
    // A usage error is also the unit's status line (it is not restarted).
    let args: CaptureArgs = parse_daemon_args();
    args.common.init_logging();
    let result = stop_on_signals().and_then(|stop| run(&args, &stop).map(drop));
    // Failures that a restart cannot cure exit with EX_CONFIG (78).
    let config = result.as_ref().err().and_then(config_exit_code);
    let status = exit_status(result);
    config.map_or(status, ExitCode::from)
}
