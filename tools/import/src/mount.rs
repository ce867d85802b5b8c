//! The camera mount from a bag's `/tf_static`: the static transforms form a
//! tree (each child frame has one parent); the camera's pose in the base
//! frame is the product of the transforms from the base frame down to the
//! camera's frame (the depth image's `frame_id`), which
//! [`slope_tools::mount_transform::transform_to_mount`] turns into height,
//! pitch and roll.

use std::collections::HashMap;

use nalgebra::Isometry3;
use slope_sensor::recording::MountInfo;
use slope_tools::mount_transform::{isometry, transform_to_mount};
use slope_tools::ros2_messages::TfMessage;

/// The static transforms seen so far: child frame → (parent, pose of the
/// child in the parent).
#[derive(Debug, Default)]
pub struct StaticTransforms {
    parents: HashMap<String, (String, Isometry3<f64>)>,
}

/// A frame name without a leading `/` (ROS 1 bags often have one).
fn frame(name: &str) -> &str {
    name.trim_start_matches('/')
}

impl StaticTransforms {
    /// Adds the transforms of a `/tf_static` message (a transform that is
    /// no rotation is skipped with a warning).
    pub fn add(&mut self, message: &TfMessage) {
        for t in &message.transforms {
            match isometry(&t.transform) {
                Some(pose) => {
                    self.parents.insert(
                        frame(&t.child_frame_id).to_string(),
                        (frame(&t.header.frame_id).to_string(), pose),
                    );
                }
                None => tracing::warn!(
                    parent = t.header.frame_id,
                    child = t.child_frame_id,
                    "a static transform without a valid rotation; ignored"
                ),
            }
        }
    }

    pub fn is_empty(&self) -> bool {
        self.parents.is_empty()
    }

    /// The pose of `camera` in `base`, when the transforms link them.
    pub fn pose(&self, base: &str, camera: &str) -> Option<Isometry3<f64>> {
        let (base, mut at) = (frame(base), frame(camera));
        let mut pose = Isometry3::identity();
        // A tree of n frames has paths of at most n steps; more is a cycle.
        for _ in 0..=self.parents.len() {
            if at == base {
                return Some(pose);
            }
            let (parent, child_in_parent) = self.parents.get(at)?;
            pose = child_in_parent * pose;
            at = parent;
        }
        None
    }

    /// The mount of `camera` on `base`, when the transforms link them.
    pub fn mount(&self, base: &str, camera: &str) -> Option<MountInfo> {
        self.pose(base, camera)
            .map(|pose| transform_to_mount(&pose))
    }

    /// The frames known, for a message when the base is not among them.
    pub fn frames(&self) -> Vec<String> {
        let mut frames: Vec<String> = self
            .parents
            .iter()
            .flat_map(|(child, (parent, _))| [child.clone(), parent.clone()])
            .collect();
        frames.sort();
        frames.dedup();
        frames
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use slope_tools::mount_transform::mount_to_transform;
    use slope_tools::ros2_messages::{Header, Quaternion, Transform, TransformStamped, Vector3};

    fn stamped(parent: &str, child: &str, transform: Transform) -> TransformStamped {
        TransformStamped {
            header: Header {
                frame_id: parent.to_string(),
                ..Header::default()
            },
            child_frame_id: child.to_string(),
            transform,
        }
    }

    #[test]
    fn a_chain_of_transforms_gives_the_cameras_mount() {
        // base_link -> kinect2_link (the mount), then kinect2_link ->
        // kinect2_ir_optical_frame (no offset), with ROS 1's leading '/'.
        let mount = MountInfo {
            height_m: Some(0.3),
            pitch_deg: Some(-20.0),
            roll_deg: Some(1.5),
        };
        let link = mount_to_transform(&mount).unwrap();
        let lift = Transform {
            translation: Vector3 {
                x: 0.0,
                y: 0.0,
                z: 0.0,
            },
            rotation: Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 1.0,
            },
        };
        let mut transforms = StaticTransforms::default();
        transforms.add(&TfMessage {
            transforms: vec![
                stamped("/base_link", "kinect2_link", link),
                stamped("kinect2_link", "kinect2_ir_optical_frame", lift),
            ],
        });
        let got = transforms
            .mount("base_link", "/kinect2_ir_optical_frame")
            .unwrap();
        assert_eq!(got, mount);
        assert!(transforms
            .mount("odom", "kinect2_ir_optical_frame")
            .is_none());
        assert_eq!(
            transforms.frames(),
            ["base_link", "kinect2_ir_optical_frame", "kinect2_link"]
        );
    }

    #[test]
    fn a_cycle_ends() {
        let identity = Transform {
            rotation: Quaternion {
                w: 1.0,
                ..Quaternion::default()
            },
            ..Transform::default()
        };
        let mut transforms = StaticTransforms::default();
        transforms.add(&TfMessage {
            transforms: vec![stamped("a", "b", identity), stamped("b", "a", identity)],
        });
        assert!(transforms.pose("base_link", "a").is_none());
    }
}
