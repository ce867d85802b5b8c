//! What the node runs with ([`Settings`]): each value from its flag, else
//! from the config file, else the default; discovery from ROS 2's
//! environment variables.

use std::path::Path;

use anyhow::Context;
use slope_sensor::recording::MountInfo;
use slope_tools::config_file::{config_path, SlopeFile, DEFAULT_CONFIG_PATH};

use super::args::Ros2Args;
use crate::discovery::Discovery;
use crate::topics::{DEFAULT_FRAME_ID, DEFAULT_NODE_NAME};

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
    pub fn of(args: &Ros2Args) -> anyhow::Result<Self> {
        Self::with_default_file(args, Path::new(DEFAULT_CONFIG_PATH))
    }

    /// [`Self::of`] with `default` for /etc/slope/slope.toml.
    pub fn with_default_file(args: &Ros2Args, default: &Path) -> anyhow::Result<Self> {
        let path = config_path(args.config.as_deref(), default);
        let file = SlopeFile::load(path.as_deref())?;
        file.validate().context("invalid settings")?;
        let discovery = Discovery::from_env(args.domain_id)?;
        Ok(Self {
            service_prefix: args.common.prefix_or(&file.service_prefix),
            namespace: args.namespace.clone().unwrap_or_else(|| "/".to_string()),
            node_name: args
                .node_name
                .clone()
                .unwrap_or_else(|| DEFAULT_NODE_NAME.to_string()),
            frame_id: args
                .frame_id
                .clone()
                .unwrap_or_else(|| DEFAULT_FRAME_ID.to_string()),
            base_frame: args.base_frame.clone(),
            mount: file.mount,
            discovery,
        })
    }
}
