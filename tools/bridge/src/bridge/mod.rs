//! The forwarding loop: iceoryx2 `<prefix>/estimate` and `<prefix>/health`
//! to Zenoh `<key prefix>/estimate` and `<key prefix>/health`.
//!
//! One concern per file:
//! - `args.rs`: the flags ([`BridgeArgs`]) and the checks of their values
//!   ([`endpoint_arg`], [`key_prefix_arg`]);
//! - `config.rs`: the Zenoh configuration: the `--zenoh-config` file, the
//!   flags over it, the bridge's defaults ([`zenoh_config`]);
//! - `session.rs`: opening the Zenoh session, waiting for a client's router
//!   until it answers or a stop;
//! - `forward.rs`: the loop from iceoryx2 to Zenoh ([`run`], [`BridgeStats`]);
//! - `reason.rs`: Zenoh's errors as one readable line ([`zenoh_reason`]);
//! - `tests.rs`: unit tests.

mod args;
mod config;
mod forward;
mod reason;
mod session;
#[cfg(test)]
mod tests;

pub use args::{endpoint_arg, key_prefix_arg, BridgeArgs};
pub use config::zenoh_config;
pub use forward::{run, BridgeStats};
pub use reason::zenoh_reason;
