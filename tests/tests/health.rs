//! The health topic across real processes: slope-replay -> slope-estimator,
//! and `slope-echo --health --json` reading the estimator's reports: the
//! counts follow the frames, every stage of the paper method is timed, and
//! the rates and latencies are those of a running pipeline.

use serde_json::Value;
use slope_integration_tests::{deadline, replay_frames, unique_prefix, Proc};

fn number(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number: {v}"))
}

#[test]
fn the_estimator_reports_its_health_every_interval() {
    let prefix = unique_prefix("health");
    let _estimator = Proc::spawn(
        "slope-estimator",
        ["--service-prefix", &prefix, "--health-interval-s", "0.5"],
    )
    .assert_ready("estimator ready");
    let mut echo = Proc::spawn(
        "slope-echo",
        [
            "--health",
            "--json",
            "--service-prefix",
            &prefix,
            "--timeout-s",
            "120",
        ],
    )
    .assert_ready("subscribed to health reports");
    let frames = 12;
    let mut replay = replay_frames(&prefix, "ramp16", 10.0, frames, 1);
    replay.assert_exits_zero_within(std::time::Duration::from_secs(60));

    // Reports until one has seen every frame out.
    let until = deadline(30.0);
    let mut reports = Vec::new();
    let mut busy = None;
    while let Some(line) = echo.stdout_line(until) {
        let report: Value =
            serde_json::from_str(&line).unwrap_or_else(|e| panic!("invalid JSON {line:?}: {e}"));
        assert_eq!(report["component"], "estimator", "{report}");
        if number(&report, "rate_out_hz") > 0.0 && busy.is_none() {
            busy = Some(report.clone());
        }
        // Under load the estimator may supersede a frame: it counts as dropped.
        let accounted = number(&report, "frames_out") + number(&report, "frames_dropped");
        let done = accounted as u64 >= frames;
        reports.push(report);
        if done {
            break;
        }
    }
    let last = reports.last().expect("no health report arrived");
    let frames_out = number(last, "frames_out") as u64;
    let dropped = number(last, "frames_dropped") as u64;
    assert_eq!(number(last, "frames_in") as u64, frames, "{last}");
    assert_eq!(frames_out + dropped, frames, "{last}");
    assert!(frames_out >= frames / 2, "{last}");
    // Each report's rates are its window's frames over its window: the
    // frames counted since the report before (none before the first: the
    // replay started after the echo subscribed) over `window_ms`, to the
    // rounding of `window_ms` to whole milliseconds.
    let mut before = (0.0, 0.0);
    for report in &reports {
        let window_s = number(report, "window_ms") / 1e3;
        assert!(window_s > 0.0, "{report}");
        let counted = (number(report, "frames_in"), number(report, "frames_out"));
        for (key, frames_in_window) in [
            ("rate_in_hz", counted.0 - before.0),
            ("rate_out_hz", counted.1 - before.1),
        ] {
            let rate = number(report, key);
            assert!(
                (rate * window_s - frames_in_window).abs() < 0.02,
                "{key} {rate} over {window_s} s is not {frames_in_window} frames: {report}"
            );
        }
        before = counted;
    }
    assert_eq!(number(last, "errors"), 0.0, "{last}");
    assert!(last["last_error"].is_null(), "{last}");
    // Reports come every 0.5 s: uptimes increase by about that much.
    let uptimes: Vec<f64> = reports.iter().map(|r| number(r, "uptime_ms")).collect();
    for pair in uptimes.windows(2) {
        let step = pair[1] - pair[0];
        assert!((300.0..=1500.0).contains(&step), "uptimes {uptimes:?}");
    }

    // A report from while frames flowed: rates near the replay's 10 Hz,
    // every stage of the paper method timed, the stages within the total.
    let busy = busy.expect("no report while frames flowed");
    let rate = number(&busy, "rate_out_hz");
    assert!(rate > 2.0 && rate < 25.0, "{busy}");
    let stages = busy["stages"].as_array().expect("stages");
    let names: Vec<&str> = stages.iter().filter_map(|s| s["name"].as_str()).collect();
    for stage in ["outlier", "ransac", "normals", "kmeans", "total"] {
        assert!(names.contains(&stage), "{stage} missing from {names:?}");
    }
    let of = |name: &str| {
        stages
            .iter()
            .find(|s| s["name"] == name)
            .unwrap_or_else(|| panic!("{name}: {busy}"))
    };
    let total = of("total");
    for s in stages {
        assert!(number(s, "count") >= 1.0, "{s}");
        assert!(number(s, "median_ms") <= number(s, "p95_ms"), "{s}");
        assert!(number(s, "p95_ms") <= number(s, "max_ms"), "{s}");
        assert!(number(s, "max_ms") <= number(total, "max_ms") + 1e-9, "{s}");
    }
    let latency = &busy["latency"];
    assert!(
        number(latency, "median_ms") >= number(total, "median_ms") * 0.5,
        "{busy}"
    );
    assert!(number(latency, "max_ms") < 5_000.0, "{busy}");
}
