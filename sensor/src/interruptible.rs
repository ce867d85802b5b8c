//! [`run_interruptible`]: a blocking call that a stop request does not have
//! to wait for.
//!
//! Opening a Kinect v2 (libfreenect2 resets the USB device, waits for it to
//! come back, uploads firmware commands) and starting its streams block for
//! seconds inside C++ that cannot be interrupted. Run on a thread of their
//! own, the caller still looks at the [`StopFlag`] every slice and returns
//! as soon as it is set; the abandoned call finishes on its thread and
//! drops its result there (closing the device it may have opened), or dies
//! with the process.

use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use crate::publish::StopFlag;

/// The background call could not run to the end.
#[derive(Debug, thiserror::Error)]
pub enum InterruptibleError {
    #[error("cannot start the thread '{name}': {source}")]
    Spawn {
        name: String,
        #[source]
        source: std::io::Error,
    },
    #[error("the thread '{name}' panicked")]
    Panicked { name: String },
}

/// Runs `work` on a thread named `name` and waits for it in slices of
/// `slice`, calling `on_slice` after each slice that ends without a result
/// (a watchdog ping, say). `Ok(Some(result))` when it finished,
/// `Ok(None)` when `stop` was set first: then this returns within one
/// slice, whatever `work` is doing.
pub fn run_interruptible<T: Send + 'static>(
    name: &str,
    stop: &StopFlag,
    slice: Duration,
    on_slice: &mut dyn FnMut(),
    work: impl FnOnce() -> T + Send + 'static,
) -> Result<Option<T>, InterruptibleError> {
    if stop.is_stopped() {
        return Ok(None);
    }
    let (tx, rx) = mpsc::sync_channel(1);
    std::thread::Builder::new()
        .name(name.to_string())
        .spawn(move || {
            // The receiver is gone when the caller stopped waiting: the
            // result is dropped here.
            let _ = tx.send(work());
        })
        .map_err(|source| InterruptibleError::Spawn {
            name: name.to_string(),
            source,
        })?;
    loop {
        match rx.recv_timeout(slice) {
            Ok(result) => return Ok(Some(result)),
            Err(RecvTimeoutError::Timeout) => {
                if stop.is_stopped() {
                    return Ok(None);
                }
                on_slice();
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(InterruptibleError::Panicked {
                    name: name.to_string(),
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    const SLICE: Duration = Duration::from_millis(200);

    /// How long a test waits for a call that should end at once: past
    /// it, the test fails instead of hanging (no speed is asserted).
    const DEADLINE: Duration = Duration::from_secs(60);

    /// Runs `test` on a thread of its own and gives its result, or fails
    /// when it has not ended within [`DEADLINE`].
    fn within_deadline<T: Send + 'static>(test: impl FnOnce() -> T + Send + 'static) -> T {
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(test());
        });
        rx.recv_timeout(DEADLINE)
            .unwrap_or_else(|e| panic!("no result within {DEADLINE:?}: {e}"))
    }

    /// A simulated open that blocks until released: a stop request made
    /// during the first slice ends the wait at the end of the next one
    /// (no further slice is waited for), and the open finishes (and
    /// cleans up) on its own thread afterwards.
    #[test]
    fn a_stop_during_a_slow_open_returns_within_one_slice() {
        let (release, gate) = mpsc::channel::<()>();
        let (finished_tx, finished) = mpsc::channel::<()>();
        let (outcome, slices) = within_deadline(move || {
            let stop = StopFlag::new();
            let stopper = stop.clone();
            let mut slices = 0;
            let on_slice = &mut || {
                slices += 1;
                if slices == 1 {
                    stopper.stop();
                }
            };
            let outcome = run_interruptible("slow-open", &stop, SLICE, on_slice, move || {
                // Blocks until the test releases it (or drops the sender).
                let _ = gate.recv();
                let _ = finished_tx.send(());
                42
            })
            .expect("runs");
            (outcome, slices)
        });
        assert_eq!(outcome, None);
        assert_eq!(slices, 1, "the wait went on past the slice after the stop");
        assert!(finished.try_recv().is_err(), "the open had not finished");
        release.send(()).expect("the open is still waiting");
        finished
            .recv_timeout(DEADLINE)
            .expect("the abandoned open finishes on its own thread");
    }

    /// A call that outlasts two slices (it waits for the second slice's
    /// callback) gives its result, and the slices it outlasted were
    /// reported.
    #[test]
    fn a_quick_call_gives_its_result_and_slices_are_reported() {
        let (outcome, slices) = within_deadline(|| {
            let stop = StopFlag::new();
            let (release, gate) = mpsc::channel::<()>();
            let mut slices = 0;
            let on_slice = &mut || {
                slices += 1;
                if slices == 2 {
                    let _ = release.send(());
                }
            };
            let outcome = run_interruptible(
                "quick",
                &stop,
                Duration::from_millis(10),
                on_slice,
                move || {
                    let _ = gate.recv();
                    "opened"
                },
            )
            .expect("runs");
            (outcome, slices)
        });
        assert_eq!(outcome, Some("opened"));
        assert!(slices >= 2, "{slices}");
    }

    #[test]
    fn a_stop_before_the_call_runs_nothing_and_a_panic_is_an_error() {
        let stop = StopFlag::new();
        stop.stop();
        let ran = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&ran);
        let outcome = run_interruptible("never", &stop, SLICE, &mut || {}, move || {
            flag.store(true, Ordering::SeqCst)
        })
        .expect("runs");
        assert_eq!(outcome, None);
        assert!(!ran.load(Ordering::SeqCst));
        let running = StopFlag::new();
        let err = run_interruptible("boom", &running, SLICE, &mut || {}, || -> u8 {
            panic!("simulated failure")
        })
        .expect_err("panicked");
        assert!(err.to_string().contains("boom"), "{err}");
    }
}
