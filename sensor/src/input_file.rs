//! Opening and reading the files a program is given: only regular files,
//! text files read up to a size cap, as UTF-8 with the place of a bad byte.
//!
//! A FIFO, a device (`/dev/zero`, `/dev/urandom`) or a directory where a
//! recording's `recording.toml`, `frames.csv`, an image or a config file is
//! expected would block the open (a FIFO without a writer), never end
//! (`/dev/zero` read whole) or fail with a message about something else.
//! [`open_regular`] opens without blocking (`O_NONBLOCK`, which a regular
//! file ignores) and refuses anything but a regular file; [`read_text`]
//! also caps the size read. Every error is an [`io::Error`] whose source
//! is an [`InputFileError`], so the callers' own errors (which name the
//! file) keep their shape.

use std::fs::{File, FileType};
use std::io::{self, Read};
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::Path;

/// The largest `recording.toml` or config file read, bytes: a few hundred
/// lines are a large one.
pub const MAX_SETTINGS_BYTES: u64 = 1 << 20;

/// The largest `frames.csv` read, bytes: about 4 million rows (37 hours at
/// 30 Hz).
pub const MAX_FRAME_TABLE_BYTES: u64 = 256 << 20;

/// Why a file was not read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum InputFileError {
    /// A directory, FIFO, socket or device.
    #[error("it is {kind}, not a regular file")]
    NotRegular { kind: &'static str },
    /// Larger than the cap of its kind of file.
    #[error("it is {size} bytes, more than the {limit} read for such a file")]
    TooLarge { size: u64, limit: u64 },
    /// Bytes that are not UTF-8 text.
    #[error("it is not UTF-8 text: invalid bytes at line {line}, column {column}")]
    NotUtf8 { line: usize, column: usize },
}

impl From<InputFileError> for io::Error {
    fn from(err: InputFileError) -> Self {
        let kind = match err {
            InputFileError::NotRegular { .. } => io::ErrorKind::InvalidInput,
            InputFileError::TooLarge { .. } => io::ErrorKind::FileTooLarge,
            InputFileError::NotUtf8 { .. } => io::ErrorKind::InvalidData,
        };
        io::Error::new(kind, err)
    }
}

/// What a file that is not a regular one is, for messages.
fn kind_of(file_type: FileType) -> &'static str {
    if file_type.is_dir() {
        "a directory"
    } else if file_type.is_fifo() {
        "a FIFO"
    } else if file_type.is_socket() {
        "a socket"
    } else if file_type.is_char_device() {
        "a character device"
    } else if file_type.is_block_device() {
        "a block device"
    } else {
        "not a file"
    }
}

/// Opens `path` for reading if it is a regular file (symbolic links
/// followed). Never blocks on a FIFO: it is opened non-blocking, seen to be
/// one and refused.
pub fn open_regular(path: &Path) -> io::Result<File> {
    // Looked at first: a socket cannot even be opened (ENXIO says nothing
    // useful); the open's own fstat below is what holds.
    refuse_irregular(std::fs::metadata(path)?.file_type())?;
    let file = File::options()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)?;
    refuse_irregular(file.metadata()?.file_type())?;
    Ok(file)
}

fn refuse_irregular(file_type: FileType) -> io::Result<()> {
    if file_type.is_file() {
        Ok(())
    } else {
        Err(InputFileError::NotRegular {
            kind: kind_of(file_type),
        }
        .into())
    }
}

/// The bytes of the regular file `path`, at most `limit` of them (a larger
/// file is refused, also one that grows past the cap while it is read).
pub fn read_bytes(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let file = open_regular(path)?;
    let size = file.metadata()?.len();
    if size > limit {
        return Err(InputFileError::TooLarge { size, limit }.into());
    }
    let mut bytes = Vec::with_capacity(usize::try_from(size).unwrap_or(0));
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    let read = bytes.len() as u64;
    if read > limit {
        return Err(InputFileError::TooLarge { size: read, limit }.into());
    }
    Ok(bytes)
}

/// The text of the regular file `path`, at most `limit` bytes of UTF-8.
pub fn read_text(path: &Path, limit: u64) -> io::Result<String> {
    let bytes = read_bytes(path, limit)?;
    text_of(bytes).map_err(io::Error::from)
}

/// `bytes` as a string, or where the first invalid byte is (1-based line
/// and column, counted in characters).
pub fn text_of(bytes: Vec<u8>) -> Result<String, InputFileError> {
    String::from_utf8(bytes).map_err(|err| {
        let valid = err.utf8_error().valid_up_to();
        let before = &err.as_bytes()[..valid];
        // The prefix up to `valid` is UTF-8 by the definition of valid_up_to.
        let before = std::str::from_utf8(before).unwrap_or_default();
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        InputFileError::NotUtf8 {
            line: before.matches('\n').count() + 1,
            column: before[line_start..].chars().count() + 1,
        }
    })
}

/// The [`InputFileError`] an I/O error carries, if any.
pub fn input_file_error(err: &io::Error) -> Option<&InputFileError> {
    err.get_ref()?.downcast_ref()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::net::UnixListener;

    fn refusal(path: &Path) -> InputFileError {
        let err = read_text(path, 100).expect_err("refused");
        input_file_error(&err)
            .cloned()
            .expect("an input-file error")
    }

    #[test]
    fn directories_fifos_sockets_and_devices_are_refused_at_once() {
        let dir = tempfile::tempdir().expect("temp dir");
        assert_eq!(
            refusal(dir.path()),
            InputFileError::NotRegular {
                kind: "a directory"
            }
        );
        // A FIFO without a writer: a plain open would block forever.
        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .expect("mkfifo runs");
        assert!(made.success());
        assert_eq!(
            refusal(&fifo),
            InputFileError::NotRegular { kind: "a FIFO" }
        );
        let socket = dir.path().join("socket");
        let _listener = UnixListener::bind(&socket).expect("socket");
        assert_eq!(
            refusal(&socket),
            InputFileError::NotRegular { kind: "a socket" }
        );
        for device in ["/dev/zero", "/dev/urandom"] {
            assert_eq!(
                refusal(Path::new(device)),
                InputFileError::NotRegular {
                    kind: "a character device"
                },
                "{device}"
            );
        }
        let missing = read_text(&dir.path().join("missing"), 100).expect_err("missing");
        assert_eq!(missing.kind(), io::ErrorKind::NotFound);
    }

    #[test]
    fn text_is_capped_and_bad_utf8_is_located() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("text");
        std::fs::write(&path, "0123456789").expect("write");
        assert_eq!(read_text(&path, 10).expect("at the cap"), "0123456789");
        assert_eq!(
            refusal_with(&path, 9),
            InputFileError::TooLarge { size: 10, limit: 9 }
        );
        std::fs::write(&path, b"a = 1\nb = \"\xc3\xa9\xff\"\n").expect("write");
        assert_eq!(
            refusal_with(&path, 100),
            InputFileError::NotUtf8 { line: 2, column: 7 }
        );
        let message = read_text(&path, 100).expect_err("not UTF-8").to_string();
        assert!(message.contains("not UTF-8 text"), "{message}");
    }

    fn refusal_with(path: &Path, limit: u64) -> InputFileError {
        let err = read_text(path, limit).expect_err("refused");
        input_file_error(&err)
            .cloned()
            .expect("an input-file error")
    }
}
