//! Hostile input and faults, as a probe of the running programs found
//! them: files that are no regular files, clouds whose headers lie, bursts
//! of clouds, a file-size limit on the output, a bad frame met on every
//! pass of a loop. Each test spawns the real binaries with its own service
//! prefix and waits on deadlines.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use slope_integration_tests::{deadline, recording, start_estimator, unique_prefix, Proc};
use slope_ipc_types::{
    CloudSource, EstimateStatus, Health, Intrinsics, Mount, ServiceNames, SlopeEstimate,
};
use slope_sensor::ipc::{create_node, CloudPublisher, EstimateSubscriber, HealthSubscriber};
use slope_sensor::recording::DepthImage;
use slope_sensor::source::{SourceFrame, SourceInfo};

fn mkfifo(path: &Path) {
    let made = Command::new("mkfifo")
        .arg(path)
        .status()
        .expect("mkfifo runs");
    assert!(made.success(), "mkfifo {}", path.display());
}

/// Copies the bundled recording `name` into `to` (its files, not the images'
/// folders' other content).
fn copy_recording(name: &str, to: &Path) {
    let from = recording(name);
    std::fs::create_dir_all(to.join("depth")).expect("mkdir");
    for file in ["recording.toml", "frames.csv"] {
        std::fs::copy(from.join(file), to.join(file)).expect("copy");
    }
    for entry in std::fs::read_dir(from.join("depth")).expect("depth/") {
        let path = entry.expect("entry").path();
        let name = path.file_name().expect("a name");
        std::fs::copy(&path, to.join("depth").join(name)).expect("copy");
    }
}

/// Runs `program` with `args` and returns its status code and stderr, or
/// fails the test if it is still running after 20 s.
fn run_within_20_s(program: &str, args: &[&str]) -> (Option<i32>, String) {
    let mut child = Proc::spawn(program, args);
    let status = child.wait_exit(deadline(20.0));
    let stderr = child.diagnostics();
    let status = status.unwrap_or_else(|| panic!("{program} blocked\n{stderr}"));
    (status.code(), stderr)
}

/// A FIFO where a recording's recording.toml or frames.csv belongs, or as
/// the config file, blocked slope-eval, slope-replay, slope-convert and
/// slope-estimator (606 s under `timeout`; a signal logged "stopping" and
/// changed nothing). Each now refuses it at once, saying what it is; and
/// `/dev/zero` as a config file (read whole: 2.1 GB) is refused as a
/// device.
#[test]
fn fifos_and_devices_are_refused_at_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    for file in ["recording.toml", "frames.csv"] {
        let rec = dir.path().join(format!("fifo-{file}"));
        copy_recording("ramp16-clean", &rec);
        std::fs::remove_file(rec.join(file)).expect("rm");
        mkfifo(&rec.join(file));
        let rec = rec.to_str().expect("utf-8");
        let out = dir.path().join("out.mcap");
        let prefix = unique_prefix("fifo-replay");
        for (program, args) in [
            ("slope-eval", vec![rec]),
            (
                "slope-replay",
                vec![rec, "--service-prefix", prefix.as_str()],
            ),
            (
                "slope-convert",
                vec![rec, "-o", out.to_str().expect("utf-8")],
            ),
        ] {
            let (code, stderr) = run_within_20_s(program, &args);
            assert_ne!(code, Some(0), "{program}\n{stderr}");
            assert!(
                stderr.contains(&format!("fifo-{file}/{file}"))
                    && stderr.contains("it is a FIFO, not a regular file"),
                "{program} {file}\n{stderr}"
            );
        }
        assert!(!out.exists());
    }
    let fifo = dir.path().join("slope.toml");
    mkfifo(&fifo);
    let prefix = unique_prefix("fifo-config");
    for (config, what) in [
        (fifo.to_str().expect("utf-8"), "a FIFO"),
        ("/dev/zero", "a character device"),
    ] {
        let (code, stderr) = run_within_20_s(
            "slope-estimator",
            &["--config", config, "--service-prefix", prefix.as_str()],
        );
        assert_eq!(code, Some(78), "{config}\n{stderr}");
        assert!(
            stderr.contains(&format!("it is {what}, not a regular file")),
            "{config}\n{stderr}"
        );
    }
    let entries: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .filter(|name| name.to_string_lossy().ends_with(".part"))
        .collect();
    assert!(entries.is_empty(), "left behind: {entries:?}");
}

const W: u32 = 64;
const H: u32 = 48;

/// A 64 x 48 camera looking at a wall 2 m away.
fn wall_info(intrinsics: Intrinsics, mount: Mount) -> SourceInfo {
    SourceInfo {
        width: W,
        height: H,
        intrinsics,
        unit_m: 0.001,
        mount,
        source: CloudSource::Replay,
        has_color: false,
        sensor: "synthetic".into(),
    }
}

fn good_intrinsics() -> Intrinsics {
    Intrinsics {
        fx: 45.6,
        fy: 45.6,
        cx: 31.5,
        cy: 23.5,
    }
}

fn unknown_mount() -> Mount {
    Mount {
        height_m: f64::NAN,
        pitch_deg: f64::NAN,
        roll_deg: f64::NAN,
    }
}

fn wall_frame(index: u64, capture_stamp_ns: u64) -> SourceFrame {
    SourceFrame {
        index,
        source_stamp_ns: capture_stamp_ns,
        capture_stamp_ns,
        depth: DepthImage {
            width: W,
            height: H,
            data: vec![2000; (W * H) as usize],
        },
        color: None,
    }
}

fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .expect("after 1970")
        .as_nanos() as u64
}

/// Waits for the estimator to subscribe to the cloud topic of `publisher`.
fn wait_for_subscriber(publisher: &CloudPublisher) {
    let until = deadline(20.0);
    while publisher.subscriber_count() == 0 {
        assert!(Instant::now() < until, "the estimator never subscribed");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Every health report of the estimator until one satisfies `done` (or
/// 20 s pass); the last one.
fn health_until(health: &HealthSubscriber, done: impl Fn(&Health) -> bool) -> Option<Health> {
    let until = deadline(20.0);
    let mut last = None;
    while Instant::now() < until {
        while let Some(report) = health.receive().expect("health") {
            last = Some(report);
        }
        if last.as_ref().is_some_and(&done) {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    last
}

/// Clouds whose headers lie (focal length 0, NaN, infinite or 5e-324, a
/// mount pitch of 1e308, more points than `--max-points`) each got
/// `bad_frame` only after being estimated (fx = 0 gave `ok` at 16.2
/// degrees) and health said `errors 0`. Now each is refused before the
/// estimator sees it: a `bad_frame` estimate, an error in health with the
/// reason as `last_error`, and one WARN line for the lot (rate limited).
#[test]
fn clouds_with_lying_headers_are_refused_and_counted() {
    let prefix = unique_prefix("lying-headers");
    let mut estimator = start_estimator(
        &prefix,
        &["--health-interval-s", "0.1", "--max-points", "4000"],
    );
    let names = ServiceNames::new(prefix.clone());
    let node = create_node("hostile-input-test").expect("node");
    let estimates = EstimateSubscriber::create(&node, &names).expect("estimates");
    let health = HealthSubscriber::create(&node, &names).expect("health");
    let liars: Vec<(Intrinsics, Mount, &str)> = [0.0, f64::NAN, f64::INFINITY, 5e-324]
        .into_iter()
        .map(|fx| {
            let mut k = good_intrinsics();
            k.fx = fx;
            (k, unknown_mount(), "`fx`")
        })
        .chain(std::iter::once((
            good_intrinsics(),
            Mount {
                pitch_deg: 1e308,
                ..unknown_mount()
            },
            "`mount.pitch_deg`",
        )))
        .collect();
    let mut index = 0;
    for (intrinsics, mount, key) in &liars {
        // One publisher per header (a header's intrinsics are its source's).
        let publisher =
            CloudPublisher::create(&node, &names, &wall_info(*intrinsics, *mount), 10_000)
                .expect("publisher");
        wait_for_subscriber(&publisher);
        publisher
            .publish(&wall_frame(index, now_ns()))
            .expect("published");
        let estimate = next_estimate(&estimates, index);
        assert_eq!(
            estimate.status,
            EstimateStatus::BadFrame as u32,
            "{key}: {estimate:?}"
        );
        let report = health_until(&health, |h| h.errors > index).expect("a health report");
        assert!(report.last_error().contains(key), "{}", report.last_error());
        index += 1;
    }
    // A cloud over --max-points (64 x 96 = 6144 > 4000).
    let mut big = wall_info(good_intrinsics(), unknown_mount());
    big.height = 2 * H;
    let publisher = CloudPublisher::create(&node, &names, &big, 10_000).expect("publisher");
    wait_for_subscriber(&publisher);
    let mut frame = wall_frame(index, now_ns());
    frame.depth.height = 2 * H;
    frame.depth.data = vec![2000; (W * 2 * H) as usize];
    publisher.publish(&frame).expect("published");
    let estimate = next_estimate(&estimates, index);
    assert_eq!(estimate.status, EstimateStatus::BadFrame as u32);
    let report = health_until(&health, |h| h.errors > index).expect("a health report");
    assert!(
        report
            .last_error()
            .contains("6144 points; the limit is 4000"),
        "{}",
        report.last_error()
    );
    estimator.signal(nix::sys::signal::Signal::SIGTERM);
    estimator.assert_exits_zero_within(Duration::from_secs(10));
    let warnings: Vec<_> = estimator
        .stderr_lines()
        .iter()
        .filter(|l| l.contains("WARN") && l.contains("refused cloud"))
        .cloned()
        .collect();
    assert_eq!(warnings.len(), 1, "{warnings:#?}");
    assert!(warnings[0].contains("refused cloud 0"), "{warnings:#?}");
}

/// The estimate of cloud `index`, within 20 s.
fn next_estimate(estimates: &EstimateSubscriber, index: u64) -> SlopeEstimate {
    let until = deadline(20.0);
    while Instant::now() < until {
        if let Some(estimate) = estimates.receive().expect("receive") {
            if estimate.frame_index == index {
                return estimate;
            }
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    panic!("no estimate of cloud {index}");
}

/// 200 clouds in 120 ms (1.7 kHz): the estimator took 8 and said 28
/// dropped (an index that jumped faster than 1 kHz was "another stream",
/// which also restarted the tracked slope). Every cloud is now either
/// estimated or dropped: health counts 200 in, and out + dropped = 200.
#[test]
fn a_burst_of_clouds_is_counted_whole() {
    let prefix = unique_prefix("burst");
    let _estimator = start_estimator(&prefix, &["--health-interval-s", "0.1"]);
    let names = ServiceNames::new(prefix.clone());
    let node = create_node("hostile-burst-test").expect("node");
    let health = HealthSubscriber::create(&node, &names).expect("health");
    let info = wall_info(good_intrinsics(), unknown_mount());
    let publisher = CloudPublisher::create(&node, &names, &info, 10_000).expect("publisher");
    wait_for_subscriber(&publisher);
    // The first cloud starts the stream; the burst follows once it is
    // estimated (clouds before the first one seen cannot be counted).
    let start = now_ns();
    publisher.publish(&wall_frame(0, start)).expect("published");
    health_until(&health, |h| h.frames_out >= 1).expect("the first estimate");
    for index in 1..200u64 {
        // Stamped 0.6 ms apart, whenever they go out.
        publisher
            .publish(&wall_frame(index, start + index * 600_000))
            .expect("published");
    }
    let report = health_until(&health, |h| h.frames_in >= 200).expect("a health report");
    assert_eq!(report.frames_in, 200, "{report:?}");
    assert_eq!(report.frames_out + report.frames_dropped, 200, "{report:?}");
    assert!(report.frames_out >= 1, "{report:?}");
}

/// Under a file-size limit (`ulimit -f`), slope-convert died of SIGXFSZ
/// (exit 153, no message) and left its `.part`. Now the write fails with
/// "File too large", the run exits 1 and the temporary file is removed.
#[test]
fn a_file_size_limit_is_an_error_that_leaves_nothing_behind() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out.mcap");
    let rec = recording("ramp16");
    // 1 MB: the header and a frame or so.
    let output = Command::new("prlimit")
        .arg("--fsize=1000000")
        .arg("--")
        .arg(slope_integration_tests::binary("slope-convert"))
        .arg(&rec)
        .arg("-o")
        .arg(&out)
        .arg("--no-estimates")
        .output()
        .expect("prlimit runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(
        output.status.code(),
        Some(1),
        "{:?}\n{stderr}",
        output.status
    );
    assert!(stderr.contains("File too large"), "{stderr}");
    let left: Vec<PathBuf> = std::fs::read_dir(dir.path())
        .expect("dir")
        .map(|e| e.expect("entry").path())
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

/// `slope-record --format mcap` under a file-size limit died of SIGXFSZ
/// with a truncated file and no word. Now it says the write failed and
/// what the file holds.
#[test]
fn a_recorder_that_hits_the_size_limit_says_what_the_file_holds() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out.mcap");
    let prefix = unique_prefix("record-efbig");
    let mut record = Command::new("prlimit");
    record
        .arg("--fsize=3000000")
        .arg("--")
        .arg(slope_integration_tests::binary("slope-record"))
        .arg("--service-prefix")
        .arg(&prefix)
        .arg(&out)
        .arg("--wait-timeout-s")
        .arg("30");
    let record = record
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("prlimit runs");
    let _replay = Proc::spawn(
        "slope-replay",
        [
            recording("ramp16").to_str().expect("utf-8"),
            "--service-prefix",
            prefix.as_str(),
            "--rate",
            "10",
            "--loop",
            "--wait-subscribers",
            "1",
        ],
    );
    let output = wait_with_deadline(record, Duration::from_secs(60));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(
        output.status.code(),
        Some(1),
        "{:?}\n{stderr}",
        output.status
    );
    assert!(stderr.contains("File too large"), "{stderr}");
    assert!(stderr.contains("frame(s) recorded before"), "{stderr}");
}

/// Waits for `child` to end within `within`, killing it (and failing) if not.
fn wait_with_deadline(mut child: std::process::Child, within: Duration) -> std::process::Output {
    let until = Instant::now() + within;
    while child.try_wait().expect("try_wait").is_none() {
        if Instant::now() >= until {
            let _ = child.kill();
            panic!("still running after {within:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().expect("output")
}

/// `slope-replay --loop --skip-bad-frames` warned about the same bad frame
/// on every pass (1,100 lines in 5 s at --rate 1000): one warning per bad
/// frame per run now, however many passes.
#[test]
fn a_bad_frame_is_warned_about_once_per_run() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rec = dir.path().join("one-bad");
    copy_recording("ramp16-clean", &rec);
    let csv = std::fs::read_to_string(rec.join("frames.csv")).expect("frames.csv");
    let second = csv.lines().nth(2).expect("a second frame");
    let depth = second.split(',').nth(2).expect("a depth column");
    std::fs::write(rec.join(depth), b"not a png").expect("break it");
    let frames_per_pass = csv.lines().count() - 1;
    let prefix = unique_prefix("bad-once");
    let max_frames = (5 * frames_per_pass).to_string();
    let mut replay = Proc::spawn(
        "slope-replay",
        [
            rec.to_str().expect("utf-8"),
            "--loop",
            "--skip-bad-frames",
            "--rate",
            "1000",
            "--max-frames",
            max_frames.as_str(),
            "--linger-s",
            "0",
            "--service-prefix",
            prefix.as_str(),
        ],
    );
    replay.assert_exits_zero_within(Duration::from_secs(30));
    let warnings = replay
        .stderr_lines()
        .iter()
        .filter(|l| l.contains("skipping bad frame"))
        .count();
    assert_eq!(warnings, 1, "{}", replay.diagnostics());
}

/// The recorder beside the estimator and a 30 Hz replay on this 2-core
/// machine, for `SLOPE_RECORD_SOAK_S` seconds (default 300): it missed 12
/// of 30 clouds under load; now it must miss none. The numbers go into
/// BENCHMARKS.md ("Recording under load"). Heavy (about 15 GB of MCAP in a
/// temporary directory for 5 minutes): `cargo test --release -p
/// slope-integration-tests --test hostile_input -- --ignored --nocapture`.
#[test]
#[ignore]
fn the_recorder_loses_no_cloud_at_30_hz_under_load() {
    let seconds: f64 = std::env::var("SLOPE_RECORD_SOAK_S")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(300.0);
    // `SLOPE_RECORD_SOAK_FORMAT=recording`: a recording directory instead.
    let name = match std::env::var("SLOPE_RECORD_SOAK_FORMAT").as_deref() {
        Ok("recording") => "soak",
        _ => "soak.mcap",
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join(name);
    let prefix = unique_prefix("record-soak");
    let duration = seconds.to_string();
    let _estimator = start_estimator(&prefix, &["--health-interval-s", "1"]);
    let mut record = Proc::spawn(
        "slope-record",
        [
            out.to_str().expect("utf-8"),
            "--service-prefix",
            prefix.as_str(),
            "--duration-s",
            duration.as_str(),
            "--wait-timeout-s",
            "30",
        ],
    );
    let _replay = Proc::spawn(
        "slope-replay",
        [
            recording("ramp16").to_str().expect("utf-8"),
            "--service-prefix",
            prefix.as_str(),
            "--rate",
            "30",
            "--loop",
            "--wait-subscribers",
            "2",
        ],
    );
    let started = Instant::now();
    record.assert_exits_zero_within(Duration::from_secs_f64(seconds + 120.0));
    let elapsed = started.elapsed().as_secs_f64();
    let finished = record
        .stderr_lines()
        .iter()
        .find(|l| l.contains("recording finished"))
        .cloned()
        .unwrap_or_else(|| panic!("no summary\n{}", record.diagnostics()));
    let field = |name: &str| -> u64 {
        finished
            .split_whitespace()
            .find_map(|w| w.strip_prefix(&format!("{name}=")))
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("no {name} in {finished}"))
    };
    let (written, missed) = (field("written"), field("missed"));
    let size_mb = bytes_under(&out) / 1_000_000;
    println!("{finished}");
    println!(
        "recorded {written} clouds in {seconds:.0} s ({elapsed:.0} s with start and finish), \
         missed {missed}, {size_mb} MB"
    );
    assert_eq!(missed, 0, "{finished}");
    assert!(written as f64 >= 0.9 * 30.0 * seconds, "{finished}");
}

/// The bytes of the file `path`, or of every file below the directory.
fn bytes_under(path: &std::path::Path) -> u64 {
    match std::fs::read_dir(path) {
        Ok(entries) => entries
            .flatten()
            .map(|entry| bytes_under(&entry.path()))
            .sum(),
        Err(_) => std::fs::metadata(path).map_or(0, |m| m.len()),
    }
}
