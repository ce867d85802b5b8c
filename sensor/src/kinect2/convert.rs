//! From libfreenect2's images to the recording format's: pure functions,
//! no device needed.
//!
//! libfreenect2 delivers every image horizontally mirrored (column 0 shows
//! the right-hand side of the scene, as in a mirror; upstream issue #172) and
//! places pixel centres at +0.5 (`x = (c + 0.5 - cx) * z / fx`). We undo the
//! mirroring, so that the published cloud is the camera's true right-handed
//! frame (x right, y down, z forward) and a recording looks like the scene
//! does, and convert the intrinsics to the recording format's convention
//! (pixel centres at integer coordinates). For mirrored column `c` and
//! unmirrored column `u = W - 1 - c`:
//!
//! `x_true = -(c + 0.5 - cx_f2) * z / fx = (u - (W - 0.5 - cx_f2)) * z / fx`,
//!
//! so `cx = W - 0.5 - cx_f2` and, with no flip vertically, `cy = cy_f2 - 0.5`.
//! Depth is rounded from float millimetres to whole millimetres
//! (`unit_m = 0.001`), as a recording stores it, so a live cloud and the
//! replay of its recording are identical.

use slope_ipc_types::Intrinsics;

use super::frame::FrameFormat;
use super::params::IrParams;
use crate::recording::{ColorImage, DepthImage};

/// Metres per depth count of the images we produce.
pub const DEPTH_UNIT_M: f64 = 0.001;

/// The recording-format intrinsics of the unmirrored `width`-wide depth
/// image, from libfreenect2's IR parameters.
pub fn unmirrored_intrinsics(ir: &IrParams, width: u32) -> Intrinsics {
    Intrinsics {
        fx: f64::from(ir.fx),
        fy: f64::from(ir.fy),
        cx: f64::from(width) - 0.5 - f64::from(ir.cx),
        cy: f64::from(ir.cy) - 0.5,
    }
}

/// libfreenect2's depth (float millimetres; non-positive, NaN or infinite
/// means no reading) as a whole number of millimetres, 0 for no reading.
/// Depth that rounds beyond 65535 mm cannot be stored and is no reading
/// either (0), never a bogus 65.535 m.
#[inline]
pub fn depth_mm_to_count(depth_mm: f32) -> u16 {
    let mm = depth_mm.round();
    if mm.is_finite() && mm > 0.0 && mm <= f32::from(u16::MAX) {
        // Exact: a whole number in 1..=65535.
        mm as u16
    } else {
        0
    }
}

/// Writes the unmirrored, rounded `undistorted` depth (row-major,
/// `width * height` float mm, mirrored) into `out`, resizing it.
pub fn unmirror_depth(undistorted: &[f32], width: u32, height: u32, out: &mut DepthImage) {
    let w = width as usize;
    out.width = width;
    out.height = height;
    out.data.clear();
    out.data.reserve(w * height as usize);
    for row in undistorted.chunks_exact(w.max(1)).take(height as usize) {
        out.data
            .extend(row.iter().rev().map(|&mm| depth_mm_to_count(mm)));
    }
}

/// The RGB of one 4-byte pixel of a colour frame of `format` (libfreenect2
/// stores pixels as bytes in memory: B, G, R, X for BGRX).
#[inline]
pub fn pixel_rgb(pixel: u32, format: FrameFormat) -> [u8; 3] {
    let [b0, b1, b2, _] = pixel.to_ne_bytes();
    match format {
        FrameFormat::Rgbx => [b0, b1, b2],
        // BGRX is what the CPU/turbojpeg decoder produces; anything else
        // (VAAPI, Tegra) is documented as BGRX or RGBX.
        _ => [b2, b1, b0],
    }
}

/// Writes the unmirrored registered colour (row-major, `width * height`
/// 4-byte pixels in `format`, mirrored) into `out`, resizing it. Pixels
/// without colour (0) stay black.
pub fn unmirror_color(
    registered: &[u32],
    format: FrameFormat,
    width: u32,
    height: u32,
    out: &mut ColorImage,
) {
    let w = width as usize;
    out.width = width;
    out.height = height;
    out.data.clear();
    out.data.reserve(w * height as usize);
    for row in registered.chunks_exact(w.max(1)).take(height as usize) {
        out.data
            .extend(row.iter().rev().map(|&px| pixel_rgb(px, format)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::projection::Projector;

    #[test]
    fn depth_rounds_to_whole_millimetres_and_drops_invalid() {
        assert_eq!(depth_mm_to_count(1234.49), 1234);
        assert_eq!(depth_mm_to_count(1234.5), 1235);
        assert_eq!(depth_mm_to_count(0.4), 0);
        assert_eq!(depth_mm_to_count(0.0), 0);
        assert_eq!(depth_mm_to_count(-5.0), 0);
        assert_eq!(depth_mm_to_count(f32::NAN), 0);
        assert_eq!(depth_mm_to_count(f32::INFINITY), 0);
        assert_eq!(depth_mm_to_count(65_535.4), u16::MAX);
        assert_eq!(depth_mm_to_count(65_535.5), 0);
        assert_eq!(depth_mm_to_count(1e9), 0);
    }

    #[test]
    fn unmirroring_reverses_each_row() {
        let mirrored = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let mut out = DepthImage::default();
        unmirror_depth(&mirrored, 3, 2, &mut out);
        assert_eq!((out.width, out.height), (3, 2));
        assert_eq!(out.data, vec![3, 2, 1, 6, 5, 4]);
    }

    #[test]
    fn colour_byte_order_follows_the_frame_format() {
        let pixel = u32::from_ne_bytes([10, 20, 30, 0]);
        assert_eq!(pixel_rgb(pixel, FrameFormat::Bgrx), [30, 20, 10]);
        assert_eq!(pixel_rgb(pixel, FrameFormat::Rgbx), [10, 20, 30]);
        let registered = [pixel, 0];
        let mut out = ColorImage::default();
        unmirror_color(&registered, FrameFormat::Bgrx, 2, 1, &mut out);
        assert_eq!(out.data, vec![[0, 0, 0], [30, 20, 10]]);
    }

    /// libfreenect2's own point formula on the mirrored image, negated in x
    /// (the un-mirrored world), must equal our projection of the unmirrored
    /// image with the converted intrinsics, for every pixel.
    #[test]
    fn unmirrored_projection_matches_libfreenect2_geometry() {
        let ir = IrParams {
            fx: 365.5,
            fy: 365.1,
            cx: 257.3,
            cy: 205.9,
            ..Default::default()
        };
        let (width, height) = (512u32, 424u32);
        let mirrored: Vec<f32> = (0..width * height)
            .map(|i| 800.0 + (i % 977) as f32 * 3.0)
            .collect();
        let mut depth = DepthImage::default();
        unmirror_depth(&mirrored, width, height, &mut depth);
        let intrinsics = unmirrored_intrinsics(&ir, width);
        let projector = Projector::new(width, height, intrinsics, DEPTH_UNIT_M);
        let mut worst = 0.0f64;
        for r in 0..height as usize {
            for c in 0..width as usize {
                let z = f64::from(mirrored[r * width as usize + c]) / 1000.0;
                // Registration::getPointXYZ, with the mirror undone.
                let x = -((c as f64 + 0.5 - f64::from(ir.cx)) / f64::from(ir.fx) * z);
                let y = (r as f64 + 0.5 - f64::from(ir.cy)) / f64::from(ir.fy) * z;
                let u = width as usize - 1 - c;
                let i = r * width as usize + u;
                let p = projector.point(i, depth.data[i], 0);
                for (ours, theirs) in [(p.x_m, x), (p.y_m, y), (p.z_m, z)] {
                    worst = worst.max((f64::from(ours) - theirs).abs());
                }
            }
        }
        // f32 storage of metres: well under a tenth of a millimetre.
        assert!(worst < 1e-4, "worst difference {worst} m");
    }
}
