//! Fuzzing the config file parser (property tests, in the default test
//! run): arbitrary text and structured mutations of a file that sets every
//! key. Every input is a valid file or an error naming what is wrong, never
//! a panic; what parses is in range and writes back to the same settings.
//! `SLOPE_FUZZ_CASES=N` runs N cases per property.

use proptest::prelude::*;
use proptest::test_runner::Config;
use slope_tools::config_file::SlopeFile;

fn config(default: u32) -> Config {
    let cases = std::env::var("SLOPE_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(default);
    Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    }
}

/// Every key, as `--print-config` writes it.
fn full_file() -> String {
    SlopeFile::default().to_toml().expect("the defaults write")
}

const HOSTILE_VALUES: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "1e308",
    "5e-324",
    "18446744073709551616",
    "\"\"",
    "\"probe\u{e9}\"",
    "\"\\u001b[2J\"",
    "[]",
    "{}",
    "true",
    "[1.0, 0.5]",
    "[0.5, 4.5]",
    "\"kinect1\"",
    "\"tls\"",
];

/// One edit of a line of the file.
#[derive(Debug, Clone)]
enum Edit {
    /// The value of line `nth` (if it has one) replaced.
    Value { nth: usize, value: &'static str },
    /// Line `nth` removed.
    Remove { nth: usize },
    /// Line `nth` repeated (a duplicate key).
    Duplicate { nth: usize },
    /// Arbitrary characters inserted into line `nth`.
    Insert { nth: usize, at: usize, text: String },
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        3 => (any::<usize>(), prop::sample::select(HOSTILE_VALUES))
            .prop_map(|(nth, value)| Edit::Value { nth, value }),
        1 => any::<usize>().prop_map(|nth| Edit::Remove { nth }),
        1 => any::<usize>().prop_map(|nth| Edit::Duplicate { nth }),
        1 => (any::<usize>(), any::<usize>(), ".{0,6}").prop_map(|(nth, at, text)| Edit::Insert { nth, at, text }),
    ]
}

fn apply(text: &str, edits: &[Edit]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for edit in edits {
        if lines.is_empty() {
            break;
        }
        let n = lines.len();
        match edit {
            Edit::Value { nth, value } => {
                let line = &mut lines[nth % n];
                if let Some((key, _)) = line.split_once('=') {
                    *line = format!("{key}= {value}");
                }
            }
            Edit::Remove { nth } => {
                lines.remove(nth % n);
            }
            Edit::Duplicate { nth } => {
                let line = lines[nth % n].clone();
                lines.insert(nth % n, line);
            }
            Edit::Insert { nth, at, text } => {
                let line = &mut lines[nth % n];
                let mut cut = at % (line.len() + 1);
                while !line.is_char_boundary(cut) {
                    cut -= 1;
                }
                line.insert_str(cut, text);
            }
        }
    }
    lines.join("\n")
}

/// What parses is valid and writes back to the same settings.
fn check(text: &str) -> Result<(), TestCaseError> {
    match SlopeFile::from_toml_str(text) {
        Ok(file) => {
            prop_assert!(file.validate().is_ok());
            let written = file.to_toml().expect("a parsed file writes");
            let back = SlopeFile::from_toml_str(&written).expect("what is written parses");
            prop_assert_eq!(back.to_toml().expect("writes"), written);
        }
        Err(err) => prop_assert!(!err.to_string().is_empty()),
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(512))]

    #[test]
    fn mutated_config_files_parse_or_are_refused(edits in prop::collection::vec(edit(), 1..5)) {
        check(&apply(&full_file(), &edits))?;
    }

    #[test]
    fn arbitrary_text_parses_or_is_refused(text in any::<String>()) {
        check(&text)?;
    }
}

/// The mutations reach the range checks: a hostile value on a line of the
/// full file is mostly refused (some values fit some keys).
#[test]
fn hostile_values_are_mostly_refused() {
    let text = full_file();
    let lines = text.lines().filter(|l| l.contains('=')).count();
    let (mut refused, mut tried) = (0, 0);
    for nth in 0..text.lines().count() {
        for value in ["nan", "-1", "\"probe\u{e9}\""] {
            let edited = apply(&text, &[Edit::Value { nth, value }]);
            if edited != text {
                tried += 1;
                refused += usize::from(SlopeFile::from_toml_str(&edited).is_err());
            }
        }
    }
    assert!(tried >= lines, "{tried} edits of {lines} keys");
    assert!(refused * 2 > tried, "{refused} of {tried} refused");
}
