//! `slope-convert RECORDING OUT.mcap`: a recording as an MCAP file that
//! Foxglove opens: per frame the depth image, the cloud and the estimate
//! (the estimator run in this process, as `slope-eval` does).
//!
//! The file is written under a temporary name beside OUT.mcap and renamed
//! over it once finished: a failed run leaves a previous OUT.mcap as it
//! was. SIGINT/SIGTERM stop the conversion after the frame under way; the
//! frames converted so far are then finished into OUT.mcap, a valid file,
//! and the run says "interrupted after N of M frames" ([`Interruption`]).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use clap::Parser;
use slope_ipc_types::{CloudPoint, SlopeEstimate, Surfaces, DEFAULT_MAX_CLOUD_POINTS};
use slope_pipeline::{CloudView, Estimator, FrameInfo};
use slope_sensor::error_chain::ErrorChain;
use slope_sensor::frame_reads::{read_frame_images, Colour};
use slope_sensor::recording::{ColorImage, DepthImage, FrameEntry, Recording, RecordingError};

use slope_sensor::publish::StopFlag;

use crate::cli::{max_frames_arg, open_recording, Interruption, LogArgs, OutputArgs};
use crate::estimator::{load_config, method_arg};
use crate::export_format::{ExportFormat, FrameExporter};
use crate::mcap_export::{McapCompression, McapFrame};

#[derive(Debug, Parser)]
#[command(
    name = "slope-convert",
    // The output is required (checked by `ConvertArgs::parse_checked`, to
    // say how to give it), which the derived usage cannot know.
    override_usage = "slope-convert [OPTIONS] <RECORDING> --output <FILE>",
    version,
    about = "Convert a recording into an MCAP file (Foxglove, ROS 2 tooling): depth, cloud, estimates",
    long_about = "Writes OUT.mcap with, per frame of RECORDING, the depth image \
(/slope/depth, foxglove.RawImage, 16UC1), the point cloud (/slope/cloud, foxglove.PointCloud: x, y, \
z float32 and rgb: the recording's colour image, 0 for a frame without one) and the slope estimate (/slope/estimate, JSON with schema \
slope.estimate.json/1: the keys of slope-echo --json) with every surface seen (/slope/surfaces, \
JSON with schema slope.surfaces.json/1: the keys of slope-echo --surfaces --json), every channel \
JSON with a JSON Schema. The estimates come from the estimator run here on each frame (--no-estimates leaves them out). A colour \
image that cannot be read is a warning: that frame's points get rgb 0. A depth image \
that cannot be read skips its frame (a warning); a recording whose frames.csv lists no frames, or \
none of whose frames can be read, is refused (no file is written).

OUT.mcap is written under a temporary name in its directory and renamed into place when finished: \
a run that fails leaves an existing OUT.mcap as it was. SIGINT or SIGTERM (Ctrl-C) stops the \
conversion after the frame under way: OUT.mcap then holds the frames converted so far, as a \
finished file, the run says \"interrupted after N of M frames\" and exits with status 0. A second \
signal ends the run at once with status 130: the temporary file is removed and an existing OUT.mcap \
stays as it was.",
    after_help = "Examples:
  slope-convert tests/recordings/ramp16 -o ramp16.mcap     # then open ramp16.mcap in Foxglove
  slope-convert REC -o out.mcap --method tls --max-frames 10
  slope-convert REC -o out.mcap --no-estimates            # depth and cloud only
  slope-convert REC -o bag --format rosbag2               # a ROS 2 bag: ros2 bag play bag"
)]
pub struct ConvertArgs {
    /// The recording directory (holds recording.toml and frames.csv).
    pub recording: PathBuf,

    /// The MCAP file to write (replaced, once finished, if it exists).
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: Option<PathBuf>,

    /// The same as -o (given without the flag).
    #[arg(value_name = "OUTPUT", hide = true, conflicts_with = "output")]
    pub output_positional: Option<PathBuf>,

    /// Fit used for the estimates: paper, least-squares or tls.
    #[arg(long, value_parser = method_arg)]
    pub method: Option<slope_ipc_types::SlopeMethod>,

    /// TOML file with estimator parameters.
    #[arg(long)]
    pub config: Option<PathBuf>,

    /// Convert at most this many frames (the first ones).
    #[arg(long, value_parser = max_frames_arg)]
    pub max_frames: Option<u64>,

    /// mcap: one MCAP file for Foxglove (JSON: depth, cloud, estimates).
    /// rosbag2: a ROS 2 bag, the directory OUT (new or empty) with
    /// metadata.yaml and OUT_0.mcap, CDR messages: /slope/depth
    /// (sensor_msgs/msg/Image 16UC1), /slope/camera_info, /slope/estimate
    /// (slope_msgs/msg/SlopeEstimate, ros2/slope_msgs) and the mount on
    /// /tf_static (base_link to slope_camera).
    #[arg(long, value_enum, default_value_t = ExportFormat::Mcap)]
    pub format: ExportFormat,

    /// Leave the estimates out (depth and cloud only).
    #[arg(long)]
    pub no_estimates: bool,

    /// Compression of the file's chunks: zstd (about 1.7 MB a Kinect v2
    /// frame), lz4 (2.3 MB) or none (4.4 MB). Foxglove reads all three.
    #[arg(long, value_enum, value_name = "KIND", default_value_t = McapCompression::Zstd)]
    pub mcap_compression: McapCompression,

    /// Largest frame (the depth image's width x height) to accept; a recording
    /// with a larger one is refused before any cloud is allocated.
    #[arg(long, default_value_t = DEFAULT_MAX_CLOUD_POINTS)]
    pub max_points: usize,

    #[command(flatten)]
    pub log: LogArgs,
}

/// What `slope-convert` without an output says (a usage error, status 2).
pub const OUTPUT_MISSING: &str = "an output file is required: give it as -o FILE";

impl OutputArgs for ConvertArgs {
    const OUTPUT_MISSING: &'static str = OUTPUT_MISSING;

    fn outputs(&self) -> (Option<&Path>, Option<&Path>) {
        (self.output.as_deref(), self.output_positional.as_deref())
    }
}

impl ConvertArgs {
    /// `-o FILE` (or FILE without the flag).
    pub fn output(&self) -> &Path {
        match (&self.output, &self.output_positional) {
            (Some(path), _) | (None, Some(path)) => path,
            // Only without [`Self::try_parse_checked_from`]: no path.
            (None, None) => Path::new(""),
        }
    }

    pub fn init_logging(&self) {
        self.log.init_logging();
    }
}

/// What was written.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ConvertStats {
    pub frames: u64,
    pub estimates: u64,
    pub bad_frames: u64,
    /// Frames converted without colour (rgb 0) because their colour image
    /// could not be read.
    pub bad_colors: u64,
    /// Set when a signal stopped the run before every frame was converted.
    pub interrupted: Option<Interruption>,
}

/// Converts the recording of `args` into its output file. When `stop` is
/// set, the run ends after the frame under way and finishes the file with
/// the frames converted so far.
pub fn run(args: &ConvertArgs, stop: &StopFlag) -> anyhow::Result<ConvertStats> {
    let recording = open_recording(&args.recording, args.max_points, stop)
        .with_context(|| format!("cannot convert {}", args.recording.display()))?;
    let config =
        load_config(args.config.as_ref(), args.method, stop)?.for_sensor(&recording.meta().sensor);
    let mut estimator = (!args.no_estimates).then(|| Estimator::new(config));
    let mut exporter = FrameExporter::create_replacing(
        args.format,
        args.output(),
        args.mcap_compression,
        recording.meta(),
    )?;
    let stats = convert_frames(args, stop, &recording, estimator.as_mut(), &mut exporter)?;
    if stats.frames == 0 {
        return refuse_empty(args, stats);
    }
    exporter.finish()?;
    log_summary(args, &stats);
    Ok(stats)
}

/// Converts the frames of `recording` (at most `--max-frames`) into
/// `exporter`, until `stop` is set; counts what was written and skipped.
fn convert_frames(
    args: &ConvertArgs,
    stop: &StopFlag,
    recording: &Recording,
    mut estimator: Option<&mut Estimator>,
    exporter: &mut FrameExporter,
) -> anyhow::Result<ConvertStats> {
    let depth_meta = &recording.meta().depth;
    let projector = recording.projector();
    let mut depth = DepthImage::default();
    let mut points = vec![CloudPoint::INVALID; projector.len()];
    let limit = args.max_frames.map_or(usize::MAX, |m| m as usize);
    let total = recording.frames().len().min(limit);
    let mut stats = ConvertStats::default();
    for (done, frame) in recording.frames().iter().take(limit).enumerate() {
        if stop.is_stopped() {
            stats.interrupted = Some(Interruption {
                frames_done: done,
                frames_total: total,
            });
            break;
        }
        // On a thread of its own: a stop request ends a read that blocks.
        let images = read_frame_images(recording, frame, &mut depth, Colour::Read, Some(stop))?;
        let Some(images) = images else {
            stats.interrupted = Some(Interruption {
                frames_done: done,
                frames_total: total,
            });
            break;
        };
        if let Err(err) = images.depth {
            tracing::warn!(
                frame = frame.index,
                "skipping a bad frame: {}",
                ErrorChain(&err)
            );
            stats.bad_frames += 1;
            continue;
        }
        let color = colour_or_none(images.color, frame, &mut stats);
        projector.project_into(
            &depth.data,
            color.as_ref().map(|c| &c.data[..]),
            &mut points,
        );
        let message = estimator
            .as_deref_mut()
            .map(|estimator| estimate_message(estimator, recording, &points, frame));
        exporter.write(&McapFrame {
            stamp_ns: frame.timestamp_ns,
            width: depth_meta.width,
            height: depth_meta.height,
            depth: &depth.data,
            depth_unit_m: depth_meta.unit_m,
            points: &points,
            estimate: message.as_ref().map(|(estimate, _)| estimate),
            surfaces: message.as_ref().map(|(_, surfaces)| surfaces),
        })?;
        stats.frames += 1;
        stats.estimates += u64::from(message.is_some());
        tracing::debug!(frame = frame.index, "frame converted");
    }
    Ok(stats)
}

/// The estimate of one projected frame and its surfaces, as the messages
/// `slope-echo` shows.
fn estimate_message(
    estimator: &mut Estimator,
    recording: &Recording,
    points: &[CloudPoint],
    frame: &FrameEntry,
) -> (SlopeEstimate, Surfaces) {
    let depth_meta = &recording.meta().depth;
    let view = CloudView {
        points,
        width: depth_meta.width as usize,
        height: depth_meta.height as usize,
        intrinsics: recording.intrinsics(),
        mount: recording.mount(),
    };
    let info = FrameInfo {
        index: frame.index,
        stamp_ns: frame.timestamp_ns,
    };
    let estimate = estimator.estimate_frame(&view, info);
    let mut message = SlopeEstimate {
        frame_index: frame.index,
        capture_stamp_ns: frame.timestamp_ns,
        ..SlopeEstimate::default()
    };
    estimate.write_message(&mut message);
    let mut surfaces = Surfaces {
        frame_index: frame.index,
        capture_stamp_ns: frame.timestamp_ns,
        ..Surfaces::default()
    };
    estimate.write_surfaces(&mut surfaces);
    (message, surfaces)
}

/// The end of a run that converted no frame: Ok after an interruption, an
/// error otherwise. The exporter, dropped unfinished, removes its temporary
/// file: an earlier output stays as it was.
fn refuse_empty(args: &ConvertArgs, stats: ConvertStats) -> anyhow::Result<ConvertStats> {
    let output = args.output().display();
    if stats.interrupted.is_some() {
        tracing::warn!("stopped before the first frame; {output} left as it was");
        return Ok(stats);
    }
    bail!(
        "no frame of {} could be read ({} bad frame(s), see the warnings above); {output} \
         was not written",
        args.recording.display(),
        stats.bad_frames
    );
}

/// Logs what a finished run wrote: the colourless frames, an interruption,
/// and the counts.
fn log_summary(args: &ConvertArgs, stats: &ConvertStats) {
    if stats.bad_colors > 0 {
        tracing::warn!(
            "{} frame(s) converted without colour: their colour image could not be read",
            stats.bad_colors
        );
    }
    if let Some(interruption) = stats.interrupted {
        tracing::warn!(
            "{interruption}; {} holds the frames converted",
            args.output().display()
        );
    }
    tracing::info!(
        output = %args.output().display(),
        frames = stats.frames,
        estimates = stats.estimates,
        bad_frames = stats.bad_frames,
        bad_colors = stats.bad_colors,
        "converted"
    );
}

/// The colour image of `frame` as `read` (registered to its depth image:
/// the recording format's colour/), or `None`: none in frames.csv, or one
/// that could not be read (a warning, counted in `stats.bad_colors`; the
/// frame is converted with rgb 0, as without colour).
fn colour_or_none(
    read: Result<Option<ColorImage>, RecordingError>,
    frame: &FrameEntry,
    stats: &mut ConvertStats,
) -> Option<ColorImage> {
    match read {
        Ok(color) => color,
        Err(err) => {
            tracing::warn!(
                frame = frame.index,
                "converting without colour: {}",
                ErrorChain(&err)
            );
            stats.bad_colors += 1;
            None
        }
    }
}
