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
//!
//! What a line means (which thread's problem, a depth decoder's error) is
//! pure; installing the callback and receiving lines from C++ are the FFI
//! calls (feature `kinect2`).

// Without the `kinect2` feature only the tests log lines.
#![cfg_attr(not(feature = "kinect2"), allow(dead_code))]

use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// The level of a libfreenect2 log line (`libfreenect2::Logger::Level`,
/// the shim's `f2s_log_level`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LogLevel {
    None,
    Error,
    Warning,
    Info,
    Debug,
}

impl LogLevel {
    /// The level of libfreenect2's code `code` (the device layer checks
    /// the codes against the shim's header at compile time); an unknown
    /// code is the most verbose.
    pub(crate) fn from_code(code: u32) -> Self {
        match code {
            0 => Self::None,
            1 => Self::Error,
            2 => Self::Warning,
            3 => Self::Info,
            _ => Self::Debug,
        }
    }
}

/// The target libfreenect2's lines are logged under.
pub const LOG_TARGET: &str = "libfreenect2";

#[cfg(feature = "kinect2")]
static INSTALL: std::sync::Once = std::sync::Once::new();

thread_local! {
    /// The last error or warning libfreenect2 logged on this thread.
    static LAST_PROBLEM: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Errors the depth decoders logged, from any thread.
static DEPTH_PIPELINE_ERRORS: AtomicU64 = AtomicU64::new(0);
/// The last of them.
static LAST_DEPTH_PIPELINE_ERROR: Mutex<Option<String>> = Mutex::new(None);

/// Installs the forwarding once per process (later calls do nothing).
#[cfg(feature = "kinect2")]
pub fn install() {
    use super::sys;
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
pub(crate) fn is_depth_pipeline_error(level: LogLevel, text: &str) -> bool {
    level == LogLevel::Error
        && text
            .strip_prefix('[')
            .and_then(|rest| rest.split_once(']'))
            .is_some_and(|(source, _)| source.contains("DepthPacketProcessor"))
}

/// Remembers a line of `level` logged on the calling thread.
fn remember(level: LogLevel, text: &str) {
    if level == LogLevel::Error || level == LogLevel::Warning {
        let _ = LAST_PROBLEM.try_with(|last| *last.borrow_mut() = Some(text.to_string()));
    }
    if is_depth_pipeline_error(level, text) {
        DEPTH_PIPELINE_ERRORS.fetch_add(1, Ordering::SeqCst);
        if let Ok(mut last) = LAST_DEPTH_PIPELINE_ERROR.lock() {
            *last = Some(text.to_string());
        }
    }
}

#[cfg(feature = "kinect2")]
extern "C" fn forward(
    level: i32,
    message: *const std::ffi::c_char,
    length: usize,
    _user: *mut std::ffi::c_void,
) {
    if message.is_null() {
        return;
    }
    // SAFETY: the shim passes std::string::data() and size() of a string that
    // lives for the duration of this call.
    let bytes = unsafe { std::slice::from_raw_parts(message.cast::<u8>(), length) };
    let text = String::from_utf8_lossy(bytes);
    // Never unwind into C++: contain anything a subscriber might do.
    let _ = std::panic::catch_unwind(|| log_line(LogLevel::from_code(level as u32), &text));
}

/// Remembers a line and passes it on to `tracing`.
fn log_line(level: LogLevel, text: &str) {
    remember(level, text);
    match level {
        LogLevel::Error => tracing::error!(target: LOG_TARGET, "{text}"),
        LogLevel::Warning => tracing::warn!(target: LOG_TARGET, "{text}"),
        LogLevel::Info => tracing::debug!(target: LOG_TARGET, "{text}"),
        _ => tracing::trace!(target: LOG_TARGET, "{text}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A line as libfreenect2 would log it: through the C callback with
    /// the library, straight to what it calls without.
    fn log_line(level: LogLevel, text: &str) {
        #[cfg(feature = "kinect2")]
        forward(
            match level {
                LogLevel::None => 0,
                LogLevel::Error => 1,
                LogLevel::Warning => 2,
                LogLevel::Info => 3,
                LogLevel::Debug => 4,
            },
            text.as_ptr().cast(),
            text.len(),
            std::ptr::null_mut(),
        );
        #[cfg(not(feature = "kinect2"))]
        super::log_line(level, text);
    }

    #[test]
    fn another_threads_warning_is_not_this_threads_problem() {
        clear_last_problem();
        std::thread::spawn(|| {
            log_line(LogLevel::Warning, "[UsbIsoTransferPool] usb transfer error")
        })
        .join()
        .expect("logging thread");
        assert_eq!(take_last_problem(), None);
        log_line(
            LogLevel::Error,
            "[Freenect2Impl] failed to open Kinect v2: LIBUSB_ERROR_ACCESS",
        );
        log_line(LogLevel::Info, "[Freenect2Impl] opening");
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
        std::thread::spawn(move || log_line(LogLevel::Error, line))
            .join()
            .expect("logging thread");
        let (after, last) = depth_pipeline_errors();
        assert!(after > before);
        assert_eq!(last.as_deref(), Some(line));
        let error = LogLevel::Error;
        assert!(is_depth_pipeline_error(
            error,
            "[CudaDepthPacketProcessorImpl] No CUDA device found"
        ));
        assert!(!is_depth_pipeline_error(
            LogLevel::Warning,
            "[OpenCLDepthPacketProcessor] slow"
        ));
        assert!(!is_depth_pipeline_error(
            error,
            "[Freenect2DeviceImpl] DepthPacketProcessor mentioned later"
        ));
        assert!(!is_depth_pipeline_error(error, "no source prefix"));
    }
}
