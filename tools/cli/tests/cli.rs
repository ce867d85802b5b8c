//! Every binary teaches with --help and refuses bad arguments with a
//! non-zero exit. (These tests also make `cargo test` build the binaries
//! that the multi-process tests in tests/ spawn.)

use std::process::Command;

use slope_test_support::{require, Requirement};

fn run(bin: &str, args: &[&str]) -> (bool, String, String) {
    let output = Command::new(bin)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {bin}: {e}"));
    (
        output.status.success(),
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

const BINARIES: [(&str, &str); 5] = [
    ("slope-replay", env!("CARGO_BIN_EXE_slope-replay")),
    ("slope-estimator", env!("CARGO_BIN_EXE_slope-estimator")),
    ("slope-echo", env!("CARGO_BIN_EXE_slope-echo")),
    ("slope-demo", env!("CARGO_BIN_EXE_slope-demo")),
    ("slope-record", env!("CARGO_BIN_EXE_slope-record")),
];

#[test]
fn help_names_the_program_and_shows_examples() {
    for (name, bin) in BINARIES {
        let (ok, stdout, _) = run(bin, &["--help"]);
        assert!(ok, "{name} --help failed");
        assert!(stdout.contains(name), "{name} --help does not name it");
        assert!(
            stdout.contains("Examples:"),
            "{name} --help has no examples"
        );
        assert!(
            stdout.contains("--service-prefix"),
            "{name} --help lacks --service-prefix"
        );
    }
}

/// Every example in --help is one line at 100 columns (a wrapped comment
/// would read as a command of its own); every program's help, the ones
/// without --service-prefix too.
#[test]
fn help_examples_fit_on_one_line_each() {
    let others = [
        ("slope-eval", env!("CARGO_BIN_EXE_slope-eval")),
        ("slope-convert", env!("CARGO_BIN_EXE_slope-convert")),
    ];
    for (name, bin) in BINARIES.into_iter().chain(others) {
        let output = Command::new(bin)
            .arg("--help")
            .env("COLUMNS", "100")
            .output()
            .unwrap_or_else(|e| panic!("cannot run {bin}: {e}"));
        let stdout = String::from_utf8_lossy(&output.stdout);
        let examples: Vec<&str> = stdout
            .lines()
            .skip_while(|l| *l != "Examples:")
            .skip(1)
            .take_while(|l| !l.is_empty())
            .collect();
        assert!(!examples.is_empty(), "{name}: no examples in\n{stdout}");
        for line in examples {
            assert!(
                line.starts_with("  slope-") && line.len() <= 100,
                "{name}: a wrapped or overlong example line: {line:?}"
            );
        }
    }
}

/// The usage and flag texts that once said something else.
#[test]
fn help_texts_match_what_the_programs_do() {
    let (_, convert, _) = run(env!("CARGO_BIN_EXE_slope-convert"), &["--help"]);
    assert!(
        convert.contains("Usage: slope-convert [OPTIONS] <RECORDING> --output <FILE>\n"),
        "{convert}"
    );
    let (_, demo, _) = run(env!("CARGO_BIN_EXE_slope-demo"), &["--help"]);
    let prefix = demo
        .split("--service-prefix <SERVICE_PREFIX>")
        .nth(1)
        .and_then(|rest| rest.split("[env: SLOPE_SERVICE_PREFIX").next())
        .unwrap_or_else(|| panic!("no --service-prefix in {demo}"));
    assert!(prefix.contains("-demo-<pid>"), "{prefix}");
    assert!(!prefix.contains("config file"), "{prefix}");
    let (_, eval, _) = run(env!("CARGO_BIN_EXE_slope-eval"), &["--help"]);
    assert!(!eval.contains("paper's defaults"), "{eval}");
    assert!(eval.contains("missing keys keep our"), "{eval}");
}

/// A program whose output is `-o` (or, as before, given without the flag)
/// says, when it has none, what is missing and how to give it: a usage
/// error (status 2), not clap's name of its argument group.
#[test]
fn a_missing_output_says_how_to_give_it() {
    for (bin, args, message) in [
        (
            env!("CARGO_BIN_EXE_slope-convert"),
            &["REC"][..],
            "an output file is required: give it as -o FILE",
        ),
        (
            env!("CARGO_BIN_EXE_slope-record"),
            &[][..],
            "an output is required: give it as -o DIR (a recording directory), \
             or as -o FILE with --format mcap",
        ),
    ] {
        let output = Command::new(bin).args(args).output().expect("run");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{bin}: {stderr}");
        assert!(
            stderr.starts_with(&format!("error: {message}\n")),
            "{bin}: {stderr}"
        );
        assert!(!stderr.contains("OUTPUT>"), "{bin}: {stderr}");
    }
}

#[test]
fn unknown_flags_fail_with_a_message() {
    for (name, bin) in BINARIES {
        let (ok, _, stderr) = run(bin, &["--no-such-flag"]);
        assert!(!ok, "{name} accepted an unknown flag");
        assert!(stderr.contains("--no-such-flag"), "{name}: {stderr}");
    }
}

#[test]
fn bad_values_are_refused() {
    let replay = env!("CARGO_BIN_EXE_slope-replay");
    let (ok, _, stderr) = run(replay, &["somewhere", "--speed", "0"]);
    assert!(!ok);
    assert!(stderr.contains("positive"), "{stderr}");
    // More subscribers than the cloud topic takes could never connect.
    let (ok, _, stderr) = run(replay, &["somewhere", "--wait-subscribers", "7"]);
    assert!(!ok);
    assert!(stderr.contains("at most 6"), "{stderr}");
    let estimator = env!("CARGO_BIN_EXE_slope-estimator");
    let (ok, _, stderr) = run(estimator, &["--method", "magic"]);
    assert!(!ok);
    assert!(stderr.contains("paper, least-squares or tls"), "{stderr}");
    // Values that would overflow a clock are refused, not panicked on.
    let echo = env!("CARGO_BIN_EXE_slope-echo");
    let (ok, _, stderr) = run(echo, &["--timeout-s", "1e300"]);
    assert!(!ok);
    assert!(stderr.contains("from 0.001 to 10000000"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let (ok, _, stderr) = run(echo, &["--service-prefix", ""]);
    assert!(!ok);
    assert!(stderr.contains("service prefix is empty"), "{stderr}");
    // The longest prefix allowed alone: the demo's -demo-<pid> does not
    // fit after it, said before anything starts.
    let longest = "p".repeat(slope_tools::cli::max_prefix_len());
    let demo = env!("CARGO_BIN_EXE_slope-demo");
    let (ok, _, stderr) = run(demo, &["--service-prefix", &longest]);
    assert!(!ok);
    assert!(
        stderr.contains("with the demo's -demo-<pid> added: the service prefix is"),
        "{stderr}"
    );
    let eval = env!("CARGO_BIN_EXE_slope-eval");
    let (ok, _, stderr) = run(eval, &["REC", "--render", "out", "--render-every", "0"]);
    assert!(!ok);
    assert!(
        stderr.contains("--render-every <N>': must be at least 1 (1 renders every frame"),
        "{stderr}"
    );
    assert!(!stderr.contains("18446744073709551615"), "{stderr}");
}

/// A user's error is printed once, a line per cause, and never with a
/// backtrace, whatever RUST_BACKTRACE says.
#[test]
fn user_errors_are_printed_once_without_a_backtrace() {
    let replay = env!("CARGO_BIN_EXE_slope-replay");
    let eval = env!("CARGO_BIN_EXE_slope-eval");
    let not_a_recording = env!("CARGO_MANIFEST_DIR");
    for (bin, args, named) in [
        (
            replay,
            vec!["/nonexistent/recording"],
            "not a recording directory",
        ),
        (eval, vec![not_a_recording], "not a recording directory"),
    ] {
        let output = Command::new(bin)
            .args(&args)
            .env("RUST_BACKTRACE", "1")
            .output()
            .expect("run");
        assert!(!output.status.success());
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(stderr.matches("error:").count(), 1, "{stderr}");
        assert_eq!(stderr.matches(named).count(), 1, "{stderr}");
        assert!(!stderr.to_lowercase().contains("backtrace"), "{stderr}");
        let lines: Vec<&str> = stderr.lines().collect();
        for (k, line) in lines.iter().enumerate() {
            assert!(
                !lines[..k].contains(line),
                "repeated line {line:?}: {stderr}"
            );
        }
    }
}

/// `--print-config` prints the settings in effect (file, defaults for the
/// keys it leaves out, the flags), which parse back to the same
/// configuration; a bad file is refused naming the key.
#[test]
fn the_estimator_prints_the_configuration_in_effect() {
    use slope_tools::config_file::SlopeFile;
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("slope.toml");
    std::fs::write(
        &file,
        "service_prefix = \"robot2\"\n[mount]\nheight_m = 0.5\n\
         [estimator]\nseed = 7\n[estimator.ransac]\nmax_planes = 12\n",
    )
    .expect("write");
    let bin = env!("CARGO_BIN_EXE_slope-estimator");
    let path = file.to_str().expect("utf-8 path");
    let (ok, stdout, stderr) = run(
        bin,
        &[
            "--config",
            path,
            "--method",
            "tls",
            "--health-interval-s",
            "0",
            "--print-config",
        ],
    );
    assert!(ok, "{stderr}");
    let printed = SlopeFile::from_toml_str(&stdout).unwrap_or_else(|e| panic!("{e}\n{stdout}"));
    let mut expected = SlopeFile {
        service_prefix: "robot2".into(),
        ..SlopeFile::default()
    };
    expected.mount.height_m = Some(0.5);
    expected.health.interval_s = 0.0;
    expected.estimator.seed = 7;
    expected.estimator.method = slope_ipc_types::SlopeMethod::Tls;
    expected.estimator.ransac.max_planes = Some(12);
    assert_eq!(printed, expected);
    assert!(
        stdout.contains("[estimator.normals]") && stdout.contains("[capture]"),
        "every section is printed:\n{stdout}"
    );
    assert!(
        !stderr.contains('\u{1b}'),
        "no colour off a terminal: {stderr}"
    );
    for (text, named) in [
        (
            "[estimator.ransac]\nmax_planez = 12\n",
            "`estimator.ransac.max_planez` (line 2): unknown field",
        ),
        (
            "[mount]\npitch_deg = -95.0\n",
            "`mount.pitch_deg` = -95: the mount pitch (degrees) must be at least -90 and at most 90",
        ),
        ("seed = 7\n", "move `seed` under [estimator]"),
    ] {
        std::fs::write(&file, text).expect("write");
        let (ok, _, stderr) = run(bin, &["--config", path, "--print-config"]);
        assert!(!ok, "{text} accepted");
        assert!(stderr.contains(named), "{text}: {stderr}");
        assert!(stderr.contains(path), "the file is named: {stderr}");
    }
}

/// With SLOPE_SERVICE_PREFIX set, a usage error's usage line shows only
/// what the program needs, not `--service-prefix <SERVICE_PREFIX>` as if
/// it were required; a bad value in the variable is still refused.
#[test]
fn the_prefix_from_the_environment_is_not_in_the_usage_line() {
    let cases = [
        (env!("CARGO_BIN_EXE_slope-replay"), &[][..]),
        (env!("CARGO_BIN_EXE_slope-record"), &["--bogus"][..]),
    ];
    for (bin, args) in cases {
        let output = Command::new(bin)
            .args(args)
            .env("SLOPE_SERVICE_PREFIX", "robot9")
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{bin}: {stderr}");
        let usage = stderr
            .lines()
            .find(|l| l.starts_with("Usage:"))
            .unwrap_or_else(|| panic!("{bin}: no usage line: {stderr}"));
        assert!(!usage.contains("--service-prefix"), "{usage}");
    }
    let output = Command::new(env!("CARGO_BIN_EXE_slope-replay"))
        .arg("rec")
        .env("SLOPE_SERVICE_PREFIX", "/robot9")
        .output()
        .expect("runs");
    assert_eq!(
        output.status.code(),
        Some(2),
        "a bad prefix is a usage error"
    );
}

/// slope-echo and slope-record have no --config; their --service-prefix
/// help does not send the user to one.
#[test]
fn the_clients_prefix_help_names_no_config_flag() {
    for bin in [
        env!("CARGO_BIN_EXE_slope-echo"),
        env!("CARGO_BIN_EXE_slope-record"),
    ] {
        let (ok, stdout, _) = run(bin, &["--help"]);
        assert!(ok);
        assert!(!stdout.contains("--config"), "{bin}: {stdout}");
        assert!(stdout.contains("/etc/slope/slope.toml"), "{bin}: {stdout}");
    }
}

/// A subscriber started as another user than the slope processes (the
/// first mistake the one-user trust model invites) is told so: iceoryx2's
/// root path belongs to that user. It said "failed to create the node on
/// service '...': InternalError". Needs root (to run as `nobody`): a skip
/// elsewhere, a failure in CI (`.ci/run` runs it as root).
#[test]
fn another_user_is_told_whose_files_iceoryx2_keeps() {
    let uid = Command::new("id").arg("-u").output().map(|o| o.stdout);
    let root = uid.is_ok_and(|id| id.trim_ascii() == b"0");
    let found = if !root {
        Err("not running as root (to start a program as nobody)".to_string())
    } else if Command::new("runuser").arg("--help").output().is_err() {
        Err("runuser does not run".to_string())
    } else {
        Ok(())
    };
    if require(Requirement::Root, found).is_none() {
        return;
    }
    let echo = env!("CARGO_BIN_EXE_slope-echo");
    let prefix = format!("cli-user-{}", std::process::id());
    let echo_args = [
        "--service-prefix",
        &prefix,
        "--count",
        "1",
        "--timeout-s",
        "0.5",
    ];
    // As root first: iceoryx2's root path exists, and is root's.
    let (ok, _, stderr) = run(echo, &echo_args);
    assert!(!ok && stderr.contains("estimates arrived"), "{stderr}");
    let as_nobody = [&["-u", "nobody", "--", echo][..], &echo_args].concat();
    let (ok, _, stderr) = run("runuser", &as_nobody);
    assert!(!ok);
    assert!(
        stderr.contains("failed to start iceoryx2 on node 'slope-echo-")
            && stderr.contains("belongs to user id 0")
            && stderr.contains("run every slope process and every subscriber as that user"),
        "{stderr}"
    );
}
