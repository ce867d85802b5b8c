//! Faults across real processes: a SIGKILLed estimator or replay is
//! restarted and the chain resumes without manual cleanup; a subscriber
//! that stops reading blocks nobody; the files iceoryx2 creates for a
//! stack are not writable by other users. Each test under a service prefix
//! of its own.

use std::collections::{BTreeSet, HashMap};
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use nix::sys::signal::Signal;
use serde_json::Value;
use slope_integration_tests::{deadline, recording, unique_prefix, Proc};
use slope_ipc_types::now_ns;

/// `slope-echo --json` on `prefix`, subscribed, printing every estimate.
fn start_echo(prefix: &str) -> Proc {
    Proc::spawn("slope-echo", ["--json", "--service-prefix", prefix])
        .assert_ready("subscribed to estimates")
}

fn start_estimator(prefix: &str) -> Proc {
    Proc::spawn("slope-estimator", ["--service-prefix", prefix]).assert_ready("estimator ready")
}

/// `slope-replay --loop` of the bundled clean ramp at `rate` Hz.
fn start_replay(prefix: &str, rate: &str) -> Proc {
    let dir = recording("ramp16-clean");
    Proc::spawn(
        "slope-replay",
        [
            dir.to_str().expect("utf-8 path"),
            "--service-prefix",
            prefix,
            "--loop",
            "--rate",
            rate,
        ],
    )
}

/// The next estimate the echo prints, parsed, before `until`.
fn next_estimate(echo: &mut Proc, until: Instant) -> Option<Value> {
    let line = echo.stdout_line(until)?;
    Some(
        serde_json::from_str(&line)
            .unwrap_or_else(|e| panic!("slope-echo printed invalid JSON {line:?}: {e}")),
    )
}

/// Waits (until `until`) for an estimate published after `after_ns`;
/// returns it with the moment it was read. Estimates published earlier
/// (still in the pipe from before a fault) are skipped.
fn estimate_published_after(
    echo: &mut Proc,
    after_ns: u64,
    until: Instant,
) -> Option<(Value, Instant)> {
    while let Some(estimate) = next_estimate(echo, until) {
        let stamp = estimate["publish_stamp_ns"].as_u64().expect("a stamp");
        if stamp > after_ns {
            return Some((estimate, Instant::now()));
        }
    }
    None
}

/// SIGKILL of the estimator, then a new one: the echo that stayed up the
/// whole time receives the new estimator's estimates within a second of its
/// start, with no manual cleanup of the dead process's shared memory (the
/// estimate and cloud services allow one publisher each, so the dead one's
/// ports must be gone). Twice, so the first recovery is not luck.
#[test]
fn a_killed_estimator_is_restarted_and_estimates_resume_within_a_second() {
    let prefix = unique_prefix("kill-estimator");
    let mut echo = start_echo(&prefix);
    let mut estimator = start_estimator(&prefix);
    let mut replay = start_replay(&prefix, "30");
    assert!(
        next_estimate(&mut echo, deadline(30.0)).is_some(),
        "no estimate before the fault\n{}\n{}",
        estimator.diagnostics(),
        replay.diagnostics()
    );
    let mut resume_times = Vec::new();
    for round in 0..2 {
        estimator.signal(Signal::SIGKILL);
        let status = estimator.wait_exit(deadline(5.0));
        assert!(
            status.is_some_and(|s| !s.success()),
            "round {round}: {status:?}"
        );
        let killed_ns = now_ns();
        let started = Instant::now();
        estimator = Proc::spawn("slope-estimator", ["--service-prefix", &prefix]);
        let resumed = estimate_published_after(&mut echo, killed_ns, deadline(20.0));
        let (estimate, at) = resumed.unwrap_or_else(|| {
            panic!(
                "round {round}: no estimate after the restart\n{}\n{}\n{}",
                estimator.diagnostics(),
                echo.diagnostics(),
                replay.diagnostics()
            )
        });
        let resume = at - started;
        eprintln!("round {round}: estimates resumed {resume:?} after the estimator started");
        assert_eq!(estimate["status"], "ok", "{estimate}");
        resume_times.push(resume);
        // The new estimator carries on, estimate after estimate.
        for _ in 0..5 {
            let next = next_estimate(&mut echo, deadline(5.0));
            assert!(next.is_some(), "round {round}: the estimates stopped again");
        }
    }
    for (round, resume) in resume_times.iter().enumerate() {
        assert!(
            *resume < Duration::from_secs(1),
            "round {round}: estimates resumed only {resume:?} after the restart (all: \
             {resume_times:?})"
        );
    }
    for proc in [&mut replay, &mut estimator, &mut echo] {
        proc.signal(Signal::SIGTERM);
        proc.assert_exits_zero_within(Duration::from_secs(2));
    }
}

/// SIGKILL of the publisher (slope-replay) and a new one: the estimator,
/// left alone, picks up the new publisher's clouds by itself and the echo
/// sees estimates again; nobody was restarted but the replay.
#[test]
fn a_killed_replay_is_restarted_and_the_estimator_resumes_by_itself() {
    let prefix = unique_prefix("kill-replay");
    let mut echo = start_echo(&prefix);
    let mut estimator = start_estimator(&prefix);
    let mut replay = start_replay(&prefix, "20");
    assert!(
        next_estimate(&mut echo, deadline(30.0)).is_some(),
        "no estimate before the fault\n{}\n{}",
        estimator.diagnostics(),
        replay.diagnostics()
    );
    replay.signal(Signal::SIGKILL);
    assert!(replay.wait_exit(deadline(5.0)).is_some(), "replay survived");
    let killed_ns = now_ns();
    let started = Instant::now();
    let mut replay = start_replay(&prefix, "20");
    let resumed = estimate_published_after(&mut echo, killed_ns, deadline(20.0));
    let (estimate, at) = resumed.unwrap_or_else(|| {
        panic!(
            "no estimate after the replay restarted\n{}\n{}",
            estimator.diagnostics(),
            replay.diagnostics()
        )
    });
    eprintln!(
        "estimates resumed {:?} after the new replay started",
        at - started
    );
    assert_eq!(estimate["status"], "ok", "{estimate}");
    // Frames of the new replay (its indices start again from 0).
    assert!(estimate["frame"].as_u64() < Some(40), "{estimate}");
    for _ in 0..5 {
        assert!(
            next_estimate(&mut echo, deadline(5.0)).is_some(),
            "the estimates stopped again\n{}",
            estimator.diagnostics()
        );
    }
    assert!(
        estimator.wait_exit(deadline(0.0)).is_none(),
        "the estimator exited"
    );
    for proc in [&mut replay, &mut estimator, &mut echo] {
        proc.signal(Signal::SIGTERM);
        proc.assert_exits_zero_within(Duration::from_secs(2));
    }
}

/// A subscriber to the estimates (slope-echo) and one to the clouds
/// (slope-record) are frozen with SIGSTOP while the chain runs. Their
/// queues fill and overflow (2 clouds, 64 estimates), and still: the replay
/// publishes at its rate, and the echo that reads on receives every
/// estimate the estimator publishes, in order. (The estimator may skip
/// clouds when the machine is busy; it says so in `dropped_frames`, and
/// those are the only gaps allowed.) After SIGCONT both carry on and stop
/// cleanly.
#[test]
fn a_subscriber_that_stops_reading_blocks_nobody() {
    let prefix = unique_prefix("stalled");
    let rate_hz = 10.0;
    let out = tempfile::tempdir().expect("temp dir");
    let out_dir = out.path().join("stalled-recording");
    let mut witness = start_echo(&prefix);
    let mut stalled_echo = start_echo(&prefix);
    let mut stalled_record = Proc::spawn(
        "slope-record",
        [
            out_dir.to_str().expect("utf-8 path"),
            "--service-prefix",
            &prefix,
        ],
    )
    .assert_ready("recording the cloud topic");
    let mut estimator = start_estimator(&prefix);
    let mut replay = start_replay(&prefix, &rate_hz.to_string());

    // Both stalled subscribers have received data before they freeze.
    let stalled_seen = stalled_echo.stdout_line(deadline(30.0));
    assert!(stalled_seen.is_some(), "{}", estimator.diagnostics());
    let recording = stalled_record.wait_stderr("first cloud; recording", deadline(30.0));
    assert!(recording.is_some(), "{}", stalled_record.diagnostics());
    stalled_echo.signal(Signal::SIGSTOP);
    stalled_record.signal(Signal::SIGSTOP);
    let frozen_ns = now_ns();

    // More estimates than the frozen echo's queue holds.
    let wanted = 80;
    let mut frames: Vec<(u64, u64, Instant)> = Vec::new();
    let until = deadline(60.0);
    while frames.len() < wanted {
        let Some((estimate, at)) = estimate_published_after(&mut witness, frozen_ns, until) else {
            break;
        };
        frames.push((
            estimate["frame"].as_u64().expect("a frame index"),
            estimate["dropped_frames"].as_u64().expect("a count"),
            at,
        ));
    }
    assert_eq!(
        frames.len(),
        wanted,
        "estimates stopped while subscribers were frozen\n{}\n{}",
        estimator.diagnostics(),
        replay.diagnostics()
    );
    for pair in frames.windows(2) {
        let ((frame, dropped, _), (next, next_dropped, _)) = (pair[0], pair[1]);
        assert!(next > frame, "out of order: {frame} then {next}");
        assert_eq!(
            next - frame - 1,
            next_dropped - dropped,
            "the echo missed an estimate between frames {frame} and {next} (the estimator \
             dropped {} clouds there)",
            next_dropped - dropped
        );
    }
    // The replay kept its pace: frame indices are its count of clouds sent.
    let (first, last) = (frames[0], frames[wanted - 1]);
    let seconds = (last.2 - first.2).as_secs_f64();
    let replay_hz = (last.0 - first.0) as f64 / seconds;
    let dropped = last.1 - first.1;
    eprintln!(
        "{wanted} estimates in {seconds:.1} s while two subscribers were frozen: the replay at \
         {replay_hz:.2} Hz, {dropped} clouds skipped by the estimator, none missed by the echo"
    );
    assert!(
        (replay_hz - rate_hz).abs() <= 0.15 * rate_hz,
        "the replay sent {replay_hz:.2} Hz, not {rate_hz} Hz"
    );

    stalled_echo.signal(Signal::SIGCONT);
    stalled_record.signal(Signal::SIGCONT);
    // The thawed echo reads on: its queue, then new estimates.
    let thawed = stalled_echo.stdout_line(deadline(10.0));
    assert!(thawed.is_some(), "{}", stalled_echo.diagnostics());
    for proc in [
        &mut replay,
        &mut estimator,
        &mut witness,
        &mut stalled_echo,
        &mut stalled_record,
    ] {
        proc.signal(Signal::SIGTERM);
        proc.assert_exits_zero_within(Duration::from_secs(3));
    }
}

/// Every file a process holds open or maps that lies under /dev/shm or
/// `root`, with the unix sockets it holds resolved to their paths.
fn iceoryx2_files_of(pid: u32, root: &Path, sockets: &HashMap<String, PathBuf>) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let fds = std::fs::read_dir(format!("/proc/{pid}/fd"))
        .unwrap_or_else(|e| panic!("cannot list the descriptors of {pid}: {e}"));
    for fd in fds.flatten() {
        let Ok(target) = std::fs::read_link(fd.path()) else {
            continue;
        };
        let text = target.to_string_lossy().into_owned();
        if let Some(path) = sockets.get(&text) {
            files.push(path.clone());
        } else if target.starts_with("/dev/shm") || target.starts_with(root) {
            files.push(target);
        }
    }
    let maps = std::fs::read_to_string(format!("/proc/{pid}/maps")).expect("maps readable");
    for line in maps.lines() {
        if let Some(path) = line.split_whitespace().nth(5) {
            if path.starts_with("/dev/shm/") {
                files.push(PathBuf::from(path));
            }
        }
    }
    files
}

/// `socket:[inode]` -> the path a unix socket is bound to.
fn unix_socket_paths() -> HashMap<String, PathBuf> {
    let table = std::fs::read_to_string("/proc/net/unix").expect("/proc/net/unix readable");
    table
        .lines()
        .skip(1)
        .filter_map(|line| {
            let columns: Vec<&str> = line.split_whitespace().collect();
            let path = columns.get(7)?;
            Some((format!("socket:[{}]", columns[6]), PathBuf::from(path)))
        })
        .collect()
}

/// iceoryx2's root path, from the node details file a process holds open
/// (`root-path = "/tmp/iceoryx2/"` unless a config file says otherwise).
fn iceoryx2_root_of(pid: u32) -> PathBuf {
    let fds = std::fs::read_dir(format!("/proc/{pid}/fd")).expect("descriptors listable");
    for fd in fds.flatten() {
        let Ok(target) = std::fs::read_link(fd.path()) else {
            continue;
        };
        if target.file_name().is_some_and(|n| n == "iox2_node.details") {
            let details = std::fs::read_to_string(&target).expect("node details readable");
            let root = details
                .lines()
                .find_map(|l| l.strip_prefix("root-path = "))
                .unwrap_or_else(|| panic!("no root-path in {}:\n{details}", target.display()));
            return PathBuf::from(root.trim_matches('"'));
        }
    }
    panic!("process {pid} holds no iceoryx2 node details file");
}

fn mode_of(path: &Path) -> u32 {
    std::fs::metadata(path)
        .unwrap_or_else(|e| panic!("cannot stat {}: {e}", path.display()))
        .permissions()
        .mode()
}

/// While replay -> estimator -> echo run, every file iceoryx2 created for
/// them (shared memory of the samples, service and port bookkeeping in
/// /dev/shm; node, service and event-socket files under iceoryx2's root
/// path, and the directories on the way) is neither group- nor
/// other-writable. The one file iceoryx2 0.10 makes writable for everyone
/// by design, its global node counter `*.global_mgmt` in /dev/shm, is not
/// per stack (no process keeps it open); it is checked to be that small
/// counter (README, "Faults and trust model").
#[test]
fn iceoryx2_files_are_not_writable_by_other_users() {
    let prefix = unique_prefix("modes");
    let mut echo = start_echo(&prefix);
    let mut estimator = start_estimator(&prefix);
    let mut replay = start_replay(&prefix, "10");
    assert!(
        next_estimate(&mut echo, deadline(30.0)).is_some(),
        "no estimate\n{}\n{}",
        estimator.diagnostics(),
        replay.diagnostics()
    );
    let root = iceoryx2_root_of(estimator.pid());
    let sockets = unix_socket_paths();
    let mut files = BTreeSet::new();
    for proc in [&echo, &estimator, &replay] {
        files.extend(iceoryx2_files_of(proc.pid(), &root, &sockets));
    }
    // The directories between the files and the root, and the root.
    let mut dirs = BTreeSet::new();
    for file in files.iter().filter(|f| f.starts_with(&root)) {
        let mut dir = file.parent();
        while let Some(d) = dir.filter(|d| d.starts_with(&root)) {
            dirs.insert(d.to_path_buf());
            dir = d.parent();
        }
    }
    // Every kind of file the chain needs is among them, or the check
    // would prove little.
    for kind in [
        ".data",
        ".dynamic",
        ".connection",
        ".event_mgmt",
        ".event",
        ".service",
        ".node_monitor",
        "iox2_node.details",
    ] {
        assert!(
            files.iter().any(|f| f.to_string_lossy().ends_with(kind)),
            "no {kind} file among {files:#?}"
        );
    }
    let writable: Vec<String> = files
        .iter()
        .chain(&dirs)
        .map(|f| (f, mode_of(f)))
        .filter(|(_, mode)| mode & 0o022 != 0)
        .map(|(f, mode)| format!("{} {:o}", f.display(), mode & 0o7777))
        .collect();
    assert!(
        writable.is_empty(),
        "writable by group or others: {writable:#?}"
    );
    eprintln!(
        "{} files and {} directories, none writable by group or others",
        files.len(),
        dirs.len()
    );

    // The exception the README names: iceoryx2's global node counter, the
    // same file for every iceoryx2 process of the machine, a few bytes.
    let counters: Vec<(String, u64)> = std::fs::read_dir("/dev/shm")
        .expect("/dev/shm listable")
        .flatten()
        .filter_map(|entry| {
            let name = entry.file_name().to_string_lossy().into_owned();
            let wanted = name.starts_with("iox2_") && name.ends_with("_node.0_10_0.global_mgmt");
            // Removed meanwhile by another test: nothing to check.
            let size = entry.metadata().ok()?.len();
            wanted.then_some((name, size))
        })
        .collect();
    assert!(!counters.is_empty(), "no global management segment");
    for (name, size) in &counters {
        assert!(*size <= 64, "{name} holds {size} bytes, not just a counter");
    }
    for proc in [&mut replay, &mut estimator, &mut echo] {
        proc.signal(Signal::SIGTERM);
        proc.assert_exits_zero_within(Duration::from_secs(2));
    }
}

/// Copies the bundled recording `name` into `to` with every depth image
/// replaced by bytes that are no PNG.
fn copy_with_broken_depth(name: &str, to: &Path) {
    let from = recording(name);
    for entry in walk(&from) {
        let relative = entry.strip_prefix(&from).expect("inside the recording");
        let target = to.join(relative);
        std::fs::create_dir_all(target.parent().expect("a parent")).expect("mkdir");
        if relative.starts_with("depth") {
            std::fs::write(&target, b"not a png").expect("write");
        } else {
            std::fs::copy(&entry, &target).expect("copy");
        }
    }
}

/// Every file under `dir`.
fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).expect("read_dir") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            files.extend(walk(&path));
        } else {
            files.push(path);
        }
    }
    files
}

/// `--skip-bad-frames` (with and without `--loop`) on a recording none of
/// whose frames can be read publishes nothing: that is a failure, not a
/// replay that went well.
#[test]
fn a_replay_with_no_readable_frame_fails() {
    let dir = tempfile::tempdir().expect("temp dir");
    let broken = dir.path().join("broken");
    copy_with_broken_depth("ramp16", &broken);
    let prefix = unique_prefix("replay-unreadable");
    for looping in [true, false] {
        let mut args = vec![
            broken.to_str().expect("utf-8 path"),
            "--skip-bad-frames",
            "--rate",
            "1000",
            "--service-prefix",
            prefix.as_str(),
        ];
        if looping {
            args.push("--loop");
        }
        let mut replay = Proc::spawn("slope-replay", args);
        let status = replay.wait_exit(deadline(20.0));
        let diagnostics = replay.diagnostics();
        assert!(
            status.is_some_and(|s| !s.success()),
            "loop {looping}: {status:?}\n{diagnostics}"
        );
        assert!(
            diagnostics.contains("no frame could be read"),
            "{diagnostics}"
        );
    }
}
