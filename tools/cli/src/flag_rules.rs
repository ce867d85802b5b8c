//! The flag rules every slope program follows ("one voice"), checked over a
//! program's clap [`Command`] by the tests of each crate that has programs:
//!
//! - `-v/--verbose` (counted) and `-q/--quiet`;
//! - a file or directory written is `-o/--output` (an older spelling may
//!   stay as a hidden alias), and no other visible flag is named `out...`;
//! - `--max-frames` and `--count` refuse 0 with one message ([`max_frames_arg`]:
//!   at least 1, no flag for no limit);
//! - angles (`...-deg` flags, `DEG` values) take negative numbers;
//! - a flag named with its unit (`...-s`, `-ms`, `-m`, `-deg`, `-hz`,
//!   `-mps`) shows that unit as its value (`S`, `MS`, `M`, `DEG`, `HZ`,
//!   `M/S`) and takes a negative number as a value, so that its range check
//!   answers (`--linger-s -1`), not "unexpected argument".
//!
//! [`max_frames_arg`]: crate::cli::max_frames_arg

use clap::error::ErrorKind;
use clap::{ArgAction, Command};

pub use crate::cli::MAX_FRAMES_ZERO;

/// Every rule `command` breaks, one line each; empty when it follows them.
pub fn violations(command: &Command) -> Vec<String> {
    let name = command.get_name().to_string();
    let mut found = Vec::new();
    for (long, short, counted) in [("verbose", 'v', true), ("quiet", 'q', false)] {
        match command.get_arguments().find(|a| a.get_long() == Some(long)) {
            None => found.push(format!("{name}: no --{long}")),
            Some(arg) => {
                if arg.get_short() != Some(short) {
                    found.push(format!("{name}: --{long} is not -{short}"));
                }
                if counted && !matches!(arg.get_action(), ArgAction::Count) {
                    found.push(format!("{name}: --{long} does not count (-vv)"));
                }
            }
        }
    }
    for arg in command.get_arguments().filter(|a| !a.is_hide_set()) {
        let long = arg.get_long().unwrap_or_default();
        if long == "output" && arg.get_short() != Some('o') {
            found.push(format!("{name}: --output is not -o"));
        }
        if long != "output" && long.starts_with("out") {
            found.push(format!("{name}: --{long} should be -o/--output"));
        }
        if arg.is_positional() && arg.get_id().as_str().starts_with("out") {
            found.push(format!(
                "{name}: the positional {} should be -o/--output",
                arg.get_id()
            ));
        }
        if long == "max-frames" || long == "count" {
            found.extend(zero_refused(command, long));
        }
        let angle = long.ends_with("-deg")
            || arg
                .get_value_names()
                .is_some_and(|names| names.iter().any(|n| n.as_str() == "DEG"));
        let unit = UNITS.iter().find(|(suffix, _)| long.ends_with(suffix));
        if let Some((suffix, value)) = unit {
            let names = arg.get_value_names().unwrap_or_default();
            if !names.iter().all(|n| n.as_str() == *value) || names.is_empty() {
                found.push(format!(
                    "{name}: --{long} shows <{}>, not its unit <{value}>",
                    names
                        .iter()
                        .map(|n| n.as_str())
                        .collect::<Vec<_>>()
                        .join(" ")
                ));
            }
            if *suffix != "-deg" {
                found.extend(negative_taken(command, long));
            }
        }
        if angle && !long.is_empty() {
            found.extend(negative_taken(command, long));
        }
    }
    found
}

/// Flag-name suffixes that are units, and the value name each shows.
const UNITS: [(&str, &str); 6] = [
    ("-s", "S"),
    ("-ms", "MS"),
    ("-m", "M"),
    ("-deg", "DEG"),
    ("-hz", "HZ"),
    ("-mps", "M/S"),
];

/// `--<long> 0` is refused with [`MAX_FRAMES_ZERO`].
fn zero_refused(command: &Command, long: &str) -> Option<String> {
    let name = command.get_name();
    let flag = format!("--{long}");
    match command
        .clone()
        .try_get_matches_from([name, flag.as_str(), "0"])
    {
        Err(err) if err.kind() == ErrorKind::ValueValidation => {
            let text = err.render().to_string();
            (!text.contains(MAX_FRAMES_ZERO)).then(|| {
                format!("{name}: {flag} 0 is refused, but not with the shared message: {text}")
            })
        }
        _ => Some(format!("{name}: {flag} 0 is not refused as a bad value")),
    }
}

/// `--<long> -5` is read as a value, not as an unknown flag.
fn negative_taken(command: &Command, long: &str) -> Option<String> {
    let name = command.get_name();
    let flag = format!("--{long}");
    match command
        .clone()
        .try_get_matches_from([name, flag.as_str(), "-5"])
    {
        Err(err) if matches!(err.kind(), ErrorKind::UnknownArgument | ErrorKind::NoEquals) => {
            Some(format!("{name}: {flag} -5 is not taken as a value"))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use clap::{Arg, ArgAction, Command};

    use super::*;

    /// The checks can fail: a program that breaks each rule is caught.
    #[test]
    fn a_program_that_breaks_the_rules_is_caught() {
        let bad = Command::new("slope-bad")
            .arg(
                Arg::new("verbose")
                    .long("verbose")
                    .action(ArgAction::SetTrue),
            )
            .arg(Arg::new("out_dir").long("out-dir"))
            .arg(
                Arg::new("max_frames")
                    .long("max-frames")
                    .value_parser(clap::value_parser!(u64)),
            )
            .arg(
                Arg::new("pitch")
                    .long("pitch-deg")
                    .value_parser(clap::value_parser!(f64)),
            )
            .arg(
                Arg::new("linger")
                    .long("linger-s")
                    .value_name("LINGER")
                    .value_parser(clap::value_parser!(f64)),
            );
        let found = violations(&bad);
        for expected in [
            "slope-bad: --verbose is not -v",
            "slope-bad: --verbose does not count (-vv)",
            "slope-bad: no --quiet",
            "slope-bad: --out-dir should be -o/--output",
            "slope-bad: --max-frames 0 is not refused as a bad value",
            "slope-bad: --pitch-deg -5 is not taken as a value",
            "slope-bad: --pitch-deg shows <>, not its unit <DEG>",
            "slope-bad: --linger-s shows <LINGER>, not its unit <S>",
            "slope-bad: --linger-s -5 is not taken as a value",
        ] {
            assert!(
                found.iter().any(|f| f == expected),
                "{expected} not in {found:?}"
            );
        }
        assert_eq!(found.len(), 9, "{found:?}");
    }
}
