//! The camera mount on the command line, shared by `slope-capture` and
//! `slope-record`: `--mount-height-m`, `--mount-pitch-deg`,
//! `--mount-roll-deg`, each checked for a plausible range when parsed.

use clap::Args;
use slope_ipc_types::Mount;
use slope_sensor::recording::MountRange;

/// The camera's pose on the robot; every value optional (unknown = NaN).
#[derive(Debug, Clone, Copy, Default, PartialEq, Args)]
pub struct MountArgs {
    /// Camera height above the ground, metres (0 < h <= 10).
    #[arg(
        id = "mount_height_m",
        long = "mount-height-m",
        value_name = "M",
        allow_hyphen_values = true,
        value_parser = height_m
    )]
    pub height_m: Option<f64>,

    /// Camera pitch, degrees (-90 ..= 90); negative looks down.
    #[arg(
        id = "mount_pitch_deg",
        long = "mount-pitch-deg",
        value_name = "DEG",
        allow_hyphen_values = true,
        value_parser = pitch_deg
    )]
    pub pitch_deg: Option<f64>,

    /// Camera roll about the optical axis, degrees (-180 ..= 180); positive
    /// dips the image's right side.
    #[arg(
        id = "mount_roll_deg",
        long = "mount-roll-deg",
        value_name = "DEG",
        allow_hyphen_values = true,
        value_parser = roll_deg
    )]
    pub roll_deg: Option<f64>,
}

impl MountArgs {
    /// The command line's values over `base`.
    pub fn over(&self, base: Mount) -> Mount {
        Mount {
            height_m: self.height_m.unwrap_or(base.height_m),
            pitch_deg: self.pitch_deg.unwrap_or(base.pitch_deg),
            roll_deg: self.roll_deg.unwrap_or(base.roll_deg),
        }
    }
}

fn parse_in(text: &str, range: MountRange) -> Result<f64, String> {
    let value: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    range.check(value)
}

fn height_m(text: &str) -> Result<f64, String> {
    parse_in(text, MountRange::HEIGHT_M)
}

fn pitch_deg(text: &str) -> Result<f64, String> {
    parse_in(text, MountRange::PITCH_DEG)
}

fn roll_deg(text: &str) -> Result<f64, String> {
    parse_in(text, MountRange::ROLL_DEG)
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;

    #[derive(Debug, Parser)]
    struct Cli {
        #[command(flatten)]
        mount: MountArgs,
    }

    fn parse(args: &[&str]) -> Result<MountArgs, clap::Error> {
        Cli::try_parse_from(std::iter::once("test").chain(args.iter().copied())).map(|c| c.mount)
    }

    #[test]
    fn values_in_range_are_taken_over_the_base() {
        let mount =
            parse(&["--mount-height-m", "0.5", "--mount-pitch-deg", "-20"]).expect("valid mount");
        let over = mount.over(Mount {
            height_m: 1.0,
            pitch_deg: 0.0,
            roll_deg: 3.0,
        });
        assert_eq!(
            (over.height_m, over.pitch_deg, over.roll_deg),
            (0.5, -20.0, 3.0)
        );
        assert!(MountArgs::default().over(Mount::UNKNOWN).height_m.is_nan());
    }

    #[test]
    fn implausible_values_are_refused() {
        for args in [
            ["--mount-height-m", "-0.5"],
            ["--mount-height-m", "0"],
            ["--mount-height-m", "NaN"],
            ["--mount-height-m", "11"],
            ["--mount-pitch-deg", "400"],
            ["--mount-pitch-deg", "inf"],
            ["--mount-roll-deg", "-181"],
        ] {
            assert!(parse(&args).is_err(), "{args:?} accepted");
        }
        assert!(parse(&["--mount-pitch-deg", "-90", "--mount-roll-deg", "180"]).is_ok());
    }
}
