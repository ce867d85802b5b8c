//! What the estimator returns for one frame: the [`Estimate`], its fitted
//! planes and its per-stage timings. Data only; the stages that fill it
//! run in `estimator.rs`.

use slope_ipc_types::{EstimateStatus, SlopeMethod};

use crate::selection::RoadScene;
use crate::tracking::{RoadPlace, TrackedSlope};

/// The result for one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    pub status: EstimateStatus,
    pub method: SlopeMethod,
    /// Signed slope, degrees: + uphill, - downhill; NaN unless `Ok`.
    pub slope_deg: f64,
    /// Spread of the averaged angle samples, degrees; NaN for the
    /// baselines (one fit, no spread: a planner gating on the spread must
    /// not trust them blindly; use the confidence).
    pub slope_std_deg: f64,
    /// Angle samples averaged (1 for the baselines).
    pub samples: u32,
    /// Distance to the inclined plane along the optical axis, metres.
    pub distance_m: f64,
    pub ground: Option<PlaneEstimate>,
    pub inclined: Option<PlaneEstimate>,
    /// True when the ground normal is the mount's up vector.
    pub ground_from_mount: bool,
    /// How far ahead the ground plane was seen, metres (`ground_reach.rs`):
    /// short of the sensor's range before a drop-off. NaN without a
    /// measured ground plane.
    pub ground_seen_to_m: f64,
    /// How far to trust `slope_deg`, 0..=1 (0 unless `Ok`).
    pub confidence: f64,
    /// Why the confidence is below 1: bits of
    /// `slope_ipc_types::confidence`.
    pub confidence_reasons: u32,
    /// The slope followed over frames (`Estimator::estimate_frame`).
    pub tracked: Option<TrackedSlope>,
    /// Every surface in view with its role, and which is the road (`None`
    /// without a ground, or when the frame failed before the selection).
    pub scene: Option<RoadScene>,
    pub timings: StageTimings,
}

impl Estimate {
    /// The estimate of a frame that failed with `status`: no slope, no
    /// planes, confidence 0.
    pub(crate) fn failed(status: EstimateStatus, method: SlopeMethod) -> Self {
        Self {
            status,
            method,
            slope_deg: f64::NAN,
            slope_std_deg: f64::NAN,
            samples: 0,
            distance_m: f64::NAN,
            ground: None,
            inclined: None,
            ground_from_mount: false,
            ground_seen_to_m: f64::NAN,
            confidence: 0.0,
            confidence_reasons: 0,
            tracked: None,
            scene: None,
            timings: StageTimings::default(),
        }
    }
}

impl Estimate {
    /// Where the road is, for tracking: its nearest point in the corridor
    /// and its heading; `None` without a road.
    pub fn road_place(&self) -> Option<RoadPlace> {
        let road = self.scene.as_ref()?.road_surface()?;
        Some(RoadPlace {
            distance_m: road.corridor_distance_m,
            heading_deg: road.heading_deg,
        })
    }
}

/// A fitted plane in the estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneEstimate {
    /// `[a, b, c, d]`: `a x + b y + c z + d = 0`, `(a, b, c)` a unit normal
    /// towards the camera side.
    pub coefficients: [f64; 4],
    /// RANSAC inliers of the plane (of all its segments for the ground).
    pub inliers: u32,
    /// RMS distance of the inliers from the plane, metres.
    pub rms_m: f64,
    /// Surface the inliers cover, square metres.
    pub area_m2: f64,
}

/// Milliseconds per stage.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageTimings {
    pub total_ms: f64,
    /// Stage name and milliseconds, in pipeline order.
    pub stages: Vec<(&'static str, f64)>,
}

impl StageTimings {
    /// The time of a stage, 0 when it did not run.
    pub fn stage_ms(&self, name: &str) -> f64 {
        self.stages
            .iter()
            .filter(|(n, _)| *n == name)
            .map(|(_, ms)| ms)
            .sum()
    }
}
