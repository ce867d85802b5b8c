//! `slope-bridge`: forwards the estimate and health topics of one service
//! prefix from iceoryx2 (this host) to Zenoh (any host), as versioned JSON.
//!
//! [`payload`] is the wire format (always built, so that subscribers in
//! Rust can decode it without Zenoh); `bridge` is the forwarding loop,
//! behind the `zenoh` feature.

pub mod payload;

#[cfg(feature = "zenoh")]
pub mod bridge;
