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

/// The daemon's command line, parsed; a usage error (a typo in the flags
/// of `/etc/default/slope`, say) is also sent to the service manager as
/// `STATUS=failed: invalid command line: ...` before clap prints it and
/// exits with status 2, which the units do not restart
/// (`RestartPreventExitStatus=78 2`). `--help` and `--version` print as
/// usual.
pub fn parse_daemon_args<T: clap::Parser>() -> T {
    T::try_parse().unwrap_or_else(|err| usage_exit(err))
}

/// [`parse_daemon_args`] of `args` (the program's name first) instead of
/// the process's.
pub fn parse_daemon_args_from<T: clap::Parser>(
    args: impl IntoIterator<Item = std::ffi::OsString>,
) -> T {
    T::try_parse_from(args).unwrap_or_else(|err| usage_exit(err))
}

/// Ends a daemon on `err` as [`parse_daemon_args`] does: a usage error is
/// also the service manager's status line; exits with clap's status.
pub fn usage_exit(err: clap::Error) -> ! {
    if err.use_stderr() {
        send(&[NotifyState::Status(&usage_failure(&err.to_string()))]);
    }
    err.exit()
}

/// `failed: invalid command line: <clap's first line without "error: ">`.
fn usage_failure(clap_message: &str) -> String {
    let first = clap_message.lines().next().unwrap_or_default();
    format!(
        "failed: invalid command line: {}",
        first.strip_prefix("error: ").unwrap_or(first)
    )
}

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
