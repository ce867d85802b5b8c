//! The Kinect v2 through libfreenect2.
//!
//! libfreenect2's API is C++, so `sensor/shim/` wraps the part a robot needs
//! in a small `extern "C"` layer; `build.rs` compiles it with `cc` and
//! generates `sys` from its header with bindgen. Only the calls into it
//! need libfreenect2 (cargo feature `kinect2`); everything that needs no
//! library (conversions, the camera's parameters and their checks, frame
//! checks, the device clock, the error mapping, the settings) builds and is
//! tested without the feature:
//!
//! | file | what | feature |
//! |---|---|---|
//! | `convert.rs` | mirroring, pixel centres, mm rounding, colour byte order | |
//! | `params.rs` | [`IrParams`], [`ColorParams`], [`DepthConfig`], [`validate_params`] | |
//! | `frame.rs` | [`FrameView`], [`FrameFormat`]; layout, size and depth-value checks | |
//! | `choice.rs` | [`Pipeline`] names, [`DeviceSelector`], the serials open, [`check_opened_serial`] | |
//! | `clock.rs` | the device clock, unwrapped and never going back | |
//! | `options.rs` | [`Kinect2Options`], [`CaptureStats`] | |
//! | `error.rs` | [`Kinect2Error`], [`ShimStatus`] (the shim's codes) | |
//! | `log.rs` | libfreenect2's log into `tracing`; the last problem per thread, depth decoder errors counted | the callback |
//! | `sys.rs` | the generated raw bindings | `kinect2` |
//! | `ffi_error.rs` | a shim status and the caught C++ exception as a [`Kinect2Error`] | `kinect2` |
//! | `device.rs` | `Context` (enumerate, open), `Device` (config, parameters, start/stop), `FrameSet` | `kinect2` |
//! | `registration.rs` | `Registration`: undistorted depth and registered colour | `kinect2` |
//! | `source.rs` | `Kinect2Source`: the device as a [`crate::source::FrameSource`], with reconnection, open/start interruptible by a stop request, a failed depth pipeline detected | `kinect2` |
//!
//! Every `unsafe` block is in a file marked `kinect2` (and in `log.rs`'s
//! callback, behind the same feature).
//!
//! Clouds from the Kinect are unmirrored (libfreenect2 delivers mirror
//! images) and use the recording format's intrinsics, so the cloud published
//! live and the one replayed from its recording are the same; see
//! `convert.rs`.

mod choice;
mod clock;
mod convert;
mod error;
mod frame;
mod log;
mod options;
mod params;

#[cfg(feature = "kinect2")]
mod device;
#[cfg(feature = "kinect2")]
mod ffi_error;
#[cfg(feature = "kinect2")]
mod registration;
#[cfg(feature = "kinect2")]
mod source;
#[cfg(feature = "kinect2")]
pub mod sys;

pub use choice::{check_opened_serial, DeviceSelector, Pipeline, UnknownPipeline, LOCK_KIND};
pub use convert::{
    depth_mm_to_count, pixel_rgb, unmirror_color, unmirror_depth, unmirrored_intrinsics,
    DEPTH_UNIT_M,
};
pub use error::{Kinect2Error, ShimStatus};
pub use frame::{FrameFormat, FrameMetadata, FrameView};
pub use log::{depth_pipeline_errors, LOG_TARGET};
pub use options::{CaptureStats, Kinect2Options, SENSOR_NAME};
pub use params::{
    validate_params, ColorParams, DepthConfig, IrParams, COLOR_HEIGHT, COLOR_WIDTH, DEPTH_HEIGHT,
    DEPTH_PIXELS, DEPTH_WIDTH,
};

#[cfg(feature = "kinect2")]
pub use device::{library_version, Context, Device, FrameSet, Streams};
#[cfg(feature = "kinect2")]
pub use registration::Registration;
#[cfg(feature = "kinect2")]
pub use source::Kinect2Source;
