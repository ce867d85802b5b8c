//! `--format mcap`: the checks before an MCAP recording, and the estimates
//! and surfaces it writes beside the clouds (those received meanwhile, and
//! those of the last clouds, which arrive after them).

use std::time::{Duration, Instant};

use anyhow::Context;
use iceoryx2::prelude::*;
use slope_ipc_types::ServiceNames;
use slope_sensor::ipc::{EstimateSubscriber, SurfacesSubscriber};
use slope_sensor::publish::StopFlag;

use super::args::{RecordArgs, RecordFormat, RecordLimits, RecordSource};
use super::output::check_parent;
use super::topic::record_topic;
use super::writer_thread::SinkThread;
use super::RecordStats;

/// `--format mcap`: the cloud topic (and the estimates) into an MCAP file.
pub(super) fn record_mcap(
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
            "{} exists; give a new name for the MCAP file (or the rosbag2 directory)",
            out.display()
        );
    }
    check_parent(out, "")?;
    let stats = record_topic(args, limits, stop)?;
    tracing::info!(
        written = stats.written,
        estimates = stats.estimates,
        surfaces = stats.surfaces,
        missed = stats.missed,
        interrupted = stats.stopped,
        out = %out.display(),
        "recording finished"
    );
    Ok(stats)
}

/// What an MCAP recording writes beside the clouds: the estimator's
/// estimates and, for `--format mcap`, its surfaces (a ROS 2 bag has no
/// surfaces topic).
pub(super) struct Messages {
    estimates: EstimateSubscriber,
    surfaces: Option<SurfacesSubscriber>,
}

/// How many messages [`Messages`] queued.
#[derive(Debug, Default, Clone, Copy)]
pub(super) struct Queued {
    pub estimates: u64,
    pub surfaces: u64,
}

impl std::ops::AddAssign for Queued {
    fn add_assign(&mut self, other: Self) {
        self.estimates += other.estimates;
        self.surfaces += other.surfaces;
    }
}

impl Messages {
    /// The subscribers of `format` (none for a recording directory).
    pub(super) fn create(
        node: &Node<ipc::Service>,
        names: &ServiceNames,
        format: RecordFormat,
    ) -> anyhow::Result<Option<Self>> {
        let surfaces = match format {
            RecordFormat::Recording => return Ok(None),
            RecordFormat::Rosbag2 => None,
            RecordFormat::Mcap => Some(
                SurfacesSubscriber::create(node, names)
                    .context("cannot subscribe to the surfaces")?,
            ),
        };
        let estimates =
            EstimateSubscriber::create(node, names).context("cannot subscribe to estimates")?;
        Ok(Some(Self {
            estimates,
            surfaces,
        }))
    }

    /// Queues the messages received so far for `writer`.
    pub(super) fn write(&self, writer: &SinkThread) -> anyhow::Result<Queued> {
        let mut queued = Queued::default();
        while let Some(estimate) = self.estimates.receive()? {
            if !writer.write_estimate(estimate) {
                anyhow::bail!("the recorder's writer stopped");
            }
            queued.estimates += 1;
        }
        if let Some(subscriber) = &self.surfaces {
            while let Some(surfaces) = subscriber.receive()? {
                if !writer.write_surfaces(surfaces) {
                    anyhow::bail!("the recorder's writer stopped");
                }
                queued.surfaces += 1;
            }
        }
        Ok(queued)
    }

    /// Writes the messages of the last clouds, published while they were
    /// written, for up to 300 ms (less when `stop` is set).
    pub(super) fn settle(&self, writer: &SinkThread, stop: &StopFlag) -> anyhow::Result<Queued> {
        let mut queued = Queued::default();
        let settle = Instant::now() + Duration::from_millis(300);
        while Instant::now() < settle && !stop.is_stopped() {
            queued += self.write(writer)?;
            self.estimates.listener().wait(Duration::from_millis(50))?;
        }
        queued += self.write(writer)?;
        Ok(queued)
    }
}
