//! The ROS 2 names `slope-ros2` publishes under: topics (relative to the
//! node's namespace, except the global `/diagnostics` and `/tf_static`),
//! their message types, and the node's default names.

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

/// Checks a ROS 2 namespace (`--namespace`): `/`, or `/` followed by
/// tokens separated by `/`, each starting with a letter or `_` and made
/// of letters, digits and `_` (no `__`), no trailing `/`.
pub fn namespace_arg(text: &str) -> Result<String, String> {
    let expected = "expected / or /NAME[/NAME...] with names of letters, digits and _ \
                    (starting with a letter or _, no __), e.g. /robot1";
    if text == "/" {
        return Ok(text.to_string());
    }
    let Some(rest) = text.strip_prefix('/') else {
        return Err(format!("'{text}' is not a ROS 2 namespace: {expected}"));
    };
    if rest.split('/').all(is_name_token) {
        Ok(text.to_string())
    } else {
        Err(format!("'{text}' is not a ROS 2 namespace: {expected}"))
    }
}

/// Checks a node name (`--node-name`): one token of letters, digits and
/// `_`, starting with a letter or `_`.
pub fn node_name_arg(text: &str) -> Result<String, String> {
    if is_name_token(text) {
        Ok(text.to_string())
    } else {
        Err(format!(
            "'{text}' is not a ROS 2 node name: expected letters, digits and _ (starting with a \
             letter or _, no __), e.g. slope_ros2"
        ))
    }
}

/// Checks a TF frame id (`--frame-id`, `--base-frame`): not empty, no
/// whitespace, no leading `/` (tf2 refuses it).
pub fn frame_id_arg(text: &str) -> Result<String, String> {
    if text.is_empty() || text.starts_with('/') || text.contains(char::is_whitespace) {
        Err(format!(
            "'{text}' is not a TF frame id: expected a name without spaces and without a \
             leading /, e.g. base_link"
        ))
    } else {
        Ok(text.to_string())
    }
}

fn is_name_token(token: &str) -> bool {
    token.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
        && token.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        && !token.contains("__")
}

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

    #[test]
    fn names_follow_the_ros_2_rules() {
        for good in ["/", "/robot1", "/a/b_c", "/_x"] {
            assert_eq!(namespace_arg(good).as_deref(), Ok(good));
        }
        for bad in [
            "", "robot1", "/robot1/", "//", "/1robot", "/a__b", "/a-b", "/a b",
        ] {
            let err = namespace_arg(bad).unwrap_err();
            assert!(err.contains("not a ROS 2 namespace"), "{bad}: {err}");
        }
        assert!(node_name_arg("slope_ros2").is_ok());
        for bad in ["", "slope-ros2", "2slope", "a/b"] {
            assert!(node_name_arg(bad).is_err(), "{bad}");
        }
        assert!(frame_id_arg("base_link").is_ok());
        for bad in ["", "/base_link", "base link"] {
            assert!(frame_id_arg(bad).is_err(), "{bad}");
        }
    }
}
