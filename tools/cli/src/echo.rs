//! `slope-echo`: prints every slope estimate, one line each, readable or JSON.

use std::io::Write;
use std::time::{Duration, Instant};

use clap::Parser;
use serde::Serialize;
use slope_ipc_types::{EstimateStatus, SlopeEstimate};
use slope_sensor::ipc::{create_node, EstimateSubscriber};
use slope_sensor::publish::StopFlag;

use crate::cli::{node_name, wait_loop, CommonArgs};
use crate::replay::positive_f64;

#[derive(Debug, Parser)]
#[command(
    name = "slope-echo",
    version,
    about = "Print slope estimates from the estimate topic, one line each",
    after_help = "Examples:
  slope-echo                          # readable lines until Ctrl-C
  slope-echo --json | jq .slope_deg   # one JSON object per line
  slope-echo --count 10 --timeout 5   # ten estimates, fail if they take over 5 s

JSON fields: frame, timestamp_ns (capture, ns since the Unix epoch), status, method, \
slope_deg, std_deg, distance_m, latency_ms (capture to publish), dropped_frames, \
ground_inliers, inclined_inliers, samples, ground_from_mount, processing_ms."
)]
pub struct EchoArgs {
    /// One JSON object per line instead of readable text.
    #[arg(long)]
    pub json: bool,

    /// Exit (status 0) after this many estimates.
    #[arg(long)]
    pub count: Option<u64>,

    /// Exit after this many seconds: status 0 when no --count was given,
    /// non-zero when fewer than --count estimates arrived.
    #[arg(long, value_parser = positive_f64)]
    pub timeout: Option<f64>,

    #[command(flatten)]
    pub common: CommonArgs,
}

/// The JSON form of one estimate (`slope-echo --json`).
#[derive(Debug, Serialize)]
pub struct EstimateJson {
    pub frame: u64,
    pub timestamp_ns: u64,
    pub status: &'static str,
    pub method: &'static str,
    pub slope_deg: Option<f64>,
    pub std_deg: Option<f64>,
    pub distance_m: Option<f64>,
    pub latency_ms: f64,
    pub dropped_frames: u64,
    pub ground_inliers: u32,
    pub inclined_inliers: u32,
    pub samples: u32,
    pub ground_from_mount: bool,
    pub processing_ms: f64,
}

fn finite(value: f64) -> Option<f64> {
    value.is_finite().then_some(value)
}

impl From<&SlopeEstimate> for EstimateJson {
    fn from(e: &SlopeEstimate) -> Self {
        Self {
            frame: e.frame_index,
            timestamp_ns: e.capture_stamp_ns,
            status: e.status().name(),
            method: e.method().map_or("unknown", |m| m.name()),
            slope_deg: finite(e.slope_deg),
            std_deg: finite(e.slope_std_deg),
            distance_m: finite(e.distance_m),
            latency_ms: e.latency_ms(),
            dropped_frames: e.dropped_frames,
            ground_inliers: e.ground_inliers,
            inclined_inliers: e.inclined_inliers,
            samples: e.samples,
            ground_from_mount: e.ground_from_mount != 0,
            processing_ms: e.processing_us as f64 / 1000.0,
        }
    }
}

/// The readable line for one estimate.
pub fn format_line(e: &SlopeEstimate) -> String {
    let status = e.status();
    let head = format!("frame {:>6}", e.frame_index);
    let tail = format!(
        "latency {:>6.1} ms  dropped {}",
        e.latency_ms(),
        e.dropped_frames
    );
    if status == EstimateStatus::Ok {
        let distance = if e.distance_m.is_finite() {
            format!("{:5.2} m", e.distance_m)
        } else {
            "  -   ".to_string()
        };
        format!(
            "{head}  slope {:+7.2}° ± {:5.2}°  ahead {distance}  {tail}",
            e.slope_deg, e.slope_std_deg
        )
    } else {
        format!("{head}  {:<30} {tail}", status.name())
    }
}

pub fn run(args: &EchoArgs, stop: &StopFlag) -> anyhow::Result<u64> {
    let names = args.common.service_names();
    let node = create_node(&node_name("slope-echo"))?;
    let subscriber = EstimateSubscriber::create(&node, &names)?;
    tracing::info!(service = %names.estimate(), "subscribed to estimates");

    let deadline = args
        .timeout
        .map(|s| Instant::now() + Duration::from_secs_f64(s));
    let mut received = 0u64;
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let count_reached = |received: u64| args.count.is_some_and(|c| received >= c);
    let result = wait_loop(subscriber.listener(), stop, || {
        while !count_reached(received) {
            let Some(estimate) = subscriber.receive()? else {
                break;
            };
            let line = if args.json {
                serde_json::to_string(&EstimateJson::from(&estimate))?
            } else {
                format_line(&estimate)
            };
            writeln!(out, "{line}").and_then(|()| out.flush())?;
            received += 1;
        }
        let timed_out = deadline.is_some_and(|d| Instant::now() >= d);
        Ok(!count_reached(received) && !timed_out)
    });
    if let Err(err) = result {
        // A reader that went away (`slope-echo --json | head`) is not an error.
        let closed_pipe = err
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe);
        if closed_pipe {
            return Ok(received);
        }
        return Err(err.context("slope-echo stopped"));
    }
    if let Some(count) = args.count {
        if received < count && !stop.is_stopped() {
            anyhow::bail!(
                "only {received} of {count} estimates arrived on '{}' within {} s",
                names.estimate(),
                args.timeout.unwrap_or_default()
            );
        }
    }
    Ok(received)
}
