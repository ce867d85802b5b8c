//! What became of one frame under one method ([`FrameResult`]): its status,
//! slope, truth, timings and planes, as they appear in the JSON.

use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};
use slope_ipc_types::{EstimateStatus, Surfaces};
use slope_pipeline::tracking::TrackedSlope;
use slope_pipeline::{Estimate, PlaneEstimate, StageTimings};

use crate::surfaces_json::SurfaceJson;

/// What became of one frame under one method.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameResult {
    /// The frame's `index` in frames.csv.
    pub index: u64,
    pub status: &'static str,
    /// Signed slope, degrees (+ uphill); `None` unless `ok`.
    pub slope_deg: Option<f64>,
    /// Spread of the averaged angle samples, degrees; `None` unless `ok`.
    pub std_deg: Option<f64>,
    /// Distance to the inclined plane along the optical axis, metres;
    /// `None` unless `ok`.
    pub distance_m: Option<f64>,
    /// The frame's ground truth, degrees, if the recording has one.
    pub truth_deg: Option<f64>,
    /// Milliseconds, total and per stage; `None` when the frame could not be
    /// read (the estimator did not run).
    pub ms: Option<Timings>,
    /// Why the frame is `bad_frame`.
    pub error: Option<String>,
    /// Planes, their quality, confidence and track; all `null` when the
    /// frame could not be read.
    #[serde(flatten)]
    pub details: FrameDetails,
}

/// What the estimator found besides the slope, for a frame it ran on. Every
/// field is `None` (`null`) when the frame could not be read; a plane's
/// fields are also `None` when that plane is absent.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct FrameDetails {
    /// `[a, b, c, d]` in the camera frame: `(a, b, c)` a unit normal towards
    /// the camera side, `d` the camera's distance to the plane.
    pub ground_plane: Option<[f64; 4]>,
    /// `[a, b, c, d]` as `ground_plane`.
    pub inclined_plane: Option<[f64; 4]>,
    pub ground_inliers: Option<u32>,
    pub inclined_inliers: Option<u32>,
    /// RMS distance of the inliers from the plane, metres.
    pub ground_rms_m: Option<f64>,
    pub inclined_rms_m: Option<f64>,
    /// Surface the inliers cover, square metres.
    pub ground_area_m2: Option<f64>,
    pub inclined_area_m2: Option<f64>,
    /// How far ahead the ground was seen, metres (short of the sensor's
    /// range before a drop-off); `None` without a measured ground.
    pub ground_seen_to_m: Option<f64>,
    /// How far to trust `slope_deg`, 0..=1 (0 unless `ok`).
    pub confidence: Option<f64>,
    /// Why the confidence is below 1, by name.
    pub confidence_reasons: Option<Vec<std::borrow::Cow<'static, str>>>,
    /// True when the ground normal is the mount's up vector.
    pub ground_from_mount: Option<bool>,
    /// The slope tracked over the recording's frames so far.
    pub tracked: Option<TrackedJson>,
    /// Every surface seen, as the estimator publishes them on
    /// `<prefix>/surfaces` (same order, the road marked); empty without a
    /// ground.
    pub surfaces: Option<Vec<SurfaceJson>>,
}

/// The tracked slope after a frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackedJson {
    /// Degrees, signed; `None` before the first accepted frame.
    pub slope_deg: Option<f64>,
    pub std_deg: Option<f64>,
    /// Frames accepted into the track since it (re)started.
    pub frames: u32,
    /// True when this frame was accepted into the track.
    pub accepted: bool,
}

impl From<&TrackedSlope> for TrackedJson {
    fn from(t: &TrackedSlope) -> Self {
        Self {
            slope_deg: t.slope_deg.is_finite().then_some(t.slope_deg),
            std_deg: t.std_deg.is_finite().then_some(t.std_deg),
            frames: t.frames,
            accepted: t.accepted,
        }
    }
}

impl FrameDetails {
    /// The details of an estimate.
    pub fn of(estimate: &Estimate) -> Self {
        let ground = estimate.ground.as_ref();
        let inclined = estimate.inclined.as_ref();
        let coefficients = |p: &PlaneEstimate| p.coefficients;
        let inliers = |p: &PlaneEstimate| p.inliers;
        let rms = |p: &PlaneEstimate| p.rms_m;
        let area = |p: &PlaneEstimate| p.area_m2;
        Self {
            ground_plane: ground.map(coefficients),
            inclined_plane: inclined.map(coefficients),
            ground_inliers: ground.map(inliers),
            inclined_inliers: inclined.map(inliers),
            ground_rms_m: ground.map(rms),
            inclined_rms_m: inclined.map(rms),
            ground_area_m2: ground.map(area),
            inclined_area_m2: inclined.map(area),
            ground_seen_to_m: Some(estimate.ground_seen_to_m).filter(|m| m.is_finite()),
            confidence: Some(estimate.confidence),
            confidence_reasons: Some(
                slope_ipc_types::confidence::names(estimate.confidence_reasons).collect(),
            ),
            ground_from_mount: Some(estimate.ground_from_mount),
            tracked: estimate.tracked.as_ref().map(TrackedJson::from),
            surfaces: Some(surfaces_of(estimate)),
        }
    }
}

/// The estimate's surfaces as its `Surfaces` message carries them.
fn surfaces_of(estimate: &Estimate) -> Vec<SurfaceJson> {
    let mut message = Surfaces::default();
    estimate.write_surfaces(&mut message);
    SurfaceJson::all(&message)
}

/// Stage timings serialised as `{"total": ms, "<stage>": ms, ...}` in
/// pipeline order.
#[derive(Debug, Clone, PartialEq)]
pub struct Timings(pub StageTimings);

impl Serialize for Timings {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.stages.len() + 1))?;
        map.serialize_entry("total", &self.0.total_ms)?;
        for (name, ms) in &self.0.stages {
            map.serialize_entry(name, ms)?;
        }
        map.end()
    }
}

/// The result of a frame the estimator ran on.
pub fn frame_result(index: u64, truth_deg: Option<f64>, estimate: &Estimate) -> FrameResult {
    let ok = estimate.status == EstimateStatus::Ok;
    let when_ok = |v: f64| (ok && v.is_finite()).then_some(v);
    FrameResult {
        index,
        status: estimate.status.name(),
        slope_deg: when_ok(estimate.slope_deg),
        std_deg: when_ok(estimate.slope_std_deg),
        distance_m: when_ok(estimate.distance_m),
        truth_deg,
        ms: Some(Timings(estimate.timings.clone())),
        error: (estimate.status == EstimateStatus::BadFrame)
            .then(|| "the estimator rejected the cloud (size mismatch or empty)".to_string()),
        details: FrameDetails::of(estimate),
    }
}
