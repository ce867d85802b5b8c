//! The health message (`slope.Health.v1`) the daemons publish on
//! `<prefix>/health` about once a second: what went in and out, how fast,
//! how long each stage took, and the last error.

use iceoryx2::prelude::ZeroCopySend;

use crate::text::{text_of, write_text};

/// Which daemon sent a health message.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HealthComponent {
    Estimator = 1,
    Capture = 2,
    Replay = 3,
}

impl HealthComponent {
    pub const ALL: [HealthComponent; 3] = [Self::Estimator, Self::Capture, Self::Replay];

    pub fn from_raw(raw: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|c| *c as u32 == raw)
    }

    /// The program's name without `slope-`, as logs and JSON show it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Estimator => "estimator",
            Self::Capture => "capture",
            Self::Replay => "replay",
        }
    }
}

/// Median, 95th percentile and maximum of a duration over the frames of
/// the window, milliseconds (NaN when `count` is 0).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("slope.TimingStats.v1")]
pub struct TimingStats {
    pub median_ms: f64,
    pub p95_ms: f64,
    pub max_ms: f64,
    /// Frames the figures cover.
    pub count: u64,
}

impl TimingStats {
    /// No frames: every figure NaN.
    pub const EMPTY: TimingStats = TimingStats {
        median_ms: f64::NAN,
        p95_ms: f64::NAN,
        max_ms: f64::NAN,
        count: 0,
    };

    /// The figures of `values` (milliseconds), sorting it in place.
    /// Percentiles are the nearest rank: the smallest value with at least
    /// that share of the values at or below it.
    pub fn of(values: &mut [f64]) -> Self {
        if values.is_empty() {
            return Self::EMPTY;
        }
        values.sort_unstable_by(f64::total_cmp);
        let rank = |share: f64| {
            let k = (share * values.len() as f64).ceil() as usize;
            values[k.clamp(1, values.len()) - 1]
        };
        Self {
            median_ms: rank(0.5),
            p95_ms: rank(0.95),
            max_ms: values[values.len() - 1],
            count: values.len() as u64,
        }
    }
}

/// Bytes of a stage name (UTF-8, NUL-padded).
pub const STAGE_NAME_LEN: usize = 16;
/// Stages a health message can carry.
pub const MAX_STAGES: usize = 12;
/// Bytes of `last_error` (UTF-8, NUL-padded, cut at a character boundary).
pub const LAST_ERROR_LEN: usize = 160;

/// The timing of one pipeline stage (or of the whole frame: `total`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("slope.StageHealth.v1")]
pub struct StageHealth {
    /// The stage's name, UTF-8, NUL-padded (`outlier`, `ransac`, ...).
    pub name: [u8; STAGE_NAME_LEN],
    pub timing: TimingStats,
}

impl StageHealth {
    /// The name as text (empty for an unused slot).
    pub fn name(&self) -> &str {
        text_of(&self.name)
    }
}

/// One health report. The layout has no implicit padding; the test
/// `layout_is_pinned` pins its size and offsets for readers in other
/// languages.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("slope.Health.v1")]
pub struct Health {
    /// When the report was made, ns since the Unix epoch.
    pub stamp_ns: u64,
    /// Time since the daemon started, milliseconds.
    pub uptime_ms: u64,
    /// A [`HealthComponent`] as its `u32` value.
    pub component: u32,
    /// The daemon's process id.
    pub pid: u32,
    /// Frames received since start (clouds for the estimator, device
    /// frames for the capture, recording frames for the replay).
    pub frames_in: u64,
    /// Messages published since start (estimates, clouds).
    pub frames_out: u64,
    /// Frames lost since start (superseded, overwritten, failed to send).
    pub frames_dropped: u64,
    /// Times the camera was re-opened since start (capture only).
    pub reconnects: u64,
    /// Errors since start (the last one in `last_error`).
    pub errors: u64,
    /// Frames received and published per second over the window.
    pub rate_in_hz: f64,
    pub rate_out_hz: f64,
    /// Length of the window the rates and timings cover, milliseconds.
    pub window_ms: u64,
    /// Capture stamp to publication, over the window's frames.
    pub latency: TimingStats,
    /// Used entries of `stages`.
    pub stage_count: u32,
    /// Always 0 (fills the gap before `stages`).
    pub reserved: u32,
    /// Per-stage timings over the window, in pipeline order; `total` is
    /// the whole frame.
    pub stages: [StageHealth; MAX_STAGES],
    /// When `last_error` happened, ns since the Unix epoch; 0 if never.
    pub last_error_stamp_ns: u64,
    /// The last error, UTF-8, NUL-padded; empty if none.
    pub last_error: [u8; LAST_ERROR_LEN],
}

const _: () = assert!(core::mem::size_of::<Health>() == 872);

impl Health {
    /// An empty report from `component`.
    pub fn new(component: HealthComponent) -> Self {
        Self {
            component: component as u32,
            pid: std::process::id(),
            ..Self::default()
        }
    }

    pub fn component(&self) -> Option<HealthComponent> {
        HealthComponent::from_raw(self.component)
    }

    /// The used stage entries.
    pub fn stages(&self) -> &[StageHealth] {
        &self.stages[..(self.stage_count as usize).min(MAX_STAGES)]
    }

    /// The timing of stage `name`, if the report has it.
    pub fn stage(&self, name: &str) -> Option<&TimingStats> {
        self.stages()
            .iter()
            .find(|s| s.name() == name)
            .map(|s| &s.timing)
    }

    /// Appends a stage; false (and nothing changes) when all
    /// [`MAX_STAGES`] slots are used. A longer name is cut.
    pub fn push_stage(&mut self, name: &str, timing: TimingStats) -> bool {
        let k = self.stage_count as usize;
        if k >= MAX_STAGES {
            return false;
        }
        let mut slot = StageHealth {
            name: [0; STAGE_NAME_LEN],
            timing,
        };
        write_text(&mut slot.name, name);
        self.stages[k] = slot;
        self.stage_count += 1;
        true
    }

    /// The last error as text (empty if none).
    pub fn last_error(&self) -> &str {
        text_of(&self.last_error)
    }

    /// Sets the last error (cut to [`LAST_ERROR_LEN`] bytes at a character
    /// boundary) and its time.
    pub fn set_last_error(&mut self, text: &str, stamp_ns: u64) {
        self.last_error = [0; LAST_ERROR_LEN];
        write_text(&mut self.last_error, text);
        self.last_error_stamp_ns = stamp_ns;
    }
}

impl Default for Health {
    fn default() -> Self {
        Self {
            stamp_ns: 0,
            uptime_ms: 0,
            component: 0,
            pid: 0,
            frames_in: 0,
            frames_out: 0,
            frames_dropped: 0,
            reconnects: 0,
            errors: 0,
            rate_in_hz: 0.0,
            rate_out_hz: 0.0,
            window_ms: 0,
            latency: TimingStats::EMPTY,
            stage_count: 0,
            reserved: 0,
            stages: [StageHealth {
                name: [0; STAGE_NAME_LEN],
                timing: TimingStats::EMPTY,
            }; MAX_STAGES],
            last_error_stamp_ns: 0,
            last_error: [0; LAST_ERROR_LEN],
        }
    }
}

#[cfg(test)]
mod tests {
    use core::mem::{offset_of, size_of};

    use super::*;

    /// The wire layout of `slope.Health.v1`: a change is a new version.
    #[test]
    fn layout_is_pinned() {
        // SAFETY: `type_name` is unsafe to implement, not to call: it
        // returns the pinned constant.
        let type_name = unsafe { <Health as ZeroCopySend>::type_name() };
        assert_eq!(type_name, "slope.Health.v1");
        assert_eq!(size_of::<TimingStats>(), 32);
        assert_eq!(size_of::<StageHealth>(), 48);
        let expected = [
            ("stamp_ns", offset_of!(Health, stamp_ns), 0),
            ("uptime_ms", offset_of!(Health, uptime_ms), 8),
            ("component", offset_of!(Health, component), 16),
            ("pid", offset_of!(Health, pid), 20),
            ("frames_in", offset_of!(Health, frames_in), 24),
            ("frames_out", offset_of!(Health, frames_out), 32),
            ("frames_dropped", offset_of!(Health, frames_dropped), 40),
            ("reconnects", offset_of!(Health, reconnects), 48),
            ("errors", offset_of!(Health, errors), 56),
            ("rate_in_hz", offset_of!(Health, rate_in_hz), 64),
            ("rate_out_hz", offset_of!(Health, rate_out_hz), 72),
            ("window_ms", offset_of!(Health, window_ms), 80),
            ("latency", offset_of!(Health, latency), 88),
            ("stage_count", offset_of!(Health, stage_count), 120),
            ("reserved", offset_of!(Health, reserved), 124),
            ("stages", offset_of!(Health, stages), 128),
            (
                "last_error_stamp_ns",
                offset_of!(Health, last_error_stamp_ns),
                128 + 48 * MAX_STAGES,
            ),
            ("last_error", offset_of!(Health, last_error), 712),
        ];
        for (name, actual, pinned) in expected {
            assert_eq!(actual, pinned, "{name}");
        }
        assert_eq!(712 + LAST_ERROR_LEN, size_of::<Health>());
    }

    #[test]
    fn percentiles_are_nearest_rank() {
        let mut values: Vec<f64> = (1..=100).rev().map(f64::from).collect();
        let t = TimingStats::of(&mut values);
        assert_eq!(
            (t.median_ms, t.p95_ms, t.max_ms, t.count),
            (50.0, 95.0, 100.0, 100)
        );
        let t = TimingStats::of(&mut [7.0]);
        assert_eq!((t.median_ms, t.p95_ms, t.max_ms), (7.0, 7.0, 7.0));
        let t = TimingStats::of(&mut [3.0, 1.0, 2.0]);
        assert_eq!((t.median_ms, t.p95_ms, t.max_ms), (2.0, 3.0, 3.0));
        assert!(TimingStats::of(&mut []).median_ms.is_nan());
    }

    #[test]
    fn stages_and_errors_round_trip_as_text() {
        let mut h = Health::new(HealthComponent::Estimator);
        assert_eq!(h.component(), Some(HealthComponent::Estimator));
        assert!(h.push_stage("outlier", TimingStats::of(&mut [2.0, 4.0])));
        assert!(h.push_stage("a-very-long-stage-name", TimingStats::EMPTY));
        assert_eq!(h.stages().len(), 2);
        assert_eq!(h.stage("outlier").map(|t| t.max_ms), Some(4.0));
        assert_eq!(h.stages()[1].name(), "a-very-long-stag");
        for k in 2..MAX_STAGES {
            assert!(h.push_stage(&format!("s{k}"), TimingStats::EMPTY));
        }
        assert!(!h.push_stage("one too many", TimingStats::EMPTY));
        assert_eq!(h.stages().len(), MAX_STAGES);

        assert_eq!(h.last_error(), "");
        // 'é' is two bytes: a cut inside it keeps the whole characters.
        let long = "é".repeat(LAST_ERROR_LEN);
        h.set_last_error(&long, 5);
        assert_eq!(h.last_error(), "é".repeat(LAST_ERROR_LEN / 2));
        h.set_last_error("cloud service gone", 6);
        assert_eq!(h.last_error(), "cloud service gone");
        assert_eq!(h.last_error_stamp_ns, 6);
    }
}
