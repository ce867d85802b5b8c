//! Reading a config file ([`SlopeFile::load_or_stop`], [`SlopeFile::from_toml_str`])
//! and writing one ([`SlopeFile::to_toml`]): TOML errors and unknown keys
//! named with their full path and line, a file of the old layout refused
//! with how to fix it.

use std::io;
use std::path::{Path, PathBuf};
use std::time::Duration;

use slope_sensor::input_file::{read_text, MAX_SETTINGS_BYTES};
use slope_sensor::interruptible::run_interruptible;
use slope_sensor::publish::StopFlag;

use super::error::ConfigFileError;
use super::locate::{first_line_of, key_path, line_of};
use super::sections::SlopeFile;

/// The top-level keys of [`EstimatorConfig`](slope_pipeline::EstimatorConfig), which live under `[estimator]`.
const ESTIMATOR_KEYS: [&str; 11] = [
    "method",
    "seed",
    "outlier",
    "ransac",
    "pass_through",
    "normals",
    "kmeans",
    "cumulative",
    "selection",
    "road",
    "tracking",
];

/// How often [`SlopeFile::load_or_stop`] looks at the stop request while
/// the file is being read.
pub const READ_SLICE: Duration = Duration::from_millis(50);

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

    /// Reads `path`, or the defaults when `path` is `None`. Only a regular
    /// file of UTF-8 text, at most [`MAX_SETTINGS_BYTES`] long, is read (a
    /// FIFO would block, `/dev/zero` never end). The file is read on a
    /// thread of its own, so a stop request ends the wait for a read that
    /// blocks in the kernel (a config file on a stalled network mount)
    /// within 50 ms (`READ_SLICE`). `Ok(None)` when `stop` came first.
    pub fn load_or_stop(
        path: Option<&Path>,
        stop: &StopFlag,
    ) -> Result<Option<Self>, ConfigFileError> {
        Self::load_with(path, stop, |path| read_text(path, MAX_SETTINGS_BYTES))
    }

    /// [`Self::load_or_stop`] with `read` for the file's text.
    pub(super) fn load_with(
        path: Option<&Path>,
        stop: &StopFlag,
        read: impl FnOnce(&Path) -> io::Result<String> + Send + 'static,
    ) -> Result<Option<Self>, ConfigFileError> {
        let Some(path) = path else {
            return Ok(Some(Self::default()));
        };
        let read_error = |source| ConfigFileError::Read {
            path: path.to_path_buf(),
            source,
        };
        let owned: PathBuf = path.to_path_buf();
        let text = run_interruptible("read-config", stop, READ_SLICE, &mut || {}, move || {
            read(&owned)
        })
        .map_err(|err| read_error(io::Error::other(err)))?;
        match text {
            Some(text) => Self::parse_file(path, &text.map_err(read_error)?).map(Some),
            None => Ok(None),
        }
    }

    /// The text of the file `path`, parsed and validated.
    fn parse_file(path: &Path, text: &str) -> Result<Self, ConfigFileError> {
        Self::from_toml_str(text).map_err(|e| ConfigFileError::InFile {
            path: path.to_path_buf(),
            source: Box::new(e),
        })
    }

    /// Every key in effect, as TOML (`--print-config`).
    pub fn to_toml(&self) -> Result<String, toml::ser::Error> {
        toml::to_string(self)
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
