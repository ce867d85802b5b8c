//! `--format mcap`: the checks before an MCAP recording, and the estimates
//! it writes beside the clouds (those received meanwhile, and those of the
//! last clouds, which arrive after them).

use std::time::{Duration, Instant};

use slope_sensor::ipc::EstimateSubscriber;
use slope_sensor::publish::StopFlag;

use super::args::{RecordArgs, RecordLimits, RecordSource};
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
        missed = stats.missed,
        interrupted = stats.stopped,
        out = %out.display(),
        "recording finished"
    );
    Ok(stats)
}

/// Queues the estimates received so far for `writer`; returns how many.
pub(super) fn write_estimates(
    estimates: &EstimateSubscriber,
    writer: &SinkThread,
) -> anyhow::Result<u64> {
    let mut written = 0;
    while let Some(estimate) = estimates.receive()? {
        if !writer.write_estimate(estimate) {
            anyhow::bail!("the recorder's writer stopped");
        }
        written += 1;
    }
    Ok(written)
}

/// Writes the estimates of the last clouds, published while they were
/// written, for up to 300 ms (less when `stop` is set); returns how many.
pub(super) fn settle_estimates(
    estimates: &EstimateSubscriber,
    writer: &SinkThread,
    stop: &StopFlag,
) -> anyhow::Result<u64> {
    let mut written = 0;
    let settle = Instant::now() + Duration::from_millis(300);
    while Instant::now() < settle && !stop.is_stopped() {
        written += write_estimates(estimates, writer)?;
        estimates.listener().wait(Duration::from_millis(50))?;
    }
    Ok(written)
}
