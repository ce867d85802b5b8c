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
//!
//! | file | holds |
//! |---|---|
//! | `mod.rs` | [`run`]: which recorder runs, and what a run did ([`RecordStats`]) |
//! | `args.rs` | the command line ([`RecordArgs`]) and the limits it sets |
//! | `images.rs` | a cloud back into depth and colour images, the recording.toml of a stream |
//! | `timeline.rs` | the recording's timestamps from a source's stamps |
//! | `output.rs` | the output directory, checked (and made) before anything is waited for |
//! | `failure.rs` | what a failed recording says it left |
//! | `source.rs` | recording a frame source: the Kinect v2, a recording |
//! | `topic.rs` | the recording loop of the cloud topic |
//! | `sink.rs` | where the topic's frames go: a recording directory or an MCAP file |
//! | `mcap_output.rs` | `--format mcap`: its checks and the estimates and surfaces it writes |
//! | `writer_thread.rs` | the sink on a thread of its own, so that encoding never delays receiving |
//! | `tests.rs` | the unit tests |

mod args;
mod failure;
mod images;
mod mcap_output;
mod output;
mod sink;
mod source;
#[cfg(test)]
mod tests;
mod timeline;
mod topic;
mod writer_thread;

pub use args::{
    Compression, PipelineArg, RecordArgs, RecordFormat, RecordLimits, RecordSource, OUTPUT_MISSING,
};
pub use images::{cloud_to_images, depth_count, meta_for, sensor_of, TOPIC_DEPTH_UNIT_M};
pub use output::prepare_out_dir;
pub use source::record_source;
pub use topic::record_topic;

use slope_sensor::publish::StopFlag;

use failure::explain_failure;
use mcap_output::record_mcap;
use output::is_empty_dir;
use source::record_kinect;

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
    /// Estimates written (MCAP and ROS 2 bags only).
    pub estimates: u64,
    /// Surfaces messages written (MCAP only).
    pub surfaces: u64,
}

pub fn run(args: &RecordArgs, stop: &StopFlag) -> anyhow::Result<RecordStats> {
    let limits = RecordLimits::from_args(args);
    if args.source == RecordSource::Kinect && cfg!(not(feature = "kinect2")) {
        // Say so before touching the output directory.
        return record_kinect(args, &limits, stop);
    }
    if matches!(args.format(), RecordFormat::Mcap | RecordFormat::Rosbag2) {
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
