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
//! max_planes = 24
//! ```
//!
//! Every daemon parses the whole file, so a typo anywhere is an error that
//! names the key with its full path (`estimator.ransac.max_planez`), and a
//! value out of its range names the key and the range. Command-line flags
//! override the file.

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use slope_ipc_types::DEFAULT_SERVICE_PREFIX;
use slope_pipeline::config::ConfigError;
use slope_pipeline::EstimatorConfig;
use slope_sensor::recording::MountInfo;

use crate::cli::prefix_arg;
use crate::health::DEFAULT_HEALTH_INTERVAL_S;
use crate::replay::POSITIVE_RANGE;

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

/// The depth decoding pipelines `[capture] pipeline` names.
pub const PIPELINES: [&str; 7] = ["default", "cpu", "cl", "clkde", "cuda", "cudakde", "gl"];

/// The whole file; every section and key optional.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SlopeFile {
    /// Prefix of the iceoryx2 service names.
    pub service_prefix: String,
    pub health: HealthSection,
    /// `[mount]`: the camera's pose on the robot; a key left out is unknown.
    pub mount: MountInfo,
    pub capture: CaptureSection,
    pub estimator: EstimatorConfig,
}

impl Default for SlopeFile {
    fn default() -> Self {
        Self {
            service_prefix: DEFAULT_SERVICE_PREFIX.to_string(),
            health: HealthSection::default(),
            mount: MountInfo::default(),
            capture: CaptureSection::default(),
            estimator: EstimatorConfig::default(),
        }
    }
}

/// `[health]`: the daemons' reports on `<prefix>/health`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HealthSection {
    /// Seconds between reports; 0: none.
    pub interval_s: f64,
}

impl Default for HealthSection {
    fn default() -> Self {
        Self {
            interval_s: DEFAULT_HEALTH_INTERVAL_S,
        }
    }
}

/// `[capture]`: the Kinect v2 and libfreenect2's depth processing. The
/// defaults are libfreenect2's (`slope_sensor::kinect2::DepthConfig`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CaptureSection {
    /// The camera to open; the first one when neither this nor
    /// `device_index` is set (`serial` wins when both are).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub serial: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub device_index: Option<u32>,
    /// One of [`PIPELINES`].
    pub pipeline: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu_device: Option<u32>,
    pub min_depth_m: f64,
    pub max_depth_m: f64,
    pub bilateral_filter: bool,
    pub edge_aware_filter: bool,
    pub color: bool,
    pub frame_timeout_s: f64,
}

impl Default for CaptureSection {
    fn default() -> Self {
        Self {
            serial: None,
            device_index: None,
            pipeline: "default".to_string(),
            gpu_device: None,
            min_depth_m: 0.5,
            max_depth_m: 4.5,
            bilateral_filter: true,
            edge_aware_filter: true,
            color: true,
            frame_timeout_s: 3.0,
        }
    }
}

/// Why the file was refused.
#[derive(Debug, thiserror::Error)]
pub enum ConfigFileError {
    #[error("cannot read the config file {path}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("invalid config file {path}")]
    InFile {
        path: PathBuf,
        #[source]
        source: Box<ConfigFileError>,
    },
    #[error("not TOML{}: {message}", at_line(*.line))]
    Syntax {
        /// 1-based; `None` when the parser did not say.
        line: Option<usize>,
        message: String,
    },
    #[error("`{key}`{}: {message}", at_line(*.line))]
    Key {
        key: String,
        /// 1-based; `None` when it is not known.
        line: Option<usize>,
        message: String,
    },
    #[error("`{key}` belongs to the estimator: {fix}")]
    OldLayout { key: String, fix: String },
    #[error("`{key}` = {value}: {range}")]
    OutOfRange {
        key: String,
        value: String,
        range: String,
    },
    /// Two keys that must be in order, each named with its value (either
    /// may be the one the user set).
    #[error("`{high_key}` = {high} must be above `{low_key}` = {low}")]
    NotAbove {
        high_key: String,
        high: String,
        low_key: String,
        low: String,
    },
}

/// " (line N)", or nothing for an unknown line.
fn at_line(line: Option<usize>) -> String {
    line.map_or(String::new(), |line| format!(" (line {line})"))
}

/// The top-level keys of [`EstimatorConfig`], which live under `[estimator]`.
const ESTIMATOR_KEYS: [&str; 10] = [
    "method",
    "seed",
    "outlier",
    "ransac",
    "pass_through",
    "normals",
    "kmeans",
    "cumulative",
    "selection",
    "tracking",
];

impl SlopeFile {
    /// Parses and validates a file's text; missing keys keep their defaults.
    pub fn from_toml_str(text: &str) -> Result<Self, ConfigFileError> {
        let table: toml::Table = toml::from_str(text).map_err(|e| ConfigFileError::Syntax {
            line: e.span().map(|span| line_of(text, span.start)),
            message: e.message().to_string(),
        })?;
        check_layout(text, &table)?;
        let file: Self = toml::from_str(text).map_err(|e| key_error(text, &e))?;
        file.validate()?;
        Ok(file)
    }

    /// Reads `path`, or the defaults when `path` is `None`.
    pub fn load(path: Option<&Path>) -> Result<Self, ConfigFileError> {
        let Some(path) = path else {
            return Ok(Self::default());
        };
        let text = std::fs::read_to_string(path).map_err(|source| ConfigFileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_toml_str(&text).map_err(|e| ConfigFileError::InFile {
            path: path.to_path_buf(),
            source: Box::new(e),
        })
    }

    /// Every key in effect, as TOML (`--print-config`).
    pub fn to_toml(&self) -> Result<String, toml::ser::Error> {
        toml::to_string(self)
    }

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

/// `--health-interval-s` and `[health] interval_s`: 0 (no reports) or
/// 0.05-3600 seconds.
pub fn check_health_interval(value: f64) -> Result<f64, String> {
    if value == 0.0 || (0.05..=3600.0).contains(&value) {
        Ok(value)
    } else {
        Err("must be 0 (no reports) or from 0.05 to 3600 seconds".to_string())
    }
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

/// A file laid out before the sections existed: how to fix it.
fn check_layout(text: &str, table: &toml::Table) -> Result<(), ConfigFileError> {
    if table.contains_key("kinect2") {
        return Err(ConfigFileError::Key {
            key: "kinect2".into(),
            line: first_line_of(text, "kinect2"),
            message:
                "the capture settings are the section [capture]: rename [kinect2] to [capture]"
                    .into(),
        });
    }
    if let Some(key) = ESTIMATOR_KEYS.iter().find(|k| table.contains_key(**k)) {
        let fix = if table.get(*key).is_some_and(toml::Value::is_table) {
            format!("rename [{key}] to [estimator.{key}]")
        } else {
            format!("move `{key}` under [estimator]")
        };
        return Err(ConfigFileError::OldLayout {
            key: (*key).to_string(),
            fix,
        });
    }
    Ok(())
}

/// A deserialisation error with the full path of the key it is about.
fn key_error(text: &str, err: &toml::de::Error) -> ConfigFileError {
    let message = err.message().to_string();
    let Some(span) = err.span() else {
        return ConfigFileError::Syntax {
            line: None,
            message,
        };
    };
    ConfigFileError::Key {
        key: key_path(text, &span),
        line: Some(line_of(text, span.start)),
        message,
    }
}

/// The 1-based line where the top-level `key` first appears: a table
/// header (`[key]`, `[key.sub]`, `[[key]]`) or a key at the top (`key = `,
/// `key.sub = `, before any header). `None` if it is written some other
/// way (quoted, say).
fn first_line_of(text: &str, key: &str) -> Option<usize> {
    let mut top = true;
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if let Some(header) = line.strip_prefix('[') {
            let header = header.trim_start_matches('[').trim_start();
            if header
                .strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with([']', '.']))
            {
                return Some(k + 1);
            }
            top = false;
        } else if top
            && line
                .strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with(['=', '.']))
        {
            return Some(k + 1);
        }
    }
    None
}

/// The 1-based line holding byte `at`.
fn line_of(text: &str, at: usize) -> usize {
    text[..at.min(text.len())].matches('\n').count() + 1
}

/// The full path of the key on the line of `span`: the last table header
/// above it, then the key before the `=` (or, on a header line, the header
/// up to the end of `span`).
fn key_path(text: &str, span: &Range<usize>) -> String {
    let start = span.start.min(text.len());
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[start..].find('\n').map_or(text.len(), |i| start + i);
    let line = text[line_start..line_end].trim();
    if line.starts_with('[') {
        let end = span.end.clamp(start, line_end);
        return text[line_start..end]
            .trim()
            .trim_start_matches('[')
            .trim_end_matches(']')
            .trim()
            .to_string();
    }
    let header = text[..line_start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| {
            let l = l.trim_start_matches('[');
            l.split(']').next().unwrap_or_default().trim().to_string()
        });
    let key = line.split('=').next().unwrap_or_default().trim();
    match header {
        Some(header) if !header.is_empty() => format!("{header}.{key}"),
        _ => key.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(text: &str) -> String {
        SlopeFile::from_toml_str(text)
            .map(|file| panic!("accepted: {file:?}"))
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn every_section_is_read() {
        let file = SlopeFile::from_toml_str(
            "service_prefix = \"robot2\"\n[health]\ninterval_s = 0.5\n\
             [mount]\nheight_m = 0.4\npitch_deg = -20.0\n\
             [capture]\nserial = \"111\"\npipeline = \"cpu\"\ncolor = false\n\
             [estimator]\nmethod = \"tls\"\n[estimator.ransac]\nmax_planes = 12\n",
        )
        .expect("valid");
        assert_eq!(file.service_prefix, "robot2");
        assert_eq!(file.health.interval_s, 0.5);
        assert_eq!(
            (
                file.mount.height_m,
                file.mount.pitch_deg,
                file.mount.roll_deg
            ),
            (Some(0.4), Some(-20.0), None)
        );
        assert_eq!(file.capture.serial.as_deref(), Some("111"));
        assert_eq!(file.capture.pipeline, "cpu");
        assert!(!file.capture.color);
        assert_eq!(file.capture.max_depth_m, 4.5);
        assert_eq!(file.estimator.method, slope_ipc_types::SlopeMethod::Tls);
        assert_eq!(file.estimator.ransac.max_planes, 12);
        assert_eq!(
            SlopeFile::from_toml_str("").expect("empty"),
            SlopeFile::default()
        );
    }

    #[test]
    fn unknown_keys_are_named_with_their_full_path() {
        let message = refused("[estimator]\nseed = 1\n[estimator.ransac]\nmax_planez = 12\n");
        assert!(
            message.starts_with("`estimator.ransac.max_planez` (line 4)"),
            "{message}"
        );
        assert!(
            message.contains("max_planes"),
            "the keys it expects: {message}"
        );
        let message = refused("[capture]\nserail = \"1\"\n");
        assert!(
            message.starts_with("`capture.serail` (line 2)"),
            "{message}"
        );
        let message = refused("[estimator.ransak]\nmax_planes = 12\n");
        assert!(message.starts_with("`estimator.ransak`"), "{message}");
        let message = refused("prefix = \"x\"\n");
        assert!(message.starts_with("`prefix` (line 1)"), "{message}");
        let message = refused("[mount]\nheight_m = \"high\"\n");
        assert!(
            message.starts_with("`mount.height_m` (line 2)"),
            "{message}"
        );
    }

    #[test]
    fn values_out_of_range_are_named_with_their_range() {
        for (text, key, range) in [
            (
                "[mount]\npitch_deg = 400.0\n",
                "`mount.pitch_deg` = 400",
                "at most 90",
            ),
            (
                "[mount]\nheight_m = 0.0\n",
                "`mount.height_m` = 0",
                "above 0",
            ),
            (
                "[mount]\nheight_m = nan\n",
                "`mount.height_m` = NaN",
                "above 0",
            ),
            (
                "[mount]\nheight_m = 0.4\npitch_deg = nan\n",
                "`mount.pitch_deg` = NaN",
                "at most 90",
            ),
            (
                "[mount]\nroll_deg = -inf\n",
                "`mount.roll_deg` = -inf",
                "at most 180",
            ),
            (
                "[health]\ninterval_s = 0.01\n",
                "`health.interval_s` = 0.01",
                "from 0.05 to 3600",
            ),
            (
                "[capture]\npipeline = \"vulkan\"\n",
                "`capture.pipeline` = \"vulkan\"",
                "one of default, cpu",
            ),
            (
                "[capture]\nmin_depth_m = 0.0\n",
                "`capture.min_depth_m` = 0",
                "from 0.001 to 10000000 m",
            ),
            (
                "[capture]\nmax_depth_m = inf\n",
                "`capture.max_depth_m` = inf",
                "from 0.001 to 10000000 m",
            ),
            (
                "[capture]\nmax_depth_m = nan\n",
                "`capture.max_depth_m` = NaN",
                "from 0.001 to 10000000 m",
            ),
            (
                "[capture]\nframe_timeout_s = 0.0\n",
                "`capture.frame_timeout_s` = 0",
                "from 0.001",
            ),
            (
                "service_prefix = \"/x\"\n",
                "`service_prefix` = \"/x\"",
                "no leading or trailing",
            ),
            (
                "service_prefix = \"\"\n",
                "`service_prefix` = \"\"",
                "leave the key out for the default 'slope'",
            ),
            (
                "[estimator.normals]\nneighbours = 2\n",
                "`estimator.normals.neighbours` = 2",
                "must be at least 3",
            ),
            (
                "[estimator.ransac]\nconfidence = 1.5\n",
                "`estimator.ransac.confidence` = 1.5",
                "0",
            ),
        ] {
            let message = refused(text);
            assert!(message.starts_with(key), "{text}: {message}");
            assert!(message.contains(range), "{text}: {message}");
        }
    }

    /// Whichever of the two keys was set, the message names both with
    /// their values.
    #[test]
    fn keys_out_of_order_are_both_named() {
        for text in [
            "[capture]\nmax_depth_m = 0.2\n",
            "[capture]\nmin_depth_m = 0.5\nmax_depth_m = 0.2\n",
        ] {
            assert_eq!(
                refused(text),
                "`capture.max_depth_m` = 0.2 must be above `capture.min_depth_m` = 0.5",
                "{text}"
            );
        }
        assert_eq!(
            refused("[capture]\nmin_depth_m = 5.0\n"),
            "`capture.max_depth_m` = 4.5 must be above `capture.min_depth_m` = 5"
        );
        assert_eq!(
            refused("[capture]\nmin_depth_m = 2.0\nmax_depth_m = 2.0\n"),
            "`capture.max_depth_m` = 2 must be above `capture.min_depth_m` = 2"
        );
    }

    #[test]
    fn an_old_layout_says_how_to_fix_it() {
        let message = refused("method = \"tls\"\n");
        assert!(
            message.contains("move `method` under [estimator]"),
            "{message}"
        );
        let message = refused("seed = 3\n[ransac]\nmax_planes = 4\n");
        assert!(message.contains("`seed`"), "{message}");
        let message = refused("[ransac]\nmax_planes = 4\n");
        assert!(
            message.contains("rename [ransac] to [estimator.ransac]"),
            "{message}"
        );
        let message = refused("[kinect2]\nserial = \"1\"\n");
        assert!(
            message.starts_with("`kinect2` (line 1): ")
                && message.contains("rename [kinect2] to [capture]"),
            "{message}"
        );
        let message = refused("# the camera\n\n[kinect2.more]\nserial = \"1\"\n");
        assert!(message.starts_with("`kinect2` (line 3): "), "{message}");
        let message = refused("service_prefix = \"x\"\nkinect2.serial = \"1\"\n");
        assert!(message.starts_with("`kinect2` (line 2): "), "{message}");
        // Quoted: found by the parser, not by the line scan; no line then.
        let message = refused("[\"kinect2\"]\nserial = \"1\"\n");
        assert!(message.starts_with("`kinect2`: "), "{message}");
        assert!(!message.contains("line 0"), "{message}");
    }

    #[test]
    fn the_printed_file_parses_back_to_the_same_configuration() {
        let mut file = SlopeFile::from_toml_str(
            "service_prefix = \"robot2\"\n[mount]\nroll_deg = 2.5\n[capture]\ndevice_index = 1\n",
        )
        .expect("valid");
        file.estimator.seed = 9;
        let printed = file.to_toml().expect("serialises");
        assert_eq!(SlopeFile::from_toml_str(&printed).expect("parses"), file);
        assert!(printed.contains("[estimator.normals]"), "{printed}");
    }

    #[test]
    fn the_shipped_paper_literal_preset_is_a_daemon_config_file() {
        let text = include_str!("../../../pipeline/presets/paper-literal.toml");
        let file = SlopeFile::from_toml_str(text).expect("valid");
        assert_eq!(file.estimator, EstimatorConfig::paper_literal());
        assert_eq!(
            SlopeFile {
                estimator: EstimatorConfig::default(),
                ..file
            },
            SlopeFile::default()
        );
    }

    #[test]
    fn a_missing_default_file_means_the_defaults() {
        let dir = tempfile::tempdir().expect("temp dir");
        let default = dir.path().join("slope.toml");
        assert_eq!(config_path(None, &default), None);
        std::fs::write(&default, "[estimator]\nseed = 7\n").expect("write");
        assert_eq!(config_path(None, &default), Some(default.clone()));
        let file = SlopeFile::load(Some(&default)).expect("valid");
        assert_eq!(file.estimator.seed, 7);
        let given = dir.path().join("other.toml");
        assert_eq!(config_path(Some(&given), &default), Some(given.clone()));
        let err = SlopeFile::load(Some(&given)).expect_err("no such file");
        assert!(err.to_string().contains("other.toml"), "{err}");
    }
}
