//! [`MissingDepthDetector`]: tells a depth pipeline that never works from a
//! camera that went away.
//!
//! When libfreenect2's OpenCL or CUDA depth decoder cannot initialise (no
//! driver, a wrong `--gpu-device`), the camera keeps streaming: colour
//! frames arrive, depth never does, and the decoder logs an error for every
//! depth packet (about 30 a second). To the frame timeout that looks like a
//! lost device, and reconnecting (which resets the USB device) cannot cure
//! it. The detector is fed what the listener and libfreenect2's log saw
//! (cumulative counts) and reports when, for a whole window with no depth
//! frame, colour kept flowing or the decoder kept failing. Pure logic, no
//! device: `Kinect2Source` feeds it on every empty wait slice.

use std::time::{Duration, Instant};

/// Colour frames that must arrive without depth before colour counts as
/// flowing (a few stray frames around a reset do not).
pub const MIN_COLOR_FRAMES: u64 = 10;
/// Decoder errors that must be logged without depth before they count.
pub const MIN_PIPELINE_ERRORS: u64 = 3;

/// What the detector saw when it gave its verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MissingDepth {
    /// Colour frames that arrived since the last depth frame.
    pub color_frames: u64,
    /// Depth decoder errors logged since the last depth frame.
    pub pipeline_errors: u64,
    /// How long that went on.
    pub waited: Duration,
}

/// Watches the cumulative frame and error counts of one stream.
#[derive(Debug, Clone)]
pub struct MissingDepthDetector {
    window: Duration,
    /// The counts at the last observation: colour, depth, decoder errors.
    last: Option<(u64, u64, u64)>,
    /// Since when colour flowed or the decoder failed without depth.
    since: Option<Instant>,
    color_frames: u64,
    pipeline_errors: u64,
}

impl MissingDepthDetector {
    /// A detector that reports after `window` without depth.
    pub fn new(window: Duration) -> Self {
        Self {
            window,
            last: None,
            since: None,
            color_frames: 0,
            pipeline_errors: 0,
        }
    }

    /// Starts over (a new device, a new listener: its counts start at 0).
    pub fn restart(&mut self) {
        *self = Self::new(self.window);
    }

    /// Feeds the counts at `now`: colour and depth frames delivered so far
    /// by this stream's listener, and depth decoder errors logged so far in
    /// the process. `Some` once depth has been missing for the whole window
    /// while colour flowed or the decoder kept failing.
    pub fn observe(
        &mut self,
        now: Instant,
        color_frames: u64,
        depth_frames: u64,
        pipeline_errors: u64,
    ) -> Option<MissingDepth> {
        let Some((last_color, last_depth, last_errors)) =
            self.last
                .replace((color_frames, depth_frames, pipeline_errors))
        else {
            // The first observation is the baseline: errors logged by an
            // earlier stream are not this one's.
            return None;
        };
        if depth_frames != last_depth {
            self.since = None;
            self.color_frames = 0;
            self.pipeline_errors = 0;
            return None;
        }
        let new_color = color_frames.saturating_sub(last_color);
        let new_errors = pipeline_errors.saturating_sub(last_errors);
        if new_color > 0 || new_errors > 0 {
            self.since.get_or_insert(now);
        }
        self.color_frames += new_color;
        self.pipeline_errors += new_errors;
        let since = self.since?;
        let waited = now.saturating_duration_since(since);
        let evidence =
            self.color_frames >= MIN_COLOR_FRAMES || self.pipeline_errors >= MIN_PIPELINE_ERRORS;
        (waited >= self.window && evidence).then_some(MissingDepth {
            color_frames: self.color_frames,
            pipeline_errors: self.pipeline_errors,
            waited,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WINDOW: Duration = Duration::from_secs(2);

    /// Feeds 30 Hz of colour (and of depth when `depth`) for `seconds`,
    /// observing every 200 ms as the source does; the first verdict.
    fn stream(
        detector: &mut MissingDepthDetector,
        start: Instant,
        seconds: f64,
        depth: bool,
        errors_per_s: u64,
    ) -> Option<(f64, MissingDepth)> {
        let slices = (seconds / 0.2).round() as u64;
        (0..=slices).find_map(|slice| {
            let t = slice as f64 * 0.2;
            let frames = (t * 30.0) as u64;
            let now = start + Duration::from_secs_f64(t);
            let errors = (t * errors_per_s as f64) as u64;
            detector
                .observe(now, frames, if depth { frames } else { 0 }, errors)
                .map(|verdict| (t, verdict))
        })
    }

    #[test]
    fn colour_without_depth_for_the_window_is_reported_once_the_window_is_over() {
        let mut detector = MissingDepthDetector::new(WINDOW);
        let (t, verdict) = stream(&mut detector, Instant::now(), 5.0, false, 0).expect("a verdict");
        // Colour starts flowing at the second slice (0.2 s); 2 s later.
        assert!((2.2..=2.41).contains(&t), "reported at {t} s");
        assert!(verdict.color_frames >= 60, "{verdict:?}");
        assert_eq!(verdict.pipeline_errors, 0);
        assert!(verdict.waited >= WINDOW);
    }

    #[test]
    fn a_stream_with_depth_is_never_reported() {
        let mut detector = MissingDepthDetector::new(WINDOW);
        assert_eq!(stream(&mut detector, Instant::now(), 10.0, true, 0), None);
    }

    #[test]
    fn a_silent_camera_is_a_lost_device_not_a_broken_pipeline() {
        // Nothing at all arrives: the frame timeout's business.
        let mut detector = MissingDepthDetector::new(WINDOW);
        let start = Instant::now();
        for slice in 0..50 {
            let now = start + Duration::from_millis(200 * slice);
            assert_eq!(detector.observe(now, 0, 0, 0), None);
        }
    }

    #[test]
    fn decoder_errors_alone_are_enough_without_colour() {
        // Depth-only streaming with a failing OpenCL decoder: 30 errors a second.
        let mut detector = MissingDepthDetector::new(WINDOW);
        let start = Instant::now();
        let verdict = (0..=25).find_map(|slice| {
            let t = slice as f64 * 0.2;
            let now = start + Duration::from_secs_f64(t);
            detector.observe(now, 0, 0, 100 + (t * 30.0) as u64)
        });
        let verdict = verdict.expect("a verdict");
        assert_eq!(verdict.color_frames, 0);
        assert!(verdict.pipeline_errors >= 60, "{verdict:?}");
    }

    #[test]
    fn a_depth_frame_starts_the_window_over_and_so_does_a_restart() {
        let mut detector = MissingDepthDetector::new(WINDOW);
        let start = Instant::now();
        detector.observe(start, 0, 0, 0);
        detector.observe(start + Duration::from_millis(1900), 57, 0, 0);
        // One depth frame at 1.9 s: still working, just slow.
        assert_eq!(
            detector.observe(start + Duration::from_millis(2100), 63, 1, 0),
            None
        );
        assert_eq!(
            detector.observe(start + Duration::from_millis(3000), 90, 1, 0),
            None
        );
        detector.restart();
        // Errors logged before the restart are the baseline, not evidence.
        assert_eq!(detector.observe(start, 0, 0, 500), None);
        assert_eq!(
            detector.observe(start + Duration::from_secs(3), 0, 0, 500),
            None
        );
    }
}
