//! `slope-replay`: publishes a recording's frames as clouds, standing in for
//! the camera.

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::Context;
use clap::Parser;
use slope_ipc_types::{CloudHeader, ServiceNames, DEFAULT_MAX_CLOUD_POINTS, SENSOR_NAME_LEN};
use slope_pipeline::sensor_noise::NoiseModel;
use slope_sensor::ipc::{create_node, CloudPublisher};
use slope_sensor::publish::{publish_stream, Pacing, PublishOptions, PublishStats, StopFlag};
use slope_sensor::source::{FrameSource, RecordingSource};

use crate::cli::{max_frames_arg, node_name, open_recording, CommonArgs};
use crate::config_file::{config_path, SlopeFile, DEFAULT_CONFIG_PATH};

#[derive(Debug, Parser)]
#[command(
    name = "slope-replay",
    version,
    about = "Publish a recording's depth frames as point clouds, in place of the camera",
    long_about = "Reads a recording (see the recording format: recording.toml, frames.csv, \
depth/*.png) and publishes each frame as an organised point cloud on the cloud topic, \
exactly as slope-capture does with the Kinect. By default frames go out at the recorded rate.",
    after_help = "Examples:
  slope-replay tests/recordings/ramp16                 # recorded rate, once
  slope-replay tests/recordings/ramp16 --loop          # forever, until Ctrl-C
  slope-replay REC --rate 5 --wait-subscribers 1       # 5 Hz, start when the estimator is up
  slope-replay REC --speed 0.5 --max-frames 10         # half speed, first 10 frames
  slope-replay REC --config slope.toml                 # on the service prefix of that file"
)]
pub struct ReplayArgs {
    /// The recording directory (holds recording.toml and frames.csv).
    pub recording: PathBuf,

    /// Playback speed relative to the recorded timestamps (2 = twice as fast).
    #[arg(long, default_value_t = 1.0, value_parser = positive_f64, conflicts_with = "rate")]
    pub speed: f64,

    /// Publish at a fixed rate instead of the recorded one, frames per
    /// second. Frames more than 1.5 s apart (`tracking.max_gap_s`), below
    /// 0.67 here, each start a new tracked slope in the estimator.
    #[arg(long, value_parser = positive_f64)]
    pub rate: Option<f64>,

    /// Start again from the first frame at the end (indices keep increasing).
    #[arg(long = "loop")]
    pub looping: bool,

    /// Stop after this many frames (at least 1).
    #[arg(long, value_parser = max_frames_arg)]
    pub max_frames: Option<u64>,

    /// The slope config file, for its service_prefix (the rest is checked,
    /// not used: the recording carries its own mount). Without it replay
    /// reads /etc/slope/slope.toml if that exists.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,

    /// Start only when this many subscribers are connected to the cloud
    /// topic, so that nothing is lost (0-6: the topic takes at most 6).
    #[arg(long, default_value_t = 0, value_parser = wait_subscribers_arg)]
    pub wait_subscribers: usize,

    /// Give up (non-zero exit) if the --wait-subscribers are not there after
    /// this many seconds; waits forever when not given. Needs
    /// --wait-subscribers (without it nothing is waited for).
    #[arg(
        long = "wait-timeout-s",
        alias = "wait-timeout",
        value_name = "S",
        allow_hyphen_values = true,
        value_parser = positive_f64,
        requires = "wait_subscribers"
    )]
    pub wait_timeout: Option<f64>,

    /// Skip frames whose depth images are missing or broken (with a
    /// warning) instead of stopping with an error. A recording none of whose
    /// frames can be read is still an error. (A colour image that cannot be
    /// read is always a warning: that frame is published without colour.)
    #[arg(long)]
    pub skip_bad_frames: bool,

    /// Keep the publisher up this long after the last frame, so that
    /// subscribers still read what is queued for them (skipped on Ctrl-C;
    /// 0: end at once).
    #[arg(
        long = "linger-s",
        alias = "linger",
        value_name = "S",
        allow_hyphen_values = true,
        default_value_t = 1.0,
        value_parser = seconds_or_zero
    )]
    pub linger: f64,

    /// Largest cloud (width x height) to accept.
    #[arg(long, default_value_t = DEFAULT_MAX_CLOUD_POINTS)]
    pub max_points: usize,

    #[command(flatten)]
    pub common: CommonArgs,
}

/// Smallest and largest value [`positive_f64`] accepts: rates, speeds and
/// timeouts outside this range are typing errors, and would overflow clocks.
pub const POSITIVE_RANGE: (f64, f64) = (1e-3, 1e7);

/// Parses a positive number within [`POSITIVE_RANGE`].
/// Seconds, 0 included, at most [`POSITIVE_RANGE`]'s upper end.
fn seconds_or_zero(text: &str) -> Result<f64, String> {
    let value: f64 = text
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    let max = POSITIVE_RANGE.1;
    if (0.0..=max).contains(&value) {
        Ok(value)
    } else {
        Err(format!(
            "'{text}' must be a number of seconds from 0 to {max}"
        ))
    }
}

pub fn positive_f64(text: &str) -> Result<f64, String> {
    let value: f64 = text
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    let (min, max) = POSITIVE_RANGE;
    if (min..=max).contains(&value) {
        Ok(value)
    } else {
        Err(format!(
            "'{text}' must be a positive number from {min} to {max}"
        ))
    }
}

pub fn run(args: &ReplayArgs, stop: &StopFlag) -> anyhow::Result<PublishStats> {
    let recording = open_recording(&args.recording, args.max_points, stop)
        .with_context(|| format!("cannot replay {}", args.recording.display()))?;
    let frames = recording.frames().len();
    check_carried_sensor_name(&recording.meta().sensor).with_context(|| {
        format!(
            "cannot replay {}: its recording.toml `sensor` does not fit a cloud",
            args.recording.display()
        )
    })?;
    let mut source = RecordingSource::new(recording, args.looping).stop_reads_on(stop.clone());
    let Some(names) = service_names(args, stop)? else {
        tracing::info!("stopped before the config file was read");
        return Ok(PublishStats {
            stopped: true,
            ..PublishStats::default()
        });
    };
    let node = create_node(&node_name("slope-replay"))?;
    let publisher = CloudPublisher::create(&node, &names, source.info(), args.max_points)?;
    let info = source.info();
    tracing::info!(
        recording = %args.recording.display(),
        frames,
        width = info.width,
        height = info.height,
        sensor = info.sensor,
        service = publisher.service_name(),
        "replaying"
    );
    let options = PublishOptions {
        pacing: match args.rate {
            Some(hz) => Pacing::Rate { hz },
            None => Pacing::Recorded { speed: args.speed },
        },
        max_frames: args.max_frames,
        wait_subscribers: args.wait_subscribers,
        wait_timeout: args.wait_timeout.map(Duration::from_secs_f64),
        skip_bad_frames: args.skip_bad_frames,
    };
    let stats = publish_stream(&mut source, &publisher, &options, stop)?;
    if stats.published == 0 && !stats.stopped {
        anyhow::bail!(
            "cannot replay {}: no frame could be read ({} skipped as bad)",
            args.recording.display(),
            stats.skipped_bad
        );
    }
    if !stats.stopped {
        // Leaving at once would take the last samples with us before a
        // subscriber that is still connecting could read them.
        stop.sleep(Duration::from_secs_f64(args.linger));
    }
    tracing::info!(
        published = stats.published,
        skipped_bad = stats.skipped_bad,
        interrupted = stats.stopped,
        "replay finished"
    );
    Ok(stats)
}

/// A cloud carries the sensor's name in [`SENSOR_NAME_LEN`] bytes, and
/// `slope-estimator` picks its noise model from it. A longer name is cut
/// (with a warning); when the cut name would give another noise model than
/// the whole one (which `slope-eval` and this recording's own readers use),
/// the replay would make the estimator's slopes differ from `slope-eval`'s
/// without a word: refused, saying how to fix it.
fn check_carried_sensor_name(name: &str) -> anyhow::Result<()> {
    let mut header = CloudHeader::default();
    header.set_sensor_name(name);
    let carried = header.sensor_name();
    if carried == name {
        return Ok(());
    }
    let (whole, cut) = (
        NoiseModel::for_sensor(name),
        NoiseModel::for_sensor(carried),
    );
    if whole != cut {
        anyhow::bail!(
            "the sensor name {name:?} is {} bytes and a cloud carries {SENSOR_NAME_LEN} ({carried:?}): \
             slope-estimator would use the {} noise model where the whole name gives {} \
             (as slope-eval uses); shorten `sensor` to at most {SENSOR_NAME_LEN} bytes that keep \
             the camera's name (e.g. \"{}\")",
            name.len(),
            cut.name(),
            whole.name(),
            whole.name()
        );
    }
    tracing::warn!(
        sensor = name,
        carried,
        "the sensor name is longer than a cloud carries ({SENSOR_NAME_LEN} bytes): subscribers \
         (and a slope-record of this replay) see it cut"
    );
    Ok(())
}

/// The service names: `--service-prefix`, else the config file's. `None`
/// when `stop` came while the file was read.
fn service_names(args: &ReplayArgs, stop: &StopFlag) -> anyhow::Result<Option<ServiceNames>> {
    let path = config_path(args.config.as_deref(), Path::new(DEFAULT_CONFIG_PATH));
    let file = SlopeFile::load_or_stop(path.as_deref(), stop)?;
    Ok(file.map(|file| ServiceNames::new(args.common.prefix_or(&file.service_prefix))))
}

/// `--wait-subscribers`: at most the cloud topic's subscriber limit.
fn wait_subscribers_arg(text: &str) -> Result<usize, String> {
    let n: usize = text
        .parse()
        .map_err(|_| format!("`{text}` is not a whole number"))?;
    let max = slope_sensor::ipc::CLOUD_MAX_SUBSCRIBERS;
    if n > max {
        return Err(format!(
            "{n} subscribers can never connect: the cloud topic takes at most {max}"
        ));
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sensor_name_cut_into_another_noise_model_is_refused() {
        assert!(check_carried_sensor_name("kinect2").is_ok());
        assert!(check_carried_sensor_name(&"x".repeat(SENSOR_NAME_LEN)).is_ok());
        // Cut, but "kinect1" stays within the 32 bytes: the same model.
        assert!(check_carried_sensor_name("kinect1 in the lab, second floor, left wing").is_ok());
        // "Xtion" falls beyond byte 32: the cut name reads as a Kinect v2.
        let long = "freiburg1 desk sequence, Asus Xtion";
        let err = check_carried_sensor_name(long).expect_err("the model would change");
        let text = err.to_string();
        assert!(
            text.contains("\"freiburg1 desk sequence, Asus Xt\""),
            "{text}"
        );
        assert!(
            text.contains("kinect2 noise model where the whole name gives kinect1"),
            "{text}"
        );
    }

    #[test]
    fn a_wait_timeout_needs_wait_subscribers() {
        let parse =
            |args: &[&str]| ReplayArgs::try_parse_from(["slope-replay", "rec"].iter().chain(args));
        let err = parse(&["--wait-timeout-s", "1"]).expect_err("nothing to wait for");
        assert_eq!(err.kind(), clap::error::ErrorKind::MissingRequiredArgument);
        assert!(err.to_string().contains("--wait-subscribers"), "{err}");
        let args = parse(&["--wait-timeout-s", "1", "--wait-subscribers", "1"]).expect("valid");
        assert_eq!(args.wait_timeout, Some(1.0));
    }

    /// `--linger-s 0` ends at once (it was refused: "from 0.001"); a
    /// negative linger is refused by its range.
    #[test]
    fn linger_takes_zero_and_refuses_negative() {
        let parse =
            |args: &[&str]| ReplayArgs::try_parse_from(["slope-replay", "rec"].iter().chain(args));
        assert_eq!(parse(&["--linger-s", "0"]).expect("valid").linger, 0.0);
        assert_eq!(parse(&[]).expect("valid").linger, 1.0);
        let err = parse(&["--linger-s", "-1"]).expect_err("negative");
        assert!(err.to_string().contains("from 0 to"), "{err}");
    }
}
