//! The systemd notify protocol without systemd: the test binds the
//! datagram socket systemd would (`NOTIFY_SOCKET`), asks for a watchdog
//! (`WATCHDOG_USEC`), runs the real estimator with a replay feeding it, and
//! reads what the estimator tells the service manager.

use std::os::unix::net::UnixDatagram;
use std::time::{Duration, Instant};

use nix::sys::signal::Signal;
use slope_integration_tests::{
    deadline, read_notify_until, recording, repo_root, unique_prefix, Proc,
};

#[test]
fn the_estimator_speaks_the_notify_protocol() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (socket, path) = notify_socket(dir.path());
    let prefix = unique_prefix("notify");
    let notify = path.to_str().expect("utf-8 path");
    let mut estimator = Proc::spawn_with_env(
        "slope-estimator",
        ["--service-prefix", prefix.as_str()],
        &[("NOTIFY_SOCKET", notify), ("WATCHDOG_USEC", "400000")],
    );
    let mut seen = Vec::new();
    assert!(
        read_notify_until(&socket, &mut seen, "READY=1", deadline(20.0)),
        "{seen:?}\n{}",
        estimator.diagnostics()
    );
    let rec = recording("ramp16-clean");
    let mut replay = Proc::spawn(
        "slope-replay",
        [
            rec.to_str().expect("utf-8"),
            "--service-prefix",
            &prefix,
            "--rate",
            "10",
        ],
    );
    // The watchdog is pinged at half its interval, the status says how it goes.
    assert!(
        read_notify_until(&socket, &mut seen, "WATCHDOG=1", deadline(5.0)),
        "{seen:?}"
    );
    let by = deadline(20.0);
    while Instant::now() < by
        && !seen
            .iter()
            .any(|m| m.starts_with("STATUS=") && !m.contains("STATUS=0 frames"))
    {
        read_notify_until(
            &socket,
            &mut seen,
            "never",
            Instant::now() + Duration::from_millis(500),
        );
    }
    let status = seen
        .iter()
        .rev()
        .find(|m| m.starts_with("STATUS=") && m.contains("fps"))
        .unwrap_or_else(|| panic!("no status line: {seen:?}"));
    assert!(
        status.contains("dropped") && status.contains("last slope"),
        "{status}"
    );
    replay.wait_exit(deadline(20.0));
    // The clouds stopped: within a few seconds the status says so (and its
    // rate is the recent one, 0).
    assert!(
        read_notify_until(&socket, &mut seen, "STATUS=no cloud for", deadline(8.0)),
        "{seen:?}"
    );
    let quiet = seen
        .iter()
        .rev()
        .find(|m| m.starts_with("STATUS=no cloud for"))
        .expect("found above");
    assert!(quiet.contains("(0.0 fps)"), "{quiet}");
    estimator.signal(Signal::SIGTERM);
    assert!(
        read_notify_until(&socket, &mut seen, "STOPPING=1", deadline(5.0)),
        "{seen:?}"
    );
    let exit = estimator.wait_exit(deadline(5.0));
    assert!(
        exit.is_some_and(|s| s.success()),
        "{}",
        estimator.diagnostics()
    );
}

/// A config-file error under systemd: `STATUS=failed: <reason>` naming the
/// bad key, then exit status 78 (EX_CONFIG), which the unit does not
/// restart.
#[test]
fn a_config_error_says_failed_to_systemd() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (socket, path) = notify_socket(dir.path());
    let config = dir.path().join("slope.toml");
    std::fs::write(&config, "[estimator]\nmethd = \"tls\"\n").expect("write the config file");
    let prefix = unique_prefix("notify-config");
    let mut estimator = Proc::spawn_with_env(
        "slope-estimator",
        [
            "--config",
            config.to_str().expect("utf-8 path"),
            "--service-prefix",
            prefix.as_str(),
        ],
        &[("NOTIFY_SOCKET", path.to_str().expect("utf-8 path"))],
    );
    let mut seen = Vec::new();
    assert!(
        read_notify_until(&socket, &mut seen, "STATUS=failed: ", deadline(20.0)),
        "{seen:?}\n{}",
        estimator.diagnostics()
    );
    let failed = seen
        .iter()
        .find(|m| m.starts_with("STATUS=failed: "))
        .expect("seen");
    assert!(failed.contains("methd"), "{failed}");
    let exit = estimator.wait_exit(deadline(10.0));
    assert_eq!(
        exit.and_then(|s| s.code()),
        Some(78),
        "{}",
        estimator.diagnostics()
    );
}

#[test]
fn a_refused_flag_says_failed_to_systemd_and_exits_2() {
    // What SLOPE_ESTIMATOR_ARGS="--method foo" in /etc/default/slope does:
    // the unit's RestartPreventExitStatus=78 2 must not restart it, and its
    // status line must say why.
    let dir = tempfile::tempdir().expect("temp dir");
    let (socket, path) = notify_socket(dir.path());
    let mut estimator = Proc::spawn_with_env(
        "slope-estimator",
        ["--method", "foo"],
        &[("NOTIFY_SOCKET", path.to_str().expect("utf-8 path"))],
    );
    let mut seen = Vec::new();
    assert!(
        read_notify_until(
            &socket,
            &mut seen,
            "STATUS=failed: invalid command line: ",
            deadline(20.0)
        ),
        "{seen:?}\n{}",
        estimator.diagnostics()
    );
    assert!(seen.iter().any(|m| m.contains("'foo'")), "{seen:?}");
    let exit = estimator.wait_exit(deadline(10.0));
    assert_eq!(
        exit.and_then(|s| s.code()),
        Some(2),
        "{}",
        estimator.diagnostics()
    );
    let unit = std::fs::read_to_string(repo_root().join("systemd/slope-estimator.service"))
        .expect("the unit file");
    assert!(
        unit.lines().any(|l| l == "RestartPreventExitStatus=78 2"),
        "the unit restarts on status 2"
    );
}

/// A datagram socket in `dir` for `NOTIFY_SOCKET`, read with a 100 ms
/// timeout, and its path.
fn notify_socket(dir: &std::path::Path) -> (UnixDatagram, std::path::PathBuf) {
    let path = dir.join("notify.sock");
    let socket = UnixDatagram::bind(&path).expect("bind the notify socket");
    socket
        .set_read_timeout(Some(Duration::from_millis(100)))
        .expect("timeout");
    (socket, path)
}
