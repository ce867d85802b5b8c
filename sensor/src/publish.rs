//! The publishing loop shared by every source: pull a frame, pace it, project
//! it into shared memory, send it. `slope-replay` and `slope-capture` differ
//! only in the [`FrameSource`] they pass and the [`Pacing`] they ask for.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use slope_ipc_types::now_ns;

use crate::ipc::{CloudPublisher, PublishFrameError};
use crate::source::{FrameSource, SourceError, SourceFrame};

/// Pacing offsets are capped here (about 115 days), far beyond any real
/// recording, so that no timestamp in a file can overflow a clock.
const MAX_PACING_OFFSET_S: f64 = 1e7;

/// Set when the process should stop (SIGINT, SIGTERM); cheap to clone.
#[derive(Debug, Clone, Default)]
pub struct StopFlag(Arc<AtomicBool>);

impl StopFlag {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn stop(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    pub fn is_stopped(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }

    /// Sleeps for `duration` unless stopped first; returns false if stopped.
    pub fn sleep(&self, duration: Duration) -> bool {
        let deadline = Instant::now() + duration;
        loop {
            if self.is_stopped() {
                return false;
            }
            let now = Instant::now();
            if now >= deadline {
                return true;
            }
            std::thread::sleep((deadline - now).min(Duration::from_millis(20)));
        }
    }
}

/// Tells a second stop request (the user insisting: end at once) from one
/// request delivered twice. GNU `timeout` signals its child and then the
/// child's process group, so two SIGTERMs arrive microseconds apart; a
/// signal within [`StopSignals::REPEAT_GRACE`] of the first counts as that
/// first one: 50 ms, far more than the scheduler puts between the two, far
/// less than a person takes to press Ctrl-C again. For the one
/// signal-handler thread of a program.
#[derive(Debug, Default)]
pub struct StopSignals {
    first: Option<Instant>,
}

/// What a stop signal asks for ([`StopSignals::note`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopRequest {
    /// The first: stop after the work in hand.
    First,
    /// The first again (within [`StopSignals::REPEAT_GRACE`]): nothing new.
    Repeat,
    /// A second request: end at once.
    Second,
}

impl StopSignals {
    /// Signals this close to the first are one request.
    pub const REPEAT_GRACE: Duration = Duration::from_millis(50);

    pub fn new() -> Self {
        Self::default()
    }

    /// Notes a signal arriving `now` and says what it asks for.
    pub fn note(&mut self, now: Instant) -> StopRequest {
        match self.first {
            None => {
                self.first = Some(now);
                StopRequest::First
            }
            Some(first) if now.saturating_duration_since(first) < Self::REPEAT_GRACE => {
                StopRequest::Repeat
            }
            Some(_) => StopRequest::Second,
        }
    }
}

/// When to send each frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pacing {
    /// As the source delivers them (a camera paces itself).
    Source,
    /// At the recorded timestamps, scaled: 2.0 plays twice as fast.
    Recorded { speed: f64 },
    /// At a fixed rate, frames per second.
    Rate { hz: f64 },
}

/// How to run a publishing stream.
#[derive(Debug, Clone)]
pub struct PublishOptions {
    pub pacing: Pacing,
    /// Stop after this many frames.
    pub max_frames: Option<u64>,
    /// Wait until this many subscribers are connected before the first frame.
    pub wait_subscribers: usize,
    /// Give up waiting for subscribers after this long.
    pub wait_timeout: Option<Duration>,
    /// Skip (with a warning) frames the source reports as bad, instead of failing.
    pub skip_bad_frames: bool,
}

impl Default for PublishOptions {
    fn default() -> Self {
        Self {
            pacing: Pacing::Source,
            max_frames: None,
            wait_subscribers: 0,
            wait_timeout: None,
            skip_bad_frames: false,
        }
    }
}

/// What a stream did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct PublishStats {
    pub published: u64,
    pub skipped_bad: u64,
    /// True when the stream ended because of the stop flag.
    pub stopped: bool,
}

#[derive(Debug, thiserror::Error)]
pub enum PublishError {
    #[error(transparent)]
    Source(#[from] SourceError),
    #[error(transparent)]
    Publish(#[from] PublishFrameError),
    #[error("only {connected} of {wanted} subscribers connected to '{service}' within {waited:?}")]
    NoSubscribers {
        service: String,
        connected: usize,
        wanted: usize,
        waited: Duration,
    },
}

/// Publishes `source` until it ends, `max_frames` is reached or `stop` is set.
pub fn publish_stream(
    source: &mut dyn FrameSource,
    publisher: &CloudPublisher,
    options: &PublishOptions,
    stop: &StopFlag,
) -> Result<PublishStats, PublishError> {
    publish_stream_observed(source, publisher, options, stop, &mut |_| {})
}

/// [`publish_stream`], calling `on_published` with the counters after every
/// frame sent (a daemon's readiness and status report).
pub fn publish_stream_observed(
    source: &mut dyn FrameSource,
    publisher: &CloudPublisher,
    options: &PublishOptions,
    stop: &StopFlag,
    on_published: &mut dyn FnMut(&PublishStats),
) -> Result<PublishStats, PublishError> {
    let mut stats = PublishStats::default();
    if !wait_for_subscribers(publisher, options, stop)? {
        stats.stopped = true;
        return Ok(stats);
    }
    let mut frame = SourceFrame::default();
    let mut clock: Option<(Instant, u64)> = None;
    let mut sent_at_rate: u64 = 0;
    let mut warned_rows = std::collections::HashSet::new();
    loop {
        if stop.is_stopped() {
            stats.stopped = true;
            break;
        }
        if options.max_frames.is_some_and(|max| stats.published >= max) {
            break;
        }
        match source.next_frame(&mut frame) {
            Ok(true) => {}
            // A source whose read a stop request cut short ends too.
            Ok(false) => {
                stats.stopped = stop.is_stopped();
                break;
            }
            Err(err @ SourceError::BadFrame { row, .. }) if options.skip_bad_frames => {
                stats.skipped_bad += 1;
                // One warning per bad frame per run: a loop meets it again
                // on every pass.
                if warned_rows.insert(row) {
                    tracing::warn!(error = %crate::error_chain::ErrorChain(&err), "skipping bad frame");
                } else {
                    tracing::debug!(error = %crate::error_chain::ErrorChain(&err), "skipping bad frame again");
                }
                continue;
            }
            Err(err) => return Err(err.into()),
        }
        let (start, first_stamp) = *clock.get_or_insert((Instant::now(), frame.source_stamp_ns));
        let offset = match options.pacing {
            Pacing::Source => None,
            Pacing::Recorded { speed } => Some(Duration::from_secs_f64(
                (frame.source_stamp_ns.saturating_sub(first_stamp) as f64 / 1e9 / speed)
                    .min(MAX_PACING_OFFSET_S),
            )),
            Pacing::Rate { hz } => Some(Duration::from_secs_f64(
                (sent_at_rate as f64 / hz).min(MAX_PACING_OFFSET_S),
            )),
        };
        if let Some(offset) = offset {
            let wait = (start + offset).saturating_duration_since(Instant::now());
            if !stop.sleep(wait) {
                stats.stopped = true;
                break;
            }
        }
        // Sources that stamp frames on arrival (the camera) keep their stamp;
        // replayed frames are stamped as they go out.
        if frame.capture_stamp_ns == 0 {
            frame.capture_stamp_ns = now_ns();
        }
        publisher.publish(&frame)?;
        sent_at_rate += 1;
        stats.published += 1;
        on_published(&stats);
        tracing::debug!(
            frame = frame.index,
            subscribers = publisher.subscriber_count(),
            "published cloud"
        );
    }
    Ok(stats)
}

/// Waits for the requested subscribers; false if stopped while waiting.
fn wait_for_subscribers(
    publisher: &CloudPublisher,
    options: &PublishOptions,
    stop: &StopFlag,
) -> Result<bool, PublishError> {
    if options.wait_subscribers == 0 {
        return Ok(true);
    }
    let started = Instant::now();
    tracing::info!(
        wanted = options.wait_subscribers,
        service = publisher.service_name(),
        "waiting for subscribers"
    );
    loop {
        let connected = publisher.subscriber_count();
        if connected >= options.wait_subscribers {
            tracing::info!(connected, "subscribers connected");
            return Ok(true);
        }
        if let Some(timeout) = options.wait_timeout {
            if started.elapsed() >= timeout {
                return Err(PublishError::NoSubscribers {
                    service: publisher.service_name().to_string(),
                    connected,
                    wanted: options.wait_subscribers,
                    waited: timeout,
                });
            }
        }
        if !stop.sleep(Duration::from_millis(10)) {
            return Ok(false);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stop_flag_interrupts_sleep() {
        let stop = StopFlag::new();
        assert!(stop.sleep(Duration::from_millis(1)));
        stop.stop();
        assert!(!stop.sleep(Duration::from_secs(3600)));
        assert!(stop.clone().is_stopped());
    }

    /// `timeout`'s two SIGTERMs (microseconds apart) are one request; a
    /// signal 50 ms or more after the first (no one presses Ctrl-C again
    /// that fast) is a second one.
    #[test]
    fn a_signal_repeated_at_once_is_one_request() {
        let t0 = Instant::now();
        let mut signals = StopSignals::new();
        let at = |ms: u64| t0 + Duration::from_millis(ms);
        assert_eq!(signals.note(t0), StopRequest::First);
        assert_eq!(
            signals.note(t0 + Duration::from_micros(30)),
            StopRequest::Repeat
        );
        assert_eq!(signals.note(at(49)), StopRequest::Repeat);
        assert_eq!(signals.note(at(50)), StopRequest::Second);
        assert_eq!(signals.note(at(3000)), StopRequest::Second);
    }
}
