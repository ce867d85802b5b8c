//! `slope-ros2`: the estimate, the surfaces, rviz markers and
//! `/diagnostics` as a native ROS 2 node.

use std::process::ExitCode;

use clap::CommandFactory;
use slope_ros2::node::{run, Ros2Args};
use slope_ros2::ros_args;
use slope_tools::cli::{daemon_exit_status, stop_on_signals};
use slope_tools::service_manager::{parse_daemon_args_from, usage_exit};

fn main() -> ExitCode {
    // ROS 2's `--ros-args -p frame_id:=... -r __ns:=...` become our flags.
    // A usage error is also the unit's status line (it is not restarted).
    let argv = ros_args::translate(std::env::args_os()).unwrap_or_else(|message| {
        usage_exit(Ros2Args::command().error(clap::error::ErrorKind::ValueValidation, message))
    });
    let args: Ros2Args = parse_daemon_args_from(argv);
    // RustDDS and ros2-client log through `log`: off unless -v (errors) or -vv.
    args.common
        .log
        .init_logging_quieting(&["rustdds", "ros2_client"]);
    // A config-file error exits with EX_CONFIG (78).
    daemon_exit_status(stop_on_signals().and_then(|stop| run(&args, &stop).map(drop)))
}
