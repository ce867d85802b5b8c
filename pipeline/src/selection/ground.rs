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
    let level = level_candidates(planes, reference, mounted, config);
    let Some(anchor) = family_anchor(planes, &level, reference, mounted) else {
        return mounted.then_some(Ground::Mount);
    };
    let up = planes[anchor].plane.normal;
    let family = ground_family(planes, level, &up, mount_height_m, config);
    let Some(g) = lowest_member(planes, &family, &up, config) else {
        return mounted.then_some(Ground::Mount);
    };
    Some(Ground::Planes(ground_segments(planes, g, family, config)))
}

/// Step 1: the flat planes within the tilt allowed (mount or no mount) of
/// the reference up, in index order.
fn level_candidates(
    planes: &[PlaneSummary],
    reference: &Vector3<f64>,
    mounted: bool,
    config: &SelectionConfig,
) -> Vec<usize> {
    let max_tilt = if mounted {
        config.ground_max_tilt_deg
    } else {
        config.unmounted_ground_max_tilt_deg
    };
    (0..planes.len())
        .filter(|&k| is_flat(&planes[k], config) && tilt_deg(&planes[k], reference) <= max_tilt)
        .collect()
}

/// Step 2, the plane that sets the ground family's up: with a mount the
/// level plane nearest the reference up, without one the level plane with
/// the most pixels in the bottom third of the image (ties: lowest index).
fn family_anchor(
    planes: &[PlaneSummary],
    level: &[usize],
    reference: &Vector3<f64>,
    mounted: bool,
) -> Option<usize> {
    let tilt = |k: usize| tilt_deg(&planes[k], reference);
    if mounted {
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
    }
}

/// Steps 2-3: the level planes parallel to `up` and, with a known mount
/// height, at that height below the camera.
fn ground_family(
    planes: &[PlaneSummary],
    level: Vec<usize>,
    up: &Vector3<f64>,
    mount_height_m: Option<f64>,
    config: &SelectionConfig,
) -> Vec<usize> {
    level
        .into_iter()
        .filter(|&k| {
            angle_between_deg(&planes[k].plane.normal, up) <= config.parallel_tolerance_deg
        })
        .filter(|&k| {
            mount_height_m.is_none_or(|h| {
                (depth_below(&planes[k], up) - h).abs() <= config.ground_height_tolerance_m
            })
        })
        .collect()
}

/// Step 4: the family member large enough to be the ground whose centroid
/// lies farthest below the camera along `up` (ties: lowest index).
fn lowest_member(
    planes: &[PlaneSummary],
    family: &[usize],
    up: &Vector3<f64>,
    config: &SelectionConfig,
) -> Option<usize> {
    let depth = |k: usize| depth_below(&planes[k], up);
    family
        .iter()
        .copied()
        .filter(|&k| {
            planes[k].inliers >= config.ground_min_pixels
                && planes[k].quality.area_m2 >= config.ground_min_area_m2
        })
        .max_by(|&a, &b| depth(a).total_cmp(&depth(b)).then(b.cmp(&a)))
}

/// Step 5, the connected level of the ground `g`: family members join
/// while they are coplanar with one that joined already; `g` first.
fn ground_segments(
    planes: &[PlaneSummary],
    g: usize,
    family: Vec<usize>,
    config: &SelectionConfig,
) -> Vec<usize> {
    let mut members = vec![g];
    let mut rest = family;
    rest.retain(|&k| k != g);
    while let Some(pos) = rest.iter().position(|&k| {
        members
            .iter()
            .any(|&m| coplanar(&planes[k], &planes[m], config))
    }) {
        members.push(rest.swap_remove(pos));
    }
    members
}

/// Angle between a plane's normal and the reference up, degrees.
fn tilt_deg(plane: &PlaneSummary, reference: &Vector3<f64>) -> f64 {
    angle_between_deg(&plane.plane.normal, reference)
}

/// Height of a plane's centroid below the camera along `up`, metres.
fn depth_below(plane: &PlaneSummary, up: &Vector3<f64>) -> f64 {
    -up.dot(&plane.centroid)
}

/// Each plane's centroid within `coplanar_tolerance_m` of the other plane.
fn coplanar(a: &PlaneSummary, b: &PlaneSummary, config: &SelectionConfig) -> bool {
    let tol = config.coplanar_tolerance_m;
    a.plane.signed_distance(&b.centroid).abs() <= tol
        && b.plane.signed_distance(&a.centroid).abs() <= tol
}
