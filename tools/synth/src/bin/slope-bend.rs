//! `slope-bend`: parse the command line, set up logging, call
//! [`slope_synth::bend::cli::run`].

use std::io::IsTerminal;
use std::process::ExitCode;

use clap::Parser;
use tracing_subscriber::EnvFilter;

fn main() -> ExitCode {
    let args = slope_synth::bend::cli::BendArgs::parse();
    tracing_subscriber::fmt()
        .with_env_filter(
            EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(args.log_level())),
        )
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .init();
    match slope_synth::cli::stop_on_signals()
        .and_then(|stop| slope_synth::bend::cli::run(&args, &stop))
    {
        Ok(summary) if summary.is_partial() => {
            tracing::info!(
                dir = %summary.dir.display(),
                frames = summary.frames,
                asked = summary.frames_asked,
                "interrupted: a valid recording of the frames written so far"
            );
            ExitCode::SUCCESS
        }
        Ok(summary) => {
            tracing::info!(
                dir = %summary.dir.display(),
                frames = summary.frames,
                truth_deg = args.angle_deg,
                "done"
            );
            ExitCode::SUCCESS
        }
        Err(err) => {
            // Once, a line per cause, no backtrace (as the other programs).
            eprintln!("error: {err}");
            for cause in err.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::FAILURE
        }
    }
}
