//! Helpers for the multi-process tests: find the real slope binaries, give
//! each test its own service prefix, spawn children that die with the test,
//! and wait on deadlines instead of sleeping.

pub mod python_venv;

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

use crossbeam_channel::Receiver;
use nix::sys::signal::{kill, Signal};
use nix::unistd::Pid;

/// Environment variable naming the directory of the slope binaries.
pub const BIN_DIR_ENV: &str = "SLOPE_BIN_DIR";

/// The directory holding the slope binaries: `SLOPE_BIN_DIR`, else the
/// cargo target directory this test executable was built into
/// (`target/<profile>/deps/<test>` → `target/<profile>/`).
pub fn bin_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os(BIN_DIR_ENV) {
        return PathBuf::from(dir);
    }
    let exe = std::env::current_exe().expect("the test executable has a path");
    let deps = exe.parent().expect("the test executable has a directory");
    deps.parent()
        .expect("the deps directory has a parent")
        .to_path_buf()
}

/// Path of a slope binary; panics with a fix when it has not been built.
pub fn binary(name: &str) -> PathBuf {
    let path = bin_dir().join(name);
    assert!(
        path.is_file(),
        "{} is missing: run `cargo build --workspace` (or `cargo test --workspace`, which builds \
         it) first, or set {BIN_DIR_ENV}",
        path.display()
    );
    path
}

/// The repository root.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ lives in the repository")
        .to_path_buf()
}

/// A bundled recording under tests/recordings/.
pub fn recording(name: &str) -> PathBuf {
    repo_root().join("tests/recordings").join(name)
}

/// The real Kinect frames in ../shared/data, when present; a failure when
/// they are missing in CI ([`slope_test_support::shared_data`]).
pub use slope_test_support::shared_data;

/// A service prefix no other test (or running stack) uses.
pub fn unique_prefix(test: &str) -> String {
    static COUNTER: AtomicU32 = AtomicU32::new(0);
    format!(
        "slope-test-{test}-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::SeqCst)
    )
}

/// A child process with its output collected line by line on threads;
/// killed when dropped.
pub struct Proc {
    pub name: String,
    child: Child,
    stdout: Receiver<String>,
    stderr: Receiver<String>,
    stderr_seen: Vec<String>,
}

fn pump(stream: impl Read + Send + 'static) -> Receiver<String> {
    let (tx, rx) = crossbeam_channel::unbounded();
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

impl Proc {
    /// Starts binary `name` with `args`.
    pub fn spawn<I, S>(name: &str, args: I) -> Proc
    where
        I: IntoIterator<Item = S>,
        S: AsRef<std::ffi::OsStr>,
    {
        Self::spawn_with_env(name, args, &[])
    }

    /// Starts binary `name` with `args` and the environment variables `env`.
    pub fn spawn_with_env<I, S>(name: &str, args: I, env: &[(&str, &str)]) -> Proc
    where
        I: IntoIterator<Item = S>,
        S: AsRef<std::ffi::OsStr>,
    {
        let mut command = Command::new(binary(name));
        command.args(args).env_remove("RUST_LOG");
        command.envs(env.iter().copied());
        Self::start(name, command)
    }

    /// Starts binary `name` with `args`, without the environment variables
    /// `removed` (to test what a program does when they are not set).
    pub fn spawn_without_env<I, S>(name: &str, args: I, removed: &[&str]) -> Proc
    where
        I: IntoIterator<Item = S>,
        S: AsRef<std::ffi::OsStr>,
    {
        let mut command = Command::new(binary(name));
        command.args(args).env_remove("RUST_LOG");
        for variable in removed {
            command.env_remove(variable);
        }
        Self::start(name, command)
    }

    /// Starts the program at `path` (not one of ours: a Python script's
    /// interpreter, say) with `args`.
    pub fn spawn_path<I, S>(path: &Path, args: I) -> Proc
    where
        I: IntoIterator<Item = S>,
        S: AsRef<std::ffi::OsStr>,
    {
        Self::spawn_path_with_env(path, args, &[])
    }

    /// [`Self::spawn_path`] with the environment variables `env`.
    pub fn spawn_path_with_env<I, S>(path: &Path, args: I, env: &[(&str, &std::ffi::OsStr)]) -> Proc
    where
        I: IntoIterator<Item = S>,
        S: AsRef<std::ffi::OsStr>,
    {
        let mut command = Command::new(path);
        command.args(args).env_remove("RUST_LOG");
        command.envs(env.iter().copied());
        Self::start(&path.display().to_string(), command)
    }

    /// Spawns `command` with piped output (`SLOPE_TEST_LOG` as its
    /// `RUST_LOG` when set).
    fn start(name: &str, mut command: Command) -> Proc {
        if let Some(filter) = std::env::var_os("SLOPE_TEST_LOG") {
            command.env("RUST_LOG", filter);
        }
        let mut child = command
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {name}: {e}"));
        let stdout = pump(child.stdout.take().expect("stdout is piped"));
        let stderr = pump(child.stderr.take().expect("stderr is piped"));
        Proc {
            name: name.to_string(),
            child,
            stdout,
            stderr,
            stderr_seen: Vec::new(),
        }
    }

    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Next stdout line, or None when the deadline passes or stdout closes.
    pub fn stdout_line(&mut self, deadline: Instant) -> Option<String> {
        recv_until(&self.stdout, deadline)
    }

    /// Reads stderr until a line contains `needle`; returns that line.
    pub fn wait_stderr(&mut self, needle: &str, deadline: Instant) -> Option<String> {
        while let Some(line) = recv_until(&self.stderr, deadline) {
            self.stderr_seen.push(line.clone());
            if line.contains(needle) {
                return Some(line);
            }
        }
        None
    }

    /// Every stderr line seen so far plus whatever is buffered now. Once
    /// the process has exited, reads on until its stderr closes (at most 5 s
    /// more): the reader thread may not have caught up with the exit yet.
    pub fn stderr_lines(&mut self) -> &[String] {
        if let Ok(Some(_)) = self.child.try_wait() {
            let until = deadline(5.0);
            while let Some(line) = recv_until(&self.stderr, until) {
                self.stderr_seen.push(line);
            }
        }
        while let Ok(line) = self.stderr.try_recv() {
            self.stderr_seen.push(line);
        }
        &self.stderr_seen
    }

    /// Waits for exit until the deadline; None if still running.
    pub fn wait_exit(&mut self, deadline: Instant) -> Option<ExitStatus> {
        loop {
            if let Some(status) = self.child.try_wait().expect("try_wait works") {
                return Some(status);
            }
            if Instant::now() >= deadline {
                return None;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// Waits (at most 20 s) for the stderr line containing `ready` that a
    /// program logs once it is connected; panics with the diagnostics if it
    /// does not come. Returns the process for chaining.
    pub fn assert_ready(mut self, ready: &str) -> Proc {
        if self.wait_stderr(ready, deadline(20.0)).is_none() {
            let diagnostics = self.diagnostics();
            panic!("{} never logged {ready:?}\n{diagnostics}", self.name);
        }
        self
    }

    /// Asserts that the process exits with status 0 within `within`.
    pub fn assert_exits_zero_within(&mut self, within: Duration) {
        let status = self.wait_exit(Instant::now() + within);
        let diagnostics = self.diagnostics();
        let status = status.unwrap_or_else(|| {
            panic!(
                "{} did not exit within {within:?}\n{diagnostics}",
                self.name
            )
        });
        assert!(
            status.success(),
            "{} exited with {status}\n{diagnostics}",
            self.name
        );
    }

    pub fn signal(&self, signal: Signal) {
        let pid = Pid::from_raw(i32::try_from(self.child.id()).expect("pid fits in i32"));
        kill(pid, signal).unwrap_or_else(|e| panic!("cannot signal {}: {e}", self.name));
    }

    /// Everything the process wrote to stderr, for assertion messages.
    pub fn diagnostics(&mut self) -> String {
        let lines = self.stderr_lines().join("\n");
        format!("{} stderr:\n{lines}", self.name)
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

fn recv_until(rx: &Receiver<String>, deadline: Instant) -> Option<String> {
    let timeout = deadline.saturating_duration_since(Instant::now());
    // Timed out or the stream closed: either way there is no line.
    rx.recv_timeout(timeout).ok()
}

/// Starts `slope-replay` on the bundled recording `name` under `prefix`:
/// `frames` frames at `rate_hz`, once `subscribers` are connected to the
/// cloud topic.
pub fn replay_frames(
    prefix: &str,
    name: &str,
    rate_hz: f64,
    frames: u64,
    subscribers: usize,
) -> Proc {
    let dir = recording(name);
    Proc::spawn(
        "slope-replay",
        [
            dir.to_str().expect("utf-8 path"),
            "--service-prefix",
            prefix,
            "--rate",
            &rate_hz.to_string(),
            "--max-frames",
            &frames.to_string(),
            "--wait-subscribers",
            &subscribers.to_string(),
        ],
    )
}

/// Starts `slope-replay` on every frame of the recording in `dir` under
/// `prefix`, at 5 Hz (slow enough for a debug-build estimator to take each
/// one), once one subscriber (the estimator) is connected, giving up after
/// 20 s without it.
pub fn replay_all_at_5_hz(prefix: &str, dir: &Path) -> Proc {
    Proc::spawn(
        "slope-replay",
        [
            dir.to_str().expect("utf-8 path"),
            "--service-prefix",
            prefix,
            "--rate",
            "5",
            "--wait-subscribers",
            "1",
            "--wait-timeout-s",
            "20",
        ],
    )
}

/// Reads datagrams from a notify socket (what systemd would receive) into
/// `seen` until a line of one starts with `until` or `by` passes; true when
/// such a line was seen.
pub fn read_notify_until(
    socket: &std::os::unix::net::UnixDatagram,
    seen: &mut Vec<String>,
    until: &str,
    by: Instant,
) -> bool {
    let found = |seen: &[String]| seen.iter().any(|m| m.lines().any(|l| l.starts_with(until)));
    let mut buf = [0u8; 4096];
    while Instant::now() < by {
        if found(seen) {
            return true;
        }
        if let Ok(n) = socket.recv(&mut buf) {
            seen.push(String::from_utf8_lossy(&buf[..n]).into_owned());
        }
    }
    found(seen)
}

/// A deadline `seconds` from now.
pub fn deadline(seconds: f64) -> Instant {
    Instant::now() + Duration::from_secs_f64(seconds)
}

/// Starts `slope-estimator` under `prefix` (with `extra` arguments) and
/// waits until it is subscribed.
pub fn start_estimator(prefix: &str, extra: &[&str]) -> Proc {
    let mut args = vec!["--service-prefix", prefix];
    args.extend_from_slice(extra);
    Proc::spawn("slope-estimator", &args).assert_ready("estimator ready")
}

/// Starts `slope-echo --json` under `prefix` for `count` estimates and
/// waits until it is subscribed.
pub fn start_echo(prefix: &str, count: usize) -> Proc {
    let count = count.to_string();
    Proc::spawn(
        "slope-echo",
        [
            "--json",
            "--service-prefix",
            prefix,
            "--count",
            &count,
            "--timeout-s",
            "120",
        ],
    )
    .assert_ready("subscribed to estimates")
}

/// Up to `count` JSON lines of `echo`'s stdout, within `seconds`.
pub fn read_json_lines(echo: &mut Proc, count: usize, seconds: f64) -> Vec<serde_json::Value> {
    let until = deadline(seconds);
    let mut lines = Vec::new();
    while lines.len() < count {
        let Some(line) = echo.stdout_line(until) else {
            break;
        };
        let value: serde_json::Value = serde_json::from_str(&line)
            .unwrap_or_else(|e| panic!("slope-echo printed invalid JSON {line:?}: {e}"));
        lines.push(value);
    }
    lines
}

/// Runs `slope-eval --json --method METHOD` on `recordings` and returns one
/// object per recording.
pub fn eval_json(recordings: &[PathBuf], method: &str) -> Vec<serde_json::Value> {
    let output = Command::new(binary("slope-eval"))
        .args(["--json", "--quiet", "--method", method])
        .args(recordings)
        .output()
        .expect("slope-eval runs");
    assert!(
        output.status.success(),
        "slope-eval failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("slope-eval prints JSON lines"))
        .collect()
}
