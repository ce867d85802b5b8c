//! The recording loop of the cloud topic: waits for clouds within the
//! limits, rebuilds each one's images and hands them to the [`Sink`]
//! opened at the first cloud (with the estimates and surfaces, for an MCAP
//! file).

use std::time::{Duration, Instant};

use anyhow::Context;
use slope_ipc_types::{CloudHeader, CloudPoint, CloudSource};
use slope_sensor::ipc::{create_node, CloudSubscriber};
use slope_sensor::publish::StopFlag;
use slope_sensor::recording::{ColorImage, DepthImage};
use slope_sensor::source::SourceInfo;

use super::args::{RecordArgs, RecordFormat, RecordLimits};
use super::images::{cloud_to_images, sensor_of, TOPIC_DEPTH_UNIT_M};
use super::mcap_output::Messages;
use super::sink::Sink;
use super::writer_thread::{QueuedFrame, SinkThread, Written};
use super::RecordStats;
use crate::cli::node_name;

/// Records the cloud topic until a limit is reached or `stop` is set.
pub fn record_topic(
    args: &RecordArgs,
    limits: &RecordLimits,
    stop: &StopFlag,
) -> anyhow::Result<RecordStats> {
    let names = args.common.service_names(stop)?;
    let node = create_node(&node_name("slope-record"))?;
    let subscriber =
        CloudSubscriber::create_deep(&node, &names).context("cannot subscribe to clouds")?;
    let messages = Messages::create(&node, &names, args.format())?;
    tracing::info!(service = subscriber.service_name(), out = %args.out_dir().display(), "recording the cloud topic");

    let mut recorder = TopicRecorder::new(args, limits);
    let slice = Duration::from_millis(100);
    loop {
        if stop.is_stopped() {
            recorder.stats.stopped = true;
            break;
        }
        if recorder.limit_reached(subscriber.service_name())? {
            break;
        }
        subscriber.listener().wait(slice)?;
        let received = recorder
            .write_messages(messages.as_ref())
            .and_then(|()| recorder.receive_clouds(&subscriber));
        match received {
            Ok(true) => break,
            Ok(false) => {}
            Err(err) => return Err(recorder.fail(err)),
        }
    }
    recorder.finish(messages.as_ref(), stop)
}

/// The state of [`record_topic`]: the sink (opened at the first cloud,
/// with that cloud's header), the images rebuilt from each cloud and the
/// times the limits are measured from.
struct TopicRecorder<'a> {
    args: &'a RecordArgs,
    limits: &'a RecordLimits,
    stats: RecordStats,
    writer: Option<(SinkThread, CloudHeader)>,
    depth: DepthImage,
    color: Option<ColorImage>,
    last_index: Option<u64>,
    waiting_since: Instant,
    first_at: Option<Instant>,
    last_at: Instant,
}

impl<'a> TopicRecorder<'a> {
    fn new(args: &'a RecordArgs, limits: &'a RecordLimits) -> Self {
        Self {
            args,
            limits,
            stats: RecordStats::default(),
            writer: None,
            depth: DepthImage::default(),
            color: None,
            last_index: None,
            waiting_since: Instant::now(),
            first_at: None,
            last_at: Instant::now(),
        }
    }

    /// Whether --duration-s or --idle-timeout-s ends the recording; an
    /// error when no cloud came on `service` within --wait-timeout-s.
    fn limit_reached(&self, service: &str) -> anyhow::Result<bool> {
        let limits = self.limits;
        match self.first_at {
            None => {
                if let Some(timeout) = limits.wait_timeout {
                    if self.waiting_since.elapsed() >= timeout {
                        anyhow::bail!(
                            "no cloud arrived on '{}' within {:.1} s; is a source (slope-capture, \
                             slope-replay) running with the same --service-prefix?",
                            service,
                            timeout.as_secs_f64()
                        );
                    }
                }
            }
            Some(first) => {
                if limits.duration.is_some_and(|d| first.elapsed() >= d) {
                    return Ok(true);
                }
                if limits
                    .idle_timeout
                    .is_some_and(|t| self.last_at.elapsed() >= t)
                {
                    tracing::info!("no cloud for the idle timeout; finishing");
                    return Ok(true);
                }
            }
        }
        Ok(false)
    }

    /// Estimates and surfaces (MCAP only) once the file exists; earlier
    /// ones belong to clouds that were not recorded.
    fn write_messages(&mut self, messages: Option<&Messages>) -> anyhow::Result<()> {
        if let (Some(messages), Some((writer, _))) = (messages, &self.writer) {
            let queued = messages.write(writer)?;
            self.stats.estimates += queued.estimates;
            self.stats.surfaces += queued.surfaces;
        }
        Ok(())
    }

    /// Records the clouds received so far; true once --max-frames are.
    fn receive_clouds(&mut self, subscriber: &CloudSubscriber) -> anyhow::Result<bool> {
        while let Some(sample) = subscriber.receive()? {
            if self.record_cloud(sample.header(), sample.points())? {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// Records one cloud (skipped when its payload or layout is not the
    /// first's); true once --max-frames are recorded.
    fn record_cloud(
        &mut self,
        header: &CloudHeader,
        points: &[CloudPoint],
    ) -> anyhow::Result<bool> {
        self.last_at = Instant::now();
        self.count_missed(header);
        if points.len() != header.point_count() {
            self.stats.skipped += 1;
            tracing::warn!(
                frame = header.frame_index,
                "cloud with a payload that does not match its header; skipped"
            );
            return Ok(false);
        }
        let (writer, first) = match &mut self.writer {
            Some((writer, first)) => (writer, *first),
            None => {
                let sink = open_sink(self.args, header)?;
                let writer = SinkThread::spawn(sink, self.args.out_dir().to_path_buf())?;
                self.first_at = Some(Instant::now());
                let (writer, first) = self.writer.insert((writer, *header));
                (writer, *first)
            }
        };
        if !same_layout(header, &first) {
            self.stats.skipped += 1;
            tracing::warn!(
                frame = header.frame_index,
                sensor = header.sensor_name(),
                "cloud with another size, intrinsics or sensor than the first; skipped"
            );
            return Ok(false);
        }
        cloud_to_images(
            header,
            points,
            TOPIC_DEPTH_UNIT_M,
            &mut self.depth,
            &mut self.color,
        );
        let frame = QueuedFrame {
            header: *header,
            points: match self.args.format() {
                RecordFormat::Mcap => points.to_vec(),
                // A ROS 2 bag holds the depth image, not the cloud.
                RecordFormat::Recording | RecordFormat::Rosbag2 => Vec::new(),
            },
            depth: self.depth.clone(),
            color: self.color.clone(),
        };
        if !writer.write(frame) {
            anyhow::bail!("the recorder's writer stopped");
        }
        self.stats.written += 1;
        Ok(self
            .limits
            .max_frames
            .is_some_and(|max| self.stats.written >= max))
    }

    /// Counts (and warns of) the clouds between the last one and `header`.
    fn count_missed(&mut self, header: &CloudHeader) {
        if let Some(expected) = self.last_index.and_then(|last| last.checked_add(1)) {
            if header.frame_index > expected {
                let missed = header.frame_index - expected;
                self.stats.missed += missed;
                tracing::warn!(
                    missed,
                    frame = header.frame_index,
                    "clouds were missed (recorder too slow?)"
                );
            }
        }
        self.last_index = Some(header.frame_index);
    }

    /// The error of a write that failed (a full disk, the file-size limit),
    /// saying what the output holds: see [`explain_written`].
    fn fail(self, err: anyhow::Error) -> anyhow::Error {
        match self.writer {
            None => err,
            Some((writer, _)) => match writer.join() {
                Ok(written) => explain_written(self.args, err, written),
                Err(join) => join.context(err.to_string()),
            },
        }
    }

    /// Writes the last estimates and surfaces (MCAP), waits for the writer and finishes
    /// the sink, if a cloud opened one.
    fn finish(
        mut self,
        messages: Option<&Messages>,
        stop: &StopFlag,
    ) -> anyhow::Result<RecordStats> {
        let Some((writer, _)) = &self.writer else {
            tracing::warn!("no cloud arrived; nothing was recorded");
            return Ok(self.stats);
        };
        if let Some(messages) = messages {
            match messages.settle(writer, stop) {
                Ok(settled) => {
                    self.stats.estimates += settled.estimates;
                    self.stats.surfaces += settled.surfaces;
                }
                Err(err) => return Err(self.fail(err)),
            }
        }
        let args = self.args;
        let Some((writer, _)) = self.writer.take() else {
            return Ok(self.stats);
        };
        let written = writer.join()?;
        if written.result.is_err() {
            return Err(explain_written(
                args,
                anyhow::anyhow!("the recorder's writer failed"),
                written,
            ));
        }
        written.sink.finish(args.out_dir())?;
        Ok(self.stats)
    }
}

/// A failed recording's error: the writer's own (when it failed) saying
/// what an MCAP file holds: its summary and footer are written if they
/// still fit (a finished file of the frames before), else the file is an
/// unfinished one. A recording directory is explained by the caller
/// (`failure.rs`).
fn explain_written(args: &RecordArgs, err: anyhow::Error, written: Written) -> anyhow::Error {
    let Written {
        sink,
        frames,
        result,
    } = written;
    let err = match result {
        Err(writing) => writing,
        Ok(()) => err,
    };
    let Sink::Mcap(mcap) = sink else {
        return err;
    };
    let out = args.out_dir().display();
    match mcap.finish() {
        Ok(()) => err.context(format!(
            "{out} holds the {frames} frame(s) recorded before, a finished MCAP file"
        )),
        Err(finish) => err.context(format!(
            "{out} holds the {frames} frame(s) recorded before, unfinished: no MCAP summary \
             or footer ({finish:#}); a reader that recovers unfinished files (mcap recover) \
             reads them"
        )),
    }
}

/// The sink of `args` for the clouds of `header`, the first one.
fn open_sink(args: &RecordArgs, header: &CloudHeader) -> anyhow::Result<Sink> {
    let info = SourceInfo {
        width: header.width,
        height: header.height,
        intrinsics: header.intrinsics,
        unit_m: TOPIC_DEPTH_UNIT_M,
        mount: args.mount.over(header.mount),
        source: CloudSource::from_raw(header.source).unwrap_or(CloudSource::Replay),
        has_color: header.has_color != 0,
        sensor: sensor_of(header).to_string(),
    };
    let sink = Sink::create(args, &info)?;
    tracing::info!(
        width = header.width,
        height = header.height,
        color = info.has_color,
        sensor = info.sensor,
        "first cloud; recording"
    );
    Ok(sink)
}

/// Whether a cloud has the size, intrinsics and sensor of the first.
fn same_layout(header: &CloudHeader, first: &CloudHeader) -> bool {
    header.width == first.width
        && header.height == first.height
        && header.intrinsics == first.intrinsics
        && header.sensor == first.sensor
}
