//! `slope-eval`: the estimator run offline on recordings, against their
//! ground truth.

use std::process::ExitCode;

use clap::Parser;
use slope_tools::cli::{exit_status, stop_on_signals};
use slope_tools::eval::{run, EvalArgs};

fn main() -> ExitCode {
    let args = EvalArgs::parse();
    args.init_logging();
    exit_status(
        stop_on_signals()
            .and_then(|stop| run(&args, &stop))
            .and_then(|outcome| outcome.check()),
    )
}
