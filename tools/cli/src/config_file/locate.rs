//! Where in a file's text a key or an error is: the line of a byte, the
//! line of a top-level key, the full path of the key on a line.

use std::ops::Range;

/// The 1-based line where the top-level `key` first appears: a table
/// header (`[key]`, `[key.sub]`, `[[key]]`) or a key at the top (`key = `,
/// `key.sub = `, before any header). `None` if it is written some other
/// way (quoted, say).
pub(super) fn first_line_of(text: &str, key: &str) -> Option<usize> {
    let mut top = true;
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if let Some(header) = line.strip_prefix('[') {
            let header = header.trim_start_matches('[').trim_start();
            if header
                .strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with([']', '.']))
            {
                return Some(k + 1);
            }
            top = false;
        } else if top
            && line
                .strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with(['=', '.']))
        {
            return Some(k + 1);
        }
    }
    None
}

/// The 1-based line holding byte `at`.
pub(super) fn line_of(text: &str, at: usize) -> usize {
    text[..at.min(text.len())].matches('\n').count() + 1
}

/// The full path of the key on the line of `span`: the last table header
/// above it, then the key before the `=` (or, on a header line, the header
/// up to the end of `span`).
pub(super) fn key_path(text: &str, span: &Range<usize>) -> String {
    let start = span.start.min(text.len());
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[start..].find('\n').map_or(text.len(), |i| start + i);
    let line = text[line_start..line_end].trim();
    if line.starts_with('[') {
        let end = span.end.clamp(start, line_end);
        return text[line_start..end]
            .trim()
            .trim_start_matches('[')
            .trim_end_matches(']')
            .trim()
            .to_string();
    }
    let header = text[..line_start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| {
            let l = l.trim_start_matches('[');
            l.split(']').next().unwrap_or_default().trim().to_string()
        });
    let key = line.split('=').next().unwrap_or_default().trim();
    match header {
        Some(header) if !header.is_empty() => format!("{header}.{key}"),
        _ => key.to_string(),
    }
}
