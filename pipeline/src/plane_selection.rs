//! Which segmented plane is the ground and which the inclined plane; the
//! slope's sign and the distance to the inclined plane.
//!
//! Rules (every plane's normal points towards the camera):
//!
//! 1. **Reference up.** With a mount (known pitch), the mount's up vector;
//!    without one, the camera's -y axis (an upright camera).
//! 2. **Ground.** Candidates are planes within `ground_max_tilt_deg` (mount)
//!    or `unmounted_ground_max_tilt_deg` (no mount) of the reference up.
//!    With a mount the ground is the candidate whose normal is closest to up;
//!    without one, the candidate with the most inliers in the bottom third
//!    of the image (the floor right in front of the robot). Real scenes hold
//!    many parallel planes (floor, treads, table tops): among candidates
//!    within `parallel_tolerance_deg` of that choice the best-supported one
//!    (most inliers) is taken, since parallel planes give the same angle and
//!    the largest gives the best normal. No candidate and a mount: the ground
//!    normal is the mount's up vector (`ground_from_mount`). No candidate and
//!    no mount: `NoGround`.
//! 3. **Forward.** The optical axis projected onto the ground (perpendicular
//!    to the ground normal).
//! 4. **Inclined plane.** A plane other than the ground that differs from it
//!    by at least `min_slope_deg` (parallel planes are treads or tables, not
//!    slopes) and that faces along the forward axis: its normal's horizontal
//!    part is within `max_heading_deg` of forward or backward. A wall beside
//!    a ramp has a horizontal normal perpendicular to forward and is never
//!    taken. Among candidates with at least `min_relative_support` of the
//!    best-supported one's inliers, the nearest (smallest distance of its
//!    centroid along forward) is the one the robot drives onto or faces
//!    first. None: `NoInclinedPlane`.
//! 5. **Sign.** Uphill (positive) when the inclined plane's normal points
//!    back towards the robot (`n . forward < 0`, the surface rises away from
//!    the camera), downhill (negative) when it points forward.
//! 6. **Distance.** Along the optical axis to the inclined plane,
//!    `-d / n_z`; NaN when the axis does not meet it in front of the camera.

use nalgebra::Vector3;
use slope_ipc_types::EstimateStatus;

use crate::cloud::angle_between_deg;
use crate::config::SelectionConfig;
use crate::plane_fit::Plane;

/// What selection needs to know about a segmented plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneSummary {
    /// Normal towards the camera and offset.
    pub plane: Plane,
    pub inliers: usize,
    /// Inliers in the bottom third of the image rows.
    pub bottom_inliers: usize,
    pub centroid: Vector3<f64>,
}

/// Where the ground normal comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GroundSource {
    /// The segmented plane with this index.
    Plane(usize),
    /// The mount's up vector (no ground plane visible).
    Mount,
}

/// The chosen pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Selection {
    pub ground: GroundSource,
    pub inclined: usize,
    /// Ground normal used (unit, up).
    pub up: Vector3<f64>,
    /// The robot's forward direction (unit, perpendicular to `up`).
    pub forward: Vector3<f64>,
}

/// Chooses ground and inclined plane. The error is the status to report.
pub fn select_planes(
    planes: &[PlaneSummary],
    mount_up: Option<Vector3<f64>>,
    config: &SelectionConfig,
) -> Result<Selection, EstimateStatus> {
    let mount_up = mount_up.and_then(|u| u.try_normalize(1e-12));
    let (reference, max_tilt) = match mount_up {
        Some(u) => (u, config.ground_max_tilt_deg),
        None => (-Vector3::y(), config.unmounted_ground_max_tilt_deg),
    };
    let candidates: Vec<usize> = (0..planes.len())
        .filter(|&k| angle_between_deg(&planes[k].plane.normal, &reference) <= max_tilt)
        .collect();
    let first = if mount_up.is_some() {
        candidates.iter().copied().min_by(|&a, &b| {
            angle_between_deg(&planes[a].plane.normal, &reference)
                .total_cmp(&angle_between_deg(&planes[b].plane.normal, &reference))
        })
    } else {
        candidates.iter().copied().max_by(|&a, &b| {
            planes[a]
                .bottom_inliers
                .cmp(&planes[b].bottom_inliers)
                .then(b.cmp(&a))
        })
    };
    let ground = match first {
        Some(g) => {
            let gn = planes[g].plane.normal;
            let best = candidates
                .iter()
                .copied()
                .filter(|&k| {
                    angle_between_deg(&planes[k].plane.normal, &gn) <= config.parallel_tolerance_deg
                })
                .max_by(|&a, &b| planes[a].inliers.cmp(&planes[b].inliers).then(b.cmp(&a)))
                .unwrap_or(g);
            GroundSource::Plane(best)
        }
        None if mount_up.is_some() => GroundSource::Mount,
        None => return Err(EstimateStatus::NoGround),
    };
    let up = match ground {
        GroundSource::Plane(g) => planes[g].plane.normal,
        GroundSource::Mount => reference,
    };
    let forward = forward_direction(&up);
    let cos_heading = config.max_heading_deg.to_radians().cos();
    let inclined: Vec<usize> = (0..planes.len())
        .filter(|&k| ground != GroundSource::Plane(k))
        .filter(|&k| {
            let n = planes[k].plane.normal;
            if angle_between_deg(&n, &up) < config.min_slope_deg {
                return false;
            }
            let horizontal = n - up * n.dot(&up);
            let h = horizontal.norm();
            h > 1e-9
                && horizontal.dot(&forward).abs() >= cos_heading * h
                && planes[k].centroid.dot(&forward) > 0.0
        })
        .collect();
    let support = inclined
        .iter()
        .map(|&k| planes[k].inliers)
        .max()
        .unwrap_or(0);
    let chosen = inclined
        .iter()
        .copied()
        .filter(|&k| planes[k].inliers as f64 >= config.min_relative_support * support as f64)
        .min_by(|&a, &b| {
            planes[a]
                .centroid
                .dot(&forward)
                .total_cmp(&planes[b].centroid.dot(&forward))
                .then(a.cmp(&b))
        })
        .ok_or(EstimateStatus::NoInclinedPlane)?;
    Ok(Selection {
        ground,
        inclined: chosen,
        up,
        forward,
    })
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::Scene;

    fn summary(scene: &Scene, k: usize, inliers: usize, bottom: usize) -> PlaneSummary {
        let s = &scene.surfaces[k];
        let n = scene.to_camera(&s.normal);
        let c = scene.to_camera(&(s.point - scene.camera_centre()));
        // Push the centroid into view along the surface's forward extent.
        let ahead = scene.to_camera(&Vector3::new(0.0, 1.0, 0.0));
        let centroid = c + ahead * 0.5;
        let plane = Plane::from_point_normal(&c, &n)
            .unwrap()
            .oriented_towards(&Vector3::zeros());
        PlaneSummary {
            plane,
            inliers,
            bottom_inliers: bottom,
            centroid,
        }
    }

    #[test]
    fn ramp_between_walls_is_measured_as_the_ramp() {
        for slope in [12.5, -12.5, 47.0] {
            let scene = Scene::ramp_between_walls(slope);
            // Walls get the most inliers: they must still not be chosen.
            let planes = vec![
                summary(&scene, 2, 9000, 100),
                summary(&scene, 0, 5000, 4000),
                summary(&scene, 3, 8000, 100),
                summary(&scene, 1, 3000, 0),
            ];
            let up = scene.mount().up_vector().map(Vector3::from);
            let sel = select_planes(&planes, up, &SelectionConfig::default()).unwrap();
            assert_eq!(sel.ground, GroundSource::Plane(1));
            assert_eq!(sel.inclined, 3);
            let angle = angle_between_deg(&planes[3].plane.normal, &sel.up);
            assert!((angle - slope.abs()).abs() < 1e-9);
            assert_eq!(
                slope_sign(&planes[3].plane.normal, &sel.forward),
                slope.signum()
            );
            // Same without a mount: the ground is at the bottom of the image.
            let sel = select_planes(&planes, None, &SelectionConfig::default()).unwrap();
            assert_eq!(sel.ground, GroundSource::Plane(1));
            assert_eq!(sel.inclined, 3);
        }
    }

    #[test]
    fn no_ground_uses_the_mount_and_no_mount_is_an_error() {
        let scene = Scene::ramp(30.0);
        let planes = vec![summary(&scene, 1, 3000, 0)];
        let up = scene.mount().up_vector().map(Vector3::from);
        let sel = select_planes(&planes, up, &SelectionConfig::default()).unwrap();
        assert_eq!(sel.ground, GroundSource::Mount);
        assert!((angle_between_deg(&planes[0].plane.normal, &sel.up) - 30.0).abs() < 1e-9);
        let wall = Scene::wall_facing(2.0);
        let planes = vec![summary(&wall, 0, 3000, 1000)];
        assert_eq!(
            select_planes(&planes, None, &SelectionConfig::default()),
            Err(EstimateStatus::NoGround)
        );
        let flat = Scene::ramp(0.0);
        let planes = vec![summary(&flat, 0, 3000, 1000), summary(&flat, 1, 2000, 0)];
        assert_eq!(
            select_planes(&planes, up, &SelectionConfig::default()),
            Err(EstimateStatus::NoInclinedPlane)
        );
    }

    #[test]
    fn distance_along_the_axis() {
        let plane =
            Plane::from_point_normal(&Vector3::new(0.0, 0.0, 3.0), &Vector3::new(0.0, -1.0, -1.0))
                .unwrap();
        assert!((axis_distance(&plane) - 3.0).abs() < 1e-12);
        let parallel =
            Plane::from_point_normal(&Vector3::new(0.0, 1.0, 0.0), &Vector3::y()).unwrap();
        assert!(axis_distance(&parallel).is_nan());
    }
}
