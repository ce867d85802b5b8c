//! A whole run ([`run`]): the recordings opened, each one evaluated and
//! reported (table or JSON line, `--render-frame` check, `--plot`) as soon
//! as it is done, and what a stop left undone; [`EvalOutcome`] says how it
//! went.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use indicatif::ProgressBar;
use slope_pipeline::{Estimator, EstimatorConfig};
use slope_sensor::publish::StopFlag;
use slope_sensor::recording::{FrameEntry, Recording};

use super::args::{configs, EvalArgs};
use super::progress::{print_line, progress_bar};
use super::recording::{evaluate_recording, ArtifactTarget};
use super::summary::MethodReport;
use super::table::{table_header, table_rows};
use crate::cli::{open_recording, Interruption};
use crate::eval_artifacts::Artifacts;
use crate::plot::write_recording_plot;

/// What a run produced, and which recordings failed.
#[derive(Debug, Default)]
pub struct EvalOutcome {
    pub reports: Vec<MethodReport>,
    /// One message per recording that could not be evaluated (or rendered).
    pub failures: Vec<String>,
    /// Set when a signal stopped the run before every frame was evaluated.
    pub interrupted: Option<Interruption>,
}

impl EvalOutcome {
    /// An error naming the failed recordings, if any. An interrupted run is
    /// judged on what it did: frames and recordings the stop left undone are
    /// not failures.
    pub fn check(&self) -> anyhow::Result<()> {
        if self.failures.is_empty() {
            return Ok(());
        }
        bail!(
            "{} problem(s): {}",
            self.failures.len(),
            self.failures.join("; ")
        )
    }
}

/// Evaluates every recording of `args`, printing each report as it is done
/// (table or JSON lines on stdout). Failures are logged and collected, not
/// returned: call [`EvalOutcome::check`] for the exit status. When `stop`
/// is set, the run ends after the frame under way, reports the frames
/// evaluated so far and says how far it got.
pub fn run(args: &EvalArgs, stop: &StopFlag) -> anyhow::Result<EvalOutcome> {
    let configs = configs(args, stop)?;
    let artifacts = Artifacts {
        render_dir: args.render.clone(),
        ply_dir: args.export_ply.clone(),
        frame: args.render_frame,
        every: args.render_every,
    };
    let mut outcome = EvalOutcome::default();
    let opened = open_recordings(args, stop, &mut outcome.failures)?;
    // Output directories only once something will be written into them.
    if !opened.is_empty() {
        artifacts.prepare()?;
        if let Some(dir) = &args.plot {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create the plot directory {}", dir.display()))?;
        }
    }
    let total: usize = opened.iter().map(|(_, r)| frame_limit(args, r)).sum();
    let bar = progress_bar(args.log.quiet, total * configs.len());
    let label_width = label_width(&args.recordings);
    if !args.json && !opened.is_empty() && !print_line(&bar, &table_header(label_width))? {
        return Ok(outcome);
    }
    let steps = Steps {
        args,
        configs: &configs,
        artifacts: &artifacts,
        bar: &bar,
        label_width,
        stop,
    };
    let mut render_names = RenderNames::default();
    let mut frames_done = 0;
    for (path, recording) in &opened {
        if stop.is_stopped() {
            break;
        }
        let name = render_names.claim(path);
        let (evaluated, next) = steps.recording(path, recording, &name, &mut outcome)?;
        frames_done += evaluated;
        match next {
            Next::Recording => {}
            Next::Stop => break,
            Next::ReaderGone => return Ok(outcome),
        }
    }
    bar.finish_and_clear();
    if stop.is_stopped() && frames_done < total {
        let interruption = Interruption {
            frames_done,
            frames_total: total,
        };
        tracing::warn!("{interruption}; the reports cover the frames evaluated");
        if !args.json {
            print_line(&bar, &format!("{interruption}"))?;
        }
        outcome.interrupted = Some(interruption);
    }
    Ok(outcome)
}

/// Opens the recordings of `args`, skipping files with a warning; a
/// recording that cannot be opened goes to `failures`. Only files, no
/// directory, is an error.
fn open_recordings<'a>(
    args: &'a EvalArgs,
    stop: &StopFlag,
    failures: &mut Vec<String>,
) -> anyhow::Result<Vec<(&'a PathBuf, Recording)>> {
    let mut opened = Vec::new();
    let mut files = Vec::new();
    for path in &args.recordings {
        // A shell glob over a folder of recordings also names its files
        // (README.md, make.sh): those are skipped, not failures.
        if path.is_file() {
            tracing::warn!(path = %path.display(), "skipping a file: a recording is a directory");
            files.push(path.display().to_string());
            continue;
        }
        match open_recording(path, args.max_points, stop) {
            Ok(recording) => opened.push((path, recording)),
            Err(err) => {
                let message = format!("cannot evaluate {}: {err:#}", path.display());
                // Reported once, with the others, when the run ends.
                failures.push(message);
            }
        }
    }
    if files.len() == args.recordings.len() {
        bail!(
            "no recording directory was given, only files ({}): a recording is a directory \
             with recording.toml, frames.csv and depth/",
            files.join(", ")
        );
    }
    Ok(opened)
}

/// How many frames of `recording` are evaluated (`--max-frames`).
fn frame_limit(args: &EvalArgs, recording: &Recording) -> usize {
    let max = args
        .max_frames
        .and_then(|m| usize::try_from(m).ok())
        .unwrap_or(usize::MAX);
    recording.frames().len().min(max)
}

/// The width of the table's recording column: the longest recording as
/// given, at least the header's.
fn label_width(recordings: &[PathBuf]) -> usize {
    recordings
        .iter()
        .map(|p| p.display().to_string().chars().count())
        .max()
        .unwrap_or(0)
        .max("recording".len())
}

/// What the run does after a recording.
enum Next {
    /// Goes on with the next recording.
    Recording,
    /// Stops: a signal cut this recording short or came before it.
    Stop,
    /// Returns at once: the reader of stdout went away.
    ReaderGone,
}

/// What every recording of a run is evaluated and reported with.
struct Steps<'a> {
    args: &'a EvalArgs,
    configs: &'a [EstimatorConfig],
    artifacts: &'a Artifacts,
    bar: &'a ProgressBar,
    label_width: usize,
    stop: &'a StopFlag,
}

impl Steps<'_> {
    /// Evaluates one recording with fresh estimators and reports it: the
    /// `--render-frame` check, the table rows or JSON lines, the plot.
    /// Returns how many frames were evaluated and what comes next.
    fn recording(
        &self,
        path: &Path,
        recording: &Recording,
        name: &str,
        outcome: &mut EvalOutcome,
    ) -> anyhow::Result<(usize, Next)> {
        let label = path.display().to_string();
        self.bar.set_prefix(short_name(path));
        let frames = &recording.frames()[..frame_limit(self.args, recording)];
        let mut estimators = self.estimators(recording);
        let target = ArtifactTarget {
            artifacts: self.artifacts,
            name,
        };
        let (reports, failures, evaluated) = evaluate_recording(
            recording,
            &label,
            frames,
            &mut estimators,
            &target,
            self.bar,
            self.stop,
        );
        outcome.failures.extend(failures);
        if evaluated == 0 && self.stop.is_stopped() {
            // Stopped before this recording's first frame: nothing to report.
            return Ok((evaluated, Next::Stop));
        }
        self.check_render_frame(&label, frames, evaluated, &mut outcome.failures);
        if !self.print_reports(&reports)? {
            // The reader went away (`slope-eval ... | head`): stop quietly.
            self.bar.finish_and_clear();
            return Ok((evaluated, Next::ReaderGone));
        }
        let cut_short = evaluated < frames.len();
        if let Some(dir) = &self.args.plot {
            let path = dir.join(format!("{name}-plot.png"));
            match self
                .bar
                .suspend(|| write_recording_plot(&path, &label, &reports))
            {
                Ok(()) => self
                    .bar
                    .suspend(|| tracing::info!(path = %path.display(), "plotted")),
                Err(err) => outcome.failures.push(format!("{err:#}")),
            }
        }
        outcome.reports.extend(reports);
        let next = if cut_short {
            Next::Stop
        } else {
            Next::Recording
        };
        Ok((evaluated, next))
    }

    /// Fresh estimators, one per method: the tracked slope follows this
    /// recording only. Flatness is judged against this recording's sensor
    /// unless configured.
    fn estimators(&self, recording: &Recording) -> Vec<Estimator> {
        let sensor = &recording.meta().sensor;
        let mut estimators: Vec<Estimator> = self
            .configs
            .iter()
            .map(|c| Estimator::new(c.clone().for_sensor(sensor)))
            .collect();
        for estimator in &mut estimators {
            estimator.set_inspect(self.artifacts.enabled());
        }
        estimators
    }

    /// `--render-frame`: a frame that was not among those to evaluate is a
    /// failure; one that a stop left unreached is only a warning.
    fn check_render_frame(
        &self,
        label: &str,
        frames: &[FrameEntry],
        evaluated: usize,
        failures: &mut Vec<String>,
    ) {
        let Some(frame) = self.args.render_frame else {
            return;
        };
        let asked = frames.iter().any(|f| f.index == frame);
        let reached = frames[..evaluated].iter().any(|f| f.index == frame);
        if self.artifacts.enabled() && !asked {
            failures.push(format!(
                "cannot render frame {frame} of {label}: no such frame was evaluated"
            ));
        } else if self.artifacts.enabled() && !reached {
            // Only a stop leaves an evaluated frame unreached: not a failure.
            tracing::warn!(
                recording = label,
                frame,
                "not rendered: the run was interrupted before this frame"
            );
        }
    }

    /// Prints the reports as table rows or JSON lines; `false` when stdout
    /// is a closed pipe.
    fn print_reports(&self, reports: &[MethodReport]) -> anyhow::Result<bool> {
        for report in reports {
            let text = if self.args.json {
                serde_json::to_string(report).context("cannot format the report as JSON")?
            } else {
                table_rows(report, self.label_width)
            };
            if !print_line(self.bar, &text)? {
                return Ok(false);
            }
        }
        Ok(true)
    }
}

/// File-name stems for rendered pictures: the recording's directory name,
/// with `-2`, `-3`, ... when two recordings share it.
#[derive(Debug, Default)]
pub(super) struct RenderNames {
    used: HashMap<String, usize>,
}

impl RenderNames {
    pub(super) fn claim(&mut self, path: &Path) -> String {
        let base = short_name(path);
        let count = self.used.entry(base.clone()).or_insert(0);
        *count += 1;
        if *count == 1 {
            base
        } else {
            format!("{base}-{count}")
        }
    }
}

/// The last component of a recording's path ("recording" if it has none).
fn short_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "recording".to_string())
}
