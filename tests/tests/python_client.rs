//! The Python client (`python/slope_client`): its `ctypes` structures match
//! the Rust messages field by field, and a Python planner installed into a
//! fresh venv receives real estimates from slope-replay -> slope-estimator.
//!
//! The venv needs the `iceoryx2` package from PyPI. Without network or
//! pip the end-to-end test says why and skips, unless
//! `SLOPE_REQUIRE_PYTHON` (or `CI`) is set: then it fails.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use nix::sys::signal::Signal;

use serde_json::Value;
use slope_integration_tests::python_venv::{make_venv, python, venv_or_skip};
use slope_integration_tests::{deadline, replay_frames, repo_root, unique_prefix, Proc};
use slope_ipc_types::layout::{self, FieldLayout};
use slope_ipc_types::{
    confidence, surface_flags, EstimateStatus, SlopeMethod, SurfaceRole, SurfaceSupport,
    MAX_SURFACES, NO_SURFACE,
};
use slope_sensor::ipc::ESTIMATE_MAX_SUBSCRIBERS;
use slope_test_support::{require, Requirement};

/// A venv with the client installed (and with it `iceoryx2` from PyPI),
/// made once for all the tests of this file (they run in parallel: two
/// `python3 -m venv` into one directory at once fail), or `None` (the test
/// skips) when it cannot be made and Python is not required.
fn client_python() -> Option<PathBuf> {
    static VENV: std::sync::OnceLock<Result<PathBuf, String>> = std::sync::OnceLock::new();
    let made = VENV.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("python-client-venv");
        make_venv(&dir, None, &[repo_root().join("python").as_os_str()])
    });
    venv_or_skip(made, "the Python client")
}

/// Whether the interpreter runs at all; without it the tests say so and
/// skip, unless Python is required.
fn python_runs() -> bool {
    let runs = Command::new(python())
        .arg("--version")
        .output()
        .is_ok_and(|out| out.status.success());
    let found = if runs {
        Ok(())
    } else {
        Err(format!("{} does not run", python()))
    };
    require(Requirement::Python, found).is_some()
}

/// Runs `code` with the repository's `python/` on the path; its stdout.
fn run_python(code: &str) -> String {
    let out = Command::new(python())
        .args(["-c", code])
        .env("PYTHONPATH", repo_root().join("python"))
        .output()
        .unwrap_or_else(|e| panic!("cannot run {}: {e}", python()));
    assert!(
        out.status.success(),
        "python failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8")
}

fn as_json(fields: &[FieldLayout]) -> Value {
    fields
        .iter()
        .map(|f| serde_json::json!([f.name, f.offset, f.size]))
        .collect()
}

/// Sizes, offsets and type names of every message, and the names of the
/// statuses, methods and confidence reasons.
#[test]
fn python_structures_match_the_rust_messages() {
    if !python_runs() {
        return;
    }
    let printed = run_python(
        "import json\n\
         from slope_client import messages as m\n\
         print(json.dumps({'estimate': m.layout(m.SlopeEstimate), 'health': m.layout(m.Health),\n\
           'timing': m.layout(m.TimingStats), 'stage': m.layout(m.StageHealth),\n\
           'surfaces': m.layout(m.Surfaces), 'surface': m.layout(m.SurfaceDescription),\n\
           'roles': m.ROLE_NAMES, 'supports': m.SUPPORT_NAMES,\n\
           'flags': [m.IN_CORRIDOR, m.MEASURABLE, m.JOINS_GROUND, m.NO_SURFACE, m.MAX_SURFACES],\n\
           'reasons': m.CONFIDENCE_REASONS, 'statuses': m.STATUS_NAMES, 'methods': m.METHOD_NAMES}))",
    );
    let py: Value = serde_json::from_str(&printed).expect("JSON from python");
    // SAFETY: `type_name` is unsafe to implement, not to call.
    let names = unsafe {
        use iceoryx2::prelude::ZeroCopySend;
        [
            <slope_ipc_types::SlopeEstimate as ZeroCopySend>::type_name(),
            <slope_ipc_types::Health as ZeroCopySend>::type_name(),
            <slope_ipc_types::TimingStats as ZeroCopySend>::type_name(),
            <slope_ipc_types::StageHealth as ZeroCopySend>::type_name(),
            <slope_ipc_types::Surfaces as ZeroCopySend>::type_name(),
            <slope_ipc_types::SurfaceDescription as ZeroCopySend>::type_name(),
        ]
    };
    let rust = [
        (
            "estimate",
            layout::slope_estimate(),
            size_of::<slope_ipc_types::SlopeEstimate>(),
            align_of::<slope_ipc_types::SlopeEstimate>(),
        ),
        (
            "health",
            layout::health(),
            size_of::<slope_ipc_types::Health>(),
            align_of::<slope_ipc_types::Health>(),
        ),
        (
            "timing",
            layout::timing_stats(),
            size_of::<slope_ipc_types::TimingStats>(),
            align_of::<slope_ipc_types::TimingStats>(),
        ),
        (
            "stage",
            layout::stage_health(),
            size_of::<slope_ipc_types::StageHealth>(),
            align_of::<slope_ipc_types::StageHealth>(),
        ),
        (
            "surfaces",
            layout::surfaces(),
            size_of::<slope_ipc_types::Surfaces>(),
            align_of::<slope_ipc_types::Surfaces>(),
        ),
        (
            "surface",
            layout::surface_description(),
            size_of::<slope_ipc_types::SurfaceDescription>(),
            align_of::<slope_ipc_types::SurfaceDescription>(),
        ),
    ];
    for ((key, fields, size, align), type_name) in rust.into_iter().zip(names) {
        let p = &py[key];
        assert_eq!(p["type_name"], type_name, "{key}");
        assert_eq!(p["size"], size, "{key}");
        assert_eq!(p["align"], align, "{key}");
        assert_eq!(p["fields"], as_json(&fields), "{key}");
    }
    let reasons: Vec<&str> = confidence::ALL.iter().map(|(_, name)| *name).collect();
    assert_eq!(py["reasons"], serde_json::json!(reasons));
    for status in EstimateStatus::ALL {
        assert_eq!(py["statuses"][(status as u32).to_string()], status.name());
    }
    for method in SlopeMethod::ALL {
        assert_eq!(py["methods"][(method as u32).to_string()], method.name());
    }
    for role in SurfaceRole::ALL {
        assert_eq!(py["roles"][(role as u32).to_string()], role.name());
    }
    for support in SurfaceSupport::ALL {
        assert_eq!(py["supports"][(support as u32).to_string()], support.name());
    }
    assert_eq!(
        py["roles"].as_object().map(|o| o.len()),
        Some(SurfaceRole::ALL.len())
    );
    assert_eq!(
        py["supports"].as_object().map(|o| o.len()),
        Some(SurfaceSupport::ALL.len())
    );
    assert_eq!(
        py["flags"],
        serde_json::json!([
            surface_flags::IN_CORRIDOR,
            surface_flags::MEASURABLE,
            surface_flags::JOINS_GROUND,
            NO_SURFACE,
            MAX_SURFACES
        ])
    );
}

#[test]
fn a_python_planner_receives_real_estimates() {
    let Some(bin) = client_python() else {
        return;
    };
    let prefix = unique_prefix("python");
    let _estimator = Proc::spawn("slope-estimator", ["--service-prefix", &prefix])
        .assert_ready("estimator ready");
    let planner_script = repo_root().join("python/examples/planner.py");
    let mut planner = Proc::spawn_path(
        &bin,
        [
            planner_script.to_str().expect("utf-8 path"),
            "--service-prefix",
            &prefix,
            "--json",
            "--count",
            "6",
            "--timeout-s",
            "60",
        ],
    )
    .assert_ready(&format!("subscribed to {prefix}/estimate"));
    let mut replay = replay_frames(&prefix, "ramp16", 10.0, 6, 1);
    let until = deadline(60.0);
    let mut frames = Vec::new();
    while frames.len() < 6 {
        let Some(line) = planner.stdout_line(until) else {
            break;
        };
        let e: Value = serde_json::from_str(&line).unwrap_or_else(|e| panic!("{line:?}: {e}"));
        assert_eq!(e["status"], "ok", "{e}");
        assert_eq!(e["method"], "paper", "{e}");
        let slope = e["slope_deg"].as_f64().expect("slope");
        assert!((slope - 16.0).abs() < 1.0, "{e}");
        let speed = e["speed"].as_f64().expect("speed");
        assert!((speed - (1.0 - slope.abs() / 20.0)).abs() < 0.05, "{e}");
        frames.push(e["frame"].as_u64().expect("frame"));
    }
    assert_eq!(frames, [0, 1, 2, 3, 4, 5], "{}", planner.diagnostics());
    planner.assert_exits_zero_within(Duration::from_secs(10));
    replay.assert_exits_zero_within(Duration::from_secs(30));
}

/// Subscribes to the estimates and the surfaces of `sys.argv[1]`, says so on
/// stderr, and prints one JSON line per surfaces message (its frame, the
/// slope of that frame's estimate, published just before it, and the
/// road's) until none came for 10 s; then `{"estimates": [frames]}`.
const SURFACES_SUBSCRIBER: &str = r#"
import json, sys
import slope_client
prefix = sys.argv[1]
estimates = slope_client.subscribe(prefix)
surfaces = slope_client.subscribe_surfaces(prefix, timeout_s=10)
print(f"subscribed to {prefix}/surfaces", file=sys.stderr, flush=True)
slopes = {}
def drain():
    while (e := estimates.receive()) is not None:
        slopes[e.frame_index] = e.slope_deg
for s in surfaces:
    drain()
    road = s.road_surface()
    print(json.dumps({"frame": s.frame_index, "status": s.status_name,
        "estimate_slope_deg": slopes.get(s.frame_index),
        "road_role": road.role_name if road else None,
        "road_slope_deg": road.slope_deg if road else None,
        "count": len(s.present())}), flush=True)
drain()
print(json.dumps({"estimates": sorted(slopes)}), flush=True)
"#;

/// replay -> estimator -> a Python subscriber of the surfaces: the frames of
/// the estimates (all six unless the machine is too loaded for the
/// estimator to take every frame), each with a road whose slope is the
/// estimate's.
#[test]
fn a_python_subscriber_receives_the_surfaces_of_each_estimate() {
    let Some(bin) = client_python() else {
        return;
    };
    let prefix = unique_prefix("python-surfaces");
    let _estimator = Proc::spawn("slope-estimator", ["--service-prefix", &prefix])
        .assert_ready("estimator ready");
    let mut subscriber = Proc::spawn_path(&bin, ["-c", SURFACES_SUBSCRIBER, &prefix])
        .assert_ready(&format!("subscribed to {prefix}/surfaces"));
    let mut replay = replay_frames(&prefix, "ramp16", 5.0, 6, 1);
    let until = deadline(60.0);
    let mut frames = Vec::new();
    let estimates = loop {
        let Some(line) = subscriber.stdout_line(until) else {
            panic!("no end of the surfaces\n{}", subscriber.diagnostics());
        };
        let s: Value = serde_json::from_str(&line).unwrap_or_else(|e| panic!("{line:?}: {e}"));
        if let Some(estimates) = s.get("estimates") {
            break estimates.clone();
        }
        assert_eq!(s["status"], "ok", "{s}");
        assert_eq!(s["road_role"], "ramp", "{s}");
        let estimate = s["estimate_slope_deg"]
            .as_f64()
            .expect("the frame's estimate arrived first");
        let road = s["road_slope_deg"].as_f64().expect("a road");
        // The road's RANSAC plane, which the fit refines: 0.02 to 0.09°
        // apart on ramp16.
        assert!((road - estimate).abs() < 0.25, "{s}");
        assert!(s["count"].as_u64().expect("count") >= 2, "{s}");
        frames.push(s["frame"].as_u64().expect("frame"));
    };
    assert_eq!(
        serde_json::json!(frames),
        estimates,
        "the estimates' frames"
    );
    assert!(
        frames.windows(2).all(|w| w[0] < w[1]),
        "in order: {frames:?}"
    );
    assert!(
        frames.len() >= 3 && frames.iter().all(|&f| f < 6),
        "{frames:?}\n{}",
        subscriber.diagnostics()
    );
    subscriber.assert_exits_zero_within(Duration::from_secs(10));
    replay.assert_exits_zero_within(Duration::from_secs(30));
}

/// Runs the rest of its arguments with SIGINT at its default, as a shell in
/// a terminal starts a program (a test harness may have it ignored, and
/// Python then never raises `KeyboardInterrupt`).
const SIGINT_DEFAULT: &str = "import os, signal, sys; signal.signal(signal.SIGINT, \
signal.SIG_DFL); os.execv(sys.argv[1], sys.argv[1:])";

#[test]
fn ctrl_c_ends_a_python_planner_cleanly() {
    let Some(bin) = client_python() else {
        return;
    };
    let prefix = unique_prefix("python-sigint");
    let _estimator = Proc::spawn("slope-estimator", ["--service-prefix", &prefix])
        .assert_ready("estimator ready");
    let planner_script = repo_root().join("python/examples/planner.py");
    let bin_text = bin.to_str().expect("utf-8 path");
    let mut planner = Proc::spawn_path(
        &bin,
        [
            "-c",
            SIGINT_DEFAULT,
            bin_text,
            planner_script.to_str().expect("utf-8 path"),
            "--service-prefix",
            &prefix,
        ],
    )
    .assert_ready(&format!("subscribed to {prefix}/estimate"));
    // Waiting on the topic's event when the signal comes: iceoryx2's wait
    // ends with its own error, which must not escape as a traceback.
    planner.signal(Signal::SIGINT);
    planner.assert_exits_zero_within(Duration::from_secs(10));
    let stderr = planner.stderr_lines().join("\n");
    assert!(!stderr.contains("Error"), "{stderr}");
}

#[test]
fn a_subscriber_beyond_the_topics_limit_is_told_why() {
    let Some(bin) = client_python() else {
        return;
    };
    let prefix = unique_prefix("python-limit");
    let _estimator = Proc::spawn("slope-estimator", ["--service-prefix", &prefix])
        .assert_ready("estimator ready");
    let code = format!(
        "import slope_client\n\
         subs = []\n\
         try:\n\
         \x20   for _ in range(100):\n\
         \x20       subs.append(slope_client.subscribe({prefix:?}))\n\
         except slope_client.TooManySubscribers as err:\n\
         \x20   print(len(subs), err)\n"
    );
    let out = Command::new(&bin)
        .args(["-c", &code])
        .output()
        .unwrap_or_else(|e| panic!("cannot run {}: {e}", bin.display()));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let limit = ESTIMATE_MAX_SUBSCRIBERS;
    assert!(
        stdout.starts_with(&format!(
            "{limit} cannot subscribe to '{prefix}/estimate': the topic takes at most {limit} \
             subscribers at once"
        )),
        "{stdout}"
    );
}

#[test]
fn the_example_planner_slows_down_where_it_cannot_see_the_floor_ahead() {
    if !python_runs() {
        return;
    }
    // `speed_for` alone, on stand-ins for estimates: no ramp seen is
    // --no-ramp-speed (a drop-off the camera cannot see reads the same),
    // never full speed, and a stop where the floor was seen to end closer
    // than --min-ground-ahead (1 m here; unknown reach: --no-ramp-speed); an
    // untrusted estimate stops; a trusted 10° ramp is half speed at
    // --max-slope 20.
    let planner = repo_root().join("python/examples/planner.py");
    let code = format!(
        "import importlib.util, types\n\
         spec = importlib.util.spec_from_file_location('planner', {planner:?})\n\
         planner = importlib.util.module_from_spec(spec)\n\
         spec.loader.exec_module(planner)\n\
         def estimate(status, ok, confidence, slope, seen=None):\n\
         \x20   return types.SimpleNamespace(status_name=status, ok=ok, confidence=confidence,\n\
         \x20       slope_deg=slope, tracked_slope_deg=slope, tracked_accepted=True,\n\
         \x20       ground_seen_to=seen)\n\
         nan = float('nan')\n\
         print(planner.speed_for(estimate('no_inclined_plane', False, 0.0, nan), 20, 0.5, 0.4, 1.0))\n\
         print(planner.speed_for(estimate('no_inclined_plane', False, 0.0, nan, 0.8), 20, 0.5, 0.4, 1.0))\n\
         print(planner.speed_for(estimate('no_inclined_plane', False, 0.0, nan, 3.5), 20, 0.5, 0.4, 1.0))\n\
         print(planner.speed_for(estimate('ok', True, 0.3, 10.0), 20, 0.5, 0.4, 1.0))\n\
         print(planner.speed_for(estimate('ok', True, 0.9, 10.0), 20, 0.5, 0.4, 1.0))\n"
    );
    let out = run_python(&code);
    assert_eq!(
        out.split_whitespace().collect::<Vec<_>>(),
        ["0.4", "0.0", "0.4", "0.0", "0.5"]
    );
}
