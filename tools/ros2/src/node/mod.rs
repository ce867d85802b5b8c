//! The node (feature `ros2`): iceoryx2 `<prefix>/estimate`, `/surfaces`
//! and `/health` to ROS 2 topics over DDS.
//!
//! One concern per file:
//! - `args.rs`: the flags ([`Ros2Args`]);
//! - `settings.rs`: the flags over the config file, the discovery settings
//!   of the environment ([`Settings`]);
//! - `participant.rs`: the DDS participant, the ROS 2 node and its
//!   publishers with their QoS ([`Outputs`]);
//! - `forward.rs`: the loop from iceoryx2 to DDS ([`run`], [`Ros2Stats`]);
//! - `tests.rs`: unit tests of the flags and settings.

mod args;
mod forward;
mod participant;
mod settings;
#[cfg(test)]
mod tests;

pub use args::Ros2Args;
pub use forward::{run, Ros2Stats};
pub use participant::Outputs;
pub use settings::Settings;
