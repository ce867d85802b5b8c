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

use std::collections::HashMap;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use clap::{ArgGroup, Parser};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};
use slope_ipc_types::{CloudPoint, EstimateStatus, SlopeMethod, DEFAULT_MAX_CLOUD_POINTS};
use slope_pipeline::tracking::TrackedSlope;
use slope_pipeline::{
    CloudView, Estimate, Estimator, EstimatorConfig, FrameInfo, PlaneEstimate, StageTimings,
};
use slope_sensor::recording::{DepthImage, FrameEntry, Recording};

use slope_sensor::publish::StopFlag;

use crate::cli::{count_arg, max_frames_arg, open_recording, Interruption, LogArgs};
use crate::demo::median;
use crate::estimator::{load_config, method_arg};
use crate::eval_artifacts::{Artifacts, Snapshot};
use crate::plot::write_recording_plot;

/// An `ok` frame whose confidence is below this counts as low-confidence in
/// the summary.
pub const LOW_CONFIDENCE: f64 = 0.5;

#[derive(Debug, Parser)]
#[command(
    name = "slope-eval",
    // --render-frame and --render-every choose what --render and
    // --export-ply write: without one of those they would do nothing.
    group(ArgGroup::new("artifact_output").args(["render", "export_ply"]).multiple(true)),
    version,
    about = "Run the slope estimator offline on recordings: accuracy against ground truth, per-stage timings",
    long_about = "Runs the estimator in this process (no IPC) on each frame of each recording and \
reports, per recording and method: frames, frames with status ok, the median signed slope, the \
ground truth, the error and the median processing time, with a per-stage breakdown.\n\n\
Ground truth is the frame's slope_deg cell in frames.csv when present, else [truth] slope_deg in \
recording.toml; a recording's truth is the median of its frames' truths. Truth is unsigned (the \
angle between the two planes, 0..90 degrees) while estimates are signed (+ uphill, - downhill), so \
the error is computed on magnitudes:\n  \
abs_error_deg = | median over ok frames of |slope_deg|  -  truth_deg |\n\
(median_frame_error_deg in the JSON is the median of the per-frame | |slope_deg| - truth |).\n\n\
Each recording gets fresh estimators that see its frames in order, so the tracked slope follows \
the recording. Per frame the JSON also gives both planes ([a, b, c, d], camera frame), their \
inliers, RMS and area, the confidence and its reasons, ground_from_mount and the tracked slope; \
the summary counts the ok frames whose confidence is below 0.5 (low_confidence_frames).\n\n\
A frame whose depth image cannot be read is reported with status bad_frame and its error; the \
evaluation goes on. A recording that cannot be opened, whose frames.csv lists no frames or none \
of whose frames can be read is reported by name, the others are still evaluated, and the exit status is non-zero.\n\n\
SIGINT or SIGTERM (Ctrl-C) stops the run after the frame being evaluated: the recording under way \
is reported with the frames evaluated so far (its summary covers those frames only), recordings \
not reached are not reported, and the run says \"interrupted after N of M frames\" (below the \
table on stdout; on stderr with --json, whose stdout stays JSON lines). The exit status is then 0: \
frames, recordings and a --render frame that the stop left undone are not failures. Problems found \
before the stop (a recording that did not open, a frame that could not be rendered) still make it \
non-zero. A second signal ends the program at once (status 130).",
    after_help = "Examples:
  slope-eval tests/recordings/ramp16                       # table: paper method
  slope-eval tests/recordings/* --method all               # the three methods side by side
  slope-eval REC --json | jq .summary                      # a JSON line per recording and method
  slope-eval REC --config slope.toml --seed 7              # a file's [estimator], another seed
  slope-eval REC --preset paper-literal                    # the paper as written (slow)
  slope-eval REC --render out/ --render-frame 12           # overlay PNG of frame 12
  slope-eval REC --render out/ --render-every 10 --export-ply out/   # every 10th frame, PNG and PLY
  slope-eval REC --method all --plot out/                  # slope and time over the frames"
)]
pub struct EvalArgs {
    /// Recording directories (each holds recording.toml and frames.csv).
    /// Files among them are skipped with a warning (for shell globs such
    /// as DIR/*); only files, no directory, is an error.
    #[arg(required = true, value_name = "RECORDING")]
    pub recordings: Vec<PathBuf>,

    /// Fit used for the planes: paper, least-squares, tls, or all (the three
    /// side by side). Default: the config file's method, else paper.
    #[arg(long, value_parser = method_choice_arg)]
    pub method: Option<MethodChoice>,

    /// TOML file with estimator parameters (see the pipeline README);
    /// missing keys keep our defaults (those of --preset default).
    #[arg(long)]
    pub config: Option<PathBuf>,

    /// Seed of every random draw of the estimator (RANSAC, averaging);
    /// overrides the config file.
    #[arg(long)]
    pub seed: Option<u64>,

    /// Start from a named configuration instead of a file: default (ours)
    /// or paper-literal (the paper as written, every documented change
    /// off; slow; the same as pipeline/presets/paper-literal.toml).
    #[arg(long, conflicts_with = "config", value_parser = ["default", "paper-literal"])]
    pub preset: Option<String>,

    /// Evaluate at most this many frames of each recording (the first ones).
    #[arg(long, value_parser = max_frames_arg)]
    pub max_frames: Option<u64>,

    /// Print one JSON object per recording and method, one per line, instead
    /// of the table.
    #[arg(long)]
    pub json: bool,

    /// Write, per recording and method, an overlay PNG of a frame into DIR:
    /// every segmented plane in its own colour (ground red, inclined plane
    /// blue, labelled), the paper method's normals (kept green, dropped
    /// yellow) and a caption with slope, spread, confidence and status.
    #[arg(long, value_name = "DIR")]
    pub render: Option<PathBuf>,

    /// The frame to render and export (its index in frames.csv); default:
    /// the middle one of the evaluated frames. A frame that was not
    /// evaluated, or whose depth image cannot be read, is an error.
    #[arg(
        long,
        value_name = "INDEX",
        conflicts_with = "render_every",
        requires = "artifact_output"
    )]
    pub render_frame: Option<u64>,

    /// Render and export every Nth evaluated frame (the first, the N+1th,
    /// ...) instead of one. Like --render-frame, needs --render or
    /// --export-ply.
    #[arg(long, value_name = "N", value_parser = render_every_arg, requires = "artifact_output")]
    pub render_every: Option<u64>,

    /// Write the cloud of the rendered frame(s) as PLY into DIR (plane
    /// label, role and normal per point; CloudCompare, MeshLab, Open3D).
    #[arg(long, value_name = "DIR")]
    pub export_ply: Option<PathBuf>,

    /// Write one PNG per recording into DIR: each method's per-frame slope,
    /// the tracked slope and the truth, and the time per frame.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,

    /// Largest frame (the depth image's width x height) to accept; a recording
    /// with a larger one is refused before any cloud is allocated.
    #[arg(long, default_value_t = DEFAULT_MAX_CLOUD_POINTS)]
    pub max_points: usize,

    /// -v/-q (-q also hides the progress bar).
    #[command(flatten)]
    pub log: LogArgs,
}

impl EvalArgs {
    /// Sets up `tracing` to stderr, as every slope program does.
    pub fn init_logging(&self) {
        self.log.init_logging();
    }
}

/// `--method`: one method, or all three.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MethodChoice {
    One(SlopeMethod),
    All,
}

pub fn method_choice_arg(text: &str) -> Result<MethodChoice, String> {
    if text == "all" {
        return Ok(MethodChoice::All);
    }
    method_arg(text)
        .map(MethodChoice::One)
        .map_err(|_| format!("unknown method '{text}': expected paper, least-squares, tls or all"))
}

/// The estimator configurations `args` asks for, one per method, in the
/// order of [`SlopeMethod::ALL`] for `--method all`.
pub fn configs(args: &EvalArgs) -> anyhow::Result<Vec<EstimatorConfig>> {
    let methods: Vec<Option<SlopeMethod>> = match args.method {
        None => vec![None],
        Some(MethodChoice::One(method)) => vec![Some(method)],
        Some(MethodChoice::All) => SlopeMethod::ALL.into_iter().map(Some).collect(),
    };
    methods
        .into_iter()
        .map(|method| {
            let mut config = match args.preset.as_deref().and_then(EstimatorConfig::preset) {
                Some(preset) => EstimatorConfig {
                    method: method.unwrap_or(preset.method),
                    ..preset
                },
                None => load_config(args.config.as_ref(), method)?,
            };
            if let Some(seed) = args.seed {
                config.seed = seed;
            }
            Ok(config)
        })
        .collect()
}

/// What became of one frame under one method.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameResult {
    /// The frame's `index` in frames.csv.
    pub index: u64,
    pub status: &'static str,
    /// Signed slope, degrees (+ uphill); `None` unless `ok`.
    pub slope_deg: Option<f64>,
    /// Spread of the averaged angle samples, degrees; `None` unless `ok`.
    pub std_deg: Option<f64>,
    /// Distance to the inclined plane along the optical axis, metres;
    /// `None` unless `ok`.
    pub distance_m: Option<f64>,
    /// The frame's ground truth, degrees, if the recording has one.
    pub truth_deg: Option<f64>,
    /// Milliseconds, total and per stage; `None` when the frame could not be
    /// read (the estimator did not run).
    pub ms: Option<Timings>,
    /// Why the frame is `bad_frame`.
    pub error: Option<String>,
    /// Planes, their quality, confidence and track; all `null` when the
    /// frame could not be read.
    #[serde(flatten)]
    pub details: FrameDetails,
}

/// What the estimator found besides the slope, for a frame it ran on. Every
/// field is `None` (`null`) when the frame could not be read; a plane's
/// fields are also `None` when that plane is absent.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct FrameDetails {
    /// `[a, b, c, d]` in the camera frame: `(a, b, c)` a unit normal towards
    /// the camera side, `d` the camera's distance to the plane.
    pub ground_plane: Option<[f64; 4]>,
    /// `[a, b, c, d]` as `ground_plane`.
    pub inclined_plane: Option<[f64; 4]>,
    pub ground_inliers: Option<u32>,
    pub inclined_inliers: Option<u32>,
    /// RMS distance of the inliers from the plane, metres.
    pub ground_rms_m: Option<f64>,
    pub inclined_rms_m: Option<f64>,
    /// Surface the inliers cover, square metres.
    pub ground_area_m2: Option<f64>,
    pub inclined_area_m2: Option<f64>,
    /// How far to trust `slope_deg`, 0..=1 (0 unless `ok`).
    pub confidence: Option<f64>,
    /// Why the confidence is below 1, by name.
    pub confidence_reasons: Option<Vec<std::borrow::Cow<'static, str>>>,
    /// True when the ground normal is the mount's up vector.
    pub ground_from_mount: Option<bool>,
    /// The slope tracked over the recording's frames so far.
    pub tracked: Option<TrackedJson>,
}

/// The tracked slope after a frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackedJson {
    /// Degrees, signed; `None` before the first accepted frame.
    pub slope_deg: Option<f64>,
    pub std_deg: Option<f64>,
    /// Frames accepted into the track since it (re)started.
    pub frames: u32,
    /// True when this frame was accepted into the track.
    pub accepted: bool,
}

impl From<&TrackedSlope> for TrackedJson {
    fn from(t: &TrackedSlope) -> Self {
        Self {
            slope_deg: t.slope_deg.is_finite().then_some(t.slope_deg),
            std_deg: t.std_deg.is_finite().then_some(t.std_deg),
            frames: t.frames,
            accepted: t.accepted,
        }
    }
}

impl FrameDetails {
    /// The details of an estimate.
    pub fn of(estimate: &Estimate) -> Self {
        let ground = estimate.ground.as_ref();
        let inclined = estimate.inclined.as_ref();
        let coefficients = |p: &PlaneEstimate| p.coefficients;
        let inliers = |p: &PlaneEstimate| p.inliers;
        let rms = |p: &PlaneEstimate| p.rms_m;
        let area = |p: &PlaneEstimate| p.area_m2;
        Self {
            ground_plane: ground.map(coefficients),
            inclined_plane: inclined.map(coefficients),
            ground_inliers: ground.map(inliers),
            inclined_inliers: inclined.map(inliers),
            ground_rms_m: ground.map(rms),
            inclined_rms_m: inclined.map(rms),
            ground_area_m2: ground.map(area),
            inclined_area_m2: inclined.map(area),
            confidence: Some(estimate.confidence),
            confidence_reasons: Some(
                slope_ipc_types::confidence::names(estimate.confidence_reasons).collect(),
            ),
            ground_from_mount: Some(estimate.ground_from_mount),
            tracked: estimate.tracked.as_ref().map(TrackedJson::from),
        }
    }
}

/// Stage timings serialised as `{"total": ms, "<stage>": ms, ...}` in
/// pipeline order.
#[derive(Debug, Clone, PartialEq)]
pub struct Timings(pub StageTimings);

impl Serialize for Timings {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.stages.len() + 1))?;
        map.serialize_entry("total", &self.0.total_ms)?;
        for (name, ms) in &self.0.stages {
            map.serialize_entry(name, ms)?;
        }
        map.end()
    }
}

/// Named medians, serialised as a JSON object in their order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StageMedians(pub Vec<(String, f64)>);

impl Serialize for StageMedians {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (name, ms) in &self.0 {
            map.serialize_entry(name, ms)?;
        }
        map.end()
    }
}

/// The numbers of one recording under one method.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Frames evaluated.
    pub frames: usize,
    /// Frames with status `ok`.
    pub ok_frames: usize,
    /// Frames with status `ok` whose confidence is below [`LOW_CONFIDENCE`].
    pub low_confidence_frames: usize,
    /// Median signed slope of the `ok` frames, degrees.
    pub median_slope_deg: Option<f64>,
    /// Median of `|slope_deg|` over the `ok` frames, degrees.
    pub median_abs_slope_deg: Option<f64>,
    /// `|median_abs_slope_deg - truth_deg|`; `None` without truth.
    pub abs_error_deg: Option<f64>,
    /// Median over the `ok` frames with truth of `| |slope_deg| - truth |`.
    pub median_frame_error_deg: Option<f64>,
    /// Median total processing time of the frames the estimator ran on.
    pub median_ms: Option<f64>,
    /// Median time of each stage over the frames it ran in, pipeline order.
    pub median_stage_ms: StageMedians,
    /// Frames per status other than `ok`.
    pub not_ok: StatusCounts,
}

/// Status name and count, serialised as a JSON object.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StatusCounts(pub Vec<(&'static str, usize)>);

impl Serialize for StatusCounts {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (name, count) in &self.0 {
            map.serialize_entry(name, count)?;
        }
        map.end()
    }
}

/// One recording under one method: the JSON object of one output line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MethodReport {
    /// The recording directory as given on the command line.
    pub recording: String,
    #[serde(serialize_with = "method_name")]
    pub method: SlopeMethod,
    /// Median of the evaluated frames' truths; `None` without truth.
    pub truth_deg: Option<f64>,
    pub estimates: Vec<FrameResult>,
    pub summary: Summary,
}

fn method_name<S: Serializer>(method: &SlopeMethod, serializer: S) -> Result<S::Ok, S::Error> {
    serializer.serialize_str(method.name())
}

impl MethodReport {
    /// The report of `frames`; the truth and the summary are computed here.
    pub fn new(recording: String, method: SlopeMethod, estimates: Vec<FrameResult>) -> Self {
        let mut truths: Vec<f64> = estimates.iter().filter_map(|f| f.truth_deg).collect();
        let truth_deg = median(&mut truths);
        let summary = summarize(&estimates, truth_deg);
        Self {
            recording,
            method,
            truth_deg,
            estimates,
            summary,
        }
    }
}

/// The summary of `frames` against the recording's `truth_deg`.
pub fn summarize(frames: &[FrameResult], truth_deg: Option<f64>) -> Summary {
    let ok: Vec<&FrameResult> = frames.iter().filter(|f| f.status == "ok").collect();
    let mut slopes: Vec<f64> = ok.iter().filter_map(|f| f.slope_deg).collect();
    let mut magnitudes: Vec<f64> = slopes.iter().map(|s| s.abs()).collect();
    let mut frame_errors: Vec<f64> = ok
        .iter()
        .filter_map(|f| Some((f.slope_deg?.abs() - f.truth_deg?).abs()))
        .collect();
    let median_abs_slope_deg = median(&mut magnitudes);
    let mut totals: Vec<f64> = frames
        .iter()
        .filter_map(|f| f.ms.as_ref().map(|t| t.0.total_ms))
        .collect();

    let mut stage_names: Vec<&'static str> = Vec::new();
    let mut stage_times: HashMap<&'static str, Vec<f64>> = HashMap::new();
    for timings in frames.iter().filter_map(|f| f.ms.as_ref()) {
        for &(name, ms) in &timings.0.stages {
            if !stage_names.contains(&name) {
                stage_names.push(name);
            }
            stage_times.entry(name).or_default().push(ms);
        }
    }
    let median_stage_ms = stage_names
        .iter()
        .filter_map(|name| {
            let ms = median(stage_times.get_mut(name)?)?;
            Some((name.to_string(), ms))
        })
        .collect();

    let not_ok = EstimateStatus::ALL
        .into_iter()
        .filter(|s| *s != EstimateStatus::Ok)
        .map(|s| {
            (
                s.name(),
                frames.iter().filter(|f| f.status == s.name()).count(),
            )
        })
        .filter(|(_, count)| *count > 0)
        .collect();

    let low_confidence_frames = ok
        .iter()
        .filter(|f| f.details.confidence.is_some_and(|c| c < LOW_CONFIDENCE))
        .count();

    Summary {
        frames: frames.len(),
        ok_frames: ok.len(),
        low_confidence_frames,
        median_slope_deg: median(&mut slopes),
        median_abs_slope_deg,
        abs_error_deg: median_abs_slope_deg
            .zip(truth_deg)
            .map(|(m, t)| (m - t).abs()),
        median_frame_error_deg: median(&mut frame_errors),
        median_ms: median(&mut totals),
        median_stage_ms: StageMedians(median_stage_ms),
        not_ok: StatusCounts(not_ok),
    }
}

/// The result of a frame the estimator ran on.
pub fn frame_result(index: u64, truth_deg: Option<f64>, estimate: &Estimate) -> FrameResult {
    let ok = estimate.status == EstimateStatus::Ok;
    let when_ok = |v: f64| (ok && v.is_finite()).then_some(v);
    FrameResult {
        index,
        status: estimate.status.name(),
        slope_deg: when_ok(estimate.slope_deg),
        std_deg: when_ok(estimate.slope_std_deg),
        distance_m: when_ok(estimate.distance_m),
        truth_deg,
        ms: Some(Timings(estimate.timings.clone())),
        error: (estimate.status == EstimateStatus::BadFrame)
            .then(|| "the estimator rejected the cloud (size mismatch or empty)".to_string()),
        details: FrameDetails::of(estimate),
    }
}

/// What `--render-every 0` answers.
pub const RENDER_EVERY_ZERO: &str =
    "must be at least 1 (1 renders every frame; leave the flag out for one frame)";

/// `--render-every N`: at least 1.
fn render_every_arg(text: &str) -> Result<u64, String> {
    count_arg(text, RENDER_EVERY_ZERO)
}

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
    let configs = configs(args)?;
    let artifacts = Artifacts {
        render_dir: args.render.clone(),
        ply_dir: args.export_ply.clone(),
        frame: args.render_frame,
        every: args.render_every,
    };
    let mut outcome = EvalOutcome::default();
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
        match open_recording(path, args.max_points) {
            Ok(recording) => opened.push((path, recording)),
            Err(err) => {
                let message = format!("cannot evaluate {}: {err:#}", path.display());
                // Reported once, with the others, when the run ends.
                outcome.failures.push(message);
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
    // Output directories only once something will be written into them.
    if !opened.is_empty() {
        artifacts.prepare()?;
        if let Some(dir) = &args.plot {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create the plot directory {}", dir.display()))?;
        }
    }
    let frame_limit = |recording: &Recording| {
        let max = args
            .max_frames
            .and_then(|m| usize::try_from(m).ok())
            .unwrap_or(usize::MAX);
        recording.frames().len().min(max)
    };
    let total: usize = opened.iter().map(|(_, r)| frame_limit(r)).sum();
    let bar = progress_bar(args.log.quiet, total * configs.len());
    let label_width = args
        .recordings
        .iter()
        .map(|p| p.display().to_string().chars().count())
        .max()
        .unwrap_or(0)
        .max("recording".len());
    if !args.json && !opened.is_empty() && !print_line(&bar, &table_header(label_width))? {
        return Ok(outcome);
    }
    let mut render_names = RenderNames::default();
    let mut frames_done = 0;

    for (path, recording) in &opened {
        if stop.is_stopped() {
            break;
        }
        let label = path.display().to_string();
        bar.set_prefix(short_name(path));
        let frames = &recording.frames()[..frame_limit(recording)];
        let name = render_names.claim(path);
        // Fresh estimators: the tracked slope follows this recording only.
        // Flatness is judged against this recording's sensor unless configured.
        let sensor = &recording.meta().sensor;
        let mut estimators: Vec<Estimator> = configs
            .iter()
            .map(|c| Estimator::new(c.clone().for_sensor(sensor)))
            .collect();
        for estimator in &mut estimators {
            estimator.set_inspect(artifacts.enabled());
        }
        let target = ArtifactTarget {
            artifacts: &artifacts,
            name: &name,
        };
        let (reports, failures, evaluated) = evaluate_recording(
            recording,
            &label,
            frames,
            &mut estimators,
            &target,
            &bar,
            stop,
        );
        outcome.failures.extend(failures);
        frames_done += evaluated;
        if evaluated == 0 && stop.is_stopped() {
            // Stopped before this recording's first frame: nothing to report.
            break;
        }
        if let Some(frame) = args.render_frame {
            let asked = frames.iter().any(|f| f.index == frame);
            let reached = frames[..evaluated].iter().any(|f| f.index == frame);
            if artifacts.enabled() && !asked {
                outcome.failures.push(format!(
                    "cannot render frame {frame} of {label}: no such frame was evaluated"
                ));
            } else if artifacts.enabled() && !reached {
                // Only a stop leaves an evaluated frame unreached: not a failure.
                tracing::warn!(
                    recording = label.as_str(),
                    frame,
                    "not rendered: the run was interrupted before this frame"
                );
            }
        }
        for report in &reports {
            let text = if args.json {
                serde_json::to_string(report).context("cannot format the report as JSON")?
            } else {
                table_rows(report, label_width)
            };
            if !print_line(&bar, &text)? {
                // The reader went away (`slope-eval ... | head`): stop quietly.
                bar.finish_and_clear();
                return Ok(outcome);
            }
        }
        let cut_short = evaluated < frames.len();
        if let Some(dir) = &args.plot {
            let path = dir.join(format!("{name}-plot.png"));
            match bar.suspend(|| write_recording_plot(&path, &label, &reports)) {
                Ok(()) => bar.suspend(|| tracing::info!(path = %path.display(), "plotted")),
                Err(err) => outcome.failures.push(format!("{err:#}")),
            }
        }
        outcome.reports.extend(reports);
        if cut_short {
            break;
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

/// Writes one line to stdout without disturbing the progress bar. `false`
/// when stdout is a closed pipe.
fn print_line(bar: &ProgressBar, text: &str) -> anyhow::Result<bool> {
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

/// Runs every estimator on every frame of one recording, in order, until
/// `stop` is set, writing the pictures and clouds asked for; returns the
/// reports, what could not be written and how many frames were evaluated.
fn evaluate_recording(
    recording: &Recording,
    label: &str,
    frames: &[FrameEntry],
    estimators: &mut [Estimator],
    target: &ArtifactTarget<'_>,
    bar: &ProgressBar,
    stop: &StopFlag,
) -> (Vec<MethodReport>, Vec<String>, usize) {
    let projector = recording.projector();
    let mut depth = DepthImage::default();
    let mut points = vec![CloudPoint::INVALID; projector.len()];
    let mut results: Vec<Vec<FrameResult>> =
        vec![Vec::with_capacity(frames.len()); estimators.len()];
    let mut failures = Vec::new();
    let meta = recording.meta();
    let (width, height) = (meta.depth.width as usize, meta.depth.height as usize);
    let mut evaluated = 0;
    let mut first_bad: Option<String> = None;
    let mut bad = 0;
    for (position, frame) in frames.iter().enumerate() {
        if stop.is_stopped() {
            break;
        }
        evaluated += 1;
        let wanted = target.artifacts.wants(position, frame.index, frames.len());
        let truth_deg = recording.truth_deg(frame);
        match recording.read_depth_into(frame, &mut depth) {
            Err(err) => {
                let error = err.to_string();
                bar.suspend(|| {
                    tracing::warn!(recording = label, frame = frame.index, "bad frame: {error}")
                });
                if wanted && target.artifacts.frame == Some(frame.index) {
                    failures.push(format!(
                        "cannot render frame {} of {label}: it is a bad frame: {error}",
                        frame.index
                    ));
                } else if wanted {
                    bar.suspend(|| {
                        tracing::warn!(
                            recording = label,
                            frame = frame.index,
                            "not rendered: bad frame"
                        )
                    });
                }
                for per_method in &mut results {
                    per_method.push(FrameResult {
                        index: frame.index,
                        status: EstimateStatus::BadFrame.name(),
                        slope_deg: None,
                        std_deg: None,
                        distance_m: None,
                        truth_deg,
                        ms: None,
                        error: Some(error.clone()),
                        details: FrameDetails::default(),
                    });
                }
                bar.inc(estimators.len() as u64);
                bad += 1;
                first_bad.get_or_insert(error);
            }
            Ok(()) => {
                projector.project_into(&depth.data, None, &mut points);
                let view = CloudView {
                    points: &points,
                    width,
                    height,
                    intrinsics: recording.intrinsics(),
                    mount: recording.mount(),
                };
                let info = FrameInfo {
                    index: frame.index,
                    stamp_ns: frame.timestamp_ns,
                };
                for (estimator, per_method) in estimators.iter_mut().zip(&mut results) {
                    let estimate = estimator.estimate_frame(&view, info);
                    tracing::debug!(
                        recording = label,
                        frame = frame.index,
                        method = estimate.method.name(),
                        status = estimate.status.name(),
                        slope_deg = estimate.slope_deg,
                        ms = estimate.timings.total_ms,
                        "estimated"
                    );
                    per_method.push(frame_result(frame.index, truth_deg, &estimate));
                    if wanted {
                        let snapshot = Snapshot {
                            recording: label,
                            name: target.name,
                            index: frame.index,
                            points: &points,
                            width: meta.depth.width,
                            height: meta.depth.height,
                            estimate: &estimate,
                            inspection: estimator.inspection(),
                            truth_deg,
                        };
                        match bar.suspend(|| target.artifacts.write(&snapshot)) {
                            Ok(paths) => {
                                for path in paths {
                                    bar.suspend(
                                        || tracing::info!(path = %path.display(), "written"),
                                    );
                                }
                            }
                            Err(err) => failures.push(format!("{err:#}")),
                        }
                    }
                    bar.inc(1);
                }
            }
        }
    }
    if evaluated > 0 && bad == evaluated {
        // Some bad frames are counted in the report; none readable at all
        // is a broken recording.
        failures.push(format!(
            "cannot evaluate {label}: none of its {bad} frame(s) could be read (the first: {})",
            first_bad.unwrap_or_default()
        ));
    }
    let reports = estimators
        .iter()
        .zip(results)
        .map(|(estimator, estimates)| {
            MethodReport::new(label.to_string(), estimator.config().method, estimates)
        })
        .collect();
    (reports, failures, evaluated)
}

/// Where one recording's pictures and clouds go.
struct ArtifactTarget<'a> {
    artifacts: &'a Artifacts,
    /// File-name stem of the recording.
    name: &'a str,
}

/// File-name stems for rendered pictures: the recording's directory name,
/// with `-2`, `-3`, ... when two recordings share it.
#[derive(Debug, Default)]
struct RenderNames {
    used: HashMap<String, usize>,
}

impl RenderNames {
    fn claim(&mut self, path: &Path) -> String {
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

fn progress_bar(quiet: bool, len: usize) -> ProgressBar {
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

/// The header line of the table.
pub fn table_header(label_width: usize) -> String {
    format!(
        "{:<label_width$}  {:<13}  {:>6}  {:>6}  {:>12}  {:>8}  {:>8}  {:>9}",
        "recording", "method", "frames", "ok", "median slope", "truth", "|error|", "median ms"
    )
}

/// The table row of a report and its indented detail lines (per-stage
/// medians, frames that are not ok, the first bad frame's error).
pub fn table_rows(report: &MethodReport, label_width: usize) -> String {
    let s = &report.summary;
    let deg = |v: Option<f64>, signed: bool| match v {
        Some(v) if signed => format!("{v:+.2}°"),
        Some(v) => format!("{v:.2}°"),
        None => "-".to_string(),
    };
    let mut text = format!(
        "{:<label_width$}  {:<13}  {:>6}  {:>6}  {:>12}  {:>8}  {:>8}  {:>9}",
        report.recording,
        report.method.name(),
        s.frames,
        s.ok_frames,
        deg(s.median_slope_deg, true),
        deg(report.truth_deg, false),
        deg(s.abs_error_deg, false),
        s.median_ms.map_or("-".to_string(), |ms| format!("{ms:.1}")),
    );
    if !s.median_stage_ms.0.is_empty() {
        let stages: Vec<String> = s
            .median_stage_ms
            .0
            .iter()
            .map(|(name, ms)| format!("{name} {ms:.2}"))
            .collect();
        text.push_str(&format!("\n    stages (median ms): {}", stages.join(", ")));
    }
    if s.low_confidence_frames > 0 {
        text.push_str(&format!(
            "\n    low confidence (< {LOW_CONFIDENCE}): {} of {} ok frames",
            s.low_confidence_frames, s.ok_frames
        ));
    }
    if !s.not_ok.0.is_empty() {
        let counts: Vec<String> = s
            .not_ok
            .0
            .iter()
            .map(|(name, count)| format!("{name} {count}"))
            .collect();
        text.push_str(&format!("\n    not ok: {}", counts.join(", ")));
    }
    if let Some(bad) = report.estimates.iter().find(|f| f.error.is_some()) {
        if let Some(error) = &bad.error {
            text.push_str(&format!("\n    first bad frame ({}): {error}", bad.index));
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok_frame(index: u64, slope: f64, truth: Option<f64>, total_ms: f64) -> FrameResult {
        FrameResult {
            index,
            status: "ok",
            slope_deg: Some(slope),
            std_deg: Some(0.1),
            distance_m: Some(2.0),
            truth_deg: truth,
            ms: Some(Timings(StageTimings {
                total_ms,
                stages: vec![("outlier", total_ms / 2.0), ("ransac", total_ms / 4.0)],
            })),
            error: None,
            details: FrameDetails {
                confidence: Some(0.9),
                ..FrameDetails::default()
            },
        }
    }

    fn failed_frame(index: u64, status: EstimateStatus, ms: Option<f64>) -> FrameResult {
        FrameResult {
            index,
            status: status.name(),
            slope_deg: None,
            std_deg: None,
            distance_m: None,
            truth_deg: Some(10.0),
            ms: ms.map(|total_ms| {
                Timings(StageTimings {
                    total_ms,
                    stages: vec![("outlier", total_ms)],
                })
            }),
            error: None,
            details: FrameDetails::default(),
        }
    }

    #[test]
    fn summary_compares_magnitudes_with_truth() {
        let frames = vec![
            ok_frame(0, -9.0, Some(10.0), 4.0),
            ok_frame(1, 12.0, Some(10.0), 8.0),
            ok_frame(2, 10.5, Some(10.0), 6.0),
            failed_frame(3, EstimateStatus::NoInclinedPlane, Some(1.0)),
            failed_frame(4, EstimateStatus::BadFrame, None),
        ];
        let report = MethodReport::new("r".into(), SlopeMethod::Paper, frames);
        let s = &report.summary;
        assert_eq!(report.truth_deg, Some(10.0));
        assert_eq!((s.frames, s.ok_frames), (5, 3));
        assert_eq!(s.median_slope_deg, Some(10.5));
        // |slope| = 9, 12, 10.5 -> median 10.5; error 0.5.
        assert_eq!(s.median_abs_slope_deg, Some(10.5));
        assert_eq!(s.abs_error_deg, Some(0.5));
        // Per-frame errors 1, 2, 0.5 -> median 1.
        assert_eq!(s.median_frame_error_deg, Some(1.0));
        // Totals 4, 8, 6, 1 (the unread frame has none) -> median 5.
        assert_eq!(s.median_ms, Some(5.0));
        // outlier: 2, 4, 3, 1 -> 2.5; ransac: 1, 2, 1.5 -> 1.5.
        assert_eq!(
            s.median_stage_ms.0,
            vec![("outlier".to_string(), 2.5), ("ransac".to_string(), 1.5)]
        );
        assert_eq!(s.not_ok.0, vec![("no_inclined_plane", 1), ("bad_frame", 1)]);
    }

    #[test]
    fn low_confidence_counts_ok_frames_below_the_threshold() {
        let with_confidence = |index, confidence| {
            let mut frame = ok_frame(index, 10.0, None, 1.0);
            frame.details.confidence = confidence;
            frame
        };
        let frames = vec![
            with_confidence(0, Some(0.2)),
            with_confidence(1, Some(0.5)),
            with_confidence(2, Some(0.49)),
            with_confidence(3, None),
            // Not ok: counted under not_ok, not as low confidence.
            failed_frame(4, EstimateStatus::NoGround, Some(1.0)),
        ];
        let report = MethodReport::new("r".into(), SlopeMethod::Paper, frames);
        assert_eq!(report.summary.low_confidence_frames, 2);
        let table = table_rows(&report, 9);
        assert!(
            table.contains("low confidence (< 0.5): 2 of 4 ok frames"),
            "{table}"
        );
    }

    #[test]
    fn details_carry_the_planes_confidence_and_track() {
        let estimate = Estimate {
            confidence: 0.3,
            confidence_reasons: slope_ipc_types::confidence::SMALL_AREA,
            tracked: Some(TrackedSlope {
                slope_deg: f64::NAN,
                std_deg: f64::NAN,
                frames: 0,
                accepted: false,
            }),
            ..ramp_estimate()
        };
        let frame = frame_result(4, Some(16.0), &estimate);
        let d = &frame.details;
        let (ground, inclined) = (estimate.ground.unwrap(), estimate.inclined.unwrap());
        assert_eq!(d.ground_plane, Some(ground.coefficients));
        assert_eq!(d.inclined_plane, Some(inclined.coefficients));
        assert_eq!(d.ground_inliers, Some(ground.inliers));
        assert_eq!(d.inclined_rms_m, Some(inclined.rms_m));
        assert_eq!(d.ground_area_m2, Some(ground.area_m2));
        assert_eq!(d.confidence, Some(0.3));
        assert_eq!(d.confidence_reasons, Some(vec!["small_area".into()]));
        assert_eq!(d.ground_from_mount, Some(false));
        let tracked = d.tracked.as_ref().unwrap();
        assert_eq!((tracked.slope_deg, tracked.frames), (None, 0));
        let json = serde_json::to_value(&frame).unwrap();
        assert_eq!(
            json["confidence_reasons"],
            serde_json::json!(["small_area"])
        );
        assert_eq!(
            json["tracked"],
            serde_json::json!({"slope_deg": null, "std_deg": null, "frames": 0, "accepted": false})
        );
        // Flattened: the details sit beside the v1 keys.
        assert!(json["ground_plane"].is_array() && json["details"].is_null());
    }

    /// An estimate of an analytic ramp.
    fn ramp_estimate() -> Estimate {
        use slope_pipeline::fixtures::{Scene, SceneCloud};
        let mut estimator = Estimator::new(EstimatorConfig {
            method: SlopeMethod::Tls,
            ..EstimatorConfig::default()
        });
        let cloud = SceneCloud::kinect2(&Scene::ramp(16.0), 1);
        let estimate = estimator.estimate(&cloud.view());
        assert_eq!(estimate.status, EstimateStatus::Ok);
        estimate
    }

    #[test]
    fn without_truth_or_ok_frames_the_numbers_are_absent() {
        let report = MethodReport::new(
            "r".into(),
            SlopeMethod::Tls,
            vec![ok_frame(0, 5.0, None, 1.0)],
        );
        assert_eq!(report.truth_deg, None);
        assert_eq!(report.summary.abs_error_deg, None);
        assert_eq!(report.summary.median_frame_error_deg, None);
        let failed = MethodReport::new(
            "r".into(),
            SlopeMethod::Tls,
            vec![failed_frame(0, EstimateStatus::NoGround, None)],
        );
        assert_eq!(failed.truth_deg, Some(10.0));
        assert_eq!(failed.summary.median_slope_deg, None);
        assert_eq!(failed.summary.abs_error_deg, None);
        assert_eq!(failed.summary.median_ms, None);
    }

    #[test]
    fn per_frame_truth_gives_the_median_truth() {
        let frames = vec![
            ok_frame(0, 10.0, Some(10.0), 1.0),
            ok_frame(1, 21.0, Some(20.0), 1.0),
            ok_frame(2, 30.0, Some(30.0), 1.0),
            ok_frame(3, 40.0, Some(40.0), 1.0),
        ];
        let report = MethodReport::new("r".into(), SlopeMethod::Paper, frames);
        assert_eq!(report.truth_deg, Some(25.0));
        assert_eq!(report.summary.median_frame_error_deg, Some(0.0));
    }

    #[test]
    fn json_has_the_documented_keys_in_order() {
        let report = MethodReport::new(
            "rec".into(),
            SlopeMethod::LeastSquares,
            vec![ok_frame(0, 5.0, None, 2.0)],
        );
        let text = serde_json::to_string(&report).unwrap();
        assert!(
            text.starts_with(
                "{\"recording\":\"rec\",\"method\":\"least-squares\",\"truth_deg\":null,\"estimates\":[{\"index\":0,\"status\":\"ok\",\"slope_deg\":5.0"
            ),
            "{text}"
        );
        assert!(
            text.contains("\"ms\":{\"total\":2.0,\"outlier\":1.0,\"ransac\":0.5}"),
            "{text}"
        );
    }

    #[test]
    fn method_choices() {
        assert_eq!(method_choice_arg("all"), Ok(MethodChoice::All));
        assert_eq!(
            method_choice_arg("tls"),
            Ok(MethodChoice::One(SlopeMethod::Tls))
        );
        let err = method_choice_arg("magic").unwrap_err();
        assert!(err.contains("tls or all"), "{err}");
    }

    #[test]
    fn render_names_are_unique() {
        let mut names = RenderNames::default();
        assert_eq!(names.claim(Path::new("a/ramp")), "ramp");
        assert_eq!(names.claim(Path::new("b/ramp")), "ramp-2");
        assert_eq!(names.claim(Path::new("b/wall/")), "wall");
    }
    #[test]
    fn preset_paper_literal() {
        let args = EvalArgs::try_parse_from([
            "slope-eval",
            "rec",
            "--preset",
            "paper-literal",
            "--method",
            "tls",
            "--seed",
            "3",
        ])
        .unwrap();
        let expected = EstimatorConfig {
            method: SlopeMethod::Tls,
            seed: 3,
            ..EstimatorConfig::paper_literal()
        };
        assert_eq!(configs(&args).unwrap(), vec![expected]);
        let args = EvalArgs::try_parse_from(["slope-eval", "rec", "--preset", "default"]).unwrap();
        assert_eq!(configs(&args).unwrap(), vec![EstimatorConfig::default()]);
        for bad in [
            &["slope-eval", "rec", "--preset", "paper"][..],
            &[
                "slope-eval",
                "rec",
                "--preset",
                "default",
                "--config",
                "x.toml",
            ][..],
        ] {
            assert!(EvalArgs::try_parse_from(bad).is_err(), "{bad:?}");
        }
    }
}
