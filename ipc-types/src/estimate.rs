//! The slope estimate every subscriber receives.

use iceoryx2::prelude::ZeroCopySend;

/// What became of one frame.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EstimateStatus {
    /// A slope was measured; `slope_deg` and the planes are valid.
    Ok = 0,
    /// No ground plane was found and the mount gives no up vector.
    NoGround = 1,
    /// No inclined plane (ramp, wall) ahead was found.
    NoInclinedPlane = 2,
    /// Too few valid points to run the method.
    TooFewPoints = 3,
    /// The frame itself was malformed (size mismatch, empty).
    BadFrame = 4,
}

impl EstimateStatus {
    pub const ALL: [EstimateStatus; 5] = [
        Self::Ok,
        Self::NoGround,
        Self::NoInclinedPlane,
        Self::TooFewPoints,
        Self::BadFrame,
    ];

    pub fn from_raw(raw: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|s| *s as u32 == raw)
    }

    /// The name used in logs and JSON output.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ok => "ok",
            Self::NoGround => "no_ground",
            Self::NoInclinedPlane => "no_inclined_plane",
            Self::TooFewPoints => "too_few_points",
            Self::BadFrame => "bad_frame",
        }
    }
}

/// Which fit produced the estimate.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SlopeMethod {
    /// The paper's method: normals, cosine k-means, cumulative averaging.
    Paper = 0,
    /// Ordinary least squares z = ax + by + c on each plane's points.
    LeastSquares = 1,
    /// Total least squares (PCA) on each plane's RANSAC inliers.
    Tls = 2,
}

impl SlopeMethod {
    pub const ALL: [SlopeMethod; 3] = [Self::Paper, Self::LeastSquares, Self::Tls];

    pub fn from_raw(raw: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|m| *m as u32 == raw)
    }

    /// The name used on command lines and in JSON output.
    pub fn name(self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::LeastSquares => "least-squares",
            Self::Tls => "tls",
        }
    }
}

/// One slope estimate, published once per processed frame.
///
/// Planes are `[a, b, c, d]` with `a x + b y + c z + d = 0` in the camera
/// frame, `(a, b, c)` a unit normal pointing up and out of the surface
/// (towards the camera side); all zero when absent.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("slope.SlopeEstimate.v1")]
pub struct SlopeEstimate {
    /// The cloud's `frame_index`.
    pub frame_index: u64,
    /// The cloud's `capture_stamp_ns` (ns since the Unix epoch).
    pub capture_stamp_ns: u64,
    /// When this estimate was published (ns since the Unix epoch).
    pub publish_stamp_ns: u64,
    /// The cloud's `source_stamp_ns`.
    pub source_stamp_ns: u64,
    /// Clouds the estimator skipped so far because a newer one was waiting
    /// (or never saw: gaps in `frame_index`), cumulative.
    pub dropped_frames: u64,
    /// An [`EstimateStatus`] as its `u32` value.
    pub status: u32,
    /// A [`SlopeMethod`] as its `u32` value.
    pub method: u32,
    /// Signed slope, degrees: the angle between the inclined plane and the
    /// ground, positive uphill (the surface rises away from the camera),
    /// negative downhill. NaN unless `status` is ok.
    pub slope_deg: f64,
    /// Standard deviation of the averaged angle samples, degrees.
    pub slope_std_deg: f64,
    /// Distance from the camera to the inclined plane along the viewing
    /// direction (optical axis), metres; NaN when the axis does not meet it.
    pub distance_m: f64,
    pub ground_plane: [f64; 4],
    pub inclined_plane: [f64; 4],
    pub ground_inliers: u32,
    pub inclined_inliers: u32,
    /// Angle samples averaged into `slope_deg`.
    pub samples: u32,
    /// 1 when the ground normal came from the mount's up vector instead of a
    /// measured ground plane.
    pub ground_from_mount: u32,
    /// Time spent estimating this frame, microseconds.
    pub processing_us: u64,
}

const _: () = assert!(core::mem::size_of::<SlopeEstimate>() == 160);

impl SlopeEstimate {
    /// The status, or `BadFrame` for a value this build does not know.
    pub fn status(&self) -> EstimateStatus {
        EstimateStatus::from_raw(self.status).unwrap_or(EstimateStatus::BadFrame)
    }

    pub fn method(&self) -> Option<SlopeMethod> {
        SlopeMethod::from_raw(self.method)
    }

    /// Capture-to-publish latency, milliseconds.
    pub fn latency_ms(&self) -> f64 {
        self.publish_stamp_ns.saturating_sub(self.capture_stamp_ns) as f64 / 1e6
    }
}

impl Default for SlopeEstimate {
    fn default() -> Self {
        Self {
            frame_index: 0,
            capture_stamp_ns: 0,
            publish_stamp_ns: 0,
            source_stamp_ns: 0,
            dropped_frames: 0,
            status: EstimateStatus::BadFrame as u32,
            method: SlopeMethod::Paper as u32,
            slope_deg: f64::NAN,
            slope_std_deg: f64::NAN,
            distance_m: f64::NAN,
            ground_plane: [0.0; 4],
            inclined_plane: [0.0; 4],
            ground_inliers: 0,
            inclined_inliers: 0,
            samples: 0,
            ground_from_mount: 0,
            processing_us: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_round_trips_through_raw() {
        for s in EstimateStatus::ALL {
            assert_eq!(EstimateStatus::from_raw(s as u32), Some(s));
        }
        assert_eq!(EstimateStatus::from_raw(99), None);
        let e = SlopeEstimate {
            status: 99,
            ..Default::default()
        };
        assert_eq!(e.status(), EstimateStatus::BadFrame);
    }

    #[test]
    fn latency_is_publish_minus_capture() {
        let e = SlopeEstimate {
            capture_stamp_ns: 1_000_000_000,
            publish_stamp_ns: 1_012_500_000,
            ..Default::default()
        };
        assert!((e.latency_ms() - 12.5).abs() < 1e-9);
    }
}
