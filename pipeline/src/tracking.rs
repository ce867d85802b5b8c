//! Tracking: one stable slope for the plane ahead, followed from frame to
//! frame.
//!
//! A robot wants one number for the ramp ahead, not 30 raw ones a second.
//! The tracker keeps the last `window` accepted per-frame slopes of the
//! plane it follows and reports their median:
//!
//! - **Which frames count.** An `ok` estimate with at least
//!   `min_confidence`. Others leave the track as it is; after `max_missed`
//!   such frames in a row (1 s at 30 Hz) the track ends (the plane is out of
//!   view).
//! - **Same plane.** A frame belongs to the tracked plane when its signed
//!   slope is within the gate of the track's median: `max(gate_deg,
//!   gate_sigmas * sigma)`, sigma the robust spread (1.4826 MAD) of the
//!   window. The slope of a plane does not change as the robot drives
//!   towards it, so distance is not gated (it shrinks as the robot
//!   approaches).
//! - **Outliers are rejected, not averaged in.** A frame outside the gate is
//!   not added to the window.
//! - **Reset when the road changes.** A frame whose road (the surface the
//!   slope is measured on, `selection/road.rs`) lies more than
//!   `road_change_m` nearer or farther than the last accepted frame's, or
//!   turns by more than `road_change_heading_deg`, is another surface (the
//!   wall behind a ramp, a ramp beside the first): the track restarts from
//!   it at once, even at the same slope. A glitch at the same place is no
//!   new road and is gated as any frame.
//! - **Reset when the plane ahead changes.** When `reset_after` rejected
//!   frames in a row agree with each other (all within the gate of their own
//!   median), the track restarts from them: a new ramp, a wall after a
//!   ramp.
//! - **One stream, one track.** The track restarts when the frames stop
//!   continuing one stream ([`StreamPosition::continues`]): the frame index
//!   does not grow (a new stream, a replay started again), the
//!   capture time goes back or jumps by more than `max_gap_s` (the camera
//!   paused or was restarted; 1.5 s, so that a replay at 1 Hz keeps its
//!   track whatever its timing jitter), the index jumps further than the
//!   time allows at [`MAX_FRAME_RATE_HZ`], or the image size or intrinsics
//!   change (another camera). A slope tracked before a pause is not the slope of
//!   what is ahead after it.
//! - **Its own standard deviation.** `1.2533 sigma / sqrt(n)` (the standard
//!   error of a median of n), sigma the larger of the window's robust spread
//!   and the median of the frames' own errors (`slope_std_deg / sqrt(samples)`),
//!   so a window of identical values does not claim zero error. Without
//!   the frames' own errors (the least-squares and TLS baselines have no
//!   spread), the window's spread once it holds 3 frames that differ; NaN
//!   (unknown) before.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};
use slope_ipc_types::{EstimateStatus, Intrinsics};

use crate::cloud::CloudView;
use crate::validate::{at_least, fraction, non_negative, positive, InvalidValue};

/// The tracked slope after a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackedSlope {
    /// Signed slope of the tracked plane, degrees (NaN when there is no
    /// track).
    pub slope_deg: f64,
    /// Standard deviation of `slope_deg`, degrees (NaN when there is no
    /// track, or while it is unknown: see the module doc).
    pub std_deg: f64,
    /// Frames accepted into the track since it (re)started (0: no track).
    pub frames: u32,
    /// True when this frame's estimate was accepted into the track.
    pub accepted: bool,
}

/// Tracking parameters (`[tracking]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrackingConfig {
    /// Accepted frames whose median is the tracked slope.
    pub window: usize,
    /// Frames with less confidence are not used.
    pub min_confidence: f64,
    /// The smallest gate around the track's median, degrees.
    pub gate_deg: f64,
    /// The gate in robust spreads of the window.
    pub gate_sigmas: f64,
    /// Rejected frames in a row that agree with each other restart the
    /// track.
    pub reset_after: usize,
    /// Frames in a row without a usable estimate end the track.
    pub max_missed: usize,
    /// A longer pause between two frames' capture times, seconds, ends the
    /// track: 1.5 s, half a second more than `max_missed` frames at 30 Hz,
    /// so that frames one second apart (`slope-replay --rate 1`) keep it
    /// whatever their jitter.
    pub max_gap_s: f64,
    /// The road is another surface when its nearest point in the corridor
    /// moved by more than this since the last accepted frame, metres (a
    /// robot covers a few centimetres a frame).
    pub road_change_m: f64,
    /// ...or its heading turned by more than this, degrees.
    pub road_change_heading_deg: f64,
}

impl Default for TrackingConfig {
    fn default() -> Self {
        Self {
            window: 15,
            min_confidence: 0.3,
            gate_deg: 2.0,
            gate_sigmas: 4.0,
            reset_after: 5,
            max_missed: 30,
            max_gap_s: 1.5,
            road_change_m: 0.5,
            road_change_heading_deg: 20.0,
        }
    }
}

impl TrackingConfig {
    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), InvalidValue> {
        at_least("window", self.window, 1)?;
        at_least("reset_after", self.reset_after, 1)?;
        at_least("max_missed", self.max_missed, 1)?;
        fraction("min_confidence", self.min_confidence)?;
        non_negative("gate_deg", self.gate_deg)?;
        non_negative("gate_sigmas", self.gate_sigmas)?;
        positive("max_gap_s", self.max_gap_s)?;
        positive("road_change_m", self.road_change_m)?;
        crate::validate::angle("road_change_heading_deg", self.road_change_heading_deg)
    }
}

/// Where a frame sits in its stream, as far as the track goes: its index,
/// capture time and camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamPosition {
    pub index: u64,
    /// Capture time, nanoseconds (any epoch, one clock per stream).
    pub stamp_ns: u64,
    pub width: usize,
    pub height: usize,
    pub intrinsics: Intrinsics,
}

/// The fastest frame rate a stream is taken to have: an index that grows
/// by more than one frame plus this rate times the time since the last
/// frame is another stream (or a broken counter), not dropped frames. Far
/// above any camera: a burst from a replay or another publisher (200
/// clouds in 120 ms, 1.7 kHz) is still one stream whose skipped clouds are
/// dropped frames, while an index that jumps to 2^64 - 1 is not.
pub const MAX_FRAME_RATE_HZ: f64 = 100_000.0;

impl StreamPosition {
    /// The position of frame `index`, captured at `stamp_ns`, of `cloud`'s
    /// camera.
    pub fn of(cloud: &CloudView<'_>, index: u64, stamp_ns: u64) -> Self {
        Self {
            index,
            stamp_ns,
            width: cloud.width,
            height: cloud.height,
            intrinsics: cloud.intrinsics,
        }
    }

    /// True when `next` is a later frame of the same stream: a larger
    /// index, by at most 1 + [`MAX_FRAME_RATE_HZ`] times the time between
    /// them; a capture time neither earlier nor more than `max_gap_s`
    /// later; the same image size and intrinsics (bit for bit).
    pub fn continues(&self, next: &StreamPosition, max_gap_s: f64) -> bool {
        let gap_s = next
            .stamp_ns
            .checked_sub(self.stamp_ns)
            .map(|ns| ns as f64 * 1e-9);
        let camera = |p: &StreamPosition| {
            let k = p.intrinsics;
            (
                p.width,
                p.height,
                [k.fx, k.fy, k.cx, k.cy].map(f64::to_bits),
            )
        };
        let plausible = |gap_s: f64| {
            let step = (next.index - self.index) as f64;
            step <= 1.0 + MAX_FRAME_RATE_HZ * gap_s
        };
        next.index > self.index
            && gap_s.is_some_and(|gap| gap <= max_gap_s && plausible(gap))
            && camera(self) == camera(next)
    }
}

/// One frame's estimate as the tracker sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameSlope {
    pub status: EstimateStatus,
    pub slope_deg: f64,
    /// The frame's own error of `slope_deg`, degrees.
    pub error_deg: f64,
    pub confidence: f64,
    /// Where the road is (`None`: unknown, never a change of road).
    pub road: Option<RoadPlace>,
}

/// Where a frame's road is: what tells one surface from another as the
/// robot drives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoadPlace {
    /// Forward distance to its nearest point in the corridor, metres.
    pub distance_m: f64,
    /// Heading of its uphill direction, degrees.
    pub heading_deg: f64,
}

impl RoadPlace {
    /// True when `next` is another surface than `self`.
    fn is_other(&self, next: &RoadPlace, config: &TrackingConfig) -> bool {
        let turn = (next.heading_deg - self.heading_deg + 540.0).rem_euclid(360.0) - 180.0;
        (next.distance_m - self.distance_m).abs() > config.road_change_m
            || turn.abs() > config.road_change_heading_deg
    }
}

#[derive(Debug, Clone, Copy)]
struct Sample {
    slope_deg: f64,
    /// The frame's own error, NaN when unknown.
    error_deg: f64,
}

/// Follows the inclined plane's slope over frames.
#[derive(Debug, Clone, Default)]
pub struct SlopeTracker {
    window: VecDeque<Sample>,
    rejected: Vec<Sample>,
    frames: u32,
    missed: usize,
    scratch: Vec<f64>,
    /// The last frame seen.
    last: Option<StreamPosition>,
    /// The road of the last accepted frame.
    road: Option<RoadPlace>,
}

impl SlopeTracker {
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds one frame at `position` of its stream; returns the track after
    /// it. A frame that does not continue the last one's stream starts a
    /// new track.
    pub fn update_at(
        &mut self,
        position: StreamPosition,
        frame: &FrameSlope,
        config: &TrackingConfig,
    ) -> TrackedSlope {
        let continues = self
            .last
            .is_some_and(|last| last.continues(&position, config.max_gap_s));
        if !continues {
            self.clear();
            self.missed = 0;
        }
        self.last = Some(position);
        self.update(frame, config)
    }

    /// Feeds the next frame of the stream; returns the track after it.
    fn update(&mut self, frame: &FrameSlope, config: &TrackingConfig) -> TrackedSlope {
        let usable = frame.status == EstimateStatus::Ok
            && frame.slope_deg.is_finite()
            && frame.confidence >= config.min_confidence;
        if !usable {
            self.missed += 1;
            if self.missed >= config.max_missed.max(1) {
                self.clear();
            }
            return self.tracked(false);
        }
        self.missed = 0;
        if let (Some(last), Some(next)) = (self.road, frame.road) {
            if last.is_other(&next, config) {
                self.clear();
            }
        }
        let sample = Sample {
            slope_deg: frame.slope_deg,
            error_deg: frame.error_deg,
        };
        let accepted = match self.median_and_sigma() {
            None => true,
            Some((median, sigma)) => {
                (sample.slope_deg - median).abs() <= config.gate_deg.max(config.gate_sigmas * sigma)
            }
        };
        if accepted {
            self.rejected.clear();
            self.road = frame.road;
            self.push(sample, config);
        } else {
            self.rejected.push(sample);
            if self.rejected.len() >= config.reset_after.max(1) && self.rejected_agree(config) {
                let restart = std::mem::take(&mut self.rejected);
                self.clear();
                for s in restart {
                    self.push(s, config);
                }
                self.road = frame.road;
                return self.tracked(true);
            }
        }
        self.tracked(accepted)
    }

    fn push(&mut self, sample: Sample, config: &TrackingConfig) {
        self.window.push_back(sample);
        while self.window.len() > config.window.max(1) {
            self.window.pop_front();
        }
        self.frames = self.frames.saturating_add(1);
    }

    fn clear(&mut self) {
        self.road = None;
        self.window.clear();
        self.rejected.clear();
        self.frames = 0;
    }

    /// True when the rejected frames all lie within the gate of their median.
    fn rejected_agree(&mut self, config: &TrackingConfig) -> bool {
        self.scratch.clear();
        self.scratch
            .extend(self.rejected.iter().map(|s| s.slope_deg));
        let median = median(&mut self.scratch);
        self.rejected
            .iter()
            .all(|s| (s.slope_deg - median).abs() <= config.gate_deg)
    }

    /// The window's median and robust spread (the larger of 1.4826 MAD and
    /// the median of the frames' own errors).
    fn median_and_sigma(&mut self) -> Option<(f64, f64)> {
        if self.window.is_empty() {
            return None;
        }
        self.scratch.clear();
        self.scratch.extend(self.window.iter().map(|s| s.slope_deg));
        let m = median(&mut self.scratch);
        self.scratch.clear();
        self.scratch
            .extend(self.window.iter().map(|s| (s.slope_deg - m).abs()));
        let mad = 1.4826 * median(&mut self.scratch);
        self.scratch.clear();
        let known = self.window.iter().map(|s| s.error_deg);
        self.scratch.extend(known.filter(|e| e.is_finite()));
        let own = median(&mut self.scratch);
        let sigma = if own.is_finite() {
            mad.max(own)
        } else if self.window.len() >= 3 && mad > 0.0 {
            // No frame's own error is known (the baselines: one fit, no
            // spread): the window's spread alone, once it says something.
            mad
        } else {
            f64::NAN
        };
        Some((m, sigma))
    }

    fn tracked(&mut self, accepted: bool) -> TrackedSlope {
        match self.median_and_sigma() {
            Some((slope, sigma)) => TrackedSlope {
                slope_deg: slope,
                std_deg: 1.2533 * sigma / (self.window.len() as f64).sqrt(),
                frames: self.frames,
                accepted,
            },
            None => TrackedSlope {
                slope_deg: f64::NAN,
                std_deg: f64::NAN,
                frames: 0,
                accepted: false,
            },
        }
    }
}

/// The median of `values` (reordered); NaN when empty.
fn median(values: &mut [f64]) -> f64 {
    let n = values.len();
    if n == 0 {
        return f64::NAN;
    }
    values.sort_unstable_by(f64::total_cmp);
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok(slope_deg: f64) -> FrameSlope {
        FrameSlope {
            status: EstimateStatus::Ok,
            slope_deg,
            error_deg: 0.05,
            confidence: 1.0,
            road: None,
        }
    }

    #[test]
    fn outliers_are_rejected_and_a_new_plane_restarts_the_track() {
        let config = TrackingConfig::default();
        let mut t = SlopeTracker::new();
        let raw = [16.1, 15.9, 16.0, 31.0, 16.05, 3.0, 15.95, 16.0, 60.0, 16.02];
        for (k, &s) in raw.iter().enumerate() {
            let tr = t.update(&ok(s), &config);
            assert!(
                (tr.slope_deg - 16.0).abs() <= 0.1 + 1e-9,
                "frame {k}: {tr:?}"
            );
            assert_eq!(tr.accepted, (s - 16.0f64).abs() < 1.0, "frame {k}");
        }
        // A wall after the ramp: four rejected frames, the fifth restarts.
        for k in 0..config.reset_after {
            let tr = t.update(&ok(90.0 + 0.1 * k as f64), &config);
            if k + 1 < config.reset_after {
                assert!((tr.slope_deg - 16.0).abs() <= 0.1 + 1e-9, "{tr:?}");
            } else {
                assert!((tr.slope_deg - 90.2).abs() <= 0.11, "{tr:?}");
                assert_eq!(tr.frames, config.reset_after as u32);
            }
        }
    }

    #[test]
    fn unusable_frames_hold_the_track_until_it_is_lost() {
        let config = TrackingConfig::default();
        let mut t = SlopeTracker::new();
        t.update(&ok(10.0), &config);
        let none = FrameSlope {
            status: EstimateStatus::NoInclinedPlane,
            slope_deg: f64::NAN,
            error_deg: f64::NAN,
            confidence: 0.0,
            road: None,
        };
        let low = FrameSlope {
            confidence: 0.1,
            ..ok(40.0)
        };
        for _ in 0..config.max_missed - 1 {
            for f in [&none, &low] {
                let tr = t.update(f, &config);
                assert!(!tr.accepted);
                assert_eq!(tr.slope_deg, 10.0);
            }
            // The usable frame in between keeps the track alive.
            t.update(&ok(10.0), &config);
        }
        for _ in 0..config.max_missed {
            t.update(&none, &config);
        }
        let tr = t.update(&none, &config);
        assert!(tr.slope_deg.is_nan() && tr.frames == 0, "{tr:?}");
    }

    fn at(index: u64, stamp_s: f64) -> StreamPosition {
        StreamPosition {
            index,
            stamp_ns: (stamp_s * 1e9) as u64,
            width: 512,
            height: 424,
            intrinsics: Intrinsics {
                fx: 365.0,
                fy: 365.0,
                cx: 256.3,
                cy: 207.0,
            },
        }
    }

    /// A 16 degree track, then a wall: as the next frame of the stream the
    /// wall is rejected (it takes `reset_after` frames to restart); as the
    /// first frame after a break of the stream it starts a new track.
    #[test]
    fn a_break_in_the_stream_restarts_the_track() {
        let config = TrackingConfig::default();
        let track_16 = || {
            let mut t = SlopeTracker::new();
            for k in 0..10 {
                let tr = t.update_at(at(100 + k, 10.0 + k as f64 / 30.0), &ok(16.0), &config);
                assert_eq!((tr.frames, tr.slope_deg), (k as u32 + 1, 16.0));
            }
            t
        };
        let last = at(109, 10.3);
        let mut next = at(110, 10.3 + 1.0 / 30.0);
        let tr = track_16().update_at(next, &ok(90.0), &config);
        assert!(!tr.accepted && tr.slope_deg == 16.0, "{tr:?}");
        // Dropped frames within the gap still continue the stream.
        next.index = 140;
        next.stamp_ns = last.stamp_ns + 1_499_000_000;
        assert!(last.continues(&next, config.max_gap_s));
        let mut other_intrinsics = next;
        other_intrinsics.intrinsics.cx = 254.69;
        let breaks = [
            // The index starts again (a replay looped or restarted) ...
            StreamPosition { index: 0, ..next },
            StreamPosition { index: 109, ..next },
            // ... the camera paused, or its clock went back ...
            StreamPosition {
                stamp_ns: last.stamp_ns + 1_501_000_000,
                ..next
            },
            StreamPosition {
                stamp_ns: last.stamp_ns - 1,
                ..next
            },
            // ... the index jumps further than 100 kHz allows ...
            StreamPosition {
                index: u64::MAX,
                ..next
            },
            StreamPosition {
                index: 109 + 1 + 100_000 + 1,
                stamp_ns: last.stamp_ns + 1_000_000_000,
                ..next
            },
            // ... or another camera (size, intrinsics).
            StreamPosition {
                width: 640,
                height: 480,
                ..next
            },
            other_intrinsics,
        ];
        for position in breaks {
            assert!(!last.continues(&position, config.max_gap_s), "{position:?}");
            let tr = track_16().update_at(position, &ok(90.0), &config);
            assert!(
                tr.accepted && tr.slope_deg == 90.0 && tr.frames == 1,
                "{position:?}: {tr:?}"
            );
        }
    }

    /// Frames without an error of their own (the baselines) never give a
    /// track of zero error: unknown (NaN) until 3 frames that differ, then
    /// their spread (it was 0 from the first frame).
    #[test]
    fn frames_without_their_own_error_never_claim_zero() {
        let config = TrackingConfig::default();
        let mut t = SlopeTracker::new();
        let fit = |slope_deg| FrameSlope {
            error_deg: f64::NAN,
            ..ok(slope_deg)
        };
        for slope in [16.0, 16.0, 16.0] {
            let tr = t.update(&fit(slope), &config);
            assert!(tr.accepted && tr.std_deg.is_nan(), "{tr:?}");
        }
        let tr = t.update(&fit(16.2), &config);
        assert!(tr.std_deg.is_nan(), "MAD of 16, 16, 16, 16.2 is 0: {tr:?}");
        t.update(&fit(15.8), &config);
        let tr = t.update(&fit(16.1), &config);
        assert!(tr.std_deg > 0.0 && tr.std_deg < 0.2, "{tr:?}");
    }

    #[test]
    fn the_spread_shrinks_with_frames_but_not_to_zero() {
        let config = TrackingConfig::default();
        let mut t = SlopeTracker::new();
        let first = t.update(&ok(5.0), &config);
        let mut last = first;
        for _ in 0..20 {
            last = t.update(&ok(5.0), &config);
        }
        assert!((first.std_deg - 1.2533 * 0.05).abs() < 1e-12);
        assert!((last.std_deg - 1.2533 * 0.05 / 15f64.sqrt()).abs() < 1e-12);
    }
}
