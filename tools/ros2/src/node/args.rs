//! The flags of `slope-ros2` ([`Ros2Args`]).

use std::path::PathBuf;

use clap::Parser;
use slope_tools::cli::CommonArgs;

use crate::discovery::domain_id_arg;
use crate::topics::{frame_id_arg, namespace_arg, node_name_arg};

#[derive(Debug, Parser)]
#[command(
    name = "slope-ros2",
    version,
    about = "Publish slope estimates, surfaces, rviz markers and diagnostics as a ROS 2 node",
    long_about = "A native ROS 2 node (DDS through RustDDS: no ROS installation needed) that \
subscribes to the estimate, surfaces and health topics of one service prefix on this host \
(iceoryx2) and publishes them to ROS 2 (<ns>: --namespace):

  <ns>/slope/estimate  slope_msgs/msg/SlopeEstimate (reliable, last 10, transient local)
  <ns>/slope/surfaces  slope_msgs/msg/Surfaces (reliable, last 10, transient local)
  <ns>/slope/markers   visualization_msgs/msg/MarkerArray (best effort, last 1)
  /diagnostics         diagnostic_msgs/msg/DiagnosticArray (reliable, last 10)
  /tf_static           tf2_msgs/msg/TFMessage (with --base-frame; transient local)

Header stamps are the frames' capture stamps, frame_id the camera's optical frame (--frame-id). \
Discovery follows ROS 2's settings: ROS_DOMAIN_ID (or --domain-id), \
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST or ROS_LOCALHOST_ONLY=1 to stay on this host, else every \
interface. The settings come from the flags, else from the config file's [ros2] section \
(--config, else /etc/slope/slope.toml if it exists). Stops cleanly on SIGINT or SIGTERM.",
    after_help = "Examples:
  slope-ros2                                   # /slope/estimate ... on ROS_DOMAIN_ID
  slope-ros2 --namespace /robot1 --domain-id 7 # /robot1/slope/estimate on domain 7
  slope-ros2 --base-frame base_link            # and the mount on /tf_static
  ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST slope-ros2
  slope-ros2 --ros-args -p frame_id:=camera_depth_optical_frame -r __ns:=/robot1

ROS 2's arguments after --ros-args (until --) are read as these flags: the parameters -p frame_id:= and -p base_frame:=, the remappings -r __ns:= and -r __node:=; any other parameter, remapping or ROS option is refused.

On a ROS 2 computer, with slope_msgs built (ros2/slope_msgs): \
`ros2 topic echo /slope/estimate`; in rviz2, add a MarkerArray display on /slope/markers with \
the fixed frame slope_camera (or the --base-frame) and its Reliability Policy set to Best Effort."
)]
pub struct Ros2Args {
    /// The daemons' config file (service_prefix, `[mount]`, `[ros2]`).
    /// Default: /etc/slope/slope.toml if it exists.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,

    /// The node's namespace: topics are `<namespace>/slope/...` (the
    /// global /diagnostics and /tf_static stay). Default: `[ros2] namespace`,
    /// else /.
    #[arg(long, value_parser = namespace_arg)]
    pub namespace: Option<String>,

    /// The node's name. Default: `[ros2] node_name`, else slope_ros2.
    #[arg(long, value_parser = node_name_arg)]
    pub node_name: Option<String>,

    /// The DDS domain (0-232). Default: `[ros2] domain_id`, else the
    /// environment variable ROS_DOMAIN_ID, else 0.
    #[arg(long, value_parser = domain_id_arg)]
    pub domain_id: Option<u16>,

    /// The frame_id of every header: the camera's optical frame (x right,
    /// y down, z forward). Default: `[ros2] frame_id`, else slope_camera.
    #[arg(long, value_parser = frame_id_arg)]
    pub frame_id: Option<String>,

    /// Publish the camera's pose in this frame (e.g. base_link) on
    /// /tf_static, from the config file's `[mount]` (height_m and pitch_deg
    /// needed, roll_deg optional). Default: `[ros2] base_frame`, else none.
    #[arg(long, value_parser = frame_id_arg)]
    pub base_frame: Option<String>,

    #[command(flatten)]
    pub common: CommonArgs,
}
