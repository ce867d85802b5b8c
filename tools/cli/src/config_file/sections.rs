//! The sections of the file and their defaults: [`SlopeFile`] (the whole
//! file), `[health]` ([`HealthSection`]) and `[capture]`
//! ([`CaptureSection`]), `[ros2]` ([`Ros2Section`]); `[mount]` and `[estimator]` are types of the
//! sensor and pipeline crates.

use serde::{Deserialize, Serialize};
use slope_ipc_types::DEFAULT_SERVICE_PREFIX;
use slope_pipeline::EstimatorConfig;
use slope_sensor::recording::MountInfo;

use crate::health::DEFAULT_HEALTH_INTERVAL_S;

/// The depth decoding pipelines `[capture] pipeline` names.
pub const PIPELINES: [&str; 7] = ["default", "cpu", "cl", "clkde", "cuda", "cudakde", "gl"];

/// The whole file; every section and key optional.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SlopeFile {
    /// Prefix of the iceoryx2 service names.
    pub service_prefix: String,
    pub health: HealthSection,
    /// `[mount]`: the camera's pose on the robot; a key left out is unknown.
    pub mount: MountInfo,
    pub capture: CaptureSection,
    pub estimator: EstimatorConfig,
    pub ros2: Ros2Section,
}

impl Default for SlopeFile {
    fn default() -> Self {
        Self {
            service_prefix: DEFAULT_SERVICE_PREFIX.to_string(),
            health: HealthSection::default(),
            mount: MountInfo::default(),
            capture: CaptureSection::default(),
            estimator: EstimatorConfig::default(),
            ros2: Ros2Section::default(),
        }
    }
}

/// `[health]`: the daemons' reports on `<prefix>/health`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HealthSection {
    /// Seconds between reports; 0: none.
    pub interval_s: f64,
}

impl Default for HealthSection {
    fn default() -> Self {
        Self {
            interval_s: DEFAULT_HEALTH_INTERVAL_S,
        }
    }
}

/// `[capture]`: the Kinect v2 and libfreenect2's depth processing. The
/// defaults are libfreenect2's (`slope_sensor::kinect2::DepthConfig`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CaptureSection {
    /// The camera to open; the first one when neither this nor
    /// `device_index` is set (`serial` wins when both are).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub serial: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub device_index: Option<u32>,
    /// One of [`PIPELINES`].
    pub pipeline: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu_device: Option<u32>,
    pub min_depth_m: f64,
    pub max_depth_m: f64,
    pub bilateral_filter: bool,
    pub edge_aware_filter: bool,
    pub color: bool,
    pub frame_timeout_s: f64,
}

impl Default for CaptureSection {
    fn default() -> Self {
        Self {
            serial: None,
            device_index: None,
            pipeline: "default".to_string(),
            gpu_device: None,
            min_depth_m: 0.5,
            max_depth_m: 4.5,
            bilateral_filter: true,
            edge_aware_filter: true,
            color: true,
            frame_timeout_s: 3.0,
        }
    }
}

/// `[ros2]`: the ROS 2 node (`slope-ros2`); each key is also a flag of
/// its own, which wins.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Ros2Section {
    /// The node's namespace: topics are `<namespace>/slope/...`.
    pub namespace: String,
    pub node_name: String,
    /// The DDS domain; unset: `ROS_DOMAIN_ID`, else 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub domain_id: Option<u16>,
    /// The frame of every header: the camera's optical frame.
    pub frame_id: String,
    /// Publish the `[mount]` pose of the camera in this frame on
    /// `/tf_static`; unset: none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub base_frame: Option<String>,
}

impl Default for Ros2Section {
    fn default() -> Self {
        Self {
            namespace: "/".to_string(),
            node_name: "slope_ros2".to_string(),
            domain_id: None,
            frame_id: "slope_camera".to_string(),
            base_frame: None,
        }
    }
}
