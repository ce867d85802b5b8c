//! The ROS 2 names `slope-ros2` publishes under: topics (relative to the
//! node's namespace, except the global `/diagnostics` and `/tf_static`),
//! their message types, and the node's default names; the checks of the
//! names given (`slope_tools::ros2_names`, shared with the config file).

/// The node's name unless `--node-name` says otherwise.
pub const DEFAULT_NODE_NAME: &str = "slope_ros2";
/// The camera's optical frame, the `frame_id` of every header unless
/// `--frame-id` says otherwise (the rosbag2 export's too).
pub const DEFAULT_FRAME_ID: &str = "slope_camera";

/// `<namespace>/slope/estimate`: `slope_msgs/msg/SlopeEstimate`.
pub const ESTIMATE_TOPIC: &str = "slope/estimate";
/// `<namespace>/slope/surfaces`: `slope_msgs/msg/Surfaces`.
pub const SURFACES_TOPIC: &str = "slope/surfaces";
/// `<namespace>/slope/markers`: `visualization_msgs/msg/MarkerArray`.
pub const MARKERS_TOPIC: &str = "slope/markers";
/// `/diagnostics` (global, as every ROS 2 driver's):
/// `diagnostic_msgs/msg/DiagnosticArray`.
pub const DIAGNOSTICS_TOPIC: &str = "/diagnostics";
/// `/tf_static` (global): `tf2_msgs/msg/TFMessage`.
pub const TF_STATIC_TOPIC: &str = "/tf_static";

/// A ROS 2 message type: package and name (`slope_msgs`, `SlopeEstimate`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MessageType {
    pub package: &'static str,
    pub name: &'static str,
}

impl MessageType {
    /// `slope_msgs/msg/SlopeEstimate`, as ROS 2 tools print it.
    pub fn ros_name(self) -> String {
        format!("{}/msg/{}", self.package, self.name)
    }

    /// `slope_msgs::msg::dds_::SlopeEstimate_`, the type name on DDS (what
    /// `rmw_cyclonedds` and `rmw_fastrtps` register).
    pub fn dds_name(self) -> String {
        format!("{}::msg::dds_::{}_", self.package, self.name)
    }
}

pub const SLOPE_ESTIMATE: MessageType = MessageType {
    package: "slope_msgs",
    name: "SlopeEstimate",
};
pub const SURFACES: MessageType = MessageType {
    package: "slope_msgs",
    name: "Surfaces",
};
pub const MARKER_ARRAY: MessageType = MessageType {
    package: "visualization_msgs",
    name: "MarkerArray",
};
pub const DIAGNOSTIC_ARRAY: MessageType = MessageType {
    package: "diagnostic_msgs",
    name: "DiagnosticArray",
};
pub const TF_MESSAGE: MessageType = MessageType {
    package: "tf2_msgs",
    name: "TFMessage",
};

pub use slope_tools::ros2_names::{frame_id_arg, namespace_arg, node_name_arg};

/// The absolute topic name of `topic` for a node in `namespace`: a global
/// topic (`/diagnostics`) as it is, a relative one under the namespace
/// (`/robot1` + `slope/estimate` = `/robot1/slope/estimate`).
pub fn resolve(namespace: &str, topic: &str) -> String {
    if topic.starts_with('/') {
        topic.to_string()
    } else if namespace == "/" {
        format!("/{topic}")
    } else {
        format!("{namespace}/{topic}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dds_type_names_are_those_of_the_ros_2_rmw_layers() {
        assert_eq!(
            SLOPE_ESTIMATE.dds_name(),
            "slope_msgs::msg::dds_::SlopeEstimate_"
        );
        assert_eq!(
            DIAGNOSTIC_ARRAY.ros_name(),
            "diagnostic_msgs/msg/DiagnosticArray"
        );
    }

    #[test]
    fn topics_resolve_under_the_namespace_unless_global() {
        assert_eq!(resolve("/", ESTIMATE_TOPIC), "/slope/estimate");
        assert_eq!(resolve("/robot1", ESTIMATE_TOPIC), "/robot1/slope/estimate");
        assert_eq!(resolve("/a/b", MARKERS_TOPIC), "/a/b/slope/markers");
        assert_eq!(resolve("/robot1", DIAGNOSTICS_TOPIC), "/diagnostics");
    }
}
