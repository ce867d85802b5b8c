//! `slope-capture` with libfreenect2 installed but no Kinect v2 attached
//! (the situation on CI machines and on a robot whose camera is unplugged).
//! Needs the `kinect2` feature: `cargo test --workspace --features kinect2`.
#![cfg(feature = "kinect2")]

use std::time::{Duration, Instant};

use nix::sys::signal::Signal;
use slope_integration_tests::{deadline, read_notify_until, unique_prefix, Proc};
use slope_sensor::device_lock::{DeviceLock, LOCK_DIR_ENV};
use slope_sensor::kinect2::LOCK_KIND;
use slope_test_support::{require, Requirement};

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

/// The notify protocol of the real slope-capture without a device: while
/// it waits for one it pings the watchdog and extends its start-up time
/// (never READY=1: nothing streams), and on SIGTERM says STOPPING=1; a
/// failed start leaves the reason in its status line.
#[test]
fn waiting_and_failing_are_told_to_systemd() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("notify.sock");
    let socket = std::os::unix::net::UnixDatagram::bind(&path).expect("bind");
    socket
        .set_read_timeout(Some(Duration::from_millis(100)))
        .expect("timeout");
    let notify = path.to_str().expect("utf-8 path");
    let prefix = unique_prefix("capture-notify");
    let mut capture = Proc::spawn_with_env(
        "slope-capture",
        ["--service-prefix", &prefix, "--wait-for-device"],
        &[("NOTIFY_SOCKET", notify), ("WATCHDOG_USEC", "400000")],
    );
    let mut seen = Vec::new();
    assert!(
        read_notify_until(&socket, &mut seen, "EXTEND_TIMEOUT_USEC=", deadline(10.0)),
        "{seen:?}\n{}",
        capture.diagnostics()
    );
    assert!(
        read_notify_until(&socket, &mut seen, "WATCHDOG=1", deadline(5.0)),
        "{seen:?}"
    );
    assert!(
        seen.iter()
            .any(|m| m.contains("STATUS=waiting for a Kinect v2")),
        "{seen:?}"
    );
    capture.signal(Signal::SIGTERM);
    assert!(
        read_notify_until(&socket, &mut seen, "STOPPING=1", deadline(5.0)),
        "{seen:?}"
    );
    assert!(capture
        .wait_exit(deadline(2.0))
        .is_some_and(|s| s.success()));
    assert!(!seen.iter().any(|m| m.contains("READY=1")), "{seen:?}");

    let mut failing = Proc::spawn_with_env(
        "slope-capture",
        ["--service-prefix", &prefix],
        &[("NOTIFY_SOCKET", notify)],
    );
    let mut seen = Vec::new();
    assert!(
        read_notify_until(&socket, &mut seen, "STATUS=failed:", deadline(10.0)),
        "{seen:?}\n{}",
        failing.diagnostics()
    );
    let failed = seen
        .iter()
        .find(|m| m.starts_with("STATUS=failed:"))
        .expect("found above");
    assert!(failed.contains("no Kinect v2 found"), "{failed}");
    assert!(failing
        .wait_exit(deadline(5.0))
        .is_some_and(|s| !s.success()));
}

/// A pipeline this libfreenect2 lacks is refused before any device is
/// touched, with exit status 78 (EX_CONFIG: a restart cannot cure it).
#[test]
fn a_pipeline_that_is_not_built_in_exits_with_ex_config() {
    use slope_sensor::kinect2::Pipeline;
    let missing = [Pipeline::OpenCl, Pipeline::Cuda, Pipeline::OpenGl]
        .into_iter()
        .find(|p| !p.is_available())
        .ok_or_else(|| "this libfreenect2 has every GPU pipeline".to_string());
    let Some(missing) = require(Requirement::MissingGpuPipeline, missing) else {
        return;
    };
    let prefix = unique_prefix("capture-pipeline");
    let mut capture = Proc::spawn(
        "slope-capture",
        ["--service-prefix", &prefix, "--pipeline", missing.name()],
    );
    let status = capture.wait_exit(deadline(10.0));
    let diagnostics = capture.diagnostics();
    let status = status.unwrap_or_else(|| panic!("still running\n{diagnostics}"));
    assert_eq!(status.code(), Some(78), "{diagnostics}");
    assert!(
        diagnostics.contains("not built into this libfreenect2")
            && diagnostics.contains("available: default, cpu"),
        "{diagnostics}"
    );
}
