//! [`SegmentationConfig`]: which design proposes the planes, and the
//! parameters of the cell grid.

use serde::{Deserialize, Serialize};

use crate::validate::{angle, check, count_in, positive, InvalidValue};

/// How the planes of a frame are proposed before the RANSAC fit
/// (`segmentation.proposal`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Proposal {
    /// Planar cells of the pixel grid grown into regions, each region's
    /// plane fitted by RANSAC over its own points and flooded over its
    /// band (`segmentation/cells/`; the default).
    #[default]
    Cells,
    /// RANSAC extractions one after another on the sample grid, each plane
    /// the largest connected region of the best hypothesis's inliers
    /// (`ransac_planes/`; an option, which the ablation compares).
    Sequential,
}

impl Proposal {
    /// The plane cap when `ransac.max_planes` is unset. The cells fit their
    /// regions largest first, and 16 planes hold every surface the tests
    /// rely on; the sequential extraction does not find planes largest
    /// first (a 26-row riser strip is hard to hit on the sample grid) and
    /// needs 24 for the stair risers and the office's wall at every seed
    /// (pipeline README, "Mirror images give the same slope").
    pub fn max_planes(self) -> usize {
        match self {
            Self::Cells => 16,
            Self::Sequential => 24,
        }
    }
}

/// Plane segmentation: the proposal design and the cell grid's parameters.
/// `ransac.scoring = "every-point"` (the paper as written) ignores it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SegmentationConfig {
    pub proposal: Proposal,
    /// Side of a cell, pixels; rounded to a multiple of
    /// `ransac.sample_stride_px` (a cell is a block of sample cells).
    pub cell_size_px: usize,
    /// A cell's moments take every `cell_point_step_px`-th pixel of it in
    /// both directions.
    pub cell_point_step_px: usize,
    /// A cell is planar when the RMS distance of its points from their TLS
    /// plane is at most this times the inlier distance at its centroid.
    pub cell_rms_ratio: f64,
    /// A cell joins a neighbouring region when its normal is within this of
    /// the region's, degrees (and its centroid within the inlier distance
    /// of the region's plane).
    pub merge_angle_deg: f64,
}

impl Default for SegmentationConfig {
    fn default() -> Self {
        Self {
            proposal: Proposal::Cells,
            cell_size_px: 8,
            cell_point_step_px: 2,
            cell_rms_ratio: 0.5,
            merge_angle_deg: 20.0,
        }
    }
}

impl SegmentationConfig {
    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), InvalidValue> {
        count_in("cell_size_px", self.cell_size_px, 2, 64)?;
        count_in("cell_point_step_px", self.cell_point_step_px, 1, 8)?;
        check(
            self.cell_point_step_px <= self.cell_size_px,
            "cell_point_step_px",
            self.cell_point_step_px,
            "must be at most cell_size_px",
        )?;
        positive("cell_rms_ratio", self.cell_rms_ratio)?;
        angle("merge_angle_deg", self.merge_angle_deg)?;
        check(
            self.merge_angle_deg > 0.0 && self.merge_angle_deg < 90.0,
            "merge_angle_deg",
            self.merge_angle_deg,
            "must be in the open interval (0, 90)",
        )
    }
}
