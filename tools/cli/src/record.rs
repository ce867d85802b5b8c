//! `slope-record OUT_DIR`: writes a recording (see the recording format)
//! that `slope-replay` can play back later, either from the cloud topic of
//! whatever source is running (`slope-capture`, `slope-replay`, ...) or
//! straight from the Kinect v2 (`--source kinect`, with the `kinect2`
//! feature).
//!
//! From the topic, each cloud becomes a depth image again: `depth =
//! round(z_m / 0.001)` (0 where the point is invalid), colour from `rgb` when
//! the header says so, intrinsics and mount from the header. Since a cloud is
//! projected from whole-millimetre depth, this gives back the source's depth
//! to the millimetre.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::{Parser, ValueEnum};
use slope_ipc_types::{CloudHeader, CloudPoint, CloudSource, Mount};
use slope_sensor::ipc::{create_node, CloudSubscriber, EstimateSubscriber};
use slope_sensor::publish::StopFlag;
use slope_sensor::recording::{
    ColorImage, DepthImage, DepthInfo, MountInfo, PngCompression, Recording, RecordingMeta,
    RecordingWriter, TruthInfo,
};
use slope_sensor::source::{FrameSource, SourceFrame, SourceInfo};

use crate::cli::{max_frames_arg, node_name, CommonArgs, OutputArgs, CLIENT_PREFIX_HELP};
use crate::mcap_export::{McapCompression, McapExporter, McapFrame};
use crate::mount_args::MountArgs;
use crate::replay::positive_f64;

/// The Kinect's depth pipeline, parsed when the arguments are (a plain name
/// in a build without the Kinect, which then refuses `--source kinect`).
#[cfg(feature = "kinect2")]
pub type PipelineArg = slope_sensor::kinect2::Pipeline;
#[cfg(not(feature = "kinect2"))]
pub type PipelineArg = String;

/// Metres per depth count of recordings written from the topic.
pub const TOPIC_DEPTH_UNIT_M: f64 = 0.001;

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
    /// estimator runs, its estimates (topic source only). JSON in
    /// zstd-compressed chunks (--mcap-compression): about 1.7 MB a Kinect
    /// v2 frame, 50 MB a second at 30 Hz (a recording directory takes
    /// about 0.23 MB a frame): for short clips; record long runs as a
    /// recording and convert the part you need.
    Mcap,
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
    fn from_args(args: &RecordArgs) -> Self {
        Self {
            max_frames: args.max_frames,
            duration: args.duration_s.map(Duration::from_secs_f64),
            wait_timeout: args.wait_timeout_s.map(Duration::from_secs_f64),
            idle_timeout: args.idle_timeout_s.map(Duration::from_secs_f64),
        }
    }
}

/// What a recording run did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RecordStats {
    pub written: u64,
    /// Clouds the topic had but the recorder never saw (gaps in frame_index).
    pub missed: u64,
    /// Clouds skipped because their size or layout differed from the first.
    pub skipped: u64,
    /// True when a signal ended the recording.
    pub stopped: bool,
    /// Estimates written (MCAP only).
    pub estimates: u64,
}

fn mount_info(mount: &Mount) -> MountInfo {
    let known = |v: f64| v.is_finite().then_some(v);
    MountInfo {
        height_m: known(mount.height_m),
        pitch_deg: known(mount.pitch_deg),
        roll_deg: known(mount.roll_deg),
    }
}

/// The recording.toml of a stream.
pub fn meta_for(info: &SourceInfo) -> RecordingMeta {
    RecordingMeta {
        sensor: info.sensor.clone(),
        depth: DepthInfo {
            width: info.width,
            height: info.height,
            unit_m: info.unit_m,
            fx: info.intrinsics.fx,
            fy: info.intrinsics.fy,
            cx: info.intrinsics.cx,
            cy: info.intrinsics.cy,
        },
        mount: mount_info(&info.mount),
        truth: TruthInfo::default(),
    }
}

/// The sensor a recording of the topic names: the cloud header's, else
/// (a header that names none) `kinect2` for camera clouds and `replay` for
/// the rest.
pub fn sensor_of(header: &CloudHeader) -> &str {
    match (header.sensor_name(), CloudSource::from_raw(header.source)) {
        ("", Some(CloudSource::Camera)) => "kinect2",
        ("", _) => "replay",
        (name, _) => name,
    }
}

/// A cloud's depth in whole counts of `unit_m`: `round(z_m / unit_m)`;
/// 0 (no reading) for an invalid point and for depth that does not fit in
/// a u16 count, never a bogus saturated value.
#[inline]
pub fn depth_count(point: &CloudPoint, unit_m: f64) -> u16 {
    slope_sensor::recording::metres_to_count(f64::from(point.z_m), unit_m)
}

/// Rebuilds the depth (and colour) images of a received cloud.
pub fn cloud_to_images(
    header: &CloudHeader,
    points: &[CloudPoint],
    unit_m: f64,
    depth: &mut DepthImage,
    color: &mut Option<ColorImage>,
) {
    depth.width = header.width;
    depth.height = header.height;
    depth.data.clear();
    depth
        .data
        .extend(points.iter().map(|p| depth_count(p, unit_m)));
    if header.has_color != 0 {
        let image = color.get_or_insert_with(ColorImage::default);
        image.width = header.width;
        image.height = header.height;
        image.data.clear();
        image.data.extend(points.iter().map(|p| {
            let [_, r, g, b] = p.rgb.to_be_bytes();
            [r, g, b]
        }));
    } else {
        *color = None;
    }
}

/// Recording timestamps from a source's stamps: starting at 0 and
/// following the source, but never going backwards. When the source's
/// clock jumps back (a restarted device, a looped replay), the timeline is
/// rebased: that frame comes one previous frame interval after the last,
/// and later frames follow the source from there. So stamps neither freeze
/// nor repeat, and a replay keeps the original pace.
struct Timeline {
    /// The last source stamp and the timestamp it became.
    last: Option<(u64, u64)>,
    /// The last forward step, used across a jump back.
    step_ns: u64,
}

impl Timeline {
    fn new() -> Self {
        Self {
            last: None,
            step_ns: 1,
        }
    }

    fn stamp(&mut self, source_stamp_ns: u64) -> u64 {
        let out = match self.last {
            None => 0,
            Some((last_source, last_out)) if source_stamp_ns >= last_source => {
                let step = source_stamp_ns - last_source;
                if step > 0 {
                    self.step_ns = step;
                }
                last_out.saturating_add(step)
            }
            Some((last_source, last_out)) => {
                tracing::warn!(
                    source_ns = source_stamp_ns,
                    previous_ns = last_source,
                    "source clock went backwards; continuing the recording's time"
                );
                last_out.saturating_add(self.step_ns)
            }
        };
        self.last = Some((source_stamp_ns, out));
        out
    }
}

/// Makes sure `dir` can take a new recording before anything is waited
/// for: an empty directory, or one that does not exist yet in a directory
/// that does (then created; a typing error in a parent is refused, not
/// created). Returns whether it was created.
pub fn prepare_out_dir(dir: &Path) -> anyhow::Result<bool> {
    match std::fs::read_dir(dir) {
        Ok(mut entries) => {
            if entries.next().is_some() {
                anyhow::bail!(
                    "the output directory {} is not empty; give a new or empty directory",
                    dir.display()
                );
            }
            Ok(false)
        }
        Err(err) if err.kind() == std::io::ErrorKind::NotFound => {
            check_parent(dir, "the output directory ")?;
            std::fs::create_dir(dir)
                .with_context(|| format!("cannot create the output directory {}", dir.display()))?;
            Ok(true)
        }
        Err(err) => Err(err).with_context(|| {
            format!(
                "cannot use {} as the output directory (is it a file, or unreadable?)",
                dir.display()
            )
        }),
    }
}

/// Records any frame source (the Kinect, a recording) until it ends, a
/// limit is reached or `stop` is set.
pub fn record_source(
    source: &mut dyn FrameSource,
    writer: &mut RecordingWriter,
    limits: &RecordLimits,
    stop: &StopFlag,
) -> anyhow::Result<RecordStats> {
    let mut stats = RecordStats::default();
    let mut frame = SourceFrame::default();
    let mut timeline = Timeline::new();
    let mut started: Option<Instant> = None;
    loop {
        if stop.is_stopped() {
            stats.stopped = true;
            break;
        }
        if limits.max_frames.is_some_and(|max| stats.written >= max)
            || limits
                .duration
                .zip(started)
                .is_some_and(|(duration, start)| start.elapsed() >= duration)
        {
            break;
        }
        if !source.next_frame(&mut frame).context("the source failed")? {
            stats.stopped = stop.is_stopped();
            break;
        }
        started.get_or_insert_with(Instant::now);
        let timestamp_ns = timeline.stamp(frame.source_stamp_ns);
        writer
            .write_frame(timestamp_ns, &frame.depth, frame.color.as_ref(), None)
            .with_context(|| {
                format!(
                    "cannot write frame {} into {}",
                    stats.written,
                    writer.dir().display()
                )
            })?;
        stats.written += 1;
    }
    Ok(stats)
}

/// Where the topic's frames go.
enum Sink {
    Recording(Box<RecordingWriter>),
    Mcap(Box<McapExporter>),
}

impl Sink {
    /// Creates the sink of `args` for clouds described by `info`.
    fn create(args: &RecordArgs, info: &SourceInfo) -> anyhow::Result<Self> {
        let out = args.out_dir();
        Ok(match args.format() {
            RecordFormat::Recording => {
                let mut recording = RecordingWriter::create(out, &meta_for(info), false)
                    .with_context(|| format!("cannot create the recording {}", out.display()))?;
                recording.set_compression(args.compression.into());
                Sink::Recording(Box::new(recording))
            }
            RecordFormat::Mcap => Sink::Mcap(Box::new(McapExporter::create(
                out,
                args.mcap_compression,
                &meta_for(info),
            )?)),
        })
    }

    fn finish(self, out: &Path) -> anyhow::Result<()> {
        match self {
            Sink::Recording(recording) => recording
                .finish()
                .map(drop)
                .with_context(|| format!("cannot finish the recording {}", out.display())),
            Sink::Mcap(mcap) => mcap.finish(),
        }
    }
}

/// Records the cloud topic until a limit is reached or `stop` is set.
pub fn record_topic(
    args: &RecordArgs,
    limits: &RecordLimits,
    stop: &StopFlag,
) -> anyhow::Result<RecordStats> {
    let names = args.common.service_names()?;
    let node = create_node(&node_name("slope-record"))?;
    let subscriber =
        CloudSubscriber::create(&node, &names).context("cannot subscribe to clouds")?;
    let estimates = match args.format() {
        RecordFormat::Mcap => Some(
            EstimateSubscriber::create(&node, &names).context("cannot subscribe to estimates")?,
        ),
        RecordFormat::Recording => None,
    };
    tracing::info!(service = subscriber.service_name(), out = %args.out_dir().display(), "recording the cloud topic");

    let mut stats = RecordStats::default();
    let mut writer: Option<(Sink, CloudHeader)> = None;
    let mut depth = DepthImage::default();
    let mut color: Option<ColorImage> = None;
    let mut timeline = Timeline::new();
    let mut last_index: Option<u64> = None;
    let waiting_since = Instant::now();
    let mut first_at: Option<Instant> = None;
    let mut last_at = Instant::now();
    let slice = Duration::from_millis(100);
    'outer: loop {
        if stop.is_stopped() {
            stats.stopped = true;
            break;
        }
        match first_at {
            None => {
                if let Some(timeout) = limits.wait_timeout {
                    if waiting_since.elapsed() >= timeout {
                        anyhow::bail!(
                            "no cloud arrived on '{}' within {:.1} s; is a source (slope-capture, \
                             slope-replay) running with the same --service-prefix?",
                            subscriber.service_name(),
                            timeout.as_secs_f64()
                        );
                    }
                }
            }
            Some(first) => {
                if limits.duration.is_some_and(|d| first.elapsed() >= d) {
                    break;
                }
                if limits.idle_timeout.is_some_and(|t| last_at.elapsed() >= t) {
                    tracing::info!("no cloud for the idle timeout; finishing");
                    break;
                }
            }
        }
        subscriber.listener().wait(slice)?;
        // Estimates (MCAP only) once the file exists; earlier ones belong
        // to clouds that were not recorded.
        if let (Some(estimates), Some((Sink::Mcap(mcap), _))) = (&estimates, &mut writer) {
            while let Some(estimate) = estimates.receive()? {
                mcap.write_estimate(&estimate)?;
                stats.estimates += 1;
            }
        }
        while let Some(sample) = subscriber.receive()? {
            let header = *sample.header();
            let points = sample.points();
            last_at = Instant::now();
            if let Some(expected) = last_index.and_then(|last| last.checked_add(1)) {
                if header.frame_index > expected {
                    let missed = header.frame_index - expected;
                    stats.missed += missed;
                    tracing::warn!(
                        missed,
                        frame = header.frame_index,
                        "clouds were missed (recorder too slow?)"
                    );
                }
            }
            last_index = Some(header.frame_index);
            if points.len() != header.point_count() {
                stats.skipped += 1;
                tracing::warn!(
                    frame = header.frame_index,
                    "cloud with a payload that does not match its header; skipped"
                );
                continue;
            }
            let (recording, first) = match &mut writer {
                Some((recording, first)) => (recording, *first),
                None => {
                    let info = SourceInfo {
                        width: header.width,
                        height: header.height,
                        intrinsics: header.intrinsics,
                        unit_m: TOPIC_DEPTH_UNIT_M,
                        mount: args.mount.over(header.mount),
                        source: CloudSource::from_raw(header.source).unwrap_or(CloudSource::Replay),
                        has_color: header.has_color != 0,
                        sensor: sensor_of(&header).to_string(),
                    };
                    let recording = Sink::create(args, &info)?;
                    first_at = Some(Instant::now());
                    tracing::info!(
                        width = header.width,
                        height = header.height,
                        color = info.has_color,
                        sensor = info.sensor,
                        "first cloud; recording"
                    );
                    let (recording, first) = writer.insert((recording, header));
                    (recording, *first)
                }
            };
            if header.width != first.width
                || header.height != first.height
                || header.intrinsics != first.intrinsics
                || header.sensor != first.sensor
            {
                stats.skipped += 1;
                tracing::warn!(
                    frame = header.frame_index,
                    sensor = header.sensor_name(),
                    "cloud with another size, intrinsics or sensor than the first; skipped"
                );
                continue;
            }
            cloud_to_images(&header, points, TOPIC_DEPTH_UNIT_M, &mut depth, &mut color);
            match recording {
                Sink::Recording(recording) => {
                    let timestamp_ns = timeline.stamp(header.source_stamp_ns);
                    recording
                        .write_frame(timestamp_ns, &depth, color.as_ref(), None)
                        .with_context(|| {
                            format!(
                                "cannot write frame {} into {}",
                                stats.written,
                                args.out_dir().display()
                            )
                        })?;
                }
                Sink::Mcap(mcap) => mcap.write(&McapFrame {
                    stamp_ns: header.capture_stamp_ns,
                    width: header.width,
                    height: header.height,
                    depth: &depth.data,
                    depth_unit_m: TOPIC_DEPTH_UNIT_M,
                    points,
                    estimate: None,
                })?,
            }
            stats.written += 1;
            if limits.max_frames.is_some_and(|max| stats.written >= max) {
                break 'outer;
            }
        }
    }
    match writer {
        Some((mut sink, _)) => {
            if let (Some(estimates), Sink::Mcap(mcap)) = (&estimates, &mut sink) {
                // The estimates of the last clouds, published while they were written.
                let settle = Instant::now() + Duration::from_millis(300);
                while Instant::now() < settle && !stop.is_stopped() {
                    match estimates.receive()? {
                        Some(estimate) => {
                            mcap.write_estimate(&estimate)?;
                            stats.estimates += 1;
                        }
                        None => {
                            estimates.listener().wait(Duration::from_millis(50))?;
                        }
                    }
                }
            }
            sink.finish(args.out_dir())?;
        }
        None => tracing::warn!("no cloud arrived; nothing was recorded"),
    }
    Ok(stats)
}

#[cfg(feature = "kinect2")]
fn record_kinect(
    args: &RecordArgs,
    limits: &RecordLimits,
    stop: &StopFlag,
) -> anyhow::Result<RecordStats> {
    use slope_sensor::kinect2::{DeviceSelector, Kinect2Options, Kinect2Source};
    let options = Kinect2Options {
        device: args
            .serial
            .clone()
            .map_or(DeviceSelector::First, DeviceSelector::Serial),
        pipeline: args.pipeline.unwrap_or_default(),
        color: !args.depth_only,
        mount: args.mount.over(Mount::UNKNOWN),
        ..Kinect2Options::default()
    };
    let Some(mut source) =
        Kinect2Source::open(options, stop.clone()).context("cannot start the Kinect v2")?
    else {
        return Ok(RecordStats {
            stopped: true,
            ..RecordStats::default()
        });
    };
    let mut writer = RecordingWriter::create(args.out_dir(), &meta_for(source.info()), false)
        .with_context(|| format!("cannot create the recording {}", args.out_dir().display()))?;
    writer.set_compression(args.compression.into());
    tracing::info!(serial = source.serial(), out = %args.out_dir().display(), "recording the Kinect v2");
    let stats = record_source(&mut source, &mut writer, limits, stop);
    source.close();
    let stats = stats?;
    writer
        .finish()
        .with_context(|| format!("cannot finish the recording {}", args.out_dir().display()))?;
    Ok(stats)
}

#[cfg(not(feature = "kinect2"))]
fn record_kinect(_: &RecordArgs, _: &RecordLimits, _: &StopFlag) -> anyhow::Result<RecordStats> {
    anyhow::bail!(
        "this slope-record was built without the Kinect v2; rebuild with \
         `cargo build --release -p slope-tools --features kinect2` (see README \"Running on the robot\"), \
         or record the cloud topic of a running slope-capture (--source topic)"
    )
}

pub fn run(args: &RecordArgs, stop: &StopFlag) -> anyhow::Result<RecordStats> {
    let limits = RecordLimits::from_args(args);
    if args.source == RecordSource::Kinect && cfg!(not(feature = "kinect2")) {
        // Say so before touching the output directory.
        return record_kinect(args, &limits, stop);
    }
    if args.format() == RecordFormat::Mcap {
        return record_mcap(args, &limits, stop);
    }
    let created = prepare_out_dir(args.out_dir())?;
    let result = match args.source {
        RecordSource::Topic => record_topic(args, &limits, stop),
        RecordSource::Kinect => record_kinect(args, &limits, stop),
    };
    let out = args.out_dir();
    if created && is_empty_dir(out) {
        // Nothing was recorded into the directory we made: leave no trace.
        if let Err(err) = std::fs::remove_dir(out) {
            tracing::debug!(error = %err, "could not remove the empty output directory");
        }
    }
    let stats = result.map_err(|err| explain_failure(err, out, created))?;
    tracing::info!(
        written = stats.written,
        missed = stats.missed,
        skipped = stats.skipped,
        interrupted = stats.stopped,
        out = %args.out_dir().display(),
        "recording finished"
    );
    Ok(stats)
}

/// `--format mcap`: the cloud topic (and the estimates) into an MCAP file.
fn record_mcap(
    args: &RecordArgs,
    limits: &RecordLimits,
    stop: &StopFlag,
) -> anyhow::Result<RecordStats> {
    if args.source != RecordSource::Topic {
        anyhow::bail!(
            "an MCAP output (--format mcap, or a name ending in .mcap) records the cloud topic \
             only: record the Kinect into a recording (--format recording, a directory not named \
             *.mcap) and convert it with slope-convert RECORDING OUT.mcap"
        );
    }
    let out = args.out_dir();
    if out.exists() {
        anyhow::bail!(
            "{} exists; give a new file name for the MCAP file",
            out.display()
        );
    }
    check_parent(out, "")?;
    let stats = record_topic(args, limits, stop)?;
    tracing::info!(
        written = stats.written,
        estimates = stats.estimates,
        missed = stats.missed,
        interrupted = stats.stopped,
        out = %out.display(),
        "recording finished"
    );
    Ok(stats)
}

/// Refuses an output (`what` names it in the message) whose directory does
/// not exist: a typing error in a parent is said, not created.
fn check_parent(path: &Path, what: &str) -> anyhow::Result<()> {
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
    if parent.is_some_and(|p| !p.is_dir()) {
        anyhow::bail!(
            "cannot create {what}{}: its directory does not exist",
            path.display()
        );
    }
    Ok(())
}

/// A failed recording's error, saying what is left in `out`: the frames
/// recorded before (a valid recording), or nothing (a directory this run
/// `created` and whose first frame failed, a full disk, is removed).
fn explain_failure(err: anyhow::Error, out: &Path, created: bool) -> anyhow::Error {
    match frames_recorded(out) {
        Some(0) if created => match std::fs::remove_dir_all(out) {
            Ok(()) => err.context(format!(
                "no frame was recorded; {} was removed",
                out.display()
            )),
            Err(_) => err.context(format!(
                "no frame was recorded; remove {} by hand",
                out.display()
            )),
        },
        Some(frames) if frames > 0 => err.context(format!(
            "{} holds the {frames} frame(s) recorded before, a valid recording",
            out.display()
        )),
        _ => err,
    }
}

/// The frames a recording directory lists (`None` when it holds no
/// readable recording).
fn frames_recorded(dir: &Path) -> Option<usize> {
    match Recording::open(dir) {
        Ok(recording) => Some(recording.frames().len()),
        Err(_) => dir.join("recording.toml").is_file().then_some(0),
    }
}

fn is_empty_dir(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|mut entries| entries.next().is_none())
}

#[cfg(test)]
mod tests {
    use super::*;
    use slope_ipc_types::Intrinsics;
    use slope_sensor::projection::Projector;
    use slope_sensor::recording::Recording;
    use slope_sensor::source::RecordingSource;

    #[test]
    fn an_output_named_mcap_is_an_mcap_file_unless_told_otherwise() {
        let format = |args: &[&str]| {
            RecordArgs::try_parse_checked_from(["slope-record"].iter().chain(args))
                .expect("valid arguments")
                .format()
        };
        assert_eq!(format(&["-o", "new.mcap"]), RecordFormat::Mcap);
        assert_eq!(format(&["run.MCAP"]), RecordFormat::Mcap);
        assert_eq!(format(&["-o", "scene1"]), RecordFormat::Recording);
        assert_eq!(format(&["-o", "x", "--format", "mcap"]), RecordFormat::Mcap);
        let told = ["-o", "new.mcap", "--format", "recording"];
        assert_eq!(format(&told), RecordFormat::Recording);
    }

    #[test]
    fn depth_from_a_projected_cloud_is_the_original_to_the_count() {
        let intrinsics = Intrinsics {
            fx: 365.3,
            fy: 365.3,
            cx: 254.7,
            cy: 208.6,
        };
        let (width, height) = (64u32, 48u32);
        let projector = Projector::new(width, height, intrinsics, 0.001);
        let original: Vec<u16> = (0..width * height)
            .map(|i| {
                if i.is_multiple_of(13) {
                    0
                } else {
                    400 + ((i * 7919) % 11_000) as u16
                }
            })
            .collect();
        let points: Vec<CloudPoint> = original
            .iter()
            .enumerate()
            .map(|(i, &d)| projector.point(i, d, CloudPoint::pack_rgb(1, 2, (i % 256) as u8)))
            .collect();
        let header = CloudHeader {
            width,
            height,
            intrinsics,
            has_color: 1,
            ..CloudHeader::default()
        };
        let mut depth = DepthImage::default();
        let mut color = None;
        cloud_to_images(&header, &points, 0.001, &mut depth, &mut color);
        assert_eq!(depth.data, original);
        let color = color.expect("colour");
        // A point without depth carries no colour.
        for (i, (rgb, d)) in color.data.iter().zip(&original).enumerate() {
            let expected = if *d == 0 {
                [0, 0, 0]
            } else {
                [1, 2, (i % 256) as u8]
            };
            assert_eq!(*rgb, expected, "pixel {i}");
        }
    }

    #[test]
    fn recording_a_source_reproduces_it() {
        let Some(src) = ["../../../shared/data/kinect2-stairs-front"]
            .iter()
            .map(|p| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(p))
            .find(|p| p.is_dir())
        else {
            eprintln!("shared/data is not here; nothing to record");
            return;
        };
        let recording = Recording::open(&src).expect("source recording");
        let expected = recording.read_depth(&recording.frames()[0]).expect("depth");
        let mut source = RecordingSource::new(recording, false);
        let out = tempfile::tempdir().expect("tempdir");
        let dir = out.path().join("copy");
        let mut writer =
            RecordingWriter::create(&dir, &meta_for(source.info()), false).expect("writer");
        let stats = record_source(
            &mut source,
            &mut writer,
            &RecordLimits::default(),
            &StopFlag::new(),
        )
        .expect("record");
        writer.finish().expect("finish");
        assert_eq!(stats.written, 1);
        let copy = Recording::open(&dir).expect("copy");
        assert_eq!(copy.intrinsics(), source.info().intrinsics);
        assert_eq!(copy.read_depth(&copy.frames()[0]).expect("depth"), expected);
    }

    #[test]
    fn the_recorded_sensor_is_the_headers_else_the_source_kind() {
        let mut header = CloudHeader {
            source: CloudSource::Replay as u32,
            ..CloudHeader::default()
        };
        assert_eq!(sensor_of(&header), "replay");
        header.set_sensor_name("kinect1");
        assert_eq!(sensor_of(&header), "kinect1");
        header.source = CloudSource::Camera as u32;
        assert_eq!(sensor_of(&header), "kinect1");
        header.set_sensor_name("");
        assert_eq!(sensor_of(&header), "kinect2");
    }

    #[test]
    fn timestamps_start_at_zero_and_continue_across_a_jump_back() {
        let mut timeline = Timeline::new();
        assert_eq!(timeline.stamp(1_000), 0);
        assert_eq!(timeline.stamp(34_000), 33_000);
        // Back in time: one previous interval on, not frozen.
        assert_eq!(timeline.stamp(20_000), 66_000);
        // Then following the source again from there.
        assert_eq!(timeline.stamp(70_000), 116_000);
        assert_eq!(timeline.stamp(70_000), 116_000);
        assert_eq!(timeline.stamp(u64::MAX), u64::MAX);
        assert_eq!(timeline.stamp(0), u64::MAX);
    }

    #[test]
    fn depth_that_a_count_cannot_hold_is_no_reading() {
        let at = |z_m: f32| CloudPoint {
            x_m: 0.0,
            y_m: 0.0,
            z_m,
            rgb: 0,
        };
        assert_eq!(depth_count(&at(1.2344), 0.001), 1234);
        assert_eq!(depth_count(&at(65.535), 0.001), 65_535);
        assert_eq!(depth_count(&at(65.6), 0.001), 0);
        assert_eq!(depth_count(&at(1e30), 0.001), 0);
        assert_eq!(depth_count(&at(-1.0), 0.001), 0);
        assert_eq!(depth_count(&at(0.0004), 0.001), 0);
        assert_eq!(depth_count(&CloudPoint::INVALID, 0.001), 0);
    }

    #[test]
    fn the_output_directory_is_checked_before_waiting() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let fresh = tmp.path().join("a/b");
        // A missing parent (a typing error) is refused, and nothing made.
        let message = prepare_out_dir(&fresh).expect_err("no a/").to_string();
        assert!(
            message.contains("its directory does not exist"),
            "{message}"
        );
        assert!(!tmp.path().join("a").exists());
        std::fs::create_dir(tmp.path().join("a")).expect("mkdir a");
        assert!(prepare_out_dir(&fresh).expect("created"));
        assert!(fresh.is_dir());
        assert!(!prepare_out_dir(&fresh).expect("empty is fine"));
        std::fs::write(fresh.join("x"), b"x").expect("file");
        let message = prepare_out_dir(&fresh).expect_err("not empty").to_string();
        assert!(message.contains("not empty"), "{message}");
        assert!(prepare_out_dir(&fresh.join("x")).is_err());
    }

    /// A recording that failed says what is left: its first frame failed
    /// (a full disk), so the directory it made is removed; or the frames
    /// before the failure, readable.
    #[test]
    fn a_failed_recording_says_what_it_left() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let dir = tmp.path().join("rec");
        let info = SourceInfo {
            width: 2,
            height: 2,
            intrinsics: Intrinsics {
                fx: 1.0,
                fy: 1.0,
                cx: 0.5,
                cy: 0.5,
            },
            unit_m: 0.001,
            mount: Mount::UNKNOWN,
            source: CloudSource::Replay,
            has_color: false,
            sensor: "kinect2".into(),
        };
        // Its recording.toml and frames.csv header, no frame.
        RecordingWriter::create(&dir, &meta_for(&info), false).expect("create");
        let failure = || anyhow::anyhow!("cannot write frame 0: No space left on device");
        let message = format!("{:#}", explain_failure(failure(), &dir, true));
        assert!(message.contains("no frame was recorded; ") && message.contains("was removed"));
        assert!(message.contains("No space left on device"), "{message}");
        assert!(!dir.exists());

        let mut writer = RecordingWriter::create(&dir, &meta_for(&info), false).expect("again");
        let depth = DepthImage {
            width: 2,
            height: 2,
            data: vec![1000; 4],
        };
        for stamp in [0, 1] {
            writer
                .write_frame(stamp, &depth, None, None)
                .expect("frame");
        }
        let message = format!("{:#}", explain_failure(failure(), &dir, true));
        assert!(
            message.contains("holds the 2 frame(s) recorded before"),
            "{message}"
        );
        assert!(dir.join("frames.csv").is_file());
        // A directory the user gave (not made here) is left as it is.
        drop(writer);
        let message = format!("{:#}", explain_failure(failure(), tmp.path(), false));
        assert_eq!(message, "cannot write frame 0: No space left on device");
    }

    /// `--format mcap` stores the sensor of the clouds (the header's) and
    /// their intrinsics as the file's `slope.recording` metadata.
    #[test]
    fn an_mcap_recording_names_its_sensor() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let out = tmp.path().join("run.mcap");
        let args =
            RecordArgs::try_parse_checked_from(["slope-record", out.to_str().expect("utf-8")])
                .expect("args");
        let info = SourceInfo {
            width: 4,
            height: 3,
            intrinsics: Intrinsics {
                fx: 365.25,
                fy: 366.0,
                cx: 1.5,
                cy: 1.0,
            },
            unit_m: TOPIC_DEPTH_UNIT_M,
            mount: Mount::UNKNOWN,
            source: CloudSource::Camera,
            has_color: false,
            sensor: "kinect1".into(),
        };
        Sink::create(&args, &info)
            .expect("sink")
            .finish(&out)
            .expect("finish");
        let bytes = std::fs::read(&out).expect("the MCAP file");
        let summary = mcap::Summary::read(&bytes)
            .expect("summary")
            .expect("a finished file");
        let [index] = &summary.metadata_indexes[..] else {
            panic!("one metadata record: {:?}", summary.metadata_indexes);
        };
        let metadata = mcap::read::metadata(&bytes, index).expect("metadata");
        assert_eq!(metadata.name, "slope.recording");
        let value = |key: &str| metadata.metadata.get(key).map(String::as_str);
        assert_eq!(value("sensor"), Some("kinect1"));
        assert_eq!((value("width"), value("height")), (Some("4"), Some("3")));
        assert_eq!((value("fx"), value("fy")), (Some("365.25"), Some("366")));
        assert_eq!((value("cx"), value("cy")), (Some("1.5"), Some("1")));
        assert_eq!(
            value("mount_pitch_deg"),
            None,
            "an unknown mount is left out"
        );
    }

    #[test]
    fn zero_frames_is_refused_and_the_pipeline_is_parsed_early() {
        let parse = |args: &[&str]| {
            RecordArgs::try_parse_checked_from(
                std::iter::once("slope-record").chain(args.iter().copied()),
            )
        };
        assert!(parse(&["out", "--max-frames", "0"]).is_err());
        assert!(parse(&["out", "--max-frames", "1"]).is_ok());
        let flag = parse(&["-o", "out1"]).expect("-o");
        assert_eq!(flag.out_dir(), Path::new("out1"));
        let positional = parse(&["out2"]).expect("positional");
        assert_eq!(positional.out_dir(), Path::new("out2"));
        assert!(parse(&[]).is_err(), "no output");
        assert!(parse(&["-o", "a", "b"]).is_err(), "two outputs");
        #[cfg(feature = "kinect2")]
        {
            assert!(parse(&["out", "--pipeline", "vulkan"]).is_err());
            let args = parse(&["out", "--pipeline", "cpu"]).expect("args");
            assert_eq!(args.pipeline, Some(slope_sensor::kinect2::Pipeline::Cpu));
        }
    }
}
