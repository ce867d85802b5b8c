//! [`CloudView`]: a borrowed organised point cloud, and the small geometric
//! helpers every stage shares.

use nalgebra::Vector3;
use slope_ipc_types::{CloudHeader, CloudPoint, Intrinsics, Mount};

/// A borrowed organised cloud: `width * height` points in row-major order,
/// camera frame (x right, y down, z forward), NaN coordinates where the
/// sensor had no reading.
#[derive(Debug, Clone, Copy)]
pub struct CloudView<'a> {
    pub points: &'a [CloudPoint],
    pub width: usize,
    pub height: usize,
    pub intrinsics: Intrinsics,
    pub mount: Mount,
}

impl<'a> CloudView<'a> {
    /// A view of a cloud sample: the header gives size, intrinsics and mount.
    /// The slice is not checked here; [`crate::Estimator::estimate`] reports
    /// a size mismatch as a bad frame.
    pub fn from_header(header: &CloudHeader, points: &'a [CloudPoint]) -> Self {
        Self {
            points,
            width: header.width as usize,
            height: header.height as usize,
            intrinsics: header.intrinsics,
            mount: header.mount,
        }
    }

    /// True when the slice holds exactly `width * height` points and the
    /// frame is not empty.
    pub fn is_well_formed(&self) -> bool {
        self.width > 0
            && self.height > 0
            && self
                .width
                .checked_mul(self.height)
                .is_some_and(|n| n == self.points.len())
    }

    /// The point of pixel index `i` as `f64`, or `None` when it has no reading
    /// (any coordinate not finite).
    #[inline]
    pub fn point(&self, i: usize) -> Option<Vector3<f64>> {
        let p = self.points.get(i)?;
        if p.x_m.is_finite() && p.y_m.is_finite() && p.z_m.is_finite() {
            Some(Vector3::new(
                f64::from(p.x_m),
                f64::from(p.y_m),
                f64::from(p.z_m),
            ))
        } else {
            None
        }
    }

    /// The largest focal length, or 1 when the intrinsics are unusable
    /// (zero, negative or NaN).
    pub fn focal_px(&self) -> f64 {
        let f = self.intrinsics.fx.max(self.intrinsics.fy);
        if f.is_finite() && f > 0.0 {
            f
        } else {
            1.0
        }
    }
}

/// The pixel bounding box of some pixels of an image, inclusive
/// (`u0..=u1` x `v0..=v1`); empty (`u0 > u1`) before the first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelBox {
    pub u0: usize,
    pub v0: usize,
    pub u1: usize,
    pub v1: usize,
}

impl PixelBox {
    /// The box of no pixel.
    pub const EMPTY: Self = Self {
        u0: usize::MAX,
        v0: usize::MAX,
        u1: 0,
        v1: 0,
    };

    /// True before the first pixel.
    pub fn is_empty(&self) -> bool {
        self.u0 > self.u1 || self.v0 > self.v1
    }

    /// Adds the pixels `u_first..=u_last` of row `v`.
    #[inline]
    pub fn add_run(&mut self, v: usize, u_first: usize, u_last: usize) {
        self.u0 = self.u0.min(u_first);
        self.u1 = self.u1.max(u_last);
        self.v0 = self.v0.min(v);
        self.v1 = self.v1.max(v);
    }

    /// The box of both boxes' pixels.
    pub fn union(&self, other: &Self) -> Self {
        Self {
            u0: self.u0.min(other.u0),
            v0: self.v0.min(other.v0),
            u1: self.u1.max(other.u1),
            v1: self.v1.max(other.v1),
        }
    }
}

/// True when all three coordinates are finite.
#[inline]
pub(crate) fn is_measured(p: &CloudPoint) -> bool {
    p.x_m.is_finite() && p.y_m.is_finite() && p.z_m.is_finite()
}

/// The point's coordinates as `f64`.
#[inline]
pub(crate) fn to_vec3(p: &CloudPoint) -> Vector3<f64> {
    Vector3::new(f64::from(p.x_m), f64::from(p.y_m), f64::from(p.z_m))
}

/// The angle between two vectors, degrees, as `atan2(|a x b|, a . b)`: exact
/// near 0 and 180 degrees where `acos` loses precision. 0..=180.
#[inline]
pub fn angle_between_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.cross(b).norm().atan2(a.dot(b)).to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angle_of_known_vectors() {
        let x = Vector3::new(1.0, 0.0, 0.0);
        let y = Vector3::new(0.0, 2.0, 0.0);
        assert!((angle_between_deg(&x, &y) - 90.0).abs() < 1e-12);
        assert!((angle_between_deg(&x, &-x) - 180.0).abs() < 1e-12);
        let t = 12.5f64.to_radians();
        let r = Vector3::new(t.cos(), t.sin(), 0.0) * 3.0;
        assert!((angle_between_deg(&x, &r) - 12.5).abs() < 1e-12);
        // Tiny angles stay exact where acos would round to 0.
        let e = 1e-9;
        let s = Vector3::new(1.0, e, 0.0);
        assert!((angle_between_deg(&x, &s).to_radians() - e).abs() < 1e-18);
    }

    #[test]
    fn well_formedness() {
        let pts = vec![CloudPoint::INVALID; 6];
        let mut view = CloudView {
            points: &pts,
            width: 3,
            height: 2,
            intrinsics: Intrinsics::default(),
            mount: Mount::UNKNOWN,
        };
        assert!(view.is_well_formed());
        view.width = 4;
        assert!(!view.is_well_formed());
        view.width = 0;
        view.height = 0;
        assert!(!view.is_well_formed());
        view.width = usize::MAX;
        view.height = 2;
        assert!(!view.is_well_formed());
    }
}
