//! `/diagnostics` from the daemons' health reports: the
//! `diagnostic_msgs/msg/DiagnosticArray` of each report, one
//! `DiagnosticStatus` named `<node>: <component>` (`slope_ros2: estimator`)
//! whose level follows this rule ([`DiagnosticsRule`]), first match wins:
//!
//! - **ERROR** when the daemon had an error since its previous report
//!   (its `errors` count grew; for its first report, or a new pid: the last
//!   error is no older than the report's window); the message is the error;
//! - **WARN** when nothing came in over the window (`rate_in_hz` 0: "no
//!   clouds" for the estimator, "no frames" for the capture and the replay),
//!   or frames were dropped since the previous report ("N frames dropped");
//! - **OK** otherwise ("N.N Hz in, N.N Hz out").
//!
//! Every figure of the report is a key/value, numbers as Rust prints them
//! (the shortest text that reads back as the same value; NaN as `NaN`),
//! and the header's stamp is the report's. `hardware_id` is the service
//! prefix (which slope stack on the robot).

use std::collections::HashMap;

use serde::{Deserialize, Serialize};
use slope_ipc_types::{Health, HealthComponent};
use slope_tools::ros2_messages::{Header, Time};

/// `diagnostic_msgs/msg/DiagnosticStatus` levels.
pub const OK: u8 = 0;
pub const WARN: u8 = 1;
pub const ERROR: u8 = 2;

/// `diagnostic_msgs/msg/KeyValue`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct KeyValue {
    pub key: String,
    pub value: String,
}

/// `diagnostic_msgs/msg/DiagnosticStatus`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct DiagnosticStatus {
    pub level: u8,
    pub name: String,
    pub message: String,
    pub hardware_id: String,
    pub values: Vec<KeyValue>,
}

/// `diagnostic_msgs/msg/DiagnosticArray`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct DiagnosticArray {
    pub header: Header,
    pub status: Vec<DiagnosticStatus>,
}

/// What the rule remembers of a daemon's previous report.
#[derive(Debug, Clone, Copy)]
struct Previous {
    pid: u32,
    errors: u64,
    frames_dropped: u64,
}

/// The level rule (module documentation) over the reports of every daemon
/// on the prefix, remembering each one's previous report.
#[derive(Debug, Clone)]
pub struct DiagnosticsRule {
    node_name: String,
    hardware_id: String,
    previous: HashMap<u32, Previous>,
}

impl DiagnosticsRule {
    /// Statuses named `<node_name>: <component>`, `hardware_id` the
    /// service prefix.
    pub fn new(node_name: &str, service_prefix: &str) -> Self {
        Self {
            node_name: node_name.to_string(),
            hardware_id: service_prefix.to_string(),
            previous: HashMap::new(),
        }
    }

    /// The `/diagnostics` message of `report`.
    pub fn array(&mut self, report: &Health) -> DiagnosticArray {
        let (level, message) = self.level(report);
        let component = report.component().map_or("unknown", HealthComponent::name);
        DiagnosticArray {
            header: Header {
                stamp: Time::from_ns(report.stamp_ns),
                frame_id: String::new(),
            },
            status: vec![DiagnosticStatus {
                level,
                name: format!("{}: {component}", self.node_name),
                message,
                hardware_id: self.hardware_id.clone(),
                values: values(report),
            }],
        }
    }

    /// The level and message of `report`, by the rule.
    fn level(&mut self, report: &Health) -> (u8, String) {
        let before = self
            .previous
            .insert(
                report.component,
                Previous {
                    pid: report.pid,
                    errors: report.errors,
                    frames_dropped: report.frames_dropped,
                },
            )
            .filter(|p| p.pid == report.pid);
        let new_error = match before {
            Some(p) => report.errors > p.errors,
            None => {
                let window_ns = report.window_ms.saturating_mul(1_000_000);
                report.last_error_stamp_ns > 0
                    && report.stamp_ns.saturating_sub(report.last_error_stamp_ns) <= window_ns
            }
        };
        if new_error {
            let error = report.last_error();
            let text = if error.is_empty() { "an error" } else { error };
            return (ERROR, format!("error: {text}"));
        }
        if report.rate_in_hz <= 0.0 || !report.rate_in_hz.is_finite() {
            let what = match report.component() {
                Some(HealthComponent::Estimator) => "no clouds",
                _ => "no frames",
            };
            let seconds = report.window_ms as f64 / 1000.0;
            return (WARN, format!("{what} in the last {seconds} s"));
        }
        let dropped = before.map_or(0, |p| {
            report.frames_dropped.saturating_sub(p.frames_dropped)
        });
        if dropped > 0 {
            return (WARN, format!("{dropped} frames dropped"));
        }
        (
            OK,
            format!(
                "{:.1} Hz in, {:.1} Hz out",
                report.rate_in_hz, report.rate_out_hz
            ),
        )
    }
}

/// Every figure of `report` as a key/value.
fn values(report: &Health) -> Vec<KeyValue> {
    let mut out = Vec::new();
    let mut put = |key: String, value: String| out.push(KeyValue { key, value });
    put("pid".into(), report.pid.to_string());
    put("uptime_ms".into(), report.uptime_ms.to_string());
    put("frames_in".into(), report.frames_in.to_string());
    put("frames_out".into(), report.frames_out.to_string());
    put("frames_dropped".into(), report.frames_dropped.to_string());
    put("reconnects".into(), report.reconnects.to_string());
    put("errors".into(), report.errors.to_string());
    put("rate_in_hz".into(), report.rate_in_hz.to_string());
    put("rate_out_hz".into(), report.rate_out_hz.to_string());
    put("window_ms".into(), report.window_ms.to_string());
    let timings = std::iter::once(("latency", &report.latency))
        .chain(report.stages().iter().map(|s| (s.name(), &s.timing)));
    for (name, t) in timings {
        put(format!("{name}.median_ms"), t.median_ms.to_string());
        put(format!("{name}.p95_ms"), t.p95_ms.to_string());
        put(format!("{name}.max_ms"), t.max_ms.to_string());
        put(format!("{name}.count"), t.count.to_string());
    }
    if !report.last_error().is_empty() {
        put("last_error".into(), report.last_error().to_string());
        put(
            "last_error_stamp_ns".into(),
            report.last_error_stamp_ns.to_string(),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use slope_ipc_types::TimingStats;
    use slope_tools::ros2_messages::{from_cdr, to_cdr};

    use super::*;

    fn report(frames_in: u64) -> Health {
        let mut h = Health::new(HealthComponent::Estimator);
        h.pid = 42;
        h.stamp_ns = 1_700_000_010_000_000_000;
        h.window_ms = 1000;
        h.frames_in = frames_in;
        h.rate_in_hz = 30.0;
        h.rate_out_hz = 29.5;
        h.push_stage("total", TimingStats::of(&mut [10.0, 12.0, 20.0]));
        h
    }

    fn level_of(rule: &mut DiagnosticsRule, h: &Health) -> (u8, String) {
        let array = rule.array(h);
        let status = &array.status[0];
        (status.level, status.message.clone())
    }

    #[test]
    fn a_report_at_rate_is_ok_with_every_figure_as_a_key_value() {
        let mut rule = DiagnosticsRule::new("slope_ros2", "slope");
        let array = rule.array(&report(300));
        assert_eq!(array.header.stamp.sec, 1_700_000_010);
        let status = &array.status[0];
        assert_eq!(
            (status.level, status.message.as_str()),
            (OK, "30.0 Hz in, 29.5 Hz out")
        );
        assert_eq!(status.name, "slope_ros2: estimator");
        assert_eq!(status.hardware_id, "slope");
        let get = |key: &str| {
            status
                .values
                .iter()
                .find(|kv| kv.key == key)
                .map(|kv| kv.value.as_str())
        };
        assert_eq!(get("frames_in"), Some("300"));
        assert_eq!(get("rate_out_hz"), Some("29.5"));
        assert_eq!(get("total.median_ms"), Some("12"));
        assert_eq!(get("total.count"), Some("3"));
        assert_eq!(get("latency.median_ms"), Some("NaN"));
        assert_eq!(get("last_error"), None);
        let back: DiagnosticArray = from_cdr(&to_cdr(&array).unwrap()).unwrap();
        assert_eq!(back, array);
    }

    #[test]
    fn no_input_or_new_drops_warn_and_a_new_error_is_an_error() {
        let mut rule = DiagnosticsRule::new("n", "p");
        let mut idle = report(0);
        idle.rate_in_hz = 0.0;
        assert_eq!(
            level_of(&mut rule, &idle),
            (WARN, "no clouds in the last 1 s".into())
        );
        let mut h = report(30);
        assert_eq!(level_of(&mut rule, &h).0, OK);
        h.frames_dropped = 3;
        assert_eq!(level_of(&mut rule, &h), (WARN, "3 frames dropped".into()));
        // The same count again: nothing new.
        assert_eq!(level_of(&mut rule, &h).0, OK);
        h.errors = 1;
        h.set_last_error("cloud header v1 refused", h.stamp_ns - 5_000_000_000);
        assert_eq!(
            level_of(&mut rule, &h),
            (ERROR, "error: cloud header v1 refused".into())
        );
        // No new error: the old one no longer counts.
        assert_eq!(level_of(&mut rule, &h).0, OK);
        let mut capture = report(0);
        capture.component = HealthComponent::Capture as u32;
        capture.rate_in_hz = 0.0;
        assert_eq!(level_of(&mut rule, &capture).1, "no frames in the last 1 s");
    }

    #[test]
    fn a_first_report_is_an_error_only_for_an_error_within_its_window() {
        let mut h = report(30);
        h.errors = 4;
        h.set_last_error("old", h.stamp_ns - 5_000_000_000);
        assert_eq!(level_of(&mut DiagnosticsRule::new("n", "p"), &h).0, OK);
        h.set_last_error("recent", h.stamp_ns - 500_000_000);
        assert_eq!(
            level_of(&mut DiagnosticsRule::new("n", "p"), &h),
            (ERROR, "error: recent".into())
        );
        // A restarted daemon (new pid) starts afresh.
        let mut rule = DiagnosticsRule::new("n", "p");
        assert_eq!(level_of(&mut rule, &h).0, ERROR);
        h.pid = 43;
        h.errors = 0;
        assert_eq!(level_of(&mut rule, &h).0, ERROR, "its first report");
    }
}
