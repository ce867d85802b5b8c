//! libfreenect2's `Registration`: undistorts the depth image with the IR
//! camera's distortion model and maps the colour image onto it.

use std::ptr::NonNull;

use super::device::{
    ColorParams, FrameView, IrParams, COLOR_HEIGHT, COLOR_WIDTH, DEPTH_HEIGHT, DEPTH_WIDTH,
};
use super::error::{Kinect2Error, ShimStatus};
use super::sys;

/// Pixels of a depth image.
pub const DEPTH_PIXELS: usize = DEPTH_WIDTH * DEPTH_HEIGHT;

/// Owns a libfreenect2::Registration (about 3.5 MB of lookup tables built
/// from the camera parameters).
pub struct Registration {
    handle: NonNull<sys::f2s_registration>,
    ir: IrParams,
}

// SAFETY: a Registration is immutable after construction (apply and
// undistortDepth are const and keep no state between calls).
unsafe impl Send for Registration {}
// SAFETY: as above: only const methods, no interior mutability.
unsafe impl Sync for Registration {}

impl std::fmt::Debug for Registration {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Registration")
            .field("ir", &self.ir)
            .finish_non_exhaustive()
    }
}

fn check(status: sys::f2s_status, action: &'static str) -> Result<(), Kinect2Error> {
    let status = ShimStatus::from_raw(status);
    if status.is_ok() {
        Ok(())
    } else {
        Err(Kinect2Error::Operation {
            action,
            serial: None,
            status,
            libfreenect2_log: None,
        })
    }
}

fn check_view(
    view: &FrameView<'_>,
    width: usize,
    height: usize,
    what: &str,
) -> Result<(), Kinect2Error> {
    if view.width() == width && view.height() == height && view.bytes_per_pixel() == 4 {
        Ok(())
    } else {
        Err(Kinect2Error::BadImageSize {
            expected: format!("a {width} x {height} x 4 {what} frame"),
            got: format!(
                "{} x {} x {}",
                view.width(),
                view.height(),
                view.bytes_per_pixel()
            ),
        })
    }
}

fn check_len(len: usize, what: &str) -> Result<(), Kinect2Error> {
    if len == DEPTH_PIXELS {
        Ok(())
    } else {
        Err(Kinect2Error::BadImageSize {
            expected: format!(
                "a {DEPTH_WIDTH} x {DEPTH_HEIGHT} {what} buffer ({DEPTH_PIXELS} pixels)"
            ),
            got: format!("{len} pixels"),
        })
    }
}

impl Registration {
    /// Builds the registration from the device's parameters (read them after
    /// the streams have started).
    pub fn new(ir: &IrParams, color: &ColorParams) -> Result<Self, Kinect2Error> {
        let raw_ir = ir.to_raw();
        let mut raw = std::ptr::null_mut();
        // SAFETY: both parameter structs are valid for reads; `raw` is a
        // valid out-pointer.
        let status = unsafe { sys::f2s_registration_new(&raw_ir, color.raw(), &mut raw) };
        check(status, "build the depth/colour registration")?;
        let handle = NonNull::new(raw).ok_or(Kinect2Error::Operation {
            action: "build the depth/colour registration",
            serial: None,
            status: ShimStatus(sys::f2s_status::F2S_ERR_NULL_ARGUMENT.0),
            libfreenect2_log: None,
        })?;
        Ok(Self { handle, ir: *ir })
    }

    /// The IR parameters the registration was built with.
    pub fn ir_params(&self) -> &IrParams {
        &self.ir
    }

    /// Undistorts `depth` (512 x 424 float mm) into `undistorted` (0 where no
    /// distorted pixel maps).
    pub fn undistort(
        &self,
        depth: &FrameView<'_>,
        undistorted: &mut [f32],
    ) -> Result<(), Kinect2Error> {
        check_view(depth, DEPTH_WIDTH, DEPTH_HEIGHT, "depth")?;
        check_len(undistorted.len(), "undistorted depth")?;
        let mut out = sys::f2s_image {
            width: DEPTH_WIDTH,
            height: DEPTH_HEIGHT,
            bytes_per_pixel: 4,
            data: undistorted.as_mut_ptr().cast(),
        };
        // SAFETY: the registration is alive; `depth` views 512*424*4 readable
        // bytes; `out` points to 512*424 writable f32 (checked above), which
        // the shim writes as 4-byte pixels and nothing else aliases.
        let status =
            unsafe { sys::f2s_registration_undistort(self.handle.as_ptr(), depth.raw(), &mut out) };
        check(status, "undistort the depth image")
    }

    /// Undistorts `depth` and maps `color` (1920 x 1080 x 4) onto it:
    /// `registered[i]` holds the 4 colour bytes (in `color`'s byte order) of
    /// undistorted depth pixel `i`, 0 where there is none. With `filter`,
    /// colour pixels hidden behind nearer depth are dropped.
    pub fn apply(
        &self,
        color: &FrameView<'_>,
        depth: &FrameView<'_>,
        undistorted: &mut [f32],
        registered: &mut [u32],
        filter: bool,
    ) -> Result<(), Kinect2Error> {
        check_view(color, COLOR_WIDTH, COLOR_HEIGHT, "colour")?;
        check_view(depth, DEPTH_WIDTH, DEPTH_HEIGHT, "depth")?;
        check_len(undistorted.len(), "undistorted depth")?;
        check_len(registered.len(), "registered colour")?;
        let mut undistorted_image = sys::f2s_image {
            width: DEPTH_WIDTH,
            height: DEPTH_HEIGHT,
            bytes_per_pixel: 4,
            data: undistorted.as_mut_ptr().cast(),
        };
        let mut registered_image = sys::f2s_image {
            width: DEPTH_WIDTH,
            height: DEPTH_HEIGHT,
            bytes_per_pixel: 4,
            data: registered.as_mut_ptr().cast(),
        };
        // SAFETY: the registration is alive; the views point to readable
        // frames of the checked sizes; both outputs are distinct, writable
        // 512*424 four-byte buffers (checked above).
        let status = unsafe {
            sys::f2s_registration_apply(
                self.handle.as_ptr(),
                color.raw(),
                depth.raw(),
                &mut undistorted_image,
                &mut registered_image,
                i32::from(filter),
            )
        };
        check(status, "register colour to depth")
    }
}

impl Drop for Registration {
    fn drop(&mut self) {
        // SAFETY: the pointer came from f2s_registration_new and is freed once.
        unsafe { sys::f2s_registration_free(self.handle.as_ptr()) };
    }
}
