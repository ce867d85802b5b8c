//! `slope-ros2`: a native ROS 2 node (DDS through `ros2-client` and
//! RustDDS, no ROS installation) that publishes the estimate, the
//! surfaces, rviz markers and `/diagnostics` of one service prefix.
//!
//! The mapping from our messages to ROS 2's is always built (pure
//! functions, tested without DDS); the node itself is behind the `ros2`
//! feature:
//! - [`topics`]: the ROS 2 topic and type names, the node's default names;
//! - [`diagnostics`]: `/diagnostics` of a health report, the level rule;
//! - [`markers`]: the rviz2 markers of a frame;
//! - [`surfaces_msg`]: `slope_msgs/msg/Surfaces` of a `Surfaces`;
//! - [`discovery`]: ROS 2's discovery settings (`ROS_DOMAIN_ID`,
//!   `ROS_AUTOMATIC_DISCOVERY_RANGE`, `ROS_LOCALHOST_ONLY`) read and checked;
//! - [`ros_args`]: ROS 2's `--ros-args -p ... -r ...` as our flags;
//! - `node` (feature `ros2`): the flags, the DDS participant and its
//!   publishers, the loop from iceoryx2 to DDS.

pub mod diagnostics;
pub mod discovery;
pub mod markers;
pub mod ros_args;
pub mod surfaces_msg;
pub mod topics;

#[cfg(feature = "ros2")]
pub mod node;
