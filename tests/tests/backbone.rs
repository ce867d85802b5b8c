//! The backbone across real processes: slope-replay -> slope-estimator ->
//! an independent subscriber (slope-echo), each a separate process talking
//! over iceoryx2 under a service prefix of its own.

use std::collections::HashSet;
use std::path::Path;
use std::time::Duration;

use nix::sys::signal::Signal;
use serde_json::Value;
use slope_integration_tests::{
    deadline, eval_json, read_json_lines, recording, replay_all_at_5_hz, shared_data, start_echo,
    start_estimator, unique_prefix, Proc,
};
use slope_sensor::recording::Recording;

/// Every key of `slope-echo --json`: the fields of `slope.SlopeEstimate.v2`.
const ECHO_KEYS: [&str; 29] = [
    "frame",
    "timestamp_ns",
    "publish_stamp_ns",
    "source_stamp_ns",
    "status",
    "method",
    "slope_deg",
    "std_deg",
    "distance_m",
    "latency_ms",
    "dropped_frames",
    "ground_plane",
    "inclined_plane",
    "ground_inliers",
    "inclined_inliers",
    "ground_rms_m",
    "inclined_rms_m",
    "ground_area_m2",
    "inclined_area_m2",
    "ground_seen_to_m",
    "samples",
    "ground_from_mount",
    "processing_ms",
    "confidence",
    "confidence_reasons",
    "tracked_slope_deg",
    "tracked_std_deg",
    "tracked_frames",
    "tracked_accepted",
];

fn number(e: &Value, key: &str) -> f64 {
    e[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number: {e}"))
}

/// The version 2 fields of an `ok` estimate that crossed the processes:
/// both planes (unit normals, camera on their positive side), their
/// quality, the confidence and the tracked slope.
fn check_v2_fields(e: &Value, truth: f64) {
    let mut found: Vec<&str> = e
        .as_object()
        .expect("an object")
        .keys()
        .map(String::as_str)
        .collect();
    let mut expected = ECHO_KEYS.to_vec();
    expected.sort_unstable();
    found.sort_unstable();
    assert_eq!(found, expected, "{e}");
    for plane in ["ground", "inclined"] {
        let coefficients: Vec<f64> = e[format!("{plane}_plane").as_str()]
            .as_array()
            .unwrap_or_else(|| panic!("no {plane} plane: {e}"))
            .iter()
            .map(|c| c.as_f64().expect("a number"))
            .collect();
        assert_eq!(coefficients.len(), 4, "{e}");
        let norm = coefficients[..3].iter().map(|c| c * c).sum::<f64>().sqrt();
        assert!((norm - 1.0).abs() < 1e-9, "{plane} normal {norm}: {e}");
        assert!(coefficients[3] > 0.0, "{plane} d: {e}");
        assert!(
            e[format!("{plane}_inliers").as_str()].as_u64() > Some(0),
            "{e}"
        );
        assert!(number(e, &format!("{plane}_rms_m")) >= 0.0, "{e}");
        assert!(number(e, &format!("{plane}_area_m2")) > 0.0, "{e}");
    }
    // How far ahead the ground was seen: some metres (a Kinect sees up to
    // 4.5 m), carried across the processes as an f32.
    let seen = number(e, "ground_seen_to_m");
    assert!((0.3..6.0).contains(&seen), "{e}");
    let confidence = number(e, "confidence");
    assert!((0.0..=1.0).contains(&confidence), "{e}");
    assert!(e["confidence_reasons"].is_array(), "{e}");
    // The estimator tracks over the stream; a track counts at most the
    // frames seen so far, and follows the ramp.
    let frame = e["frame"].as_u64().expect("frame is a number");
    let tracked_frames = e["tracked_frames"].as_u64().expect("a count");
    assert!(tracked_frames <= frame + 1, "{e}");
    assert!(e["tracked_accepted"].is_boolean(), "{e}");
    if let Some(tracked) = e["tracked_slope_deg"].as_f64() {
        assert!((tracked - truth).abs() <= 1.0, "{e}");
    }
}

fn truth_of(dir: &Path) -> f64 {
    let rec = Recording::open(dir).expect("bundled recording opens");
    rec.meta()
        .truth
        .slope_deg
        .expect("bundled recording has truth")
}

#[test]
fn every_frame_gives_one_estimate_in_order_within_a_degree() {
    let dir = recording("ramp16-clean");
    let frames = Recording::open(&dir).expect("opens").frames().len();
    let truth = truth_of(&dir);
    let prefix = unique_prefix("every-frame");

    let mut echo = start_echo(&prefix, frames);
    let mut estimator = start_estimator(&prefix, &[]);
    let mut replay = replay_all_at_5_hz(&prefix, &dir);

    let estimates = read_json_lines(&mut echo, frames, 60.0);
    assert_eq!(
        estimates.len(),
        frames,
        "expected one estimate per frame\n{}\n{}",
        estimator.diagnostics(),
        replay.diagnostics()
    );
    let indices: Vec<u64> = estimates
        .iter()
        .map(|e| e["frame"].as_u64().expect("frame is a number"))
        .collect();
    assert_eq!(
        indices,
        (0..frames as u64).collect::<Vec<_>>(),
        "frame order"
    );
    for e in &estimates {
        for key in [
            "frame",
            "timestamp_ns",
            "status",
            "slope_deg",
            "std_deg",
            "latency_ms",
        ] {
            assert!(e.get(key).is_some(), "missing {key} in {e}");
        }
        assert_eq!(e["status"], "ok", "{e}");
        let slope = e["slope_deg"].as_f64().expect("slope is a number");
        assert!(
            (slope - truth).abs() <= 1.0,
            "slope {slope} vs truth {truth}: {e}"
        );
        let latency = e["latency_ms"].as_f64().expect("latency is a number");
        assert!(latency > 0.0 && latency < 5_000.0, "latency {latency}");
        assert_eq!(e["dropped_frames"], 0, "{e}");
        check_v2_fields(e, truth);
    }

    echo.assert_exits_zero_within(Duration::from_secs(5));
    replay.assert_exits_zero_within(Duration::from_secs(10));
    estimator.signal(Signal::SIGTERM);
    estimator.assert_exits_zero_within(Duration::from_secs(1));
}

#[test]
fn sigterm_ends_every_process_with_status_zero_within_a_second() {
    let dir = recording("ramp16-clean");
    let prefix = unique_prefix("sigterm");
    let mut echo = Proc::spawn("slope-echo", ["--service-prefix", &prefix]);
    assert!(
        echo.wait_stderr("subscribed to estimates", deadline(20.0))
            .is_some(),
        "{}",
        echo.diagnostics()
    );
    let mut estimator = start_estimator(&prefix, &[]);
    let mut replay = Proc::spawn(
        "slope-replay",
        [
            dir.to_str().expect("utf-8 path"),
            "--service-prefix",
            &prefix,
            "--loop",
            "--rate",
            "10",
        ],
    );
    // Wait until estimates flow through the whole chain.
    let first = echo.stdout_line(deadline(30.0));
    assert!(
        first.is_some(),
        "no estimate arrived\n{}\n{}",
        estimator.diagnostics(),
        replay.diagnostics()
    );
    for proc in [&mut replay, &mut estimator, &mut echo] {
        proc.signal(Signal::SIGTERM);
        proc.assert_exits_zero_within(Duration::from_secs(1));
    }
}

#[test]
fn sigint_stops_a_replay_waiting_for_subscribers() {
    let dir = recording("ramp16-clean");
    let prefix = unique_prefix("sigint-wait");
    let mut replay = Proc::spawn(
        "slope-replay",
        [
            dir.to_str().expect("utf-8 path"),
            "--service-prefix",
            &prefix,
            "--wait-subscribers",
            "3",
        ],
    );
    assert!(
        replay
            .wait_stderr("waiting for subscribers", deadline(20.0))
            .is_some(),
        "{}",
        replay.diagnostics()
    );
    replay.signal(Signal::SIGINT);
    replay.assert_exits_zero_within(Duration::from_secs(1));
}

/// Zero-copy, shown from the outside: the estimator logs the address of the
/// cloud it runs the pipeline on (the slice it borrows from the received
/// sample). That address must lie in a shared-memory file mapping of the
/// estimator process, and the replay process must map the very same file:
/// the estimator reads the bytes the publisher wrote, in place.
#[test]
fn estimator_reads_the_cloud_in_the_publishers_shared_memory() {
    let dir = recording("ramp16-clean");
    let prefix = unique_prefix("zero-copy");
    let mut estimator = start_estimator(&prefix, &["-v"]);
    let mut replay = Proc::spawn(
        "slope-replay",
        [
            dir.to_str().expect("utf-8 path"),
            "--service-prefix",
            &prefix,
            "--loop",
            "--rate",
            "10",
        ],
    );
    let line = estimator
        .wait_stderr("payload_addr=", deadline(30.0))
        .unwrap_or_else(|| panic!("no payload address logged\n{}", replay.diagnostics()));
    let hex = line
        .split("payload_addr=")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .expect("an address follows payload_addr=");
    let addr = u64::from_str_radix(hex.trim_start_matches("0x"), 16).expect("hex address");

    let estimator_maps = std::fs::read_to_string(format!("/proc/{}/maps", estimator.pid()))
        .expect("estimator maps readable");
    let mapping = estimator_maps
        .lines()
        .find(|l| {
            let range = l.split_whitespace().next().unwrap_or("");
            let mut ends = range.split('-');
            let start = u64::from_str_radix(ends.next().unwrap_or(""), 16).unwrap_or(u64::MAX);
            let end = u64::from_str_radix(ends.next().unwrap_or(""), 16).unwrap_or(0);
            (start..end).contains(&addr)
        })
        .unwrap_or_else(|| panic!("{addr:#x} is in no mapping of the estimator"));
    let file = mapping
        .split_whitespace()
        .nth(5)
        .unwrap_or_else(|| panic!("{addr:#x} lies in an anonymous mapping: {mapping}"));
    assert!(
        file.starts_with("/dev/shm/"),
        "the cloud is read from {file}, not from shared memory: {mapping}"
    );

    let replay_maps = std::fs::read_to_string(format!("/proc/{}/maps", replay.pid()))
        .expect("replay maps readable");
    let replay_files: HashSet<&str> = replay_maps
        .lines()
        .filter_map(|l| l.split_whitespace().nth(5))
        .collect();
    assert!(
        replay_files.contains(file),
        "the replay (publisher) does not map {file}; it maps {replay_files:?}"
    );
    for proc in [&mut replay, &mut estimator] {
        proc.signal(Signal::SIGTERM);
        proc.assert_exits_zero_within(Duration::from_secs(1));
    }
}

/// The chain judges a cloud as `slope-eval` judges the recording it came
/// from: the cloud header names the sensor, and the estimator takes that
/// sensor's noise model as slope-eval does from `recording.toml`. One
/// estimator sees the recordings one after another (synthetic, Kinect v2,
/// Kinect v1, Kinect v2), so it must switch models as the sensor changes,
/// once per change and not per frame. The real frames come from
/// ../shared/data when it is there (the Kinect v1 office is the one whose
/// answer depends on the model).
#[test]
fn the_chain_gives_what_slope_eval_gives_whatever_the_sensor() {
    let mut recordings = vec![recording("ramp16-clean")];
    recordings.extend(
        [
            "kinect2-stairs-front",
            "kinect1-office",
            "kinect2-stairs-top",
        ]
        .iter()
        .filter_map(|name| shared_data(name)),
    );
    if recordings.len() == 1 {
        eprintln!("../shared/data is not beside this checkout: the bundled recording only");
    }
    let reports = eval_json(&recordings, "paper");
    assert_eq!(reports.len(), recordings.len());
    let total: usize = reports
        .iter()
        .map(|r| r["estimates"].as_array().expect("estimates").len())
        .sum();
    let prefix = unique_prefix("chain-vs-eval");
    let mut echo = start_echo(&prefix, total);
    let mut estimator = start_estimator(&prefix, &["--method", "paper"]);
    for (dir, report) in recordings.iter().zip(&reports) {
        let expected = report["estimates"].as_array().expect("estimates");
        let mut replay = replay_all_at_5_hz(&prefix, dir);
        let published = read_json_lines(&mut echo, expected.len(), 120.0);
        replay.assert_exits_zero_within(Duration::from_secs(10));
        assert_eq!(
            published.len(),
            expected.len(),
            "{}: one estimate per frame
{}",
            dir.display(),
            estimator.diagnostics()
        );
        for (e, x) in published.iter().zip(expected) {
            let what = format!(
                "{}: published {e}
slope-eval {x}",
                dir.display()
            );
            assert_eq!(e["frame"], x["index"], "{what}");
            assert_eq!(e["status"], x["status"], "{what}");
            for key in ["slope_deg", "confidence"] {
                let (found, wanted) = (e[key].as_f64(), x[key].as_f64());
                match (found, wanted) {
                    (Some(found), Some(wanted)) => {
                        assert!((found - wanted).abs() <= 1e-6, "{key}: {what}")
                    }
                    (found, wanted) => assert_eq!(found, wanted, "{key}: {what}"),
                }
            }
        }
    }
    echo.assert_exits_zero_within(Duration::from_secs(5));
    estimator.signal(Signal::SIGTERM);
    estimator.assert_exits_zero_within(Duration::from_secs(1));
    let switches: Vec<&String> = estimator
        .stderr_lines()
        .iter()
        .filter(|l| l.contains("clouds from a new sensor"))
        .collect();
    assert_eq!(
        switches.len(),
        recordings.len(),
        "one switch per recording, none per frame: {switches:#?}"
    );
    if recordings.iter().any(|r| r.ends_with("kinect1-office")) {
        assert!(
            switches.iter().any(|l| l.contains("kinect1")),
            "{switches:#?}"
        );
    }
}

#[test]
fn a_missing_recording_is_a_clear_error_and_a_nonzero_exit() {
    let prefix = unique_prefix("bad-recording");
    let missing = std::env::temp_dir().join(format!("{prefix}-does-not-exist"));
    let mut replay = Proc::spawn(
        "slope-replay",
        [
            missing.to_str().expect("utf-8 path"),
            "--service-prefix",
            &prefix,
        ],
    );
    let status = replay.wait_exit(deadline(10.0)).expect("replay exits");
    assert!(!status.success(), "replay of a missing recording succeeded");
    let stderr = replay.stderr_lines().join("\n");
    assert!(stderr.contains("recording.toml"), "unclear error: {stderr}");
    assert!(!stderr.contains("panicked"), "replay panicked: {stderr}");
}

#[test]
fn demo_runs_the_chain_and_summarises_against_truth() {
    let mut demo = Proc::spawn(
        "slope-demo",
        [
            "--recording",
            recording("ramp16-clean").to_str().expect("utf-8 path"),
            "--rate",
            "5",
        ],
    );
    let until = deadline(90.0);
    let mut lines = Vec::new();
    while let Some(line) = demo.stdout_line(until) {
        lines.push(line);
    }
    let status = demo.wait_exit(deadline(5.0)).expect("demo exits");
    let diagnostics = demo.diagnostics();
    assert!(status.success(), "demo failed: {status}\n{diagnostics}");
    let summary = lines
        .iter()
        .find(|l| l.starts_with("summary:"))
        .unwrap_or_else(|| panic!("no summary in {lines:#?}"));
    let frame_lines = lines.iter().filter(|l| l.starts_with("frame")).count();
    assert_eq!(frame_lines, 10, "one line per frame: {lines:#?}");
    assert!(
        summary.starts_with("summary: 10 estimates of a 10-frame recording ("),
        "{summary}"
    );
    let error: f64 = summary
        .split("|error| ")
        .nth(1)
        .and_then(|s| s.split('°').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no error in {summary}"));
    assert!(error <= 1.0, "{summary}");
}
