//! `slope-capture`: the Kinect v2 daemon. Opens the camera through our
//! libfreenect2 binding and publishes every frame as an organised cloud on
//! the same service, in the same layout, as `slope-replay`.

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::Context;
use clap::Parser;
use serde::Deserialize;
use slope_ipc_types::{HealthComponent, Mount, DEFAULT_MAX_CLOUD_POINTS};
use slope_sensor::device_lock::DeviceLock;
use slope_sensor::ipc::{create_node, CloudPublisher, HealthPublisher};
use slope_sensor::kinect2::{
    library_version, CaptureStats, Context as Freenect2, DepthConfig, DeviceSelector,
    Kinect2Options, Kinect2Source, Pipeline, LOCK_KIND,
};
use slope_sensor::publish::{Pacing, PublishOptions, PublishStats, StopFlag};
use slope_sensor::source::FrameSource;

use crate::capture_notify::{publish_notifying, CaptureNotifier, SharedNotifier, SourceCounters};

use crate::cli::{node_name, CommonArgs};
use crate::health::{HealthReporter, DEFAULT_HEALTH_INTERVAL_S};
use crate::mount_args::{check_mount, MountArgs};
use crate::replay::positive_f64;

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
  slope-capture --config /etc/slope/capture.toml --wait-for-device
  slope-capture --mount-height-m 0.5 --mount-pitch-deg -20

Config file (every key optional; command-line flags win):
  [kinect2]
  serial = \"011054343347\"
  pipeline = \"cl\"            # default, cpu, cl, clkde, cuda, cudakde, gl (gl needs a display)
  min_depth_m = 0.5
  max_depth_m = 4.5
  bilateral_filter = true
  edge_aware_filter = true
  color = true
  frame_timeout_s = 3.0
  [mount]
  height_m = 0.50
  pitch_deg = -20.0
  roll_deg = 0.0"
)]
pub struct CaptureArgs {
    /// Print the connected Kinect v2 devices on stdout, one per line
    /// (`<serial> firmware <version>`), or "no Kinect v2 found", and exit.
    /// A device another process streams is not opened (that would reset it).
    #[arg(long)]
    pub list: bool,

    /// TOML file with [kinect2] and [mount] settings (see below).
    #[arg(long)]
    pub config: Option<PathBuf>,

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
    #[arg(long, value_parser = positive_f64)]
    pub min_depth_m: Option<f64>,

    /// Drop depth beyond this, metres (libfreenect2 default 4.5).
    #[arg(long, value_parser = positive_f64)]
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
    #[arg(long, value_parser = positive_f64)]
    pub frame_timeout_s: Option<f64>,

    /// Stop after this many frames (at least 1).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub max_frames: Option<u64>,

    /// Largest cloud (width x height) to accept.
    #[arg(long, default_value_t = DEFAULT_MAX_CLOUD_POINTS)]
    pub max_points: usize,

    #[command(flatten)]
    pub common: CommonArgs,
}

/// The config file: `[kinect2]` and `[mount]`, every key optional.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaptureConfig {
    #[serde(default)]
    pub kinect2: Kinect2Section,
    #[serde(default)]
    pub mount: MountSection,
}

#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Kinect2Section {
    pub serial: Option<String>,
    pub device_index: Option<u32>,
    pub pipeline: Option<String>,
    pub gpu_device: Option<u32>,
    pub min_depth_m: Option<f64>,
    pub max_depth_m: Option<f64>,
    pub bilateral_filter: Option<bool>,
    pub edge_aware_filter: Option<bool>,
    pub color: Option<bool>,
    pub frame_timeout_s: Option<f64>,
}

#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MountSection {
    pub height_m: Option<f64>,
    pub pitch_deg: Option<f64>,
    pub roll_deg: Option<f64>,
}

impl CaptureConfig {
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read the config file {}", path.display()))?;
        toml::from_str(&text).with_context(|| format!("invalid config file {}", path.display()))
    }
}

/// The device settings from the command line over the config file over
/// libfreenect2's defaults.
pub fn resolve_options(
    args: &CaptureArgs,
    config: &CaptureConfig,
) -> anyhow::Result<Kinect2Options> {
    let file = &config.kinect2;
    let device = match (&args.serial, args.device_index) {
        (Some(serial), _) => DeviceSelector::Serial(serial.clone()),
        (None, Some(index)) => DeviceSelector::Index(index),
        (None, None) => match (&file.serial, file.device_index) {
            (Some(serial), _) => DeviceSelector::Serial(serial.clone()),
            (None, Some(index)) => DeviceSelector::Index(index),
            (None, None) => DeviceSelector::First,
        },
    };
    let pipeline = match (args.pipeline, &file.pipeline) {
        (Some(pipeline), _) => pipeline,
        (None, Some(name)) => name
            .parse()
            .with_context(|| "in the config file's [kinect2] pipeline".to_string())?,
        (None, None) => Pipeline::Default,
    };
    let defaults = DepthConfig::default();
    let depth = DepthConfig {
        min_depth_m: args
            .min_depth_m
            .or(file.min_depth_m)
            .map_or(defaults.min_depth_m, |m| m as f32),
        max_depth_m: args
            .max_depth_m
            .or(file.max_depth_m)
            .map_or(defaults.max_depth_m, |m| m as f32),
        bilateral_filter: args
            .bilateral_filter
            .or(file.bilateral_filter)
            .unwrap_or(defaults.bilateral_filter),
        edge_aware_filter: args
            .edge_aware_filter
            .or(file.edge_aware_filter)
            .unwrap_or(defaults.edge_aware_filter),
    };
    if !(depth.min_depth_m > 0.0
        && depth.max_depth_m.is_finite()
        && depth.max_depth_m > depth.min_depth_m)
    {
        anyhow::bail!(
            "the depth range {} m .. {} m is empty; min_depth_m must be positive and below max_depth_m",
            depth.min_depth_m,
            depth.max_depth_m
        );
    }
    let frame_timeout_s = args.frame_timeout_s.or(file.frame_timeout_s).unwrap_or(3.0);
    if !(frame_timeout_s.is_finite() && frame_timeout_s > 0.0) {
        anyhow::bail!(
            "frame_timeout_s must be a positive number of seconds, not {frame_timeout_s}"
        );
    }
    let file_mount = Mount {
        height_m: config.mount.height_m.unwrap_or(f64::NAN),
        pitch_deg: config.mount.pitch_deg.unwrap_or(f64::NAN),
        roll_deg: config.mount.roll_deg.unwrap_or(f64::NAN),
    };
    check_mount(&file_mount)
        .map_err(|message| anyhow::anyhow!("in the config file's [mount]: {message}"))?;
    let mount = args.mount.over(file_mount);
    Ok(Kinect2Options {
        device,
        pipeline,
        gpu_device: args.gpu_device.or(file.gpu_device),
        depth,
        color: !args.depth_only && file.color.unwrap_or(true),
        mount,
        wait_for_device: args.wait_for_device,
        frame_timeout: Duration::from_secs_f64(frame_timeout_s),
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

/// Exit status for failures that restarting cannot cure (a depth pipeline
/// that is not built in or cannot initialise): `EX_CONFIG` (78), so that a
/// unit with `RestartPreventExitStatus=78` stays failed instead of
/// restarting every few seconds.
pub const EXIT_CONFIG: u8 = 78;

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
    err.chain()
        .any(|cause| {
            cause.downcast_ref::<Kinect2Error>().is_some_and(lasting)
                || matches!(
                    cause.downcast_ref::<PublishError>(),
                    Some(PublishError::Source(SourceError::Kinect2(inner))) if lasting(inner)
                )
        })
        .then_some(EXIT_CONFIG)
}

/// The counters of the status line.
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
pub fn run(args: &CaptureArgs, stop: &StopFlag) -> anyhow::Result<CaptureOutcome> {
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

fn capture(
    args: &CaptureArgs,
    stop: &StopFlag,
    notifier: &SharedNotifier,
) -> anyhow::Result<CaptureOutcome> {
    let config = match &args.config {
        Some(path) => CaptureConfig::load(path)?,
        None => CaptureConfig::default(),
    };
    let options = resolve_options(args, &config)?;
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
    let names = args.common.service_names();
    let node = create_node(&node_name("slope-capture"))?;
    let publisher = CloudPublisher::create(&node, &names, source.info(), args.max_points)
        .context("cannot publish clouds")?;
    let health = HealthPublisher::create(&node, &names).context("cannot publish health reports")?;
    notifier.borrow_mut().attach_health(HealthReporter::new(
        HealthComponent::Capture,
        Some(health),
        DEFAULT_HEALTH_INTERVAL_S,
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

    #[test]
    fn command_line_wins_over_the_config_file() {
        let config: CaptureConfig = toml::from_str(
            "[kinect2]\nserial = \"111\"\npipeline = \"cpu\"\nmax_depth_m = 6.0\ncolor = false\n\
             [mount]\nheight_m = 0.4\npitch_deg = -15.0\n",
        )
        .expect("config");
        let from_file = resolve_options(&parse(&[]), &config).expect("options");
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

        let overridden = resolve_options(
            &parse(&[
                "--serial",
                "222",
                "--pipeline",
                "cl",
                "--max-depth-m",
                "4",
                "--mount-pitch-deg",
                "-20",
            ]),
            &config,
        )
        .expect("options");
        assert_eq!(overridden.device, DeviceSelector::Serial("222".into()));
        assert_eq!(overridden.pipeline, Pipeline::OpenCl);
        assert_eq!(overridden.depth.max_depth_m, 4.0);
        assert_eq!(overridden.mount.pitch_deg, -20.0);
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
    }

    #[test]
    fn bad_settings_are_refused() {
        let bad_pipeline: CaptureConfig =
            toml::from_str("[kinect2]\npipeline = \"vulkan\"\n").expect("config");
        assert!(resolve_options(&parse(&[]), &bad_pipeline).is_err());
        assert!(toml::from_str::<CaptureConfig>("[kinect2]\nserail = \"1\"\n").is_err());
        let empty_range = parse(&["--min-depth-m", "3", "--max-depth-m", "2"]);
        assert!(resolve_options(&empty_range, &CaptureConfig::default()).is_err());
        let endless: CaptureConfig =
            toml::from_str("[kinect2]\nmax_depth_m = inf\n").expect("config");
        assert!(resolve_options(&parse(&[]), &endless).is_err());
        let upside_down: CaptureConfig =
            toml::from_str("[mount]\npitch_deg = 400.0\n").expect("config");
        let message = resolve_options(&parse(&[]), &upside_down)
            .expect_err("pitch 400")
            .to_string();
        assert!(
            message.contains("[mount]") && message.contains("pitch"),
            "{message}"
        );
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
