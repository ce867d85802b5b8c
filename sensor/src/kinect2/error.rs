//! Errors of the Kinect v2 layer. Each says which device (serial) and which
//! operation failed, and carries the last error libfreenect2 logged, which
//! usually names the USB cause (permissions, bandwidth, a lost device).

use std::fmt;
use std::ptr::NonNull;

use super::log;
use super::sys;

/// A failed libfreenect2 call through the shim, as reported by the shim.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShimStatus(pub u32);

impl ShimStatus {
    pub(crate) fn from_raw(status: sys::f2s_status) -> Self {
        Self(status.0)
    }

    pub(crate) fn is_ok(self) -> bool {
        self.0 == sys::f2s_status::F2S_OK.0
    }

    fn describe(self) -> &'static str {
        match sys::f2s_status(self.0) {
            sys::f2s_status::F2S_OK => "ok",
            sys::f2s_status::F2S_ERR_NULL_ARGUMENT => "null argument",
            sys::f2s_status::F2S_ERR_NOT_FOUND => "not found",
            sys::f2s_status::F2S_ERR_OPEN_FAILED => "libfreenect2 could not open the device",
            sys::f2s_status::F2S_ERR_PIPELINE_UNAVAILABLE => {
                "the depth pipeline is not built into libfreenect2"
            }
            sys::f2s_status::F2S_ERR_START_FAILED => "libfreenect2 could not start the streams",
            sys::f2s_status::F2S_ERR_STOP_FAILED => "libfreenect2 could not stop the streams",
            sys::f2s_status::F2S_ERR_CLOSE_FAILED => "libfreenect2 could not close the device",
            sys::f2s_status::F2S_ERR_TIMEOUT => "timed out",
            sys::f2s_status::F2S_ERR_NO_FRAME => "the frame set lacks that frame",
            sys::f2s_status::F2S_ERR_BAD_SIZE => "an image has the wrong size",
            sys::f2s_status::F2S_ERR_BUFFER_TOO_SMALL => "a buffer is too small",
            sys::f2s_status::F2S_ERR_EXCEPTION => "libfreenect2 threw a C++ exception",
            _ => "unknown shim status",
        }
    }
}

impl fmt::Display for ShimStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} (status {})", self.describe(), self.0)
    }
}

/// Everything the Kinect v2 layer can report.
#[derive(Debug, thiserror::Error)]
pub enum Kinect2Error {
    /// libfreenect2 enumerated no Kinect v2 on the USB bus.
    #[error(
        "no Kinect v2 found (libfreenect2 {version} enumerated 0 devices){}; check that it is \
         powered, on a USB 3 port, and that the udev rules allow access \
         (README \"Running on the robot\")",
        log_suffix(.libfreenect2_log)
    )]
    NoDevice {
        version: String,
        libfreenect2_log: Option<String>,
    },
    /// A serial was asked for that is not connected.
    #[error("no Kinect v2 with serial {serial} is connected (connected: {})", list(.connected))]
    SerialNotFound {
        serial: String,
        connected: Vec<String>,
    },
    /// A device index was asked for that is not connected.
    #[error("no Kinect v2 at index {index}: {count} connected")]
    IndexOutOfRange { index: u32, count: u32 },
    /// The chosen depth pipeline is not compiled into libfreenect2.
    #[error(
        "the '{pipeline}' depth pipeline is not built into this libfreenect2 \
         (available: {available}); rebuild libfreenect2 with it or choose another"
    )]
    PipelineUnavailable {
        pipeline: &'static str,
        available: String,
    },
    /// A libfreenect2 operation failed.
    #[error(
        "failed to {action} (Kinect v2 {}): {status}{}{}",
        serial.as_deref().unwrap_or("-"),
        exception_suffix(.exception),
        log_suffix(.libfreenect2_log)
    )]
    Operation {
        action: &'static str,
        serial: Option<String>,
        status: ShimStatus,
        /// The text of the C++ exception the shim caught, if it caught one.
        exception: Option<String>,
        libfreenect2_log: Option<String>,
    },
    /// A frame from the device does not have the layout libfreenect2 documents.
    #[error("Kinect v2 {serial}: {what}")]
    UnexpectedFrame { serial: String, what: String },
    /// Images handed to the registration have the wrong size.
    #[error("registration needs {expected} but got {got}")]
    BadImageSize { expected: String, got: String },
    /// The device is already open through this context (libfreenect2 would
    /// hand out the same device twice).
    #[error(
        "Kinect v2 {serial} is already open in this process; close it (drop its Device) \
         before opening it again"
    )]
    AlreadyOpen { serial: String },
    /// Another process has the device open (its lock file is held).
    #[error(transparent)]
    Locked(#[from] crate::device_lock::DeviceLockError),
    /// libfreenect2 opened another device than the one asked for (after
    /// its USB reset made the wanted one vanish, it re-opens by index).
    #[error(
        "asked libfreenect2 for Kinect v2 {requested} but it opened {opened} (the device vanished \
         during its USB reset and libfreenect2 re-opened by index); closed it again"
    )]
    SerialMismatch { requested: String, opened: String },
    /// The depth pipeline delivers no depth while the camera streams (colour
    /// flows, or the decoder keeps logging errors): OpenCL/CUDA could not
    /// initialise. Reconnecting cannot cure that.
    #[error(
        "Kinect v2 {serial}: the '{pipeline}' depth pipeline delivered no depth in {waited_s:.1} s \
         while the camera streamed ({color_frames} colour frames, {pipeline_errors} depth decoder \
         errors){}; the GPU decoder could not initialise (no OpenCL/CUDA driver, or a wrong \
         --gpu-device?). Use --pipeline cpu (works everywhere, more CPU), or fix the GPU set-up",
        log_suffix(.libfreenect2_log)
    )]
    DepthPipelineFailed {
        serial: String,
        pipeline: &'static str,
        color_frames: u64,
        pipeline_errors: u64,
        waited_s: f64,
        libfreenect2_log: Option<String>,
    },
    /// Opening on a thread of its own failed (the thread could not start or
    /// panicked).
    #[error("opening the Kinect v2 failed: {0}")]
    Background(String),
    /// Camera parameters that libfreenect2's registration cannot use safely.
    #[error("invalid camera parameters: {0}")]
    InvalidParams(String),
    /// A serial number with an interior NUL byte.
    #[error("invalid serial number {0:?}")]
    InvalidSerial(String),
}

fn exception_suffix(exception: &Option<String>) -> String {
    match exception {
        Some(text) => format!(": {text}"),
        None => String::new(),
    }
}

fn log_suffix(log: &Option<String>) -> String {
    match log {
        Some(line) => format!(" (libfreenect2: {line})"),
        None => String::new(),
    }
}

fn list(items: &[String]) -> String {
    if items.is_empty() {
        "none".to_string()
    } else {
        items.join(", ")
    }
}

/// `Ok` for `F2S_OK`, else the failed `action` (on the device `serial`, if
/// any) with the last problem libfreenect2 logged.
pub(crate) fn check(
    status: sys::f2s_status,
    action: &'static str,
    serial: Option<&str>,
) -> Result<(), Kinect2Error> {
    let status = ShimStatus::from_raw(status);
    if status.is_ok() {
        Ok(())
    } else {
        let exception = if status.0 == sys::f2s_status::F2S_ERR_EXCEPTION.0 {
            take_exception()
        } else {
            None
        };
        Err(Kinect2Error::Operation {
            action,
            serial: serial.map(str::to_string),
            status,
            exception,
            libfreenect2_log: log::take_last_problem(),
        })
    }
}

/// The text of the last C++ exception the shim caught on this thread (and
/// forgets it), if any.
pub(crate) fn take_exception() -> Option<String> {
    let mut buffer = vec![0u8; 256];
    loop {
        let mut length = 0usize;
        // SAFETY: `buffer` holds `buffer.len()` writable bytes; `length` is
        // writable. The text is thread-local in the shim.
        let status = unsafe {
            sys::f2s_take_exception(buffer.as_mut_ptr().cast(), buffer.len(), &mut length)
        };
        if status == sys::f2s_status::F2S_ERR_BUFFER_TOO_SMALL && length + 1 > buffer.len() {
            buffer.resize(length + 1, 0);
            continue;
        }
        if status != sys::f2s_status::F2S_OK {
            return None;
        }
        buffer.truncate(length.min(buffer.len()));
        return Some(String::from_utf8_lossy(&buffer).into_owned());
    }
}

/// The handle a shim constructor returned with `F2S_OK`; an error naming
/// `action` should it be null all the same.
pub(crate) fn non_null<T>(
    raw: *mut T,
    action: &'static str,
    serial: Option<&str>,
) -> Result<NonNull<T>, Kinect2Error> {
    NonNull::new(raw).ok_or_else(|| Kinect2Error::Operation {
        action,
        serial: serial.map(str::to_string),
        status: ShimStatus(sys::f2s_status::F2S_ERR_NULL_ARGUMENT.0),
        exception: None,
        libfreenect2_log: log::take_last_problem(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn throw(message: Option<&std::ffi::CStr>) -> Result<(), Kinect2Error> {
        let pointer = message.map_or(std::ptr::null(), std::ffi::CStr::as_ptr);
        // SAFETY: `pointer` is null or a NUL-terminated string that outlives
        // the call; the shim catches what it throws.
        let status = unsafe { sys::f2s_selftest_throw(pointer) };
        check(status, "run the exception self-test", Some("test"))
    }

    #[test]
    fn the_text_of_a_caught_exception_reaches_the_error_of_its_thread_only() {
        let err = throw(Some(c"LIBUSB_ERROR_NO_MEM in the shim")).expect_err("threw");
        match &err {
            Kinect2Error::Operation { exception, .. } => {
                assert_eq!(
                    exception.as_deref(),
                    Some("LIBUSB_ERROR_NO_MEM in the shim")
                );
            }
            other => panic!("expected Operation, got {other:?}"),
        }
        assert!(
            err.to_string().contains("LIBUSB_ERROR_NO_MEM in the shim"),
            "{err}"
        );
        // Taken once; another thread's exception is not ours.
        assert_eq!(take_exception(), None);
        std::thread::spawn(|| {
            // SAFETY: as above.
            let status = unsafe { sys::f2s_selftest_throw(c"elsewhere".as_ptr()) };
            assert_eq!(status, sys::f2s_status::F2S_ERR_EXCEPTION);
        })
        .join()
        .expect("thread");
        assert_eq!(take_exception(), None);
        let err = throw(None).expect_err("threw an int");
        assert!(err.to_string().contains("unknown type"), "{err}");
    }
}
