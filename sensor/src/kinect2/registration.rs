//! libfreenect2's `Registration`: undistorts the depth image with the IR
//! camera's distortion model and maps the colour image onto it.

use std::ptr::NonNull;

use super::device::{
    ColorParams, FrameView, IrParams, COLOR_HEIGHT, COLOR_WIDTH, DEPTH_HEIGHT, DEPTH_WIDTH,
};
use super::error::{check, non_null, Kinect2Error};
use super::sys;

/// Pixels of a depth image.
pub const DEPTH_PIXELS: usize = DEPTH_WIDTH * DEPTH_HEIGHT;

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

/// Checks that `value` is finite and within `lo..=hi`.
fn in_range(name: &str, value: f32, lo: f32, hi: f32) -> Result<(), Kinect2Error> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(Kinect2Error::InvalidParams(format!(
            "{name} = {value} is outside {lo} ..= {hi}"
        )))
    }
}

/// Refuses camera parameters for which libfreenect2's registration would
/// convert a non-finite or out-of-`int`-range coordinate (undefined
/// behaviour in C++). The bounds are generous for a Kinect v2 (IR fx ~365,
/// colour fx ~1081, shift_d ~863, shift_m ~52, polynomial coefficients
/// below 1) and keep every mapped coordinate, and the colour offset
/// `cx + cy * 1920`, well inside `i32`.
pub fn validate_params(ir: &IrParams, color: &ColorParams) -> Result<(), Kinect2Error> {
    in_range("IR fx", ir.fx, 200.0, 2000.0)?;
    in_range("IR fy", ir.fy, 200.0, 2000.0)?;
    in_range("IR cx", ir.cx, 0.0, DEPTH_WIDTH as f32)?;
    in_range("IR cy", ir.cy, 0.0, DEPTH_HEIGHT as f32)?;
    for (name, k) in [
        ("IR k1", ir.k1),
        ("IR k2", ir.k2),
        ("IR k3", ir.k3),
        ("IR p1", ir.p1),
        ("IR p2", ir.p2),
    ] {
        in_range(name, k, -1.0, 1.0)?;
    }
    let c = color.raw();
    in_range("colour fx", c.fx, 200.0, 5000.0)?;
    in_range("colour fy", c.fy, 200.0, 5000.0)?;
    in_range(
        "colour cx",
        c.cx,
        -(COLOR_WIDTH as f32),
        2.0 * COLOR_WIDTH as f32,
    )?;
    in_range(
        "colour cy",
        c.cy,
        -(COLOR_HEIGHT as f32),
        2.0 * COLOR_HEIGHT as f32,
    )?;
    in_range("colour shift_d", c.shift_d, 1.0, 1e5)?;
    in_range("colour shift_m", c.shift_m, -1000.0, 1000.0)?;
    let polynomial = [
        c.mx_x3y0, c.mx_x0y3, c.mx_x2y1, c.mx_x1y2, c.mx_x2y0, c.mx_x0y2, c.mx_x1y1, c.mx_x1y0,
        c.mx_x0y1, c.mx_x0y0, c.my_x3y0, c.my_x0y3, c.my_x2y1, c.my_x1y2, c.my_x2y0, c.my_x0y2,
        c.my_x1y1, c.my_x1y0, c.my_x0y1, c.my_x0y0,
    ];
    for value in polynomial {
        in_range("a colour polynomial coefficient", value, -1.0, 1.0)?;
    }
    Ok(())
}

/// Depth (float mm) that libfreenect2's registration handles safely: NaN,
/// +infinity and positive values below 1 mm (far below the sensor's range)
/// would reach an unchecked float-to-int conversion, so they count as no
/// reading (0). Borrowed unchanged when every value is fine.
fn sanitized_depth<'a>(
    depth: &FrameView<'a>,
    scratch: &'a mut Vec<u8>,
) -> Result<FrameView<'a>, Kinect2Error> {
    let unsafe_value = |z: f32| z.is_nan() || z == f32::INFINITY || (z > 0.0 && z < 1.0);
    let data = depth.data();
    if !data
        .chunks_exact(4)
        .any(|b| unsafe_value(f32::from_ne_bytes([b[0], b[1], b[2], b[3]])))
    {
        return Ok(*depth);
    }
    scratch.clear();
    scratch.extend(data.chunks_exact(4).flat_map(|b| {
        let z = f32::from_ne_bytes([b[0], b[1], b[2], b[3]]);
        if unsafe_value(z) { 0.0f32 } else { z }.to_ne_bytes()
    }));
    FrameView::from_bytes(
        depth.width(),
        depth.height(),
        depth.bytes_per_pixel(),
        depth.format(),
        scratch,
    )
    .ok_or_else(|| Kinect2Error::BadImageSize {
        expected: "a depth frame of 4-byte pixels".to_string(),
        got: format!("{} bytes", data.len()),
    })
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
        // SAFETY: both parameter structs are valid for reads; `raw` is a
        // valid out-pointer.
        let status = unsafe { sys::f2s_registration_new(&raw_ir, color.raw(), &mut raw) };
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
        // SAFETY: the registration is alive; `depth` views 512*424*4 readable
        // bytes; `out` points to 512*424 writable f32 (checked above), which
        // the shim writes as 4-byte pixels and nothing else aliases.
        let status =
            unsafe { sys::f2s_registration_undistort(self.handle.as_ptr(), depth.raw(), &mut out) };
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
        // SAFETY: the registration is alive and borrowed mutably (the shim
        // writes its buffers); the views point to readable frames of the
        // checked sizes; both outputs are distinct, writable 512*424
        // four-byte buffers (checked above).
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
    use crate::kinect2::FrameFormat;

    fn kinect_like() -> (IrParams, ColorParams) {
        let ir = IrParams {
            fx: 365.5,
            fy: 365.5,
            cx: 257.3,
            cy: 205.9,
            k1: 0.0905,
            k2: -0.2685,
            k3: 0.0911,
            ..Default::default()
        };
        let color = ColorParams::from_raw(sys::f2s_color_params {
            fx: 1081.37,
            fy: 1081.37,
            cx: 959.5,
            cy: 539.5,
            shift_d: 863.0,
            shift_m: 52.0,
            mx_x1y0: 0.64,
            mx_x0y0: 0.14,
            my_x0y1: 0.64,
            my_x0y0: 0.002,
            ..Default::default()
        });
        (ir, color)
    }

    #[test]
    fn plausible_parameters_pass_and_broken_ones_are_named() {
        let (ir, color) = kinect_like();
        validate_params(&ir, &color).expect("a Kinect-like calibration");
        for (bad, name) in [
            (IrParams { fx: f32::NAN, ..ir }, "IR fx"),
            (IrParams { cy: 1e9, ..ir }, "IR cy"),
            (
                IrParams {
                    k2: f32::INFINITY,
                    ..ir
                },
                "IR k2",
            ),
            (IrParams { fy: 0.0, ..ir }, "IR fy"),
        ] {
            let message = validate_params(&bad, &color)
                .expect_err("broken IR parameters")
                .to_string();
            assert!(message.contains(name), "{message}");
        }
        let mut raw = *color.raw();
        raw.shift_d = 0.0;
        let message = validate_params(&ir, &ColorParams::from_raw(raw))
            .expect_err("shift_d of 0 divides by zero")
            .to_string();
        assert!(message.contains("shift_d"), "{message}");
        let mut raw = *color.raw();
        raw.my_x0y3 = f32::NAN;
        assert!(validate_params(&ir, &ColorParams::from_raw(raw)).is_err());
        assert!(Registration::new(&IrParams { fx: f32::NAN, ..ir }, &color).is_err());
    }

    #[test]
    fn unsafe_depth_values_become_no_reading() {
        let values = [1500.0f32, f32::NAN, f32::INFINITY, 0.25, -3.0, 0.0, 1.0];
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_ne_bytes()).collect();
        let view =
            FrameView::from_bytes(values.len(), 1, 4, FrameFormat::Float, &bytes).expect("view");
        let mut scratch = Vec::new();
        let clean = sanitized_depth(&view, &mut scratch).expect("sanitised");
        let got: Vec<f32> = clean
            .data()
            .chunks_exact(4)
            .map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        assert_eq!(got, vec![1500.0, 0.0, 0.0, 0.0, -3.0, 0.0, 1.0]);
        // Clean depth is passed through without a copy.
        let fine: Vec<u8> = [800.0f32, 0.0]
            .iter()
            .flat_map(|v| v.to_ne_bytes())
            .collect();
        let view = FrameView::from_bytes(2, 1, 4, FrameFormat::Float, &fine).expect("view");
        let mut scratch = Vec::new();
        let same = sanitized_depth(&view, &mut scratch).expect("unchanged");
        assert_eq!(same.data().as_ptr(), fine.as_ptr());
        assert!(scratch.is_empty());
    }
}
