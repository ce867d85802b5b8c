//! Stage 3, pass-through filter (paper 3.1): a plane with more than
//! `max_points` (10,000) points is cut down to at most that many.
//!
//! **Which points.** The paper names neither the axis nor the range. We
//! keep a subsample spread *uniformly over the plane's surface*, each point
//! kept with a probability proportional to the area its pixel covers there
//! (`z^3` on one plane), by systematic sampling in pixel order. Why:
//!
//! - *Not a band.* Real floors are not flat to a degree or two over a frame
//!   (the Kinect v2 stair frame's floor bends by ~2 degrees between its near
//!   and far part, at the image edge), so which band of rows is kept moved
//!   the answer by degrees. The whole plane is what the TLS baseline
//!   measures.
//! - *Not every n-th pixel.* Near the camera a pixel covers `1/z^3` less
//!   surface, so a pixel-uniform subsample weights a floor's first metre
//!   most and its normal comes from there; on the stair frame the kept
//!   per-point normals of a pixel-uniform sample averaged 1.7 degrees off
//!   the floor's TLS normal, those of the surface-uniform sample 0.4.
//! - *Not a metric coordinate.* Depth noise moves a point along its ray, so
//!   cutting a range of x, y or z keeps the points whose noise pushed them
//!   inside and tilts the kept surface (1 degree on a wall band). The
//!   footprint weights only decide *which pixels*, not where their points
//!   are, and the normals still take their neighbourhoods from all of the
//!   plane's points (`NormalEstimator::estimate_with_support`).

use crate::validate::{at_least, InvalidValue};
use serde::{Deserialize, Serialize};
use slope_ipc_types::CloudPoint;

/// The range a pass-through kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassThroughRange {
    /// Kept range of the ray elevation `y / z` (both NaN when the input was
    /// empty).
    pub min_elevation: f64,
    pub max_elevation: f64,
    /// True when points were removed.
    pub cut: bool,
}

/// Reusable buffers of the filter.
#[derive(Debug, Default, Clone)]
pub struct PassThrough {
    kept: Vec<u32>,
}

impl PassThrough {
    pub fn new() -> Self {
        Self::default()
    }

    /// Keeps at most `max_points` of `members` (pixel indices into `points`),
    /// uniformly over the plane's surface (all of them when there are no
    /// more). Members without a reading are dropped. Returns the kept
    /// indices (in pixel order) and the range of ray elevations `y / z`
    /// they span.
    pub fn filter(
        &mut self,
        points: &[CloudPoint],
        members: &[u32],
        max_points: usize,
    ) -> (&[u32], PassThroughRange) {
        self.kept.clear();
        self.kept.extend(members.iter().copied().filter(|&i| {
            points.get(i as usize).is_some_and(|p| {
                p.z_m.is_finite() && p.x_m.is_finite() && p.y_m.is_finite() && p.z_m != 0.0
            })
        }));
        if !self.kept.is_sorted() {
            self.kept.sort_unstable();
            self.kept.dedup();
        }
        let cut = self.kept.len() > max_points;
        if cut {
            surface_sample(points, &mut self.kept, max_points);
        }
        let (mut lo, mut hi) = (f64::NAN, f64::NAN);
        for &i in &self.kept {
            let p = &points[i as usize];
            let e = f64::from(p.y_m / p.z_m);
            lo = if lo.is_nan() { e } else { lo.min(e) };
            hi = if hi.is_nan() { e } else { hi.max(e) };
        }
        (
            &self.kept,
            PassThroughRange {
                min_elevation: lo,
                max_elevation: hi,
                cut,
            },
        )
    }
}

/// Keeps at most `max_points` of `kept` (pixels in pixel order), each with
/// a probability proportional to its pixel's footprint on the plane.
///
/// A pixel sees the solid angle `cos^3(a) / f^2` (a: off the optical axis,
/// `cos a = z / r`); on a plane `n . p + d = 0` at range `r` that is the
/// area `r^2 / cos(t)` times it, with `cos t = |d| / r`. Together
/// `z^3 / (f^2 |d|)`: on one plane, a pixel's footprint grows as `z^3`.
/// Systematic sampling: walking the points in pixel order, a point is kept
/// when the running sum of footprints crosses the next multiple of
/// `total / max_points` (once, even if it crosses several).
fn surface_sample(points: &[CloudPoint], kept: &mut Vec<u32>, max_points: usize) {
    let footprint = |i: u32| {
        let z = f64::from(points[i as usize].z_m).abs();
        z * z * z
    };
    let total: f64 = kept.iter().map(|&i| footprint(i)).sum();
    if max_points == 0 || !(total.is_finite() && total > 0.0) {
        kept.truncate(max_points);
        return;
    }
    let step = total / max_points as f64;
    let (mut sum, mut next, mut out) = (0.0, 0.5 * step, 0);
    for k in 0..kept.len() {
        sum += footprint(kept[k]);
        if sum >= next && out < max_points {
            kept[out] = kept[k];
            out += 1;
            next += step * ((sum - next) / step).floor().max(0.0) + step;
        }
    }
    kept.truncate(out);
}

/// Pass-through filter (`pass_through.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PassThroughConfig {
    /// A plane with more points is cut down to at most this many (paper: 10,000).
    pub max_points: usize,
    /// Uniform over the surface (ours) or the nearest along the depth axis
    /// (the paper as we read it, `literal/depth_pass_through.rs`).
    pub mode: crate::literal::PassThroughMode,
}

impl Default for PassThroughConfig {
    fn default() -> Self {
        Self {
            max_points: 10_000,
            mode: crate::literal::PassThroughMode::SurfaceUniform,
        }
    }
}

impl PassThroughConfig {
    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), InvalidValue> {
        at_least("max_points", self.max_points, 3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points at 2 m depth whose rays have the given elevations `y / z`.
    fn points_at_elevations(elevations: &[f32]) -> Vec<CloudPoint> {
        elevations
            .iter()
            .map(|&e| CloudPoint {
                x_m: 0.1,
                y_m: 2.0 * e,
                z_m: 2.0,
                rgb: 0,
            })
            .collect()
    }

    #[test]
    fn surface_sample_is_uniform_over_area() {
        // 1000 pixels at 1 m and 1000 at 2 m on one plane: a far pixel
        // covers 8 times the area, so of 900 kept, 100 are near, 800 far.
        let mut pts = Vec::new();
        for k in 0..2000u32 {
            let z = if k % 2 == 0 { 1.0 } else { 2.0 };
            pts.push(CloudPoint {
                x_m: 0.0,
                y_m: 0.3 * z,
                z_m: z,
                rgb: 0,
            });
        }
        let members: Vec<u32> = (0..2000).collect();
        let mut pt = PassThrough::new();
        let (kept, range) = pt.filter(&pts, &members, 900);
        assert!(range.cut);
        let near = kept.iter().filter(|&&i| i % 2 == 0).count();
        let far = kept.len() - near;
        assert!((99..=101).contains(&near), "{near}");
        assert!((799..=801).contains(&far), "{far}");
        // Every member at most once, in pixel order.
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
        // A cap above the count keeps everything.
        assert_eq!(pt.filter(&pts, &members, 2000).0.len(), 2000);
    }

    #[test]
    fn small_planes_pass_unchanged_and_ties_are_capped() {
        let pts = points_at_elevations(&[2.0; 50]);
        let members: Vec<u32> = (0..50).collect();
        let mut pt = PassThrough::new();
        let (kept, range) = pt.filter(&pts, &members, 50);
        assert_eq!(kept.len(), 50);
        assert!(!range.cut);
        let (kept, range) = pt.filter(&pts, &members, 20);
        assert_eq!(kept.len(), 20);
        assert!(range.cut);
        let mut bad = pts.clone();
        bad[3] = CloudPoint::INVALID;
        let (kept, _) = pt.filter(&bad, &[3, 4, 999], 10);
        assert_eq!(kept, &[4]);
    }
}
