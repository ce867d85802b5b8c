//! Message layouts shared by every slope process, and the names of the
//! iceoryx2 services that carry them.
//!
//! Everything here is plain data: `#[repr(C)]`, fixed size, no pointers, with
//! a pinned type name so a refactor never changes the wire identity. There is
//! no logic beyond small accessors; producers and consumers live in `sensor`,
//! `pipeline` and `tools`.
//!
//! | service (with the default prefix `slope`) | pattern | payload | user header |
//! |---|---|---|---|
//! | `slope/cloud` | publish-subscribe | `[CloudPoint]` (row-major, `width * height`) | [`CloudHeader`] |
//! | `slope/cloud` | event | "a new cloud was sent" | - |
//! | `slope/estimate` | publish-subscribe | [`SlopeEstimate`] (`slope.SlopeEstimate.v2`) | - |
//! | `slope/estimate` | event | "a new estimate was sent" | - |
//! | `slope/health` | publish-subscribe | [`Health`] (`slope.Health.v1`), about once a second from each daemon | - |
//! | `slope/health` | event | "a new health report was sent" | - |

mod cloud;
pub mod confidence;
mod estimate;
mod health;
mod services;

pub use cloud::{CloudHeader, CloudPoint, CloudSource, Intrinsics, Mount};
pub use estimate::{EstimateStatus, SlopeEstimate, SlopeMethod};
pub use health::{
    Health, HealthComponent, StageHealth, TimingStats, LAST_ERROR_LEN, MAX_STAGES, STAGE_NAME_LEN,
};
pub use services::{
    ServiceNames, DEFAULT_MAX_CLOUD_POINTS, DEFAULT_SERVICE_PREFIX, SERVICE_PREFIX_ENV,
};

/// Nanoseconds since the Unix epoch (CLOCK_REALTIME), the clock every
/// `*_stamp_ns` field uses so that stamps compare across processes.
pub fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
        .unwrap_or(0)
}
