//! The camera mount as a ROS transform and back: a base frame (x forward,
//! y left, z up: REP 103) to the camera's optical frame (x right, y down,
//! z forward), with the optical centre `height_m` above the base frame's
//! origin, pitched by `pitch_deg` (negative looks down) and rolled by
//! `roll_deg` about the optical axis (positive dips the image's right
//! side), as the recording format defines them: the up vector in the
//! camera frame is `[-sin r cos p, -cos r cos p, sin p]`
//! ([`slope_ipc_types::Mount::up_vector`]).

use nalgebra::{
    Isometry3, Matrix3, Quaternion as NaQuaternion, Rotation3, Translation3, UnitQuaternion,
    Vector3 as NaVector3,
};
use slope_sensor::recording::MountInfo;

use crate::ros2_messages::{Quaternion, Transform, Vector3};

/// The optical frame's axes in the base frame at zero pitch and roll:
/// x right = -y, y down = -z, z forward = x (the columns).
fn optical_alignment() -> Rotation3<f64> {
    Rotation3::from_matrix_unchecked(Matrix3::new(
        0.0, 0.0, 1.0, //
        -1.0, 0.0, 0.0, //
        0.0, -1.0, 0.0,
    ))
}

/// The pose of the camera's optical frame in the base frame for a mount
/// with `height_m` and `pitch_deg` (and `roll_deg`, 0 when unknown);
/// `None` when the height or the pitch is unknown.
pub fn mount_to_transform(mount: &MountInfo) -> Option<Transform> {
    let height = mount.height_m?;
    let pitch = mount.pitch_deg?.to_radians();
    let roll = mount.roll_deg.unwrap_or(0.0).to_radians();
    // Pitch about the base's y axis (positive turns forward down, so a
    // negative pitch_deg), then roll about the forward axis.
    let body = Rotation3::from_axis_angle(&NaVector3::y_axis(), -pitch)
        * Rotation3::from_axis_angle(&NaVector3::x_axis(), roll);
    let rotation = UnitQuaternion::from_rotation_matrix(&(body * optical_alignment()));
    Some(Transform {
        translation: Vector3 {
            x: 0.0,
            y: 0.0,
            z: height,
        },
        rotation: Quaternion {
            x: rotation.i,
            y: rotation.j,
            z: rotation.k,
            w: rotation.w,
        },
    })
}

/// A transform as an isometry; `None` for a rotation that is no
/// quaternion (all zero, or not finite).
pub fn isometry(transform: &Transform) -> Option<Isometry3<f64>> {
    let q = transform.rotation;
    let t = transform.translation;
    let values = [q.x, q.y, q.z, q.w, t.x, t.y, t.z];
    if values.iter().any(|v| !v.is_finite()) || (q.x, q.y, q.z, q.w) == (0.0, 0.0, 0.0, 0.0) {
        return None;
    }
    let rotation = UnitQuaternion::from_quaternion(NaQuaternion::new(q.w, q.x, q.y, q.z));
    Some(Isometry3::from_parts(
        Translation3::new(t.x, t.y, t.z),
        rotation,
    ))
}

/// The mount of a camera whose optical frame has the pose `camera_in_base`
/// in a base frame on the ground: height (the optical centre above the
/// base frame's origin), pitch and roll, rounded to 1e-9 (m, degrees) so
/// that the float noise of a quaternion does not make 0.5 m into
/// 0.49999999999999994. A yaw is ignored. Each value is checked by the
/// caller against [`slope_sensor::recording::MountRange`].
pub fn transform_to_mount(camera_in_base: &Isometry3<f64>) -> MountInfo {
    let up = camera_in_base.rotation.inverse() * NaVector3::z();
    let round = |v: f64| (v * 1e9).round() / 1e9;
    MountInfo {
        height_m: Some(round(camera_in_base.translation.z)),
        pitch_deg: Some(round(up.z.clamp(-1.0, 1.0).asin().to_degrees())),
        roll_deg: Some(round((-up.x).atan2(-up.y).to_degrees()) + 0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use slope_ipc_types::Mount;

    #[test]
    fn a_mount_survives_the_transform_and_gives_the_recording_formats_up_vector() {
        for (height, pitch, roll) in [(0.5, -20.0, 0.0), (1.2, -45.5, 3.25), (0.3, 10.0, -170.0)] {
            let mount = MountInfo {
                height_m: Some(height),
                pitch_deg: Some(pitch),
                roll_deg: Some(roll),
            };
            let transform = mount_to_transform(&mount).unwrap();
            let pose = isometry(&transform).unwrap();
            let back = transform_to_mount(&pose);
            assert_eq!(back, mount);
            // The base's up in the camera frame is the recording format's.
            let up = pose.rotation.inverse() * NaVector3::z();
            let expected = Mount {
                height_m: height,
                pitch_deg: pitch,
                roll_deg: roll,
            }
            .up_vector()
            .unwrap();
            for (a, b) in up.iter().zip(expected) {
                assert!((a - b).abs() < 1e-12, "{up:?} {expected:?}");
            }
        }
    }

    #[test]
    fn a_level_camera_looks_along_the_base_frames_x_axis() {
        let mount = MountInfo {
            height_m: Some(1.0),
            pitch_deg: Some(0.0),
            roll_deg: None,
        };
        let pose = isometry(&mount_to_transform(&mount).unwrap()).unwrap();
        let forward = pose.rotation * NaVector3::z();
        let right = pose.rotation * NaVector3::x();
        assert!((forward - NaVector3::x()).norm() < 1e-12);
        assert!((right + NaVector3::y()).norm() < 1e-12);
    }

    #[test]
    fn an_unknown_height_or_pitch_gives_no_transform_and_a_zero_quaternion_no_pose() {
        assert!(mount_to_transform(&MountInfo::default()).is_none());
        assert!(isometry(&Transform::default()).is_none());
    }
}
