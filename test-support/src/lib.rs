//! The one way a test may skip.
//!
//! A test that needs something beyond the repository and a Rust toolchain
//! (the real Kinect frames in `../shared/data`, Python and PyPI, root, no
//! Kinect attached, ...) asks for it here: [`shared_data`] for the frames,
//! [`require`] for anything else. Where it is missing, the test says so on
//! stderr (`SKIPPED: ...`) and returns; in CI (`CI` set, or the
//! requirement's `SLOPE_REQUIRE_*` variable) the same is a failure naming
//! what was missing, so a test that cannot run there is never a pass.
//!
//! `tests/skips.rs` lists every test that can skip (every call of these
//! two helpers, by file and function) against the checked-in `skips.txt`,
//! and refuses a skip that goes around them: a new one shows up in review.

use std::path::{Path, PathBuf};

/// Set (to anything), every skip is a failure: CI machines set it.
pub const CI_ENV: &str = "CI";

/// What a test needs that a checkout with a Rust toolchain may lack.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Requirement {
    /// The real Kinect frames in `../shared/data`.
    SharedData,
    /// `python3` with `venv`, and PyPI to install packages from.
    Python,
    /// Root and `runuser` (to start a program as another user).
    Root,
    /// No Kinect v2 attached (the checks of what happens without one).
    NoKinect,
    /// A libfreenect2 built without at least one GPU depth pipeline.
    MissingGpuPipeline,
}

impl Requirement {
    /// The variable that makes a missing requirement a failure (as `CI`
    /// does for every one).
    pub fn env(self) -> &'static str {
        match self {
            Requirement::SharedData => "SLOPE_REQUIRE_SHARED_DATA",
            Requirement::Python => "SLOPE_REQUIRE_PYTHON",
            Requirement::Root => "SLOPE_REQUIRE_ROOT",
            Requirement::NoKinect => "SLOPE_REQUIRE_NO_KINECT",
            Requirement::MissingGpuPipeline => "SLOPE_REQUIRE_MISSING_GPU_PIPELINE",
        }
    }

    /// What it is, in words.
    pub fn what(self) -> &'static str {
        match self {
            Requirement::SharedData => "the real frames in ../shared/data",
            Requirement::Python => "python3 with venv and pip, and PyPI",
            Requirement::Root => "root and runuser",
            Requirement::NoKinect => "no Kinect v2 attached",
            Requirement::MissingGpuPipeline => {
                "a libfreenect2 without some GPU pipeline (OpenCL, CUDA, OpenGL)"
            }
        }
    }

    /// True when a test may not skip for want of it: `CI` or
    /// [`Requirement::env`] is set.
    pub fn is_required(self) -> bool {
        std::env::var_os(CI_ENV).is_some() || std::env::var_os(self.env()).is_some()
    }
}

/// `found`'s value, or `None` (the test skips, saying why on stderr) when
/// `requirement` is missing and it may be; a failure naming the
/// requirement and why when it may not ([`Requirement::is_required`]).
pub fn require<T>(requirement: Requirement, found: Result<T, String>) -> Option<T> {
    match found {
        Ok(value) => Some(value),
        Err(why) => {
            assert!(
                !requirement.is_required(),
                "{} is missing: {why} ({} or {CI_ENV} is set: this test may not skip)",
                requirement.what(),
                requirement.env(),
            );
            eprintln!(
                "SKIPPED: {} is missing: {why} (set {} to make this a failure)",
                requirement.what(),
                requirement.env()
            );
            None
        }
    }
}

/// The repository root (where `Cargo.toml` of the workspace is).
pub fn repo_root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("test-support/ lives in the repository")
}

/// `../shared/data` beside the repository: the real frames.
pub fn shared_data_dir() -> PathBuf {
    repo_root().join("../shared/data")
}

/// The recording `../shared/data/<name>` (a directory with its
/// `recording.toml`), or `None` when it is not there and the test may
/// skip ([`require`] with [`Requirement::SharedData`]).
pub fn shared_data(name: &str) -> Option<PathBuf> {
    let dir = shared_data_dir().join(name);
    let found = if dir.join("recording.toml").is_file() {
        Ok(dir)
    } else {
        Err(format!("{} is not there", dir.display()))
    };
    require(Requirement::SharedData, found)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_found_requirement_is_its_value() {
        assert_eq!(require(Requirement::Root, Ok::<_, String>(7)), Some(7));
    }

    /// A missing requirement is a failure that names it whenever the test
    /// runs required (CI), and a skip otherwise.
    #[test]
    fn a_missing_requirement_fails_when_required_else_skips() {
        for requirement in [
            Requirement::SharedData,
            Requirement::Python,
            Requirement::Root,
            Requirement::NoKinect,
            Requirement::MissingGpuPipeline,
        ] {
            let outcome = std::panic::catch_unwind(|| {
                require::<()>(requirement, Err("not on this machine".to_string()))
            });
            if requirement.is_required() {
                let panic = outcome.expect_err("a failure in CI");
                let text = panic.downcast_ref::<String>().expect("a formatted message");
                assert!(
                    text.contains(requirement.what())
                        && text.contains("not on this machine")
                        && text.contains(requirement.env()),
                    "{text}"
                );
            } else {
                assert_eq!(outcome.expect("a skip"), None);
            }
        }
    }

    #[test]
    fn a_recording_absent_from_shared_data_is_never_found() {
        let outcome = std::panic::catch_unwind(|| shared_data("no-such-recording"));
        match outcome {
            Ok(found) => {
                assert!(!Requirement::SharedData.is_required());
                assert_eq!(found, None);
            }
            Err(panic) => {
                assert!(Requirement::SharedData.is_required());
                let text = panic.downcast_ref::<String>().expect("a message");
                assert!(text.contains("no-such-recording"), "{text}");
            }
        }
    }
}
