//! One voice: every slope program follows the flag rules of
//! `slope_tools::flag_rules` (-v/-q, -o/--output, --max-frames refusing 0
//! with one message, negative angles). A program added to `src/bin/` must
//! be listed here, so a new tool that breaks the rules fails too; so must
//! the programs of slope-synth (`slope-synth`, `slope-bend`), checked in
//! `every_synth_program_is_checked`. (slope-bridge is checked in its own
//! crate, with the zenoh feature.)

use clap::{Command, CommandFactory};
use slope_tools::flag_rules::violations;

fn commands() -> Vec<Command> {
    #[allow(unused_mut)] // slope-capture only with the kinect2 feature
    let mut all = vec![
        slope_tools::convert::ConvertArgs::command(),
        slope_tools::demo::DemoArgs::command(),
        slope_tools::echo::EchoArgs::command(),
        slope_tools::estimator::EstimatorArgs::command(),
        slope_tools::eval::EvalArgs::command(),
        slope_tools::record::RecordArgs::command(),
        slope_tools::replay::ReplayArgs::command(),
        slope_synth::Args::command(),
        slope_synth::bend::cli::BendArgs::command(),
    ];
    #[cfg(feature = "kinect2")]
    all.push(slope_tools::capture::CaptureArgs::command());
    all
}

#[test]
fn every_program_follows_the_flag_rules() {
    let found: Vec<String> = commands().iter().flat_map(violations).collect();
    assert!(found.is_empty(), "{}", found.join("\n"));
}

#[test]
fn every_program_is_checked() {
    let checked: Vec<String> = commands()
        .iter()
        .map(|c| c.get_name().to_string())
        .collect();
    let bin_dir = concat!(env!("CARGO_MANIFEST_DIR"), "/src/bin");
    let mut programs = 0;
    for entry in std::fs::read_dir(bin_dir).expect("src/bin") {
        let path = entry.expect("entry").path();
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .expect("a program's name");
        programs += 1;
        if name == "slope-capture" && cfg!(not(feature = "kinect2")) {
            continue;
        }
        assert!(
            checked.iter().any(|c| c == name),
            "{name} is not in commands(): add it"
        );
    }
    assert!(programs >= 8, "{programs} programs in {bin_dir}");
}

/// slope-synth's programs (its `[[bin]]`s) are in `commands()` too.
#[test]
fn every_synth_program_is_checked() {
    let checked: Vec<String> = commands()
        .iter()
        .map(|c| c.get_name().to_string())
        .collect();
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/../synth/Cargo.toml");
    let text = std::fs::read_to_string(manifest).expect("tools/synth/Cargo.toml");
    let table: toml::Table = text.parse().expect("a TOML manifest");
    let bins = table
        .get("bin")
        .and_then(|b| b.as_array())
        .expect("[[bin]] entries");
    for bin in bins {
        let name = bin
            .get("name")
            .and_then(|n| n.as_str())
            .expect("a bin's name");
        assert!(
            checked.iter().any(|c| c == name),
            "{name} (tools/synth) is not in commands(): add it"
        );
    }
    assert!(bins.len() >= 2, "{} programs in {manifest}", bins.len());
}

/// The rules in action on the programs themselves.
#[test]
fn the_shared_rules_hold_on_the_command_line() {
    use slope_tools::cli::MAX_FRAMES_ZERO;
    let replay = slope_tools::replay::ReplayArgs::command();
    let err = replay
        .try_get_matches_from(["slope-replay", "REC", "--max-frames", "0"])
        .expect_err("0 frames");
    assert!(err.to_string().contains(MAX_FRAMES_ZERO), "{err}");
    let synth = slope_synth::Args::try_parse_from(["slope-synth", "-o", "x", "--slope", "-5"])
        .expect("a descending slope");
    assert_eq!(synth.slope, Some(-5.0));
    use clap::Parser;
    let convert = slope_tools::convert::ConvertArgs::try_parse_from([
        "slope-convert",
        "REC",
        "-o",
        "out.mcap",
        "-q",
    ])
    .expect("-o and -q");
    assert_eq!(convert.output(), std::path::Path::new("out.mcap"));
    assert!(convert.log.quiet);
    let old = slope_tools::convert::ConvertArgs::try_parse_from(["slope-convert", "REC", "o.mcap"])
        .expect("the output without -o still works");
    assert_eq!(old.output(), std::path::Path::new("o.mcap"));
}
