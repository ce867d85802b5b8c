//! Temporary files of outputs not finished yet (`slope-convert`'s
//! `.OUT.mcap.XXXXXX.part`), removed when a second SIGINT/SIGTERM ends the
//! program at once ([`remove_all_and_exit`], called by
//! [`crate::cli::stop_on_signals`]): `std::process::exit` runs no
//! destructors, so without this the temporary file would stay behind.
//!
//! One lock orders everything: a file is registered while it is created,
//! and renamed into place ([`UnfinishedFile::finish_with`]) and forgotten
//! while the lock is held, so a second signal either removes the temporary
//! file before the rename (the previous output stays as it was) or comes
//! after it and finds nothing to remove (the output is finished). It never
//! removes a finished output: only temporary paths are ever registered.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

/// The temporary files of this process not finished yet.
static UNFINISHED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The registry; a thread that panicked while holding it left a list that
/// is still valid (every change is a single push or remove).
fn registry() -> MutexGuard<'static, Vec<PathBuf>> {
    UNFINISHED.lock().unwrap_or_else(PoisonError::into_inner)
}

/// A registered temporary file: forgotten when dropped (whoever owns the
/// file removes it or renames it).
#[derive(Debug)]
pub struct UnfinishedFile {
    path: PathBuf,
}

impl UnfinishedFile {
    /// Creates a temporary file with `create` and registers its path, under
    /// the lock: a second signal cannot come between the two.
    pub fn create(
        create: impl FnOnce() -> std::io::Result<tempfile::NamedTempFile>,
    ) -> std::io::Result<(tempfile::NamedTempFile, Self)> {
        let mut unfinished = registry();
        let file = create()?;
        let path = file.path().to_path_buf();
        unfinished.push(path.clone());
        Ok((file, Self { path }))
    }

    /// Runs `finish` (which renames the file into place) under the lock and
    /// forgets the file: a second signal waits until the rename is done.
    pub fn finish_with<T>(self, finish: impl FnOnce() -> T) -> T {
        let mut unfinished = registry();
        let result = finish();
        forget(&mut unfinished, &self.path);
        result
    }
}

impl Drop for UnfinishedFile {
    fn drop(&mut self) {
        forget(&mut registry(), &self.path);
    }
}

fn forget(unfinished: &mut Vec<PathBuf>, path: &Path) {
    unfinished.retain(|p| p != path);
}

/// Removes every registered file and ends the process with `code`. The
/// lock stays held until the process ends, so no rename starts meanwhile.
pub fn remove_all_and_exit(code: i32) -> ! {
    let unfinished = registry();
    for path in unfinished.iter() {
        match std::fs::remove_file(path) {
            // Its owner removed it already (a run that failed).
            Err(err) if err.kind() != std::io::ErrorKind::NotFound => {
                eprintln!("cannot remove {}: {err}", path.display());
            }
            _ => {}
        }
    }
    std::process::exit(code)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn registered(path: &Path) -> bool {
        registry().iter().any(|p| p == path)
    }

    #[test]
    fn a_file_is_registered_until_finished_or_dropped() {
        let dir = tempfile::tempdir().expect("temp dir");
        let (file, unfinished) =
            UnfinishedFile::create(|| tempfile::Builder::new().suffix(".part").tempfile_in(&dir))
                .expect("created");
        let temp = file.path().to_path_buf();
        assert!(registered(&temp));
        let out = dir.path().join("out");
        unfinished
            .finish_with(|| file.persist(&out).map_err(|e| e.error))
            .expect("renamed");
        assert!(!registered(&temp));
        assert!(out.is_file());

        let (file, unfinished) =
            UnfinishedFile::create(|| tempfile::Builder::new().tempfile_in(&dir)).expect("created");
        let temp = file.path().to_path_buf();
        drop(unfinished);
        assert!(!registered(&temp));
    }
}
