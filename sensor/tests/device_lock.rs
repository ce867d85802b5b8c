//! [`DeviceLock`] between two processes (issue #13, item 3): this test
//! executable runs itself a second time as the lock holder
//! (`holder_process`, which does nothing unless `SLOPE_TEST_LOCK_HOLDER_DIR`
//! is set), so the lock is contended across a real process boundary.

use std::io::{BufRead, BufReader, Write};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use slope_sensor::device_lock::{DeviceLock, DeviceLockError};

const HOLDER_DIR_ENV: &str = "SLOPE_TEST_LOCK_HOLDER_DIR";
const SERIAL: &str = "011054343347";

/// The child's side: takes the lock, says so, holds it until stdin closes.
#[test]
fn holder_process() {
    let Some(dir) = std::env::var_os(HOLDER_DIR_ENV) else {
        return;
    };
    let _lock = DeviceLock::acquire_in(std::path::Path::new(&dir), "kinect2", SERIAL)
        .expect("the holder takes the free lock");
    let mut stdout = std::io::stdout();
    writeln!(stdout, "LOCKED").expect("stdout");
    stdout.flush().expect("stdout");
    let mut line = String::new();
    // Returns at EOF: the parent closed our stdin (or died).
    while std::io::stdin().read_line(&mut line).is_ok_and(|n| n > 0) {}
}

/// Kills the holder if the test fails half-way.
struct Holder(Child);

impl Drop for Holder {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn a_lock_held_by_another_process_is_refused_with_its_pid_until_it_exits() {
    let dir = tempfile::tempdir().expect("temp dir");
    let exe = std::env::current_exe().expect("test executable");
    let child = Command::new(exe)
        .args([
            "--exact",
            "holder_process",
            "--nocapture",
            "--test-threads",
            "1",
        ])
        .env(HOLDER_DIR_ENV, dir.path())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn the holder");
    let mut holder = Holder(child);
    let holder_pid = holder.0.id();
    // Read the child's stdout on a thread, so that the wait has a deadline.
    let stdout = holder.0.stdout.take().expect("piped stdout");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        match rx.recv_timeout(left) {
            Ok(line) if line.contains("LOCKED") => break,
            Ok(_) => continue,
            Err(_) => panic!("the holder never took the lock"),
        }
    }

    match DeviceLock::acquire_in(dir.path(), "kinect2", SERIAL) {
        Err(err @ DeviceLockError::Busy { .. }) => {
            let message = err.to_string();
            assert!(
                message.contains(&format!("PID {holder_pid}")),
                "does not name the holder {holder_pid}: {message}"
            );
        }
        other => panic!("expected Busy, got {other:?}"),
    }
    assert_eq!(
        DeviceLock::holder_in(dir.path(), "kinect2", SERIAL),
        Some(Some(holder_pid))
    );

    // The holder exits (stdin closed): the kernel releases its lock.
    drop(holder.0.stdin.take());
    let deadline = Instant::now() + Duration::from_secs(10);
    let lock = loop {
        match DeviceLock::acquire_in(dir.path(), "kinect2", SERIAL) {
            Ok(lock) => break lock,
            Err(DeviceLockError::Busy { .. }) if Instant::now() < deadline => {
                std::thread::sleep(Duration::from_millis(10));
            }
            Err(err) => panic!("the lock was not released: {err}"),
        }
    };
    assert!(lock
        .path()
        .ends_with(format!("slope-kinect2-{SERIAL}.lock")));
}
