//! `slope-estimator`: subscribes to clouds, estimates the slope of the newest
//! one, publishes a `SlopeEstimate` per processed frame.
//!
//! It sleeps in an iceoryx2 `WaitSet` until the cloud event fires (no busy
//! polling), then takes the newest cloud waiting and drops older ones, so it
//! never falls behind the camera. The cloud is read in place from the
//! publisher's shared memory: the pipeline borrows the sample's slice.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Parser;
use slope_ipc_types::{HealthComponent, SlopeEstimate, SlopeMethod};
use slope_pipeline::{parse_method, CloudView, Estimator, EstimatorConfig, FrameInfo};
use slope_sensor::ipc::{create_node, CloudSubscriber, EstimatePublisher, HealthPublisher};
use slope_sensor::publish::StopFlag;

use crate::cli::{node_name, wait_loop, CommonArgs, SilenceNote};
use crate::health::{HealthReporter, DEFAULT_HEALTH_INTERVAL_S};
use crate::service_manager::ServiceManager;

#[derive(Debug, Parser)]
#[command(
    name = "slope-estimator",
    version,
    about = "Estimate the road slope from the cloud topic and publish it on the estimate topic",
    long_about = "Subscribes to organised point clouds (from slope-capture or slope-replay), runs the \
estimator on the newest frame and publishes one SlopeEstimate per processed frame. Frames that \
arrive while a frame is being processed are superseded by the newest one and counted as dropped. \
Stops cleanly on SIGINT or SIGTERM.",
    after_help = "Examples:
  slope-estimator                              # parameters from /etc/slope/slope.toml if it exists, else the defaults
  slope-estimator --method tls                 # total-least-squares baseline
  slope-estimator --config estimator.toml      # parameters from a TOML file
  slope-estimator --config estimator.toml --print-config   # every parameter in effect, then exit
  slope-estimator --service-prefix robot2 -v   # another stack, debug logs

Health: a report on <prefix>/health every --health-interval-s seconds (frames in/out/dropped, \
rates, capture-to-publish latency and per-stage median/p95/max ms over that interval, the last \
error); `slope-echo --health` shows it. The same summary over 10 s goes to the log at INFO."
)]
pub struct EstimatorArgs {
    /// Fit used for the planes: paper (normals, cosine k-means, cumulative
    /// averaging), least-squares, or tls. Overrides the config file.
    #[arg(long, value_parser = method_arg)]
    pub method: Option<SlopeMethod>,

    /// TOML file with estimator parameters (see the pipeline README);
    /// missing keys keep the paper's defaults. Without it the estimator
    /// reads /etc/slope/slope.toml if that exists.
    #[arg(long)]
    pub config: Option<PathBuf>,

    /// Stop after publishing this many estimates.
    #[arg(long)]
    pub max_frames: Option<u64>,

    /// Print every parameter in effect (the config file's, the defaults for
    /// keys it leaves out, and --method) as TOML and exit, without
    /// connecting to anything: what the daemon would run with.
    #[arg(long)]
    pub print_config: bool,

    /// Seconds between health reports on the topic PREFIX/health (0: none, the
    /// summary is still logged every 10 s).
    #[arg(
        long = "health-interval-s",
        alias = "health-interval",
        default_value_t = DEFAULT_HEALTH_INTERVAL_S,
        value_parser = health_interval_arg
    )]
    pub health_interval: f64,

    #[command(flatten)]
    pub common: CommonArgs,
}

/// `--health-interval-s`: 0 (off) or 0.05-3600 seconds.
pub fn health_interval_arg(text: &str) -> Result<f64, String> {
    let value: f64 = text
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    if value == 0.0 || (0.05..=3600.0).contains(&value) {
        Ok(value)
    } else {
        Err(format!(
            "'{text}' must be 0 (no reports) or from 0.05 to 3600 seconds"
        ))
    }
}

pub fn method_arg(text: &str) -> Result<SlopeMethod, String> {
    parse_method(text)
        .ok_or_else(|| format!("unknown method '{text}': expected paper, least-squares or tls"))
}

/// The file the estimator reads when not given `--config`, if it exists
/// (the Debian package installs it, every key commented out).
pub const DEFAULT_CONFIG_PATH: &str = "/etc/slope/slope.toml";

/// The config file to read: `given` (`--config`), else `default` if it
/// exists. A `default` that cannot even be looked at (a directory without
/// permission) is returned too, so that reading it fails with a message
/// rather than the defaults being used silently.
pub fn config_path(given: Option<&Path>, default: &Path) -> Option<PathBuf> {
    match given {
        Some(path) => Some(path.to_path_buf()),
        None => match default.try_exists() {
            Ok(false) => None,
            Ok(true) | Err(_) => Some(default.to_path_buf()),
        },
    }
}

/// Reads the configuration file (if any) and applies command-line overrides.
pub fn load_config(
    path: Option<&PathBuf>,
    method: Option<SlopeMethod>,
) -> anyhow::Result<EstimatorConfig> {
    let mut config = match path {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read estimator config {}", path.display()))?;
            EstimatorConfig::from_toml_str(&text)
                .with_context(|| format!("invalid estimator config {}", path.display()))?
        }
        None => EstimatorConfig::default(),
    };
    if let Some(method) = method {
        config.method = method;
    }
    config.validate().context("invalid estimator config")?;
    Ok(config)
}

/// What the estimator did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct EstimatorStats {
    pub processed: u64,
    pub dropped: u64,
}

/// The configuration as TOML, every key (a config file for the estimator).
pub fn config_toml(config: &EstimatorConfig) -> anyhow::Result<String> {
    toml::to_string(config).context("cannot write the configuration as TOML")
}

pub fn run(args: &EstimatorArgs, stop: &StopFlag) -> anyhow::Result<EstimatorStats> {
    let path = config_path(args.config.as_deref(), Path::new(DEFAULT_CONFIG_PATH));
    let config = load_config(path.as_ref(), args.method)?;
    match &path {
        Some(path) => tracing::info!(config = %path.display(), "estimator parameters loaded"),
        None => tracing::info!("no {DEFAULT_CONFIG_PATH} and no --config: default parameters"),
    }
    if args.print_config {
        print!("{}", config_toml(&config)?);
        return Ok(EstimatorStats::default());
    }
    let names = args.common.service_names();
    let node = create_node(&node_name("slope-estimator"))?;
    let subscriber = CloudSubscriber::create(&node, &names)?;
    let publisher = EstimatePublisher::create(&node, &names)?;
    let health_publisher = if args.health_interval > 0.0 {
        Some(HealthPublisher::create(&node, &names)?)
    } else {
        None
    };
    tracing::info!(
        method = config.method.name(),
        clouds = subscriber.service_name(),
        estimates = %names.estimate(),
        "estimator ready"
    );
    let mut worker = Worker {
        estimator: Estimator::new(config),
        subscriber: &subscriber,
        publisher: &publisher,
        stats: EstimatorStats::default(),
        last_index: None,
        last_slope_deg: None,
        max_frames: args.max_frames,
        health: HealthReporter::new(
            HealthComponent::Estimator,
            health_publisher,
            args.health_interval,
        ),
    };
    let mut silence = SilenceNote::new(
        "cloud",
        subscriber.service_name(),
        "slope-capture or slope-replay",
    );
    let mut manager = ServiceManager::from_env();
    manager.ready("waiting for clouds");
    let started = Instant::now();
    let result = wait_loop(subscriber.listener(), stop, || {
        let processed = worker.stats.processed;
        worker.on_cloud_event()?;
        if worker.stats.processed > processed {
            silence.heard();
        }
        silence.tick();
        manager.tick(|| worker.status_line(started.elapsed()));
        worker.health.tick();
        Ok(!worker.done())
    });
    manager.stopping();
    result?;
    tracing::info!(
        processed = worker.stats.processed,
        dropped = worker.stats.dropped,
        "estimator stopped"
    );
    Ok(worker.stats.clone())
}

struct Worker<'a> {
    estimator: Estimator,
    subscriber: &'a CloudSubscriber,
    publisher: &'a EstimatePublisher,
    stats: EstimatorStats,
    last_index: Option<u64>,
    /// The last `ok` slope, degrees.
    last_slope_deg: Option<f64>,
    max_frames: Option<u64>,
    health: HealthReporter,
}

impl Worker<'_> {
    /// `30 frames in 1.0 s (30.0 fps), 0 dropped, last slope +16.01°`.
    fn status_line(&self, elapsed: std::time::Duration) -> String {
        let s = &self.stats;
        let fps = s.processed as f64 / elapsed.as_secs_f64().max(1e-3);
        let last = match self.last_slope_deg {
            Some(slope) => format!("{slope:+.2}°"),
            None => "-".to_string(),
        };
        format!(
            "{} frames in {:.0} s ({fps:.1} fps), {} dropped, last slope {last}",
            s.processed,
            elapsed.as_secs_f64(),
            s.dropped
        )
    }

    fn done(&self) -> bool {
        self.max_frames
            .is_some_and(|max| self.stats.processed >= max)
    }

    fn on_cloud_event(&mut self) -> anyhow::Result<()> {
        let (sample, skipped) = self.subscriber.receive_newest()?;
        let Some(sample) = sample else {
            return Ok(());
        };
        let header = *sample.header();
        let points = sample.points();
        // Frames the queue overwrote before we saw them show up as gaps.
        let gap = match self.last_index {
            Some(last) if header.frame_index > last => header.frame_index - last - 1,
            _ => 0,
        };
        let missed = gap.max(skipped);
        if missed > 0 {
            tracing::debug!(frame = header.frame_index, missed, "dropped stale clouds");
        }
        self.stats.dropped += missed;
        self.health.monitor.frames_in(1 + missed);
        self.health.monitor.dropped(missed);
        self.last_index = Some(header.frame_index);
        tracing::debug!(
            frame = header.frame_index,
            points = points.len(),
            payload_addr = format_args!("{:#x}", points.as_ptr() as usize),
            "processing cloud in place"
        );
        let view = CloudView::from_header(&header, points);
        // The frame index seeds this frame's random draws; the tracker
        // follows the slope over the stream.
        let frame = FrameInfo {
            index: header.frame_index,
            stamp_ns: header.capture_stamp_ns,
        };
        let estimate = self.estimator.estimate_frame(&view, frame);
        let mut message = SlopeEstimate {
            frame_index: header.frame_index,
            capture_stamp_ns: header.capture_stamp_ns,
            source_stamp_ns: header.source_stamp_ns,
            dropped_frames: self.stats.dropped,
            ..SlopeEstimate::default()
        };
        estimate.write_message(&mut message);
        if estimate.slope_deg.is_finite() {
            self.last_slope_deg = Some(estimate.slope_deg);
        }
        drop(sample);
        let sent = self.publisher.publish(&message)?;
        self.stats.processed += 1;
        let mut stages = estimate.timings.stages.clone();
        stages.push(("total", estimate.timings.total_ms));
        self.health
            .monitor
            .frame_out(Some(sent.latency_ms()), &stages);
        tracing::debug!(
            frame = sent.frame_index,
            status = sent.status().name(),
            slope_deg = sent.slope_deg,
            confidence = sent.confidence,
            tracked_slope_deg = sent.tracked_slope_deg,
            ms = estimate.timings.total_ms,
            "published estimate"
        );
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_config_the_default_file_is_read_when_it_exists() {
        let dir = tempfile::tempdir().expect("temp dir");
        let default = dir.path().join("slope.toml");
        assert_eq!(config_path(None, &default), None);
        assert_eq!(
            load_config(config_path(None, &default).as_ref(), None).expect("defaults"),
            EstimatorConfig::default()
        );
        std::fs::write(&default, "seed = 7\n[ransac]\nmax_planes = 12\n").expect("write");
        assert_eq!(config_path(None, &default), Some(default.clone()));
        let config = load_config(config_path(None, &default).as_ref(), None).expect("config");
        assert_eq!((config.seed, config.ransac.max_planes), (7, 12));
        // --config wins, and is read even when it does not exist (an error).
        let given = dir.path().join("other.toml");
        assert_eq!(config_path(Some(&given), &default), Some(given.clone()));
        let err = load_config(Some(&given), None).expect_err("no such file");
        assert!(format!("{err:#}").contains("other.toml"), "{err:#}");
    }
}
