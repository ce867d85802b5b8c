//! The Python venvs of the tests that check us against an independent
//! implementation from PyPI (Cyclone DDS, rosbags, the `iceoryx2` client):
//! made once per test binary in its `CARGO_TARGET_TMPDIR`, skipped only
//! where Python may be missing (never in CI: `SLOPE_REQUIRE_PYTHON` or `CI`).

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;

use slope_test_support::{require, Requirement};

/// The interpreter that makes the venvs: `PYTHON`, else `python3`.
pub fn python() -> String {
    std::env::var("PYTHON").unwrap_or_else(|_| "python3".to_string())
}

/// The interpreter of a venv in `dir` with `packages` (names or paths)
/// installed by pip, or why there is none. With `present`, a venv where
/// `import <present>` already works is used as it is.
pub fn make_venv(
    dir: &Path,
    present: Option<&str>,
    packages: &[&OsStr],
) -> Result<PathBuf, String> {
    let bin = dir.join("bin/python");
    if !bin.exists() {
        let made = Command::new(python())
            .args(["-m", "venv"])
            .arg(dir)
            .output()
            .map_err(|e| format!("cannot run {}: {e}", python()))?;
        if !made.status.success() {
            return Err(format!(
                "python3 -m venv failed: {}",
                String::from_utf8_lossy(&made.stderr)
            ));
        }
    }
    if let Some(modules) = present {
        let found = Command::new(&bin)
            .args(["-c", &format!("import {modules}")])
            .output()
            .is_ok_and(|out| out.status.success());
        if found {
            return Ok(bin);
        }
    }
    let installed = Command::new(&bin)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
        ])
        .args(packages)
        .output()
        .map_err(|e| format!("cannot run pip: {e}"))?;
    if !installed.status.success() {
        let names: Vec<_> = packages.iter().map(|p| p.to_string_lossy()).collect();
        return Err(format!(
            "pip install {} failed: {}",
            names.join(" "),
            String::from_utf8_lossy(&installed.stderr)
        ));
    }
    Ok(bin)
}

/// The interpreter `made` holds, or `None` (the test skips, saying so)
/// when it could not be made and Python may be missing; a failure in CI
/// ([`slope_test_support::require`] with [`Requirement::Python`]).
/// `what` names what the venv was for.
pub fn venv_or_skip(made: &Result<PathBuf, String>, what: &str) -> Option<PathBuf> {
    let made = made
        .clone()
        .map_err(|why| format!("{what} cannot be installed: {why}"));
    require(Requirement::Python, made)
}
