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
//! | `slope/cloud` | publish-subscribe | `[CloudPoint]` (row-major, `width * height`) | [`CloudHeader`] (`slope.CloudHeader.v2`) |
//! | `slope/cloud` | event | "a new cloud was sent" | - |
//! | `slope/estimate` | publish-subscribe | [`SlopeEstimate`] (`slope.SlopeEstimate.v2`) | - |
//! | `slope/estimate` | event | "a new estimate was sent" | - |
//! | `slope/surfaces` | publish-subscribe | [`Surfaces`] (`slope.Surfaces.v1`): every surface of the frame with its role, and the road | - |
//! | `slope/surfaces` | event | "new surfaces were sent" | - |
//! | `slope/health` | publish-subscribe | [`Health`] (`slope.Health.v1`), about once a second from each daemon | - |
//! | `slope/health` | event | "a new health report was sent" | - |

mod cloud;
pub mod confidence;
mod estimate;
mod health;
mod services;
mod surfaces;
mod text;

pub use cloud::{CloudHeader, CloudPoint, CloudSource, Intrinsics, Mount, SENSOR_NAME_LEN};
pub use estimate::{EstimateStatus, SlopeEstimate, SlopeMethod};
pub use health::{
    Health, HealthComponent, StageHealth, TimingStats, LAST_ERROR_LEN, MAX_STAGES, STAGE_NAME_LEN,
};
pub use services::{
    ServiceNames, DEFAULT_MAX_CLOUD_POINTS, DEFAULT_SERVICE_PREFIX, SERVICE_PREFIX_ENV,
};
pub use surfaces::{
    surface_flags, SurfaceDescription, SurfaceRole, SurfaceSupport, Surfaces, MAX_SURFACES,
    NO_SURFACE,
};

/// Nanoseconds since the Unix epoch (CLOCK_REALTIME), the clock every
/// `*_stamp_ns` field uses so that stamps compare across processes.
pub fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
        .unwrap_or(0)
}

/// Where each field of a message lies: for bindings in other languages and
/// the tests that keep them in step (`tests/tests/python_client.rs`).
pub mod layout {
    use core::mem::{offset_of, size_of};

    /// One field: name, byte offset, byte size.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub struct FieldLayout {
        pub name: &'static str,
        pub offset: usize,
        pub size: usize,
    }

    /// The size of a field, from a projection onto it.
    fn field_size<T, F>(_: fn(&T) -> &F) -> usize {
        size_of::<F>()
    }

    macro_rules! fields {
        ($ty:ty: $($name:ident),* $(,)?) => {
            vec![$(FieldLayout {
                name: stringify!($name),
                offset: offset_of!($ty, $name),
                size: field_size(|v: &$ty| &v.$name),
            }),*]
        };
    }

    /// The fields of [`crate::SlopeEstimate`], in declaration order.
    pub fn slope_estimate() -> Vec<FieldLayout> {
        fields!(crate::SlopeEstimate:
            frame_index, capture_stamp_ns, publish_stamp_ns, source_stamp_ns, dropped_frames,
            status, method, slope_deg, slope_std_deg, distance_m, ground_plane, inclined_plane,
            ground_inliers, inclined_inliers, samples, ground_from_mount, processing_us,
            confidence, confidence_reasons, ground_seen_to_m, ground_rms_m, inclined_rms_m,
            ground_area_m2, inclined_area_m2, tracked_slope_deg, tracked_std_deg,
            tracked_frames, tracked_accepted,
        )
    }

    /// The fields of [`crate::Surfaces`], in declaration order.
    pub fn surfaces() -> Vec<FieldLayout> {
        fields!(crate::Surfaces:
            frame_index, capture_stamp_ns, publish_stamp_ns, source_stamp_ns, status, count,
            road, ground_from_mount, up, forward, ground_plane, corridor_half_width_m,
            look_ahead_m, surfaces,
        )
    }

    /// The fields of [`crate::SurfaceDescription`], in declaration order.
    pub fn surface_description() -> Vec<FieldLayout> {
        fields!(crate::SurfaceDescription:
            role, support, supported_by, inliers, flags, segments, slope_deg, heading_deg,
            distance_m, far_m, left_m, right_m, lowest_m, highest_m, area_m2, rms_m,
            noise_ratio, plane, outline,
        )
    }

    /// The fields of [`crate::Health`], in declaration order.
    pub fn health() -> Vec<FieldLayout> {
        fields!(crate::Health:
            stamp_ns, uptime_ms, component, pid, frames_in, frames_out, frames_dropped,
            reconnects, errors, rate_in_hz, rate_out_hz, window_ms, latency, stage_count,
            reserved, stages, last_error_stamp_ns, last_error,
        )
    }

    /// The fields of [`crate::TimingStats`].
    pub fn timing_stats() -> Vec<FieldLayout> {
        fields!(crate::TimingStats: median_ms, p95_ms, max_ms, count)
    }

    /// The fields of [`crate::StageHealth`].
    pub fn stage_health() -> Vec<FieldLayout> {
        fields!(crate::StageHealth: name, timing)
    }
}
