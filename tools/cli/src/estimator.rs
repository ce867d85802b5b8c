//! `slope-estimator`: subscribes to clouds, estimates the slope of the newest
//! one, publishes a `SlopeEstimate` per processed frame.
//!
//! It sleeps in an iceoryx2 `WaitSet` until the cloud event fires (no busy
//! polling), then takes the newest cloud waiting and drops older ones, so it
//! never falls behind the camera. The cloud is read in place from the
//! publisher's shared memory: the pipeline borrows the sample's slice.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Parser;
use slope_ipc_types::{
    CloudHeader, HealthComponent, ServiceNames, SlopeEstimate, SlopeMethod,
    DEFAULT_MAX_CLOUD_POINTS, SENSOR_NAME_LEN,
};
use slope_pipeline::tracking::StreamPosition;
use slope_pipeline::{parse_method, CloudView, Estimator, EstimatorConfig, FrameInfo};
use slope_sensor::cloud_checks::check_cloud;
use slope_sensor::ipc::{
    create_node, CloudSubscriber, EstimatePublisher, HealthPublisher, SurfacesPublisher,
};
use slope_sensor::publish::StopFlag;

use crate::cli::{max_frames_arg, node_name, read_settings, wait_loop, CommonArgs, SilenceNote};
use crate::config_file::{check_health_interval, config_path, SlopeFile, DEFAULT_CONFIG_PATH};
use crate::health::HealthReporter;
use crate::rejected_clouds::RejectedClouds;
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
  slope-estimator                              # /etc/slope/slope.toml if present, else defaults
  slope-estimator --method tls                 # total-least-squares baseline
  slope-estimator --config slope.toml          # settings from another file
  slope-estimator --config slope.toml --print-config   # every setting in effect, then exit
  slope-estimator --service-prefix robot2 -v   # another stack, debug logs

Config file: the one every slope daemon reads; this program takes service_prefix, [health] \
and [estimator] (with [estimator.ransac] and the other stages' sections, see the pipeline \
README) and checks the rest. Command-line flags win over the file.

Health: a report on <prefix>/health every --health-interval-s seconds (frames in/out/dropped, \
rates, capture-to-publish latency and per-stage median/p95/max ms over that interval, the last \
error); `slope-echo --health` shows it. The same summary over 10 s goes to the log at INFO."
)]
pub struct EstimatorArgs {
    /// Fit used for the planes: paper (normals, cosine k-means, cumulative
    /// averaging), least-squares, or tls. Overrides `[estimator] method`.
    #[arg(long, value_parser = method_arg)]
    pub method: Option<SlopeMethod>,

    /// The slope config file (missing keys keep their defaults). Without
    /// it the estimator reads /etc/slope/slope.toml if that exists.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,

    /// Stop after publishing this many estimates (at least 1).
    #[arg(long, value_parser = max_frames_arg)]
    pub max_frames: Option<u64>,

    /// Print every setting in effect (the config file's, the defaults for
    /// keys it leaves out, and the flags) as a config file and exit,
    /// without connecting to anything: what the daemon would run with.
    #[arg(long)]
    pub print_config: bool,

    /// Seconds between health reports on the topic PREFIX/health (0: none, the
    /// summary is still logged every 10 s). Overrides `[health] interval_s`
    /// (default 1).
    #[arg(
        long = "health-interval-s",
        alias = "health-interval",
        value_name = "S",
        allow_hyphen_values = true,
        value_parser = health_interval_arg
    )]
    pub health_interval: Option<f64>,

    /// Threads a frame's stages may run on (1-64; default 1, or the config
    /// file's `[estimator] threads`): with 2 the outlier filter and the
    /// labelling of the planes run in bands of rows, and the ground's and
    /// the inclined plane's normals at once; the estimate is the same.
    #[arg(long, value_parser = threads_arg)]
    pub threads: Option<usize>,
    /// Largest cloud (width x height) to estimate: a larger one is refused
    /// (health counts it, the estimate says bad_frame) before the estimator
    /// touches it.
    #[arg(long, default_value_t = DEFAULT_MAX_CLOUD_POINTS)]
    pub max_points: usize,

    #[command(flatten)]
    pub common: CommonArgs,
}

/// `--threads`: 1 to 64.
pub fn threads_arg(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if (1..=slope_pipeline::config::MAX_THREADS).contains(&n) => Ok(n),
        _ => Err(format!(
            "'{text}' must be a whole number of threads from 1 to 64"
        )),
    }
}

/// `--health-interval-s`: 0 (off) or 0.05-3600 seconds.
pub fn health_interval_arg(text: &str) -> Result<f64, String> {
    let value: f64 = text
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    check_health_interval(value).map_err(|range| format!("'{text}' {range}"))
}

pub fn method_arg(text: &str) -> Result<SlopeMethod, String> {
    parse_method(text)
        .ok_or_else(|| format!("unknown method '{text}': expected paper, least-squares or tls"))
}

/// The estimator parameters of a config file (its `[estimator]`), or the
/// defaults without one, with `method` over them: what slope-eval and
/// slope-convert run. The file is read as [`read_settings`] reads it.
pub fn load_config(
    path: Option<&PathBuf>,
    method: Option<SlopeMethod>,
    stop: &StopFlag,
) -> anyhow::Result<EstimatorConfig> {
    let mut config = read_settings(path.map(PathBuf::as_path), stop)?.estimator;
    if let Some(method) = method {
        config.method = method;
    }
    Ok(config)
}

/// The settings in effect: the config file (`--config`, else
/// [`DEFAULT_CONFIG_PATH`] if it exists), else the defaults, with the
/// command line over them. `None` when `stop` came while the file was read.
pub fn effective_config(
    args: &EstimatorArgs,
    stop: &StopFlag,
) -> anyhow::Result<Option<SlopeFile>> {
    let path = config_path(args.config.as_deref(), Path::new(DEFAULT_CONFIG_PATH));
    let Some(mut file) = SlopeFile::load_or_stop(path.as_deref(), stop)? else {
        return Ok(None);
    };
    match &path {
        Some(path) => tracing::info!(config = %path.display(), "settings loaded"),
        None => tracing::info!("no {DEFAULT_CONFIG_PATH} and no --config: default settings"),
    }
    file.service_prefix = args.common.prefix_or(&file.service_prefix);
    if let Some(method) = args.method {
        file.estimator.method = method;
    }
    if let Some(interval) = args.health_interval {
        file.health.interval_s = interval;
    }
    if let Some(threads) = args.threads {
        file.estimator.threads = threads;
    }
    file.validate().context("invalid settings")?;
    Ok(Some(file))
}

/// What the estimator did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct EstimatorStats {
    pub processed: u64,
    pub dropped: u64,
}

/// Runs the estimator as a systemd notify daemon: `READY=1` once subscribed,
/// a status line a second, `STATUS=failed: <reason>` before a failed exit
/// (a config-file error included) and `STOPPING=1` on the way out. Outside
/// systemd the notifications go nowhere.
pub fn run(args: &EstimatorArgs, stop: &StopFlag) -> anyhow::Result<EstimatorStats> {
    let mut manager = ServiceManager::from_env();
    let result = estimate(args, stop, &mut manager);
    if let Err(err) = &result {
        manager.status(&format!("failed: {err:#}").replace('\n', " "));
    }
    manager.stopping();
    result
}

/// Loads the settings, opens the services and runs the estimator until
/// stopped; the body of [`run`].
fn estimate(
    args: &EstimatorArgs,
    stop: &StopFlag,
    manager: &mut ServiceManager,
) -> anyhow::Result<EstimatorStats> {
    let Some(file) = effective_config(args, stop)? else {
        tracing::info!("stopped before the config file was read");
        return Ok(EstimatorStats::default());
    };
    if args.print_config {
        return print_config(&file);
    }
    let config = file.estimator;
    let health_interval_s = file.health.interval_s;
    let names = ServiceNames::new(file.service_prefix);
    let node = create_node(&node_name("slope-estimator"))?;
    let subscriber = CloudSubscriber::create(&node, &names)?;
    let publisher = EstimatePublisher::create(&node, &names)?;
    let surfaces = SurfacesPublisher::create(&node, &names)?;
    let health_publisher = if health_interval_s > 0.0 {
        Some(HealthPublisher::create(&node, &names)?)
    } else {
        None
    };
    tracing::info!(
        method = config.method.name(),
        clouds = subscriber.service_name(),
        estimates = %names.estimate(),
        surfaces = %names.surfaces(),
        "estimator ready"
    );
    let health = HealthReporter::new(
        HealthComponent::Estimator,
        health_publisher,
        health_interval_s,
    );
    let outputs = Outputs {
        estimates: &publisher,
        surfaces: &surfaces,
    };
    let mut worker = Worker::new(config, &subscriber, outputs, args.max_frames, health);
    worker.max_points = args.max_points;
    serve(&mut worker, stop, manager)?;
    tracing::info!(
        processed = worker.stats.processed,
        dropped = worker.stats.dropped,
        "estimator stopped"
    );
    Ok(worker.stats.clone())
}

/// `--print-config`: prints every setting in effect as TOML, estimates
/// nothing.
fn print_config(file: &SlopeFile) -> anyhow::Result<EstimatorStats> {
    print!(
        "{}",
        file.to_toml()
            .context("cannot write the settings as TOML")?
    );
    Ok(EstimatorStats::default())
}

/// Tells the service manager the estimator is ready, then handles clouds
/// as they arrive until `stop` is set or `--max-frames` is reached, noting
/// silences, status lines and health reports on the way.
fn serve(
    worker: &mut Worker<'_>,
    stop: &StopFlag,
    manager: &mut ServiceManager,
) -> anyhow::Result<()> {
    let mut silence = SilenceNote::new(
        "cloud",
        worker.subscriber.service_name(),
        "slope-capture or slope-replay",
    );
    manager.ready("waiting for clouds");
    let started = Instant::now();
    wait_loop(worker.subscriber.listener(), stop, || {
        let processed = worker.stats.processed;
        worker.on_cloud_event()?;
        if worker.stats.processed > processed {
            silence.heard();
            worker.status.heard(Instant::now());
        }
        silence.tick();
        manager.tick(|| worker.status_line(started.elapsed()));
        worker.health.tick();
        Ok(!worker.done())
    })
}

/// Frames the queue overwrote before we saw them, from the gap in the
/// frame index since the `last` cloud: only when `next` continues its
/// stream as the tracker judges it ([`StreamPosition::continues`] with
/// `tracking.max_gap_s`). A stream that starts again (a replay restarted,
/// a new camera), a recording that skips indices after a pause, or an
/// index that jumps further than the time allows drops nothing.
fn index_gap(last: Option<StreamPosition>, next: &StreamPosition, max_gap_s: f64) -> u64 {
    match last {
        Some(last) if last.continues(next, max_gap_s) => next.index - last.index - 1,
        _ => 0,
    }
}

/// Clouds quiet this long make the status line say so.
const QUIET_STATUS: Duration = Duration::from_secs(2);

/// `912 frames in 31 s (29.4 fps), 3 dropped, last slope +16.02°`: totals
/// since the start, the rate since the last line (not the mean since the
/// start, which hides a camera that stopped), and once the clouds have been
/// `quiet` for [`QUIET_STATUS`] or more, `no cloud for 12 s; ` before it.
fn status_text(
    stats: &EstimatorStats,
    elapsed: Duration,
    fps: f64,
    last_slope_deg: Option<f64>,
    quiet: Option<Duration>,
) -> String {
    let last = match last_slope_deg {
        Some(slope) => format!("{slope:+.2}°"),
        None => "-".to_string(),
    };
    let totals = format!(
        "{} frames in {:.0} s ({fps:.1} fps), {} dropped, last slope {last}",
        stats.processed,
        elapsed.as_secs_f64(),
        stats.dropped
    );
    match quiet {
        Some(quiet) if quiet >= QUIET_STATUS => {
            format!("no cloud for {:.0} s; {totals}", quiet.as_secs_f64())
        }
        _ => totals,
    }
}

/// What the status line's rate and silence are measured from.
#[derive(Debug, Clone, Copy)]
struct StatusRate {
    /// Clouds processed at the last status line, and when.
    frames: u64,
    at: Instant,
    /// The last cloud processed (none yet: `None`).
    last_cloud: Option<Instant>,
}

impl StatusRate {
    fn new(now: Instant) -> Self {
        Self {
            frames: 0,
            at: now,
            last_cloud: None,
        }
    }

    fn heard(&mut self, now: Instant) {
        self.last_cloud = Some(now);
    }

    /// Clouds a second since the last call, with `processed` clouds now.
    fn fps(&mut self, processed: u64, now: Instant) -> f64 {
        let seconds = now.duration_since(self.at).as_secs_f64();
        let frames = processed.saturating_sub(self.frames);
        (self.frames, self.at) = (processed, now);
        frames as f64 / seconds.max(1e-3)
    }

    /// How long since the last cloud (none yet: `None`).
    fn quiet(&self, now: Instant) -> Option<Duration> {
        self.last_cloud.map(|t| now.duration_since(t))
    }
}

struct Worker<'a> {
    /// The estimator for the clouds of [`Worker::sensor`].
    estimator: Estimator,
    /// The settings in effect, before a sensor's noise model fills an unset
    /// `selection.noise_model`.
    config: EstimatorConfig,
    /// The cloud header's sensor field the estimator was built for (all 0:
    /// no name).
    sensor: [u8; SENSOR_NAME_LEN],
    subscriber: &'a CloudSubscriber,
    publisher: Outputs<'a>,
    stats: EstimatorStats,
    /// Index and capture time of the last cloud.
    last_frame: Option<StreamPosition>,
    /// The last `ok` slope, degrees.
    last_slope_deg: Option<f64>,
    max_frames: Option<u64>,
    health: HealthReporter,
    status: StatusRate,
    /// `--max-points`.
    max_points: usize,
    /// Clouds refused by the input checks.
    rejected: RejectedClouds,
    /// The floor seen disagrees with the mount, as of the last frame.
    mount_mismatch: bool,
}

/// Where a worker publishes each frame: the estimate and its surfaces.
#[derive(Clone, Copy)]
struct Outputs<'a> {
    estimates: &'a EstimatePublisher,
    surfaces: &'a SurfacesPublisher,
}

impl<'a> Worker<'a> {
    /// A worker that has processed nothing yet, its estimator built for a
    /// cloud without a sensor name until the first cloud says otherwise.
    fn new(
        config: EstimatorConfig,
        subscriber: &'a CloudSubscriber,
        publisher: Outputs<'a>,
        max_frames: Option<u64>,
        health: HealthReporter,
    ) -> Self {
        Self {
            estimator: Estimator::new(config.clone().for_sensor("")),
            config,
            sensor: [0; SENSOR_NAME_LEN],
            subscriber,
            publisher,
            stats: EstimatorStats::default(),
            last_frame: None,
            last_slope_deg: None,
            max_frames,
            health,
            status: StatusRate::new(Instant::now()),
            max_points: DEFAULT_MAX_CLOUD_POINTS,
            rejected: RejectedClouds::default(),
            mount_mismatch: false,
        }
    }

    /// Warns (log and health, once each time it starts) when the floor the
    /// camera sees disagrees with the configured mount, and logs when it
    /// agrees again.
    fn check_mount(&mut self, frame_index: u64) {
        let mismatch = self.estimator.mount_mismatch();
        if mismatch && !self.mount_mismatch {
            let text = format!(
                "frame {frame_index}: the floor seen disagrees with the mount (tilted against it, \
                 or off its height): check [mount], or the robot stands tilted"
            );
            tracing::warn!("{text}");
            self.health.monitor.error(&text);
        } else if !mismatch && self.mount_mismatch {
            tracing::info!(
                frame = frame_index,
                "the floor seen agrees with the mount again"
            );
        }
        self.mount_mismatch = mismatch;
    }
}

impl Worker<'_> {
    /// The service manager's status line ([`status_text`]), the rate over
    /// the time since the last one.
    fn status_line(&mut self, elapsed: Duration) -> String {
        let now = Instant::now();
        let fps = self.status.fps(self.stats.processed, now);
        let quiet = self.status.quiet(now);
        status_text(&self.stats, elapsed, fps, self.last_slope_deg, quiet)
    }

    fn done(&self) -> bool {
        self.max_frames
            .is_some_and(|max| self.stats.processed >= max)
    }

    /// Rebuilds the estimator for the sensor of `header`, as slope-eval
    /// configures it for a recording's `sensor`: its noise model unless the
    /// config sets one. A new estimator also starts a new track: the slope
    /// of another sensor's stream is not followed on from this one's.
    fn use_sensor(&mut self, header: &CloudHeader) {
        let name = header.sensor_name();
        let config = self.config.clone().for_sensor(name);
        tracing::info!(
            sensor = name,
            noise_model = config.selection.noise_model.unwrap_or_default().name(),
            frame = header.frame_index,
            "clouds from a new sensor; estimator set up for it"
        );
        self.estimator = Estimator::new(config);
        self.sensor = header.sensor;
        // Another stream: its first index says nothing of drops.
        self.last_frame = None;
    }

    /// A cloud the input checks refuse: counted in health (an error, its
    /// reason the last error), logged at WARN (rate limited), answered with
    /// a `bad_frame` estimate. Its index carries the stream on, so the next
    /// good cloud does not count it as dropped.
    fn refuse(
        &mut self,
        header: &CloudHeader,
        skipped: u64,
        err: &slope_sensor::cloud_checks::CloudCheckError,
    ) -> anyhow::Result<()> {
        if let Some(line) = self
            .rejected
            .refused(header.frame_index, err, Instant::now())
        {
            tracing::warn!("{line}");
        }
        self.health
            .monitor
            .error(&format!("refused cloud {}: {err}", header.frame_index));
        self.stats.dropped = self.stats.dropped.saturating_add(skipped);
        self.health.monitor.frames_in(skipped.saturating_add(1));
        self.health.monitor.dropped(skipped);
        if let Some(last) = self.last_frame.as_mut() {
            if header.frame_index > last.index && header.capture_stamp_ns >= last.stamp_ns {
                (last.index, last.stamp_ns) = (header.frame_index, header.capture_stamp_ns);
            }
        }
        let message = SlopeEstimate {
            frame_index: header.frame_index,
            capture_stamp_ns: header.capture_stamp_ns,
            source_stamp_ns: header.source_stamp_ns,
            dropped_frames: self.stats.dropped,
            method: self.config.method as u32,
            ..SlopeEstimate::default()
        };
        self.publisher.estimates.publish(&message)?;
        self.stats.processed += 1;
        self.health.monitor.frame_out(None, &[]);
        Ok(())
    }

    fn on_cloud_event(&mut self) -> anyhow::Result<()> {
        let (sample, skipped) = self.subscriber.receive_newest()?;
        let Some(sample) = sample else {
            return Ok(());
        };
        let header = *sample.header();
        let points = sample.points();
        if let Err(err) = check_cloud(&header, points.len(), self.max_points) {
            drop(sample);
            return self.refuse(&header, skipped, &err);
        }
        if header.sensor != self.sensor {
            self.use_sensor(&header);
        }
        let view = CloudView::from_header(&header, points);
        let position = StreamPosition::of(&view, header.frame_index, header.capture_stamp_ns);
        let gap = index_gap(self.last_frame, &position, self.config.tracking.max_gap_s);
        let missed = gap.max(skipped);
        if missed > 0 {
            tracing::debug!(frame = header.frame_index, missed, "dropped stale clouds");
        }
        self.stats.dropped = self.stats.dropped.saturating_add(missed);
        self.health.monitor.frames_in(missed.saturating_add(1));
        self.health.monitor.dropped(missed);
        self.last_frame = Some(position);
        tracing::debug!(
            frame = header.frame_index,
            points = points.len(),
            payload_addr = format_args!("{:#x}", points.as_ptr() as usize),
            "processing cloud in place"
        );
        // The frame index seeds this frame's random draws; the tracker
        // follows the slope over the stream.
        let frame = FrameInfo {
            index: header.frame_index,
            stamp_ns: header.capture_stamp_ns,
        };
        let estimate = self.estimator.estimate_frame(&view, frame);
        self.check_mount(header.frame_index);
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
        let sent = self.publisher.estimates.publish(&message)?;
        self.publisher.surfaces.publish(|surfaces| {
            (surfaces.frame_index, surfaces.capture_stamp_ns) =
                (header.frame_index, header.capture_stamp_ns);
            surfaces.source_stamp_ns = header.source_stamp_ns;
            estimate.write_surfaces(surfaces);
        })?;
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

    fn parse(args: &[&str]) -> EstimatorArgs {
        EstimatorArgs::try_parse_from(
            std::iter::once("slope-estimator").chain(args.iter().copied()),
        )
        .expect("valid arguments")
    }

    #[test]
    fn the_status_line_gives_the_recent_rate_and_says_when_clouds_stop() {
        let start = Instant::now();
        let at = |s: f64| start + Duration::from_secs_f64(s);
        let mut rate = StatusRate::new(start);
        let stats = |processed| EstimatorStats {
            processed,
            dropped: 3,
        };
        // No cloud yet: the plain totals.
        assert_eq!(
            status_text(
                &stats(0),
                Duration::from_secs(2),
                rate.fps(0, at(2.0)),
                None,
                rate.quiet(at(2.0))
            ),
            "0 frames in 2 s (0.0 fps), 3 dropped, last slope -"
        );
        // 60 clouds in the next 2 s, the last one just now: 30 fps.
        rate.heard(at(4.0));
        let line = status_text(
            &stats(60),
            Duration::from_secs(4),
            rate.fps(60, at(4.0)),
            Some(16.02),
            rate.quiet(at(4.0)),
        );
        assert_eq!(
            line,
            "60 frames in 4 s (30.0 fps), 3 dropped, last slope +16.02°"
        );
        // Then nothing for 10 s: 0 fps now (the mean since the start would
        // still say 4.3), and the line says for how long.
        let line = status_text(
            &stats(60),
            Duration::from_secs(14),
            rate.fps(60, at(14.0)),
            Some(16.02),
            rate.quiet(at(14.0)),
        );
        assert_eq!(
            line,
            "no cloud for 10 s; 60 frames in 14 s (0.0 fps), 3 dropped, last slope +16.02°"
        );
    }

    #[test]
    fn the_command_line_wins_over_the_file() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("slope.toml");
        std::fs::write(
            &path,
            "service_prefix = \"robot2\"\n[health]\ninterval_s = 5.0\n\
             [estimator]\nmethod = \"tls\"\nseed = 7\n",
        )
        .expect("write");
        let file_arg = path.to_str().expect("utf-8");
        let effective = |args: &EstimatorArgs| effective_config(args, &StopFlag::new());
        let from_file = effective(&parse(&["--config", file_arg]))
            .expect("valid")
            .expect("not stopped");
        assert_eq!(from_file.service_prefix, "robot2");
        assert_eq!(from_file.health.interval_s, 5.0);
        assert_eq!(from_file.estimator.method, SlopeMethod::Tls);
        let overridden = effective(&parse(&[
            "--config",
            file_arg,
            "--service-prefix",
            "robot3",
            "--health-interval-s",
            "0",
            "--method",
            "paper",
        ]))
        .expect("valid")
        .expect("not stopped");
        assert_eq!(overridden.service_prefix, "robot3");
        assert_eq!(overridden.health.interval_s, 0.0);
        assert_eq!(overridden.estimator.method, SlopeMethod::Paper);
        assert_eq!(
            overridden.estimator.seed, 7,
            "what no flag sets stays the file's"
        );
        let missing = dir.path().join("missing.toml");
        let err = effective(&parse(&["--config", missing.to_str().expect("utf-8")]))
            .expect_err("no such file");
        assert!(format!("{err:#}").contains("missing.toml"), "{err:#}");
    }

    /// Drops are counted from index gaps within one stream only, and a
    /// jump to the largest index is no drop (it panicked the estimator:
    /// "attempt to add with overflow", then counted 1.8e19 drops).
    #[test]
    fn index_gaps_count_as_drops_within_one_stream_only() {
        let camera = CloudView::from_header(&CloudHeader::default(), &[]);
        let at =
            |index: u64, stamp_ms: u64| StreamPosition::of(&camera, index, stamp_ms * 1_000_000);
        let gap = |next| index_gap(Some(at(10, 1000)), &next, 1.5);
        assert_eq!(index_gap(None, &at(10, 1000), 1.5), 0);
        assert_eq!(gap(at(11, 1033)), 0);
        assert_eq!(gap(at(14, 1133)), 3);
        assert_eq!(gap(at(50, 2400)), 39);
        // A burst (200 clouds in 120 ms, of which this estimator saw 8):
        // the 24 skipped in 15 ms are dropped, not a new stream.
        assert_eq!(gap(at(35, 1015)), 24);
        // A new stream: the index starts again, comes after a pause, the
        // clock went back, or the index jumps further than 100 kHz allows.
        for next in [
            at(0, 1033),
            at(10, 1033),
            at(50, 2501),
            at(50, 999),
            at(u64::MAX, 1033),
            at(10_000, 1033),
        ] {
            assert_eq!(gap(next), 0, "{next:?}");
        }
    }
}
