//! The Lloyd iterations: assign every normal, move every centre to its
//! members' mean direction, until converged.

use nalgebra::Vector3;

use super::{cosine_distance, CosineKmeans};

/// Lloyd iterations stop when no centre moves by more than this angle,
/// degrees: a hundredth of a degree, far below the spreads (degrees) and
/// the answer's resolution (the real frames' slopes are unchanged to the
/// digit, the simulated ramp16's median moves by 0.015 degrees).
pub const CONVERGED_DEG: f64 = 1e-2;

/// [`CONVERGED_DEG`] as a cosine distance, `1 - cos`.
pub(super) const CONVERGED_COSINE_DISTANCE: f64 = 1.523e-8;

impl CosineKmeans {
    /// Lloyd iterations from `centres` (moved in place) until converged or
    /// `max_iterations` (at least one) ran: `labels` holds each unit
    /// vector's cluster; returns the clusters' sizes and the iterations run.
    pub(super) fn lloyd(
        &mut self,
        centres: &mut [Vector3<f64>],
        max_iterations: usize,
    ) -> (Vec<usize>, usize) {
        let n = self.unit.len();
        let mut iterations = 0;
        let mut counts = vec![0usize; centres.len()];
        self.clear_sums(centres.len());
        for _ in 0..max_iterations.max(1) {
            iterations += 1;
            self.assign(centres);
            let changed = self.move_labels();
            let mut moved: f64 = 0.0;
            for (j, (c, count)) in centres.iter_mut().zip(&mut counts).enumerate() {
                *count = self.sums[j].1;
                if let Some(m) = self.cluster_sum(j).try_normalize(1e-12) {
                    moved = moved.max(cosine_distance(c, &m));
                    *c = m;
                }
            }
            // Converged: fewer than one in a thousand labels moved, or no
            // centre moved by more than CONVERGED_DEG (a population cut in
            // pieces trades a few labels back and forth for ever).
            if changed * 1000 <= n || moved <= CONVERGED_COSINE_DISTANCE {
                break;
            }
        }
        (counts, iterations)
    }
}
