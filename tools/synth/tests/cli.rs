//! The `slope-synth` binary: writes what the flags say, teaches in --help,
//! and fails with a non-zero exit and a message naming the problem.

use std::process::Command;

use slope_sensor::recording::Recording;

fn synth() -> Command {
    Command::new(env!("CARGO_BIN_EXE_slope-synth"))
}

#[test]
fn writes_the_documented_default_scene() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("ramp");
    // The mount by its older flag names, kept as aliases of
    // --mount-height-m and --mount-pitch-deg.
    let status = synth()
        .args([
            "--slope",
            "16",
            "--distance",
            "1.5",
            "--height",
            "0.5",
            "--pitch",
            "-20",
        ])
        .args(["--frames", "2", "--seed", "7", "-o"])
        .arg(&out)
        .env("RUST_LOG", "warn")
        .status()
        .expect("runs");
    assert!(status.success());
    let rec = Recording::open(&out).expect("readable");
    assert_eq!(rec.frames().len(), 2);
    assert_eq!(rec.meta().truth.slope_deg, Some(16.0));
    assert_eq!(rec.meta().sensor, "synthetic");
    assert_eq!(rec.frames()[1].timestamp_ns, 33_333_333);
    let mount = rec.mount();
    assert_eq!(
        (mount.height_m, mount.pitch_deg, mount.roll_deg),
        (0.5, -20.0, 0.0)
    );
    let color = rec.read_color(&rec.frames()[0]).expect("readable");
    assert!(color.is_some());
}

#[test]
fn help_teaches_with_examples() {
    let out = synth().arg("--help").output().expect("runs");
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "Examples:",
        "--descending",
        "--clean",
        "--scene",
        "slope-synth --slope 16",
    ] {
        assert!(text.contains(needle), "--help lacks {needle}");
    }
}

#[test]
fn failures_exit_non_zero_and_say_why() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("something"), "x").expect("writable");
    let out = synth()
        .args(["--frames", "1", "-o"])
        .arg(dir.path())
        .output()
        .expect("runs");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("failed to write recording"), "{err}");

    let scene = dir.path().join("bad.toml");
    std::fs::write(&scene, "[ramp]\nslope_deg = -5.0\n").expect("writable");
    let out = synth()
        .arg("--scene")
        .arg(&scene)
        .arg("-o")
        .arg(dir.path().join("new"))
        .output()
        .expect("runs");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("ramp.slope_deg") && err.contains("bad.toml"),
        "{err}"
    );
}

/// A value out of range is named as the user gave it: by its flag and the
/// value typed when it came from a flag (a usage error, status 2, nothing
/// written), by its key and the file when it came from a scene file.
#[test]
fn out_of_range_values_are_named_by_flag_or_by_scene_key() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("new");
    for (flag, value, key) in [
        ("--mount-pitch-deg", "95", "mount.pitch_deg"),
        ("--mount-roll-deg", "-90", "mount.roll_deg"),
        ("--mount-height-m", "0", "mount.height_m"),
        ("--speed-mps", "20", "motion.speed_mps"),
        ("--distance", "0", "ramp.distance_m"),
        ("--width", "nan", "ramp.width_m"),
        ("--length", "0", "ramp.length_m"),
        ("--landing", "inf", "ramp.landing_m"),
        ("--yaw", "90", "ramp.yaw_deg"),
        ("--side-walls", "0", "x_m"),
        // Negative lengths are refused by their range, not taken for flags.
        ("--mount-height-m", "-1", "mount.height_m"),
        ("--distance", "-1", "ramp.distance_m"),
        ("--width", "-2", "ramp.width_m"),
        ("--length", "-2", "ramp.length_m"),
        ("--landing", "-0.5", "ramp.landing_m"),
    ] {
        let run = synth()
            .args([flag, value, "-o"])
            .arg(&out)
            .output()
            .expect("runs");
        let err = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{flag} {value}: {err}");
        assert!(
            err.contains(&format!("'{value}' for '{flag} <")),
            "{flag} {value}: {err}"
        );
        assert!(!err.contains(key), "{flag} {value}: {err}");
        assert!(!out.exists(), "{flag} {value} wrote {}", out.display());
    }
    // No frames: a usage error, before anything is written.
    let run = synth()
        .args(["--frames", "0", "-o"])
        .arg(&out)
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert!(
        err.contains("'0' for '--frames <FRAMES>': must be at least 1"),
        "{err}"
    );
    assert!(!out.exists());
    // A descending wall: the flag that made it one is named.
    let run = synth()
        .args(["--slope", "90", "--descending", "-o"])
        .arg(&out)
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success(), "{err}");
    assert!(err.contains("--descending: a descending slope"), "{err}");
    assert!(!err.contains("ramp.slope_deg"), "{err}");
    // The same value from a scene file: its key and the file.
    let scene = dir.path().join("steep.toml");
    std::fs::write(&scene, "[mount]\npitch_deg = 95.0\n").expect("writable");
    let run = synth()
        .arg("--scene")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success(), "{err}");
    assert!(
        err.contains("steep.toml: key `mount.pitch_deg`: must lie in (-90, 90)"),
        "{err}"
    );
    assert!(!err.contains("--mount-pitch-deg"), "{err}");
}
