//! slope-import follows the flag rules of every slope program
//! (`slope_tools::flag_rules`: -v/-q, -o/--output, negative angles).

use clap::{CommandFactory, Parser};
use slope_import::ImportArgs;
use slope_tools::flag_rules::violations;

#[test]
fn slope_import_follows_the_flag_rules() {
    let found = violations(&ImportArgs::command());
    assert!(found.is_empty(), "{}", found.join("\n"));
}

#[test]
fn a_negative_pitch_and_the_list_without_output_parse() {
    let args = ImportArgs::try_parse_from([
        "slope-import",
        "x.bag",
        "-o",
        "rec",
        "--mount-pitch-deg",
        "-20",
    ])
    .expect("parses");
    assert_eq!(args.mount.pitch_deg, Some(-20.0));
    assert!(ImportArgs::try_parse_from(["slope-import", "x.bag", "--list"]).is_ok());
    let err = ImportArgs::try_parse_from(["slope-import", "x.bag"]).expect_err("no output");
    assert!(err.to_string().contains("--output"), "{err}");
    let err = ImportArgs::try_parse_from(["slope-import", "x.bag", "-o", "r", "--every", "0"])
        .expect_err("every 0");
    assert!(err.to_string().contains("at least 1"), "{err}");
}
