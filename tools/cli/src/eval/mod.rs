//! `slope-eval`: runs the estimator in-process (no IPC) on every frame of
//! one or more recordings and reports accuracy against the recordings'
//! ground truth and per-stage timings, as a table or as JSON lines, and
//! optionally as pictures of the planes found.
//!
//! Per frame: decode the depth PNG, project it with the recording's
//! intrinsics, run one [`Estimator`] per method on the same cloud
//! ([`Estimator::estimate_frame`] with the frame's index and timestamp from
//! frames.csv). Each recording gets fresh estimators that see its frames in
//! order, so the tracked slope follows the recording as it would follow the
//! camera, and never carries over from one recording to the next. A frame
//! whose image cannot be read is reported as `bad_frame` with the reader's
//! error and the evaluation goes on; a recording that cannot be opened, or
//! lists no frames, is reported by name, the others are still evaluated, and the program exits
//! non-zero at the end ([`EvalOutcome::check`]).
//!
//! SIGINT/SIGTERM stop the run after the frame being evaluated: the
//! recording under way is reported with the frames evaluated so far, the
//! recordings not reached are not, and the run says how far it got
//! ([`Interruption`]). What the stop left undone is no failure; problems
//! found before it still are.
//!
//! Accuracy: the ground truth of a recording is unsigned (0..90 degrees, the
//! angle between the two planes), the estimates are signed (+ uphill), so the
//! error compares magnitudes: `abs_error_deg = |median(|slope_deg|) - truth_deg|`
//! over the frames whose status is `ok`.
//!
//! One concern per file:
//! - `args.rs`: the flags ([`EvalArgs`], `--method` as [`MethodChoice`]) and
//!   the estimator configurations they ask for ([`configs`]);
//! - `run.rs`: the run over the recordings ([`run`], [`EvalOutcome`]):
//!   opening them, reporting each as it is done, `--render-frame`, `--plot`,
//!   the stop;
//! - `recording.rs`: one recording's frames under every method, and the
//!   pictures and clouds of the frames asked for;
//! - `frame.rs`: what became of one frame ([`FrameResult`], [`frame_result`]);
//! - `summary.rs`: one recording under one method, the JSON line
//!   ([`MethodReport`]), and its numbers against the truth ([`summarize`]);
//! - `table.rs`: the table printed without `--json`;
//! - `progress.rs`: the progress bar, and stdout lines printed past it;
//! - `tests.rs`: unit tests.
//!
//! [`Estimator`]: slope_pipeline::Estimator
//! [`Estimator::estimate_frame`]: slope_pipeline::Estimator::estimate_frame
//! [`Interruption`]: crate::cli::Interruption

mod args;
mod frame;
mod progress;
mod recording;
mod run;
mod summary;
mod table;
#[cfg(test)]
mod tests;

pub use args::{configs, method_choice_arg, EvalArgs, MethodChoice, RENDER_EVERY_ZERO};
pub use frame::{frame_result, FrameDetails, FrameResult, Timings, TrackedJson};
pub use run::{run, EvalOutcome};
pub use summary::{summarize, MethodReport, StageMedians, StatusCounts, Summary, LOW_CONFIDENCE};
pub use table::{table_header, table_rows};
