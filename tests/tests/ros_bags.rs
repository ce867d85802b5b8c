//! ROS bags in and out, checked by an independent implementation of the
//! formats: the `rosbags` package from PyPI (pure Python), installed into
//! a venv once for this file's tests (`tests/python/ros_bags.py` drives it).
//!
//! - `slope-convert --format rosbag2`: rosbags reads every message with the
//!   schemas in the bag; depth, camera info, the mount on /tf_static and
//!   the estimates are the recording's and `slope-eval --json`'s, and
//!   `ros2/slope_msgs/msg/SlopeEstimate.msg` parses to the bag's schema.
//! - `slope-import` of bags that rosbags wrote from `ramp16` (ROS 1 16UC1,
//!   ROS 2 MCAP 32FC1, ROS 2 SQLite compressedDepth, each with camera info
//!   and /tf_static): the depth of the original to the millimetre, its
//!   intrinsics and mount, and the same `slope-eval` answers.
//! - Bad bags (cut short, an unsupported encoding, no camera info, empty
//!   images): a clear error, exit status 1.
//!
//! Without Python or PyPI the tests say why and skip, unless
//! `SLOPE_REQUIRE_PYTHON` (or `CI`) is set: then they fail.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Duration;

use serde_json::{json, Value};
use slope_integration_tests::python_venv::{make_venv, venv_or_skip};
use slope_integration_tests::{binary, recording, replay_frames, repo_root, unique_prefix, Proc};
use slope_ipc_types::layout;
use slope_sensor::recording::Recording;

/// Frames of ramp16 in each bag: enough for the tracker to matter.
const FRAMES: usize = 8;
/// Added to the recording's stamps (which start at 0): a bag's stamps are
/// since the Unix epoch.
const EPOCH_NS: u64 = 1_700_000_000_000_000_000;

/// A venv with `rosbags` (and numpy, its dependency), made once for all the
/// tests of this file (they run in parallel: two `python3 -m venv` into one
/// directory fail), or `None` (the test skips) when it cannot be made and
/// Python is optional.
fn rosbags_python() -> Option<PathBuf> {
    static VENV: std::sync::OnceLock<Result<PathBuf, String>> = std::sync::OnceLock::new();
    let made = VENV.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("rosbags-venv");
        make_venv(&dir, Some("rosbags"), &[OsStr::new("rosbags")])
    });
    venv_or_skip(made, "rosbags")
}

/// Runs `tests/python/ros_bags.py` with `args`; its stdout.
fn ros_bags(python: &Path, args: &[&Path]) -> String {
    let script = repo_root().join("tests/python/ros_bags.py");
    let out = Command::new(python)
        .arg(&script)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {}: {e}", python.display()));
    assert!(
        out.status.success(),
        "ros_bags.py {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8")
}

/// Runs one of our programs to its end.
fn run(name: &str, args: &[&std::ffi::OsStr]) -> Output {
    Command::new(binary(name))
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .unwrap_or_else(|e| panic!("cannot run {name}: {e}"))
}

fn run_ok(name: &str, args: &[&std::ffi::OsStr]) -> Output {
    let out = run(name, args);
    assert!(
        out.status.success(),
        "{name} {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// `slope-eval --json` of the first [`FRAMES`] frames of `dir`: its estimates.
fn eval_estimates(dir: &Path) -> Vec<Value> {
    let frames = FRAMES.to_string();
    let out = run_ok(
        "slope-eval",
        &[
            "--json".as_ref(),
            "--quiet".as_ref(),
            "--max-frames".as_ref(),
            frames.as_ref(),
            dir.as_os_str(),
        ],
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    let report: Value = serde_json::from_str(text.lines().next().expect("one line")).expect("JSON");
    let estimates = report["estimates"].as_array().expect("estimates").clone();
    assert_eq!(estimates.len(), FRAMES, "{report}");
    estimates
}

/// What the estimator answered, without the timings (and the truth, which
/// a bag does not carry).
fn answers(estimates: &[Value]) -> Vec<Value> {
    estimates
        .iter()
        .map(|e| {
            let mut e = e.clone();
            let object = e.as_object_mut().expect("object");
            object.remove("ms");
            object.remove("truth_deg");
            e
        })
        .collect()
}

fn depth_of(rec: &Recording, index: usize) -> Vec<u16> {
    rec.read_depth(&rec.frames()[index]).expect("depth").data
}

#[test]
fn rosbags_reads_every_message_of_a_converted_bag() {
    let Some(python) = rosbags_python() else {
        return;
    };
    let tmp = tempfile::tempdir().expect("temp dir");
    let source = recording("ramp16");
    let bag = tmp.path().join("ramp16-bag");
    let frames = FRAMES.to_string();
    run_ok(
        "slope-convert",
        &[
            source.as_os_str(),
            "-o".as_ref(),
            bag.as_os_str(),
            "--format".as_ref(),
            "rosbag2".as_ref(),
            "--max-frames".as_ref(),
            frames.as_ref(),
        ],
    );
    assert!(bag.join("metadata.yaml").is_file());
    assert!(bag.join("ramp16-bag_0.mcap").is_file());
    let msg_file = repo_root().join("ros2/slope_msgs/msg/SlopeEstimate.msg");
    let read: Value = serde_json::from_str(&ros_bags(
        &python,
        &["read".as_ref(), &bag, tmp.path(), &msg_file],
    ))
    .expect("JSON from ros_bags.py");

    let topics = &read["topics"];
    for (topic, ty, count) in [
        ("/slope/depth", "sensor_msgs/msg/Image", FRAMES),
        ("/slope/camera_info", "sensor_msgs/msg/CameraInfo", FRAMES),
        ("/slope/estimate", "slope_msgs/msg/SlopeEstimate", FRAMES),
        ("/tf_static", "tf2_msgs/msg/TFMessage", 1),
    ] {
        assert_eq!(topics[topic]["type"], ty, "{topics}");
        assert_eq!(topics[topic]["count"], count, "{topics}");
        assert_eq!(topics[topic]["encoding"], "cdr", "{topics}");
    }

    // Depth: the recording's, to the millimetre, at its stamps.
    let rec = Recording::open(&source).expect("ramp16");
    let meta = rec.meta().depth;
    for (i, image) in read["depth"].as_array().expect("depth").iter().enumerate() {
        let stamp = rec.frames()[i].timestamp_ns;
        assert_eq!(image["encoding"], "16UC1");
        assert_eq!(
            (image["width"].as_u64(), image["height"].as_u64()),
            (Some(512), Some(424))
        );
        assert_eq!(image["step"], 1024);
        assert_eq!(image["log_time"], stamp);
        assert_eq!(
            image["stamp"],
            json!([stamp / 1_000_000_000, stamp % 1_000_000_000])
        );
        assert_eq!(image["frame_id"], "slope_camera");
        let raw = std::fs::read(tmp.path().join(format!("depth-{i}.raw"))).expect("raw depth");
        let mm: Vec<u16> = raw
            .chunks_exact(2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .collect();
        assert_eq!(mm, depth_of(&rec, i), "frame {i}");
    }
    for info in read["camera_info"].as_array().expect("camera info") {
        assert_eq!(
            info["k"],
            json!([meta.fx, 0.0, meta.cx, 0.0, meta.fy, meta.cy, 0.0, 0.0, 1.0])
        );
    }

    // The mount: base_link to slope_camera, 0.5 m up, pitched -20°. The
    // base's up in the camera frame is the rotation matrix's last row.
    let transform = &read["tf_static"][0]["transforms"][0];
    assert_eq!(transform["header"]["frame_id"], "base_link");
    assert_eq!(transform["child_frame_id"], "slope_camera");
    assert_eq!(transform["transform"]["translation"]["z"], 0.5);
    let q = &transform["transform"]["rotation"];
    let [x, y, z, w] = ["x", "y", "z", "w"].map(|k| q[k].as_f64().expect("number"));
    let up = [
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        1.0 - 2.0 * (x * x + y * y),
    ];
    assert!((up[2].asin().to_degrees() + 20.0).abs() < 1e-9, "{up:?}");
    assert!(((-up[0]).atan2(-up[1]).to_degrees()).abs() < 1e-9, "{up:?}");

    // The estimates: slope-eval's, field by field.
    let eval = eval_estimates(&source);
    let estimates = read["estimates"].as_array().expect("estimates");
    assert_eq!(estimates.len(), eval.len());
    for (bag, eval) in estimates.iter().zip(&eval) {
        assert_eq!(bag["frame_index"], eval["index"]);
        assert_eq!(bag["header"]["frame_id"], "slope_camera");
        assert_eq!(bag["status"], 0, "{bag}");
        assert_eq!(eval["status"], "ok");
        for (ours, theirs) in [
            ("slope_deg", "slope_deg"),
            ("slope_std_deg", "std_deg"),
            ("distance_m", "distance_m"),
            ("ground_plane", "ground_plane"),
            ("inclined_plane", "inclined_plane"),
            ("ground_inliers", "ground_inliers"),
            ("inclined_inliers", "inclined_inliers"),
            ("confidence", "confidence"),
            ("ground_rms_m", "ground_rms_m"),
            ("inclined_area_m2", "inclined_area_m2"),
        ] {
            assert_eq!(bag[ours], eval[theirs], "{ours} of frame {}", eval["index"]);
        }
        assert_eq!(bag["tracked_slope_deg"], eval["tracked"]["slope_deg"]);
        assert_eq!(bag["tracked_frames"], eval["tracked"]["frames"]);
    }

    // The .msg shipped in ros2/slope_msgs is the schema in the bag, and it
    // has every field of slope.SlopeEstimate.v2 after the header.
    assert_eq!(read["msg_file_fields"], read["schema_fields"]);
    let names: Vec<&str> = read["schema_fields"]
        .as_array()
        .expect("fields")
        .iter()
        .map(|f| f[0].as_str().expect("name"))
        .collect();
    let expected: Vec<&str> = std::iter::once("header")
        .chain(layout::slope_estimate().iter().map(|f| f.name))
        .collect();
    assert_eq!(names, expected);
}

/// The bag description `ros_bags.py write` reads: the first [`FRAMES`]
/// frames of ramp16 (raw depth written into `dir`), the mount as the
/// transform base_link -> kinect2_ir_optical_frame.
fn bag_spec(dir: &Path, encoding: &str, extra: Value) -> PathBuf {
    let rec = Recording::open(&recording("ramp16")).expect("ramp16");
    let meta = rec.meta();
    let mut raw = Vec::new();
    let mut png = Vec::new();
    let mut stamps = Vec::new();
    let mut color = Vec::new();
    for i in 0..FRAMES {
        let rgb = rec
            .read_color(&rec.frames()[i])
            .expect("colour")
            .expect("ramp16 has colour");
        let path = dir.join(format!("frame-{i}.rgb"));
        std::fs::write(&path, rgb.data.concat()).expect("raw colour");
        color.push(path);
        let path = dir.join(format!("frame-{i}.u16"));
        let bytes: Vec<u8> = depth_of(&rec, i)
            .iter()
            .flat_map(|d| d.to_le_bytes())
            .collect();
        std::fs::write(&path, bytes).expect("raw frame");
        raw.push(path);
        png.push(rec.dir().join(&rec.frames()[i].depth));
        stamps.push(EPOCH_NS + rec.frames()[i].timestamp_ns);
    }
    // Pitch -20° about the base's y axis, then the optical frame's axes:
    // the quaternion of R = Ry(20°) * [[0,0,1],[-1,0,0],[0,-1,0]].
    let (s, c) = (10f64.to_radians().sin(), 10f64.to_radians().cos());
    // q_align = (-0.5, 0.5, -0.5, 0.5) (x, y, z, w); q_pitch = (0, s, 0, c).
    let (ax, ay, az, aw) = (-0.5, 0.5, -0.5, 0.5);
    let (px, py, pz, pw) = (0.0, s, 0.0, c);
    let q = [
        pw * ax + px * aw + py * az - pz * ay,
        pw * ay - px * az + py * aw + pz * ax,
        pw * az + px * ay - py * ax + pz * aw,
        pw * aw - px * ax - py * ay - pz * az,
    ];
    let mut spec = json!({
        "width": meta.depth.width, "height": meta.depth.height,
        "fx": meta.depth.fx, "fy": meta.depth.fy, "cx": meta.depth.cx, "cy": meta.depth.cy,
        "base_frame": "base_link", "camera_frame": "kinect2_ir_optical_frame",
        "transform": [[0.0, 0.0, meta.mount.height_m], q],
        "depth_encoding": encoding, "stamps_ns": stamps,
        "depth_raw": raw, "depth_png": png, "color_raw": color,
    });
    if let (Some(spec), Some(extra)) = (spec.as_object_mut(), extra.as_object()) {
        spec.extend(extra.clone());
    }
    let path = dir.join("spec.json");
    std::fs::write(&path, spec.to_string()).expect("spec");
    path
}

/// Writes a bag of `format` with rosbags; its path.
fn make_bag(python: &Path, dir: &Path, format: &str, encoding: &str, extra: Value) -> PathBuf {
    let spec = bag_spec(dir, encoding, extra);
    let bag = dir.join(if format == "ros1" {
        "kinect.bag"
    } else {
        "kinect"
    });
    ros_bags(python, &["write".as_ref(), format.as_ref(), &spec, &bag]);
    bag
}

/// Imports a bag that rosbags wrote from ramp16 and checks it against
/// ramp16: depth, intrinsics, mount, stamps, slope-eval's answers and,
/// with a `color` encoding, the registered colour (else none: the bag
/// has no colour topic).
fn imports_to_the_original(format: &str, encoding: &str, color: Option<&str>) {
    let Some(python) = rosbags_python() else {
        return;
    };
    let tmp = tempfile::tempdir().expect("temp dir");
    let extra = match color {
        Some(color) => json!({"color_encoding": color}),
        None => json!({"color_raw": null}),
    };
    let bag = make_bag(&python, tmp.path(), format, encoding, extra);
    let out = tmp.path().join("imported");
    run_ok(
        "slope-import",
        &[
            bag.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
            "--sensor".as_ref(),
            "synthetic".as_ref(),
        ],
    );
    let original = Recording::open(&recording("ramp16")).expect("ramp16");
    let imported = Recording::open(&out).expect("the imported recording");
    assert_eq!(imported.frames().len(), FRAMES);
    assert_eq!(imported.meta().depth, original.meta().depth);
    assert_eq!(imported.meta().mount, original.meta().mount);
    assert_eq!(imported.meta().sensor, "synthetic");
    for i in 0..FRAMES {
        assert_eq!(depth_of(&imported, i), depth_of(&original, i), "frame {i}");
        assert_eq!(
            imported.frames()[i].timestamp_ns,
            EPOCH_NS + original.frames()[i].timestamp_ns
        );
        let frame = &imported.frames()[i];
        match color {
            Some(_) => assert_eq!(
                imported.read_color(frame).expect("colour"),
                original.read_color(&original.frames()[i]).expect("colour"),
                "frame {i}"
            ),
            None => assert_eq!(frame.color, None),
        }
    }
    assert_eq!(
        answers(&eval_estimates(&out)),
        answers(&eval_estimates(&recording("ramp16")))
    );
}

#[test]
fn a_ros1_bag_of_16uc1_and_rgb8_images_imports_to_the_original() {
    imports_to_the_original("ros1", "16UC1", Some("rgb8"));
}

#[test]
fn a_ros2_mcap_bag_of_32fc1_and_bgr8_images_imports_to_the_original() {
    imports_to_the_original("ros2-mcap", "32FC1", Some("bgr8"));
}

#[test]
fn a_ros2_sqlite_bag_of_compressed_depth_imports_to_the_original() {
    imports_to_the_original("ros2-sqlite", "compressedDepth", None);
}

/// Runs slope-import on `bag`; asserts a failure (status 1, no panic)
/// whose message contains `needle`.
fn import_fails(bag: &Path, out: &Path, needle: &str) -> String {
    let result = run(
        "slope-import",
        &[bag.as_os_str(), "-o".as_ref(), out.as_os_str()],
    );
    let stderr = String::from_utf8_lossy(&result.stderr).into_owned();
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains(needle), "expected {needle:?} in: {stderr}");
    stderr
}

#[test]
fn bad_bags_are_refused_with_a_clear_error() {
    let Some(python) = rosbags_python() else {
        return;
    };
    let tmp = tempfile::tempdir().expect("temp dir");
    let case = |name: &str, format: &str, encoding: &str, extra: Value| {
        let dir = tmp.path().join(name);
        std::fs::create_dir(&dir).expect("case dir");
        (
            make_bag(&python, &dir, format, encoding, extra),
            dir.join("out"),
        )
    };

    let (bag, out) = case("mono8", "ros2-mcap", "mono8", json!({}));
    import_fails(&bag, &out, "unsupported depth encoding 'mono8'");
    assert!(!out.exists(), "a failed import leaves no recording");

    let (bag, out) = case("no-info", "ros1", "16UC1", json!({"no_camera_info": true}));
    import_fails(
        &bag,
        &out,
        "the camera info never arrived on /kinect2/sd/camera_info",
    );

    let (bag, out) = case("empty", "ros2-sqlite", "16UC1", json!({"zero_size": true}));
    import_fails(&bag, &out, "the image is empty (0 x 0)");

    // Cut short: the frames before the cut are kept, the error says where
    // it stopped.
    for (name, format) in [("cut-ros1", "ros1"), ("cut-mcap", "ros2-mcap")] {
        let (bag, out) = case(name, format, "16UC1", json!({}));
        let file = if format == "ros1" {
            bag.clone()
        } else {
            bag.join("kinect.mcap")
        };
        let len = std::fs::metadata(&file).expect("bag file").len();
        let data = std::fs::read(&file).expect("bag");
        std::fs::write(&file, &data[..(len * 6 / 10) as usize]).expect("cut");
        let stderr = import_fails(&bag, &out, "stops early");
        let kept = Recording::open(&out).expect("the frames read are kept");
        let n = kept.frames().len();
        assert!((1..FRAMES).contains(&n), "{n} frames kept: {stderr}");
        assert!(
            stderr.contains(&format!("holds the {n} frames read")),
            "{stderr}"
        );
        let original = Recording::open(&recording("ramp16")).expect("ramp16");
        for i in 0..n {
            assert_eq!(
                depth_of(&kept, i),
                depth_of(&original, i),
                "{name} frame {i}"
            );
        }
    }
}

/// `slope-record --format rosbag2` beside a running chain (replay ->
/// estimator): rosbags reads a depth image and a camera info per recorded
/// cloud (the recording's depth), the mount on /tf_static, and one
/// estimate per frame estimated, each at its frame's capture stamp.
#[test]
fn a_rosbag2_recording_of_the_chain_reads_back_with_rosbags() {
    let Some(python) = rosbags_python() else {
        return;
    };
    let prefix = unique_prefix("record-rosbag2");
    let tmp = tempfile::tempdir().expect("temp dir");
    let bag = tmp.path().join("run");
    let _estimator = Proc::spawn("slope-estimator", ["--service-prefix", &prefix])
        .assert_ready("estimator ready");
    let mut record = Proc::spawn(
        "slope-record",
        [
            bag.to_str().expect("utf-8 path"),
            "--format",
            "rosbag2",
            "--service-prefix",
            &prefix,
            "--idle-timeout-s",
            "2",
        ],
    )
    .assert_ready("recording the cloud topic");
    let frames = 6usize;
    let mut replay = replay_frames(&prefix, "ramp16", 4.0, frames as u64, 2);
    replay.assert_exits_zero_within(Duration::from_secs(60));
    record.assert_exits_zero_within(Duration::from_secs(30));

    let msg_file = repo_root().join("ros2/slope_msgs/msg/SlopeEstimate.msg");
    let read: Value = serde_json::from_str(&ros_bags(
        &python,
        &["read".as_ref(), &bag, tmp.path(), &msg_file],
    ))
    .expect("JSON from ros_bags.py");
    let depth = read["depth"].as_array().expect("depth");
    assert_eq!(depth.len(), frames, "{}", read["topics"]);
    assert_eq!(read["camera_info"].as_array().map(Vec::len), Some(frames));
    let rec = Recording::open(&recording("ramp16")).expect("ramp16");
    for i in 0..frames {
        let raw = std::fs::read(tmp.path().join(format!("depth-{i}.raw"))).expect("raw depth");
        let mm: Vec<u16> = raw
            .chunks_exact(2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .collect();
        assert_eq!(mm, depth_of(&rec, i), "frame {i}");
    }
    let transform = &read["tf_static"][0]["transforms"][0];
    assert_eq!(transform["transform"]["translation"]["z"], 0.5);
    // One estimate per frame (the estimator may supersede a frame on a
    // loaded machine: it then counts it), each at a recorded frame's stamp.
    let estimates = read["estimates"].as_array().expect("estimates");
    let dropped = estimates
        .last()
        .and_then(|e| e["dropped_frames"].as_u64())
        .unwrap_or(0);
    assert_eq!(
        estimates.len() as u64 + dropped,
        frames as u64,
        "{estimates:?}"
    );
    let stamps: Vec<&Value> = depth.iter().map(|d| &d["stamp"]).collect();
    for e in estimates {
        assert_eq!(e["status"], 0, "{e}");
        assert!(
            (e["slope_deg"].as_f64().expect("slope") - 16.0).abs() < 0.5,
            "{e}"
        );
        let stamp = json!([e["header"]["stamp"]["sec"], e["header"]["stamp"]["nanosec"]]);
        assert!(stamps.contains(&&stamp), "{e}");
    }
    assert_eq!(read["schema_fields"], read["msg_file_fields"]);
}

/// Our own export imports back (no Python needed): `slope-convert
/// --format rosbag2` then `slope-import` gives ramp16's depth, stamps,
/// intrinsics and mount (from the /tf_static the export wrote).
#[test]
fn a_converted_bag_imports_back_to_the_recording() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let source = recording("ramp16");
    let bag = tmp.path().join("bag");
    let out = tmp.path().join("back");
    let frames = FRAMES.to_string();
    run_ok(
        "slope-convert",
        &[
            source.as_os_str(),
            "-o".as_ref(),
            bag.as_os_str(),
            "--format".as_ref(),
            "rosbag2".as_ref(),
            "--no-estimates".as_ref(),
            "--max-frames".as_ref(),
            frames.as_ref(),
        ],
    );
    run_ok(
        "slope-import",
        &[bag.as_os_str(), "-o".as_ref(), out.as_os_str()],
    );
    let original = Recording::open(&source).expect("ramp16");
    let back = Recording::open(&out).expect("the imported recording");
    assert_eq!(back.meta().depth, original.meta().depth);
    assert_eq!(back.meta().mount, original.meta().mount);
    assert_eq!(back.frames().len(), FRAMES);
    for i in 0..FRAMES {
        assert_eq!(
            back.frames()[i].timestamp_ns,
            original.frames()[i].timestamp_ns
        );
        assert_eq!(depth_of(&back, i), depth_of(&original, i), "frame {i}");
    }
    // --start 0.1 --duration 0.1 --every 2: of the frames stamped 0.1 to
    // 0.2 s after the first (frames 4, 5 and 6: 133, 167 and 200 ms less a
    // nanosecond), every second one.
    let cut = tmp.path().join("cut");
    run_ok(
        "slope-import",
        &[
            bag.as_os_str(),
            "-o".as_ref(),
            cut.as_os_str(),
            "--start".as_ref(),
            "0.1".as_ref(),
            "--duration".as_ref(),
            "0.1".as_ref(),
            "--every".as_ref(),
            "2".as_ref(),
        ],
    );
    let cut = Recording::open(&cut).expect("the cut recording");
    let stamps: Vec<u64> = cut.frames().iter().map(|f| f.timestamp_ns).collect();
    let expected: Vec<u64> = [4, 6]
        .iter()
        .map(|&i| original.frames()[i].timestamp_ns)
        .collect();
    assert_eq!(stamps, expected);
    assert_eq!(depth_of(&cut, 1), depth_of(&original, 6));
    // --list names the topics an import takes.
    let listed = run_ok("slope-import", &[bag.as_os_str(), "--list".as_ref()]);
    let text = String::from_utf8_lossy(&listed.stdout);
    assert!(
        text.contains("/slope/depth") && text.contains("<- depth"),
        "{text}"
    );
    assert!(
        text.contains("/slope/camera_info") && text.contains("<- camera info"),
        "{text}"
    );
    assert!(
        text.contains("/tf_static") && text.contains("<- mount"),
        "{text}"
    );
}
