//! The command line of `slope-bend` and [`run`], which its `main` calls
//! after parsing and setting up logging.

use std::ops::ControlFlow;
use std::path::PathBuf;

use anyhow::Context;
use clap::Parser;
use slope_sensor::publish::StopFlag;

use super::{write_bent_recording, BendParams, BendSummary, ANGLE_RANGE, HINGE_RANGE};
use crate::cli::Compression;

const EXAMPLES: &str = "\
Examples:
  # A wheelchair ramp (5°) 1.5 m ahead on the floor of a real Kinect v2 frame
  slope-bend ../shared/data/kv2-mine-tunnel-0 -o /tmp/tunnel-ramp5 --angle-deg 5 --hinge-m 1.5

  # Frame 12 of a recording of your own floor, bent 16° from 2 m ahead
  slope-bend scene1 -o /tmp/scene1-ramp16 --angle-deg 16 --hinge-m 2 --frame 12

  # How well the estimator finds it
  slope-eval /tmp/tunnel-ramp5

Without --frame every frame is bent, each with its own floor fit. The floor is found by RANSAC
(seeded by --seed) over the up-facing points of the lower image, with the recording's [mount] as
the hint for up (else the camera's -y); everything beyond the hinge line is rotated upward about
it and re-rendered with a z-buffer. A frame whose floor does not reach past the hinge is refused.
The output keeps the source's sensor, intrinsics and mount, sets [truth] slope_deg to the angle
and writes bend.toml (the fitted floor per frame). What such data does not reproduce is listed
in tools/synth/README.md.";

/// Bends a real frame's floor into a ramp of known angle: everything
/// beyond a hinge line across the path is rotated upward about it and
/// re-rendered, and the angle is written as the recording's truth.
#[derive(Debug, Clone, Parser)]
#[command(name = "slope-bend", version, after_help = EXAMPLES)]
pub struct BendArgs {
    /// The source recording (a directory with recording.toml).
    #[arg(value_name = "RECORDING")]
    pub recording: PathBuf,

    /// Output recording directory (must not exist, or be empty).
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub output: PathBuf,

    /// The ramp's angle to the floor, degrees, above 0 and at most 90.
    #[arg(
        long = "angle-deg",
        value_name = "DEG",
        allow_hyphen_values = true,
        value_parser = angle_arg
    )]
    pub angle_deg: f64,

    /// Distance of the hinge line ahead of the camera's foot on the floor,
    /// metres.
    #[arg(
        long = "hinge-m",
        value_name = "M",
        allow_hyphen_values = true,
        value_parser = hinge_arg,
        default_value_t = 1.5
    )]
    pub hinge_m: f64,

    /// Bend only this frame (0-based row of frames.csv); without it, every
    /// frame.
    #[arg(long, value_name = "N")]
    pub frame: Option<usize>,

    /// Seed of the floor fit (the same seed gives the same bytes).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,

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

impl BendArgs {
    /// The log level of `-v`/`-q`, as in every slope program.
    pub fn log_level(&self) -> &'static str {
        match (self.quiet, self.verbose) {
            (true, _) => "error",
            (false, 0) => "info",
            (false, 1) => "debug",
            (false, _) => "trace",
        }
    }

    pub fn params(&self) -> BendParams {
        BendParams {
            angle_deg: self.angle_deg,
            hinge_m: self.hinge_m,
            seed: self.seed,
        }
    }
}

/// Bends and writes the recording the arguments describe; stops after the
/// frame being written when `stop` is set (a valid, shorter recording).
pub fn run(args: &BendArgs, stop: &StopFlag) -> anyhow::Result<BendSummary> {
    write_bent_recording(
        &args.recording,
        &args.output,
        args.frame,
        &args.params(),
        args.compression.into(),
        |k| {
            tracing::debug!(frame = k, "written");
            if stop.is_stopped() {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        },
    )
    .with_context(|| {
        format!(
            "failed to bend {} into {}",
            args.recording.display(),
            args.output.display()
        )
    })
}

fn number(text: &str) -> Result<f64, String> {
    text.trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))
}

/// `--angle-deg`: above 0, at most 90.
fn angle_arg(text: &str) -> Result<f64, String> {
    let value = number(text)?;
    if value > 0.0 && value <= 90.0 {
        Ok(value)
    } else {
        Err(ANGLE_RANGE.to_string())
    }
}

/// `--hinge-m`: a finite distance above 0.
fn hinge_arg(text: &str) -> Result<f64, String> {
    let value = number(text)?;
    if value > 0.0 && value.is_finite() {
        Ok(value)
    } else {
        Err(HINGE_RANGE.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_and_their_ranges() {
        let args = BendArgs::try_parse_from([
            "slope-bend",
            "REC",
            "-o",
            "OUT",
            "--angle-deg",
            "5",
            "--hinge-m",
            "2",
            "--frame",
            "3",
            "-v",
        ])
        .expect("valid");
        assert_eq!(
            args.params(),
            BendParams {
                angle_deg: 5.0,
                hinge_m: 2.0,
                seed: 0
            }
        );
        assert_eq!((args.frame, args.log_level()), (Some(3), "debug"));
        for (flag, bad, reason) in [
            ("--angle-deg", "-5", ANGLE_RANGE),
            ("--angle-deg", "0", ANGLE_RANGE),
            ("--angle-deg", "91", ANGLE_RANGE),
            ("--hinge-m", "-1", HINGE_RANGE),
            ("--hinge-m", "inf", HINGE_RANGE),
        ] {
            let mut all = vec!["slope-bend", "REC", "-o", "OUT", flag, bad];
            if flag != "--angle-deg" {
                all.extend(["--angle-deg", "5"]);
            }
            let err = BendArgs::try_parse_from(all).expect_err("out of range");
            let text = err.render().to_string();
            assert!(text.contains(flag) && text.contains(reason), "{text}");
        }
        assert!(BendArgs::try_parse_from(["slope-bend", "REC", "-o", "OUT"]).is_err());
    }
}
