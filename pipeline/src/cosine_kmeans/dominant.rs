//! The dominant (largest) cluster, its spread, and the clusters merged into
//! it (the addition in the module doc).

use nalgebra::Vector3;

use super::{Clustering, CosineKmeans};
use crate::cloud::angle_between_deg;

impl CosineKmeans {
    /// The clustering after the Lloyd iterations left `centres` of sizes
    /// `counts`: the largest cluster (the first of equals) is dominant, and
    /// every non-empty cluster whose centre is within `merge_spread_ratio`
    /// times the dominant cluster's spread of its centre is kept with it.
    pub(super) fn keep_dominant(
        &self,
        centres: Vec<Vector3<f64>>,
        counts: Vec<usize>,
        iterations: usize,
        merge_spread_ratio: f64,
    ) -> Clustering {
        let dominant = counts
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(&a.0)))
            .map_or(0, |(j, _)| j);
        let centre = centres[dominant];
        let spread_deg = self.spread_deg(dominant, &centre);
        let merge_deg = merge_spread_ratio * spread_deg;
        let kept = (0..centres.len())
            .filter(|&j| {
                j == dominant
                    || (counts[j] > 0 && angle_between_deg(&centres[j], &centre) <= merge_deg)
            })
            .collect();
        Clustering {
            centres,
            counts,
            dominant,
            kept,
            spread_deg,
            iterations,
        }
    }

    /// RMS angle, degrees, of the members of cluster `label` to `centre`
    /// (0 for an empty cluster).
    fn spread_deg(&self, label: usize, centre: &Vector3<f64>) -> f64 {
        let (mut sum_sq, mut count) = (0.0, 0usize);
        for (u, &l) in self.unit.iter().zip(&self.labels) {
            if l as usize == label {
                let a = angle_between_deg(u, centre);
                sum_sq += a * a;
                count += 1;
            }
        }
        (sum_sq / count.max(1) as f64).sqrt()
    }
}
