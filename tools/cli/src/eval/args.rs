//! The command line of `slope-eval` ([`EvalArgs`]) and the estimator
//! configurations it asks for ([`configs`]).

use std::path::PathBuf;

use clap::{ArgGroup, Parser};
use slope_ipc_types::{SlopeMethod, DEFAULT_MAX_CLOUD_POINTS};
use slope_pipeline::EstimatorConfig;
use slope_sensor::publish::StopFlag;

use crate::cli::{count_arg, max_frames_arg, LogArgs};
use crate::estimator::{load_config, method_arg};

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
inliers, RMS and area, the confidence and its reasons, ground_from_mount, how far ahead the \
ground was seen (ground_seen_to_m) and the tracked slope; \
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

    /// Threads each frame's stages may run on (1-64; default 1 or the
    /// config file's); the estimates are the same for every count.
    #[arg(long, value_parser = crate::estimator::threads_arg)]
    pub threads: Option<usize>,

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
pub fn configs(args: &EvalArgs, stop: &StopFlag) -> anyhow::Result<Vec<EstimatorConfig>> {
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
                None => load_config(args.config.as_ref(), method, stop)?,
            };
            if let Some(seed) = args.seed {
                config.seed = seed;
            }
            if let Some(threads) = args.threads {
                config.threads = threads;
            }
            Ok(config)
        })
        .collect()
}

/// What `--render-every 0` answers.
pub const RENDER_EVERY_ZERO: &str =
    "must be at least 1 (1 renders every frame; leave the flag out for one frame)";

/// `--render-every N`: at least 1.
fn render_every_arg(text: &str) -> Result<u64, String> {
    count_arg(text, RENDER_EVERY_ZERO)
}
