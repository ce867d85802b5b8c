//! The ground: the support surface the robot stands on.
//!
//! 1. **Level candidates** are flat planes (see [`super::is_flat`], or
//!    flat at the sensor's noise level: [`super::is_flat_for_ground`]) whose
//!    normal is within `ground_max_tilt_deg` (mount) or
//!    `unmounted_ground_max_tilt_deg` (no mount) of the reference up.
//! 2. **The ground's family**: with a mount, the candidate whose normal is
//!    closest to the mount's up; without one, the nearest floor: the
//!    candidate large enough to be the ground (step 4's size) whose inliers
//!    reach lowest in the image ([`nearest_floor`]), the surface that
//!    continues under the robot, however large a ramp beyond it. Every
//!    candidate parallel to it (`parallel_tolerance_deg`) is in its family:
//!    floor, treads, table and bed tops; a ramp is not.
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
//!    centroid within `coplanar_tolerance_m` of the other's plane, their
//!    normals within the sensor's floor bend: a gentle ramp is not) are
//!    segments too, and the ground is measured on all of them together: the
//!    same floor whichever piece RANSAC found first. (Pieces of the floor
//!    that the sensor's range bias bends further join the ground's surface
//!    later, by their heights: `floor.rs`.)

use nalgebra::Vector3;

use super::SelectionConfig;
use super::{is_flat_for_ground, PlaneSummary};
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
    let Some(anchor) = family_anchor(planes, &level, reference, mounted, config) else {
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
        .filter(|&k| {
            is_flat_for_ground(&planes[k], config) && tilt_deg(&planes[k], reference) <= max_tilt
        })
        .collect()
}

/// The nearest floor among the `level` candidates: among those large
/// enough to be the ground whose inliers reach within
/// [`NEAREST_ROWS_SHARE`] of the image's height of the lowest row any of
/// them reaches ([`PlaneSummary::lowest_row`]), the one with the most
/// pixels in the image's lowest rows ([`super::BOTTOM_BAND_SHARE`]), then
/// in its bottom third (ties: the lowest index). A narrow patch of floor
/// between a person's legs reaches as low as the floor around it; a ramp
/// ahead starts higher in the image than the floor before it, however
/// large it is, and where only a strip of floor shows before it, the strip
/// fills the lowest rows.
pub fn nearest_floor(
    planes: &[PlaneSummary],
    level: &[usize],
    config: &SelectionConfig,
) -> Option<usize> {
    let large: Vec<usize> = level
        .iter()
        .copied()
        .filter(|&k| large_enough(&planes[k], config))
        .collect();
    let lowest = large
        .iter()
        .map(|&k| planes[k].lowest_row)
        .max_by(f64::total_cmp)?;
    large
        .into_iter()
        .filter(|&k| planes[k].lowest_row + NEAREST_ROWS_SHARE >= lowest)
        .max_by(|&a, &b| {
            let (pa, pb) = (&planes[a], &planes[b]);
            pa.bottom_band_pixels
                .cmp(&pb.bottom_band_pixels)
                .then(pa.bottom_pixels.cmp(&pb.bottom_pixels))
                .then(b.cmp(&a))
        })
}

/// Level candidates whose inliers reach this share of the image's height
/// from the lowest row reached are all "the nearest floor".
pub const NEAREST_ROWS_SHARE: f64 = 0.1;

/// Step 2, the plane that sets the ground family's up: with a mount the
/// level plane nearest the reference up, without one the nearest floor
/// ([`nearest_floor`]).
fn family_anchor(
    planes: &[PlaneSummary],
    level: &[usize],
    reference: &Vector3<f64>,
    mounted: bool,
    config: &SelectionConfig,
) -> Option<usize> {
    let tilt = |k: usize| tilt_deg(&planes[k], reference);
    if mounted {
        level
            .iter()
            .copied()
            .min_by(|&a, &b| tilt(a).total_cmp(&tilt(b)))
    } else {
        nearest_floor(planes, level, config)
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
        .filter(|&k| large_enough(&planes[k], config))
        .max_by(|&a, &b| depth(a).total_cmp(&depth(b)).then(b.cmp(&a)))
}

/// At least `ground_min_pixels` pixels and `ground_min_area_m2` of surface.
fn large_enough(plane: &PlaneSummary, config: &SelectionConfig) -> bool {
    plane.inliers >= config.ground_min_pixels && plane.quality.area_m2 >= config.ground_min_area_m2
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

/// Each plane's centroid within `coplanar_tolerance_m` of the other plane,
/// and their normals within the sensor's floor bend at the deeper
/// centroid (a gentle ramp's near half is close to the floor's plane, but
/// tilted beyond the bend).
fn coplanar(a: &PlaneSummary, b: &PlaneSummary, config: &SelectionConfig) -> bool {
    let tol = config.coplanar_tolerance_m;
    let bend = config
        .noise_model
        .unwrap_or_default()
        .floor_bend_deg(a.centroid.z.max(b.centroid.z));
    a.plane.signed_distance(&b.centroid).abs() <= tol
        && b.plane.signed_distance(&a.centroid).abs() <= tol
        && angle_between_deg(&a.plane.normal, &b.plane.normal) <= bend
}
