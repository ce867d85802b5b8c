//! Unit tests: every section read, unknown keys and values out of range
//! named, the old layout refused, the printed file read back.

use slope_pipeline::EstimatorConfig;

use super::*;

fn refused(text: &str) -> String {
    SlopeFile::from_toml_str(text)
        .map(|file| panic!("accepted: {file:?}"))
        .unwrap_err()
        .to_string()
}

#[test]
fn every_section_is_read() {
    let file = SlopeFile::from_toml_str(
        "service_prefix = \"robot2\"\n[health]\ninterval_s = 0.5\n\
         [mount]\nheight_m = 0.4\npitch_deg = -20.0\n\
         [capture]\nserial = \"111\"\npipeline = \"cpu\"\ncolor = false\n\
         [estimator]\nmethod = \"tls\"\n[estimator.ransac]\nmax_planes = 12\n",
    )
    .expect("valid");
    assert_eq!(file.service_prefix, "robot2");
    assert_eq!(file.health.interval_s, 0.5);
    assert_eq!(
        (
            file.mount.height_m,
            file.mount.pitch_deg,
            file.mount.roll_deg
        ),
        (Some(0.4), Some(-20.0), None)
    );
    assert_eq!(file.capture.serial.as_deref(), Some("111"));
    assert_eq!(file.capture.pipeline, "cpu");
    assert!(!file.capture.color);
    assert_eq!(file.capture.max_depth_m, 4.5);
    assert_eq!(file.estimator.method, slope_ipc_types::SlopeMethod::Tls);
    assert_eq!(file.estimator.ransac.max_planes, Some(12));
    assert_eq!(
        SlopeFile::from_toml_str("").expect("empty"),
        SlopeFile::default()
    );
}

#[test]
fn unknown_keys_are_named_with_their_full_path() {
    let message = refused("[estimator]\nseed = 1\n[estimator.ransac]\nmax_planez = 12\n");
    assert!(
        message.starts_with("`estimator.ransac.max_planez` (line 4)"),
        "{message}"
    );
    assert!(
        message.contains("max_planes"),
        "the keys it expects: {message}"
    );
    let message = refused("[capture]\nserail = \"1\"\n");
    assert!(
        message.starts_with("`capture.serail` (line 2)"),
        "{message}"
    );
    let message = refused("[estimator.ransak]\nmax_planes = 12\n");
    assert!(message.starts_with("`estimator.ransak`"), "{message}");
    let message = refused("prefix = \"x\"\n");
    assert!(message.starts_with("`prefix` (line 1)"), "{message}");
    let message = refused("[mount]\nheight_m = \"high\"\n");
    assert!(
        message.starts_with("`mount.height_m` (line 2)"),
        "{message}"
    );
}

#[test]
fn values_out_of_range_are_named_with_their_range() {
    for (text, key, range) in [
        (
            "[mount]\npitch_deg = 400.0\n",
            "`mount.pitch_deg` = 400",
            "at most 90",
        ),
        (
            "[mount]\nheight_m = 0.0\n",
            "`mount.height_m` = 0",
            "above 0",
        ),
        (
            "[mount]\nheight_m = nan\n",
            "`mount.height_m` = NaN",
            "above 0",
        ),
        (
            "[mount]\nheight_m = 0.4\npitch_deg = nan\n",
            "`mount.pitch_deg` = NaN",
            "at most 90",
        ),
        (
            "[mount]\nroll_deg = -inf\n",
            "`mount.roll_deg` = -inf",
            "at most 180",
        ),
        (
            "[health]\ninterval_s = 0.01\n",
            "`health.interval_s` = 0.01",
            "from 0.05 to 3600",
        ),
        (
            "[capture]\npipeline = \"vulkan\"\n",
            "`capture.pipeline` = \"vulkan\"",
            "one of default, cpu",
        ),
        (
            "[capture]\nmin_depth_m = 0.0\n",
            "`capture.min_depth_m` = 0",
            "from 0.001 to 10000000 m",
        ),
        (
            "[capture]\nmax_depth_m = inf\n",
            "`capture.max_depth_m` = inf",
            "from 0.001 to 10000000 m",
        ),
        (
            "[capture]\nmax_depth_m = nan\n",
            "`capture.max_depth_m` = NaN",
            "from 0.001 to 10000000 m",
        ),
        (
            "[capture]\nframe_timeout_s = 0.0\n",
            "`capture.frame_timeout_s` = 0",
            "from 0.001",
        ),
        (
            "service_prefix = \"/x\"\n",
            "`service_prefix` = \"/x\"",
            "no leading or trailing",
        ),
        (
            "service_prefix = \"\"\n",
            "`service_prefix` = \"\"",
            "leave the key out for the default 'slope'",
        ),
        (
            "[estimator.normals]\nneighbours = 2\n",
            "`estimator.normals.neighbours` = 2",
            "must be in 3..=1000",
        ),
        (
            "[estimator.ransac]\nconfidence = 1.5\n",
            "`estimator.ransac.confidence` = 1.5",
            "0",
        ),
    ] {
        let message = refused(text);
        assert!(message.starts_with(key), "{text}: {message}");
        assert!(message.contains(range), "{text}: {message}");
    }
}

/// Whichever of the two keys was set, the message names both with
/// their values.
#[test]
fn keys_out_of_order_are_both_named() {
    for text in [
        "[capture]\nmax_depth_m = 0.2\n",
        "[capture]\nmin_depth_m = 0.5\nmax_depth_m = 0.2\n",
    ] {
        assert_eq!(
            refused(text),
            "`capture.max_depth_m` = 0.2 must be above `capture.min_depth_m` = 0.5",
            "{text}"
        );
    }
    assert_eq!(
        refused("[capture]\nmin_depth_m = 5.0\n"),
        "`capture.max_depth_m` = 4.5 must be above `capture.min_depth_m` = 5"
    );
    assert_eq!(
        refused("[capture]\nmin_depth_m = 2.0\nmax_depth_m = 2.0\n"),
        "`capture.max_depth_m` = 2 must be above `capture.min_depth_m` = 2"
    );
}

#[test]
fn an_old_layout_says_how_to_fix_it() {
    let message = refused("method = \"tls\"\n");
    assert!(
        message.contains("move `method` under [estimator]"),
        "{message}"
    );
    let message = refused("seed = 3\n[ransac]\nmax_planes = 4\n");
    assert!(message.contains("`seed`"), "{message}");
    let message = refused("[ransac]\nmax_planes = 4\n");
    assert!(
        message.contains("rename [ransac] to [estimator.ransac]"),
        "{message}"
    );
    let message = refused("[kinect2]\nserial = \"1\"\n");
    assert!(
        message.starts_with("`kinect2` (line 1): ")
            && message.contains("rename [kinect2] to [capture]"),
        "{message}"
    );
    let message = refused("# the camera\n\n[kinect2.more]\nserial = \"1\"\n");
    assert!(message.starts_with("`kinect2` (line 3): "), "{message}");
    let message = refused("service_prefix = \"x\"\nkinect2.serial = \"1\"\n");
    assert!(message.starts_with("`kinect2` (line 2): "), "{message}");
    // Quoted: found by the parser, not by the line scan; no line then.
    let message = refused("[\"kinect2\"]\nserial = \"1\"\n");
    assert!(message.starts_with("`kinect2`: "), "{message}");
    assert!(!message.contains("line 0"), "{message}");
}

#[test]
fn the_printed_file_parses_back_to_the_same_configuration() {
    let mut file = SlopeFile::from_toml_str(
        "service_prefix = \"robot2\"\n[mount]\nroll_deg = 2.5\n[capture]\ndevice_index = 1\n",
    )
    .expect("valid");
    file.estimator.seed = 9;
    let printed = file.to_toml().expect("serialises");
    assert_eq!(SlopeFile::from_toml_str(&printed).expect("parses"), file);
    assert!(printed.contains("[estimator.normals]"), "{printed}");
}

#[test]
fn the_shipped_paper_literal_preset_is_a_daemon_config_file() {
    let text = include_str!("../../../../pipeline/presets/paper-literal.toml");
    let file = SlopeFile::from_toml_str(text).expect("valid");
    assert_eq!(file.estimator, EstimatorConfig::paper_literal());
    assert_eq!(
        SlopeFile {
            estimator: EstimatorConfig::default(),
            ..file
        },
        SlopeFile::default()
    );
}

#[test]
fn a_missing_default_file_means_the_defaults() {
    let dir = tempfile::tempdir().expect("temp dir");
    let default = dir.path().join("slope.toml");
    assert_eq!(config_path(None, &default), None);
    std::fs::write(&default, "[estimator]\nseed = 7\n").expect("write");
    assert_eq!(config_path(None, &default), Some(default.clone()));
    let load = |path: &std::path::Path| {
        SlopeFile::load_or_stop(Some(path), &slope_sensor::publish::StopFlag::new())
    };
    let file = load(&default).expect("valid").expect("not stopped");
    assert_eq!(file.estimator.seed, 7);
    let given = dir.path().join("other.toml");
    assert_eq!(config_path(Some(&given), &default), Some(given.clone()));
    let err = load(&given).expect_err("no such file");
    assert!(err.to_string().contains("other.toml"), "{err}");
}

#[test]
fn the_ros2_section_is_read_and_its_names_checked_as_ros_2_does() {
    let file = SlopeFile::from_toml_str(
        "[ros2]\nnamespace = \"/robot1\"\ndomain_id = 7\nbase_frame = \"base_link\"\n",
    )
    .expect("valid");
    assert_eq!(file.ros2.namespace, "/robot1");
    assert_eq!(file.ros2.domain_id, Some(7));
    assert_eq!(file.ros2.base_frame.as_deref(), Some("base_link"));
    assert_eq!(file.ros2.frame_id, "slope_camera");
    for (text, key) in [
        ("namespace = \"robot1\"", "`ros2.namespace` = \"robot1\""),
        ("node_name = \"slope-ros2\"", "`ros2.node_name`"),
        (
            "domain_id = 233",
            "`ros2.domain_id` = 233: must be a DDS domain id from 0 to 232",
        ),
        ("frame_id = \"/cam\"", "`ros2.frame_id`"),
        ("base_frame = \"base link\"", "`ros2.base_frame`"),
    ] {
        let err = refused(&format!("[ros2]\n{text}\n"));
        assert!(err.contains(key), "{text}: {err}");
    }
}

/// A read that blocks in the kernel (a stalled network mount) held a daemon
/// past its stop request: a stop requested while the read blocks ends the
/// wait (that it does so within a slice is counted in
/// `slope_sensor::interruptible`'s tests), and the same load, unblocked,
/// reads the file. A load that ignored the stop fails the test at a
/// deadline instead of hanging it.
#[test]
fn a_stop_request_ends_the_wait_for_a_config_read_that_blocks() {
    use std::sync::mpsc;
    use std::time::Duration;

    use slope_sensor::publish::StopFlag;

    /// Past this, the load ignored the stop (no speed is asserted).
    const DEADLINE: Duration = Duration::from_secs(60);

    let path = std::path::Path::new("/mnt/stalled/slope.toml");
    let stop = StopFlag::new();
    let (release, blocked) = mpsc::channel::<()>();
    let (started_tx, started) = mpsc::channel::<()>();
    let stopper = stop.clone();
    // The stop is requested once the read is blocked.
    let requested = std::thread::spawn(move || {
        started.recv_timeout(DEADLINE).expect("the read starts");
        stopper.stop();
    });
    let (outcome_tx, outcome_rx) = mpsc::channel();
    std::thread::spawn(move || {
        let outcome = SlopeFile::load_with(Some(path), &stop, move |_| {
            let _ = started_tx.send(());
            // Blocks until the test releases it (or drops the sender).
            let _ = blocked.recv();
            Ok(String::new())
        });
        let _ = outcome_tx.send(outcome.map(|file| file.is_none()));
    });
    let stopped = outcome_rx
        .recv_timeout(DEADLINE)
        .unwrap_or_else(|e| panic!("the load did not end on the stop request: {e}"))
        .expect("no error");
    requested.join().expect("stopper");
    assert!(stopped, "the load gave a file, not the stop");
    drop(release);

    let read = SlopeFile::load_with(Some(path), &StopFlag::new(), |_| {
        Ok("[estimator]\nseed = 9\n".to_string())
    })
    .expect("valid")
    .expect("not stopped");
    assert_eq!(read.estimator.seed, 9);
    let err = SlopeFile::load_with(Some(path), &StopFlag::new(), |_| {
        Err(std::io::Error::other("stale file handle"))
    })
    .expect_err("a read error");
    assert!(
        chain_of(&err).contains("/mnt/stalled/slope.toml: stale file handle"),
        "{}",
        chain_of(&err)
    );
}

/// `err` and its causes, joined by ": ".
fn chain_of(err: &dyn std::error::Error) -> String {
    let mut text = err.to_string();
    let mut cause = err.source();
    while let Some(next) = cause {
        text.push_str(&format!(": {next}"));
        cause = next.source();
    }
    text
}
