//! Recording a frame source: the Kinect v2 (`--source kinect`), or any
//! [`FrameSource`] such as a recording.

use std::time::Instant;

use anyhow::Context;
#[cfg(feature = "kinect2")]
use slope_ipc_types::Mount;
use slope_sensor::publish::StopFlag;
use slope_sensor::recording::RecordingWriter;
use slope_sensor::source::{FrameSource, SourceFrame};

use super::args::{RecordArgs, RecordLimits};
#[cfg(feature = "kinect2")]
use super::images::meta_for;
use super::timeline::Timeline;
use super::RecordStats;

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

#[cfg(feature = "kinect2")]
pub(super) fn record_kinect(
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
pub(super) fn record_kinect(
    _: &RecordArgs,
    _: &RecordLimits,
    _: &StopFlag,
) -> anyhow::Result<RecordStats> {
    anyhow::bail!(
        "this slope-record was built without the Kinect v2; rebuild with \
         `cargo build --release -p slope-tools --features kinect2` (see README \"Running on the robot\"), \
         or record the cloud topic of a running slope-capture (--source topic)"
    )
}
