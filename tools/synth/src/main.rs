//! `slope-synth`: parse the command line, set up logging, call [`slope_synth::run`].

use std::process::ExitCode;

use clap::Parser;
use slope_synth::cli::{exit_code, init_logging, stop_on_signals};

fn main() -> ExitCode {
    let args = slope_synth::Args::parse();
    init_logging(args.log_level());
    exit_code(
        stop_on_signals()
            .and_then(|stop| slope_synth::run(&args, &stop))
            .map(|s| (s.dir, s.frames, s.frames_asked)),
    )
}
