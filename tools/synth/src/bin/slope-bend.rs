//! `slope-bend`: parse the command line, set up logging, call
//! [`slope_synth::bend::cli::run`].

use std::process::ExitCode;

use clap::Parser;
use slope_synth::cli::{exit_code, init_logging, stop_on_signals};

fn main() -> ExitCode {
    let args = slope_synth::bend::cli::BendArgs::parse();
    init_logging(args.log_level());
    exit_code(
        stop_on_signals()
            .and_then(|stop| slope_synth::bend::cli::run(&args, &stop))
            .map(|s| {
                tracing::info!(truth_deg = args.angle_deg, "the bent part's angle");
                (s.dir, s.frames as u64, s.frames_asked as u64)
            }),
    )
}
