//! Soak: `slope-replay --loop` at 30 Hz -> `slope-estimator` ->
//! `slope-echo --json` for `SLOPE_SOAK_SECS` (default 600), then checks that
//! every frame got an estimate, that no process's memory grew, and that the
//! shared memory our processes used is gone once they stop.
//!
//! Memory is sampled every 10 s from the first estimate on: `VmRSS` and
//! `RssAnon` of each process (/proc/PID/status) and the /dev/shm segments
//! the three map (/proc/PID/maps). Growth is judged on `RssAnon`, private
//! memory, where a leak shows: `VmRSS` also counts the pages of the fixed
//! sample pool in shared memory as they are first touched, which is bounded
//! by the pool and no leak. The baseline is the sample 10 s in (warm).
//!
//! Ignored by `cargo test`; run the release binaries with
//!
//! ```sh
//! cargo build --release --workspace    # the test runs what is in target/release
//! cargo test --release -p slope-integration-tests --test soak -- --ignored --nocapture
//! SLOPE_SOAK_SECS=60 cargo test --release ...   # a short run
//! ```
//!
//! Frames the estimator skips because it is slower than 30 Hz are counted
//! apart from estimates lost between processes (always a failure).
//! `SLOPE_SOAK_MAX_SKIPPED_PCT` (default 0) is how many skipped frames, in
//! percent of those published, still pass.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use nix::sys::signal::Signal;
use serde_json::Value;
use slope_integration_tests::{binary, deadline, recording, unique_prefix, Proc};

const SECS_ENV: &str = "SLOPE_SOAK_SECS";
const MAX_SKIPPED_PCT_ENV: &str = "SLOPE_SOAK_MAX_SKIPPED_PCT";
const RATE_HZ: u64 = 30;
/// The processes, in the order of every memory sample.
const NAMES: [&str; 3] = ["slope-replay", "slope-estimator", "slope-echo"];
const SAMPLE_INTERVAL: Duration = Duration::from_secs(10);
/// Private memory may move this much between the baseline and the end
/// (allocator pools breathe); a leak of 100 bytes a frame is 1.8 MB in 10 min.
const ANON_TOLERANCE_KIB: u64 = 1024;

fn env_number(name: &str, default: f64) -> f64 {
    std::env::var(name)
        .ok()
        .map(|v| {
            v.parse()
                .unwrap_or_else(|_| panic!("{name}={v:?} is not a number"))
        })
        .unwrap_or(default)
}

/// A `kB` field of /proc/PID/status (`VmRSS`, `RssAnon`).
fn status_kib(pid: u32, field: &str) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status"))
        .unwrap_or_else(|e| panic!("cannot read the status of process {pid}: {e}"));
    status
        .lines()
        .find_map(|line| line.strip_prefix(field)?.strip_prefix(':'))
        .and_then(|rest| rest.trim().trim_end_matches(" kB").trim().parse().ok())
        .unwrap_or_else(|| panic!("no {field} in /proc/{pid}/status"))
}

/// The /dev/shm files a process has mapped: its iceoryx2 segments.
fn shm_files_of(pid: u32) -> BTreeSet<PathBuf> {
    let maps = std::fs::read_to_string(format!("/proc/{pid}/maps")).unwrap_or_default();
    maps.lines()
        .filter_map(|line| line.split_whitespace().nth(5))
        .filter(|path| path.starts_with("/dev/shm/"))
        .map(PathBuf::from)
        .collect()
}

/// Files in /dev/shm and their total size, bytes.
fn shm_usage() -> (usize, u64) {
    let entries: Vec<_> = std::fs::read_dir("/dev/shm")
        .expect("/dev/shm is readable")
        .filter_map(Result::ok)
        .collect();
    let bytes = entries
        .iter()
        .filter_map(|e| e.metadata().ok())
        .map(|m| m.len())
        .sum();
    (entries.len(), bytes)
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

/// One memory sample of the three processes.
struct MemorySample {
    t_s: f64,
    /// (VmRSS, RssAnon) KiB, in the order of [`NAMES`].
    rss_kib: Vec<(u64, u64)>,
    /// Size of the /dev/shm files the three map, bytes.
    shm_bytes: u64,
}

#[derive(Default)]
struct MemoryLog {
    samples: Vec<MemorySample>,
    /// Every /dev/shm file any of the processes mapped.
    shm_files: BTreeSet<PathBuf>,
}

impl MemoryLog {
    fn sample(&mut self, since: Instant, procs: &[&Proc]) {
        let mut mapped = BTreeSet::new();
        let rss_kib = procs
            .iter()
            .map(|p| {
                mapped.extend(shm_files_of(p.pid()));
                (status_kib(p.pid(), "VmRSS"), status_kib(p.pid(), "RssAnon"))
            })
            .collect();
        let shm_bytes = mapped
            .iter()
            .filter_map(|p| std::fs::metadata(p).ok())
            .map(|m| m.len())
            .sum();
        self.shm_files.extend(mapped);
        self.samples.push(MemorySample {
            t_s: since.elapsed().as_secs_f64(),
            rss_kib,
            shm_bytes,
        });
    }

    fn table(&self) -> String {
        let mut out = String::from("    t s");
        for name in NAMES {
            let _ = write!(out, "  {name:>15} VmRSS/RssAnon MiB");
        }
        out.push_str("  shm mapped MiB");
        for s in &self.samples {
            let _ = write!(out, "\n{:7.0}", s.t_s);
            for (rss, anon) in &s.rss_kib {
                let _ = write!(out, "  {:>24.1} / {:>5.1}", kib_mib(*rss), kib_mib(*anon));
            }
            let _ = write!(out, "  {:14.1}", mib(s.shm_bytes));
        }
        out
    }
}

fn kib_mib(kib: u64) -> f64 {
    kib as f64 / 1024.0
}

#[test]
#[ignore = "a 10-minute soak: cargo test --release -p slope-integration-tests --test soak -- --ignored --nocapture"]
fn replay_estimator_subscriber_soak_drops_nothing_and_stays_flat() {
    let secs = env_number(SECS_ENV, 600.0);
    let max_skipped_pct = env_number(MAX_SKIPPED_PCT_ENV, 0.0);
    let frames = (secs * RATE_HZ as f64).round() as u64;
    assert!(frames > 0, "{SECS_ENV} must be positive");
    let dir = recording("ramp16");
    let prefix = unique_prefix("soak");
    for name in NAMES {
        println!("soak: {}", binary(name).display());
    }
    let (shm_files_start, shm_bytes_start) = shm_usage();

    let mut echo = Proc::spawn("slope-echo", ["--json", "--service-prefix", &prefix])
        .assert_ready("subscribed to estimates");
    let mut estimator = Proc::spawn("slope-estimator", ["--service-prefix", &prefix])
        .assert_ready("estimator ready");
    let rate = RATE_HZ.to_string();
    let max_frames = frames.to_string();
    let mut replay = Proc::spawn(
        "slope-replay",
        [
            dir.to_str().expect("a UTF-8 path"),
            "--service-prefix",
            &prefix,
            "--loop",
            "--rate",
            &rate,
            "--max-frames",
            &max_frames,
            "--wait-subscribers",
            "1",
            "--wait-timeout-s",
            "20",
        ],
    );
    println!(
        "soak: {frames} frames of {} at {RATE_HZ} Hz ({secs} s), prefix {prefix}",
        dir.display()
    );

    // Estimates by frame index; memory every 10 s from the first estimate.
    let mut estimates: BTreeMap<u64, Value> = BTreeMap::new();
    let mut memory = MemoryLog::default();
    let started = Instant::now();
    let hard_deadline = deadline(secs + 60.0);
    let mut next_sample: Option<Instant> = None;
    let mut replay_done: Option<Instant> = None;
    loop {
        let now = Instant::now();
        if next_sample.is_some_and(|t| now >= t) {
            memory.sample(started, &[&replay, &estimator, &echo]);
            next_sample = Some(now + SAMPLE_INTERVAL);
        }
        if replay_done.is_none() && replay.wait_exit(now).is_some() {
            replay_done = Some(now);
        }
        // The last frame's estimate, or a grace period after the replay ended.
        let last_seen = estimates.contains_key(&(frames - 1));
        let grace_over = replay_done.is_some_and(|t| t.elapsed() > Duration::from_secs(5));
        if last_seen || grace_over {
            break;
        }
        assert!(
            now < hard_deadline,
            "the soak overran\n{}\n{}",
            replay.diagnostics(),
            estimator.diagnostics()
        );
        let wait_until =
            next_sample.map_or(now + SAMPLE_INTERVAL, |t| t.min(now + SAMPLE_INTERVAL));
        if let Some(line) = echo.stdout_line(wait_until) {
            let e: Value = serde_json::from_str(&line)
                .unwrap_or_else(|err| panic!("slope-echo printed {line:?}: {err}"));
            let frame = e["frame"].as_u64().expect("frame is a number");
            estimates.insert(frame, e);
            // The chain is live: the first sample.
            next_sample.get_or_insert(now);
        }
    }
    // The end sample, all three still running (the replay lingers 1 s after
    // its last frame).
    assert!(
        replay_done.is_none(),
        "the replay ended before the last estimate\n{}",
        estimator.diagnostics()
    );
    memory.sample(started, &[&replay, &estimator, &echo]);
    let (shm_files_running, shm_bytes_running) = shm_usage();

    replay.assert_exits_zero_within(Duration::from_secs(10));
    for proc in [&mut estimator, &mut echo] {
        proc.signal(Signal::SIGTERM);
        proc.assert_exits_zero_within(Duration::from_secs(2));
    }
    let (shm_files_end, shm_bytes_end) = shm_usage();
    let left_behind: Vec<_> = memory.shm_files.iter().filter(|p| p.exists()).collect();

    // Drops: the estimator's own count of the clouds it skipped (it takes the
    // newest), and whatever else is missing, which was lost on the way.
    let received = estimates.len() as u64;
    let last = estimates
        .values()
        .next_back()
        .expect("at least one estimate");
    let last_frame = last["frame"].as_u64().expect("a frame");
    let skipped = last["dropped_frames"].as_u64().expect("a count") + (frames - 1 - last_frame);
    let lost = (frames - received).saturating_sub(skipped);
    let latencies: Vec<f64> = {
        let mut l: Vec<f64> = estimates
            .values()
            .filter_map(|e| e["latency_ms"].as_f64())
            .collect();
        l.sort_by(f64::total_cmp);
        l
    };
    let median_latency = latencies
        .get(latencies.len() / 2)
        .copied()
        .unwrap_or(f64::NAN);
    let skipped_pct = 100.0 * skipped as f64 / frames as f64;

    println!(
        "soak: {frames} published, {received} estimates, {skipped} skipped by the estimator \
         ({skipped_pct:.2}%), {lost} lost between processes; median latency {median_latency:.1} ms"
    );
    println!("{}", memory.table());
    println!(
        "/dev/shm: {shm_files_start} files {:.1} MiB at start, {shm_files_running} files {:.1} MiB \
         at the end (running), {shm_files_end} files {:.1} MiB after stopping; our processes \
         mapped {} files, {} left behind",
        mib(shm_bytes_start),
        mib(shm_bytes_running),
        mib(shm_bytes_end),
        memory.shm_files.len(),
        left_behind.len()
    );

    // Every check, so that one run reports all that failed.
    let mut failures = Vec::new();
    if lost > 0 {
        failures.push(format!("{lost} estimates lost between processes"));
    }
    if skipped_pct > max_skipped_pct {
        failures.push(format!(
            "the estimator skipped {skipped} of {frames} frames ({skipped_pct:.2}% > \
             {MAX_SKIPPED_PCT_ENV}={max_skipped_pct}): it is slower than {RATE_HZ} Hz"
        ));
    }
    if !left_behind.is_empty() {
        failures.push(format!("shared memory left behind: {left_behind:?}"));
    }
    // Flat: from the sample 10 s in (warm) to the end.
    match (memory.samples.get(1), memory.samples.last()) {
        (Some(warm), Some(end)) if end.t_s > warm.t_s => {
            for ((name, &(_, warm_kib)), &(_, end_kib)) in
                NAMES.iter().zip(&warm.rss_kib).zip(&end.rss_kib)
            {
                if end_kib > warm_kib + ANON_TOLERANCE_KIB {
                    failures.push(format!(
                        "{name} RssAnon grew from {warm_kib} KiB to {end_kib} KiB"
                    ));
                }
            }
            if end.shm_bytes > warm.shm_bytes {
                failures.push(format!(
                    "shared memory mapped grew from {} to {} bytes",
                    warm.shm_bytes, end.shm_bytes
                ));
            }
        }
        _ => println!("soak: too short for a memory trend (a sample every {SAMPLE_INTERVAL:?})"),
    }
    assert!(failures.is_empty(), "soak failed:\n{}", failures.join("\n"));
}
