//! The command line of `slope-synth`: flags for the common cases, a TOML
//! scene file for the rest, and [`run`], which the binary calls after
//! parsing and setting up logging.

use std::ops::ControlFlow;
use std::path::PathBuf;

use anyhow::Context;
use clap::{Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use slope_sensor::publish::{StopFlag, StopRequest, StopSignals};
use slope_sensor::recording::PngCompression;

use crate::recording::{write_recording_with, RecordingSummary, WriteOptions};
use crate::scene::{self, load_scene_file, Ramp, Scene, SlopeDirection, ValueRule};
use crate::sensor_model::{RangeBias, SensorModel};

const EXAMPLES: &str = "\
Examples:
  # The default scene: a 16° ramp up, 1.5 m ahead, camera 0.5 m high looking 20° down
  slope-synth --slope 16 --distance 1.5 --mount-height-m 0.5 --mount-pitch-deg -20 -o /tmp/ramp16

  # Exact geometry (no noise, no jitter, no dropouts) for tests
  slope-synth --slope 16 --clean --frames 10 -o /tmp/ramp16-clean

  # The ground drops away 8° from 1.2 m ahead; look down steeper to see it
  slope-synth --slope 8 --descending --distance 1.2 --mount-pitch-deg -35 -o /tmp/down8

  # A wall 2 m ahead, seen at a 20° yaw, driving towards it at 0.3 m/s
  slope-synth --slope 90 --distance 2 --yaw 20 --speed-mps 0.3 -o /tmp/wall

  # A flat floor read with the Kinect v1's range bias (depth z + k z^2: the floor
  # seen z metres ahead lies 0.01 z below the truth), exact otherwise
  slope-synth --slope 0 --mount-height-m 1.2 --mount-pitch-deg -30 --clean --range-bias kinect1 -o /tmp/bent

  # Everything else (boxes, side walls, tables, a ceiling, soft blocks, sensor
  # parameters) from a scene file; flags given on the command line override it
  slope-synth --scene scene.toml --seed 3 -o /tmp/scene

SIGINT or SIGTERM (Ctrl-C) stops after the frame being rendered: the recording then holds the
frames written so far (recording.toml, a frames.csv row for every depth image), the log says how
many, and the exit status is 0. A second signal ends the program at once (status 130).

Conventions: world x right, y forward, z up; camera x right, y down, z forward.
Depth PNGs hold z along the optical axis in millimetres (0 = no reading).
The scene file format and the sensor model are documented in tools/synth/README.md.";

/// Simulates a Kinect v2 looking at a ramp and writes a slope recording
/// (recording.toml, frames.csv, depth/*.png, color/*.png) with exact ground
/// truth.
#[derive(Debug, Clone, Parser)]
#[command(name = "slope-synth", version, after_help = EXAMPLES)]
pub struct Args {
    /// Output recording directory (must not exist, or be empty).
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub output: PathBuf,

    /// TOML scene file (camera, mount, motion, ramp, walls, boxes, sensor).
    /// Without it the scene is the default ramp scene; flags override it.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,

    /// Angle of the inclined plane to the ground, degrees, above -90 and at
    /// most 90: 90 is a wall; 0 removes the ramp (flat ground only);
    /// negative is a descending slope (as --descending).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true, value_parser = slope_arg)]
    pub slope: Option<f64>,

    /// The ground drops away at the foot line instead of rising.
    #[arg(long)]
    pub descending: bool,

    /// Forward distance from the camera to the ramp's foot line, metres.
    #[arg(long, value_name = "M", allow_hyphen_values = true, value_parser = distance_arg)]
    pub distance: Option<f64>,

    /// Width of the ramp across the slope, metres ("inf" for unbounded).
    #[arg(long, value_name = "M", allow_hyphen_values = true, value_parser = width_arg)]
    pub width: Option<f64>,

    /// Length of the ramp along the slope, metres ("inf" for unbounded).
    #[arg(long, value_name = "M", allow_hyphen_values = true, value_parser = length_arg)]
    pub length: Option<f64>,

    /// Flat landing on top of an ascending ramp, metres (0 = none).
    #[arg(long, value_name = "M", allow_hyphen_values = true, value_parser = landing_arg)]
    pub landing: Option<f64>,

    /// Ramp seen at a yaw angle: positive turns its uphill direction left, degrees.
    #[arg(long, value_name = "DEG", allow_hyphen_values = true, value_parser = yaw_arg)]
    pub yaw: Option<f64>,

    /// Camera's optical centre above the ground, metres (`[mount]
    /// height_m`).
    #[arg(
        long = "mount-height-m",
        alias = "height",
        value_name = "M",
        allow_hyphen_values = true,
        value_parser = height_arg
    )]
    pub height: Option<f64>,

    /// Camera pitch, degrees; negative looks down (`[mount] pitch_deg`).
    #[arg(
        long = "mount-pitch-deg",
        alias = "pitch",
        value_name = "DEG",
        allow_hyphen_values = true,
        value_parser = pitch_arg
    )]
    pub pitch: Option<f64>,

    /// Camera roll, degrees; positive dips the image's right side
    /// (`[mount] roll_deg`).
    #[arg(
        long = "mount-roll-deg",
        alias = "roll",
        value_name = "DEG",
        allow_hyphen_values = true,
        value_parser = roll_arg
    )]
    pub roll: Option<f64>,

    /// Forward speed of the camera between frames, metres per second.
    #[arg(
        long = "speed-mps",
        alias = "speed",
        value_name = "M/S",
        allow_hyphen_values = true,
        value_parser = speed_arg
    )]
    pub speed: Option<f64>,

    /// Add two side walls 1 m high at x = -M and x = +M, from 0 to 6 m ahead.
    #[arg(long, value_name = "M", allow_hyphen_values = true, value_parser = side_walls_arg)]
    pub side_walls: Option<f64>,

    /// Number of frames (30 Hz), at least 1.
    #[arg(long, default_value_t = 30, value_parser = frames_arg)]
    pub frames: u64,

    /// Seed of the random noise: the same seed gives the same bytes.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,

    /// Exact geometry: switch off every sensor effect (noise, flying pixels,
    /// multipath, dropouts, range limits, pose jitter).
    #[arg(long)]
    pub clean: bool,

    /// The sensor's range bias: none, kinect2 or kinect1. Each depth z is
    /// read as z + k z^2 along its ray, k = c / (camera height), so a flat
    /// floor seen z ahead lies c z below the truth (c = 0.005 kinect2, 0.01
    /// kinect1: the pipeline's floor height bias). Overrides the scene
    /// file's `[sensor] range_bias`; applies after --clean.
    #[arg(long, value_enum, value_name = "SENSOR")]
    pub range_bias: Option<RangeBias>,

    /// Write depth images only (no colour images).
    #[arg(long)]
    pub depth_only: bool,

    /// PNG compression: fast, balanced or high (smallest files).
    #[arg(long, value_enum, default_value_t = Compression::Balanced)]
    pub compression: Compression,

    /// More log output (-v debug, -vv trace). RUST_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count)]
    pub verbose: u8,

    /// Less log output (errors only).
    #[arg(short, long, conflicts_with = "verbose")]
    pub quiet: bool,
}

/// PNG compression level of the written images.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Compression {
    Fast,
    Balanced,
    High,
}

impl From<Compression> for PngCompression {
    fn from(c: Compression) -> Self {
        match c {
            Compression::Fast => PngCompression::Fast,
            Compression::Balanced => PngCompression::Balanced,
            Compression::High => PngCompression::High,
        }
    }
}

impl Args {
    /// The log level of `-v`/`-q`, as in every slope program.
    pub fn log_level(&self) -> &'static str {
        match (self.quiet, self.verbose) {
            (true, _) => "error",
            (false, 0) => "info",
            (false, 1) => "debug",
            (false, _) => "trace",
        }
    }

    /// The scene and sensor model these arguments describe: the default
    /// ramp scene (or the scene file), overridden by the flags given. The
    /// flags' values were checked when parsed (an error names the flag); a
    /// scene file's are checked when loaded (an error names the key).
    pub fn scene_and_model(&self) -> anyhow::Result<(Scene, SensorModel)> {
        let (mut scene, file_model) = match &self.scene {
            Some(path) => {
                let file = load_scene_file(path)
                    .with_context(|| format!("failed to load scene file {}", path.display()))?;
                (file.scene, file.sensor)
            }
            None => (Scene::default_ramp(), None),
        };
        let mut model = file_model.unwrap_or_default();
        if self.clean {
            model = SensorModel::clean();
        }
        if let Some(bias) = self.range_bias {
            model.range_bias = bias;
        }
        self.apply_camera_and_wall_flags(&mut scene);
        self.apply_ramp_flags(&mut scene)?;
        scene.validate().context("invalid scene")?;
        model.validate().context("invalid sensor model")?;
        Ok((scene, model))
    }

    /// The mount flags, `--speed-mps` and `--side-walls`.
    fn apply_camera_and_wall_flags(&self, scene: &mut Scene) {
        if let Some(h) = self.height {
            scene.mount.height_m = h;
        }
        if let Some(p) = self.pitch {
            scene.mount.pitch_deg = p;
        }
        if let Some(r) = self.roll {
            scene.mount.roll_deg = r;
        }
        if let Some(s) = self.speed {
            scene.motion.speed_mps = s;
        }
        if let Some(x) = self.side_walls {
            for side in [-1.0, 1.0] {
                scene.walls.push(crate::scene::SideWall {
                    x_m: side * x,
                    ..Default::default()
                });
            }
        }
    }

    /// `--slope`, `--descending` and the ramp's other flags.
    fn apply_ramp_flags(&self, scene: &mut Scene) -> anyhow::Result<()> {
        let ramp_flags = self.distance.is_some()
            || self.width.is_some()
            || self.length.is_some()
            || self.landing.is_some()
            || self.yaw.is_some()
            || self.descending;
        if self.slope == Some(0.0) {
            anyhow::ensure!(
                !ramp_flags,
                "--slope 0 removes the ramp; drop the ramp flags"
            );
            scene.ramp = None;
            return Ok(());
        }
        if self.slope.is_none() && !ramp_flags {
            return Ok(());
        }
        let ramp = scene.ramp.get_or_insert_with(Ramp::default);
        if let Some(s) = self.slope {
            ramp.slope_deg = s.abs();
        }
        if self.descending || self.slope.is_some_and(|s| s < 0.0) {
            ramp.direction = SlopeDirection::Descending;
        }
        // The one check that spans two values: name the flag given.
        anyhow::ensure!(
            !(self.descending && ramp.slope_deg >= 90.0),
            "--descending: a descending slope must be below 90° (the ramp's is {}°)",
            ramp.slope_deg
        );
        if let Some(d) = self.distance {
            ramp.distance_m = d;
        }
        if let Some(w) = self.width {
            ramp.width_m = w;
        }
        if let Some(l) = self.length {
            ramp.length_m = l;
        }
        if let Some(l) = self.landing {
            ramp.landing_m = l;
        }
        if let Some(y) = self.yaw {
            ramp.yaw_deg = y;
        }
        Ok(())
    }
}

/// Installs the SIGINT/SIGTERM handler and returns the flag it sets; a
/// second signal while stopping ends the process at once (status 130). A
/// signal repeated within 50 ms is the same request
/// ([`StopSignals`]: `timeout` sends two).
pub fn stop_on_signals() -> anyhow::Result<StopFlag> {
    let stop = StopFlag::new();
    let handler_flag = stop.clone();
    let mut signals = StopSignals::new();
    ctrlc::set_handler(move || match signals.note(std::time::Instant::now()) {
        StopRequest::Second => std::process::exit(130),
        StopRequest::Repeat => {}
        StopRequest::First => handler_flag.stop(),
    })
    .context("failed to install the SIGINT/SIGTERM handler")?;
    Ok(stop)
}

/// Sets up the programs' logging: to stderr at `level` (`RUST_LOG`
/// overrides it), in colour only on a terminal.
pub fn init_logging(level: &str) {
    use std::io::IsTerminal;
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level)),
        )
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .init();
}

/// The exit status of a program whose `run` ended with `result`: on
/// success a recording `(dir, frames written, frames asked)`, logged as
/// done, or as a valid recording of the frames written before a stop; an
/// error is printed once, a line per cause, no backtrace (as the other
/// programs).
pub fn exit_code(result: anyhow::Result<(PathBuf, u64, u64)>) -> std::process::ExitCode {
    use std::process::ExitCode;
    match result {
        Ok((dir, frames, asked)) if frames < asked => {
            tracing::info!(
                dir = %dir.display(),
                frames,
                asked,
                "interrupted: a valid recording of the frames written so far"
            );
            ExitCode::SUCCESS
        }
        Ok((dir, frames, _)) => {
            tracing::info!(dir = %dir.display(), frames, "done");
            ExitCode::SUCCESS
        }
        Err(err) => {
            eprintln!("error: {err}");
            for cause in err.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::FAILURE
        }
    }
}

/// Renders and writes the recording the arguments describe. When `stop` is
/// set, it stops after the frame being rendered and leaves a valid
/// recording of the frames written so far
/// ([`RecordingSummary::is_partial`]).
pub fn run(args: &Args, stop: &StopFlag) -> anyhow::Result<RecordingSummary> {
    let (scene, model) = args.scene_and_model()?;
    let options = WriteOptions {
        color: !args.depth_only,
        compression: args.compression.into(),
    };
    let progress = ProgressBar::new(args.frames);
    progress.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames, {eta} left")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    progress.set_message("rendering");
    let summary = write_recording_with(
        &scene,
        &model,
        args.frames,
        args.seed,
        &args.output,
        options,
        |_| {
            progress.inc(1);
            if stop.is_stopped() {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        },
    )
    .with_context(|| format!("failed to write recording {}", args.output.display()));
    progress.finish_and_clear();
    summary
}

/// What `--slope` answers outside (-90, 90].
pub const SLOPE_RANGE: &str =
    "must be above -90 and at most 90 degrees (0: no ramp; negative: descending, 90: a wall)";

/// `--slope DEG`: above -90 (a descending slope is below 90°) and at most
/// 90; its magnitude is the ramp's angle, 0 none.
fn slope_arg(text: &str) -> Result<f64, String> {
    let value: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    if value > -90.0 && value <= 90.0 {
        Ok(value)
    } else {
        Err(SLOPE_RANGE.to_string())
    }
}

/// `--frames`: a whole number, at least 1.
fn frames_arg(text: &str) -> Result<u64, String> {
    match text.trim().parse::<u64>() {
        Ok(0) => Err("must be at least 1".to_string()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!("'{text}' is not a whole number")),
    }
}

/// A flag that sets a scene value: a number that `rule` accepts, else
/// the rule's reason (which clap prints after the flag and the value typed,
/// where a scene file's error names the key).
fn scene_value_arg(text: &str, rule: ValueRule) -> Result<f64, String> {
    let value: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    if (rule.accepts)(value) {
        Ok(value)
    } else {
        Err(rule.reason.to_string())
    }
}

fn distance_arg(text: &str) -> Result<f64, String> {
    scene_value_arg(text, scene::RAMP_DISTANCE)
}

fn width_arg(text: &str) -> Result<f64, String> {
    scene_value_arg(text, scene::RAMP_WIDTH)
}

fn length_arg(text: &str) -> Result<f64, String> {
    scene_value_arg(text, scene::RAMP_LENGTH)
}

fn landing_arg(text: &str) -> Result<f64, String> {
    scene_value_arg(text, scene::RAMP_LANDING)
}

fn yaw_arg(text: &str) -> Result<f64, String> {
    scene_value_arg(text, scene::RAMP_YAW)
}

fn height_arg(text: &str) -> Result<f64, String> {
    scene_value_arg(text, scene::MOUNT_HEIGHT)
}

fn pitch_arg(text: &str) -> Result<f64, String> {
    scene_value_arg(text, scene::MOUNT_PITCH)
}

fn roll_arg(text: &str) -> Result<f64, String> {
    scene_value_arg(text, scene::MOUNT_ROLL)
}

fn speed_arg(text: &str) -> Result<f64, String> {
    scene_value_arg(text, scene::MOTION_SPEED)
}

fn side_walls_arg(text: &str) -> Result<f64, String> {
    scene_value_arg(text, scene::WALL_X)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Args {
        let mut all = vec!["slope-synth", "-o", "/tmp/x"];
        all.extend_from_slice(args);
        Args::try_parse_from(all).expect("valid arguments")
    }

    #[test]
    fn flags_build_the_documented_scene() {
        let args = parse(&[
            "--slope",
            "16",
            "--distance",
            "1.5",
            "--mount-height-m",
            "0.5",
            "--mount-pitch-deg",
            "-20",
            "--frames",
            "30",
            "--seed",
            "7",
        ]);
        let (scene, model) = args.scene_and_model().expect("valid");
        assert_eq!(scene, Scene::default_ramp());
        assert_eq!(model, SensorModel::default());
        assert_eq!((args.frames, args.seed), (30, 7));
    }

    #[test]
    fn descending_clean_and_flat() {
        let (scene, model) = parse(&["--slope", "8", "--descending", "--clean", "--yaw", "-10"])
            .scene_and_model()
            .expect("valid");
        let ramp = scene.ramp.expect("ramp");
        assert_eq!(ramp.direction, SlopeDirection::Descending);
        assert_eq!((ramp.slope_deg, ramp.yaw_deg), (8.0, -10.0));
        assert!(model.is_clean());
        let (flat, _) = parse(&["--slope", "0"]).scene_and_model().expect("valid");
        assert!(flat.ramp.is_none());
        assert!(parse(&["--slope", "0", "--distance", "2"])
            .scene_and_model()
            .is_err());
        for bad in ["100", "-90", "nan", "inf"] {
            let err = Args::try_parse_from(["slope-synth", "-o", "/tmp/x", "--slope", bad])
                .expect_err("out of range");
            let text = err.render().to_string();
            assert!(text.contains("--slope"), "{text}");
            assert!(text.contains(SLOPE_RANGE), "{text}");
            assert!(!text.contains("ramp.slope_deg"), "{text}");
        }
        let (wall, _) = parse(&["--slope", "90"]).scene_and_model().expect("valid");
        assert_eq!(wall.ramp.expect("ramp").slope_deg, 90.0);
        let (steep, _) = parse(&["--slope", "-89.5"])
            .scene_and_model()
            .expect("valid");
        assert_eq!(steep.ramp.expect("ramp").slope_deg, 89.5);
        let (down, _) = parse(&["--slope", "-5"]).scene_and_model().expect("valid");
        let ramp = down.ramp.expect("ramp");
        assert_eq!(ramp.direction, SlopeDirection::Descending);
        assert_eq!(ramp.slope_deg, 5.0);
    }

    #[test]
    fn range_bias_flag_sets_the_model_after_clean() {
        let (_, model) = parse(&["--clean", "--range-bias", "kinect1"])
            .scene_and_model()
            .expect("valid");
        assert_eq!(model.range_bias, RangeBias::Kinect1);
        assert!(!model.is_clean());
        assert_eq!(
            SensorModel {
                range_bias: RangeBias::None,
                ..model
            },
            SensorModel::clean()
        );
        let (_, model) = parse(&[]).scene_and_model().expect("valid");
        assert_eq!(model.range_bias, RangeBias::None);
        assert!(
            Args::try_parse_from(["slope-synth", "-o", "x", "--range-bias", "kinect3"]).is_err()
        );
    }

    #[test]
    fn verbosity_flags_are_those_of_every_slope_program() {
        assert_eq!(parse(&["-vv"]).log_level(), "trace");
        assert_eq!(parse(&["-q"]).log_level(), "error");
        assert_eq!(parse(&[]).log_level(), "info");
        assert!(Args::try_parse_from(["slope-synth", "-o", "x", "-q", "-v"]).is_err());
    }
}
