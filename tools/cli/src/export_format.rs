//! What `slope-convert` writes (`--format`): an MCAP file for Foxglove
//! ([`McapExporter`]) or a ROS 2 bag ([`Rosbag2Exporter`]), behind one
//! [`FrameExporter`].

use std::path::Path;

use slope_ipc_types::{SlopeEstimate, Surfaces};
use slope_sensor::recording::RecordingMeta;

use crate::mcap_export::{McapCompression, McapExporter, McapFrame};
use crate::rosbag2_export::Rosbag2Exporter;

/// The output format of `slope-convert`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ExportFormat {
    /// One MCAP file with JSON messages (Foxglove): depth, cloud, estimates.
    #[default]
    Mcap,
    /// A ROS 2 bag directory (metadata.yaml and an MCAP file, CDR
    /// messages): depth, camera info, estimates, the mount on /tf_static.
    Rosbag2,
}

/// An output being written, of either format.
pub enum FrameExporter {
    Mcap(Box<McapExporter>),
    Rosbag2(Box<Rosbag2Exporter>),
}

impl FrameExporter {
    /// Writes into a temporary file beside (MCAP) or inside (rosbag2)
    /// `path` that [`Self::finish`] renames into place.
    pub fn create_replacing(
        format: ExportFormat,
        path: &Path,
        compression: McapCompression,
        meta: &RecordingMeta,
    ) -> anyhow::Result<Self> {
        Ok(match format {
            ExportFormat::Mcap => Self::Mcap(Box::new(McapExporter::create_replacing(
                path,
                compression,
                meta,
            )?)),
            ExportFormat::Rosbag2 => Self::Rosbag2(Box::new(Rosbag2Exporter::create(
                path,
                compression,
                meta,
                true,
            )?)),
        })
    }

    /// Writes one frame's messages.
    pub fn write(&mut self, frame: &McapFrame<'_>) -> anyhow::Result<()> {
        match self {
            Self::Mcap(mcap) => mcap.write(frame),
            Self::Rosbag2(bag) => bag.write(frame),
        }
    }

    /// Writes an estimate, stamped with its frame's capture time.
    pub fn write_estimate(&mut self, estimate: &SlopeEstimate) -> anyhow::Result<()> {
        match self {
            Self::Mcap(mcap) => mcap.write_estimate(estimate),
            Self::Rosbag2(bag) => bag.write_estimate(estimate),
        }
    }

    /// Writes a frame's surfaces, stamped with its capture time (MCAP:
    /// `/slope/surfaces`; a ROS 2 bag has no surfaces topic and skips them).
    pub fn write_surfaces(&mut self, surfaces: &Surfaces) -> anyhow::Result<()> {
        match self {
            Self::Mcap(mcap) => mcap.write_surfaces(surfaces),
            Self::Rosbag2(_) => Ok(()),
        }
    }

    /// Finishes the output and puts it in place.
    pub fn finish(self) -> anyhow::Result<()> {
        match self {
            Self::Mcap(mcap) => mcap.finish(),
            Self::Rosbag2(bag) => bag.finish(),
        }
    }
}
