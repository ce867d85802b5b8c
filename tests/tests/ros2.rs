//! slope-replay -> slope-estimator -> slope-ros2 -> DDS -> Eclipse Cyclone
//! DDS (the PyPI package `cyclonedds`, a DDS implementation independent of
//! RustDDS, the one `rmw_cyclonedds` uses in ROS 2) with IDL types written
//! from the .msg files (`tests/python/ros2_types.py`), on the loopback only:
//! slope-ros2 with `ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`, Cyclone
//! restricted to `lo`, multicast off, `127.0.0.1` its static peer (the
//! loopback has no multicast flag: RustDDS unicasts its localhost
//! discovery to the well-known ports, where Cyclone listens).
//!
//! Each test has its own service prefix and DDS domain. Without Python or
//! PyPI the tests say why and skip, unless `SLOPE_REQUIRE_PYTHON` (or `CI`)
//! is set: then they fail.
#![cfg(feature = "ros2")]

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicU16, Ordering};
use std::time::{Duration, Instant};

use serde_json::Value;
use slope_integration_tests::python_venv::{make_venv, venv_or_skip};
use slope_integration_tests::{
    deadline, read_json_lines, replay_frames, repo_root, start_echo, start_estimator,
    unique_prefix, Proc,
};
use slope_ipc_types::{
    confidence, surface_flags, EstimateStatus, SlopeMethod, SurfaceRole, SurfaceSupport, NO_SURFACE,
};

/// Frames replayed in a test.
const FRAMES: u64 = 8;

/// A venv with `cyclonedds` and `rosbags`, made once for all the tests of
/// this file, or `None` (the test skips) when it cannot be made and Python
/// is optional.
fn venv_python() -> Option<PathBuf> {
    static VENV: std::sync::OnceLock<Result<PathBuf, String>> = std::sync::OnceLock::new();
    let made = VENV.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("ros2-venv");
        let packages = ["cyclonedds", "rosbags"].map(OsStr::new);
        make_venv(&dir, Some("cyclonedds, rosbags"), &packages)
    });
    venv_or_skip(made, "the Python venv (cyclonedds, rosbags)")
}

/// A DDS domain no other test of this run uses (the process id spreads
/// parallel runs; 0, ROS's default, is left alone).
fn unique_domain() -> u16 {
    static NEXT: AtomicU16 = AtomicU16::new(0);
    let base = (std::process::id() % 100) as u16;
    100 + (base + NEXT.fetch_add(1, Ordering::SeqCst)) % 100
}

/// Cyclone DDS on the loopback only: no multicast, 127.0.0.1 as its peer
/// (it sends discovery to the unicast ports of participant indices 0..20
/// there, where RustDDS listens).
const CYCLONE_LOOPBACK: &str = "<CycloneDDS><Domain id=\"any\"><General><Interfaces>\
<NetworkInterface name=\"lo\"/></Interfaces><AllowMulticast>false</AllowMulticast></General>\
<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20\
</MaxAutoParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain>\
</CycloneDDS>";

/// A Cyclone DDS subscriber (`tests/python/ros2_listen.py`) on `domain`
/// to `topics` (`DDS_TOPIC:TYPE:RELIABILITY:DURABILITY`).
struct Listener {
    proc: Proc,
}

impl Listener {
    fn start(python: &Path, domain: u16, topics: &[&str]) -> Self {
        let script = repo_root().join("tests/python/ros2_listen.py");
        let domain = domain.to_string();
        let mut args: Vec<&OsStr> = vec![script.as_os_str(), domain.as_ref(), "120".as_ref()];
        args.extend(topics.iter().map(OsStr::new));
        let python_path = repo_root().join("tests/python");
        let proc = Proc::spawn_path_with_env(
            python,
            args,
            &[
                ("PYTHONPATH", python_path.as_os_str()),
                ("CYCLONEDDS_URI", OsStr::new(CYCLONE_LOOPBACK)),
            ],
        );
        Self { proc }
    }

    /// The next JSON line, or `None` at `until`.
    fn next(&mut self, until: Instant) -> Option<Value> {
        let line = self.proc.stdout_line(until)?;
        Some(serde_json::from_str(&line).unwrap_or_else(|e| panic!("{line:?}: {e}")))
    }

    /// Waits until every topic of `topics` has matched a writer; samples
    /// seen meanwhile are returned.
    fn wait_matched(&mut self, topics: &[&str], seconds: f64) -> Vec<Value> {
        let until = deadline(seconds);
        let mut left: Vec<&str> = topics.to_vec();
        let mut early = Vec::new();
        while !left.is_empty() {
            let Some(line) = self.next(until) else {
                panic!(
                    "Cyclone DDS never matched {left:?}\n{}",
                    self.proc.diagnostics()
                );
            };
            match line["matched"].as_str() {
                Some(topic) => left.retain(|t| *t != topic),
                None => early.push(line),
            }
        }
        early
    }
}

/// slope-ros2 on `prefix` and `domain`, on the loopback, with `extra`
/// flags; once it is ready.
fn start_node(prefix: &str, domain: u16, extra: &[&str]) -> Proc {
    let domain = domain.to_string();
    let mut args = vec!["--service-prefix", prefix, "--domain-id", &domain];
    args.extend_from_slice(extra);
    Proc::spawn_with_env(
        "slope-ros2",
        &args,
        &[("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")],
    )
    .assert_ready("ros2 node ready")
}

/// The echo JSON's value of `key` where absent values are `null`, and the
/// message's float (NaN arrives as `null` from the listener).
fn same_number(echo: &Value, dds: &Value, what: &str) {
    assert_eq!(echo, dds, "{what}: slope-echo {echo}, DDS {dds}");
}

/// Every value of `slope-echo --json`'s estimate `echo` in the DDS
/// message `dds`.
fn assert_same_estimate(echo: &Value, dds: &Value) {
    let frame = echo["frame"].as_u64().expect("frame");
    let what = |key: &str| format!("frame {frame} {key}");
    for (echo_key, dds_key) in [
        ("frame", "frame_index"),
        ("timestamp_ns", "capture_stamp_ns"),
        ("publish_stamp_ns", "publish_stamp_ns"),
        ("source_stamp_ns", "source_stamp_ns"),
        ("dropped_frames", "dropped_frames"),
        ("slope_deg", "slope_deg"),
        ("std_deg", "slope_std_deg"),
        ("distance_m", "distance_m"),
        ("ground_inliers", "ground_inliers"),
        ("inclined_inliers", "inclined_inliers"),
        ("samples", "samples"),
        ("confidence", "confidence"),
        ("ground_rms_m", "ground_rms_m"),
        ("inclined_rms_m", "inclined_rms_m"),
        ("ground_area_m2", "ground_area_m2"),
        ("inclined_area_m2", "inclined_area_m2"),
        ("ground_seen_to_m", "ground_seen_to_m"),
        ("tracked_slope_deg", "tracked_slope_deg"),
        ("tracked_std_deg", "tracked_std_deg"),
        ("tracked_frames", "tracked_frames"),
        ("ground_plane", "ground_plane"),
        ("inclined_plane", "inclined_plane"),
    ] {
        same_number(&echo[echo_key], &dds[dds_key], &what(echo_key));
    }
    let status = EstimateStatus::ALL
        .into_iter()
        .find(|s| Some(*s as u64) == dds["status"].as_u64())
        .expect("a known status");
    assert_eq!(echo["status"], status.name(), "{}", what("status"));
    let method = SlopeMethod::ALL
        .into_iter()
        .find(|m| Some(*m as u64) == dds["method"].as_u64())
        .expect("a known method");
    assert_eq!(echo["method"], method.name(), "{}", what("method"));
    let bits = dds["confidence_reasons"].as_u64().expect("reasons");
    let names: Vec<&str> = confidence::ALL
        .iter()
        .filter(|(bit, _)| bits & u64::from(*bit) != 0)
        .map(|(_, name)| *name)
        .collect();
    assert_eq!(echo["confidence_reasons"], serde_json::json!(names));
    assert_eq!(
        echo["ground_from_mount"].as_bool(),
        Some(dds["ground_from_mount"] == 1)
    );
    assert_eq!(
        echo["tracked_accepted"].as_bool(),
        Some(dds["tracked_accepted"] == 1)
    );
    let processing_us = dds["processing_us"].as_u64().expect("processing_us");
    assert_eq!(
        echo["processing_ms"].as_f64(),
        Some(processing_us as f64 / 1000.0)
    );
    // The header: the capture stamp, the camera's frame.
    let stamp = echo["timestamp_ns"].as_u64().expect("stamp");
    let header = &dds["header"];
    assert_eq!(header["stamp"]["sec"].as_u64(), Some(stamp / 1_000_000_000));
    assert_eq!(
        header["stamp"]["nanosec"].as_u64(),
        Some(stamp % 1_000_000_000)
    );
    assert_eq!(header["frame_id"], "slope_camera");
}

/// A ROS 2 namespace of the test's own (`/slope_test_ros2_<pid>_<n>`), so
/// that two runs that drew the same DDS domain still do not share topics.
fn test_namespace(prefix: &str) -> String {
    format!("/{}", prefix.replace('-', "_"))
}

/// Our topics in `namespace` as DDS names (`rt/<ns>/slope/estimate`) and
/// the listener's specs of them.
struct Topics {
    estimate: String,
    surfaces: String,
    markers: String,
}

impl Topics {
    fn of(namespace: &str) -> Self {
        Self {
            estimate: format!("rt{namespace}/slope/estimate"),
            surfaces: format!("rt{namespace}/slope/surfaces"),
            markers: format!("rt{namespace}/slope/markers"),
        }
    }

    fn estimate_spec(&self) -> String {
        format!("{}:SlopeEstimate:reliable:transient_local", self.estimate)
    }

    fn surfaces_spec(&self) -> String {
        format!("{}:Surfaces:reliable:transient_local", self.surfaces)
    }

    fn markers_spec(&self) -> String {
        format!("{}:MarkerArray:best_effort:volatile", self.markers)
    }
}

/// The overlay's role colours (tools/cli/src/render.rs) as ROS's floats.
fn role_rgb(role: u64) -> [f64; 3] {
    const ROLE_COLOURS: [[u8; 3]; 6] = [
        [220, 40, 40],
        [225, 130, 0],
        [30, 80, 255],
        [140, 75, 30],
        [0, 145, 135],
        [110, 60, 170],
    ];
    ROLE_COLOURS[role as usize].map(|c| f64::from(f32::from(c) / 255.0))
}

/// A frame's markers against its surfaces and estimate: a DELETEALL, a
/// filled polygon per surface (its outline's corners, its role's colour),
/// the road outlined (closed), the estimate's slope as text.
fn assert_markers(array: &Value, surfaces: &Value, estimate: &Value) {
    let markers = array["markers"].as_array().expect("markers");
    let sent = surfaces["surfaces"].as_array().expect("surfaces");
    let road = surfaces["road"].as_u64().expect("road") as usize;
    assert_eq!(markers.len(), sent.len() + 3, "{array}");
    assert_eq!(markers[0]["action"], 3, "DELETEALL first");
    let point = |p: &Value| [p["x"].as_f64(), p["y"].as_f64(), p["z"].as_f64()];
    for (k, surface) in sent.iter().enumerate() {
        let m = &markers[k + 1];
        assert_eq!(
            (m["ns"].as_str(), m["id"].as_u64()),
            (Some("surfaces"), Some(k as u64))
        );
        assert_eq!(m["type"], 11, "TRIANGLE_LIST");
        let c: Vec<_> = surface["outline"]
            .as_array()
            .expect("outline")
            .iter()
            .map(point)
            .collect();
        let triangles: Vec<_> = m["points"]
            .as_array()
            .expect("points")
            .iter()
            .map(point)
            .collect();
        assert_eq!(
            triangles,
            [c[0], c[1], c[2], c[0], c[2], c[3]],
            "surface {k}"
        );
        let rgb = role_rgb(surface["role"].as_u64().expect("role"));
        let colour = &m["color"];
        // float32 in the message: compare as f32.
        let got = [
            colour["r"].as_f64(),
            colour["g"].as_f64(),
            colour["b"].as_f64(),
        ]
        .map(|v| v.map(|v| v as f32));
        assert_eq!(got, rgb.map(|v| Some(v as f32)), "surface {k} colour");
    }
    let outline = &markers[sent.len() + 1];
    assert_eq!(
        (outline["ns"].as_str(), outline["type"].as_u64()),
        (Some("road"), Some(4))
    );
    let c: Vec<_> = sent[road]["outline"]
        .as_array()
        .expect("outline")
        .iter()
        .map(point)
        .collect();
    let strip: Vec<_> = outline["points"]
        .as_array()
        .expect("points")
        .iter()
        .map(point)
        .collect();
    assert_eq!(
        strip,
        [c[0], c[1], c[2], c[3], c[0]],
        "the road's outline, closed"
    );
    let text = &markers[sent.len() + 2];
    assert_eq!(text["type"], 9, "TEXT_VIEW_FACING");
    let slope = estimate["slope_deg"].as_f64().expect("slope");
    assert_eq!(text["text"], format!("{slope:.1}°"));
    for m in markers {
        assert_eq!(
            m["header"], surfaces["header"],
            "stamp and frame of the frame"
        );
    }
}

/// `slope-echo --surfaces --json` under `prefix` for `count` frames, once
/// subscribed.
fn start_surfaces_echo(prefix: &str, count: u64) -> Proc {
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

fn name_of<T: Copy>(
    all: &[T],
    raw: &Value,
    to_raw: fn(T) -> u64,
    name: fn(T) -> &'static str,
) -> &'static str {
    all.iter()
        .find(|x| Some(to_raw(**x)) == raw.as_u64())
        .map_or("unknown", |x| name(*x))
}

/// Every value of `slope-echo --surfaces --json`'s frame `echo` in the
/// DDS message `dds`.
fn assert_same_surfaces(echo: &Value, dds: &Value) {
    let frame = echo["frame"].as_u64().expect("frame");
    for (echo_key, dds_key) in [
        ("frame", "frame_index"),
        ("timestamp_ns", "capture_stamp_ns"),
        ("publish_stamp_ns", "publish_stamp_ns"),
        ("source_stamp_ns", "source_stamp_ns"),
        ("up", "up"),
        ("forward", "forward"),
        ("ground_plane", "ground_plane"),
        ("corridor_half_width_m", "corridor_half_width_m"),
        ("look_ahead_m", "look_ahead_m"),
    ] {
        same_number(
            &echo[echo_key],
            &dds[dds_key],
            &format!("frame {frame} {echo_key}"),
        );
    }
    let status = name_of(
        &EstimateStatus::ALL,
        &dds["status"],
        |s| s as u64,
        EstimateStatus::name,
    );
    assert_eq!(echo["status"], status);
    let road = dds["road"].as_u64().filter(|r| *r != u64::from(NO_SURFACE));
    assert_eq!(echo["road"].as_u64(), road, "frame {frame} road");
    assert_eq!(
        echo["ground_from_mount"].as_bool(),
        Some(dds["ground_from_mount"] == 1)
    );
    let echoed = echo["surfaces"].as_array().expect("surfaces");
    let sent = dds["surfaces"].as_array().expect("surfaces");
    assert_eq!(echoed.len(), sent.len(), "frame {frame}: surfaces");
    for (k, (e, d)) in echoed.iter().zip(sent).enumerate() {
        let what = |key: &str| format!("frame {frame} surface {k} {key}");
        for key in [
            "inliers",
            "segments",
            "slope_deg",
            "heading_deg",
            "distance_m",
            "far_m",
            "left_m",
            "right_m",
            "lowest_m",
            "highest_m",
            "area_m2",
            "rms_m",
            "noise_ratio",
        ] {
            same_number(&e[key], &d[key], &what(key));
        }
        let role = name_of(
            &SurfaceRole::ALL,
            &d["role"],
            |r| r as u64,
            SurfaceRole::name,
        );
        assert_eq!(e["role"], role, "{}", what("role"));
        let support = name_of(
            &SurfaceSupport::ALL,
            &d["support"],
            |s| s as u64,
            SurfaceSupport::name,
        );
        assert_eq!(e["support"], support, "{}", what("support"));
        let by = d["supported_by"]
            .as_u64()
            .filter(|b| *b != u64::from(NO_SURFACE));
        assert_eq!(e["supported_by"].as_u64(), by, "{}", what("supported_by"));
        assert_eq!(e["road"].as_bool(), Some(road == Some(k as u64)));
        let flags = d["flags"].as_u64().expect("flags");
        for (key, bit) in [
            ("in_corridor", surface_flags::IN_CORRIDOR),
            ("measurable", surface_flags::MEASURABLE),
            ("joins_ground", surface_flags::JOINS_GROUND),
        ] {
            assert_eq!(
                e[key].as_bool(),
                Some(flags & u64::from(bit) != 0),
                "{}",
                what(key)
            );
        }
        // A plane that is all zero is no plane (null in the echo).
        let plane = d["plane"].clone();
        let zero = plane == serde_json::json!([0.0, 0.0, 0.0, 0.0]);
        same_number(
            &e["plane"],
            if zero { &Value::Null } else { &plane },
            &what("plane"),
        );
        // float32 corners: slope-echo prints them as f32, Python as the
        // f64 of the same f32.
        let as_f32 = |v: &Value| v.as_f64().map(|x| x as f32);
        let corners: Vec<[Option<f32>; 3]> = d["outline"]
            .as_array()
            .expect("outline")
            .iter()
            .map(|p| [as_f32(&p["x"]), as_f32(&p["y"]), as_f32(&p["z"])])
            .collect();
        let echoed: Vec<[Option<f32>; 3]> = e["outline"]
            .as_array()
            .expect("outline")
            .iter()
            .map(|p| [as_f32(&p[0]), as_f32(&p[1]), as_f32(&p[2])])
            .collect();
        assert_eq!(echoed, corners, "{}", what("outline"));
    }
    assert_eq!(dds["header"]["frame_id"], "slope_camera");
}

#[test]
fn every_estimate_reaches_cyclone_dds_in_order_with_the_values_echo_shows() {
    let Some(python) = venv_python() else {
        return;
    };
    let prefix = unique_prefix("ros2");
    let domain = unique_domain();
    let _estimator = start_estimator(&prefix, &["--health-interval-s", "0.2"]);
    // Under a namespace of its own: --namespace is honoured.
    let namespace = test_namespace(&prefix);
    let topics = Topics::of(&namespace);
    let mut node = start_node(&prefix, domain, &["--namespace", &namespace]);
    let mut echo = start_echo(&prefix, FRAMES as usize);
    let mut surfaces_echo = start_surfaces_echo(&prefix, FRAMES);
    let specs = [
        topics.estimate_spec(),
        topics.surfaces_spec(),
        topics.markers_spec(),
    ];
    let specs: Vec<&str> = specs.iter().map(String::as_str).collect();
    let mut listener = Listener::start(&python, domain, &specs);
    let early = listener.wait_matched(&[&topics.estimate, &topics.surfaces, &topics.markers], 30.0);
    assert!(early.is_empty(), "samples before any frame: {early:?}");

    let mut replay = replay_frames(&prefix, "ramp16", 5.0, FRAMES, 1);
    // slope-echo prints every estimate the estimator published (a loaded
    // machine may make the estimator skip a frame, which it then counts).
    let mut echoed = Vec::new();
    let until = deadline(60.0);
    while echoed.last().and_then(|e: &Value| e["frame"].as_u64()) != Some(FRAMES - 1) {
        let Some(more) = read_json_lines(&mut echo, 1, 60.0).pop() else {
            break;
        };
        assert!(Instant::now() < until, "slope-echo too slow");
        echoed.push(more);
    }
    let last = echoed.last().expect("an estimate");
    let dropped = last["dropped_frames"].as_u64().expect("dropped");
    assert_eq!(echoed.len() as u64 + dropped, FRAMES, "{echoed:?}");

    let echoed_surfaces = read_json_lines(&mut surfaces_echo, echoed.len(), 30.0);
    let mut received = Vec::new();
    let mut surfaces = Vec::new();
    let mut markers = Vec::new();
    let until = deadline(30.0);
    while received.len() < echoed.len()
        || surfaces.len() < echoed_surfaces.len()
        || markers.len() < echoed_surfaces.len()
    {
        let Some(line) = listener.next(until) else {
            break;
        };
        let topic = line["topic"].as_str().unwrap_or_default();
        if topic == topics.estimate {
            received.push(line["message"].clone());
        } else if topic == topics.surfaces {
            surfaces.push(line["message"].clone());
        } else if topic == topics.markers {
            markers.push(line["message"].clone());
        } else {
            panic!("unexpected {line}");
        }
    }
    assert_eq!(
        received.len(),
        echoed.len(),
        "{}\n{}",
        node.diagnostics(),
        listener.proc.diagnostics()
    );
    for (echo, dds) in echoed.iter().zip(&received) {
        assert_same_estimate(echo, dds);
    }
    // Each estimate's surfaces, in order, as slope-echo --surfaces shows
    // them; the road a ramp.
    assert_eq!(echoed_surfaces.len(), echoed.len(), "{echoed_surfaces:?}");
    assert_eq!(
        surfaces.len(),
        echoed_surfaces.len(),
        "{}",
        node.diagnostics()
    );
    for ((echo, dds), estimate) in echoed_surfaces.iter().zip(&surfaces).zip(&received) {
        assert_same_surfaces(echo, dds);
        assert_eq!(dds["frame_index"], estimate["frame_index"]);
        let road = dds["road"].as_u64().expect("road") as usize;
        assert_eq!(
            dds["surfaces"][road]["role"],
            SurfaceRole::Ramp as u32,
            "{dds}"
        );
    }
    // Markers for every frame (best effort: none lost on the loopback).
    assert_eq!(markers.len(), surfaces.len(), "{}", node.diagnostics());
    for ((array, frame), estimate) in markers.iter().zip(&surfaces).zip(&received) {
        assert_markers(array, frame, estimate);
    }
    let slopes: Vec<f64> = received
        .iter()
        .map(|m| m["slope_deg"].as_f64().expect("a slope"))
        .collect();
    assert!(slopes.iter().all(|s| (s - 16.0).abs() < 1.0), "{slopes:?}");

    replay.assert_exits_zero_within(Duration::from_secs(30));
    node.signal(nix::sys::signal::Signal::SIGTERM);
    node.assert_exits_zero_within(Duration::from_secs(5));
    // One voice: RustDDS's own log stays out of the node's.
    let lines = node.stderr_lines().join("\n");
    assert!(!lines.contains("UDPListener"), "{lines}");
    assert!(lines.contains("ros2 node stopped"), "{lines}");
}

/// A subscriber that joins after the estimates were published gets the
/// last ones at once (transient local, keep last 10). The node is named
/// with `--ros-args -r __ns:= -p frame_id:=`.
#[test]
fn a_late_subscriber_gets_the_last_estimates() {
    let Some(python) = venv_python() else {
        return;
    };
    let prefix = unique_prefix("ros2-late");
    let domain = unique_domain();
    let _estimator = start_estimator(&prefix, &[]);
    let namespace = test_namespace(&prefix);
    let topics = Topics::of(&namespace);
    // Named in ROS 2's own syntax, as a launch file passes them.
    let ns_remap = format!("__ns:={namespace}");
    let ros_args = [
        "--ros-args",
        "-r",
        &ns_remap,
        "-p",
        "frame_id:='slope_test_frame'",
    ];
    let mut node = start_node(&prefix, domain, &ros_args);
    let mut echo = start_echo(&prefix, 3);
    let mut replay = replay_frames(&prefix, "ramp16", 5.0, 3, 1);
    let echoed = read_json_lines(&mut echo, 3, 60.0);
    replay.assert_exits_zero_within(Duration::from_secs(30));
    assert!(!echoed.is_empty());

    let mut listener = Listener::start(&python, domain, &[&topics.estimate_spec()]);
    let mut received = listener.wait_matched(&[&topics.estimate], 30.0);
    let until = deadline(20.0);
    while received.len() < echoed.len() {
        let Some(line) = listener.next(until) else {
            break;
        };
        received.push(line);
    }
    let frames: Vec<Option<u64>> = received
        .iter()
        .map(|l| l["message"]["frame_index"].as_u64())
        .collect();
    let expected: Vec<Option<u64>> = echoed.iter().map(|e| e["frame"].as_u64()).collect();
    assert_eq!(frames, expected, "{}", node.diagnostics());
    for line in &received {
        assert_eq!(
            line["message"]["header"]["frame_id"], "slope_test_frame",
            "-p frame_id:="
        );
    }
}

/// `ros2/slope_msgs/msg/*.msg` parse with the `rosbags` message parser and
/// match, field for field (names, types, array lengths), the IDL types the
/// Cyclone DDS test decodes with; so do the standard types against rosbags'
/// ROS 2 Jazzy and Humble definitions. A package built with colcon from these files
/// therefore decodes what slope-ros2 sends.
#[test]
fn the_msg_files_parse_with_rosbags_and_match_the_idl_field_for_field() {
    let Some(python) = venv_python() else {
        return;
    };
    let script = repo_root().join("tests/python/ros2_msgs_check.py");
    let out = Command::new(&python)
        .arg(&script)
        .arg(repo_root().join("ros2/slope_msgs/msg"))
        .env("PYTHONPATH", repo_root().join("tests/python"))
        .output()
        .expect("run ros2_msgs_check.py");
    assert!(
        out.status.success(),
        "ros2_msgs_check.py failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(
        report["_msg_files"],
        serde_json::json!([
            "slope_msgs/msg/SlopeEstimate",
            "slope_msgs/msg/Surface",
            "slope_msgs/msg/Surfaces"
        ])
    );
    let types = report.as_object().expect("object");
    for name in [
        "slope_msgs/msg/SlopeEstimate",
        "slope_msgs/msg/Surfaces",
        "slope_msgs/msg/Surface",
        "diagnostic_msgs/msg/DiagnosticArray",
        "diagnostic_msgs/msg/DiagnosticStatus",
        "visualization_msgs/msg/MarkerArray",
        "visualization_msgs/msg/Marker",
        "tf2_msgs/msg/TFMessage",
    ] {
        assert!(types.contains_key(name), "{name} is not checked");
    }
    for (name, check) in types.iter().filter(|(n, _)| !n.starts_with('_')) {
        assert_eq!(check["idl"], check["msg"], "{name}: IDL against .msg");
        assert_eq!(
            check["idl"], check["humble"],
            "{name}: IDL against Humble's"
        );
        assert!(
            !check["msg"].as_array().expect("fields").is_empty(),
            "{name}"
        );
    }
    let estimate = &report["slope_msgs/msg/SlopeEstimate"]["msg"];
    assert_eq!(
        estimate[0],
        serde_json::json!(["header", "std_msgs/msg/Header"])
    );
    assert_eq!(
        report["slope_msgs/msg/Surfaces"]["msg"]
            .as_array()
            .and_then(|f| f.last()),
        Some(&serde_json::json!(["surfaces", "slope_msgs/msg/Surface[]"]))
    );
}

const DIAGNOSTICS: &str = "rt/diagnostics:DiagnosticArray:reliable:volatile";

/// The value of `key` in a `DiagnosticStatus`'s key/values.
fn diagnostic_value<'a>(status: &'a Value, key: &str) -> Option<&'a str> {
    status["values"]
        .as_array()?
        .iter()
        .find(|kv| kv["key"] == key)?["value"]
        .as_str()
}

/// A figure of `slope-echo --health --json` (`null`: NaN) against the
/// diagnostic's text of it.
fn same_figure(echo: &Value, text: Option<&str>, what: &str) {
    let text = text.unwrap_or_else(|| panic!("{what}: no key/value"));
    match echo.as_f64() {
        Some(expected) => {
            let sent: f64 = text
                .parse()
                .unwrap_or_else(|e| panic!("{what}: {text}: {e}"));
            // serde_json's float parsing (without `float_roundtrip`) may be
            // a unit in the last place off Rust's.
            let ulp = (expected.abs() * f64::EPSILON).max(f64::MIN_POSITIVE);
            assert!(
                (sent - expected).abs() <= 2.0 * ulp,
                "{what}: sent {sent}, slope-echo {expected}"
            );
        }
        None => assert_eq!(text, "NaN", "{what}"),
    }
}

/// Every health report of the estimator (every 0.2 s) reaches
/// `/diagnostics` once, stamped as the report, its figures as key/values,
/// WARN "no clouds" while idle and OK while frames come: the stamps of
/// the diagnostics are the reports', so they come at the health rate.
#[test]
fn every_health_report_becomes_a_diagnostic_at_the_health_rate() {
    let Some(python) = venv_python() else {
        return;
    };
    let prefix = unique_prefix("ros2-diag");
    let domain = unique_domain();
    let _estimator = start_estimator(&prefix, &["--health-interval-s", "0.2"]);
    let mut node = start_node(&prefix, domain, &[]);
    let mut listener = Listener::start(&python, domain, &[DIAGNOSTICS]);
    let mut received = listener.wait_matched(&["rt/diagnostics"], 30.0);
    received.retain(|l| l["message"]["status"][0]["hardware_id"] == prefix.as_str());
    let reports = 16;
    let mut health = Proc::spawn(
        "slope-echo",
        [
            "--health",
            "--json",
            "--service-prefix",
            &prefix,
            "--count",
            &reports.to_string(),
            "--timeout-s",
            "60",
        ],
    )
    .assert_ready("subscribed to health reports");
    // Idle reports first, then reports over frames.
    let mut echoed = read_json_lines(&mut health, 3, 30.0);
    let mut replay = replay_frames(&prefix, "ramp16", 5.0, 10, 1);
    echoed.extend(read_json_lines(&mut health, reports - 3, 30.0));
    assert_eq!(echoed.len(), reports, "{echoed:?}");
    replay.assert_exits_zero_within(Duration::from_secs(30));

    let stamp_of = |m: &Value| {
        let stamp = &m["header"]["stamp"];
        stamp["sec"].as_u64().expect("sec") * 1_000_000_000 + stamp["nanosec"].as_u64().expect("ns")
    };
    let last_stamp = echoed
        .last()
        .and_then(|r| r["stamp_ns"].as_u64())
        .expect("stamp");
    let until = deadline(20.0);
    while received
        .last()
        .is_none_or(|l| stamp_of(&l["message"]) < last_stamp)
    {
        let Some(line) = listener.next(until) else {
            break;
        };
        assert_eq!(line["topic"], "rt/diagnostics", "{line}");
        // /diagnostics is global: only ours (another run on the same
        // domain has another service prefix).
        if line["message"]["status"][0]["hardware_id"] == prefix.as_str() {
            received.push(line);
        }
    }
    let diagnostics: Vec<&Value> = received.iter().map(|l| &l["message"]).collect();
    let mut levels = Vec::new();
    for report in &echoed {
        let stamp = report["stamp_ns"].as_u64().expect("stamp");
        let matching: Vec<&&Value> = diagnostics
            .iter()
            .filter(|d| stamp_of(d) == stamp)
            .collect();
        assert_eq!(
            matching.len(),
            1,
            "report at {stamp}: {}",
            node.diagnostics()
        );
        let status = &matching[0]["status"][0];
        assert_eq!(status["name"], "slope_ros2: estimator", "{status}");
        assert_eq!(status["hardware_id"].as_str(), Some(prefix.as_str()));
        for key in [
            "pid",
            "frames_in",
            "frames_out",
            "frames_dropped",
            "errors",
            "rate_in_hz",
            "rate_out_hz",
            "window_ms",
            "uptime_ms",
        ] {
            same_figure(&report[key], diagnostic_value(status, key), key);
        }
        for figure in ["median_ms", "p95_ms", "max_ms", "count"] {
            let key = format!("latency.{figure}");
            same_figure(
                &report["latency"][figure],
                diagnostic_value(status, &key),
                &key,
            );
        }
        for stage in report["stages"].as_array().expect("stages") {
            let name = stage["name"].as_str().expect("name");
            let key = format!("{name}.median_ms");
            same_figure(&stage["median_ms"], diagnostic_value(status, &key), &key);
        }
        // The rule: no error here; idle is WARN, frames coming in OK.
        assert_eq!(report["errors"], 0, "{report}");
        let level = status["level"].as_u64().expect("level");
        if report["rate_in_hz"].as_f64() == Some(0.0) {
            assert_eq!(level, 1, "{status}");
            assert!(status["message"]
                .as_str()
                .is_some_and(|m| m.starts_with("no clouds")));
        } else if report["frames_dropped"] == 0 {
            assert_eq!(level, 0, "{status}");
        }
        levels.push(level);
    }
    assert!(levels.contains(&0) && levels.contains(&1), "{levels:?}");
    // At the health rate: one diagnostic per report, 0.2 s apart.
    let stamps: Vec<u64> = diagnostics.iter().map(|d| stamp_of(d)).collect();
    let mut gaps: Vec<u64> = stamps.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_unstable();
    let median_s = gaps[gaps.len() / 2] as f64 / 1e9;
    assert!(
        (0.15..0.3).contains(&median_s),
        "median gap {median_s} s: {stamps:?}"
    );
}

/// `--base-frame base_link` with the config file's `[mount]` (0.5 m up,
/// pitched -20°, rolled 5°): `/tf_static` holds the camera's pose in
/// `base_link`, 0.5 m above its origin, and the base's up (z) in the
/// camera frame, the rotation's last row, is the mount's up vector
/// `[-sin r cos p, -cos r cos p, sin p]` (the recording format's
/// definition), also for a listener that joins late (transient local).
#[test]
fn the_mount_is_on_tf_static_for_late_listeners() {
    let Some(python) = venv_python() else {
        return;
    };
    let prefix = unique_prefix("ros2-tf");
    let domain = unique_domain();
    // /tf_static is global: a camera frame of its own tells ours apart
    // from another run's on the same domain.
    let camera = format!("{}_camera", test_namespace(&prefix).trim_start_matches('/'));
    let dir = tempfile::tempdir().expect("temp dir");
    let config = dir.path().join("slope.toml");
    std::fs::write(
        &config,
        format!(
            "[mount]\nheight_m = 0.5\npitch_deg = -20.0\nroll_deg = 5.0\n[ros2]\n\
             base_frame = \"base_link\"\nframe_id = \"{camera}\"\n"
        ),
    )
    .expect("write the config");
    let config = config.to_str().expect("utf-8").to_string();
    let _node = start_node(&prefix, domain, &["--config", &config]);
    let topic = "rt/tf_static:TFMessage:reliable:transient_local";
    let mut listener = Listener::start(&python, domain, &[topic]);
    let ours = |l: &Value| l["message"]["transforms"][0]["child_frame_id"] == camera.as_str();
    let mut lines = listener.wait_matched(&["rt/tf_static"], 30.0);
    lines.retain(ours);
    let until = deadline(20.0);
    while lines.is_empty() {
        let Some(line) = listener.next(until) else {
            break;
        };
        if ours(&line) {
            lines.push(line);
        }
    }
    assert_eq!(lines.len(), 1, "{lines:?}");
    let transforms = lines[0]["message"]["transforms"]
        .as_array()
        .expect("transforms");
    assert_eq!(transforms.len(), 1);
    let t = &transforms[0];
    assert_eq!(t["header"]["frame_id"], "base_link");
    assert_eq!(t["child_frame_id"], camera.as_str());
    let v = &t["transform"]["translation"];
    assert_eq!(
        [v["x"].as_f64(), v["y"].as_f64(), v["z"].as_f64()],
        [Some(0.0), Some(0.0), Some(0.5)]
    );
    let q = &t["transform"]["rotation"];
    let [x, y, z, w] = ["x", "y", "z", "w"].map(|k| q[k].as_f64().expect("quaternion"));
    assert!((x * x + y * y + z * z + w * w - 1.0).abs() < 1e-9);
    // The last row of the rotation matrix of (x, y, z, w).
    let row = [
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        1.0 - 2.0 * (x * x + y * y),
    ];
    let (p, r) = ((-20.0f64).to_radians(), 5.0f64.to_radians());
    let up = [-r.sin() * p.cos(), -r.cos() * p.cos(), p.sin()];
    for (got, want) in row.iter().zip(up) {
        assert!((got - want).abs() < 1e-9, "{row:?} against {up:?}");
    }
}

/// Settings refused before anything starts: a `[ros2]` value that is no
/// ROS 2 name (EX_CONFIG, 78, naming the key), `--base-frame` without a
/// mount, `ROS_AUTOMATIC_DISCOVERY_RANGE=OFF` (status 1, saying why).
#[test]
fn bad_settings_are_refused_with_the_reason() {
    let dir = tempfile::tempdir().expect("temp dir");
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "[ros2]\nnamespace = \"robot1\"\n").expect("write");
    let empty = dir.path().join("empty.toml");
    std::fs::write(&empty, "").expect("write");
    let prefix = unique_prefix("ros2-bad");
    let path = |p: &Path| p.to_str().expect("utf-8").to_string();
    // (flags, environment, exit status, what stderr says)
    type Case<'a> = (Vec<String>, &'a [(&'a str, &'a str)], i32, &'a str);
    let cases: [Case; 3] = [
        (
            vec!["--config".into(), path(&bad)],
            &[],
            78,
            "`ros2.namespace` = \"robot1\"",
        ),
        (
            vec![
                "--config".into(),
                path(&empty),
                "--base-frame".into(),
                "base_link".into(),
            ],
            &[("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")],
            1,
            "--base-frame base_link needs the camera's mount",
        ),
        (
            vec!["--config".into(), path(&empty)],
            &[("ROS_AUTOMATIC_DISCOVERY_RANGE", "OFF")],
            1,
            "ROS_AUTOMATIC_DISCOVERY_RANGE=OFF is not supported",
        ),
    ];
    for (args, env, status, message) in cases {
        let mut all = vec!["--service-prefix".to_string(), prefix.clone()];
        all.extend(args);
        let mut node = Proc::spawn_with_env("slope-ros2", &all, env);
        let exit = node.wait_exit(deadline(20.0)).expect("it exits");
        let stderr = node.stderr_lines().join("\n");
        assert_eq!(exit.code(), Some(status), "{all:?}: {stderr}");
        assert!(stderr.contains(message), "{all:?}: {stderr}");
    }
}

/// The unit is `Type=notify`: without systemd, the test binds the socket
/// systemd would (`NOTIFY_SOCKET`, with a watchdog asked for) and reads
/// `READY=1`, a watchdog ping, the status line with the counts, and
/// `STOPPING=1` after SIGTERM, which ends the node with status 0.
#[test]
fn the_node_speaks_the_notify_protocol_and_stops_cleanly() {
    use slope_integration_tests::read_notify_until;
    use std::os::unix::net::UnixDatagram;

    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("notify.sock");
    let socket = UnixDatagram::bind(&path).expect("bind the notify socket");
    socket
        .set_read_timeout(Some(Duration::from_millis(100)))
        .expect("timeout");
    let prefix = unique_prefix("ros2-notify");
    let domain = unique_domain().to_string();
    let mut node = Proc::spawn_with_env(
        "slope-ros2",
        ["--service-prefix", &prefix, "--domain-id", &domain],
        &[
            ("NOTIFY_SOCKET", path.to_str().expect("utf-8")),
            ("WATCHDOG_USEC", "400000"),
            ("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST"),
        ],
    );
    let mut seen = Vec::new();
    assert!(
        read_notify_until(&socket, &mut seen, "READY=1", deadline(20.0)),
        "{seen:?}\n{}",
        node.diagnostics()
    );
    assert!(
        read_notify_until(&socket, &mut seen, "WATCHDOG=1", deadline(5.0)),
        "{seen:?}"
    );
    assert!(
        read_notify_until(
            &socket,
            &mut seen,
            "STATUS=0 estimates, 0 surfaces, 0 markers, 0 diagnostics published",
            deadline(5.0)
        ),
        "{seen:?}"
    );
    node.signal(nix::sys::signal::Signal::SIGTERM);
    assert!(
        read_notify_until(&socket, &mut seen, "STOPPING=1", deadline(5.0)),
        "{seen:?}"
    );
    node.assert_exits_zero_within(Duration::from_secs(5));
}

/// An error in the estimator reaches `/diagnostics` as ERROR with its
/// reason: a cloud whose header says fx = 0 is refused (the estimator
/// counts an error, `last_error` names `fx`), and the next report's
/// diagnostic is level 2, `error: ...fx...`, with `errors` 1.
#[test]
fn an_estimator_error_is_an_error_diagnostic() {
    use slope_ipc_types::{CloudSource, Intrinsics, Mount, ServiceNames};
    use slope_sensor::ipc::{create_node, CloudPublisher};
    use slope_sensor::recording::DepthImage;
    use slope_sensor::source::{SourceFrame, SourceInfo};

    let Some(python) = venv_python() else {
        return;
    };
    let prefix = unique_prefix("ros2-error");
    let domain = unique_domain();
    let _estimator = start_estimator(&prefix, &["--health-interval-s", "0.2"]);
    let _node = start_node(&prefix, domain, &[]);
    let mut listener = Listener::start(&python, domain, &[DIAGNOSTICS]);
    listener.wait_matched(&["rt/diagnostics"], 30.0);

    // A 64 x 48 wall 2 m away, from a camera whose header says fx = 0.
    let (w, h) = (64, 48);
    let info = SourceInfo {
        width: w,
        height: h,
        intrinsics: Intrinsics {
            fx: 0.0,
            fy: 45.6,
            cx: 31.5,
            cy: 23.5,
        },
        unit_m: 0.001,
        mount: Mount {
            height_m: f64::NAN,
            pitch_deg: f64::NAN,
            roll_deg: f64::NAN,
        },
        source: CloudSource::Replay,
        has_color: false,
        sensor: "synthetic".into(),
    };
    let names = ServiceNames::new(prefix.clone());
    let ipc = create_node("ros2-error-test").expect("node");
    let publisher = CloudPublisher::create(&ipc, &names, &info, 10_000).expect("publisher");
    let until = deadline(20.0);
    while publisher.subscriber_count() == 0 {
        assert!(Instant::now() < until, "the estimator never subscribed");
        std::thread::sleep(Duration::from_millis(10));
    }
    let now_ns = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .expect("after 1970")
        .as_nanos() as u64;
    publisher
        .publish(&SourceFrame {
            index: 0,
            source_stamp_ns: now_ns,
            capture_stamp_ns: now_ns,
            depth: DepthImage {
                width: w,
                height: h,
                data: vec![2000; (w * h) as usize],
            },
            color: None,
        })
        .expect("published");

    let until = deadline(20.0);
    let mut levels = Vec::new();
    let error = loop {
        let Some(line) = listener.next(until) else {
            panic!("no ERROR diagnostic; levels seen {levels:?}");
        };
        let status = &line["message"]["status"][0];
        if status["hardware_id"] != prefix.as_str() {
            continue;
        }
        levels.push(status["level"].as_u64());
        if status["level"] == 2 {
            break status.clone();
        }
    };
    let message = error["message"].as_str().expect("message");
    assert!(
        message.starts_with("error: ") && message.contains("`fx`"),
        "{message}"
    );
    assert_eq!(diagnostic_value(&error, "errors"), Some("1"), "{error}");
    assert!(
        diagnostic_value(&error, "last_error").is_some_and(|e| e.contains("`fx`")),
        "{error}"
    );
    // Idle reports before it were WARN (no clouds), never ERROR.
    assert!(
        levels[..levels.len() - 1].iter().all(|l| *l == Some(1)),
        "{levels:?}"
    );
}
