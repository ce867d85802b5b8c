//! How far ahead the ground was seen: the largest forward distance of a
//! ground inlier from the camera, measured along the robot's forward
//! direction in the ground plane.
//!
//! A slope down past the floor's edge gives the camera no readings (the
//! surface falls away faster than the rays), so the estimate there says
//! `no_inclined_plane`, as for a flat floor. What tells the two apart is
//! where the floor ends: on a flat floor it reaches the sensor's range
//! (4-5 m for a Kinect v2 looking down), before a drop-off it stops at the
//! edge. The ground's inliers are RANSAC-labelled pixels of its connected
//! regions, so a stray reading far away is not among them and the maximum
//! needs no trimming; a point on the ground cannot lie beyond its edge by
//! more than its depth noise (millimetres), so the figure does not
//! overstate how far the floor goes.

use nalgebra::Vector3;
use slope_ipc_types::CloudPoint;

/// The largest forward distance of the `inliers` (pixel indices into
/// `points`) from the camera, metres: the largest `p . forward`, where
/// `forward` is the robot's forward direction (unit, perpendicular to the
/// ground's normal), which is the distance ahead of the point's foot on the
/// ground from the camera's. NaN without an inlier ahead of the camera.
pub fn ground_seen_to_m(points: &[CloudPoint], inliers: &[u32], forward: &Vector3<f64>) -> f64 {
    let (fx, fy, fz) = (forward.x as f32, forward.y as f32, forward.z as f32);
    let mut farthest = f32::NEG_INFINITY;
    for &i in inliers {
        if let Some(p) = points.get(i as usize) {
            let ahead = p.x_m * fx + p.y_m * fy + p.z_m * fz;
            // A NaN (no reading: never an inlier) leaves `farthest` alone.
            if ahead > farthest {
                farthest = ahead;
            }
        }
    }
    if farthest > 0.0 {
        f64::from(farthest)
    } else {
        f64::NAN
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(x: f32, y: f32, z: f32) -> CloudPoint {
        CloudPoint {
            x_m: x,
            y_m: y,
            z_m: z,
            rgb: 0,
        }
    }

    #[test]
    fn the_farthest_inlier_along_forward_counts_not_the_farthest_point() {
        // Camera frame (x right, y down, z ahead), level camera: forward is z.
        let points = [
            point(0.0, 0.5, 1.0),
            point(3.0, 0.5, 2.0), // far to the side, 2 m ahead
            point(0.0, 0.5, 2.5),
            point(0.0, 0.5, 9.0), // not an inlier
            point(f32::NAN, f32::NAN, f32::NAN),
        ];
        let forward = Vector3::z();
        assert_eq!(ground_seen_to_m(&points, &[0, 1, 2, 4], &forward), 2.5);
        assert_eq!(ground_seen_to_m(&points, &[0, 1], &forward), 2.0);
        // A pitched camera: forward has a y part.
        let pitch = 20f64.to_radians();
        let forward = Vector3::new(0.0, -pitch.sin(), pitch.cos());
        let expected = (-0.5 * pitch.sin() + 2.5 * pitch.cos()) as f32;
        assert_eq!(
            ground_seen_to_m(&points, &[0, 2], &forward),
            f64::from(expected)
        );
    }

    #[test]
    fn no_inlier_ahead_is_nan() {
        let points = [point(0.0, 0.5, -1.0)];
        let forward = Vector3::z();
        assert!(ground_seen_to_m(&points, &[], &forward).is_nan());
        assert!(ground_seen_to_m(&points, &[0], &forward).is_nan());
        // An index past the cloud is skipped, not a panic.
        assert!(ground_seen_to_m(&points, &[7], &forward).is_nan());
    }
}
