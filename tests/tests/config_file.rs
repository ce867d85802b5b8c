//! One config file for every daemon, across real processes: slope-replay
//! and slope-estimator find each other through a service prefix that only
//! the file names, and the estimator runs with the file's [estimator] and
//! [health] sections; a flag still wins over the file.

use serde_json::Value;
use slope_integration_tests::{deadline, recording, unique_prefix, Proc};
use slope_ipc_types::SERVICE_PREFIX_ENV;

/// Writes a config file with `prefix`, health reports every 0.3 s and the
/// least-squares method.
fn config_file(dir: &std::path::Path, prefix: &str) -> String {
    let path = dir.join("slope.toml");
    std::fs::write(
        &path,
        format!(
            "service_prefix = \"{prefix}\"\n[health]\ninterval_s = 0.3\n\
             [estimator]\nmethod = \"least-squares\"\n"
        ),
    )
    .expect("write the config file");
    path.to_str().expect("utf-8 path").to_string()
}

#[test]
fn a_prefix_given_only_in_the_file_connects_replay_and_estimator() {
    let dir = tempfile::tempdir().expect("temp dir");
    let prefix = unique_prefix("config-file");
    let config = config_file(dir.path(), &prefix);
    // The prefix comes from the file alone, whatever the caller's environment says.
    let mut estimator = Proc::spawn_without_env(
        "slope-estimator",
        ["--config", config.as_str()],
        &[SERVICE_PREFIX_ENV],
    )
    .assert_ready("estimator ready");
    let mut estimates = Proc::spawn(
        "slope-echo",
        ["--json", "--service-prefix", &prefix, "--count", "2"],
    )
    .assert_ready("subscribed");
    let mut health = Proc::spawn(
        "slope-echo",
        [
            "--health",
            "--json",
            "--service-prefix",
            &prefix,
            "--count",
            "2",
        ],
    )
    .assert_ready("subscribed");
    let rec = recording("ramp16");
    let mut replay = Proc::spawn_without_env(
        "slope-replay",
        [
            rec.to_str().expect("utf-8"),
            "--config",
            &config,
            "--rate",
            "10",
            "--max-frames",
            "20",
            "--wait-subscribers",
            "1",
        ],
        &[SERVICE_PREFIX_ENV],
    );
    let by = deadline(60.0);
    for _ in 0..2 {
        let line = estimates
            .stdout_line(by)
            .unwrap_or_else(|| panic!("no estimate\n{}", estimator.diagnostics()));
        let estimate: Value = serde_json::from_str(&line).expect("JSON");
        assert_eq!(estimate["method"], "least-squares", "{estimate}");
    }
    let line = health
        .stdout_line(deadline(10.0))
        .unwrap_or_else(|| panic!("no health report\n{}", estimator.diagnostics()));
    let report: Value = serde_json::from_str(&line).expect("JSON");
    assert_eq!(report["component"], "estimator", "{report}");
    let second = health.stdout_line(deadline(10.0)).expect("a second report");
    let second: Value = serde_json::from_str(&second).expect("JSON");
    let step = second["uptime_ms"].as_f64().expect("uptime")
        - report["uptime_ms"].as_f64().expect("uptime");
    assert!((150.0..=900.0).contains(&step), "every 0.3 s: {step} ms");
    replay.assert_exits_zero_within(std::time::Duration::from_secs(60));
}

#[test]
fn a_flag_wins_over_the_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file_prefix = unique_prefix("config-file-unused");
    let prefix = unique_prefix("config-flag");
    let config = config_file(dir.path(), &file_prefix);
    let _estimator = Proc::spawn(
        "slope-estimator",
        [
            "--config",
            config.as_str(),
            "--service-prefix",
            &prefix,
            "--method",
            "tls",
        ],
    )
    .assert_ready("estimator ready");
    let mut estimates = Proc::spawn(
        "slope-echo",
        ["--json", "--service-prefix", &prefix, "--count", "1"],
    )
    .assert_ready("subscribed");
    let rec = recording("ramp16");
    let _replay = Proc::spawn(
        "slope-replay",
        [
            rec.to_str().expect("utf-8"),
            "--config",
            &config,
            "--service-prefix",
            &prefix,
            "--rate",
            "10",
            "--max-frames",
            "20",
            "--wait-subscribers",
            "1",
        ],
    );
    let line = estimates.stdout_line(deadline(60.0)).expect("an estimate");
    let estimate: Value = serde_json::from_str(&line).expect("JSON");
    assert_eq!(estimate["method"], "tls", "{estimate}");
}

/// Runs `program` with `--config` on a file holding `text`; its exit status
/// (within 20 s) and stderr.
fn run_with_config(program: &str, text: &str, extra: &[&str]) -> (Option<i32>, String) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("slope.toml");
    std::fs::write(&path, text).expect("write the config file");
    let prefix = unique_prefix("config-bad");
    let mut args = vec![
        "--config",
        path.to_str().expect("utf-8 path"),
        "--service-prefix",
        prefix.as_str(),
    ];
    args.extend_from_slice(extra);
    let mut proc = Proc::spawn(program, args);
    let status = proc.wait_exit(deadline(20.0));
    let stderr = proc.diagnostics();
    (status.and_then(|s| s.code()), stderr)
}

/// A typo, a value out of range and an unreadable file in the config file
/// exit with EX_CONFIG (78), which the units do not restart
/// (`RestartPreventExitStatus=78`), and say what is wrong.
#[test]
fn a_bad_config_file_exits_with_ex_config() {
    let rec = recording("ramp16");
    let rec = rec.to_str().expect("utf-8 path");
    let cases: [(&str, &str); 3] = [
        ("[capture]\npipelin = \"cpu\"\n", "pipelin"),
        ("[mount]\npitch_deg = -95\n", "mount.pitch_deg"),
        ("[estimator\n", "not TOML"),
    ];
    for (program, extra) in [("slope-estimator", &[][..]), ("slope-replay", &[rec][..])] {
        for (text, named) in cases {
            let (code, stderr) = run_with_config(program, text, extra);
            assert_eq!(code, Some(78), "{program} on {text:?}\n{stderr}");
            assert!(stderr.contains(named), "{program} on {text:?}\n{stderr}");
        }
    }
    let mut missing = Proc::spawn(
        "slope-estimator",
        ["--config", "/nonexistent/slope.toml", "--print-config"],
    );
    let status = missing.wait_exit(deadline(20.0));
    assert_eq!(
        status.and_then(|s| s.code()),
        Some(78),
        "{}",
        missing.diagnostics()
    );
}
