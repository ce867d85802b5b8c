//! Health reports: a daemon counts what goes in and out and times each
//! frame; about once a second it publishes a [`Health`] on `<prefix>/health`
//! (rates and per-stage median/p95/max over that second), and every
//! [`LOG_INTERVAL`] it logs the same summary over the longer window at INFO
//! (the journal's view of it).

use std::time::{Duration, Instant};

use slope_ipc_types::{now_ns, Health, HealthComponent, TimingStats, MAX_STAGES};
use slope_sensor::ipc::HealthPublisher;

/// How often the summary is logged.
pub const LOG_INTERVAL: Duration = Duration::from_secs(10);

/// The default time between health reports, seconds.
pub const DEFAULT_HEALTH_INTERVAL_S: f64 = 1.0;

/// Frames and their timings since the window opened.
#[derive(Debug)]
struct Window {
    opened: Instant,
    frames_in: u64,
    frames_out: u64,
    latency_ms: Vec<f64>,
    /// Stage name and its times, in the order the stages first appeared.
    stages: Vec<(&'static str, Vec<f64>)>,
}

impl Window {
    fn new(now: Instant) -> Self {
        Self {
            opened: now,
            frames_in: 0,
            frames_out: 0,
            latency_ms: Vec::new(),
            stages: Vec::new(),
        }
    }

    fn add_stage(&mut self, name: &'static str, ms: f64) {
        if let Some(k) = self.stages.iter().position(|(n, _)| *n == name) {
            self.stages[k].1.push(ms);
        } else if self.stages.len() < MAX_STAGES {
            self.stages.push((name, vec![ms]));
        }
    }

    /// Writes the window's rates and timings into `health` and empties it.
    fn close_into(&mut self, health: &mut Health, now: Instant) {
        let seconds = now.duration_since(self.opened).as_secs_f64();
        health.window_ms = (seconds * 1e3).round() as u64;
        let rate = |n: u64| {
            if seconds > 0.0 {
                n as f64 / seconds
            } else {
                0.0
            }
        };
        health.rate_in_hz = rate(self.frames_in);
        health.rate_out_hz = rate(self.frames_out);
        health.latency = TimingStats::of(&mut self.latency_ms);
        for (name, times) in &mut self.stages {
            health.push_stage(name, TimingStats::of(times));
        }
        self.opened = now;
        self.frames_in = 0;
        self.frames_out = 0;
        self.latency_ms.clear();
        for (_, times) in &mut self.stages {
            times.clear();
        }
    }
}

/// Counts and times a daemon's frames and makes its health reports.
#[derive(Debug)]
pub struct HealthMonitor {
    component: HealthComponent,
    started: Instant,
    totals: Health,
    /// The report window (about a second) and the log window.
    report: Window,
    log: Window,
    /// Whether reports are made at all (else the report window would
    /// only grow).
    reporting: bool,
}

impl HealthMonitor {
    pub fn new(component: HealthComponent) -> Self {
        Self::new_at(component, Instant::now())
    }

    /// The same, started at `now` (a test's clock).
    fn new_at(component: HealthComponent, now: Instant) -> Self {
        Self {
            component,
            started: now,
            totals: Health::new(component),
            report: Window::new(now),
            log: Window::new(now),
            reporting: true,
        }
    }

    /// Stops (or resumes) keeping the report window: for a daemon that
    /// only logs its summary.
    pub fn set_reporting(&mut self, on: bool) {
        self.reporting = on;
        self.report = Window::new(Instant::now());
    }

    /// `n` frames came in.
    pub fn frames_in(&mut self, n: u64) {
        for count in [
            &mut self.totals.frames_in,
            &mut self.report.frames_in,
            &mut self.log.frames_in,
        ] {
            *count = count.saturating_add(n);
        }
    }

    /// `n` frames were lost (superseded, overwritten, failed to send).
    pub fn dropped(&mut self, n: u64) {
        self.totals.frames_dropped = self.totals.frames_dropped.saturating_add(n);
    }

    /// The camera was re-opened.
    pub fn reconnected(&mut self) {
        self.totals.reconnects += 1;
    }

    /// Something went wrong (the daemon goes on).
    pub fn error(&mut self, text: &str) {
        self.totals.errors += 1;
        self.totals.set_last_error(text, now_ns());
    }

    /// One message went out: its capture-to-publish latency (if known)
    /// and its stage times in pipeline order, `total` included.
    pub fn frame_out(&mut self, latency_ms: Option<f64>, stages: &[(&'static str, f64)]) {
        self.totals.frames_out += 1;
        let windows = if self.reporting {
            [Some(&mut self.report), Some(&mut self.log)]
        } else {
            [None, Some(&mut self.log)]
        };
        for window in windows.into_iter().flatten() {
            window.frames_out += 1;
            if let Some(ms) = latency_ms.filter(|ms| ms.is_finite()) {
                window.latency_ms.push(ms);
            }
            for &(name, ms) in stages {
                window.add_stage(name, ms);
            }
        }
    }

    /// The report over the window since the last report (which it starts
    /// anew).
    pub fn report(&mut self) -> Health {
        self.report_at(Instant::now())
    }

    /// The same, made at `now` (a test's clock).
    fn report_at(&mut self, now: Instant) -> Health {
        let mut health = self.snapshot(now);
        self.report.close_into(&mut health, now);
        health
    }

    /// The same over the log window, when it is [`LOG_INTERVAL`] old.
    pub fn log_report_due(&mut self) -> Option<Health> {
        let now = Instant::now();
        if now.duration_since(self.log.opened) < LOG_INTERVAL {
            return None;
        }
        let mut health = self.snapshot(now);
        self.log.close_into(&mut health, now);
        Some(health)
    }

    fn snapshot(&self, now: Instant) -> Health {
        Health {
            stamp_ns: now_ns(),
            uptime_ms: now.duration_since(self.started).as_millis() as u64,
            stage_count: 0,
            ..self.totals
        }
    }

    pub fn component(&self) -> HealthComponent {
        self.component
    }
}

/// Publishes a [`HealthMonitor`]'s reports every `interval` and logs its
/// summary every [`LOG_INTERVAL`].
pub struct HealthReporter {
    pub monitor: HealthMonitor,
    publisher: Option<HealthPublisher>,
    interval: Duration,
    last: Instant,
}

impl std::fmt::Debug for HealthReporter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HealthReporter")
            .field("monitor", &self.monitor)
            .field("publishing", &self.publisher.is_some())
            .field("interval", &self.interval)
            .finish()
    }
}

impl HealthReporter {
    /// `publisher` `None` (or `interval_s` 0): reports are only logged.
    pub fn new(
        component: HealthComponent,
        publisher: Option<HealthPublisher>,
        interval_s: f64,
    ) -> Self {
        let interval = Duration::from_secs_f64(interval_s.max(0.0));
        let publisher = publisher.filter(|_| !interval.is_zero());
        let mut monitor = HealthMonitor::new(component);
        monitor.set_reporting(publisher.is_some());
        Self {
            monitor,
            publisher,
            interval,
            last: Instant::now(),
        }
    }

    /// From the main loop: publishes when a report is due, logs when the
    /// log window is full. A report that cannot be sent is logged, not
    /// fatal (health must never stop the work it reports on).
    pub fn tick(&mut self) {
        if let Some(publisher) = &self.publisher {
            if self.last.elapsed() >= self.interval {
                self.last = Instant::now();
                let health = self.monitor.report();
                if let Err(err) = publisher.publish(&health) {
                    tracing::warn!(error = %err, "could not publish the health report");
                }
            }
        }
        if let Some(health) = self.monitor.log_report_due() {
            tracing::info!("{}", summary_line(&health));
        }
    }
}

/// One readable line: `estimator pid 42 up 12 s: in 30.0/s out 29.9/s,
/// 300 in, 299 out, 1 dropped; latency 25.1/31.0/40.2 ms; total
/// 21.3/27.0/33.1 ms (outlier 6.1/7.0/8.2, ...); last error: ...`
/// (timings as median/p95/max over the window).
pub fn summary_line(h: &Health) -> String {
    let who = h.component().map_or("unknown", |c| c.name());
    let mut line = format!(
        "{who} pid {} up {} s: in {:.1}/s out {:.1}/s, {} in, {} out, {} dropped",
        h.pid,
        h.uptime_ms / 1000,
        h.rate_in_hz,
        h.rate_out_hz,
        h.frames_in,
        h.frames_out,
        h.frames_dropped
    );
    if h.reconnects > 0 {
        line.push_str(&format!(", {} reconnects", h.reconnects));
    }
    if h.latency.count > 0 {
        line.push_str(&format!("; latency {} ms", timing_text(&h.latency)));
    }
    let stages = h.stages();
    if let Some(total) = h.stage("total").filter(|t| t.count > 0) {
        line.push_str(&format!("; total {} ms", timing_text(total)));
    }
    let parts: Vec<String> = stages
        .iter()
        .filter(|s| s.name() != "total" && s.timing.count > 0)
        .map(|s| format!("{} {}", s.name(), timing_text(&s.timing)))
        .collect();
    if !parts.is_empty() {
        line.push_str(&format!(" ({})", parts.join(", ")));
    }
    if h.errors > 0 {
        let last = printable(h.last_error());
        line.push_str(&format!("; {} errors, last: {last}", h.errors));
    }
    line
}

/// `text` with its control characters (an escape sequence that would clear
/// a terminal, a newline that would start a line of its own) written as
/// Rust escapes (`\u{1b}`, `\n`): the report comes from another process,
/// and the readable form is printed to a terminal.
pub fn printable(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// `median/p95/max`, one decimal.
fn timing_text(t: &TimingStats) -> String {
    format!("{:.1}/{:.1}/{:.1}", t.median_ms, t.p95_ms, t.max_ms)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A last error with an escape sequence (it cleared the terminal of
    /// `slope-echo --health`) and a newline is printed escaped, on one line.
    #[test]
    fn control_characters_of_a_last_error_are_escaped() {
        let mut m = HealthMonitor::new(HealthComponent::Estimator);
        m.error("bad \u{1b}[2J\u{1b}[Hcloud\nsecond line \u{e9}");
        let line = summary_line(&m.report());
        assert!(
            line.ends_with("1 errors, last: bad \\u{1b}[2J\\u{1b}[Hcloud\\nsecond line \u{e9}"),
            "{line}"
        );
        assert!(!line.chars().any(char::is_control), "{line:?}");
    }

    #[test]
    fn a_report_holds_the_window_and_the_totals() {
        // An injected clock: the window is exactly half a second.
        let started = Instant::now();
        let mut m = HealthMonitor::new_at(HealthComponent::Estimator, started);
        m.frames_in(3);
        m.dropped(1);
        for k in 1..=2 {
            let ms = f64::from(k);
            m.frame_out(
                Some(10.0 * ms),
                &[("outlier", ms), ("ransac", 2.0 * ms), ("total", 3.0 * ms)],
            );
        }
        m.error("cloud service gone");
        let h = m.report_at(started + Duration::from_millis(500));
        assert_eq!(h.component(), Some(HealthComponent::Estimator));
        assert_eq!(h.pid, std::process::id());
        assert_eq!((h.frames_in, h.frames_out, h.frames_dropped), (3, 2, 1));
        assert_eq!((h.errors, h.last_error()), (1, "cloud service gone"));
        let names: Vec<_> = h.stages().iter().map(|s| s.name()).collect();
        assert_eq!(names, ["outlier", "ransac", "total"]);
        let total = h.stage("total").unwrap();
        assert_eq!((total.median_ms, total.max_ms, total.count), (3.0, 6.0, 2));
        assert_eq!((h.latency.median_ms, h.latency.max_ms), (10.0, 20.0));
        // 3 frames in and 2 out over 0.5 s.
        assert_eq!(h.window_ms, 500);
        assert_eq!((h.rate_in_hz, h.rate_out_hz), (6.0, 4.0));
        assert_eq!(h.uptime_ms, 500);

        // The next window starts empty; the totals go on.
        m.frames_in(1);
        let h = m.report_at(started + Duration::from_millis(750));
        assert_eq!(h.window_ms, 250);
        assert_eq!((h.rate_in_hz, h.rate_out_hz), (4.0, 0.0));
        assert_eq!((h.frames_in, h.frames_out), (4, 2));
        assert_eq!(h.stage("total").unwrap().count, 0);
        assert_eq!(h.latency.count, 0);
        assert!(h.latency.median_ms.is_nan());
    }

    /// Without reports (only the log), the report window keeps nothing.
    #[test]
    fn a_daemon_that_only_logs_keeps_no_report_window() {
        let mut reporter = HealthReporter::new(HealthComponent::Estimator, None, 1.0);
        for _ in 0..1000 {
            reporter.monitor.frame_out(Some(1.0), &[("total", 2.0)]);
        }
        assert!(reporter.monitor.report.latency_ms.is_empty());
        assert!(reporter.monitor.report.stages.is_empty());
        assert_eq!(reporter.monitor.log.latency_ms.len(), 1000);
    }

    #[test]
    fn the_summary_line_names_every_part() {
        let mut m = HealthMonitor::new(HealthComponent::Capture);
        m.frames_in(2);
        m.frame_out(Some(4.0), &[("project", 0.4), ("total", 0.5)]);
        m.reconnected();
        m.error("depth stream stalled");
        let line = summary_line(&m.report());
        for part in [
            "capture pid",
            "2 in, 1 out, 0 dropped",
            "1 reconnects",
            "latency 4.0/4.0/4.0 ms",
            "total 0.5/0.5/0.5 ms (project 0.4/0.4/0.4)",
            "1 errors, last: depth stream stalled",
        ] {
            assert!(line.contains(part), "{part:?} not in {line:?}");
        }
    }
}
