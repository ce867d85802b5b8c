//! `slope-convert`: a recording as an MCAP file.

use std::process::ExitCode;

use slope_tools::cli::{exit_status, stop_on_signals, OutputArgs};
use slope_tools::convert::{run, ConvertArgs};

fn main() -> ExitCode {
    let args = ConvertArgs::parse_checked();
    args.init_logging();
    exit_status(stop_on_signals().and_then(|stop| run(&args, &stop).map(drop)))
}
