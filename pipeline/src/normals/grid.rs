//! The coarse normal of a sample point that gates RANSAC's inliers.

use nalgebra::Vector3;

use super::{moments, normal_from_sums, orient, CHANNELS};
use crate::cloud::{to_vec3, CloudView};

/// A coarse normal at pixel `(u, v)` from the measured, `keep`-marked
/// pixels of the `(2r+1)^2` window, every `step`-th in both directions,
/// that lie within a few pixel spacings of it in 3D (so a depth edge does
/// not bend it); at least 6 of them. Used to gate RANSAC inliers.
pub(crate) fn grid_normal(
    cloud: &CloudView<'_>,
    keep: &[bool],
    u: usize,
    v: usize,
    radius: usize,
    step: usize,
) -> Option<Vector3<f64>> {
    let w = cloud.width;
    let step = step.max(1);
    let centre = to_vec3(cloud.points.get(v * w + u)?);
    let focal = cloud.focal_px();
    // Up to 8 pixel spacings per pixel step: surfaces seen at down to ~7
    // degrees of grazing incidence still count.
    let reach = 8.0 * centre.z.abs() / focal;
    let mut m = [0.0; CHANNELS];
    let (u0, u1) = (u.saturating_sub(radius), (u + radius + 1).min(w));
    let (v0, v1) = (v.saturating_sub(radius), (v + radius + 1).min(cloud.height));
    // Offsets that are multiples of `step` from the centre.
    let (u0, v0) = (u - (u - u0) / step * step, v - (v - v0) / step * step);
    for vv in (v0..v1).step_by(step) {
        for uu in (u0..u1).step_by(step) {
            let i = vv * w + uu;
            if !keep.get(i).copied().unwrap_or(false) {
                continue;
            }
            let q = to_vec3(&cloud.points[i]) - centre;
            let steps = uu.abs_diff(u).max(vv.abs_diff(v)) as f64;
            let limit = reach * steps.max(1.0);
            if q.norm_squared() > limit * limit {
                continue;
            }
            let row = moments(&q);
            for (mc, r) in m.iter_mut().zip(row) {
                *mc += r;
            }
        }
    }
    if m[0] < 6.0 {
        return None;
    }
    normal_from_sums(&m, &centre, 0.0, focal).map(|n| orient(n, &centre, &Vector3::zeros()))
}
