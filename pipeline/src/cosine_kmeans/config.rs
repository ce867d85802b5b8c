//! The clustering's parameters.

use crate::validate::{count_in, non_negative, InvalidValue};
use serde::{Deserialize, Serialize};

/// Cosine k-means (`cosine_kmeans/`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct KmeansConfig {
    /// Clusters per plane; the largest is kept.
    pub clusters: usize,
    pub max_iterations: usize,
    /// Clusters whose centre is within this many RMS spreads of the dominant
    /// cluster's centre are kept with it (one population k-means cut up);
    /// 0 keeps the dominant cluster only, as the paper.
    pub merge_spread_ratio: f64,
}

impl Default for KmeansConfig {
    fn default() -> Self {
        Self {
            clusters: 3,
            max_iterations: 30,
            merge_spread_ratio: 2.5,
        }
    }
}

impl KmeansConfig {
    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), InvalidValue> {
        count_in("clusters", self.clusters, 1, 16)?;
        count_in("max_iterations", self.max_iterations, 1, 1000)?;
        non_negative("merge_spread_ratio", self.merge_spread_ratio)
    }
}
