//! The command line of `slope-record` ([`RecordArgs`]) and the limits it
//! sets ([`RecordLimits`]).

use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::{Parser, ValueEnum};
use slope_sensor::recording::PngCompression;

use crate::cli::{max_frames_arg, CommonArgs, OutputArgs, CLIENT_PREFIX_HELP};
use crate::mcap_export::McapCompression;
use crate::mount_args::MountArgs;
use crate::replay::positive_f64;

/// The Kinect's depth pipeline, parsed when the arguments are (a plain name
/// in a build without the Kinect, which then refuses `--source kinect`).
#[cfg(feature = "kinect2")]
pub type PipelineArg = slope_sensor::kinect2::Pipeline;
#[cfg(not(feature = "kinect2"))]
pub type PipelineArg = String;

/// Where frames come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum RecordSource {
    /// The cloud topic of any running source (slope-capture, slope-replay).
    Topic,
    /// The Kinect v2 directly (needs a build with `--features kinect2`).
    Kinect,
}

/// What the recorder writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum RecordFormat {
    /// A recording directory (the recording format) that slope-replay plays.
    Recording,
    /// An MCAP file (Foxglove, ROS 2 tooling): depth, cloud and, when an
    /// estimator runs, its estimates and surfaces (topic source only). JSON in
    /// zstd-compressed chunks (--mcap-compression): about 1.7 MB a Kinect
    /// v2 frame, 50 MB a second at 30 Hz (a recording directory takes
    /// about 0.23 MB a frame): for short clips; record long runs as a
    /// recording and convert the part you need.
    Mcap,
    /// A ROS 2 bag: the directory -o (new) with metadata.yaml (written
    /// when the recording ends) and an MCAP file of CDR messages:
    /// /slope/depth (sensor_msgs/msg/Image 16UC1), /slope/camera_info,
    /// every estimate published meanwhile (/slope/estimate,
    /// slope_msgs/msg/SlopeEstimate) and the mount on /tf_static (topic
    /// source only; about 0.2 MB a Kinect v2 frame with zstd, 0.44 MB
    /// uncompressed).
    Rosbag2,
}

/// PNG compression of the written images.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Compression {
    Fast,
    Balanced,
    High,
}

impl From<Compression> for PngCompression {
    fn from(value: Compression) -> Self {
        match value {
            Compression::Fast => PngCompression::Fast,
            Compression::Balanced => PngCompression::Balanced,
            Compression::High => PngCompression::High,
        }
    }
}

#[derive(Debug, Parser)]
#[command(
    // It has no --config: the daemons' file only.
    mut_arg("service_prefix", |arg| arg.help(CLIENT_PREFIX_HELP)),
    name = "slope-record",
    // The output is required (checked by `RecordArgs::parse_checked`, to
    // say how to give it), which the derived usage cannot know.
    override_usage = "slope-record [OPTIONS] --output <PATH>",
    version,
    about = "Record depth (and colour) frames into a recording that slope-replay can play",
    long_about = "Writes the -o directory in the recording format (recording.toml, frames.csv, depth/*.png, \
color/*.png) from the cloud topic of a running source, or straight from the Kinect v2. Every row \
is flushed as soon as its images are written, so a recording cut short stays readable. Stops at \
--max-frames, --duration-s, when the topic goes quiet for --idle-timeout-s, or on Ctrl-C.",
    after_help = "Examples:
  slope-record -o scene1                               # from the running capture, until Ctrl-C
  slope-record -o scene1 --max-frames 300              # ten seconds of a 30 Hz camera
  slope-record -o scene1 --source kinect --mount-pitch-deg -20 --mount-height-m 0.5
  slope-replay scene1                                  # ... and play it back later
  slope-record -o copy --idle-timeout-s 2 & slope-replay REC --wait-subscribers 1
  slope-record -o run.mcap --max-frames 90             # 3 s as MCAP (from the name, ~150 MB)"
)]
pub struct RecordArgs {
    /// The recording directory to create (must not exist, or be empty); with
    /// --format mcap, or when its name ends in .mcap, the MCAP file to
    /// create (must not exist).
    #[arg(short = 'o', long = "output", value_name = "PATH")]
    pub output: Option<PathBuf>,

    /// The same as -o (given without the flag).
    #[arg(value_name = "OUTPUT", hide = true, conflicts_with = "output")]
    pub output_positional: Option<PathBuf>,

    /// Write a recording directory, or an MCAP file: per cloud the depth
    /// image (/slope/depth, foxglove.RawImage) and the cloud
    /// (/slope/cloud, foxglove.PointCloud), and every estimate published
    /// meanwhile (/slope/estimate, JSON), stamped with the capture time.
    /// Default: mcap when the output's name ends in .mcap, else recording.
    #[arg(long, value_enum)]
    pub format: Option<RecordFormat>,

    /// Where frames come from.
    #[arg(long, value_enum, default_value_t = RecordSource::Topic)]
    pub source: RecordSource,

    /// Stop after this many frames (at least 1).
    #[arg(long, value_parser = max_frames_arg)]
    pub max_frames: Option<u64>,

    /// Stop after this many seconds from the first frame.
    #[arg(long, value_name = "S", allow_hyphen_values = true, value_parser = positive_f64)]
    pub duration_s: Option<f64>,

    /// Topic: give up (non-zero exit) when no cloud arrives within this many
    /// seconds; waits forever when not given.
    #[arg(long, value_name = "S", allow_hyphen_values = true, value_parser = positive_f64)]
    pub wait_timeout_s: Option<f64>,

    /// Topic: finish when no cloud has arrived for this many seconds after
    /// the first one (e.g. the replay ended).
    #[arg(long, value_name = "S", allow_hyphen_values = true, value_parser = positive_f64)]
    pub idle_timeout_s: Option<f64>,

    /// The camera's pose for recording.toml's `[mount]` (topic: overrides
    /// the header's).
    #[command(flatten)]
    pub mount: MountArgs,

    /// PNG compression: fast for a busy robot, high for archiving.
    #[arg(long, value_enum, default_value_t = Compression::Fast)]
    pub compression: Compression,

    /// MCAP: compression of the file's chunks: zstd (about 1.7 MB a
    /// Kinect v2 frame), lz4 (2.3 MB) or none (4.4 MB). Foxglove reads all
    /// three.
    #[arg(long, value_enum, value_name = "KIND", default_value_t = McapCompression::Zstd)]
    pub mcap_compression: McapCompression,

    /// Kinect: serial of the device (default: the first).
    #[arg(long)]
    pub serial: Option<String>,

    /// Kinect: depth pipeline (default, cpu, cl, clkde, cuda, cudakde, gl).
    #[arg(long)]
    pub pipeline: Option<PipelineArg>,

    /// Kinect: record depth only.
    #[arg(long)]
    pub depth_only: bool,

    #[command(flatten)]
    pub common: CommonArgs,
}

/// What `slope-record` without an output says (a usage error, status 2).
pub const OUTPUT_MISSING: &str =
    "an output is required: give it as -o DIR (a recording directory), \
     or as -o FILE with --format mcap";

impl OutputArgs for RecordArgs {
    const OUTPUT_MISSING: &'static str = OUTPUT_MISSING;

    fn outputs(&self) -> (Option<&Path>, Option<&Path>) {
        (self.output.as_deref(), self.output_positional.as_deref())
    }
}

impl RecordArgs {
    /// `--format`, else mcap for an output named `*.mcap` (a directory
    /// named so would only be mistaken for an MCAP file), else a recording.
    pub fn format(&self) -> RecordFormat {
        self.format.unwrap_or_else(|| {
            let mcap = self
                .out_dir()
                .extension()
                .is_some_and(|ext| ext.eq_ignore_ascii_case("mcap"));
            if mcap {
                RecordFormat::Mcap
            } else {
                RecordFormat::Recording
            }
        })
    }

    /// `-o PATH` (or PATH without the flag).
    pub fn out_dir(&self) -> &Path {
        match (&self.output, &self.output_positional) {
            (Some(path), _) | (None, Some(path)) => path,
            // Only without [`Self::try_parse_checked_from`]: no path.
            (None, None) => Path::new(""),
        }
    }
}

/// When to stop recording.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RecordLimits {
    pub max_frames: Option<u64>,
    pub duration: Option<Duration>,
    pub wait_timeout: Option<Duration>,
    pub idle_timeout: Option<Duration>,
}

impl RecordLimits {
    pub(super) fn from_args(args: &RecordArgs) -> Self {
        Self {
            max_frames: args.max_frames,
            duration: args.duration_s.map(Duration::from_secs_f64),
            wait_timeout: args.wait_timeout_s.map(Duration::from_secs_f64),
            idle_timeout: args.idle_timeout_s.map(Duration::from_secs_f64),
        }
    }
}
