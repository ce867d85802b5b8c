//! Opening the Zenoh session ([`open_session`]) on a thread of its own, so
//! that a stop ends the wait while a client retries its router.

use std::sync::mpsc::RecvTimeoutError;
use std::time::{Duration, Instant};

use anyhow::Context;
use slope_sensor::publish::StopFlag;
use slope_tools::cli::WAKE_INTERVAL;
use zenoh::Wait;

use super::reason::zenoh_reason;

/// What a Zenoh configuration says about the network, for the log and
/// for error messages (JSON, as Zenoh gives it).
#[derive(Debug, Clone, Default)]
pub(super) struct Network {
    pub(super) mode: String,
    pub(super) listen: String,
    pub(super) connect: String,
}

impl Network {
    pub(super) fn of(config: &zenoh::Config) -> Self {
        let get = |key: &str| config.get_json(key).unwrap_or_default();
        Network {
            mode: get("mode"),
            listen: get("listen/endpoints"),
            connect: get("connect/endpoints"),
        }
    }
}

/// How long the session may take to open before the log says that the
/// bridge waits.
const WAITING_NOTE_AFTER: Duration = Duration::from_secs(1);

/// Opens the Zenoh session of `config` on a thread of its own, so that a
/// stop (SIGINT, SIGTERM) ends the wait: in client mode Zenoh retries the
/// router until it answers. `None` when stopped first.
pub(super) fn open_session(
    config: zenoh::Config,
    network: &Network,
    stop: &StopFlag,
) -> anyhow::Result<Option<zenoh::Session>> {
    let Network {
        mode,
        listen,
        connect,
    } = network;
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("zenoh-open".into())
        .spawn(move || {
            // The receiver is gone only when the bridge stopped waiting.
            let _ = tx.send(zenoh::open(config).wait());
        })
        .context("cannot start the thread that opens the Zenoh session")?;
    let started = Instant::now();
    let mut noted = false;
    loop {
        match rx.recv_timeout(WAKE_INTERVAL) {
            Ok(Ok(session)) => return Ok(Some(session)),
            Ok(Err(e)) => {
                anyhow::bail!(
                    "cannot open the Zenoh session (mode {mode}, listen {listen}, connect \
                     {connect}): {}",
                    zenoh_reason(&e)
                )
            }
            Err(RecvTimeoutError::Timeout) => {
                if stop.is_stopped() {
                    tracing::info!("stopped while waiting for Zenoh");
                    return Ok(None);
                }
                if !noted && started.elapsed() >= WAITING_NOTE_AFTER {
                    noted = true;
                    tracing::info!(
                        mode = %mode,
                        connect = %connect,
                        "waiting for Zenoh to connect (client mode retries the router until it \
                         answers; SIGINT or SIGTERM stops)"
                    );
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                anyhow::bail!("the thread opening the Zenoh session ended without an answer")
            }
        }
    }
}
