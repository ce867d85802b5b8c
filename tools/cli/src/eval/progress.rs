//! What `slope-eval` shows while it runs: the progress bar on stderr, and
//! the lines it prints on stdout past the bar.

use std::io::{IsTerminal, Write};

use anyhow::Context;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A bar of `len` frame runs (frames times methods) on stderr; hidden with
/// `-q` or when stderr is not a terminal.
pub(super) fn progress_bar(quiet: bool, len: usize) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(len as u64), ProgressDrawTarget::stderr());
    // The template is a constant; should it ever fail to parse, the default
    // style is still a working bar.
    if let Ok(style) =
        ProgressStyle::with_template("{prefix:>20} [{bar:30}] {pos}/{len} frame runs, {eta} left")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// Writes one line to stdout without disturbing the progress bar. `false`
/// when stdout is a closed pipe.
pub(super) fn print_line(bar: &ProgressBar, text: &str) -> anyhow::Result<bool> {
    let written = bar.suspend(|| {
        let mut stdout = std::io::stdout().lock();
        writeln!(stdout, "{text}").and_then(|()| stdout.flush())
    });
    match written {
        Ok(()) => Ok(true),
        Err(err) if err.kind() == std::io::ErrorKind::BrokenPipe => Ok(false),
        Err(err) => Err(err).context("cannot write the results to stdout"),
    }
}
