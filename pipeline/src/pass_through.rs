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

use crate::cloud::{is_measured, CloudView, PixelBox};
use crate::normals::{PlaneSupport, SupportWalk};
use crate::validate::{at_least, InvalidValue};
use nalgebra::Vector3;
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
    /// The members with a reading, in pixel order.
    valid: Vec<u32>,
    /// The kept ones among them, when cut.
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
        self.walk(points, members, |_, _| {});
        let total = self
            .valid
            .iter()
            .map(|&i| footprint(&points[i as usize]))
            .sum();
        let cut = self.sample(points, max_points, total);
        let kept = self.kept(cut);
        let (mut lo, mut hi) = (f64::NAN, f64::NAN);
        for &i in kept {
            let p = &points[i as usize];
            let e = f64::from(p.y_m / p.z_m);
            lo = if lo.is_nan() { e } else { lo.min(e) };
            hi = if hi.is_nan() { e } else { hi.max(e) };
        }
        (
            kept,
            PassThroughRange {
                min_elevation: lo,
                max_elevation: hi,
                cut,
            },
        )
    }

    /// As [`Self::filter`] (the same kept points), without the elevation
    /// range, and with the plane's support for its normals from the same
    /// walk: every member with a reading, their bounding box and centroid
    /// ([`PlaneSupport`], what `NormalEstimator::estimate_with_support`
    /// would find in `members`). `None` for the support when that walk
    /// would differ: members out of pixel order, a member with a finite
    /// point at depth 0 (no reading here, one there), a view of width 0.
    pub fn filter_plane(
        &mut self,
        cloud: &CloudView<'_>,
        members: &[u32],
        max_points: usize,
    ) -> (&[u32], Option<PlaneSupport<'_>>) {
        let points = cloud.points;
        let Some(mut support) = SupportWalk::new(cloud.width) else {
            return (self.filter(points, members, max_points).0, None);
        };
        let mut total = -0.0;
        let (sorted, zero_depth) = self.walk(points, members, |pixel, p| {
            support.add(pixel, p);
            total += footprint(p);
        });
        if !sorted || zero_depth {
            return (self.filter(points, members, max_points).0, None);
        }
        let cut = self.sample(points, max_points, total);
        // `valid` is the members with a point, in their (pixel) order.
        (self.kept(cut), support.finish(&self.valid))
    }

    /// As [`Self::filter_plane`] for the inliers of a segmented plane
    /// (`members`, with their bounding box and centre: every one has a
    /// reading at a depth other than 0 and they are in pixel order, the
    /// labelling's promise, `SegmentedPlane::pixel_box`): the same kept
    /// points, and the support from the box without walking the members
    /// for it.
    pub fn filter_segment<'a>(
        &'a mut self,
        points: &[CloudPoint],
        members: &'a [u32],
        (pixel_box, centre): (PixelBox, Vector3<f64>),
        max_points: usize,
    ) -> (&'a [u32], Option<PlaneSupport<'a>>) {
        let mut total = -0.0;
        for p in members.iter().filter_map(|&i| points.get(i as usize)) {
            total += footprint(p);
        }
        let cut = members.len() > max_points;
        if cut {
            surface_sample(points, members, &mut self.kept, max_points, total);
        }
        let kept = if cut { &self.kept[..] } else { members };
        (kept, PlaneSupport::new(members, pixel_box, centre))
    }

    /// Collects the members with a reading into `valid`, each passed to
    /// `visit` in member order; sorts and dedups `valid` when the members
    /// are out of pixel order. Returns whether they were in order, and
    /// whether a member had a finite point at depth 0.
    fn walk(
        &mut self,
        points: &[CloudPoint],
        members: &[u32],
        mut visit: impl FnMut(usize, &CloudPoint),
    ) -> (bool, bool) {
        self.valid.clear();
        let (mut sorted, mut zero_depth, mut last) = (true, false, 0);
        for &i in members {
            let Some(p) = points.get(i as usize).filter(|p| is_measured(p)) else {
                continue;
            };
            if p.z_m == 0.0 {
                zero_depth = true;
                continue;
            }
            sorted &= i >= last;
            last = i;
            self.valid.push(i);
            visit(i as usize, p);
        }
        if !sorted {
            self.valid.sort_unstable();
            self.valid.dedup();
        }
        (sorted, zero_depth)
    }

    /// At most `max_points` of `valid` (surface-uniform, `total` their
    /// footprints' sum) into `kept` when there are more; returns whether
    /// it cut any.
    fn sample(&mut self, points: &[CloudPoint], max_points: usize, total: f64) -> bool {
        let cut = self.valid.len() > max_points;
        if cut {
            surface_sample(points, &self.valid, &mut self.kept, max_points, total);
        }
        cut
    }

    /// The kept points: `kept` when `cut`, else all of `valid`.
    fn kept(&self, cut: bool) -> &[u32] {
        if cut {
            &self.kept
        } else {
            &self.valid
        }
    }
}

/// A point's footprint on its plane, up to a factor common to the plane:
/// `|z|^3` (`surface_sample`).
#[inline]
fn footprint(p: &CloudPoint) -> f64 {
    let z = f64::from(p.z_m).abs();
    z * z * z
}

/// Keeps at most `max_points` of `valid` (pixels in pixel order), each with
/// a probability proportional to its pixel's footprint on the plane.
///
/// A pixel sees the solid angle `cos^3(a) / f^2` (a: off the optical axis,
/// `cos a = z / r`); on a plane `n . p + d = 0` at range `r` that is the
/// area `r^2 / cos(t)` times it, with `cos t = |d| / r`. Together
/// `z^3 / (f^2 |d|)`: on one plane, a pixel's footprint grows as `z^3`.
/// Systematic sampling: walking the points in pixel order, a point is kept
/// when the running sum of footprints crosses the next multiple of
/// `total / max_points` (once, even if it crosses several). `total` is the
/// footprints' sum over `valid`; the kept points go to `kept`.
fn surface_sample(
    points: &[CloudPoint],
    valid: &[u32],
    kept: &mut Vec<u32>,
    max_points: usize,
    total: f64,
) {
    kept.clear();
    if max_points == 0 || !(total.is_finite() && total > 0.0) {
        kept.extend_from_slice(&valid[..max_points.min(valid.len())]);
        return;
    }
    let step = total / max_points as f64;
    let (mut sum, mut next) = (0.0, 0.5 * step);
    for &i in valid {
        sum += footprint(&points[i as usize]);
        if sum >= next && kept.len() < max_points {
            kept.push(i);
            next += step * ((sum - next) / step).floor().max(0.0) + step;
        }
    }
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

    /// The support `filter_plane` hands the normals gives them the normals
    /// `estimate_with_support` finds from the plane's pixels, bit for bit,
    /// and the same kept points as `filter`; members out of order or a
    /// finite point at depth 0 give no support (the normals walk
    /// themselves).
    #[test]
    fn filter_plane_hands_the_normals_the_support_they_would_walk() {
        use crate::fixtures::{Scene, SceneCloud};
        use crate::normals::{NormalEstimator, NormalsConfig};
        use nalgebra::Vector3;

        let scene = Scene::ramp(30.0);
        let mut cloud = SceneCloud::render_with_intrinsics(&scene, 256, 212, 180.0, 0.002, 3);
        // Members without a reading, and one at the edge of the image.
        for i in [0, 1000, 1001, 20_000] {
            cloud.points[i] = CloudPoint::INVALID;
        }
        let members: Vec<u32> = (0..cloud.points.len() as u32).step_by(2).collect();
        let view = cloud.view();
        let mut pt = PassThrough::new();
        let expected = pt.filter(view.points, &members, 3000).0.to_vec();
        assert_eq!(expected.len(), 3000);
        let (kept, support) = pt.filter_plane(&view, &members, 3000);
        assert_eq!(kept, expected);
        let support = support.expect("members in pixel order");
        let measured = |&&i: &&u32| crate::cloud::is_measured(&cloud.points[i as usize]);
        let with_reading: Vec<u32> = members.iter().filter(measured).copied().collect();
        assert_eq!(with_reading.len(), members.len() - 3);
        assert_eq!(support.pixels(), with_reading);
        let (origin, mut walked, mut own) = (
            Vector3::zeros(),
            NormalEstimator::new(),
            NormalEstimator::new(),
        );
        for interior_only in [false, true] {
            let cfg = NormalsConfig {
                interior_only,
                ..NormalsConfig::default()
            };
            let (a, a_stats) = walked.estimate_on_plane(&view, kept, &support, &cfg, &origin);
            let (b, b_stats) = own.estimate_with_support(&view, kept, &members, &cfg, &origin);
            assert_eq!(a_stats, b_stats);
            assert!(a_stats.from_window > 2000, "{a_stats:?}");
            let bits = |n: &[Vector3<f64>]| -> Vec<[u64; 3]> {
                n.iter()
                    .map(|n| [n.x.to_bits(), n.y.to_bits(), n.z.to_bits()])
                    .collect()
            };
            assert_eq!(bits(a), bits(b));
        }
        // Out of pixel order: the same kept points, no support.
        let reversed: Vec<u32> = members.iter().rev().copied().collect();
        let (kept, support) = pt.filter_plane(&view, &reversed, 3000);
        assert_eq!(kept, expected);
        assert!(support.is_none());
        // A finite point at depth 0: dropped here, a neighbour there.
        cloud.points[members[7] as usize].z_m = 0.0;
        let view = cloud.view();
        let expected = pt.filter(view.points, &members, 3000).0.to_vec();
        let (kept, support) = pt.filter_plane(&view, &members, 3000);
        assert_eq!(kept, expected);
        assert!(support.is_none());
    }

    /// A segmented plane's pass-through from its box keeps the points the
    /// walk keeps, and hands the normals the same support pixels and box:
    /// their normals agree with the walked support's (the centres, the
    /// tables' origins, differ by rounding).
    #[test]
    fn a_segmented_plane_filtered_from_its_box_is_the_walked_plane() {
        use crate::fixtures::{Scene, SceneCloud};
        use crate::normals::{NormalEstimator, NormalsConfig};
        use crate::ransac_planes::{PlaneSegmenter, RansacConfig};
        use nalgebra::Vector3;
        use rand::SeedableRng;

        let cloud = SceneCloud::kinect2(&Scene::ramp(16.0), 6);
        let view = cloud.view();
        let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
        let planes = PlaneSegmenter::new()
            .segment(
                &view,
                &keep,
                &RansacConfig::default(),
                &mut rand_chacha::ChaCha8Rng::seed_from_u64(1),
            )
            .to_vec();
        assert!(planes.len() >= 2);
        let (mut walked_pt, mut boxed_pt) = (PassThrough::new(), PassThrough::new());
        let (mut walked_normals, mut boxed_normals) =
            (NormalEstimator::new(), NormalEstimator::new());
        let (cfg, origin) = (NormalsConfig::default(), Vector3::zeros());
        for (plane, cap) in planes.iter().take(2).zip([3000, 1_000_000]) {
            let (kept, walked) = walked_pt.filter_plane(&view, &plane.inliers, cap);
            let walked = walked.expect("inliers in pixel order");
            let pixel_box = plane.pixel_box.expect("labelled");
            let (boxed_kept, boxed) = boxed_pt.filter_segment(
                view.points,
                &plane.inliers,
                (pixel_box, plane.centroid),
                cap,
            );
            let boxed = boxed.expect("a box");
            assert_eq!(kept, boxed_kept);
            assert_eq!(kept.len(), plane.inliers.len().min(cap));
            assert_eq!(walked.pixels(), boxed.pixels());
            let (a, a_stats) =
                walked_normals.estimate_on_plane(&view, kept, &walked, &cfg, &origin);
            let (b, b_stats) = boxed_normals.estimate_on_plane(&view, kept, &boxed, &cfg, &origin);
            assert_eq!(a_stats, b_stats);
            assert!(a_stats.from_window * 10 > kept.len() * 9, "{a_stats:?}");
            for (a, b) in a.iter().zip(b) {
                assert!((a - b).norm() < 1e-9, "{a} {b}");
            }
        }
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
