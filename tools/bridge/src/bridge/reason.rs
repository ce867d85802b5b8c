//! Zenoh's error messages made readable ([`zenoh_reason`]): one line,
//! without the source locations Zenoh appends.

/// Zenoh's message of `err` without the source locations it appends to
/// each part (` at /root/.cargo/registry/src/.../config.rs:86.`).
pub fn zenoh_reason(err: &dyn std::fmt::Display) -> String {
    let text = err.to_string();
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    while let Some(at) = rest.find(" at ") {
        out.push_str(&rest[..at]);
        let after = &rest[at + " at ".len()..];
        // `<path>.rs:<line>.`: no spaces in the path.
        let location = after
            .find(".rs:")
            .filter(|&rs| !after[..rs].contains(char::is_whitespace))
            .and_then(|rs| {
                let digits = after[rs + 4..]
                    .find(|c: char| !c.is_ascii_digit())
                    .unwrap_or(after.len() - rs - 4);
                let end = rs + 4 + digits;
                (digits > 0).then(|| end + usize::from(after[end..].starts_with('.')))
            });
        match location {
            Some(end) => rest = &after[end..],
            None => {
                out.push_str(" at ");
                rest = after;
            }
        }
    }
    out.push_str(rest);
    one_line(out.trim())
}

/// A parser's multi-line report (JSON5 in a config file: ` --> 1:9`, the
/// line quoted with `|` margins, `= expected ...`) as one line: where, and
/// what was expected.
fn one_line(text: &str) -> String {
    if !text.contains('\n') {
        return text.to_string();
    }
    let mut parts = Vec::new();
    for line in text.lines().map(str::trim) {
        if let Some(place) = line.strip_prefix("--> ") {
            let (row, column) = place.split_once(':').unwrap_or((place, "?"));
            parts.push(format!("at line {row}, column {column}"));
        } else if let Some(message) = line.strip_prefix("= ") {
            parts.push(message.to_string());
        } else if !line.is_empty() && !line.contains('|') {
            parts.push(line.to_string());
        }
    }
    parts.join(": ")
}
