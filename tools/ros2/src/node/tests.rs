//! Unit tests of the node's flags and settings (no DDS).

use clap::{CommandFactory, Parser};

use super::args::Ros2Args;
use super::settings::Settings;
use slope_sensor::publish::StopFlag;

/// slope-ros2 speaks with the voice of every slope program
/// (`slope_tools::flag_rules`).
#[test]
fn the_node_follows_the_flag_rules() {
    let found = slope_tools::flag_rules::violations(&Ros2Args::command());
    assert!(found.is_empty(), "{}", found.join("\n"));
}

fn settings(flags: &[&str], file: &str) -> Settings {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("slope.toml");
    std::fs::write(&path, file).expect("write");
    let mut argv = vec!["slope-ros2", "--config", path.to_str().expect("utf-8")];
    argv.extend_from_slice(flags);
    let args = Ros2Args::try_parse_from(argv).expect("flags");
    Settings::with_default_file(&args, &dir.path().join("none.toml"), &StopFlag::new())
        .expect("settings")
        .expect("not stopped")
}

#[test]
fn flags_win_over_the_file_and_the_file_over_the_defaults() {
    let defaults = settings(&[], "");
    assert_eq!(
        (
            defaults.namespace.as_str(),
            defaults.node_name.as_str(),
            defaults.frame_id.as_str()
        ),
        ("/", "slope_ros2", "slope_camera")
    );
    assert_eq!(defaults.base_frame, None);
    let file = "service_prefix = \"robot\"\n[ros2]\nnamespace = \"/a\"\nframe_id = \"cam\"\n\
                base_frame = \"base_link\"\ndomain_id = 9\n[mount]\nheight_m = 0.4\n";
    let from_file = settings(&[], file);
    assert_eq!(from_file.service_prefix, "robot");
    assert_eq!(
        (from_file.namespace.as_str(), from_file.frame_id.as_str()),
        ("/a", "cam")
    );
    assert_eq!(from_file.base_frame.as_deref(), Some("base_link"));
    assert_eq!(from_file.discovery.domain_id, 9);
    assert_eq!(from_file.mount.height_m, Some(0.4));
    let flagged = settings(
        &["--namespace", "/b", "--domain-id", "3", "--frame-id", "k"],
        file,
    );
    assert_eq!(
        (flagged.namespace.as_str(), flagged.frame_id.as_str()),
        ("/b", "k")
    );
    assert_eq!(flagged.discovery.domain_id, 3);
}

#[test]
fn bad_names_are_usage_errors_that_say_what_is_expected() {
    for (flag, value, says) in [
        ("--namespace", "robot1", "not a ROS 2 namespace"),
        ("--node-name", "slope-ros2", "not a ROS 2 node name"),
        ("--frame-id", "/cam", "not a TF frame id"),
        ("--domain-id", "300", "from 0 to 232"),
    ] {
        let err = Ros2Args::try_parse_from(["slope-ros2", flag, value]).unwrap_err();
        assert!(err.to_string().contains(says), "{flag} {value}: {err}");
    }
}
