//! [`SlopeFile`]: the one configuration file of every slope daemon
//! (`/etc/slope/slope.toml` when it exists, or `--config FILE`).
//!
//! ```toml
//! service_prefix = "slope"   # the daemons' --service-prefix
//!
//! [health]
//! interval_s = 1.0           # --health-interval-s
//!
//! [mount]                    # the camera on the robot (slope-capture)
//! height_m = 0.5
//! pitch_deg = -20.0
//!
//! [capture]                  # the Kinect v2 (slope-capture)
//! pipeline = "cl"
//!
//! [estimator]                # slope_pipeline::EstimatorConfig (slope-estimator)
//! method = "paper"
//! [estimator.ransac]
//! max_planes = 16
//!
//! [ros2]                     # the ROS 2 node (slope-ros2)
//! namespace = "/robot1"
//! ```
//!
//! Every daemon parses the whole file, so a typo anywhere is an error that
//! names the key with its full path (`estimator.ransac.max_planez`), and a
//! value out of its range names the key and the range. Command-line flags
//! override the file.
//!
//! One concern per file:
//! - `sections.rs`: the sections and their defaults ([`SlopeFile`],
//!   [`HealthSection`], [`CaptureSection`], [`Ros2Section`]);
//! - `parse.rs`: reading and writing the file, an old layout refused with
//!   how to fix it;
//! - `locate.rs`: where in the text a key or an error is (line, full path);
//! - `validate.rs`: the ranges of the values ([`SlopeFile::validate`],
//!   [`check_health_interval`]);
//! - `error.rs`: why a file was refused ([`ConfigFileError`]);
//! - `tests.rs`: unit tests.
//!
//! This file: where the file is ([`config_path`], [`DEFAULT_CONFIG_PATH`])
//! and the exit status of a daemon it stops ([`EXIT_CONFIG`]).

use std::path::{Path, PathBuf};

mod error;
mod locate;
mod parse;
mod sections;
#[cfg(test)]
mod tests;
mod validate;

pub use error::ConfigFileError;
pub use sections::{CaptureSection, HealthSection, Ros2Section, SlopeFile, PIPELINES};
pub use validate::check_health_interval;

/// The file the daemons read when not given `--config`, if it exists (the
/// Debian package installs it, every key commented out).
pub const DEFAULT_CONFIG_PATH: &str = "/etc/slope/slope.toml";

/// Exit status of a daemon whose settings are wrong (an unreadable config
/// file, a parse error, an unknown key, a value out of range): `EX_CONFIG`
/// from sysexits.h. The units say `RestartPreventExitStatus=78`, so that a
/// typo in the file leaves the unit failed instead of restarting it forever.
pub const EXIT_CONFIG: u8 = 78;

/// Whether `err` is (or was caused by) a config-file error: see
/// [`EXIT_CONFIG`].
pub fn is_config_error(err: &anyhow::Error) -> bool {
    err.chain().any(|cause| cause.is::<ConfigFileError>())
}

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
