//! `slope-capture` with libfreenect2 installed but no Kinect v2 attached
//! (the situation on CI machines and on a robot whose camera is unplugged).
//! Needs the `kinect2` feature: `cargo test --workspace --features kinect2`.
#![cfg(feature = "kinect2")]

use std::time::{Duration, Instant};

use nix::sys::signal::Signal;
use slope_integration_tests::{deadline, unique_prefix, Proc};
use slope_sensor::device_lock::{DeviceLock, LOCK_DIR_ENV};
use slope_sensor::kinect2::LOCK_KIND;

#[test]
fn no_kinect_is_a_clear_error_and_a_nonzero_exit_within_seconds() {
    let prefix = unique_prefix("capture-none");
    let started = Instant::now();
    let mut capture = Proc::spawn("slope-capture", ["--service-prefix", &prefix]);
    let status = capture
        .wait_exit(deadline(10.0))
        .expect("slope-capture exits without a device");
    let elapsed = started.elapsed();
    let stderr = capture.stderr_lines().join("\n");
    assert!(!status.success(), "exited 0 without a Kinect:\n{stderr}");
    assert!(
        elapsed < Duration::from_secs(5),
        "took {elapsed:?} to give up"
    );
    assert!(
        stderr.contains("no Kinect v2 found"),
        "unclear message:\n{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn wait_for_device_retries_until_sigterm_then_exits_zero() {
    let prefix = unique_prefix("capture-wait");
    let mut capture = Proc::spawn(
        "slope-capture",
        ["--service-prefix", &prefix, "--wait-for-device"],
    );
    // Two attempts prove it keeps retrying rather than giving up.
    let retrying = capture.wait_stderr("no Kinect v2 found", deadline(10.0));
    assert!(retrying.is_some(), "{}", capture.diagnostics());
    let again = capture.wait_stderr("no Kinect v2 found", deadline(10.0));
    assert!(again.is_some(), "did not retry:\n{}", capture.diagnostics());
    assert!(
        capture.wait_exit(deadline(0.2)).is_none(),
        "exited while waiting for a device:\n{}",
        capture.diagnostics()
    );
    capture.signal(Signal::SIGTERM);
    let status = capture.wait_exit(deadline(1.0));
    let diagnostics = capture.diagnostics();
    let status = status.unwrap_or_else(|| panic!("still running 1 s after SIGTERM\n{diagnostics}"));
    assert!(status.success(), "{status}\n{diagnostics}");
}

/// Another process holds the camera's lock (here: this test): a second
/// slope-capture on the same serial is refused before libfreenect2 touches
/// (and resets) the device, naming the holder's PID.
#[test]
fn a_camera_locked_by_another_process_is_refused_naming_its_pid() {
    let dir = tempfile::tempdir().expect("temp dir");
    let serial = "099999999999";
    let _held = DeviceLock::acquire_in(dir.path(), LOCK_KIND, serial).expect("free lock");
    let prefix = unique_prefix("capture-locked");
    let lock_dir = dir.path().to_str().expect("utf-8 path");
    let mut capture = Proc::spawn_with_env(
        "slope-capture",
        ["--service-prefix", &prefix, "--serial", serial],
        &[(LOCK_DIR_ENV, lock_dir)],
    );
    let status = capture.wait_exit(deadline(10.0));
    let diagnostics = capture.diagnostics();
    let status = status.unwrap_or_else(|| panic!("still running\n{diagnostics}"));
    assert!(!status.success(), "{diagnostics}");
    let ours = format!("PID {}", std::process::id());
    assert!(
        diagnostics.contains(&ours) && diagnostics.contains("in use by another process"),
        "{diagnostics}"
    );
    assert!(!diagnostics.contains("no Kinect v2 found"), "{diagnostics}");
}

#[test]
fn list_says_no_kinect_found_on_stdout_and_exits_zero() {
    let mut capture = Proc::spawn("slope-capture", ["--list"]);
    let line = capture.stdout_line(deadline(10.0));
    let status = capture.wait_exit(deadline(10.0));
    let diagnostics = capture.diagnostics();
    assert_eq!(line.as_deref(), Some("no Kinect v2 found"), "{diagnostics}");
    assert!(status.is_some_and(|s| s.success()), "{diagnostics}");
    assert_eq!(capture.stdout_line(deadline(1.0)), None, "one line only");
}
