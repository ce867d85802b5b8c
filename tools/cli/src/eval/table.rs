//! The table `slope-eval` prints without `--json`: a header, then a row per
//! recording and method with its detail lines.

use super::summary::{MethodReport, LOW_CONFIDENCE};

/// The header line of the table.
pub fn table_header(label_width: usize) -> String {
    format!(
        "{:<label_width$}  {:<13}  {:>6}  {:>6}  {:>12}  {:>8}  {:>8}  {:>9}",
        "recording", "method", "frames", "ok", "median slope", "truth", "|error|", "median ms"
    )
}

/// The table row of a report and its indented detail lines (per-stage
/// medians, frames that are not ok, the first bad frame's error).
pub fn table_rows(report: &MethodReport, label_width: usize) -> String {
    let s = &report.summary;
    let deg = |v: Option<f64>, signed: bool| match v {
        Some(v) if signed => format!("{v:+.2}°"),
        Some(v) => format!("{v:.2}°"),
        None => "-".to_string(),
    };
    let mut text = format!(
        "{:<label_width$}  {:<13}  {:>6}  {:>6}  {:>12}  {:>8}  {:>8}  {:>9}",
        report.recording,
        report.method.name(),
        s.frames,
        s.ok_frames,
        deg(s.median_slope_deg, true),
        deg(report.truth_deg, false),
        deg(s.abs_error_deg, false),
        s.median_ms.map_or("-".to_string(), |ms| format!("{ms:.1}")),
    );
    if !s.median_stage_ms.0.is_empty() {
        let stages: Vec<String> = s
            .median_stage_ms
            .0
            .iter()
            .map(|(name, ms)| format!("{name} {ms:.2}"))
            .collect();
        text.push_str(&format!("\n    stages (median ms): {}", stages.join(", ")));
    }
    if s.low_confidence_frames > 0 {
        text.push_str(&format!(
            "\n    low confidence (< {LOW_CONFIDENCE}): {} of {} ok frames",
            s.low_confidence_frames, s.ok_frames
        ));
    }
    if !s.not_ok.0.is_empty() {
        let counts: Vec<String> = s
            .not_ok
            .0
            .iter()
            .map(|(name, count)| format!("{name} {count}"))
            .collect();
        text.push_str(&format!("\n    not ok: {}", counts.join(", ")));
    }
    if let Some(bad) = report.estimates.iter().find(|f| f.error.is_some()) {
        if let Some(error) = &bad.error {
            text.push_str(&format!("\n    first bad frame ({}): {error}", bad.index));
        }
    }
    text
}
