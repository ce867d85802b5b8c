//! Routes libfreenect2's log lines into `tracing` (target `libfreenect2`)
//! instead of its own stderr logger, and remembers the last error or warning
//! so that our errors can say what libfreenect2 saw.

use std::ffi::c_void;
use std::sync::{Mutex, Once};

use super::sys;

/// The target libfreenect2's lines are logged under.
pub const LOG_TARGET: &str = "libfreenect2";

static INSTALL: Once = Once::new();
static LAST_PROBLEM: Mutex<Option<String>> = Mutex::new(None);

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

/// Forgets the last problem, so that [`take_last_problem`] after a call
/// returns only what that call logged.
pub fn clear_last_problem() {
    if let Ok(mut last) = LAST_PROBLEM.lock() {
        *last = None;
    }
}

/// The last error or warning libfreenect2 logged since [`clear_last_problem`].
pub fn take_last_problem() -> Option<String> {
    LAST_PROBLEM.lock().ok().and_then(|mut last| last.take())
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
        if level == sys::f2s_log_level::F2S_LOG_ERROR
            || level == sys::f2s_log_level::F2S_LOG_WARNING
        {
            if let Ok(mut last) = LAST_PROBLEM.lock() {
                *last = Some(text.to_string());
            }
        }
        match level {
            sys::f2s_log_level::F2S_LOG_ERROR => tracing::error!(target: LOG_TARGET, "{text}"),
            sys::f2s_log_level::F2S_LOG_WARNING => tracing::warn!(target: LOG_TARGET, "{text}"),
            sys::f2s_log_level::F2S_LOG_INFO => tracing::debug!(target: LOG_TARGET, "{text}"),
            _ => tracing::trace!(target: LOG_TARGET, "{text}"),
        }
    });
}
