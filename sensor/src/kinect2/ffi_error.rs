//! From the shim's status codes to [`Kinect2Error`]s: the calls that
//! fetch the C++ exception text and check a returned handle (feature
//! `kinect2`; the errors themselves are `error.rs`).

use std::ptr::NonNull;

use super::error::{Kinect2Error, ShimStatus};
use super::log;
use super::sys;

// The status codes `error.rs` mirrors are the shim's.
const _: () = {
    assert!(ShimStatus::OK.0 == sys::f2s_status::F2S_OK.0);
    assert!(ShimStatus::NULL_ARGUMENT.0 == sys::f2s_status::F2S_ERR_NULL_ARGUMENT.0);
    assert!(ShimStatus::NOT_FOUND.0 == sys::f2s_status::F2S_ERR_NOT_FOUND.0);
    assert!(ShimStatus::OPEN_FAILED.0 == sys::f2s_status::F2S_ERR_OPEN_FAILED.0);
    assert!(ShimStatus::PIPELINE_UNAVAILABLE.0 == sys::f2s_status::F2S_ERR_PIPELINE_UNAVAILABLE.0);
    assert!(ShimStatus::START_FAILED.0 == sys::f2s_status::F2S_ERR_START_FAILED.0);
    assert!(ShimStatus::STOP_FAILED.0 == sys::f2s_status::F2S_ERR_STOP_FAILED.0);
    assert!(ShimStatus::CLOSE_FAILED.0 == sys::f2s_status::F2S_ERR_CLOSE_FAILED.0);
    assert!(ShimStatus::TIMEOUT.0 == sys::f2s_status::F2S_ERR_TIMEOUT.0);
    assert!(ShimStatus::NO_FRAME.0 == sys::f2s_status::F2S_ERR_NO_FRAME.0);
    assert!(ShimStatus::BAD_SIZE.0 == sys::f2s_status::F2S_ERR_BAD_SIZE.0);
    assert!(ShimStatus::BUFFER_TOO_SMALL.0 == sys::f2s_status::F2S_ERR_BUFFER_TOO_SMALL.0);
    assert!(ShimStatus::EXCEPTION.0 == sys::f2s_status::F2S_ERR_EXCEPTION.0);
};

impl ShimStatus {
    pub(crate) fn from_raw(status: sys::f2s_status) -> Self {
        Self(status.0)
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
        let exception = if status == ShimStatus::EXCEPTION {
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
        status: ShimStatus::NULL_ARGUMENT,
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
