//! The systemd notify protocol for the daemons (`Type=notify` units):
//! `READY=1` once really ready, `WATCHDOG=1` from the main loop at half the
//! unit's `WatchdogSec` (so a hung loop is restarted), `STATUS=` with a
//! one-line summary once a second, `STOPPING=1` on the way out. Outside
//! systemd (`NOTIFY_SOCKET` unset) every call does nothing.

use std::time::{Duration, Instant};

use sd_notify::NotifyState;

/// How often the status line is sent.
const STATUS_INTERVAL: Duration = Duration::from_secs(1);

/// While starting up (not yet `READY=1`), each status line also asks for
/// this much more start-up time (`EXTEND_TIMEOUT_USEC`), so that a daemon
/// waiting for its device is not killed by the unit's start timeout.
const START_EXTENSION: Duration = Duration::from_secs(5);

/// Talks to the service manager, when there is one.
#[derive(Debug)]
pub struct ServiceManager {
    /// Half the watchdog interval systemd asked for, if it asked.
    ping_every: Option<Duration>,
    last_ping: Instant,
    last_status: Option<Instant>,
    ready: bool,
}

impl ServiceManager {
    /// Reads `WATCHDOG_USEC` (and `WATCHDOG_PID`) from the environment.
    pub fn from_env() -> Self {
        Self {
            ping_every: sd_notify::watchdog_enabled().map(|d| d / 2),
            last_ping: Instant::now(),
            last_status: None,
            ready: false,
        }
    }

    /// `READY=1` and a first status line.
    pub fn ready(&mut self, status: &str) {
        send(&[NotifyState::Ready, NotifyState::Status(status)]);
        self.last_status = Some(Instant::now());
        self.ready = true;
    }

    pub fn is_ready(&self) -> bool {
        self.ready
    }

    /// A status line now (e.g. why the daemon is about to fail).
    pub fn status(&mut self, status: &str) {
        send(&[NotifyState::Status(status)]);
        self.last_status = Some(Instant::now());
    }

    /// From the main loop: the watchdog ping when due, and the status line
    /// (made only when it is due) once a second; before [`Self::ready`],
    /// with more start-up time (`EXTEND_TIMEOUT_USEC`).
    pub fn tick(&mut self, status: impl FnOnce() -> String) {
        if let Some(every) = self.ping_every {
            if self.last_ping.elapsed() >= every {
                send(&[NotifyState::Watchdog]);
                self.last_ping = Instant::now();
            }
        }
        if self
            .last_status
            .is_none_or(|t| t.elapsed() >= STATUS_INTERVAL)
        {
            let status = status();
            if self.ready {
                send(&[NotifyState::Status(&status)]);
            } else {
                let usec = u32::try_from(START_EXTENSION.as_micros()).unwrap_or(u32::MAX);
                send(&[
                    NotifyState::Status(&status),
                    NotifyState::ExtendTimeoutUsec(usec),
                ]);
            }
            self.last_status = Some(Instant::now());
        }
    }

    /// `STOPPING=1`.
    pub fn stopping(&self) {
        send(&[NotifyState::Stopping]);
    }
}

fn send(state: &[NotifyState<'_>]) {
    if let Err(err) = sd_notify::notify(state) {
        tracing::debug!(error = %err, "could not notify the service manager");
    }
}
