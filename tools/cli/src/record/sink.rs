//! Where the topic's frames go: a recording directory
//! ([`RecordingWriter`], stamped by a [`Timeline`]) or an MCAP file
//! ([`McapExporter`]) or a ROS 2 bag (an MCAP file too, [`Rosbag2Exporter`]).

use std::path::Path;

use anyhow::Context;
use slope_ipc_types::{CloudHeader, CloudPoint};
use slope_sensor::recording::{ColorImage, DepthImage, RecordingWriter};
use slope_sensor::source::SourceInfo;

use super::args::{RecordArgs, RecordFormat};
use super::images::{meta_for, TOPIC_DEPTH_UNIT_M};
use super::timeline::Timeline;
use crate::export_format::FrameExporter;
use crate::mcap_export::{McapExporter, McapFrame};
use crate::rosbag2_export::Rosbag2Exporter;

/// Where the topic's frames go.
pub(super) enum Sink {
    Recording(Box<RecordingWriter>, Timeline),
    /// `--format mcap` or `rosbag2`.
    Mcap(Box<FrameExporter>),
}

impl Sink {
    /// Creates the sink of `args` for clouds described by `info`.
    pub(super) fn create(args: &RecordArgs, info: &SourceInfo) -> anyhow::Result<Self> {
        let out = args.out_dir();
        Ok(match args.format() {
            RecordFormat::Recording => {
                let mut recording = RecordingWriter::create(out, &meta_for(info), false)
                    .with_context(|| format!("cannot create the recording {}", out.display()))?;
                recording.set_compression(args.compression.into());
                Sink::Recording(Box::new(recording), Timeline::new())
            }
            RecordFormat::Mcap => Sink::Mcap(Box::new(FrameExporter::Mcap(Box::new(
                McapExporter::create(out, args.mcap_compression, &meta_for(info))?,
            )))),
            RecordFormat::Rosbag2 => Sink::Mcap(Box::new(FrameExporter::Rosbag2(Box::new(
                Rosbag2Exporter::create(out, args.mcap_compression, &meta_for(info), false)?,
            )))),
        })
    }

    /// Writes the cloud of `header` (`points`), whose depth and colour
    /// images are `depth` and `color`: as the `written`-th frame of the
    /// recording `out`, or as the MCAP file's depth image and cloud.
    pub(super) fn write(
        &mut self,
        header: &CloudHeader,
        points: &[CloudPoint],
        depth: &DepthImage,
        color: Option<&ColorImage>,
        written: u64,
        out: &Path,
    ) -> anyhow::Result<()> {
        match self {
            Sink::Recording(recording, timeline) => {
                let timestamp_ns = timeline.stamp(header.source_stamp_ns);
                recording
                    .write_frame(timestamp_ns, depth, color, None)
                    .with_context(|| {
                        format!("cannot write frame {written} into {}", out.display())
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
                surfaces: None,
            })?,
        }
        Ok(())
    }

    pub(super) fn finish(self, out: &Path) -> anyhow::Result<()> {
        match self {
            Sink::Recording(recording, _) => recording
                .finish()
                .map(drop)
                .with_context(|| format!("cannot finish the recording {}", out.display())),
            Sink::Mcap(mcap) => mcap.finish(),
        }
    }
}
