//! Routes libfreenect2's log lines into `tracing` (target `libfreenect2`)
//! instead of its own stderr logger, and remembers the last error or warning
//! so that our errors can say what libfreenect2 saw.
//!
//! The last problem is kept per thread: libfreenect2 logs from the thread
//! that calls it (open, start, stop) and from its own USB and processing
//! threads, and an error of ours must only quote what our call logged, never
//! a warning another thread happened to log meanwhile. Errors of the depth
//! decoders (`[OpenCLDepthPacketProcessor] ...`, `[CudaDepthPacketProcessor]
//! ...`), which come from libfreenect2's processing thread, are counted
//! separately: [`depth_pipeline_errors`].

use std::cell::RefCell;
use std::ffi::c_void;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, Once};

use super::sys;

/// The target libfreenect2's lines are logged under.
pub const LOG_TARGET: &str = "libfreenect2";

static INSTALL: Once = Once::new();

thread_local! {
    /// The last error or warning libfreenect2 logged on this thread.
    static LAST_PROBLEM: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Errors the depth decoders logged, from any thread.
static DEPTH_PIPELINE_ERRORS: AtomicU64 = AtomicU64::new(0);
/// The last of them.
static LAST_DEPTH_PIPELINE_ERROR: Mutex<Option<String>> = Mutex::new(None);

/// Installs the forwarding once per process (later calls do nothing).
pub fn install() {
    INSTALL.call_once(|| {
        let level = match tracing::level_filters::LevelFilter::current() {
            f if f >= tracing::level_filters::LevelFilter::TRACE => {
                sys::f2s_log_level::F2S_LOG_DEBUG
            }
            f if f >= tracing::level_filters::LevelFilter::DEBUG => {
                sys::f2s_log_level::F2S_LOG_INFO
            }
            _ => sys::f2s_log_level::F2S_LOG_WARNING,
        };
        // SAFETY: `forward` is an `extern "C"` function that lives for the
        // whole process and never unwinds; `user` is unused (null). The Once
        // makes this the only call, before any context exists.
        let status =
            unsafe { sys::f2s_set_log_callback(Some(forward), std::ptr::null_mut(), level) };
        if status != sys::f2s_status::F2S_OK {
            tracing::warn!(
                status = status.0,
                "could not route libfreenect2's log into tracing"
            );
        }
    });
}

/// Forgets this thread's last problem, so that [`take_last_problem`] after
/// a call returns only what that call logged.
pub fn clear_last_problem() {
    let _ = LAST_PROBLEM.try_with(|last| last.borrow_mut().take());
}

/// The last error or warning libfreenect2 logged on this thread since
/// [`clear_last_problem`].
pub fn take_last_problem() -> Option<String> {
    LAST_PROBLEM
        .try_with(|last| last.borrow_mut().take())
        .ok()
        .flatten()
}

/// How many errors libfreenect2's depth decoders have logged in this
/// process, and the last one.
pub fn depth_pipeline_errors() -> (u64, Option<String>) {
    let count = DEPTH_PIPELINE_ERRORS.load(Ordering::SeqCst);
    let last = LAST_DEPTH_PIPELINE_ERROR
        .lock()
        .map(|last| last.clone())
        .unwrap_or_else(|poisoned| poisoned.into_inner().clone());
    (count, last)
}

/// True for an error line of a depth decoder: libfreenect2 prefixes every
/// line with its source, e.g. `[OpenCLDepthPacketProcessor] could not
/// initialize OpenCLDepthPacketProcessor`.
pub(crate) fn is_depth_pipeline_error(level: sys::f2s_log_level, text: &str) -> bool {
    level == sys::f2s_log_level::F2S_LOG_ERROR
        && text
            .strip_prefix('[')
            .and_then(|rest| rest.split_once(']'))
            .is_some_and(|(source, _)| source.contains("DepthPacketProcessor"))
}

/// Remembers a line of `level` logged on the calling thread.
fn remember(level: sys::f2s_log_level, text: &str) {
    if level == sys::f2s_log_level::F2S_LOG_ERROR || level == sys::f2s_log_level::F2S_LOG_WARNING {
        let _ = LAST_PROBLEM.try_with(|last| *last.borrow_mut() = Some(text.to_string()));
    }
    if is_depth_pipeline_error(level, text) {
        DEPTH_PIPELINE_ERRORS.fetch_add(1, Ordering::SeqCst);
        if let Ok(mut last) = LAST_DEPTH_PIPELINE_ERROR.lock() {
            *last = Some(text.to_string());
        }
    }
}

extern "C" fn forward(
    level: i32,
    message: *const std::ffi::c_char,
    length: usize,
    _user: *mut c_void,
) {
    if message.is_null() {
        return;
    }
    // SAFETY: the shim passes std::string::data() and size() of a string that
    // lives for the duration of this call.
    let bytes = unsafe { std::slice::from_raw_parts(message.cast::<u8>(), length) };
    let text = String::from_utf8_lossy(bytes);
    // Never unwind into C++: contain anything a subscriber might do.
    let _ = std::panic::catch_unwind(|| {
        let level = sys::f2s_log_level(level as u32);
        remember(level, &text);
        match level {
            sys::f2s_log_level::F2S_LOG_ERROR => tracing::error!(target: LOG_TARGET, "{text}"),
            sys::f2s_log_level::F2S_LOG_WARNING => tracing::warn!(target: LOG_TARGET, "{text}"),
            sys::f2s_log_level::F2S_LOG_INFO => tracing::debug!(target: LOG_TARGET, "{text}"),
            _ => tracing::trace!(target: LOG_TARGET, "{text}"),
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn log_line(level: sys::f2s_log_level, text: &str) {
        forward(
            level.0 as i32,
            text.as_ptr().cast(),
            text.len(),
            std::ptr::null_mut(),
        );
    }

    #[test]
    fn another_threads_warning_is_not_this_threads_problem() {
        clear_last_problem();
        std::thread::spawn(|| {
            log_line(
                sys::f2s_log_level::F2S_LOG_WARNING,
                "[UsbIsoTransferPool] usb transfer error",
            )
        })
        .join()
        .expect("logging thread");
        assert_eq!(take_last_problem(), None);
        log_line(
            sys::f2s_log_level::F2S_LOG_ERROR,
            "[Freenect2Impl] failed to open Kinect v2: LIBUSB_ERROR_ACCESS",
        );
        log_line(sys::f2s_log_level::F2S_LOG_INFO, "[Freenect2Impl] opening");
        assert_eq!(
            take_last_problem().as_deref(),
            Some("[Freenect2Impl] failed to open Kinect v2: LIBUSB_ERROR_ACCESS")
        );
        assert_eq!(take_last_problem(), None);
    }

    #[test]
    fn depth_decoder_errors_are_counted_from_any_thread() {
        let (before, _) = depth_pipeline_errors();
        let line = "[OpenCLDepthPacketProcessor] OpenCLDepthPacketProcessor is not initialized!";
        std::thread::spawn(move || log_line(sys::f2s_log_level::F2S_LOG_ERROR, line))
            .join()
            .expect("logging thread");
        let (after, last) = depth_pipeline_errors();
        assert!(after > before);
        assert_eq!(last.as_deref(), Some(line));
        let error = sys::f2s_log_level::F2S_LOG_ERROR;
        assert!(is_depth_pipeline_error(
            error,
            "[CudaDepthPacketProcessorImpl] No CUDA device found"
        ));
        assert!(!is_depth_pipeline_error(
            sys::f2s_log_level::F2S_LOG_WARNING,
            "[OpenCLDepthPacketProcessor] slow"
        ));
        assert!(!is_depth_pipeline_error(
            error,
            "[Freenect2DeviceImpl] DepthPacketProcessor mentioned later"
        ));
        assert!(!is_depth_pipeline_error(error, "no source prefix"));
    }
}
