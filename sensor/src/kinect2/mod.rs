//! The Kinect v2 through libfreenect2 (cargo feature `kinect2`).
//!
//! libfreenect2's API is C++, so `sensor/shim/` wraps the part a robot needs
//! in a small `extern "C"` layer; `build.rs` compiles it with `cc` and
//! generates [`sys`] from its header with bindgen. The modules here are the
//! safe layer over it:
//!
//! | file | what |
//! |---|---|
//! | `sys.rs` | the generated raw bindings |
//! | `device.rs` | [`Context`] (enumerate, open), [`Device`] (config, parameters, start/stop), [`FrameSet`] and [`FrameView`] |
//! | `registration.rs` | [`Registration`]: undistorted depth and registered colour |
//! | `convert.rs` | pure: mirroring, pixel centres, mm rounding, colour byte order |
//! | `source.rs` | [`Kinect2Source`]: the device as a [`crate::source::FrameSource`], with reconnection, open/start interruptible by a stop request, a failed depth pipeline detected |
//! | `log.rs` | libfreenect2's log into `tracing`; the last problem per thread, depth decoder errors counted |
//! | `error.rs` | [`Kinect2Error`] |
//!
//! Clouds from the Kinect are unmirrored (libfreenect2 delivers mirror
//! images) and use the recording format's intrinsics, so the cloud published
//! live and the one replayed from its recording are the same; see
//! `convert.rs`.

mod convert;
mod device;
mod error;
mod log;
mod registration;
mod source;
pub mod sys;

pub use convert::{
    depth_mm_to_count, pixel_rgb, unmirror_color, unmirror_depth, unmirrored_intrinsics,
    DEPTH_UNIT_M,
};
pub use device::{
    check_opened_serial, library_version, ColorParams, Context, DepthConfig, Device,
    DeviceSelector, FrameFormat, FrameSet, FrameView, IrParams, Pipeline, Streams, UnknownPipeline,
    COLOR_HEIGHT, COLOR_WIDTH, DEPTH_HEIGHT, DEPTH_WIDTH, LOCK_KIND,
};
pub use error::{Kinect2Error, ShimStatus};
pub use log::{depth_pipeline_errors, LOG_TARGET};
pub use registration::{validate_params, Registration, DEPTH_PIXELS};
pub use source::{CaptureStats, Kinect2Options, Kinect2Source, SENSOR_NAME};
