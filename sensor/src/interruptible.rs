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
    use std::time::Instant;

    const SLICE: Duration = Duration::from_millis(200);

    /// A simulated open that blocks for 5 s: a stop request 100 ms in ends
    /// the wait within one slice, and the open finishes (and cleans up) on
    /// its own thread afterwards.
    #[test]
    fn a_stop_during_a_slow_open_returns_within_one_slice() {
        let stop = StopFlag::new();
        let stopper = stop.clone();
        let finished = Arc::new(AtomicBool::new(false));
        let done = Arc::clone(&finished);
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(100));
            stopper.stop();
        });
        let started = Instant::now();
        let mut slices = 0;
        let outcome =
            run_interruptible("slow-open", &stop, SLICE, &mut || slices += 1, move || {
                std::thread::sleep(Duration::from_secs(5));
                done.store(true, Ordering::SeqCst);
                42
            })
            .expect("runs");
        let waited = started.elapsed();
        assert_eq!(outcome, None);
        assert!(
            waited < Duration::from_millis(100) + SLICE + Duration::from_millis(150),
            "{waited:?}"
        );
        assert!(!finished.load(Ordering::SeqCst));
    }

    #[test]
    fn a_quick_call_gives_its_result_and_slices_are_reported() {
        let stop = StopFlag::new();
        let mut slices = 0;
        let outcome = run_interruptible(
            "quick",
            &stop,
            Duration::from_millis(10),
            &mut || slices += 1,
            || {
                std::thread::sleep(Duration::from_millis(60));
                "opened"
            },
        )
        .expect("runs");
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
