//! The points a plane's normals take their neighbourhoods from, summarised
//! in the same walk that checks them: their pixel bounding box and their
//! centroid (the summed-area tables' extent and origin). The pass-through
//! walks the plane's pixels anyway and hands its summary over
//! ([`PlaneSupport`]), so the normals do not walk them again; the two
//! summaries are one code path ([`SupportWalk`]) and bit for bit the same.

use nalgebra::Vector3;
use slope_ipc_types::CloudPoint;

use super::Bounds;
use crate::cloud::{to_vec3, PixelBox};

/// A plane's support pixels with their bounding box and centroid.
///
/// `pixels` are in pixel order (non-decreasing) and every one has a
/// measured point (all three coordinates finite) in the cloud they were
/// walked in; the bounds and centre are over exactly these pixels.
#[derive(Debug, Clone, Copy)]
pub struct PlaneSupport<'a> {
    pub(super) pixels: &'a [u32],
    pub(super) bounds: Bounds,
    pub(super) centre: Vector3<f64>,
}

impl<'a> PlaneSupport<'a> {
    /// The support of `pixels` (in pixel order, each with a reading at a
    /// depth other than 0: the caller's promise, a walk's or the
    /// labelling's, [`crate::ransac_planes::SegmentedPlane::pixel_box`]),
    /// their bounding box and a centre near them (the summed-area tables'
    /// origin; their mean). `None` for an empty box. Crate-only: a box
    /// that does not hold the pixels would send the tables out of range,
    /// so outside the crate a support comes from a [`SupportWalk`].
    pub(crate) fn new(
        pixels: &'a [u32],
        pixel_box: PixelBox,
        centre: Vector3<f64>,
    ) -> Option<Self> {
        (!pixel_box.is_empty()).then(|| Self {
            pixels,
            bounds: Bounds {
                u0: pixel_box.u0,
                v0: pixel_box.v0,
                width: pixel_box.u1 - pixel_box.u0 + 1,
                height: pixel_box.v1 - pixel_box.v0 + 1,
            },
            centre,
        })
    }

    /// The support's pixels (pixel order, all measured).
    pub fn pixels(&self) -> &'a [u32] {
        self.pixels
    }
}

/// The running bounding box and coordinate sum of a walk over measured
/// pixels of an image `width` pixels wide. The pixel's row is found by a
/// division only when it leaves the last pixel's row (in pixel order, once
/// a row).
#[derive(Debug, Clone, Copy)]
pub struct SupportWalk {
    width: usize,
    /// First pixel of the last pixel's row; before the first pixel,
    /// `-width` (wrapping), which no pixel is within `width` of.
    row_start: usize,
    pixel_box: PixelBox,
    sum: Vector3<f64>,
    count: usize,
}

impl SupportWalk {
    /// An empty walk; `None` for a width of 0 (no pixel has a place).
    pub fn new(width: usize) -> Option<Self> {
        (width > 0).then_some(Self {
            width,
            row_start: 0usize.wrapping_sub(width),
            pixel_box: PixelBox::EMPTY,
            sum: Vector3::zeros(),
            count: 0,
        })
    }

    /// Adds the measured point `p` at `pixel`.
    #[inline]
    pub fn add(&mut self, pixel: usize, p: &CloudPoint) {
        let mut u = pixel.wrapping_sub(self.row_start);
        if u >= self.width {
            let v = pixel / self.width;
            self.row_start = v * self.width;
            let b = &mut self.pixel_box;
            (b.v0, b.v1) = (b.v0.min(v), b.v1.max(v));
            u = pixel - self.row_start;
        }
        let b = &mut self.pixel_box;
        (b.u0, b.u1) = (b.u0.min(u), b.u1.max(u));
        self.sum += to_vec3(p);
        self.count += 1;
    }

    /// The summary of `pixels`, the pixels walked (in pixel order, all
    /// measured, the caller's promise); `None` when the walk saw none.
    pub fn finish(self, pixels: &[u32]) -> Option<PlaneSupport<'_>> {
        let centre = self.sum / self.count.max(1) as f64;
        PlaneSupport::new(pixels, self.pixel_box, centre)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pixels in and out of order, rows revisited, the first row and the
    /// last column: the box is theirs and the centre their mean.
    #[test]
    fn walk_finds_the_bounding_box_and_centroid_in_any_order() {
        let width = 7;
        let pixels = [9u32, 3, 2, 40, 13, 0, 41, 6, 16];
        let point = |i: u32| CloudPoint {
            x_m: i as f32 * 0.1,
            y_m: 1.0 - i as f32 * 0.01,
            z_m: 2.0 + i as f32 * 0.05,
            rgb: 0,
        };
        let mut walk = SupportWalk::new(width).expect("width > 0");
        let mut sum = Vector3::zeros();
        for &i in &pixels {
            walk.add(i as usize, &point(i));
            sum += to_vec3(&point(i));
        }
        let support = walk.finish(&pixels).expect("pixels walked");
        let b = support.bounds;
        // Columns 2, 3, 0, 5, 6, 0, 6, 6, 2; rows 1, 0, 0, 5, 1, 0, 5, 0, 2.
        assert_eq!((b.u0, b.width, b.v0, b.height), (0, 7, 0, 6));
        assert_eq!(support.centre, sum / pixels.len() as f64);
        assert_eq!(support.pixels(), pixels);
        // Only the last row and a middle column.
        let mut walk = SupportWalk::new(width).expect("width > 0");
        for i in [38u32, 31, 39] {
            walk.add(i as usize, &point(i));
        }
        let b = walk.finish(&[]).expect("pixels walked").bounds;
        assert_eq!((b.u0, b.width, b.v0, b.height), (3, 2, 4, 2));
        assert!(SupportWalk::new(width)
            .expect("width > 0")
            .finish(&[])
            .is_none());
        assert!(SupportWalk::new(0).is_none());
    }
}
