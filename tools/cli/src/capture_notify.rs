//! What `slope-capture` tells systemd (a `Type=notify` unit), kept apart
//! from the Kinect so that it can be tested with any frame source:
//!
//! - while it waits for a device: `WATCHDOG=1` when due, and a status line
//!   a second (`waiting for a Kinect v2 ...`) with `EXTEND_TIMEOUT_USEC`,
//!   so that waiting for a camera does not run into the unit's start
//!   timeout;
//! - `READY=1` once the first cloud is published (really streaming);
//! - then `WATCHDOG=1` from the frame loop (and from every wait of the
//!   source: a lost device, a reconnect) and `STATUS=` once a second:
//!   `streaming: 30.0 fps, 1234 frames, 0 dropped, 0 reconnects`;
//! - `STATUS=failed: <reason>` before a failed exit, `STOPPING=1` on the
//!   way out.
//!
//! With [`CaptureNotifier::attach_health`] the same counters also go out as
//! health reports on `<prefix>/health` (component `capture`: frames in,
//! out, dropped, reconnects, rates) and into the log every 10 s.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;

use slope_sensor::ipc::CloudPublisher;
use slope_sensor::publish::{
    publish_stream_observed, PublishError, PublishOptions, PublishStats, StopFlag,
};
use slope_sensor::source::FrameSource;

use crate::health::HealthReporter;
use crate::service_manager::ServiceManager;

/// The source's counters, as far as the status line needs them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SourceCounters {
    /// Frame sets the camera spoiled (skipped).
    pub dropped: u64,
    /// Times the device was lost.
    pub lost: u64,
    /// Successful reopenings.
    pub reconnects: u64,
    /// Failed attempts to open a device.
    pub failed_opens: u64,
}

/// The capture's side of the notify protocol.
#[derive(Debug)]
pub struct CaptureNotifier {
    manager: ServiceManager,
    source: SourceCounters,
    published: u64,
    /// Published count and time of the last status line (for its fps).
    last_status: Option<(u64, Instant)>,
    /// Health reports, once attached, and what they have counted so far.
    health: Option<HealthReporter>,
    counted: (SourceCounters, u64),
}

/// Shared between the source's wait hook and the frame loop.
pub type SharedNotifier = Rc<RefCell<CaptureNotifier>>;

impl CaptureNotifier {
    /// Talks to systemd when started by it (`NOTIFY_SOCKET`), else does
    /// nothing.
    pub fn from_env() -> SharedNotifier {
        Rc::new(RefCell::new(Self {
            manager: ServiceManager::from_env(),
            source: SourceCounters::default(),
            published: 0,
            last_status: None,
            health: None,
            counted: (SourceCounters::default(), 0),
        }))
    }

    /// Reports the capture's health from now on (`HealthComponent::Capture`).
    pub fn attach_health(&mut self, reporter: HealthReporter) {
        self.health = Some(reporter);
    }

    /// From every wait of the source (about every 200 ms) and every frame.
    pub fn on_wait(&mut self, source: SourceCounters) {
        self.source = source;
        self.tick();
    }

    /// After every published cloud: `READY=1` after the first.
    pub fn on_published(&mut self, stats: &PublishStats) {
        self.published = stats.published;
        if !self.manager.is_ready() {
            self.last_status = Some((self.published, Instant::now()));
            let line = self.status_line(None);
            self.manager.ready(&line);
        }
        self.tick();
    }

    /// `STATUS=failed: ...` before the process exits with an error.
    pub fn failed(&mut self, reason: &str) {
        let line = format!("failed: {}", reason.replace('\n', " "));
        self.manager.status(&line);
        if let Some(health) = &mut self.health {
            health.monitor.error(reason);
        }
    }

    pub fn stopping(&self) {
        self.manager.stopping();
    }

    /// Brings the health counters up to the source's and the loop's.
    fn count_health(&mut self) {
        let Some(health) = &mut self.health else {
            return;
        };
        let (before, published_before) = self.counted;
        let m = &mut health.monitor;
        let published = self.published.saturating_sub(published_before);
        let dropped = self.source.dropped.saturating_sub(before.dropped);
        m.frames_in(published + dropped);
        m.dropped(dropped);
        for _ in 0..published {
            m.frame_out(None, &[]);
        }
        for _ in 0..self.source.reconnects.saturating_sub(before.reconnects) {
            m.reconnected();
        }
        self.counted = (self.source, self.published);
        health.tick();
    }

    fn tick(&mut self) {
        self.count_health();
        let Self {
            manager,
            source,
            published,
            last_status,
            ..
        } = self;
        let streaming = manager.is_ready();
        manager.tick(|| {
            let now = Instant::now();
            let fps = last_status.map(|(count, at)| {
                let seconds = now.duration_since(at).as_secs_f64().max(1e-3);
                (*published - count) as f64 / seconds
            });
            *last_status = Some((*published, now));
            line(*source, *published, fps, streaming)
        });
    }

    fn status_line(&self, fps: Option<f64>) -> String {
        line(self.source, self.published, fps, self.manager.is_ready())
    }
}

/// The one-line summary.
fn line(source: SourceCounters, published: u64, fps: Option<f64>, streaming: bool) -> String {
    if !streaming && published == 0 {
        return format!(
            "waiting for a Kinect v2 ({} failed opens)",
            source.failed_opens
        );
    }
    let fps = fps.map_or_else(|| "-".to_string(), |fps| format!("{fps:.1}"));
    format!(
        "streaming: {fps} fps, {published} frames, {} dropped, {} lost, {} reconnects",
        source.dropped, source.lost, source.reconnects
    )
}

/// Publishes `source` like [`slope_sensor::publish::publish_stream`],
/// telling systemd through `notifier` (`READY=1` after the first cloud).
pub fn publish_notifying(
    source: &mut dyn FrameSource,
    publisher: &CloudPublisher,
    options: &PublishOptions,
    stop: &StopFlag,
    notifier: &SharedNotifier,
) -> Result<PublishStats, PublishError> {
    publish_stream_observed(source, publisher, options, stop, &mut |stats| {
        notifier.borrow_mut().on_published(stats)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_status_line_says_what_the_capture_does() {
        let counters = SourceCounters {
            dropped: 3,
            lost: 1,
            reconnects: 1,
            failed_opens: 2,
        };
        assert_eq!(
            line(counters, 0, None, false),
            "waiting for a Kinect v2 (2 failed opens)"
        );
        assert_eq!(
            line(counters, 300, Some(29.96), true),
            "streaming: 30.0 fps, 300 frames, 3 dropped, 1 lost, 1 reconnects"
        );
    }
}
