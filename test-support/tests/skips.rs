//! Every test that can skip is listed in `skips.txt`, and every skip goes
//! through `slope_test_support` (`shared_data`, `require`): a new test that
//! can skip, or a skip that goes around the helpers (and so would pass in
//! CI without testing anything), fails here until it is listed or routed.
//!
//! The scan is textual: in every `.rs` file of the workspace, a function
//! that calls `shared_data(` or `require(`, or (transitively) a function
//! that does, can skip. Comments are left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use slope_test_support::repo_root;

/// The helpers a skip goes through.
const HELPERS: [&str; 2] = ["shared_data", "require"];

/// The checked-in list: `path::function` per line, `#` comments.
const LIST: &str = include_str!("../skips.txt");

/// Every `.rs` file under `dir`, outside build output and hidden folders.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.expect("a directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if name.starts_with('.') || name == "target" {
            continue;
        }
        if path.is_dir() {
            rust_files(&path, out);
        } else if name.ends_with(".rs") {
            out.push(path);
        }
    }
}

/// A file's code lines: comments (`//` to the end of a line) left out.
fn code_lines(text: &str) -> Vec<String> {
    text.lines()
        .map(|line| {
            let trimmed = line.trim_start();
            if trimmed.starts_with("//") {
                return String::new();
            }
            // A trailing comment (not `://` inside a string).
            match line.find(" // ") {
                Some(at) => line[..at].to_string(),
                None => line.to_string(),
            }
        })
        .collect()
}

/// The identifiers of `line` that are called: `name(` or `name::<`, not
/// a method (`.name(`) nor a definition (`fn name(`).
fn calls(line: &str) -> Vec<String> {
    let bytes = line.as_bytes();
    let mut found = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
            let name = &line[start..i];
            let called = line[i..].starts_with('(') || line[i..].starts_with("::<");
            let method = start > 0 && bytes[start - 1] == b'.';
            let defined = line[..start].trim_end().ends_with("fn");
            if called && !method && !defined {
                found.push(name.to_string());
            }
        } else {
            i += 1;
        }
    }
    found
}

/// The function a line belongs to: the name after the last `fn `.
fn defined_fn(line: &str) -> Option<String> {
    let at = line.find("fn ")?;
    if at > 0
        && (line.as_bytes()[at - 1].is_ascii_alphanumeric() || line.as_bytes()[at - 1] == b'_')
    {
        return None;
    }
    let rest = &line[at + 3..];
    let name: String = rest
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
        .collect();
    (!name.is_empty()).then_some(name)
}

/// Every workspace `.rs` file but the helpers' own, with its path from the
/// repository root.
fn sources() -> Vec<(String, String)> {
    let root = repo_root();
    let mut files = Vec::new();
    rust_files(root, &mut files);
    files
        .into_iter()
        .filter_map(|path| {
            let relative = path
                .strip_prefix(root)
                .expect("under the root")
                .to_string_lossy()
                .replace('\\', "/");
            if relative.starts_with("test-support/") {
                return None;
            }
            let text = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            Some((relative, text))
        })
        .collect()
}

/// Files of helpers that tests in other files call: a function there that
/// can skip makes its callers anywhere able to skip. Elsewhere a function
/// makes only the callers in its own file able to skip (names like `run`
/// or `estimate` recur from file to file).
fn is_shared_helper(path: &str) -> bool {
    path.starts_with("tests/src/") || path.contains("/tests/common/")
}

/// `path::function` of every function that can skip.
fn functions_that_can_skip() -> BTreeSet<String> {
    // Per function: its file and the names it calls.
    let mut functions: Vec<(String, String, BTreeSet<String>)> = Vec::new();
    for (path, text) in sources() {
        let mut current: Option<usize> = None;
        for line in code_lines(&text) {
            if let Some(name) = defined_fn(&line) {
                functions.push((path.clone(), name, BTreeSet::new()));
                current = Some(functions.len() - 1);
            }
            if let Some(k) = current {
                functions[k].2.extend(calls(&line));
            }
        }
    }
    // Names that can skip wherever they are called, and per file.
    let mut everywhere: BTreeSet<String> = HELPERS.iter().map(|h| h.to_string()).collect();
    let mut in_file: BTreeSet<(String, String)> = BTreeSet::new();
    let mut listed = BTreeSet::new();
    loop {
        let before = listed.len();
        for (path, name, called) in &functions {
            let skips = called
                .iter()
                .any(|c| everywhere.contains(c) || in_file.contains(&(path.clone(), c.clone())));
            if skips {
                listed.insert(format!("{path}::{name}"));
                if is_shared_helper(path) {
                    everywhere.insert(name.clone());
                }
                in_file.insert((path.clone(), name.clone()));
            }
        }
        if listed.len() == before {
            return listed;
        }
    }
}

#[test]
fn every_test_that_can_skip_is_listed() {
    let expected: BTreeSet<String> = LIST
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(str::to_string)
        .collect();
    let found = functions_that_can_skip();
    let unlisted: Vec<_> = found.difference(&expected).collect();
    let gone: Vec<_> = expected.difference(&found).collect();
    assert!(
        unlisted.is_empty() && gone.is_empty(),
        "test-support/skips.txt is not the list of functions that can skip.\n\
         can skip, not listed: {unlisted:#?}\nlisted, cannot skip: {gone:#?}\n\
         the list as it is now:\n{}",
        found.iter().cloned().collect::<Vec<_>>().join("\n")
    );
}

/// No test reads the CI variables itself, nor prints a skip of its own:
/// both belong to the helpers, so that every skip fails in CI.
#[test]
fn no_skip_goes_around_the_helpers() {
    let mut found: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for (path, text) in sources() {
        let lines = code_lines(&text);
        for (k, line) in lines.iter().enumerate() {
            let reads_ci = line.contains("\"SLOPE_REQUIRE_")
                || line.contains("var_os(\"CI\")")
                || line.contains("var(\"CI\")");
            let prints = line.contains("println!(") || line.contains("eprintln!(");
            let said = lines[k..(k + 3).min(lines.len())].join(" ").to_lowercase();
            let prints_a_skip = prints
                && (said.contains("skipping")
                    || said.contains("skipped:")
                    || said.contains("skipped "))
                && !said.contains("skipped by the estimator");
            if reads_ci || prints_a_skip {
                found
                    .entry(path.clone())
                    .or_default()
                    .push(format!("{}: {}", k + 1, line.trim()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "skips that go around slope_test_support (use shared_data or require): {found:#?}"
    );
}

/// The scan itself: calls, definitions and comments.
#[test]
fn the_scan_finds_calls_and_definitions() {
    assert_eq!(
        calls("let Some(d) = common::shared_data(name) else { x.require(1) };"),
        ["Some", "shared_data"]
    );
    assert_eq!(
        calls("pub fn shared_data(name: &str) {"),
        Vec::<String>::new()
    );
    assert_eq!(
        defined_fn("    pub fn venv_python() -> Option<PathBuf> {"),
        Some("venv_python".into())
    );
    assert_eq!(defined_fn("let f = define(1);"), None);
    assert_eq!(
        code_lines("a(); // shared_data(\n// require(x)"),
        ["a();", ""]
    );
}
