//! What the node runs with ([`Settings`]): each value from its flag, else
//! from the config file, else the default; discovery from ROS 2's
//! environment variables.

use std::path::Path;

use slope_sensor::publish::StopFlag;
use slope_sensor::recording::MountInfo;
use slope_tools::config_file::{config_path, SlopeFile, DEFAULT_CONFIG_PATH};

use super::args::Ros2Args;
use crate::discovery::Discovery;

/// The settings in effect.
#[derive(Debug, Clone)]
pub struct Settings {
    pub service_prefix: String,
    pub namespace: String,
    pub node_name: String,
    pub frame_id: String,
    /// `/tf_static` from this frame to `frame_id`, when given.
    pub base_frame: Option<String>,
    /// The config file's `[mount]`.
    pub mount: MountInfo,
    pub discovery: Discovery,
}

impl Settings {
    /// The flags of `args` over the config file (`--config`, else
    /// /etc/slope/slope.toml when it exists) and ROS 2's environment.
    /// `None` when `stop` came while the file was read.
    pub fn of(args: &Ros2Args, stop: &StopFlag) -> anyhow::Result<Option<Self>> {
        Self::with_default_file(args, Path::new(DEFAULT_CONFIG_PATH), stop)
    }

    /// [`Self::of`] with `default` for /etc/slope/slope.toml.
    pub fn with_default_file(
        args: &Ros2Args,
        default: &Path,
        stop: &StopFlag,
    ) -> anyhow::Result<Option<Self>> {
        let path = config_path(args.config.as_deref(), default);
        let Some(file) = SlopeFile::load_or_stop(path.as_deref(), stop)? else {
            return Ok(None);
        };
        // Loading checks every section ([ros2] too): an error names the
        // file and the key, and the daemon exits with EX_CONFIG (78).
        let ros2 = file.ros2;
        let discovery = Discovery::from_env(args.domain_id.or(ros2.domain_id))?;
        let pick = |flag: &Option<String>, key: String| flag.clone().unwrap_or(key);
        Ok(Some(Self {
            service_prefix: args.common.prefix_or(&file.service_prefix),
            namespace: pick(&args.namespace, ros2.namespace),
            node_name: pick(&args.node_name, ros2.node_name),
            frame_id: pick(&args.frame_id, ros2.frame_id),
            base_frame: args.base_frame.clone().or(ros2.base_frame),
            mount: file.mount,
            discovery,
        }))
    }
}
