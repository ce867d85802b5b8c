//! One recording under one method ([`MethodReport`], a JSON line) and its
//! numbers against the ground truth ([`summarize`]).

use std::collections::HashMap;

use serde::{Serialize, Serializer};
use slope_ipc_types::{EstimateStatus, SlopeMethod};

use super::frame::FrameResult;
use crate::demo::median;

/// An `ok` frame whose confidence is below this counts as low-confidence in
/// the summary.
pub const LOW_CONFIDENCE: f64 = 0.5;

/// Named medians, serialised as a JSON object in their order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StageMedians(pub Vec<(String, f64)>);

impl Serialize for StageMedians {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_map(self.0.iter().map(|(name, ms)| (name, ms)))
    }
}

/// The numbers of one recording under one method.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Frames evaluated.
    pub frames: usize,
    /// Frames with status `ok`.
    pub ok_frames: usize,
    /// Frames with status `ok` whose confidence is below [`LOW_CONFIDENCE`].
    pub low_confidence_frames: usize,
    /// Median signed slope of the `ok` frames, degrees.
    pub median_slope_deg: Option<f64>,
    /// Median of `|slope_deg|` over the `ok` frames, degrees.
    pub median_abs_slope_deg: Option<f64>,
    /// `|median_abs_slope_deg - truth_deg|`; `None` without truth.
    pub abs_error_deg: Option<f64>,
    /// Median over the `ok` frames with truth of `| |slope_deg| - truth |`.
    pub median_frame_error_deg: Option<f64>,
    /// Median total processing time of the frames the estimator ran on.
    pub median_ms: Option<f64>,
    /// Median time of each stage over the frames it ran in, pipeline order.
    pub median_stage_ms: StageMedians,
    /// Frames per status other than `ok`.
    pub not_ok: StatusCounts,
}

/// Status name and count, serialised as a JSON object.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StatusCounts(pub Vec<(&'static str, usize)>);

impl Serialize for StatusCounts {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_map(self.0.iter().map(|(name, count)| (name, count)))
    }
}

/// One recording under one method: the JSON object of one output line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MethodReport {
    /// The recording directory as given on the command line.
    pub recording: String,
    #[serde(serialize_with = "method_name")]
    pub method: SlopeMethod,
    /// Median of the evaluated frames' truths; `None` without truth.
    pub truth_deg: Option<f64>,
    pub estimates: Vec<FrameResult>,
    pub summary: Summary,
}

fn method_name<S: Serializer>(method: &SlopeMethod, serializer: S) -> Result<S::Ok, S::Error> {
    serializer.serialize_str(method.name())
}

impl MethodReport {
    /// The report of `frames`; the truth and the summary are computed here.
    pub fn new(recording: String, method: SlopeMethod, estimates: Vec<FrameResult>) -> Self {
        let mut truths: Vec<f64> = estimates.iter().filter_map(|f| f.truth_deg).collect();
        let truth_deg = median(&mut truths);
        let summary = summarize(&estimates, truth_deg);
        Self {
            recording,
            method,
            truth_deg,
            estimates,
            summary,
        }
    }
}

/// The summary of `frames` against the recording's `truth_deg`.
pub fn summarize(frames: &[FrameResult], truth_deg: Option<f64>) -> Summary {
    let ok: Vec<&FrameResult> = frames.iter().filter(|f| f.status == "ok").collect();
    let mut slopes: Vec<f64> = ok.iter().filter_map(|f| f.slope_deg).collect();
    let mut magnitudes: Vec<f64> = slopes.iter().map(|s| s.abs()).collect();
    let mut frame_errors: Vec<f64> = ok
        .iter()
        .filter_map(|f| Some((f.slope_deg?.abs() - f.truth_deg?).abs()))
        .collect();
    let median_abs_slope_deg = median(&mut magnitudes);
    let mut totals: Vec<f64> = frames
        .iter()
        .filter_map(|f| f.ms.as_ref().map(|t| t.0.total_ms))
        .collect();

    let low_confidence_frames = ok
        .iter()
        .filter(|f| f.details.confidence.is_some_and(|c| c < LOW_CONFIDENCE))
        .count();

    Summary {
        frames: frames.len(),
        ok_frames: ok.len(),
        low_confidence_frames,
        median_slope_deg: median(&mut slopes),
        median_abs_slope_deg,
        abs_error_deg: median_abs_slope_deg
            .zip(truth_deg)
            .map(|(m, t)| (m - t).abs()),
        median_frame_error_deg: median(&mut frame_errors),
        median_ms: median(&mut totals),
        median_stage_ms: stage_medians(frames),
        not_ok: status_counts(frames),
    }
}

/// The median time of each stage over the frames it ran in, in the order
/// the stages first appear (pipeline order).
fn stage_medians(frames: &[FrameResult]) -> StageMedians {
    let mut stage_names: Vec<&'static str> = Vec::new();
    let mut stage_times: HashMap<&'static str, Vec<f64>> = HashMap::new();
    for timings in frames.iter().filter_map(|f| f.ms.as_ref()) {
        for &(name, ms) in &timings.0.stages {
            if !stage_names.contains(&name) {
                stage_names.push(name);
            }
            stage_times.entry(name).or_default().push(ms);
        }
    }
    let median_stage_ms = stage_names
        .iter()
        .filter_map(|name| {
            let ms = median(stage_times.get_mut(name)?)?;
            Some((name.to_string(), ms))
        })
        .collect();
    StageMedians(median_stage_ms)
}

/// How many frames have each status other than `ok`, in the order of
/// [`EstimateStatus::ALL`]; statuses no frame has are left out.
fn status_counts(frames: &[FrameResult]) -> StatusCounts {
    let not_ok = EstimateStatus::ALL
        .into_iter()
        .filter(|s| *s != EstimateStatus::Ok)
        .map(|s| {
            (
                s.name(),
                frames.iter().filter(|f| f.status == s.name()).count(),
            )
        })
        .filter(|(_, count)| *count > 0)
        .collect();
    StatusCounts(not_ok)
}
