//! The filter's parameters.

use super::MAX_NEIGHBOURS;
use crate::validate::{at_least, check, non_negative, InvalidValue};
use serde::{Deserialize, Serialize};

/// Statistical outlier removal (`statistical_outlier/`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutlierConfig {
    pub enabled: bool,
    /// m: neighbours whose mean distance is the point's statistic (paper: 20).
    pub neighbours: usize,
    /// alpha: drop points beyond mean + alpha * std (paper: 2).
    pub std_ratio: f64,
    /// Neighbours from the pixel grid (ours) or a k-d tree over the whole
    /// cloud (the paper, `literal/knn_outlier.rs`).
    pub neighbourhood: crate::literal::OutlierNeighbourhood,
    /// The statistic of a pixel missing some of its m = 20 grid neighbours
    /// (grid neighbourhood only).
    pub fallback: Fallback,
    /// `[near, far]`, metres along the optical axis: points outside are no
    /// reading. Unset: the sensor's range
    /// ([`crate::sensor_noise::NoiseModel::depth_range_m`] of
    /// `selection.noise_model`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth_range_m: Option<[f64; 2]>,
}

/// What a pixel missing some of its 20 grid neighbours takes
/// (`outlier.fallback`; m = 20 only).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Fallback {
    /// The mean distance to the grid neighbours it has, with at least 10;
    /// else the exact window (the default; pipeline README, item 11).
    #[default]
    PresentNeighbours,
    /// The mean distance to its 20 nearest measured pixels of the 9x9
    /// window, exactly (the paper's statistic).
    ExactWindow,
}

impl Default for OutlierConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            neighbours: 20,
            std_ratio: 2.0,
            neighbourhood: crate::literal::OutlierNeighbourhood::Grid,
            fallback: Fallback::PresentNeighbours,
            depth_range_m: None,
        }
    }
}

impl OutlierConfig {
    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), InvalidValue> {
        at_least("neighbours", self.neighbours, 1)?;
        check(
            self.neighbours <= MAX_NEIGHBOURS,
            "neighbours",
            self.neighbours,
            "must be at most 48 (the 7x7 pixel window)",
        )?;
        non_negative("std_ratio", self.std_ratio)?;
        if let Some([near, far]) = self.depth_range_m {
            check(
                near.is_finite() && far.is_finite() && near >= 0.0 && far > near,
                "depth_range_m",
                format!("[{near}, {far}]"),
                "must be [near, far] in metres with 0 <= near < far",
            )?;
        }
        Ok(())
    }
}
