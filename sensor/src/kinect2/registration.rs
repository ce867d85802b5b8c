//! libfreenect2's `Registration`: undistorts the depth image with the IR
//! camera's distortion model and maps the colour image onto it.

use std::ptr::NonNull;

use super::error::Kinect2Error;
use super::ffi_error::{check, non_null};
use super::frame::{check_len, check_view, sanitized_depth, FrameView};
use super::params::{
    validate_params, ColorParams, IrParams, COLOR_HEIGHT, COLOR_WIDTH, DEPTH_HEIGHT, DEPTH_WIDTH,
};
use super::sys;

/// Owns a libfreenect2::Registration (about 3.5 MB of lookup tables built
/// from the camera parameters) and the buffers its `apply` works in (the
/// shim's 8.3 MB filter map and 0.87 MB colour offsets, and our copy of
/// depth that needs sanitising), so that nothing is allocated per frame.
pub struct Registration {
    handle: NonNull<sys::f2s_registration>,
    ir: IrParams,
    /// Depth with values libfreenect2 cannot handle replaced (rarely used).
    sanitized: Vec<u8>,
}

// SAFETY: the registration has no thread affinity; `apply` writes the shim's
// buffers and takes `&mut self`, `undistort` only reads (libfreenect2's
// undistortDepth is const), so moving it to another thread is sound. It is
// deliberately not Sync.
unsafe impl Send for Registration {}

impl std::fmt::Debug for Registration {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Registration")
            .field("ir", &self.ir)
            .finish_non_exhaustive()
    }
}

impl Registration {
    /// Builds the registration from the device's parameters (read them after
    /// the streams have started).
    ///
    /// Parameters outside the plausible range of a Kinect v2 (see
    /// [`validate_params`]) are refused: libfreenect2 converts the mapped
    /// coordinates to `int` unchecked, which is undefined behaviour for NaN
    /// or out-of-range values.
    pub fn new(ir: &IrParams, color: &ColorParams) -> Result<Self, Kinect2Error> {
        validate_params(ir, color)?;
        let action = "build the depth/colour registration";
        let raw_ir = ir.to_raw();
        let mut raw = std::ptr::null_mut();
        let raw_color = color.raw();
        // SAFETY: both parameter structs are valid for reads; `raw` is a
        // valid out-pointer.
        let status = unsafe { sys::f2s_registration_new(&raw_ir, &raw_color, &mut raw) };
        check(status, action, None)?;
        let handle = non_null(raw, action, None)?;
        Ok(Self {
            handle,
            ir: *ir,
            sanitized: Vec::new(),
        })
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
        let depth = depth.raw();
        // SAFETY: the registration is alive; `depth` views 512*424*4 readable
        // bytes (borrowed from the caller's view for this call); `out` points
        // to 512*424 writable f32 (checked above), which the shim writes as
        // 4-byte pixels and nothing else aliases.
        let status =
            unsafe { sys::f2s_registration_undistort(self.handle.as_ptr(), &depth, &mut out) };
        check(status, "undistort the depth image", None)
    }

    /// Undistorts `depth` and maps `color` (1920 x 1080 x 4) onto it:
    /// `registered[i]` holds the 4 colour bytes (in `color`'s byte order) of
    /// undistorted depth pixel `i`, 0 where there is none. With `filter`,
    /// colour pixels hidden behind nearer depth are dropped. Reuses the
    /// registration's buffers: nothing is allocated per call.
    pub fn apply(
        &mut self,
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
        let depth = sanitized_depth(depth, &mut self.sanitized)?;
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
        let (color, depth) = (color.raw(), depth.raw());
        // SAFETY: the registration is alive and borrowed mutably (the shim
        // writes its buffers); the views point to readable frames of the
        // checked sizes; both outputs are distinct, writable 512*424
        // four-byte buffers (checked above).
        let status = unsafe {
            sys::f2s_registration_apply(
                self.handle.as_ptr(),
                &color,
                &depth,
                &mut undistorted_image,
                &mut registered_image,
                i32::from(filter),
            )
        };
        check(status, "register colour to depth", None)
    }
}

impl Drop for Registration {
    fn drop(&mut self) {
        // SAFETY: the pointer came from f2s_registration_new and is freed once.
        unsafe { sys::f2s_registration_free(self.handle.as_ptr()) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parameters [`validate_params`] refuses never reach libfreenect2.
    #[test]
    fn broken_parameters_build_no_registration() {
        let ir = IrParams {
            fx: f32::NAN,
            fy: 365.5,
            cx: 257.3,
            cy: 205.9,
            ..Default::default()
        };
        let err = Registration::new(&ir, &ColorParams::default()).expect_err("refused");
        assert!(matches!(err, Kinect2Error::InvalidParams(_)), "{err}");
    }
}
