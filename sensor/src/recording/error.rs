//! The one error type of recording I/O. Every variant names the file, and the
//! row (1-based line number in `frames.csv`) or the key where there is one.
//!
//! Kept small (no more than 80 bytes) so that errors wrapping it stay under
//! clippy's `result_large_err` limit: image errors carry the image's path and
//! the row, not the path of `frames.csv` (it sits in the same recording).

use std::io;
use std::path::PathBuf;

use super::{FRAMES_FILE, META_FILE};

/// Why a recording could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The directory holds no `recording.toml` (or is no directory).
    #[error(
        "{} is not a recording directory (no {META_FILE}); a recording is a directory \
         with {META_FILE}, {FRAMES_FILE} and depth/",
        dir.display()
    )]
    NotARecording { dir: PathBuf },

    /// A file or directory could not be opened or read.
    #[error("cannot read {}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: io::Error,
    },

    /// A file or directory could not be created or written.
    #[error("cannot write {}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: io::Error,
    },

    /// `recording.toml` is not valid TOML: the parser's message on one line,
    /// and where (1-based line and column) when the parser says.
    #[error("{}{} is not valid TOML: {message}", path.display(), at_line_column(*.at))]
    Toml {
        path: PathBuf,
        /// Line and column, 1-based.
        at: Option<(usize, usize)>,
        message: String,
    },

    /// `format` is not `"slope-recording"`.
    #[error("{}: `format` is {found:?}, expected \"slope-recording\"", path.display())]
    WrongFormat { path: PathBuf, found: String },

    /// `version` is a number this reader does not know.
    #[error("{}: unknown `version` {found} (this reader knows version 1)", path.display())]
    UnknownVersion { path: PathBuf, found: i64 },

    /// A required key (`format`, `version`, `depth`, `depth.fx`, ...) is missing.
    #[error("{}: missing required key `{key}`", path.display())]
    MissingKey { path: PathBuf, key: String },

    /// A key has the wrong type or an impossible value.
    #[error("{}: key `{key}`: {reason}", path.display())]
    InvalidKey {
        path: PathBuf,
        key: String,
        reason: String,
    },

    /// The header row of `frames.csv` lacks a required column (or the file
    /// is empty).
    #[error(
        "{}: the header row has no column `{column}` (the first line names the columns: \
         index,timestamp_ns,depth,color and optionally slope_deg)",
        path.display()
    )]
    MissingColumn { path: PathBuf, column: &'static str },

    /// A row of `frames.csv` is malformed (field count, a number that does
    /// not parse, a value out of range, bytes that are not UTF-8, an image
    /// path that is empty, absolute or leaves the recording directory).
    #[error("{} line {row}: {reason}", path.display())]
    BadRow {
        path: PathBuf,
        row: usize,
        reason: String,
    },

    /// `index` did not increase from the previous row.
    #[error(
        "{} line {row}: index {index} does not increase (the previous row has {previous})",
        path.display()
    )]
    NonIncreasingIndex {
        path: PathBuf,
        row: usize,
        index: u64,
        previous: u64,
    },

    /// `timestamp_ns` went back in time.
    #[error(
        "{} line {row}: timestamp_ns {timestamp_ns} is before the previous row's {previous}",
        path.display()
    )]
    DecreasingTimestamp {
        path: PathBuf,
        row: usize,
        timestamp_ns: u64,
        previous: u64,
    },

    /// The image a row names is missing or unreadable.
    #[error("{FRAMES_FILE} line {row}: cannot read {}", image.display())]
    ImageRead {
        row: usize,
        image: PathBuf,
        #[source]
        source: io::Error,
    },

    /// The image a row names is not a PNG that decodes.
    #[error("{FRAMES_FILE} line {row}: cannot decode {}", image.display())]
    ImageDecode {
        row: usize,
        image: PathBuf,
        #[source]
        source: png::DecodingError,
    },

    /// The image has the wrong colour type or bit depth.
    #[error("{FRAMES_FILE} line {row}: {} is {found}, expected {expected}", image.display())]
    ImageFormat {
        row: usize,
        image: PathBuf,
        expected: &'static str,
        found: String,
    },

    /// The image's size differs from `[depth]` in `recording.toml`.
    #[error(
        "{FRAMES_FILE} line {row}: {} is {found_width}x{found_height}, [depth] says {width}x{height}",
        image.display()
    )]
    ImageSize {
        row: usize,
        image: PathBuf,
        width: u32,
        height: u32,
        found_width: u32,
        found_height: u32,
    },

    /// An image handed to the writer holds fewer or more pixels than its
    /// width and height say.
    #[error(
        "{FRAMES_FILE} line {row}: {} would hold {found} pixels, its size {width}x{height} needs {expected}",
        image.display()
    )]
    ImageData {
        row: usize,
        image: PathBuf,
        width: u32,
        height: u32,
        expected: usize,
        found: usize,
    },

    /// PNG encoding failed.
    #[error("cannot encode {}", image.display())]
    ImageEncode {
        image: PathBuf,
        #[source]
        source: png::EncodingError,
    },

    /// The writer's target exists and is not an empty directory.
    #[error("{} exists and is not an empty directory", path.display())]
    NotEmpty { path: PathBuf },

    /// A frame carries per-frame truth but the recording was created without
    /// a `slope_deg` column.
    #[error(
        "{} line {row}: per-frame slope_deg given, but the recording was created without per-frame truth",
        path.display()
    )]
    NoTruthColumn { path: PathBuf, row: usize },

    /// `[depth]` gives a frame of more points than the reader accepts: a
    /// typing error, or an image no cloud buffer should be allocated for.
    #[error(
        "{}: [depth] width x height is {width} x {height}: a frame of {points} points; \
         the limit is {max_points}",
        path.display()
    )]
    TooManyPoints {
        path: PathBuf,
        width: u32,
        height: u32,
        points: u64,
        max_points: usize,
    },
}

/// " line L, column C", or nothing.
fn at_line_column(at: Option<(usize, usize)>) -> String {
    at.map_or(String::new(), |(line, column)| {
        format!(" line {line}, column {column}")
    })
}

impl RecordingError {
    /// A `toml` parse error of `text` (the contents of `path`) as one line:
    /// the parser's message without its source snippet, with the line and
    /// column of its span.
    pub(crate) fn toml(path: &std::path::Path, text: &str, err: &toml::de::Error) -> Self {
        let at = err.span().map(|span| {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let line_start = before.rfind('\n').map_or(0, |i| i + 1);
            (line, before[line_start..].chars().count() + 1)
        });
        let message = err
            .message()
            .lines()
            .map(str::trim)
            .filter(|part| !part.is_empty())
            .collect::<Vec<_>>()
            .join("; ");
        Self::Toml {
            path: path.to_path_buf(),
            at,
            message,
        }
    }

    /// The `frames.csv` line the error is about, if it is about one frame.
    pub fn row(&self) -> Option<usize> {
        match self {
            Self::BadRow { row, .. }
            | Self::NonIncreasingIndex { row, .. }
            | Self::DecreasingTimestamp { row, .. }
            | Self::ImageRead { row, .. }
            | Self::ImageDecode { row, .. }
            | Self::ImageFormat { row, .. }
            | Self::ImageSize { row, .. }
            | Self::ImageData { row, .. }
            | Self::NoTruthColumn { row, .. } => Some(*row),
            _ => None,
        }
    }
}
