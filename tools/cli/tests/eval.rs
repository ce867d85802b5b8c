//! `slope-eval` end to end: the real binary on small analytic recordings
//! written here (flat ground and a ramp, ray-cast pixel by pixel), checked
//! against the exact geometry and against the numbers it reports itself.

use std::collections::BTreeSet;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;
use slope_sensor::recording::{
    DepthImage, DepthInfo, MountInfo, RecordingMeta, RecordingWriter, TruthInfo,
};

const EVAL: &str = env!("CARGO_BIN_EXE_slope-eval");

// A Kinect v2-like camera 0.6 m above flat ground, pitched 20° down.
const WIDTH: u32 = 512;
const HEIGHT: u32 = 424;
const FX: f64 = 365.0;
const CX: f64 = 255.5;
const CY: f64 = 211.5;
const HEIGHT_M: f64 = 0.6;
const PITCH_DEG: f64 = -20.0;
/// The ramp's foot line, metres ahead along the ground.
const FOOT_M: f64 = 1.5;
/// The ramp's length along its surface.
const RAMP_LENGTH_M: f64 = 3.0;
const MAX_RANGE_M: f64 = 8.0;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Surface {
    Ground,
    Ramp,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [s * a[0], s * a[1], s * a[2]]
}

fn lin(a: [f64; 3], s: f64, b: [f64; 3], t: f64) -> [f64; 3] {
    [
        s * a[0] + t * b[0],
        s * a[1] + t * b[1],
        s * a[2] + t * b[2],
    ]
}

/// What pixel (u, v) sees, and its depth along the optical axis: the ray
/// `t * ((u - cx) / fx, (v - cy) / fy, 1)` against the ground (before the
/// foot line) and the ramp (rising at `slope_deg` from the foot line).
fn ray_cast(u: u32, v: u32, slope_deg: f64) -> Option<(Surface, f64)> {
    let p = PITCH_DEG.to_radians();
    let up = [0.0, -p.cos(), p.sin()];
    let forward = [0.0, p.sin(), p.cos()];
    let (st, ct) = slope_deg.to_radians().sin_cos();
    let ray = [(f64::from(u) - CX) / FX, (f64::from(v) - CY) / FX, 1.0];

    let mut hits = Vec::new();
    let down = dot(up, ray);
    if down < 0.0 {
        let t = -HEIGHT_M / down;
        if dot(forward, scale(ray, t)) < FOOT_M {
            hits.push((Surface::Ground, t));
        }
    }
    let foot = lin(forward, FOOT_M, up, -HEIGHT_M);
    let normal = lin(up, ct, forward, -st);
    let uphill = lin(forward, ct, up, st);
    let facing = dot(normal, ray);
    if facing != 0.0 {
        let t = dot(normal, foot) / facing;
        let along = dot(uphill, lin(ray, t, foot, -1.0));
        if t > 0.0 && (0.0..=RAMP_LENGTH_M).contains(&along) {
            hits.push((Surface::Ramp, t));
        }
    }
    hits.into_iter()
        .filter(|(_, t)| *t <= MAX_RANGE_M)
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

fn depth_image(slope_deg: f64) -> DepthImage {
    let mut image = DepthImage::new(WIDTH, HEIGHT);
    for v in 0..HEIGHT {
        for u in 0..WIDTH {
            if let Some((_, z)) = ray_cast(u, v, slope_deg) {
                image.data[(v * WIDTH + u) as usize] = (z * 1000.0).round() as u16;
            }
        }
    }
    image
}

/// Ground truth of a test recording.
enum Truth {
    None,
    Recording(f64),
    PerFrame,
}

/// Writes a recording of one frame per slope into `dir`.
fn write_recording(dir: &Path, slopes_deg: &[f64], truth: Truth) -> PathBuf {
    let meta = RecordingMeta {
        sensor: "analytic".into(),
        depth: DepthInfo {
            width: WIDTH,
            height: HEIGHT,
            unit_m: 0.001,
            fx: FX,
            fy: FX,
            cx: CX,
            cy: CY,
        },
        mount: MountInfo {
            height_m: Some(HEIGHT_M),
            pitch_deg: Some(PITCH_DEG),
            roll_deg: Some(0.0),
        },
        truth: TruthInfo {
            slope_deg: match truth {
                Truth::Recording(t) => Some(t),
                _ => None,
            },
        },
    };
    let per_frame = matches!(truth, Truth::PerFrame);
    let mut writer = RecordingWriter::create(dir, &meta, per_frame).unwrap();
    for (i, &slope) in slopes_deg.iter().enumerate() {
        let stamp = i as u64 * 33_333_333;
        let truth = per_frame.then_some(slope);
        writer
            .write_frame(stamp, &depth_image(slope), None, truth)
            .unwrap();
    }
    writer.finish().unwrap()
}

struct Output {
    success: bool,
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

fn eval(args: &[&str]) -> Output {
    let output = Command::new(EVAL)
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .unwrap_or_else(|e| panic!("cannot run {EVAL}: {e}"));
    Output {
        success: output.status.success(),
        code: output.status.code(),
        stdout: String::from_utf8_lossy(&output.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
    }
}

fn json_lines(stdout: &str) -> Vec<Value> {
    stdout
        .lines()
        .map(|line| serde_json::from_str(line).unwrap_or_else(|e| panic!("{e}: {line}")))
        .collect()
}

fn keys(value: &Value) -> BTreeSet<&str> {
    value
        .as_object()
        .unwrap_or_else(|| panic!("not an object: {value}"))
        .keys()
        .map(String::as_str)
        .collect()
}

fn set(names: &[&'static str]) -> BTreeSet<&'static str> {
    names.iter().copied().collect()
}

fn median(mut values: Vec<f64>) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    Some(if n.is_multiple_of(2) {
        (values[n / 2 - 1] + values[n / 2]) / 2.0
    } else {
        values[n / 2]
    })
}

fn num(value: &Value) -> f64 {
    value
        .as_f64()
        .unwrap_or_else(|| panic!("not a number: {value}"))
}

/// Equal but for the last bits: serde_json's parser (without its
/// `float_roundtrip` feature) may be one ulp off the printed value.
fn assert_close(found: Option<f64>, expected: Option<f64>) {
    match (found, expected) {
        (Some(f), Some(e)) => assert!((f - e).abs() <= 1e-12 * e.abs().max(1.0), "{f} != {e}"),
        _ => assert_eq!(found, expected),
    }
}

fn path_str(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// A plane `[a, b, c, d]`: a unit normal and the camera on its positive
/// side (`d`, the camera's distance to the plane, > 0).
fn check_plane(plane: &Value, estimate: &Value) -> [f64; 4] {
    let c: Vec<f64> = plane
        .as_array()
        .unwrap_or_else(|| panic!("plane not an array: {estimate}"))
        .iter()
        .map(num)
        .collect();
    let c: [f64; 4] = c.try_into().unwrap_or_else(|_| panic!("{estimate}"));
    let norm = dot([c[0], c[1], c[2]], [c[0], c[1], c[2]]).sqrt();
    assert!((norm - 1.0).abs() < 1e-9, "|n| = {norm}: {estimate}");
    assert!(c[3] > 0.0, "d <= 0: {estimate}");
    c
}

/// The planes, confidence and track of an estimate: present and sane for
/// a frame the estimator ran on, `null` for one it could not read.
fn check_details(estimate: &Value) {
    if estimate["ms"].is_null() {
        for key in [
            "ground_plane",
            "inclined_plane",
            "ground_inliers",
            "ground_rms_m",
            "inclined_area_m2",
            "confidence",
            "confidence_reasons",
            "ground_from_mount",
            "tracked",
            "surfaces",
        ] {
            assert!(estimate[key].is_null(), "{key}: {estimate}");
        }
        return;
    }
    let confidence = num(&estimate["confidence"]);
    assert!((0.0..=1.0).contains(&confidence), "{estimate}");
    let known: Vec<&str> = slope_ipc_types::confidence::ALL
        .iter()
        .map(|(_, name)| *name)
        .collect();
    for reason in estimate["confidence_reasons"].as_array().unwrap() {
        let reason = reason.as_str().unwrap();
        assert!(known.contains(&reason), "{reason}: {estimate}");
    }
    if estimate["status"] != "ok" {
        assert_eq!(confidence, 0.0, "{estimate}");
    }
    let from_mount = estimate["ground_from_mount"].as_bool().unwrap();
    for (plane, present) in [
        ("ground", !from_mount && estimate["status"] == "ok"),
        ("inclined", estimate["status"] == "ok"),
    ] {
        let coefficients = &estimate[format!("{plane}_plane").as_str()];
        if coefficients.is_null() {
            assert!(!present, "no {plane} plane: {estimate}");
            for key in ["inliers", "rms_m", "area_m2"] {
                let key = format!("{plane}_{key}");
                assert!(estimate[key.as_str()].is_null(), "{key}: {estimate}");
            }
            continue;
        }
        check_plane(coefficients, estimate);
        let inliers = estimate[format!("{plane}_inliers").as_str()]
            .as_u64()
            .unwrap();
        assert!(inliers > 0, "{estimate}");
        let rms = num(&estimate[format!("{plane}_rms_m").as_str()]);
        assert!((0.0..0.1).contains(&rms), "{plane} rms {rms}: {estimate}");
        let area = num(&estimate[format!("{plane}_area_m2").as_str()]);
        assert!(
            area > 0.0 && area.is_finite(),
            "{plane} area {area}: {estimate}"
        );
    }
    let tracked = &estimate["tracked"];
    if !tracked.is_null() {
        assert_eq!(
            keys(tracked),
            set(&["slope_deg", "std_deg", "frames", "accepted"]),
            "{estimate}"
        );
        assert!(tracked["accepted"].is_boolean(), "{estimate}");
        // Frames accepted since the track (re)started: at most the frames
        // of this recording so far.
        let frames = tracked["frames"].as_u64().unwrap();
        let index = estimate["index"].as_u64().unwrap();
        assert!(frames <= index + 1, "{estimate}");
        if !tracked["std_deg"].is_null() {
            assert!(num(&tracked["std_deg"]) >= 0.0, "{estimate}");
        }
    }
}

/// Checks the keys of a report and that its summary follows from its
/// estimates; returns the summary.
fn check_report(report: &Value, truth: Option<f64>) -> &Value {
    assert_eq!(
        keys(report),
        set(&["recording", "method", "truth_deg", "estimates", "summary"])
    );
    let estimates = report["estimates"].as_array().unwrap();
    for estimate in estimates {
        assert_eq!(
            keys(estimate),
            set(&[
                "index",
                "status",
                "slope_deg",
                "std_deg",
                "distance_m",
                "truth_deg",
                "ms",
                "error",
                "ground_plane",
                "inclined_plane",
                "ground_inliers",
                "inclined_inliers",
                "ground_rms_m",
                "inclined_rms_m",
                "ground_area_m2",
                "inclined_area_m2",
                "ground_seen_to_m",
                "confidence",
                "confidence_reasons",
                "ground_from_mount",
                "tracked",
                "surfaces"
            ]),
            "{estimate}"
        );
        check_details(estimate);
    }
    let summary = &report["summary"];
    assert_eq!(
        keys(summary),
        set(&[
            "frames",
            "ok_frames",
            "low_confidence_frames",
            "median_slope_deg",
            "median_abs_slope_deg",
            "abs_error_deg",
            "median_frame_error_deg",
            "median_ms",
            "median_stage_ms",
            "not_ok"
        ])
    );
    let ok: Vec<&Value> = estimates.iter().filter(|e| e["status"] == "ok").collect();
    assert_eq!(summary["frames"], estimates.len());
    assert_eq!(summary["ok_frames"], ok.len());
    let low_confidence = ok.iter().filter(|e| num(&e["confidence"]) < 0.5).count();
    assert_eq!(summary["low_confidence_frames"], low_confidence);
    let slopes: Vec<f64> = ok.iter().map(|e| num(&e["slope_deg"])).collect();
    let median_slope = median(slopes.clone());
    let median_abs = median(slopes.iter().map(|s| s.abs()).collect());
    assert_close(summary["median_slope_deg"].as_f64(), median_slope);
    assert_close(summary["median_abs_slope_deg"].as_f64(), median_abs);
    let totals: Vec<f64> = estimates
        .iter()
        .filter(|e| !e["ms"].is_null())
        .map(|e| num(&e["ms"]["total"]))
        .collect();
    assert_close(summary["median_ms"].as_f64(), median(totals));
    for estimate in estimates.iter().filter(|e| !e["ms"].is_null()) {
        // Stages are laps of one clock: they add up to at most the total.
        let ms = estimate["ms"].as_object().unwrap();
        let stages: f64 = ms
            .iter()
            .filter(|(k, _)| *k != "total")
            .map(|(_, v)| num(v))
            .sum();
        assert!(
            stages > 0.0 && stages <= num(&ms["total"]) + 1e-9,
            "{estimate}"
        );
    }
    match truth {
        Some(truth) => {
            assert_eq!(num(&report["truth_deg"]), truth);
            let error = (median_abs.unwrap() - truth).abs();
            assert_close(summary["abs_error_deg"].as_f64(), Some(error));
        }
        None => {
            assert!(report["truth_deg"].is_null());
            assert!(summary["abs_error_deg"].is_null());
            assert!(summary["median_frame_error_deg"].is_null());
            assert!(estimates.iter().all(|e| e["truth_deg"].is_null()));
        }
    }
    summary
}

#[test]
fn json_report_of_a_clean_ramp_matches_its_truth() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_recording(
        &dir.path().join("ramp20"),
        &[20.0; 3],
        Truth::Recording(20.0),
    );
    let out = eval(&[path_str(&rec), "--json", "--method", "paper"]);
    assert!(out.success, "{}", out.stderr);
    let reports = json_lines(&out.stdout);
    assert_eq!(reports.len(), 1);
    let report = &reports[0];
    assert_eq!(report["recording"], path_str(&rec));
    assert_eq!(report["method"], "paper");
    let summary = check_report(report, Some(20.0));
    assert_eq!(summary["frames"], 3);
    assert_eq!(summary["ok_frames"], 3);
    assert!(num(&summary["abs_error_deg"]) < 1.0, "{summary}");
    let estimates = report["estimates"].as_array().unwrap();
    let indices: Vec<u64> = estimates
        .iter()
        .map(|e| e["index"].as_u64().unwrap())
        .collect();
    assert_eq!(indices, [0, 1, 2]);
    for estimate in estimates {
        assert_eq!(num(&estimate["truth_deg"]), 20.0);
        assert!(estimate["error"].is_null());
        // The ramp rises ahead: positive slope; its foot is about 1.5 m
        // ahead, seen along the optical axis pitched 20° down.
        assert!(num(&estimate["slope_deg"]) > 0.0);
        let distance = num(&estimate["distance_m"]);
        assert!((1.0..3.0).contains(&distance), "{estimate}");
        for stage in ["outlier", "ransac", "normals", "kmeans", "cumulative"] {
            assert!(estimate["ms"][stage].is_number(), "{stage}: {estimate}");
        }
    }
}

#[test]
fn without_truth_the_error_is_null() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_recording(&dir.path().join("ramp"), &[15.0; 2], Truth::None);
    let out = eval(&[path_str(&rec), "--json", "--method", "tls", "-q"]);
    assert!(out.success, "{}", out.stderr);
    let reports = json_lines(&out.stdout);
    assert_eq!(reports.len(), 1);
    assert_eq!(reports[0]["method"], "tls");
    let summary = check_report(&reports[0], None);
    assert_eq!(summary["ok_frames"], 2);
    assert!((num(&summary["median_abs_slope_deg"]) - 15.0).abs() < 1.0);
}

#[test]
fn method_all_reports_the_three_methods() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_recording(&dir.path().join("ramp"), &[12.0; 2], Truth::Recording(12.0));
    let out = eval(&[path_str(&rec), "--json", "--method", "all", "--seed", "3"]);
    assert!(out.success, "{}", out.stderr);
    let reports = json_lines(&out.stdout);
    let methods: Vec<&str> = reports
        .iter()
        .map(|r| r["method"].as_str().unwrap())
        .collect();
    assert_eq!(methods, ["paper", "least-squares", "tls"]);
    for report in &reports {
        let summary = check_report(report, Some(12.0));
        assert!(num(&summary["abs_error_deg"]) < 1.0, "{report}");
    }
    // The baselines fit planes, not normals: no normals stage.
    assert!(reports[0]["summary"]["median_stage_ms"]["normals"].is_number());
    assert!(reports[2]["summary"]["median_stage_ms"]["normals"].is_null());
    assert!(reports[2]["summary"]["median_stage_ms"]["fit"].is_number());
}

#[test]
fn per_frame_truth_wins_and_the_recording_truth_is_its_median() {
    let dir = tempfile::tempdir().unwrap();
    let slopes = [14.0, 22.0, 18.0];
    let rec = write_recording(&dir.path().join("ramps"), &slopes, Truth::PerFrame);
    let out = eval(&[path_str(&rec), "--json", "--method", "least-squares"]);
    assert!(out.success, "{}", out.stderr);
    let reports = json_lines(&out.stdout);
    let summary = check_report(&reports[0], Some(18.0));
    let estimates = reports[0]["estimates"].as_array().unwrap();
    let mut errors = Vec::new();
    for (estimate, truth) in estimates.iter().zip(slopes) {
        assert_eq!(num(&estimate["truth_deg"]), truth);
        let error = (num(&estimate["slope_deg"]).abs() - truth).abs();
        assert!(error < 1.0, "{estimate}");
        errors.push(error);
    }
    assert_close(summary["median_frame_error_deg"].as_f64(), median(errors));
}

#[test]
fn a_recording_that_does_not_open_is_named_and_the_others_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let good = write_recording(&dir.path().join("good"), &[10.0], Truth::Recording(10.0));
    let missing = dir.path().join("no-such-recording");
    let out = eval(&[
        path_str(&missing),
        path_str(&good),
        "--json",
        "--method",
        "tls",
    ]);
    assert!(!out.success, "exit status 0 despite a missing recording");
    assert!(out.stderr.contains(path_str(&missing)), "{}", out.stderr);
    let reports = json_lines(&out.stdout);
    assert_eq!(reports.len(), 1);
    assert_eq!(reports[0]["recording"], path_str(&good));
    assert_eq!(reports[0]["summary"]["ok_frames"], 1);
}

/// `slope-eval DIR/*` (its own help's example) names the folder's files
/// too: they are skipped; a directory without recording.toml is an error
/// that says what a recording is.
#[test]
fn files_in_a_glob_are_skipped_and_other_directories_explained() {
    let dir = tempfile::tempdir().unwrap();
    let good = write_recording(&dir.path().join("good"), &[10.0], Truth::Recording(10.0));
    let readme = dir.path().join("README.md");
    std::fs::write(&readme, "# recordings\n").unwrap();
    let out = eval(&[
        path_str(&readme),
        path_str(&good),
        "--json",
        "--method",
        "tls",
    ]);
    assert!(out.success, "{}", out.stderr);
    assert!(out.stderr.contains("skipping a file"), "{}", out.stderr);
    assert_eq!(json_lines(&out.stdout).len(), 1);
    // Only files, no directory: nothing was evaluated, and that is an
    // error (it was a warning and status 0).
    let frames_csv = good.join("frames.csv");
    let (render, plot) = (dir.path().join("render"), dir.path().join("plot"));
    let out = eval(&[
        path_str(&frames_csv),
        path_str(&readme),
        "--render",
        path_str(&render),
        "--plot",
        path_str(&plot),
    ]);
    assert_eq!(out.code, Some(1), "{}", out.stderr);
    // Nothing to write: no output directory left behind.
    assert!(!render.exists() && !plot.exists());
    assert!(out.stdout.is_empty(), "{}", out.stdout);
    assert!(
        out.stderr.contains("no recording directory was given")
            && out.stderr.contains(path_str(&frames_csv)),
        "{}",
        out.stderr
    );
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let out = eval(&[path_str(&empty), "--method", "tls"]);
    assert!(!out.success);
    assert!(
        out.stderr.contains("not a recording directory"),
        "{}",
        out.stderr
    );
}

/// A recording whose `[depth]` is a typing error (100000 x 100000): its
/// frames.csv and images are never reached.
fn write_huge_recording(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let toml = std::fs::read_to_string(bundled_ramp16().join("recording.toml")).unwrap();
    let toml = toml
        .replace("width = 512", "width = 100000")
        .replace("height = 424", "height = 100000");
    assert!(toml.contains("height = 100000"), "{toml}");
    std::fs::write(dir.join("recording.toml"), toml).unwrap();
    std::fs::write(
        dir.join("frames.csv"),
        "index,timestamp_ns,depth,color\n0,0,depth/000000.png,\n1,1,depth/000001.png,\n",
    )
    .unwrap();
    dir.to_path_buf()
}

/// Before the check, the cloud buffer of such a recording was allocated
/// (160 GB) and the program aborted (status 134).
#[test]
fn a_frame_size_beyond_the_limit_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let huge = write_huge_recording(&dir.path().join("huge"));
    let out = eval(&["--max-frames", "2", path_str(&huge)]);
    assert_eq!(out.code, Some(1), "{}", out.stderr);
    for part in [
        "recording.toml",
        "100000 x 100000",
        "10000000000 points",
        "limit is 1048576",
        "--max-points",
    ] {
        assert!(out.stderr.contains(part), "{part}: {}", out.stderr);
    }
    // The limit is a flag: raised, the size passes the check (and the
    // missing images are then bad frames).
    let small = write_recording(&dir.path().join("small"), &[10.0], Truth::None);
    let out = eval(&[path_str(&small), "--max-points", "1000"]);
    assert!(!out.success);
    assert!(out.stderr.contains("512 x 424"), "{}", out.stderr);
}

/// A recording whose frames.csv has its header only is an error, as for
/// slope-replay (it was a row of zeros and status 0); the other recordings
/// are still evaluated.
#[test]
fn a_recording_without_frames_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let empty = write_recording(&dir.path().join("empty"), &[], Truth::None);
    let out = eval(&[path_str(&empty)]);
    assert_eq!(out.code, Some(1), "{}{}", out.stdout, out.stderr);
    assert!(out.stdout.is_empty(), "{}", out.stdout);
    let expected = format!(
        "cannot evaluate {}: its frames.csv lists no frames",
        path_str(&empty)
    );
    assert!(out.stderr.contains(&expected), "{}", out.stderr);
    let good = write_recording(&dir.path().join("good"), &[10.0], Truth::Recording(10.0));
    let out = eval(&[
        path_str(&empty),
        path_str(&good),
        "--json",
        "--method",
        "tls",
    ]);
    assert_eq!(out.code, Some(1), "{}", out.stderr);
    assert!(out.stderr.contains(&expected), "{}", out.stderr);
    let reports = json_lines(&out.stdout);
    assert_eq!(reports.len(), 1);
    assert_eq!(reports[0]["recording"], path_str(&good));
}

#[test]
fn a_bad_frame_is_reported_and_the_others_evaluated() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_recording(&dir.path().join("ramp"), &[16.0; 3], Truth::Recording(16.0));
    std::fs::write(rec.join("depth/000001.png"), b"not a png").unwrap();
    let out = eval(&[path_str(&rec), "--json", "--method", "tls"]);
    assert!(out.success, "{}", out.stderr);
    let reports = json_lines(&out.stdout);
    let summary = check_report(&reports[0], Some(16.0));
    assert_eq!(summary["frames"], 3);
    assert_eq!(summary["ok_frames"], 2);
    assert_eq!(summary["not_ok"]["bad_frame"], 1);
    let bad = &reports[0]["estimates"][1];
    assert_eq!(bad["status"], "bad_frame");
    assert!(bad["slope_deg"].is_null() && bad["ms"].is_null());
    let error = bad["error"].as_str().unwrap();
    assert!(error.contains("000001.png"), "{error}");
    assert!(out.stderr.contains("000001.png"), "{}", out.stderr);
    // No frame readable: still reported, and a failure (it was status 0).
    for k in [0, 2] {
        std::fs::write(rec.join(format!("depth/00000{k}.png")), b"not a png").unwrap();
    }
    let out = eval(&[path_str(&rec), "--json", "--method", "tls"]);
    assert_eq!(out.code, Some(1), "{}", out.stderr);
    let reports = json_lines(&out.stdout);
    assert_eq!(reports[0]["summary"]["not_ok"]["bad_frame"], 3);
    assert!(
        out.stderr
            .contains("none of its 3 frame(s) could be read (the first: ")
            && out.stderr.contains("000000.png"),
        "{}",
        out.stderr
    );
}

/// A bad frame's error gives its cause: what the decoder or the file
/// system said (it stopped at "cannot decode X" / "cannot read X"), in the
/// JSON, the table and the warning.
#[test]
fn a_bad_frame_error_names_its_cause() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_recording(&dir.path().join("ramp"), &[16.0; 3], Truth::Recording(16.0));
    let truncated = rec.join("depth/000001.png");
    let bytes = std::fs::read(&truncated).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    std::fs::remove_file(rec.join("depth/000002.png")).unwrap();
    let decode = format!(
        "cannot decode {}: unexpected end of file",
        path_str(&truncated)
    );
    let read = format!(
        "cannot read {}/depth/000002.png: No such file or directory",
        path_str(&rec)
    );
    let out = eval(&[path_str(&rec), "--json", "--method", "tls"]);
    assert!(out.success, "{}", out.stderr);
    let reports = json_lines(&out.stdout);
    let error = |k: usize| {
        reports[0]["estimates"][k]["error"]
            .as_str()
            .unwrap()
            .to_owned()
    };
    assert!(error(1).ends_with(&decode), "{}", error(1));
    assert!(error(2).contains(&read), "{}", error(2));
    assert!(
        out.stderr.contains(&decode) && out.stderr.contains(&read),
        "{}",
        out.stderr
    );
    let out = eval(&[path_str(&rec), "--method", "tls"]);
    assert!(out.success, "{}", out.stderr);
    let first_bad = format!("first bad frame (1): frames.csv line 3: {decode}\n");
    assert!(out.stdout.contains(&first_bad), "{}", out.stdout);
}

#[test]
fn the_table_has_a_row_per_method_and_the_stage_breakdown() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_recording(&dir.path().join("ramp"), &[16.0; 3], Truth::Recording(16.0));
    let out = eval(&[path_str(&rec), "--method", "all", "--max-frames", "2"]);
    assert!(out.success, "{}", out.stderr);
    let lines: Vec<&str> = out.stdout.lines().collect();
    assert!(lines[0].starts_with("recording") && lines[0].contains("median ms"));
    for method in ["paper", "least-squares", "tls"] {
        let row = lines
            .iter()
            .position(|l| l.starts_with(path_str(&rec)) && l.contains(method))
            .unwrap_or_else(|| panic!("no row for {method}: {}", out.stdout));
        // frames = 2 (--max-frames), ok = 2, truth 16.00°.
        let cells: Vec<&str> = lines[row].split_whitespace().collect();
        assert_eq!(&cells[2..4], ["2", "2"], "{}", lines[row]);
        assert_eq!(cells[5], "16.00°", "{}", lines[row]);
        assert!(lines[row + 1].contains("stages (median ms): outlier"));
    }
}

/// Decodes an 8-bit RGB PNG.
fn read_rgb(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let pixels = buf[..info.buffer_size()]
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    (info.width, info.height, pixels)
}

/// Overlay pixels are drawn at this many times the depth resolution.
const OVERLAY_SCALE: u32 = 2;

#[test]
fn the_overlay_colours_the_ground_red_and_the_ramp_blue() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_recording(&dir.path().join("ramp"), &[20.0; 3], Truth::Recording(20.0));
    let out_dir = dir.path().join("pictures");
    let out = eval(&[
        path_str(&rec),
        "--method",
        "all",
        "--render",
        path_str(&out_dir),
        "-q",
    ]);
    assert!(out.success, "{}", out.stderr);
    for method in ["paper", "least-squares", "tls"] {
        // The middle of three frames: the picture at twice the depth
        // resolution, the caption under it.
        let path = out_dir.join(format!("ramp-{method}-frame000001.png"));
        let (width, height, pixels) = read_rgb(&path);
        assert_eq!(width, OVERLAY_SCALE * WIDTH);
        assert!(height > OVERLAY_SCALE * HEIGHT + 40, "{height}");
        // Every pixel coloured after the role of the surface RANSAC gave it
        // to (ground red, ramp blue); labels, normal dots, the road's
        // outline and the corridor's lines lie on their surfaces. The ground is near and every pixel
        // of it an inlier; the far end of the ramp (beyond 5 m, where the
        // pixels are sparse) is partly dropped as outliers and stays grey,
        // but no pixel of either surface takes the other's colour.
        let (mut ground, mut ramp, mut ground_red, mut ramp_blue, mut empty_black) =
            (0, 0, 0, 0, 0);
        let mut crossed = 0;
        let mut empty = 0;
        for v in 0..HEIGHT {
            for u in 0..WIDTH {
                let i = (v * OVERLAY_SCALE * width + u * OVERLAY_SCALE) as usize;
                let [r, g, b] = pixels[i];
                // The normal dots (green, yellow, black rims), the road's
                // outline (magenta), the corridor (cyan) and the white label
                // text lie on their surfaces too.
                let marks = [
                    [40, 230, 60],
                    [255, 220, 0],
                    [0, 0, 0],
                    [255, 0, 255],
                    [0, 255, 255],
                ];
                let mark = marks.contains(&[r, g, b]) || (r > 200 && g > 200 && b > 200);
                let (r, g, b) = (i32::from(r), i32::from(g), i32::from(b));
                let red = (r > g + 60 && g == b) || mark;
                let blue = (b > r + 60 && b > g + 60) || mark;
                match ray_cast(u, v, 20.0) {
                    Some((Surface::Ground, _)) => {
                        ground += 1;
                        ground_red += usize::from(red);
                        crossed += usize::from(blue && !mark);
                    }
                    Some((Surface::Ramp, _)) => {
                        ramp += 1;
                        ramp_blue += usize::from(blue);
                        crossed += usize::from(red && !mark);
                    }
                    None => {
                        empty += 1;
                        empty_black += usize::from([r, g, b] == [0, 0, 0]);
                    }
                }
            }
        }
        assert!(ground > 10_000 && ramp > 10_000, "{ground} {ramp}");
        assert!(
            ground_red as f64 > 0.97 * ground as f64,
            "{method}: {ground_red}/{ground}"
        );
        assert!(
            ramp_blue as f64 > 0.8 * ramp as f64,
            "{method}: {ramp_blue}/{ramp}"
        );
        // At most about a row of pixels along the junction line.
        assert!(
            crossed < 600,
            "{method}: {crossed} pixels in the other plane's colour"
        );
        assert!(
            empty_black as f64 >= 0.98 * empty as f64,
            "{empty_black}/{empty}"
        );
        // The paper method's sampled normals are drawn as green dots (the
        // caption's legend has a green square too: only the picture counts).
        let picture = (OVERLAY_SCALE * HEIGHT * width) as usize;
        let green = pixels[..picture]
            .iter()
            .filter(|p| **p == [40, 230, 60])
            .count();
        assert_eq!(
            method == "paper",
            green > 100,
            "{method}: {green} green pixels"
        );
    }
}

#[test]
fn render_frame_picks_the_frame_and_an_unknown_one_fails() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_recording(&dir.path().join("ramp"), &[20.0; 3], Truth::Recording(20.0));
    let out_dir = dir.path().join("pictures");
    let pictures = path_str(&out_dir);
    let out = eval(&[
        path_str(&rec),
        "--method",
        "tls",
        "--render",
        pictures,
        "--render-frame",
        "2",
    ]);
    assert!(out.success, "{}", out.stderr);
    // The chosen frame's picture and nothing else.
    let written = |dir: &Path| -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .expect("the render directory")
            .map(|entry| {
                entry
                    .expect("an entry")
                    .file_name()
                    .into_string()
                    .expect("utf-8")
            })
            .collect();
        names.sort();
        names
    };
    assert_eq!(written(&out_dir), ["ramp-tls-frame000002.png"]);
    assert!(out_dir.join("ramp-tls-frame000002.png").is_file());
    let out = eval(&[
        path_str(&rec),
        "--method",
        "tls",
        "--render",
        pictures,
        "--render-frame",
        "7",
    ]);
    assert!(!out.success);
    assert!(out.stderr.contains("frame 7"), "{}", out.stderr);
    assert!(out.stderr.contains(path_str(&rec)), "{}", out.stderr);
}

/// A requested frame whose depth image cannot be read is an error naming
/// the frame and why (it was: an empty render directory and status 0).
#[test]
fn render_frame_of_a_bad_frame_fails() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_recording(&dir.path().join("ramp"), &[20.0; 3], Truth::Recording(20.0));
    std::fs::write(rec.join("depth/000001.png"), b"not a png").unwrap();
    let out_dir = dir.path().join("pictures");
    let out = eval(&[
        path_str(&rec),
        "--method",
        "tls",
        "--render",
        path_str(&out_dir),
        "--render-frame",
        "1",
    ]);
    assert_eq!(out.code, Some(1), "{}", out.stderr);
    let expected = format!(
        "cannot render frame 1 of {}: it is a bad frame",
        path_str(&rec)
    );
    assert!(out.stderr.contains(&expected), "{}", out.stderr);
    assert!(out.stderr.contains("000001.png"), "{}", out.stderr);
}

/// --render-frame and --render-every only choose what --render and
/// --export-ply write: alone they are a usage error (they were ignored).
#[test]
fn render_choices_without_an_output_are_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_recording(&dir.path().join("ramp"), &[20.0], Truth::None);
    for flags in [["--render-every", "2"], ["--render-frame", "0"]] {
        let mut args = vec![path_str(&rec)];
        args.extend(flags);
        let out = eval(&args);
        assert_eq!(out.code, Some(2), "{flags:?}: {}", out.stderr);
        assert!(out.stdout.is_empty(), "{}", out.stdout);
        assert!(
            out.stderr.contains("--render <DIR>") && out.stderr.contains("--export-ply <DIR>"),
            "{flags:?}: {}",
            out.stderr
        );
    }
    let ply = dir.path().join("ply");
    let out = eval(&[
        path_str(&rec),
        "--render-frame",
        "0",
        "--export-ply",
        path_str(&ply),
    ]);
    assert!(out.success, "{}", out.stderr);
}

#[test]
fn bad_arguments_are_refused() {
    let out = eval(&["somewhere", "--method", "magic"]);
    assert!(!out.success);
    assert!(out.stderr.contains("tls or all"), "{}", out.stderr);
    let out = eval(&[]);
    assert!(!out.success);
    assert!(out.stderr.contains("RECORDING"), "{}", out.stderr);
    let out = eval(&["--help"]);
    assert!(out.success);
    assert!(out.stdout.contains("Examples:") && out.stdout.contains("|slope_deg|"));
}

/// The bundled noisy 16° ramp (30 frames, camera 0.5 m above the ground,
/// pitched 20° down).
fn bundled_ramp16() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/recordings/ramp16")
}

/// Angle between two unit normals, degrees.
fn angle_deg(a: [f64; 4], b: [f64; 4]) -> f64 {
    let cos = dot([a[0], a[1], a[2]], [b[0], b[1], b[2]]);
    cos.clamp(-1.0, 1.0).acos().to_degrees()
}

#[test]
fn the_bundled_ramp_reports_planes_quality_confidence_and_track() {
    let rec = bundled_ramp16();
    let out = eval(&[path_str(&rec), "--json", "--method", "all", "-q"]);
    assert!(out.success, "{}", out.stderr);
    let reports = json_lines(&out.stdout);
    assert_eq!(reports.len(), 3);
    // The recording's mount: pitch -20°, roll 0.
    let p = (-20.0f64).to_radians();
    let up = [0.0, -p.cos(), p.sin(), 0.0];
    for report in &reports {
        let summary = check_report(report, Some(16.0));
        assert_eq!(summary["frames"], 30, "{summary}");
        let ok: Vec<&Value> = report["estimates"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|e| e["status"] == "ok")
            .collect();
        assert!(ok.len() >= 27, "{summary}");
        for estimate in ok {
            // The ground plane: the mount's (0.5 m below the camera, normal
            // the up vector of a 20° pitch), within the recording's jitter.
            assert_eq!(estimate["ground_from_mount"], false, "{estimate}");
            let ground = check_plane(&estimate["ground_plane"], estimate);
            let inclined = check_plane(&estimate["inclined_plane"], estimate);
            assert!((ground[3] - 0.5).abs() < 0.02, "{estimate}");
            assert!(angle_deg(ground, up) < 1.5, "{estimate}");
            // The planes meet at the ramp's 16°.
            assert!(
                (angle_deg(ground, inclined) - 16.0).abs() < 1.0,
                "{estimate}"
            );
            // The ramp covers more of the image than the ground before it.
            let inliers = |plane: &str| estimate[plane].as_u64().unwrap();
            assert!(inliers("inclined_inliers") > 10_000, "{estimate}");
            assert!(inliers("ground_inliers") > 10_000, "{estimate}");
            assert!(num(&estimate["inclined_area_m2"]) > 1.0, "{estimate}");
            // The ground ends at the ramp's foot line, 1.5 m ahead in the
            // recording's scene; its RANSAC band takes in the ramp's first
            // few centimetres (less than 3 cm rise there).
            let seen = num(&estimate["ground_seen_to_m"]);
            assert!((1.35..1.62).contains(&seen), "{estimate}");
            // Millimetre depth with Kinect noise: RMS of a few millimetres.
            assert!(num(&estimate["ground_rms_m"]) < 0.02, "{estimate}");
            assert!(num(&estimate["inclined_rms_m"]) < 0.02, "{estimate}");
            check_road(estimate);
        }
    }
}

/// The frame's surfaces: the ground and one road, a ramp in the corridor
/// joining the ground, whose RANSAC plane's slope is the estimate's within
/// 0.25° (the fit refines it: 0.02 to 0.09° apart on ramp16), at the
/// ground's end.
fn check_road(estimate: &Value) {
    let surfaces = estimate["surfaces"].as_array().unwrap();
    let roads: Vec<&Value> = surfaces.iter().filter(|s| s["road"] == true).collect();
    assert_eq!(roads.len(), 1, "{estimate}");
    let road = roads[0];
    assert_eq!(road["role"], "ramp", "{road}");
    assert_eq!(road["support"], "ground", "{road}");
    assert_eq!(
        (&road["in_corridor"], &road["joins_ground"]),
        (&Value::Bool(true), &Value::Bool(true))
    );
    let slope = num(&estimate["slope_deg"]);
    assert!(
        (num(&road["slope_deg"]) - slope).abs() < 0.25,
        "{slope}: {road}"
    );
    assert!((1.35..1.65).contains(&num(&road["distance_m"])), "{road}");
    assert!(surfaces.iter().any(|s| s["role"] == "ground"), "{estimate}");
    for s in surfaces {
        for key in [
            "inliers",
            "area_m2",
            "rms_m",
            "noise_ratio",
            "left_m",
            "right_m",
            "lowest_m",
            "highest_m",
            "far_m",
        ] {
            assert!(!s[key].is_null(), "{key}: {s}");
        }
    }
}

#[test]
fn each_recording_gets_fresh_estimators() {
    // The same recording twice: the second report must not continue the
    // first one's track (nor anything else an estimator keeps).
    let rec = bundled_ramp16();
    let out = eval(&[
        path_str(&rec),
        path_str(&rec),
        "--json",
        "--method",
        "least-squares",
        "--max-frames",
        "6",
        "-q",
    ]);
    assert!(out.success, "{}", out.stderr);
    let reports = json_lines(&out.stdout);
    assert_eq!(reports.len(), 2);
    let without_timings = |report: &Value| -> Vec<Value> {
        report["estimates"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| {
                let mut e = e.clone();
                e.as_object_mut().unwrap().remove("ms");
                e
            })
            .collect()
    };
    for report in &reports {
        check_report(report, Some(16.0));
    }
    assert_eq!(without_timings(&reports[0]), without_timings(&reports[1]));
}
