//! The inclined plane: the ramp, wall or riser the slope is measured on.
//!
//! A candidate is a plane flat at the sensor's noise level (see
//! [`super::is_flat_at_noise_level`]) of at least `inclined_min_area_m2`
//! that is not part of
//! the ground and
//!
//! - is inclined: its normal is more than the sensor's floor bend at its
//!   centroid's depth (`sensor_noise.rs`, range bias) from the ground's
//!   (closer planes are the floor as the sensor bends it, or parallel to
//!   it) and at most `max_slope_deg` from it: a surface whose normal
//!   points further down faces the floor (a ceiling, an overhang, the
//!   underside of a table) and is never a slope;
//! - faces along the robot's way: the horizontal part of its normal is
//!   within `max_heading_deg` of forward or backward (a wall beside a ramp
//!   has a horizontal normal perpendicular to forward and is never taken);
//! - lies ahead: its centroid is in front of the camera along forward.
//!
//! Among candidates with at least `min_relative_support` of the
//! best-supported candidate's pixels, the nearest (smallest distance of its
//! centroid along forward) is the one the robot drives onto or faces first.

use nalgebra::Vector3;

use super::SelectionConfig;
use super::{is_flat_at_noise_level, PlaneSummary};
use crate::cloud::angle_between_deg;
use crate::plane_fit::Plane;

/// Chooses the inclined plane among `planes` not in `ground`, on the
/// planes' summaries alone (no pixels: the road's rules, `road.rs`, need
/// them): the nearest candidate by its centroid's forward distance.
pub fn choose_inclined(
    planes: &[PlaneSummary],
    ground: &[usize],
    up: &Vector3<f64>,
    forward: &Vector3<f64>,
    config: &SelectionConfig,
) -> Option<usize> {
    let candidates: Vec<usize> = (0..planes.len())
        .filter(|k| !ground.contains(k))
        .filter(|&k| is_inclined_candidate(&planes[k], up, forward, config))
        .collect();
    let support = candidates
        .iter()
        .map(|&k| planes[k].inliers)
        .max()
        .unwrap_or(0);
    candidates
        .iter()
        .copied()
        .filter(|&k| planes[k].inliers as f64 >= config.min_relative_support * support as f64)
        .min_by(|&a, &b| {
            planes[a]
                .centroid
                .dot(forward)
                .total_cmp(&planes[b].centroid.dot(forward))
                .then(a.cmp(&b))
        })
}

/// True when the plane passes the inclined plane's tests (module
/// documentation): flat at the noise level, large enough, inclined but not
/// facing down, facing along forward, its centroid ahead.
pub fn is_inclined_candidate(
    p: &PlaneSummary,
    up: &Vector3<f64>,
    forward: &Vector3<f64>,
    config: &SelectionConfig,
) -> bool {
    let cos_heading = config.max_heading_deg.to_radians().cos();
    let bend = config
        .noise_model
        .unwrap_or_default()
        .floor_bend_deg(p.centroid.z);
    let n = p.plane.normal;
    let angle = angle_between_deg(&n, up);
    let horizontal = n - up * n.dot(up);
    let h = horizontal.norm();
    is_flat_at_noise_level(p, config)
        && p.quality.area_m2 >= config.inclined_min_area_m2
        && angle > bend
        && angle <= config.max_slope_deg
        && h > 1e-9
        && horizontal.dot(forward).abs() >= cos_heading * h
        && p.centroid.dot(forward) > 0.0
}

/// The optical axis projected perpendicular to `up`, unit; when the camera
/// looks straight along `up`, the image's up direction (-y) projected instead.
pub fn forward_direction(up: &Vector3<f64>) -> Vector3<f64> {
    let z = Vector3::z();
    let f = z - up * z.dot(up);
    if let Some(f) = f.try_normalize(1e-6) {
        return f;
    }
    let y = -Vector3::y();
    (y - up * y.dot(up)).try_normalize(1e-12).unwrap_or(z)
}

/// The slope's sign: +1 uphill (the inclined normal points back towards the
/// robot), -1 downhill.
pub fn slope_sign(inclined_normal: &Vector3<f64>, forward: &Vector3<f64>) -> f64 {
    if inclined_normal.dot(forward) > 0.0 {
        -1.0
    } else {
        1.0
    }
}

/// Distance from the camera to `plane` along the optical axis, metres; NaN
/// when the axis is parallel to the plane or meets it behind the camera.
pub fn axis_distance(plane: &Plane) -> f64 {
    let nz = plane.normal.z;
    if nz.abs() < 1e-9 {
        return f64::NAN;
    }
    let t = -plane.d / nz;
    if t.is_finite() && t > 0.0 {
        t
    } else {
        f64::NAN
    }
}
