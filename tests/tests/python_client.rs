//! The Python client (`python/slope_client`): its `ctypes` structures match
//! the Rust messages field by field, and a Python planner installed into a
//! fresh venv receives real estimates from slope-replay -> slope-estimator.
//!
//! The venv needs the `iceoryx2` package from PyPI. Without network or
//! pip the end-to-end test says why and skips, unless
//! `SLOPE_REQUIRE_PYTHON` (or `CI`) is set: then it fails.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;
use slope_integration_tests::{deadline, replay_frames, repo_root, unique_prefix, Proc};
use slope_ipc_types::layout::{self, FieldLayout};
use slope_ipc_types::{confidence, EstimateStatus, SlopeMethod};

const REQUIRE_PYTHON_ENV: &str = "SLOPE_REQUIRE_PYTHON";

fn python() -> String {
    std::env::var("PYTHON").unwrap_or_else(|_| "python3".to_string())
}

/// True when a test may skip for want of Python (not under CI).
fn python_optional() -> bool {
    std::env::var_os(REQUIRE_PYTHON_ENV).is_none() && std::env::var_os("CI").is_none()
}

/// Whether the interpreter runs at all; without it the tests say so and
/// skip, unless Python is required.
fn python_runs() -> bool {
    let runs = Command::new(python())
        .arg("--version")
        .output()
        .is_ok_and(|out| out.status.success());
    assert!(runs || python_optional(), "{} does not run", python());
    if !runs {
        eprintln!("SKIPPED: {} does not run here", python());
    }
    runs
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
}

/// A venv with the client installed (and with it `iceoryx2` from PyPI),
/// or why there is none.
fn venv_with_client() -> Result<PathBuf, String> {
    let venv = Path::new(env!("CARGO_TARGET_TMPDIR")).join("python-client-venv");
    let bin = venv.join("bin/python");
    if !bin.exists() {
        let made = Command::new(python())
            .args(["-m", "venv"])
            .arg(&venv)
            .output()
            .map_err(|e| format!("cannot run {}: {e}", python()))?;
        if !made.status.success() {
            return Err(format!(
                "python3 -m venv failed: {}",
                String::from_utf8_lossy(&made.stderr)
            ));
        }
    }
    let installed = Command::new(&bin)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
        ])
        .arg(repo_root().join("python"))
        .output()
        .map_err(|e| format!("cannot run pip: {e}"))?;
    if !installed.status.success() {
        return Err(format!(
            "pip install python/ failed: {}",
            String::from_utf8_lossy(&installed.stderr)
        ));
    }
    Ok(bin)
}

#[test]
fn a_python_planner_receives_real_estimates() {
    let bin = match venv_with_client() {
        Ok(bin) => bin,
        Err(why) => {
            let required =
                std::env::var_os(REQUIRE_PYTHON_ENV).is_some() || std::env::var_os("CI").is_some();
            assert!(!required, "the Python client cannot be installed: {why}");
            eprintln!("SKIPPED: the Python client cannot be installed here ({why})");
            return;
        }
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
    planner.assert_exits_zero_within(std::time::Duration::from_secs(10));
    replay.assert_exits_zero_within(std::time::Duration::from_secs(30));
}
