//! The initial centres, farthest first (paper 3.1).

use nalgebra::Vector3;

use super::{cosine_distance, CosineKmeans};

impl CosineKmeans {
    /// Up to `k` initial centres, farthest first: the unit vector nearest
    /// the mean direction, then each time the vector farthest (cosine
    /// distance) from its nearest centre so far; fewer when every vector
    /// coincides with a centre. `unit` must not be empty.
    pub(super) fn farthest_first_centres(&self, k: usize) -> Option<Vec<Vector3<f64>>> {
        let mean = self.unit.iter().sum::<Vector3<f64>>();
        let first = match mean.try_normalize(1e-12) {
            Some(m) => self.argmin_distance(&m),
            None => 0,
        };
        let mut centres = vec![self.unit[first]];
        let mut nearest: Vec<f64> = self
            .unit
            .iter()
            .map(|u| cosine_distance(u, &centres[0]))
            .collect();
        while centres.len() < k {
            let (far, &d) = nearest
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))?;
            if d <= 0.0 {
                break; // every vector coincides with a centre
            }
            let c = self.unit[far];
            for (nd, u) in nearest.iter_mut().zip(&self.unit) {
                *nd = nd.min(cosine_distance(u, &c));
            }
            centres.push(c);
        }
        Some(centres)
    }

    /// The first unit vector nearest (cosine distance) to `target`.
    fn argmin_distance(&self, target: &Vector3<f64>) -> usize {
        let mut distances = self
            .unit
            .iter()
            .map(|u| cosine_distance(u, target))
            .enumerate();
        let Some(mut best) = distances.next() else {
            return 0;
        };
        for (j, d) in distances {
            if d.total_cmp(&best.1).is_lt() {
                best = (j, d);
            }
        }
        best.0
    }
}
