//! Why a config file was refused ([`ConfigFileError`]).

use std::path::PathBuf;

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
