//! The simulated depth camera: its pose in the world and the ray through
//! each pixel.
//!
//! World frame: x right, y forward, z up. Camera frame: x right, y down,
//! z forward (the recording format's). With pitch `p` and roll `r` the
//! camera's axes in world coordinates are
//!
//! ```text
//! z_cam = (0, cos p, sin p)                       optical axis, p < 0 looks down
//! y_cam = -sin r * x0 + cos r * y0,  x0 = (1, 0, 0),  y0 = (0, sin p, -cos p)
//! x_cam =  cos r * x0 + sin r * y0
//! ```
//!
//! so the world's up vector seen from the camera is
//! `(-sin r cos p, -cos r cos p, sin p)`, exactly `Mount::up_vector`.

use nalgebra::{Matrix3, Rotation3};

use crate::geometry::{Pos3, Ray, Vec3};
use crate::scene::CameraModel;

/// Where the camera is and how it is turned, in world coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraPose {
    /// Optical centre, world coordinates, metres.
    pub position: Pos3,
    /// Rotation from camera to world coordinates (its columns are the
    /// camera's x, y, z axes in the world).
    pub rotation: Matrix3<f64>,
}

impl CameraPose {
    /// The camera `height_m` above the ground at forward position
    /// `forward_m`, turned by pitch and roll as in `[mount]` and by
    /// `yaw_deg` about the vertical (positive turns left).
    pub fn new(height_m: f64, pitch_deg: f64, roll_deg: f64, yaw_deg: f64, forward_m: f64) -> Self {
        let (sp, cp) = pitch_deg.to_radians().sin_cos();
        let (sr, cr) = roll_deg.to_radians().sin_cos();
        let x0 = Vec3::new(1.0, 0.0, 0.0);
        let y0 = Vec3::new(0.0, sp, -cp);
        let z_cam = Vec3::new(0.0, cp, sp);
        let x_cam = x0 * cr + y0 * sr;
        let y_cam = -x0 * sr + y0 * cr;
        let tilt = Matrix3::from_columns(&[x_cam, y_cam, z_cam]);
        let yaw = Rotation3::from_axis_angle(&Vec3::z_axis(), yaw_deg.to_radians());
        Self {
            position: Pos3::new(0.0, forward_m, height_m),
            rotation: yaw.matrix() * tilt,
        }
    }

    /// The world's up direction in camera coordinates.
    pub fn up_in_camera(&self) -> Vec3 {
        self.rotation.transpose() * Vec3::z()
    }
}

/// A posed pinhole camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub model: CameraModel,
    pub pose: CameraPose,
}

impl Camera {
    /// The world ray through image position (u, v) (pixel centres at
    /// integer coordinates). Its direction is `(x/z, y/z, 1)` in camera
    /// coordinates, so the ray parameter of a hit is its depth along the
    /// optical axis.
    pub fn ray(&self, u: f64, v: f64) -> Ray {
        let m = &self.model;
        let d_cam = Vec3::new((u - m.cx) / m.fx, (v - m.cy) / m.fy, 1.0);
        Ray {
            origin: self.pose.position,
            direction: self.pose.rotation * d_cam,
        }
    }

    /// Camera coordinates of a world point.
    pub fn to_camera(&self, p: &Pos3) -> Vec3 {
        self.pose.rotation.transpose() * (p - self.pose.position)
    }
}

#[cfg(test)]
mod tests {
    use slope_ipc_types::Mount;

    use super::*;

    #[test]
    fn up_vector_matches_mount_convention() {
        for (pitch, roll) in [
            (-20.0, 0.0),
            (-35.0, 5.0),
            (10.0, -12.0),
            (0.0, 0.0),
            (-76.0, 3.9),
        ] {
            let pose = CameraPose::new(0.5, pitch, roll, 0.0, 0.0);
            let up = pose.up_in_camera();
            let expected = Mount {
                height_m: 0.5,
                pitch_deg: pitch,
                roll_deg: roll,
            }
            .up_vector()
            .expect("pitch known");
            for k in 0..3 {
                assert!(
                    (up[k] - expected[k]).abs() < 1e-12,
                    "{pitch} {roll}: {up:?} vs {expected:?}"
                );
            }
            // Yaw about the vertical never changes the up vector.
            let yawed = CameraPose::new(0.5, pitch, roll, 17.0, 0.0).up_in_camera();
            assert!((yawed - up).norm() < 1e-12);
        }
    }

    #[test]
    fn rotation_is_proper() {
        let r = CameraPose::new(0.5, -23.0, 7.0, 4.0, 0.0).rotation;
        assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-12);
        assert!((r.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn looking_down_the_centre_ray_hits_ground_at_height_over_sine() {
        let camera = Camera {
            model: CameraModel::KINECT2,
            pose: CameraPose::new(0.5, -30.0, 0.0, 0.0, 0.0),
        };
        let ray = camera.ray(camera.model.cx, camera.model.cy);
        // Depth along the optical axis to the ground: t with z = 0.
        let t = -ray.origin.z / ray.direction.z;
        assert!((t - 0.5 / 30f64.to_radians().sin()).abs() < 1e-12);
        // Positive roll dips the image's right side: a pixel right of the
        // centre looks lower than one on the left.
        let rolled = Camera {
            model: CameraModel::KINECT2,
            pose: CameraPose::new(0.5, 0.0, 10.0, 0.0, 0.0),
        };
        let right = rolled.ray(500.0, rolled.model.cy).direction;
        let left = rolled.ray(10.0, rolled.model.cy).direction;
        assert!(right.z < 0.0 && left.z > 0.0);
        // Round trip world -> camera of a ray point.
        let p = ray.at(2.0);
        let c = camera.to_camera(&p);
        assert!((c - Vec3::new(0.0, 0.0, 2.0)).norm() < 1e-12);
    }
}
