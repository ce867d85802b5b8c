//! The conffile the Debian package installs as `/etc/slope/slope.toml`
//! (`packaging/slope.toml`) cannot drift from the daemons: as shipped it
//! parses to the defaults; with every `# key = value` line uncommented
//! (except the keys marked "no default") it is `--print-config` of the
//! defaults, key for key and value for value, in every section; and the
//! range each comment starts with is the one the daemons enforce (a value at
//! each bound is accepted, one beyond it refused; an example value of a key
//! without a default is accepted).

use slope_tools::config_file::SlopeFile;

const CONFFILE: &str = include_str!("../../../packaging/slope.toml");

/// `# key = value   # comment` -> (key, value, comment).
fn commented_key(line: &str) -> Option<(&str, &str, &str)> {
    let (key, rest) = line.strip_prefix("# ")?.split_once(" = ")?;
    if !key.starts_with(|c: char| c.is_ascii_lowercase())
        || !key
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
    {
        return None;
    }
    let (value, comment) = rest.split_once(" #").unwrap_or((rest, ""));
    Some((key, value.trim(), comment.trim()))
}

/// The `# key = value   # comment` lines made live (but those of keys
/// without a default); other lines unchanged.
fn uncommented(text: &str) -> String {
    text.lines()
        .map(|line| match commented_key(line) {
            Some((key, value, comment)) if !comment.contains("no default") => {
                format!("{key} = {value}")
            }
            _ => line.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// How the uncommented file differs from `--print-config` of the defaults.
/// Every key of `table` with its full path (`estimator.ransac.max_planes`).
fn sections(table: &toml::Table) -> Vec<(String, toml::Value)> {
    let mut keys = Vec::new();
    for (key, value) in table {
        match value.as_table() {
            Some(inner) => keys.extend(
                sections(inner)
                    .into_iter()
                    .map(|(k, v)| (format!("{key}.{k}"), v)),
            ),
            None => keys.push((key.clone(), value.clone())),
        }
    }
    keys
}

fn differences_from_defaults(text: &str) -> Vec<String> {
    let live = uncommented(text);
    let mut found = Vec::new();
    match SlopeFile::from_toml_str(&live) {
        Ok(parsed) if parsed == SlopeFile::default() => {}
        Ok(parsed) => found.push(format!("parses to {parsed:?}")),
        Err(err) => found.push(format!("does not parse: {err:?}")),
    }
    let file: toml::Table = match toml::from_str(&live) {
        Ok(table) => table,
        Err(err) => return vec![format!("not TOML: {err}")],
    };
    let printed = SlopeFile::default()
        .to_toml()
        .expect("the defaults serialise");
    let defaults: toml::Table = toml::from_str(&printed).expect("--print-config is TOML");
    let (in_file, in_defaults) = (sections(&file), sections(&defaults));
    for (key, value) in &in_defaults {
        match in_file.iter().find(|(k, _)| k == key) {
            None => found.push(format!("{key} is missing")),
            Some((_, v)) if v != value => {
                found.push(format!("{key} = {v}, the default is {value}"))
            }
            Some(_) => {}
        }
    }
    for (key, _) in &in_file {
        if !in_defaults.iter().any(|(k, _)| k == key) {
            found.push(format!("{key} is not a key of the config file"));
        }
    }
    found
}

#[test]
fn the_shipped_conffile_parses_to_the_defaults() {
    let parsed = SlopeFile::from_toml_str(CONFFILE).expect("the conffile parses");
    assert_eq!(parsed, SlopeFile::default());
}

#[test]
fn uncommented_the_conffile_is_every_default_with_its_value() {
    let found = differences_from_defaults(CONFFILE);
    assert!(
        found.is_empty(),
        "packaging/slope.toml has drifted from `slope-estimator --print-config` \
         (update it from that output):\n{}",
        found.join("\n")
    );
}

/// Every `(section, key, value, comment)` of the file's commented keys.
fn documented_keys(text: &str) -> Vec<(String, String, String, String)> {
    let mut section = String::new();
    let mut keys = Vec::new();
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix('[') {
            section = rest.split(']').next().unwrap_or_default().to_string();
        } else if let Some((key, value, comment)) = commented_key(line) {
            keys.push((section.clone(), key.into(), value.into(), comment.into()));
        }
    }
    keys
}

/// Whether the daemons take `key = value` (in `[section]`).
fn accepts(section: &str, key: &str, value: &str) -> bool {
    let text = if section.is_empty() {
        format!("{key} = {value}\n")
    } else {
        format!("[{section}]\n{key} = {value}\n")
    };
    SlopeFile::from_toml_str(&text).is_ok()
}

/// Where a documented range and the daemons disagree. Ranges are
/// intervals `[a, b]`, `(a, b)`, `[a, b)`, `(a, b]` (a bound may name
/// another key, which is not checked here), `>= a`, `> a`, the
/// alternatives `x | y | z`, or `any`. The example value itself is always
/// accepted.
fn range_disagreements(section: &str, key: &str, default: &str, range: &str) -> Vec<String> {
    let float = default.contains('.');
    // A step that changes a value of this type at these magnitudes.
    let step = if float { 1e-6 } else { 1.0 };
    let write = |v: f64| {
        if float {
            format!("{v:?}")
        } else {
            format!("{v}")
        }
    };
    let name = if section.is_empty() {
        key.to_string()
    } else {
        format!("{section}.{key}")
    };
    let number = |text: &str| text.trim().parse::<f64>().ok();
    // (value, whether the range says it is accepted)
    let mut probes: Vec<(String, bool)> = vec![(default.to_string(), true)];
    let mut found = Vec::new();
    // The value at a bound and the one beyond it.
    let bound = |b: f64, inclusive: bool, outward: f64| {
        let beyond = b + outward * step;
        if inclusive {
            [(write(b), true), (write(beyond), false)]
        } else {
            [(write(b - outward * step), true), (write(b), false)]
        }
    };
    if range == "any" {
    } else if let Some(a) = range.strip_prefix(">=").and_then(number) {
        probes.extend(bound(a, true, -1.0));
    } else if let Some(a) = range.strip_prefix('>').and_then(number) {
        probes.extend(bound(a, false, -1.0));
    } else if let Some((open, close, a, b)) = interval(range) {
        if number(a).is_none() && number(b).is_none() {
            found.push(format!("{name}: {range} has no number"));
        }
        if let Some(a) = number(a) {
            probes.extend(bound(a, open == '[', -1.0));
        }
        if let Some(b) = number(b) {
            probes.extend(bound(b, close == ']', 1.0));
        }
    } else if range.contains(" | ") {
        probes.extend(range.split(" | ").map(|c| (c.trim().to_string(), true)));
        let other = if default.starts_with('"') {
            "\"other\""
        } else {
            "1"
        };
        probes.push((other.to_string(), false));
    } else {
        found.push(format!(
            "{name}: the comment does not start with a range: {range:?}"
        ));
    }
    for (value, accepted) in probes {
        if accepts(section, key, &value) != accepted {
            let verb = if accepted { "refused" } else { "accepted" };
            found.push(format!(
                "{name} = {value} is {verb}, the conffile says {range}"
            ));
        }
    }
    found
}

/// `[a, b]` and the like -> (opening bracket, closing bracket, a, b).
fn interval(range: &str) -> Option<(char, char, &str, &str)> {
    let open = range.chars().next().filter(|c| matches!(c, '[' | '('))?;
    let close = range.chars().last().filter(|c| matches!(c, ']' | ')'))?;
    let (a, b) = range[1..range.len() - 1].split_once(',')?;
    Some((open, close, a, b))
}

#[test]
fn every_key_states_the_range_the_daemons_enforce() {
    let keys = documented_keys(CONFFILE);
    assert!(keys.len() > 40, "{keys:?}");
    let mut found = Vec::new();
    for (section, key, default, comment) in &keys {
        let range = comment.split(": ").next().unwrap_or_default().trim();
        found.extend(range_disagreements(section, key, default, range));
    }
    assert!(found.is_empty(), "{}", found.join("\n"));
}

/// The checks can fail: a wrong default, a missing key, an unknown key and
/// a wrong range are each caught.
#[test]
fn the_checks_catch_a_drifted_conffile() {
    let wrong_default = CONFFILE.replace("# neighbours = 20 ", "# neighbours = 21 ");
    let found = differences_from_defaults(&wrong_default);
    assert_eq!(found.len(), 2, "{found:?}");
    assert!(found[0].starts_with("parses to"), "{found:?}");
    assert_eq!(
        found[1],
        "estimator.outlier.neighbours = 21, the default is 20"
    );
    let missing = CONFFILE.replace("# max_missed = 30 ", "# ");
    assert_eq!(
        differences_from_defaults(&missing),
        ["estimator.tracking.max_missed is missing"]
    );
    let unknown = CONFFILE.replace("# max_missed = 30 ", "# max_misses = 30 ");
    let found = differences_from_defaults(&unknown);
    assert!(found[0].starts_with("does not parse"), "{found:?}");
    assert!(
        found.contains(&"estimator.tracking.max_missed is missing".to_string()),
        "{found:?}"
    );
    assert!(
        found
            .contains(&"estimator.tracking.max_misses is not a key of the config file".to_string()),
        "{found:?}"
    );
    assert_eq!(
        range_disagreements("estimator.outlier", "neighbours", "20", "[1, 47]"),
        ["estimator.outlier.neighbours = 48 is accepted, the conffile says [1, 47]"]
    );
    assert_eq!(
        range_disagreements("estimator.ransac", "confidence", "0.999", "[0, 1)").len(),
        1,
        "0 is refused"
    );
    assert_eq!(
        range_disagreements("estimator", "method", "\"paper\"", "\"paper\" | \"fast\"").len(),
        1
    );
    assert_eq!(
        range_disagreements("estimator", "seed", "0", "seed").len(),
        1
    );
    // The sections of the other daemons are checked as well.
    assert_eq!(
        range_disagreements("mount", "pitch_deg", "-20.0", "[-80, 90]"),
        ["mount.pitch_deg = -80.000001 is accepted, the conffile says [-80, 90]"]
    );
    assert_eq!(
        range_disagreements("capture", "serail", "\"1\"", "any"),
        ["capture.serail = \"1\" is refused, the conffile says any"]
    );
    let wrong_health = CONFFILE.replace("# interval_s = 1.0 ", "# interval_s = 2.0 ");
    assert_eq!(
        differences_from_defaults(&wrong_health)[1],
        "health.interval_s = 2.0, the default is 1.0"
    );
}
