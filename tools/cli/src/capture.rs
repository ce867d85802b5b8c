//! `slope-capture`: the Kinect v2 daemon. Opens the camera through our
//! libfreenect2 binding and publishes every frame as an organised cloud on
//! the same service, in the same layout, as `slope-replay`.
//!
//! The arguments and settings (the config file under the flags, the device
//! options, the exit status of a failure) need no library and build
//! without the `kinect2` feature; opening the camera and capturing need it.

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::Context;
use clap::Parser;
use slope_ipc_types::DEFAULT_MAX_CLOUD_POINTS;
use slope_sensor::kinect2::{CaptureStats, DepthConfig, DeviceSelector, Kinect2Options, Pipeline};
use slope_sensor::publish::{PublishStats, StopFlag};

use crate::cli::{max_frames_arg, CommonArgs};
use crate::config_file::{config_path, is_config_error, SlopeFile, DEFAULT_CONFIG_PATH};
use crate::estimator::health_interval_arg;
use crate::mount_args::MountArgs;
use crate::replay::positive_f64;

#[cfg(feature = "kinect2")]
use {
    crate::capture_notify::{publish_notifying, CaptureNotifier, SharedNotifier, SourceCounters},
    crate::cli::node_name,
    crate::health::HealthReporter,
    slope_ipc_types::{HealthComponent, ServiceNames},
    slope_sensor::device_lock::DeviceLock,
    slope_sensor::ipc::{create_node, CloudPublisher, HealthPublisher},
    slope_sensor::kinect2::{library_version, Context as Freenect2, Kinect2Source, LOCK_KIND},
    slope_sensor::publish::{Pacing, PublishOptions},
    slope_sensor::source::FrameSource,
};

#[derive(Debug, Parser)]
#[command(
    name = "slope-capture",
    version,
    about = "Publish the Kinect v2's depth (and registered colour) as point clouds",
    long_about = "Opens a Kinect v2 through libfreenect2, undistorts each depth frame, registers \
the colour image to it, undoes libfreenect2's mirroring and publishes the result as an organised \
point cloud on the cloud topic, at the camera's rate (30 Hz), exactly as slope-replay does with a \
recording. When frames stop coming it reconnects with backoff and keeps running; SIGINT/SIGTERM \
stop the streams and exit 0.",
    after_help = "Examples:
  slope-capture --list                                  # connected devices, then exit
  slope-capture                                         # first device, default pipeline
  slope-capture --serial 011054343347 --pipeline cl     # a given camera, OpenCL decoding
  slope-capture --pipeline cpu --depth-only             # headless, no GPU, no colour
  slope-capture --config slope.toml --print-config      # every setting in effect, then exit
  slope-capture --mount-height-m 0.5 --mount-pitch-deg -20

Config file: the one every slope daemon reads (/etc/slope/slope.toml if it exists, or --config); \
this program takes service_prefix, [health], [mount] and [capture] and checks the rest. \
Command-line flags win over the file. For example:
  service_prefix = \"slope\"
  [mount]
  height_m = 0.50
  pitch_deg = -20.0
  [capture]
  serial = \"011054343347\"
  pipeline = \"cl\"             # default, cpu, cl, clkde, cuda, cudakde, gl (gl needs a display)
  max_depth_m = 4.5
  color = true"
)]
pub struct CaptureArgs {
    /// Print the connected Kinect v2 devices on stdout, one per line
    /// (`<serial> firmware <version>`), or "no Kinect v2 found", and exit.
    /// A device another process streams is not opened (that would reset it).
    #[arg(long)]
    pub list: bool,

    /// The slope config file (see below). Without it the capture reads
    /// /etc/slope/slope.toml if that exists.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,

    /// Print every setting in effect (the config file's, the defaults for
    /// keys it leaves out, and the flags) as a config file and exit,
    /// without opening a device.
    #[arg(long)]
    pub print_config: bool,

    /// Seconds between health reports on the topic PREFIX/health (0: none).
    /// Overrides `[health] interval_s` (default 1).
    #[arg(
        long = "health-interval-s",
        value_name = "S",
        allow_hyphen_values = true,
        value_parser = health_interval_arg
    )]
    pub health_interval: Option<f64>,

    /// Serial number of the Kinect v2 to open (see --list); the first one if
    /// neither this nor --device-index is given.
    #[arg(long, conflicts_with = "device_index")]
    pub serial: Option<String>,

    /// Enumeration index of the device to open (not stable across replugging;
    /// prefer --serial).
    #[arg(long)]
    pub device_index: Option<u32>,

    /// Depth decoding pipeline: default, cpu, cl, clkde, cuda, cudakde, gl.
    /// gl needs a display; headless robots want cl, cuda or cpu.
    #[arg(long)]
    pub pipeline: Option<Pipeline>,

    /// OpenCL/CUDA device id for the cl/cuda pipelines.
    #[arg(long)]
    pub gpu_device: Option<u32>,

    /// Drop depth nearer than this, metres (libfreenect2 default 0.5).
    #[arg(long, value_name = "M", allow_hyphen_values = true, value_parser = positive_f64)]
    pub min_depth_m: Option<f64>,

    /// Drop depth beyond this, metres (libfreenect2 default 4.5).
    #[arg(long, value_name = "M", allow_hyphen_values = true, value_parser = positive_f64)]
    pub max_depth_m: Option<f64>,

    /// libfreenect2's bilateral filter (removes flying pixels): true/false.
    #[arg(long)]
    pub bilateral_filter: Option<bool>,

    /// libfreenect2's edge-aware filter (removes noisy edge pixels): true/false.
    #[arg(long)]
    pub edge_aware_filter: Option<bool>,

    /// Stream depth only (no colour, less USB bandwidth and CPU).
    #[arg(long)]
    pub depth_only: bool,

    /// The camera's pose on the robot, sent with every cloud.
    #[command(flatten)]
    pub mount: MountArgs,

    /// Keep retrying (with backoff) until a Kinect v2 appears, instead of
    /// failing at once.
    #[arg(long)]
    pub wait_for_device: bool,

    /// Seconds without a frame after which the device counts as lost and is
    /// reopened.
    #[arg(long, value_name = "S", allow_hyphen_values = true, value_parser = positive_f64)]
    pub frame_timeout_s: Option<f64>,

    /// Stop after this many frames (at least 1).
    #[arg(long, value_parser = max_frames_arg)]
    pub max_frames: Option<u64>,

    /// Largest cloud (width x height) to accept.
    #[arg(long, default_value_t = DEFAULT_MAX_CLOUD_POINTS)]
    pub max_points: usize,

    #[command(flatten)]
    pub common: CommonArgs,
}

/// The settings in effect: the config file (`--config`, else
/// [`DEFAULT_CONFIG_PATH`] if it exists), else the defaults, with the
/// command line over them. `None` when `stop` came while the file was read.
pub fn effective_config(args: &CaptureArgs, stop: &StopFlag) -> anyhow::Result<Option<SlopeFile>> {
    let path = config_path(args.config.as_deref(), Path::new(DEFAULT_CONFIG_PATH));
    let Some(mut file) = SlopeFile::load_or_stop(path.as_deref(), stop)? else {
        return Ok(None);
    };
    if let Some(path) = &path {
        tracing::info!(config = %path.display(), "settings loaded");
    }
    apply_flags(args, &mut file);
    file.validate().context("invalid settings")?;
    Ok(Some(file))
}

/// The command line's settings over the file's.
fn apply_flags(args: &CaptureArgs, file: &mut SlopeFile) {
    file.service_prefix = args.common.prefix_or(&file.service_prefix);
    if let Some(interval) = args.health_interval {
        file.health.interval_s = interval;
    }
    let capture = &mut file.capture;
    if args.serial.is_some() || args.device_index.is_some() {
        capture.serial.clone_from(&args.serial);
        capture.device_index = args.device_index;
    }
    if let Some(pipeline) = args.pipeline {
        capture.pipeline = pipeline.name().to_string();
    }
    capture.gpu_device = args.gpu_device.or(capture.gpu_device);
    capture.min_depth_m = args.min_depth_m.unwrap_or(capture.min_depth_m);
    capture.max_depth_m = args.max_depth_m.unwrap_or(capture.max_depth_m);
    capture.bilateral_filter = args.bilateral_filter.unwrap_or(capture.bilateral_filter);
    capture.edge_aware_filter = args.edge_aware_filter.unwrap_or(capture.edge_aware_filter);
    capture.color = capture.color && !args.depth_only;
    capture.frame_timeout_s = args.frame_timeout_s.unwrap_or(capture.frame_timeout_s);
    let mount = &mut file.mount;
    mount.height_m = args.mount.height_m.or(mount.height_m);
    mount.pitch_deg = args.mount.pitch_deg.or(mount.pitch_deg);
    mount.roll_deg = args.mount.roll_deg.or(mount.roll_deg);
}

/// The device settings of a validated [`SlopeFile`] (flags applied).
pub fn resolve_options(args: &CaptureArgs, file: &SlopeFile) -> anyhow::Result<Kinect2Options> {
    let capture = &file.capture;
    let device = match (&capture.serial, capture.device_index) {
        (Some(serial), _) => DeviceSelector::Serial(serial.clone()),
        (None, Some(index)) => DeviceSelector::Index(index),
        (None, None) => DeviceSelector::First,
    };
    let pipeline: Pipeline = capture
        .pipeline
        .parse()
        .context("in the settings' [capture] pipeline")?;
    let depth = DepthConfig {
        min_depth_m: capture.min_depth_m as f32,
        max_depth_m: capture.max_depth_m as f32,
        bilateral_filter: capture.bilateral_filter,
        edge_aware_filter: capture.edge_aware_filter,
    };
    Ok(Kinect2Options {
        device,
        pipeline,
        gpu_device: capture.gpu_device,
        depth,
        color: capture.color,
        mount: file.mount.to_mount(),
        wait_for_device: args.wait_for_device,
        frame_timeout: Duration::from_secs_f64(capture.frame_timeout_s),
        ..Kinect2Options::default()
    })
}

/// What a capture run did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct CaptureOutcome {
    pub publish: PublishStats,
    pub capture: CaptureStats,
    /// Stopped (signal) before any device was found.
    pub stopped_waiting: bool,
}

/// Prints the connected devices on stdout, one per line: `<serial> firmware
/// <version>`, or "no Kinect v2 found". Reading the firmware version means
/// opening the device, which resets it: a device whose lock another process
/// holds is listed without opening it (`firmware unknown (in use by PID
/// n)`).
#[cfg(feature = "kinect2")]
pub fn list_devices() -> anyhow::Result<Vec<String>> {
    let context = Freenect2::new().context("cannot start libfreenect2")?;
    let serials = context
        .enumerate()
        .context("cannot enumerate Kinect v2 devices")?;
    if serials.is_empty() {
        println!("no Kinect v2 found");
    }
    let lock_dir = DeviceLock::dir();
    for serial in &serials {
        println!(
            "{serial} firmware {}",
            firmware_of(&context, &lock_dir, serial)
        );
    }
    tracing::info!(
        count = serials.len(),
        libfreenect2 = library_version(),
        "Kinect v2 devices"
    );
    Ok(serials)
}

/// The firmware version of `serial`, or why it is unknown.
#[cfg(feature = "kinect2")]
fn firmware_of(context: &Freenect2, lock_dir: &Path, serial: &str) -> String {
    if let Some(pid) = DeviceLock::holder_in(lock_dir, LOCK_KIND, serial) {
        let pid = pid.map_or_else(|| "unknown".to_string(), |pid| pid.to_string());
        return format!("unknown (in use by PID {pid})");
    }
    let selector = DeviceSelector::Serial(serial.to_string());
    match context
        .open(&selector, Pipeline::Cpu, None)
        .and_then(|mut device| device.firmware_version())
    {
        Ok(firmware) => firmware,
        Err(err) => {
            tracing::warn!(serial, error = %err, "cannot read the firmware version");
            format!("unknown ({err})")
        }
    }
}

/// Exit status for failures that restarting cannot cure (a config-file
/// error, a depth pipeline that is not built in or cannot initialise):
/// `EX_CONFIG` (78), so that a unit with `RestartPreventExitStatus=78` stays
/// failed instead of restarting every few seconds.
pub use crate::config_file::EXIT_CONFIG;

/// [`EXIT_CONFIG`] when `err` is a failure that restarting cannot cure.
pub fn config_exit_code(err: &anyhow::Error) -> Option<u8> {
    use slope_sensor::kinect2::Kinect2Error;
    use slope_sensor::publish::PublishError;
    use slope_sensor::source::SourceError;
    let lasting = |err: &Kinect2Error| {
        matches!(
            err,
            Kinect2Error::DepthPipelineFailed { .. } | Kinect2Error::PipelineUnavailable { .. }
        )
    };
    let broken_pipeline = err.chain().any(|cause| {
        cause.downcast_ref::<Kinect2Error>().is_some_and(lasting)
            || matches!(
                cause.downcast_ref::<PublishError>(),
                Some(PublishError::Source(SourceError::Kinect2(inner))) if lasting(inner)
            )
    });
    (is_config_error(err) || broken_pipeline).then_some(EXIT_CONFIG)
}

/// The counters of the status line.
#[cfg(feature = "kinect2")]
fn counters(stats: &CaptureStats) -> SourceCounters {
    SourceCounters {
        dropped: stats.bad_status + stats.malformed,
        lost: stats.lost,
        reconnects: stats.reconnects,
        failed_opens: stats.failed_opens,
    }
}

/// Runs the capture as a systemd notify daemon (see `capture_notify`):
/// `READY=1` after the first published cloud, the watchdog from every wait,
/// a status line a second, `STATUS=failed: ...` and `STOPPING=1` on the way
/// out. Outside systemd the notifications go nowhere.
#[cfg(feature = "kinect2")]
pub fn run(args: &CaptureArgs, stop: &StopFlag) -> anyhow::Result<CaptureOutcome> {
    if args.print_config {
        let Some(file) = effective_config(args, stop)? else {
            return Ok(CaptureOutcome::default());
        };
        print!(
            "{}",
            file.to_toml()
                .context("cannot write the settings as TOML")?
        );
        return Ok(CaptureOutcome::default());
    }
    if args.list {
        list_devices()?;
        return Ok(CaptureOutcome::default());
    }
    let notifier = CaptureNotifier::from_env();
    let result = capture(args, stop, &notifier);
    if let Err(err) = &result {
        notifier.borrow_mut().failed(&format!("{err:#}"));
    }
    notifier.borrow().stopping();
    result
}

#[cfg(feature = "kinect2")]
fn capture(
    args: &CaptureArgs,
    stop: &StopFlag,
    notifier: &SharedNotifier,
) -> anyhow::Result<CaptureOutcome> {
    let Some(file) = effective_config(args, stop)? else {
        tracing::info!("stopped before the config file was read");
        return Ok(CaptureOutcome::default());
    };
    let options = resolve_options(args, &file)?;
    tracing::info!(
        device = ?options.device,
        pipeline = %options.pipeline,
        color = options.color,
        wait_for_device = options.wait_for_device,
        libfreenect2 = library_version(),
        "opening the Kinect v2"
    );
    let hook_notifier = SharedNotifier::clone(notifier);
    let on_wait = Box::new(move |stats: &CaptureStats| {
        hook_notifier.borrow_mut().on_wait(counters(stats));
    });
    let Some(mut source) = Kinect2Source::open_watched(options, stop.clone(), on_wait)
        .context("cannot start the Kinect v2")?
    else {
        tracing::info!("stopped before a Kinect v2 appeared");
        return Ok(CaptureOutcome {
            stopped_waiting: true,
            ..CaptureOutcome::default()
        });
    };
    let names = ServiceNames::new(file.service_prefix.clone());
    let node = create_node(&node_name("slope-capture"))?;
    let publisher = CloudPublisher::create(&node, &names, source.info(), args.max_points)
        .context("cannot publish clouds")?;
    let health = HealthPublisher::create(&node, &names).context("cannot publish health reports")?;
    notifier.borrow_mut().attach_health(HealthReporter::new(
        HealthComponent::Capture,
        Some(health),
        file.health.interval_s,
    ));
    tracing::info!(
        serial = source.serial(),
        service = publisher.service_name(),
        "capturing"
    );
    let options = PublishOptions {
        pacing: Pacing::Source,
        max_frames: args.max_frames,
        ..PublishOptions::default()
    };
    let result = publish_notifying(&mut source, &publisher, &options, stop, notifier);
    // Stop the streams (then free the listener) before reporting.
    source.close();
    let capture = source.stats();
    let publish =
        result.with_context(|| format!("capture from Kinect v2 {} failed", source.serial()))?;
    tracing::info!(
        published = publish.published,
        bad_status = capture.bad_status,
        malformed = capture.malformed,
        lost = capture.lost,
        reconnects = capture.reconnects,
        interrupted = publish.stopped,
        "capture finished"
    );
    Ok(CaptureOutcome {
        publish,
        capture,
        stopped_waiting: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> CaptureArgs {
        CaptureArgs::try_parse_from(std::iter::once("slope-capture").chain(args.iter().copied()))
            .expect("valid arguments")
    }

    /// The file's settings under the flags `args`.
    fn resolved(file: &str, args: &[&str]) -> anyhow::Result<Kinect2Options> {
        let mut file = SlopeFile::from_toml_str(file)?;
        let args = parse(args);
        apply_flags(&args, &mut file);
        file.validate()?;
        resolve_options(&args, &file)
    }

    #[test]
    fn command_line_wins_over_the_config_file() {
        let config =
            "[capture]\nserial = \"111\"\npipeline = \"cpu\"\nmax_depth_m = 6.0\ncolor = false\n\
             [mount]\nheight_m = 0.4\npitch_deg = -15.0\n";
        let from_file = resolved(config, &[]).expect("options");
        assert_eq!(from_file.device, DeviceSelector::Serial("111".into()));
        assert_eq!(from_file.pipeline, Pipeline::Cpu);
        assert_eq!(from_file.depth.max_depth_m, 6.0);
        assert_eq!(
            from_file.depth.min_depth_m,
            DepthConfig::default().min_depth_m
        );
        assert!(!from_file.color);
        assert_eq!(from_file.mount.height_m, 0.4);
        assert_eq!(from_file.mount.pitch_deg, -15.0);
        assert!(from_file.mount.roll_deg.is_nan());

        let overridden = resolved(
            config,
            &[
                "--device-index",
                "2",
                "--pipeline",
                "cl",
                "--max-depth-m",
                "4",
                "--mount-pitch-deg",
                "-20",
            ],
        )
        .expect("options");
        assert_eq!(overridden.device, DeviceSelector::Index(2));
        assert_eq!(overridden.pipeline, Pipeline::OpenCl);
        assert_eq!(overridden.depth.max_depth_m, 4.0);
        assert_eq!(overridden.mount.pitch_deg, -20.0);
    }

    #[test]
    fn the_file_defaults_are_libfreenect2s() {
        let section = crate::config_file::CaptureSection::default();
        let depth = DepthConfig::default();
        assert_eq!(section.min_depth_m, f64::from(depth.min_depth_m));
        assert_eq!(section.max_depth_m, f64::from(depth.max_depth_m));
        assert_eq!(section.bilateral_filter, depth.bilateral_filter);
        assert_eq!(section.edge_aware_filter, depth.edge_aware_filter);
        assert_eq!(
            section.frame_timeout_s,
            Kinect2Options::default().frame_timeout.as_secs_f64()
        );
    }

    #[test]
    fn a_broken_depth_pipeline_exits_with_ex_config() {
        use slope_sensor::kinect2::Kinect2Error;
        use slope_sensor::publish::PublishError;
        use slope_sensor::source::SourceError;
        let failed = || Kinect2Error::DepthPipelineFailed {
            serial: "1".into(),
            pipeline: "cl",
            color_frames: 60,
            pipeline_errors: 60,
            waited_s: 2.0,
            libfreenect2_log: None,
        };
        let while_streaming = anyhow::Error::new(PublishError::Source(SourceError::from(failed())))
            .context("capture from Kinect v2 1 failed");
        assert_eq!(config_exit_code(&while_streaming), Some(EXIT_CONFIG));
        let at_open = anyhow::Error::new(failed()).context("cannot start the Kinect v2");
        assert_eq!(config_exit_code(&at_open), Some(EXIT_CONFIG));
        let lost = anyhow::Error::new(Kinect2Error::NoDevice {
            version: "0.2.0".into(),
            libfreenect2_log: None,
        });
        assert_eq!(config_exit_code(&lost), None);
        let typo = SlopeFile::from_toml_str("[capture]\npipelin = \"cpu\"\n")
            .map_err(anyhow::Error::new)
            .expect_err("unknown key");
        assert_eq!(config_exit_code(&typo), Some(EXIT_CONFIG));
    }

    #[test]
    fn bad_settings_are_refused() {
        let empty_range = resolved("", &["--min-depth-m", "3", "--max-depth-m", "2"]);
        let message = format!("{:#}", empty_range.expect_err("3 m .. 2 m"));
        assert!(message.contains("capture.min_depth_m"), "{message}");
        let message = format!(
            "{:#}",
            resolved("[mount]\npitch_deg = 400.0\n", &[]).expect_err("pitch 400")
        );
        assert!(message.contains("mount.pitch_deg"), "{message}");
        assert!(CaptureArgs::try_parse_from(["slope-capture", "--mount-height-m", "-1"]).is_err());
        assert!(CaptureArgs::try_parse_from([
            "slope-capture",
            "--serial",
            "1",
            "--device-index",
            "0"
        ])
        .is_err());
    }
}
