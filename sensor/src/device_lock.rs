//! [`DeviceLock`]: one process per camera.
//!
//! libfreenect2 resets the USB device on every open, so a second process
//! opening a camera that another one streams knocks the first one off. The
//! binding's "already open" check covers one process only; across processes
//! each camera has a lock file, `slope-<kind>-<serial>.lock`, held with
//! `flock` (std's [`File::try_lock`]) for as long as the device is open. The
//! kernel drops the lock when the holder exits, however it exits, so a
//! stale file never blocks anyone; the file holds the holder's PID so that a
//! refusal can name it.
//!
//! The directory: `SLOPE_LOCK_DIR` if set, else `/run/lock` (the system's
//! runtime lock directory, writable by every user), else the temporary
//! directory. Processes that must exclude each other have to agree on it.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Overrides the directory of the lock files.
pub const LOCK_DIR_ENV: &str = "SLOPE_LOCK_DIR";

/// The system's runtime directory for lock files.
const SYSTEM_LOCK_DIR: &str = "/run/lock";

/// Why a device lock could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum DeviceLockError {
    /// Another process holds the lock.
    #[error(
        "the {kind} {serial} is in use by another process ({}; lock file {}); stop that process \
         first: opening the camera would reset it and knock the other process off",
        holder(.pid),
        .path.display()
    )]
    Busy {
        kind: String,
        serial: String,
        /// The holder's PID as it wrote it, if it has yet.
        pid: Option<u32>,
        path: PathBuf,
    },
    /// The lock file could not be created or locked.
    #[error("cannot lock {} for the {kind} {serial}: {source}", .path.display())]
    Io {
        kind: String,
        serial: String,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

fn holder(pid: &Option<u32>) -> String {
    match pid {
        Some(pid) => format!("PID {pid}"),
        None => "PID unknown".to_string(),
    }
}

/// An exclusive lock on one device, held until dropped.
#[derive(Debug)]
pub struct DeviceLock {
    /// Holds the flock; closing it (on drop) releases the lock.
    _file: File,
    path: PathBuf,
}

impl DeviceLock {
    /// The directory lock files go to (see the module documentation).
    pub fn dir() -> PathBuf {
        if let Some(dir) = std::env::var_os(LOCK_DIR_ENV).filter(|d| !d.is_empty()) {
            return PathBuf::from(dir);
        }
        let system = Path::new(SYSTEM_LOCK_DIR);
        if system.is_dir() {
            return system.to_path_buf();
        }
        std::env::temp_dir()
    }

    /// The lock file of device `serial` of `kind` (e.g. "kinect2") in `dir`.
    pub fn path_in(dir: &Path, kind: &str, serial: &str) -> PathBuf {
        let safe = |text: &str| -> String {
            text.chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                .collect()
        };
        dir.join(format!("slope-{}-{}.lock", safe(kind), safe(serial)))
    }

    /// Takes the lock of `serial` in [`DeviceLock::dir`] without waiting.
    pub fn acquire(kind: &str, serial: &str) -> Result<Self, DeviceLockError> {
        Self::acquire_in(&Self::dir(), kind, serial)
    }

    /// Takes the lock of `serial` in `dir` without waiting: `Busy` naming
    /// the holder's PID when another process (or another lock in this one)
    /// holds it.
    pub fn acquire_in(dir: &Path, kind: &str, serial: &str) -> Result<Self, DeviceLockError> {
        let path = Self::path_in(dir, kind, serial);
        let io = |source: std::io::Error| DeviceLockError::Io {
            kind: kind.to_string(),
            serial: serial.to_string(),
            path: path.clone(),
            source,
        };
        std::fs::create_dir_all(dir).map_err(io)?;
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(io)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                return Err(DeviceLockError::Busy {
                    kind: kind.to_string(),
                    serial: serial.to_string(),
                    pid: read_pid(&mut file),
                    path,
                })
            }
            Err(TryLockError::Error(err)) => return Err(io(err)),
        }
        // Let another user's process open (and so try) the same lock file.
        let _ =
            std::fs::set_permissions(&path, std::os::unix::fs::PermissionsExt::from_mode(0o666));
        write_pid(&mut file).map_err(io)?;
        Ok(Self { _file: file, path })
    }

    /// The PID written in the lock of `serial` in `dir`, when another
    /// process holds that lock now; `None` when it is free (or unreadable).
    pub fn holder_in(dir: &Path, kind: &str, serial: &str) -> Option<Option<u32>> {
        let path = Self::path_in(dir, kind, serial);
        let mut file = File::open(&path).ok()?;
        match file.try_lock_shared() {
            Ok(()) => None,
            Err(TryLockError::WouldBlock) => Some(read_pid(&mut file)),
            Err(TryLockError::Error(_)) => None,
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

fn read_pid(file: &mut File) -> Option<u32> {
    let mut text = String::new();
    file.seek(SeekFrom::Start(0)).ok()?;
    file.read_to_string(&mut text).ok()?;
    text.trim().parse().ok()
}

fn write_pid(file: &mut File) -> std::io::Result<()> {
    file.set_len(0)?;
    file.seek(SeekFrom::Start(0))?;
    writeln!(file, "{}", std::process::id())?;
    file.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_on_the_same_serial_is_refused_naming_the_holder() {
        let dir = tempfile::tempdir().expect("temp dir");
        let first = DeviceLock::acquire_in(dir.path(), "kinect2", "011054343347").expect("free");
        let other = DeviceLock::acquire_in(dir.path(), "kinect2", "000000000001");
        assert!(other.is_ok(), "another serial is another lock");
        match DeviceLock::acquire_in(dir.path(), "kinect2", "011054343347") {
            Err(err @ DeviceLockError::Busy { .. }) => {
                let DeviceLockError::Busy { pid, .. } = &err else {
                    unreachable!()
                };
                assert_eq!(*pid, Some(std::process::id()));
                let message = err.to_string();
                assert!(
                    message.contains(&format!("PID {}", std::process::id()))
                        && message.contains("011054343347"),
                    "{message}"
                );
            }
            other => panic!("expected Busy, got {other:?}"),
        }
        assert_eq!(
            DeviceLock::holder_in(dir.path(), "kinect2", "011054343347"),
            Some(Some(std::process::id()))
        );
        drop(first);
        // A child that another test forks (`mkfifo`) holds a copy of the
        // lock's descriptor from its fork until its exec (O_CLOEXEC closes
        // it then): the lock is free once no such child is between the two.
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
        let freed = loop {
            let holder = DeviceLock::holder_in(dir.path(), "kinect2", "011054343347");
            if holder.is_none() || std::time::Instant::now() > deadline {
                break holder;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        };
        assert_eq!(freed, None, "the lock outlives its holder");
        DeviceLock::acquire_in(dir.path(), "kinect2", "011054343347").expect("free again");
    }

    #[test]
    fn odd_serials_make_plain_file_names() {
        let path = DeviceLock::path_in(Path::new("/run/lock"), "kinect2", "../a b");
        assert_eq!(path, Path::new("/run/lock/slope-kinect2-___a_b.lock"));
    }

    #[test]
    fn an_unusable_directory_is_an_io_error_naming_the_file() {
        let dir = tempfile::tempdir().expect("temp dir");
        let not_a_dir = dir.path().join("file");
        std::fs::write(&not_a_dir, b"").expect("write");
        let err = DeviceLock::acquire_in(&not_a_dir, "kinect2", "1").expect_err("not a directory");
        assert!(matches!(err, DeviceLockError::Io { .. }));
        assert!(err.to_string().contains("slope-kinect2-1.lock"), "{err}");
    }
}
