//! [`GroundFrame`]: the robot's frame on the ground, in camera coordinates.
//!
//! Up is the ground's normal, forward the optical axis projected onto the
//! ground ([`super::forward_direction`]), right completes them (`forward x
//! up`: the camera's +x for an upright camera). Heights are measured from
//! the ground plane (the lowest ground segment's plane, or the mount's
//! plane when no ground was seen); forward and lateral positions from the
//! camera's optical centre, which projects onto the ground without
//! changing them (both axes lie in the ground plane).

use nalgebra::Vector3;

use super::forward_direction;
use crate::plane_fit::Plane;

/// The ground frame of one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundFrame {
    /// The ground's up direction (unit).
    pub up: Vector3<f64>,
    /// The robot's forward direction (unit, perpendicular to `up`).
    pub forward: Vector3<f64>,
    /// The robot's right (unit, `forward x up`).
    pub right: Vector3<f64>,
    /// The plane heights are measured from: normal `up`, `d` the camera's
    /// height above it.
    pub ground: Plane,
}

impl GroundFrame {
    /// The frame over a ground plane whose unit normal points up (towards
    /// the camera, as every segmented plane's does).
    pub fn over(ground: Plane) -> Self {
        let up = ground.normal;
        let forward = forward_direction(&up);
        Self {
            up,
            forward,
            right: forward.cross(&up),
            ground,
        }
    }

    /// The frame over the mount's plane: `up` the mount's up vector (unit),
    /// the ground `height_m` below the camera.
    pub fn of_mount(up: Vector3<f64>, height_m: f64) -> Self {
        Self::over(Plane {
            normal: up,
            d: height_m,
        })
    }

    /// Height of a camera-frame point above the ground, metres.
    pub fn height(&self, p: &Vector3<f64>) -> f64 {
        self.ground.signed_distance(p)
    }

    /// Distance of a point ahead of the camera along forward, metres.
    pub fn ahead(&self, p: &Vector3<f64>) -> f64 {
        self.forward.dot(p)
    }

    /// Lateral position of a point, metres, positive to the right.
    pub fn lateral(&self, p: &Vector3<f64>) -> f64 {
        self.right.dot(p)
    }

    /// Angle between `normal` and up, degrees (0 level, 90 vertical, 180
    /// facing down).
    pub fn tilt_deg(&self, normal: &Vector3<f64>) -> f64 {
        crate::cloud::angle_between_deg(normal, &self.up)
    }

    /// Heading of the uphill direction of a surface with `normal`, degrees
    /// from forward, positive to the left, in (-180, 180]; NaN when the
    /// normal has no horizontal part (a level surface).
    pub fn heading_deg(&self, normal: &Vector3<f64>) -> f64 {
        // A tilted surface's normal leans towards its downhill side.
        let uphill = -(normal - self.up * normal.dot(&self.up));
        if uphill.norm() < 1e-9 {
            return f64::NAN;
        }
        let left = -self.right;
        let heading = uphill
            .dot(&left)
            .atan2(uphill.dot(&self.forward))
            .to_degrees();
        if heading <= -180.0 {
            180.0
        } else {
            heading
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An upright camera 0.5 m above a level floor: up is -y, forward z,
    /// right x, and a ramp rising ahead, to the left or falling ahead has
    /// the headings the message documents.
    #[test]
    fn upright_camera_axes_and_headings() {
        let f = GroundFrame::of_mount(-Vector3::y(), 0.5);
        assert!((f.forward - Vector3::z()).norm() < 1e-12);
        assert!((f.right - Vector3::x()).norm() < 1e-12);
        // The floor point 0.5 m below the camera is at height 0.
        assert!(f.height(&Vector3::new(0.3, 0.5, 2.0)).abs() < 1e-12);
        assert!((f.height(&Vector3::new(0.0, 0.2, 2.0)) - 0.3).abs() < 1e-12);
        let t = 16f64.to_radians();
        // Rises ahead: the normal points up and back (towards the camera).
        let rises_ahead = Vector3::new(0.0, -t.cos(), -t.sin());
        assert!(f.heading_deg(&rises_ahead).abs() < 1e-9);
        assert!((f.tilt_deg(&rises_ahead) - 16.0).abs() < 1e-9);
        // Falls ahead: the normal points up and forward.
        let falls_ahead = Vector3::new(0.0, -t.cos(), t.sin());
        assert!((f.heading_deg(&falls_ahead) - 180.0).abs() < 1e-9);
        // Rises to the left (-x): the normal leans right (+x).
        let rises_left = Vector3::new(t.sin(), -t.cos(), 0.0);
        assert!((f.heading_deg(&rises_left) - 90.0).abs() < 1e-9);
        assert!(f.heading_deg(&-Vector3::y()).is_nan());
    }
}
