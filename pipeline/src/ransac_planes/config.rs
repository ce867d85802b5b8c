//! [`RansacConfig`]: the parameters of the plane search.

use serde::{Deserialize, Serialize};

use super::MAX_PLANES;
use crate::validate::{
    angle, at_least, check, count_in, fraction, non_negative, positive, InvalidValue,
};

/// RANSAC plane segmentation .
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RansacConfig {
    /// A point within this distance of a plane is an inlier, metres...
    pub distance_threshold_m: f64,
    /// ...or within this times its squared depth (metres per square metre),
    /// whichever is larger: depth noise and quantisation grow with the
    /// square of the depth (a Kinect v1 quantises 5 m to 7 cm terraces).
    /// Without it (0, the paper) RANSAC takes a Kinect v1's depth terraces
    /// far away for planes (pipeline README, ablation, change 2b).
    pub distance_threshold_per_m2: f64,
    /// Hypotheses drawn per plane at most (fewer when `confidence` is reached).
    pub max_iterations: usize,
    /// Probability of drawing at least one all-inlier sample, which sets the
    /// adaptive iteration count.
    pub confidence: f64,
    /// Planes are found on every `sample_stride_px`-th pixel in both
    /// directions (the sample grid); at the end every pixel within the
    /// threshold goes to the nearest of the planes that took the sample
    /// points around it (its 3x3 sample cells).
    pub sample_stride_px: usize,
    /// A sample point whose local normal is further than this from the
    /// hypothesis' normal is not its inlier, degrees; 0 or >= 90 disables.
    pub normal_threshold_deg: f64,
    /// A plane's region on the sample grid must stand for at least this
    /// many pixels (`min_plane_points / stride^2` sample points), else its
    /// sample inliers are set aside as a failure (the 9th failure ends the
    /// search); planes with fewer pixels in the end are dropped.
    pub min_plane_points: usize,
    /// Stop when fewer than this fraction of the sample points is free
    /// (neither in a plane nor set aside by a failure).
    pub min_remaining_fraction: f64,
    /// Stop after this many planes (at most 65,535). Unset, the proposal's
    /// own cap ([`crate::segmentation::Proposal::max_planes`]: 16 for the
    /// cells, which propose the largest regions first; 24 for the
    /// sequential extraction, which does not find planes largest first).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_planes: Option<usize>,
    /// Score on the sample grid (ours, this module) or on every point (the
    /// paper, `literal/every_point_ransac.rs`).
    pub scoring: crate::literal::RansacScoring,
}

impl Default for RansacConfig {
    fn default() -> Self {
        Self {
            distance_threshold_m: 0.02,
            distance_threshold_per_m2: 0.003,
            max_iterations: 500,
            confidence: 0.999,
            sample_stride_px: 4,
            normal_threshold_deg: 30.0,
            min_plane_points: 800,
            min_remaining_fraction: 0.03,
            max_planes: None,
            scoring: crate::literal::RansacScoring::SampleGrid,
        }
    }
}

impl RansacConfig {
    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), InvalidValue> {
        positive("distance_threshold_m", self.distance_threshold_m)?;
        non_negative("distance_threshold_per_m2", self.distance_threshold_per_m2)?;
        count_in("max_iterations", self.max_iterations, 1, 10_000)?;
        check(
            self.confidence > 0.0 && self.confidence < 1.0,
            "confidence",
            self.confidence,
            "must be in the open interval (0, 1)",
        )?;
        at_least("sample_stride_px", self.sample_stride_px, 1)?;
        angle("normal_threshold_deg", self.normal_threshold_deg)?;
        at_least("min_plane_points", self.min_plane_points, 3)?;
        fraction("min_remaining_fraction", self.min_remaining_fraction)?;
        let Some(max_planes) = self.max_planes else {
            return Ok(());
        };
        at_least("max_planes", max_planes, 1)?;
        check(
            max_planes <= MAX_PLANES,
            "max_planes",
            max_planes,
            "must be at most 65535",
        )
    }

    /// The plane cap: `max_planes`, else `unset` (the proposal's), at most
    /// [`MAX_PLANES`].
    pub fn plane_cap(&self, unset: usize) -> usize {
        self.max_planes.unwrap_or(unset).min(MAX_PLANES)
    }
}
