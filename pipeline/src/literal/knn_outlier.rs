//! Stage 1 as the paper (and PCL's `StatisticalOutlierRemoval`) runs it:
//! each measured point's statistic is the mean distance to its `m` nearest
//! neighbours among *all* measured points, found with a k-d tree (kiddo);
//! points whose statistic exceeds `mean + alpha * std` over the cloud are
//! dropped (the paper's formulas: population mean and standard deviation).
//! A point has no neighbours but the others: the query asks for `m + 1`
//! and skips the nearest, the point itself (a duplicate point counts as a
//! neighbour at distance 0, as in PCL).

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use serde::{Deserialize, Serialize};

use crate::cloud::{is_measured, CloudView};
use crate::statistical_outlier::{OutlierConfig, OutlierStats};

/// Where the outlier filter takes a point's neighbours from
/// (`outlier.neighbourhood`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OutlierNeighbourhood {
    /// The grid-nearest pixels (`statistical_outlier/`, ours).
    #[default]
    Grid,
    /// The m nearest points of the whole cloud from a k-d tree (the paper).
    KdTree,
}

/// Reusable buffers of the k-d tree filter.
#[derive(Debug, Default, Clone)]
pub struct KnnOutlierFilter {
    entries: Vec<[f64; 3]>,
    pixels: Vec<usize>,
    mean_distance: Vec<f64>,
}

impl KnnOutlierFilter {
    pub fn new() -> Self {
        Self::default()
    }

    /// The statistic of each measured point of the last call, in pixel
    /// order of the measured points, metres.
    pub fn mean_distances(&self) -> &[f64] {
        &self.mean_distance
    }

    /// Runs the filter: `keep` is resized to the cloud, true for every
    /// measured point that survives. With fewer than `m + 1` measured
    /// points every point uses all the others.
    pub fn filter(
        &mut self,
        cloud: &CloudView<'_>,
        config: &OutlierConfig,
        keep: &mut Vec<bool>,
    ) -> OutlierStats {
        keep.clear();
        keep.resize(cloud.points.len(), false);
        self.gather_measured(cloud);
        let n = self.entries.len();
        // A lone point has no neighbour: isolated, dropped.
        let m = config.neighbours.max(1).min(n.saturating_sub(1));
        let (Some(k), Ok(tree)) = (
            std::num::NonZero::new(m + 1).filter(|_| m >= 1),
            ImmutableKdTree::<f64, 3>::new_from_slice(&self.entries),
        ) else {
            return OutlierStats {
                removed: n,
                ..OutlierStats::default()
            };
        };
        self.fill_mean_distances(&tree, k, m);
        let count = n as f64;
        let mean = self.mean_distance.iter().sum::<f64>() / count;
        let var = self
            .mean_distance
            .iter()
            .map(|d| (d - mean).powi(2))
            .sum::<f64>()
            / count;
        let threshold = mean + config.std_ratio * var.sqrt();
        let kept = self.mark_kept(threshold, keep);
        OutlierStats {
            mean_distance_m: mean,
            std_distance_m: var.sqrt(),
            threshold_m: threshold,
            kept,
            removed: n - kept,
        }
    }

    /// `entries` and `pixels`: the coordinates and pixel index of every
    /// measured point of `cloud`, in pixel order; `mean_distance` emptied.
    fn gather_measured(&mut self, cloud: &CloudView<'_>) {
        self.entries.clear();
        self.pixels.clear();
        self.mean_distance.clear();
        for (i, p) in cloud.points.iter().enumerate() {
            if is_measured(p) {
                self.entries
                    .push([f64::from(p.x_m), f64::from(p.y_m), f64::from(p.z_m)]);
                self.pixels.push(i);
            }
        }
    }

    /// `mean_distance`: for each entry, the mean distance to its `m`
    /// nearest neighbours, from the `k = m + 1` nearest in `tree` (the
    /// nearest, the point itself, skipped).
    fn fill_mean_distances(
        &mut self,
        tree: &ImmutableKdTree<f64, 3>,
        k: std::num::NonZero<usize>,
        m: usize,
    ) {
        for p in &self.entries {
            let nn = tree
                .query(p)
                .nearest_n::<SquaredEuclidean<f64>>(k)
                .execute();
            let sum: f64 = nn.iter().skip(1).map(|q| q.distance.sqrt()).sum();
            self.mean_distance.push(sum / m as f64);
        }
    }

    /// Marks in `keep` the pixels whose statistic is at most `threshold`;
    /// returns how many.
    fn mark_kept(&self, threshold: f64, keep: &mut [bool]) -> usize {
        let mut kept = 0;
        for (&pixel, &d) in self.pixels.iter().zip(&self.mean_distance) {
            if d <= threshold {
                keep[pixel] = true;
                kept += 1;
            }
        }
        kept
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::{Scene, SceneCloud};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use slope_ipc_types::CloudPoint;

    /// The oracle: every pair's distance, sorted, the m smallest summed.
    fn brute_force_kept(points: &[[f64; 3]], m: usize, alpha: f64) -> Vec<bool> {
        let stat: Vec<f64> = points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let mut d: Vec<f64> = points
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != i)
                    .map(|(_, q)| {
                        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2))
                            .sqrt()
                    })
                    .collect();
                d.sort_by(f64::total_cmp);
                d[..m].iter().sum::<f64>() / m as f64
            })
            .collect();
        let n = stat.len() as f64;
        let mean = stat.iter().sum::<f64>() / n;
        let std = (stat.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n).sqrt();
        stat.iter().map(|&d| d <= mean + alpha * std).collect()
    }

    /// A noisy ramp scene (40 x 30 pixels) plus 40 flying pixels and some
    /// holes: the same kept set as the brute-force filter, point for point.
    #[test]
    fn kept_set_equals_brute_force() {
        let mut cloud = SceneCloud::render(&Scene::ramp(16.0), 40, 30, 0.004, 5);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for _ in 0..40 {
            let i = rng.random_range(0..cloud.points.len());
            let p = &mut cloud.points[i];
            p.z_m *= rng.random_range(0.6..1.4);
        }
        for _ in 0..30 {
            let i = rng.random_range(0..cloud.points.len());
            cloud.points[i] = CloudPoint::INVALID;
        }
        let view = cloud.view();
        let pts = cloud.measured_points();
        let pixels: Vec<usize> = (0..cloud.points.len())
            .filter(|&i| is_measured(&cloud.points[i]))
            .collect();
        for (m, alpha) in [(20, 2.0), (5, 1.0)] {
            let config = OutlierConfig {
                neighbours: m,
                std_ratio: alpha,
                ..OutlierConfig::default()
            };
            let mut keep = Vec::new();
            let stats = KnnOutlierFilter::new().filter(&view, &config, &mut keep);
            let oracle = brute_force_kept(&pts, m, alpha);
            let ours: Vec<bool> = pixels.iter().map(|&i| keep[i]).collect();
            assert_eq!(ours, oracle, "m {m}");
            // Something was dropped (the flying pixels), not everything.
            assert!(stats.removed > 10 && stats.kept > 1000, "{stats:?}");
            assert_eq!(keep.iter().filter(|&&k| k).count(), stats.kept);
        }
    }

    #[test]
    fn tiny_clouds_do_not_panic() {
        let cloud = SceneCloud::render(&Scene::wall_facing(2.0), 3, 1, 0.0, 0);
        let mut keep = Vec::new();
        let stats =
            KnnOutlierFilter::new().filter(&cloud.view(), &OutlierConfig::default(), &mut keep);
        // Three collinear, evenly spaced points: the middle one is nearer
        // its two neighbours (mean) than the ends, all within 2 std.
        assert_eq!(stats.kept, 3);
        let one = SceneCloud::render(&Scene::wall_facing(2.0), 1, 1, 0.0, 0);
        let stats =
            KnnOutlierFilter::new().filter(&one.view(), &OutlierConfig::default(), &mut keep);
        assert_eq!((stats.kept, stats.removed), (0, 1));
    }
}
