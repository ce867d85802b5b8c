//! The surfaces across real processes: slope-replay -> slope-estimator ->
//! `slope-echo --surfaces --json` beside `slope-echo --json`, each a
//! separate process under a service prefix of its own; what arrives is
//! checked against the estimates and against `slope-eval --json`.

use std::time::Duration;

use nix::sys::signal::Signal;
use serde_json::Value;
use slope_integration_tests::{
    eval_json, read_json_lines, recording, replay_all_at_5_hz, start_echo, start_estimator,
    unique_prefix, Proc,
};
use slope_sensor::recording::Recording;

/// Starts `slope-echo --surfaces --json` for `count` frames and waits until
/// it is subscribed.
fn start_surfaces_echo(prefix: &str, count: usize) -> Proc {
    let count = count.to_string();
    Proc::spawn(
        "slope-echo",
        [
            "--surfaces",
            "--json",
            "--service-prefix",
            prefix,
            "--count",
            &count,
            "--timeout-s",
            "120",
        ],
    )
    .assert_ready("subscribed to surfaces")
}

/// `found` equals `wanted`, numbers to 1e-6 (arrays and objects element by
/// element); the path names what differs.
fn assert_close(found: &Value, wanted: &Value, path: &str) {
    match (found, wanted) {
        (Value::Number(f), Value::Number(w)) => {
            let (f, w) = (f.as_f64().unwrap(), w.as_f64().unwrap());
            assert!((f - w).abs() <= 1e-6, "{path}: {f} vs {w}");
        }
        (Value::Array(f), Value::Array(w)) => {
            assert_eq!(f.len(), w.len(), "{path}: lengths");
            for (k, (f, w)) in f.iter().zip(w).enumerate() {
                assert_close(f, w, &format!("{path}[{k}]"));
            }
        }
        (Value::Object(f), Value::Object(w)) => {
            let keys = |o: &serde_json::Map<String, Value>| o.keys().cloned().collect::<Vec<_>>();
            assert_eq!(keys(f), keys(w), "{path}: keys");
            for (key, w) in w {
                assert_close(&f[key], w, &format!("{path}.{key}"));
            }
        }
        (f, w) => assert_eq!(f, w, "{path}"),
    }
}

#[test]
fn every_frame_s_surfaces_arrive_with_the_estimate_s_road_and_match_slope_eval() {
    let dir = recording("ramp16");
    let frames = Recording::open(&dir).expect("opens").frames().len();
    let report = eval_json(std::slice::from_ref(&dir), "paper").remove(0);
    let expected = report["estimates"].as_array().expect("estimates").clone();
    assert_eq!(expected.len(), frames);
    let prefix = unique_prefix("surfaces");

    let mut estimates_echo = start_echo(&prefix, frames);
    let mut surfaces_echo = start_surfaces_echo(&prefix, frames);
    let mut estimator = start_estimator(&prefix, &["--method", "paper"]);
    let mut replay = replay_all_at_5_hz(&prefix, &dir);

    let estimates = read_json_lines(&mut estimates_echo, frames, 60.0);
    let surfaces = read_json_lines(&mut surfaces_echo, frames, 60.0);
    assert_eq!(
        (estimates.len(), surfaces.len()),
        (frames, frames),
        "one estimate and one surfaces message per frame\n{}\n{}",
        estimator.diagnostics(),
        replay.diagnostics()
    );
    let indices = |lines: &[Value]| -> Vec<u64> {
        lines
            .iter()
            .map(|l| l["frame"].as_u64().expect("frame"))
            .collect()
    };
    assert_eq!(indices(&surfaces), indices(&estimates), "same frames");
    assert_eq!(
        indices(&surfaces),
        (0..frames as u64).collect::<Vec<_>>(),
        "in order"
    );
    let mut roads = 0;
    for ((s, e), x) in surfaces.iter().zip(&estimates).zip(&expected) {
        let what = format!("surfaces {s}\nestimate {e}\nslope-eval {x}");
        assert_eq!(s["status"], e["status"], "{what}");
        assert_eq!(
            (&s["timestamp_ns"], &s["source_stamp_ns"]),
            (&e["timestamp_ns"], &e["source_stamp_ns"]),
            "{what}"
        );
        assert_close(&s["surfaces"], &x["surfaces"], "surfaces");
        let marked: Vec<&Value> = s["surfaces"]
            .as_array()
            .expect("surfaces")
            .iter()
            .filter(|s| s["road"] == true)
            .collect();
        if e["status"] != "ok" {
            continue;
        }
        roads += 1;
        assert_eq!(marked.len(), 1, "{what}");
        let road = &s["surfaces"][s["road"].as_u64().expect("road index") as usize];
        assert_eq!(road, marked[0], "{what}");
        assert_eq!(road["role"], "ramp", "{what}");
        // The road's RANSAC plane, which the fit refines: 0.02 to 0.09°
        // apart on ramp16.
        let (found, wanted) = (road["slope_deg"].as_f64(), e["slope_deg"].as_f64());
        assert!(
            (found.expect("road slope") - wanted.expect("slope")).abs() < 0.25,
            "{what}"
        );
    }
    assert!(roads >= frames - 3, "{roads} of {frames} frames ok");

    estimates_echo.assert_exits_zero_within(Duration::from_secs(5));
    surfaces_echo.assert_exits_zero_within(Duration::from_secs(5));
    replay.assert_exits_zero_within(Duration::from_secs(10));
    estimator.signal(Signal::SIGTERM);
    estimator.assert_exits_zero_within(Duration::from_secs(1));
}
