//! The ranges of the values ([`SlopeFile::validate`]): the first value out
//! of its range is named with its key, its value and the range.

use slope_ipc_types::DEFAULT_SERVICE_PREFIX;
use slope_pipeline::config::ConfigError;

use super::error::ConfigFileError;
use super::sections::{CaptureSection, Ros2Section, SlopeFile, PIPELINES};
use crate::cli::prefix_arg;
use crate::replay::POSITIVE_RANGE;
use crate::ros2_names::{check_domain_id, frame_id_arg, namespace_arg, node_name_arg};

impl SlopeFile {
    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), ConfigFileError> {
        let out_of_range = |key: &str, value: &dyn std::fmt::Display, range: String| {
            Err(ConfigFileError::OutOfRange {
                key: key.to_string(),
                value: value.to_string(),
                range,
            })
        };
        if self.service_prefix.is_empty() {
            return out_of_range(
                "service_prefix",
                &"\"\"",
                format!("an empty prefix names no service; leave the key out for the default '{DEFAULT_SERVICE_PREFIX}'"),
            );
        }
        if let Err(reason) = prefix_arg(&self.service_prefix) {
            return out_of_range(
                "service_prefix",
                &format!("{:?}", self.service_prefix),
                reason,
            );
        }
        if let Err(reason) = check_health_interval(self.health.interval_s) {
            return out_of_range("health.interval_s", &self.health.interval_s, reason);
        }
        self.validate_mount()?;
        self.capture.validate()?;
        self.ros2.validate()?;
        self.estimator.validate().map_err(|e| match e {
            ConfigError::Invalid(invalid) => {
                let invalid = invalid.in_section("estimator");
                ConfigFileError::OutOfRange {
                    key: invalid.key,
                    value: invalid.value,
                    range: invalid.reason.to_string(),
                }
            }
            ConfigError::Parse(e) => ConfigFileError::Syntax {
                line: None,
                message: e.to_string(),
            },
        })
    }

    fn validate_mount(&self) -> Result<(), ConfigFileError> {
        self.mount
            .check()
            .map_err(|(key, value, range)| ConfigFileError::OutOfRange {
                key: format!("mount.{key}"),
                value: value.to_string(),
                range,
            })
    }
}

impl CaptureSection {
    fn validate(&self) -> Result<(), ConfigFileError> {
        let (min, max) = POSITIVE_RANGE;
        let bad = |key: &str, value: String, range: String| {
            Err(ConfigFileError::OutOfRange {
                key: format!("capture.{key}"),
                value,
                range,
            })
        };
        if !PIPELINES.contains(&self.pipeline.as_str()) {
            return bad(
                "pipeline",
                format!("{:?}", self.pipeline),
                format!("must be one of {}", PIPELINES.join(", ")),
            );
        }
        if !(self.min_depth_m >= min && self.min_depth_m <= max) {
            return bad(
                "min_depth_m",
                self.min_depth_m.to_string(),
                format!("must be from {min} to {max} m, below max_depth_m"),
            );
        }
        if !(self.max_depth_m >= min && self.max_depth_m <= max) {
            return bad(
                "max_depth_m",
                self.max_depth_m.to_string(),
                format!("must be from {min} to {max} m, above min_depth_m"),
            );
        }
        if self.max_depth_m <= self.min_depth_m {
            return Err(ConfigFileError::NotAbove {
                high_key: "capture.max_depth_m".into(),
                high: self.max_depth_m.to_string(),
                low_key: "capture.min_depth_m".into(),
                low: self.min_depth_m.to_string(),
            });
        }
        if !(min..=max).contains(&self.frame_timeout_s) {
            return bad(
                "frame_timeout_s",
                self.frame_timeout_s.to_string(),
                format!("must be from {min} to {max} seconds"),
            );
        }
        Ok(())
    }
}

impl Ros2Section {
    fn validate(&self) -> Result<(), ConfigFileError> {
        let bad = |key: &str, value: String, range: String| {
            Err(ConfigFileError::OutOfRange {
                key: format!("ros2.{key}"),
                value,
                range,
            })
        };
        let quoted = |text: &str| format!("{text:?}");
        if let Err(reason) = namespace_arg(&self.namespace) {
            return bad("namespace", quoted(&self.namespace), reason);
        }
        if let Err(reason) = node_name_arg(&self.node_name) {
            return bad("node_name", quoted(&self.node_name), reason);
        }
        if let Some(id) = self.domain_id {
            if let Err(reason) = check_domain_id(id) {
                return bad("domain_id", id.to_string(), reason);
            }
        }
        for (key, frame) in [
            ("frame_id", Some(&self.frame_id)),
            ("base_frame", self.base_frame.as_ref()),
        ] {
            if let Some(Err(reason)) = frame.map(|f| frame_id_arg(f)) {
                return bad(key, quoted(frame.map_or("", |f| f.as_str())), reason);
            }
        }
        Ok(())
    }
}

/// `--health-interval-s` and `[health] interval_s`: 0 (no reports) or
/// 0.05-3600 seconds.
pub fn check_health_interval(value: f64) -> Result<f64, String> {
    if value == 0.0 || (0.05..=3600.0).contains(&value) {
        Ok(value)
    } else {
        Err("must be 0 (no reports) or from 0.05 to 3600 seconds".to_string())
    }
}
