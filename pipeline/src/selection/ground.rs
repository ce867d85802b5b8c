//! The ground: the support surface the robot stands on.
//!
//! 1. **Level candidates** are flat planes (see [`super::is_flat`]) whose
//!    normal is within `ground_max_tilt_deg` (mount) or
//!    `unmounted_ground_max_tilt_deg` (no mount) of the reference up.
//! 2. **The ground's family**: with a mount, the candidate whose normal is
//!    closest to the mount's up; without one, the candidate with the most
//!    pixels in the bottom third of the image (the floor right in front of
//!    the robot). Every candidate parallel to it (`parallel_tolerance_deg`)
//!    is in its family: floor, treads, table and bed tops; a shallow ramp
//!    is not.
//! 3. **Known mount height**: a family member's centroid must lie within
//!    `ground_height_tolerance_m` of the mount height below the camera.
//!    None does: the mount's plane is the ground (`ground_from_mount`).
//! 4. **The lowest** family member with at least `ground_min_pixels` pixels
//!    and `ground_min_area_m2` of surface (its centroid farthest below the
//!    camera along the family's up) is the ground. A bed, a table, a seat or
//!    a step above the visible floor is higher, whatever its size.
//! 5. **The ground's segments**: RANSAC may cut one slightly bent real floor
//!    into pieces a few centimetres apart, differently from draw to draw.
//!    Family members coplanar with a segment of the ground (each one's
//!    centroid within `coplanar_tolerance_m` of the other's plane) are
//!    segments too, and the ground is measured on all of them together: the
//!    same floor whichever piece RANSAC found first.

use nalgebra::Vector3;

use super::SelectionConfig;
use super::{is_flat, PlaneSummary};
use crate::cloud::angle_between_deg;

/// The ground as chosen: the lowest plane and every segment of it.
#[derive(Debug, Clone, PartialEq)]
pub enum Ground {
    /// Plane indices, the lowest plane first.
    Planes(Vec<usize>),
    /// The mount's plane (no level plane at the mount's height).
    Mount,
}

/// Chooses the ground. `None`: no level plane and no mount to fall back on.
pub fn choose_ground(
    planes: &[PlaneSummary],
    reference: &Vector3<f64>,
    mount_height_m: Option<f64>,
    mounted: bool,
    config: &SelectionConfig,
) -> Option<Ground> {
    let max_tilt = if mounted {
        config.ground_max_tilt_deg
    } else {
        config.unmounted_ground_max_tilt_deg
    };
    let tilt = |k: usize| angle_between_deg(&planes[k].plane.normal, reference);
    let level: Vec<usize> = (0..planes.len())
        .filter(|&k| is_flat(&planes[k], config) && tilt(k) <= max_tilt)
        .collect();
    let anchor = if mounted {
        level
            .iter()
            .copied()
            .min_by(|&a, &b| tilt(a).total_cmp(&tilt(b)))
    } else {
        level.iter().copied().max_by(|&a, &b| {
            planes[a]
                .bottom_pixels
                .cmp(&planes[b].bottom_pixels)
                .then(b.cmp(&a))
        })
    };
    let Some(anchor) = anchor else {
        return mounted.then_some(Ground::Mount);
    };
    let up = planes[anchor].plane.normal;
    // Height of a plane's centroid below the camera along the family's up.
    let depth_below = |k: usize| -up.dot(&planes[k].centroid);
    let family: Vec<usize> = level
        .into_iter()
        .filter(|&k| {
            angle_between_deg(&planes[k].plane.normal, &up) <= config.parallel_tolerance_deg
        })
        .filter(|&k| {
            mount_height_m
                .is_none_or(|h| (depth_below(k) - h).abs() <= config.ground_height_tolerance_m)
        })
        .collect();
    let lowest = family
        .iter()
        .copied()
        .filter(|&k| {
            planes[k].inliers >= config.ground_min_pixels
                && planes[k].quality.area_m2 >= config.ground_min_area_m2
        })
        .max_by(|&a, &b| depth_below(a).total_cmp(&depth_below(b)).then(b.cmp(&a)));
    let Some(g) = lowest else {
        return mounted.then_some(Ground::Mount);
    };
    let mut members = vec![g];
    let mut rest = family;
    rest.retain(|&k| k != g);
    // The connected level of the ground: members join while they are
    // coplanar with one that joined already.
    while let Some(pos) = rest.iter().position(|&k| {
        members
            .iter()
            .any(|&m| coplanar(&planes[k], &planes[m], config))
    }) {
        members.push(rest.swap_remove(pos));
    }
    Some(Ground::Planes(members))
}

/// Each plane's centroid within `coplanar_tolerance_m` of the other plane.
fn coplanar(a: &PlaneSummary, b: &PlaneSummary, config: &SelectionConfig) -> bool {
    let tol = config.coplanar_tolerance_m;
    a.plane.signed_distance(&b.centroid).abs() <= tol
        && b.plane.signed_distance(&a.centroid).abs() <= tol
}
