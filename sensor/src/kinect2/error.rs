//! Errors of the Kinect v2 layer. Each says which device (serial) and which
//! operation failed, and carries the last error libfreenect2 logged, which
//! usually names the USB cause (permissions, bandwidth, a lost device).
//! Pure: the shim's status codes are mirrored here (the device layer checks
//! them against the shim's header at compile time), and turning a status
//! into an error is `ffi_error.rs` (feature `kinect2`).

use std::fmt;

/// A failed libfreenect2 call through the shim, as reported by the shim
/// (an `f2s_status`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShimStatus(pub u32);

impl ShimStatus {
    pub const OK: Self = Self(0);
    pub const NULL_ARGUMENT: Self = Self(1);
    pub const NOT_FOUND: Self = Self(2);
    pub const OPEN_FAILED: Self = Self(3);
    pub const PIPELINE_UNAVAILABLE: Self = Self(4);
    pub const START_FAILED: Self = Self(5);
    pub const STOP_FAILED: Self = Self(6);
    pub const CLOSE_FAILED: Self = Self(7);
    pub const TIMEOUT: Self = Self(8);
    pub const NO_FRAME: Self = Self(9);
    pub const BAD_SIZE: Self = Self(10);
    pub const BUFFER_TOO_SMALL: Self = Self(11);
    pub const EXCEPTION: Self = Self(12);

    /// True for the shim's `F2S_OK`.
    pub fn is_ok(self) -> bool {
        self == Self::OK
    }

    fn describe(self) -> &'static str {
        match self {
            Self::OK => "ok",
            Self::NULL_ARGUMENT => "null argument",
            Self::NOT_FOUND => "not found",
            Self::OPEN_FAILED => "libfreenect2 could not open the device",
            Self::PIPELINE_UNAVAILABLE => "the depth pipeline is not built into libfreenect2",
            Self::START_FAILED => "libfreenect2 could not start the streams",
            Self::STOP_FAILED => "libfreenect2 could not stop the streams",
            Self::CLOSE_FAILED => "libfreenect2 could not close the device",
            Self::TIMEOUT => "timed out",
            Self::NO_FRAME => "the frame set lacks that frame",
            Self::BAD_SIZE => "an image has the wrong size",
            Self::BUFFER_TOO_SMALL => "a buffer is too small",
            Self::EXCEPTION => "libfreenect2 threw a C++ exception",
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

impl Kinect2Error {
    /// Errors worth retrying while waiting for a device (and when
    /// reopening it): it may appear, come back after its reset, or be let
    /// go by the process that holds it. The others end the stream.
    pub fn is_retryable(&self) -> bool {
        matches!(
            self,
            Kinect2Error::NoDevice { .. }
                | Kinect2Error::SerialNotFound { .. }
                | Kinect2Error::IndexOutOfRange { .. }
                | Kinect2Error::Operation { .. }
                | Kinect2Error::Locked(_)
                | Kinect2Error::SerialMismatch { .. }
        )
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_lasting_errors_end_the_stream() {
        assert!(Kinect2Error::SerialNotFound {
            serial: "1".into(),
            connected: Vec::new(),
        }
        .is_retryable());
        assert!(!Kinect2Error::InvalidParams("x".into()).is_retryable());
        assert!(!Kinect2Error::AlreadyOpen { serial: "1".into() }.is_retryable());
        assert!(Kinect2Error::SerialMismatch {
            requested: "1".into(),
            opened: "2".into(),
        }
        .is_retryable());
    }

    /// A failed call names the action, the device, the shim's status in
    /// words and number, the C++ exception and libfreenect2's last line.
    #[test]
    fn a_failed_operation_says_what_where_and_why() {
        let err = Kinect2Error::Operation {
            action: "start the streams",
            serial: Some("011054343347".into()),
            status: ShimStatus::START_FAILED,
            exception: Some("LIBUSB_ERROR_TIMEOUT".into()),
            libfreenect2_log: Some("[Freenect2DeviceImpl] failed to start".into()),
        };
        assert_eq!(
            err.to_string(),
            "failed to start the streams (Kinect v2 011054343347): libfreenect2 could not \
             start the streams (status 5): LIBUSB_ERROR_TIMEOUT (libfreenect2: \
             [Freenect2DeviceImpl] failed to start)"
        );
        let bare = Kinect2Error::Operation {
            action: "enumerate",
            serial: None,
            status: ShimStatus(99),
            exception: None,
            libfreenect2_log: None,
        };
        assert_eq!(
            bare.to_string(),
            "failed to enumerate (Kinect v2 -): unknown shim status (status 99)"
        );
        assert!(ShimStatus::OK.is_ok() && !ShimStatus::TIMEOUT.is_ok());
    }

    /// Every status the shim defines has words of its own.
    #[test]
    fn every_shim_status_is_described() {
        let described: Vec<&str> = (0..=12).map(|code| ShimStatus(code).describe()).collect();
        for (code, words) in described.iter().enumerate() {
            assert_ne!(*words, "unknown shim status", "status {code}");
        }
        let mut unique = described.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), described.len(), "{described:?}");
        assert_eq!(ShimStatus(13).describe(), "unknown shim status");
    }
}
