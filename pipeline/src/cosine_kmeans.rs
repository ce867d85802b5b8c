//! Stage 5, cosine k-means (paper 3.1): the normals of one plane are
//! clustered with the cosine distance `1 - cos(a, b)`; the initial centres
//! are picked one after another as far apart as possible (the first is the
//! normal nearest the mean direction, each next one maximises its cosine
//! distance to the nearest centre chosen so far); the dominant (largest)
//! cluster is kept and the rest dropped as outliers.
//!
//! **Addition.** k-means always returns k clusters, even when the normals of
//! a plane form one noisy population: then it cuts that population in
//! pieces, and keeping only the largest piece would bias the normal by about
//! one noise spread (degrees, on Kinect data). So a cluster whose centre is
//! within `merge_spread_ratio` times the dominant cluster's RMS angular
//! spread of the dominant centre is the same population and is kept with
//! it; clusters of genuinely different normals (edges, clutter, a
//! neighbouring plane) are many spreads away and are still dropped.
//!
//! **How it runs.** The assignment step (each normal to the centre with the
//! largest dot product) runs on an `f32` structure-of-arrays copy of the
//! normals, one centre at a time over all normals, which the compiler
//! vectorises; the update step sums each cluster's members in one pass over
//! the normals for all clusters (`f32` in 8 lanes over blocks of 256, added
//! up in `f64`); centres and spreads stay `f64`. Normals of one plane
//! differ from their centres by degrees, dot products by 1e-2 to 1e-4,
//! against `f32` rounding of 6e-8: a label can change only for a normal
//! equidistant from two centres to that precision.

use nalgebra::Vector3;

use crate::cloud::angle_between_deg;
use crate::validate::{at_least, non_negative, InvalidValue};
use serde::{Deserialize, Serialize};

/// The outcome of one clustering.
#[derive(Debug, Clone, PartialEq)]
pub struct Clustering {
    /// Unit centre of each cluster.
    pub centres: Vec<Vector3<f64>>,
    /// Members of each cluster.
    pub counts: Vec<usize>,
    /// Index of the largest cluster.
    pub dominant: usize,
    /// Clusters kept: the dominant one and those merged into it.
    pub kept: Vec<usize>,
    /// RMS angle of the dominant cluster's members to its centre, degrees.
    pub spread_deg: f64,
    /// Lloyd iterations run.
    pub iterations: usize,
}

/// Reusable buffers of the clustering.
#[derive(Debug, Default, Clone)]
pub struct CosineKmeans {
    unit: Vec<Vector3<f64>>,
    labels: Vec<usize>,
    /// `f32` copies of `unit`'s coordinates, and per normal the best dot
    /// product and centre of the assignment step.
    ux: Vec<f32>,
    uy: Vec<f32>,
    uz: Vec<f32>,
    best_dot: Vec<f32>,
    best: Vec<u32>,
    /// Per cluster, its sum and size, and its lane sums over one block of
    /// the update step.
    sums: Vec<(Vector3<f64>, usize)>,
    lanes: Vec<LaneSums>,
}

/// Lanes of the update step's `f32` sums. With `BLOCK`, it sets their
/// rounding, so changing either changes the results.
const LANES: usize = 8;
/// Normals per block of `f32` lane sums in the update step.
const BLOCK: usize = 256;

/// One cluster's `f32` sums and sizes of one block, lane by lane.
#[derive(Debug, Default, Clone, Copy)]
struct LaneSums {
    x: [f32; LANES],
    y: [f32; LANES],
    z: [f32; LANES],
    count: [u32; LANES],
}

impl LaneSums {
    /// Adds a member's coordinates to lane `l`.
    #[inline]
    fn add(&mut self, l: usize, x: f32, y: f32, z: f32) {
        self.x[l] += x;
        self.y[l] += y;
        self.z[l] += z;
        self.count[l] += 1;
    }
}

/// Lloyd iterations stop when no centre moves by more than this angle,
/// degrees: a hundredth of a degree, far below the spreads (degrees) and
/// the answer's resolution (the real frames' slopes are unchanged to the
/// digit, the simulated ramp16's median moves by 0.015 degrees).
pub const CONVERGED_DEG: f64 = 1e-2;

/// [`CONVERGED_DEG`] as a cosine distance, `1 - cos`.
const CONVERGED_COSINE_DISTANCE: f64 = 1.523e-8;

/// Cosine distance of two unit vectors.
#[inline]
pub fn cosine_distance(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    1.0 - a.dot(b)
}

impl CosineKmeans {
    pub fn new() -> Self {
        Self::default()
    }

    /// Clusters the finite, non-zero vectors of `normals` (others are
    /// ignored) into at most `k` clusters. `None` when none is usable.
    pub fn cluster(
        &mut self,
        normals: &[Vector3<f64>],
        k: usize,
        max_iterations: usize,
        merge_spread_ratio: f64,
    ) -> Option<Clustering> {
        self.load_units(normals);
        let n = self.unit.len();
        if n == 0 {
            return None;
        }
        let mut centres = self.farthest_first_centres(k.clamp(1, n))?;
        let k = centres.len();
        self.labels.clear();
        self.labels.resize(n, usize::MAX);
        self.load_f32();
        let (counts, iterations) = self.lloyd(&mut centres, max_iterations);
        let dominant = counts
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(&a.0)))
            .map_or(0, |(j, _)| j);
        let centre = centres[dominant];
        let spread_deg = self.spread_deg(dominant, &centre);
        let merge_deg = merge_spread_ratio * spread_deg;
        let kept = (0..k)
            .filter(|&j| {
                j == dominant
                    || (counts[j] > 0 && angle_between_deg(&centres[j], &centre) <= merge_deg)
            })
            .collect();
        Some(Clustering {
            centres,
            counts,
            dominant,
            kept,
            spread_deg,
            iterations,
        })
    }

    /// `unit`: the finite, non-zero vectors of `normals`, normalised.
    fn load_units(&mut self, normals: &[Vector3<f64>]) {
        self.unit.clear();
        self.unit.extend(
            normals
                .iter()
                .filter(|n| n.iter().all(|c| c.is_finite()))
                .filter_map(|n| n.try_normalize(1e-12)),
        );
    }

    /// Up to `k` initial centres, farthest first: the unit vector nearest
    /// the mean direction, then each time the vector farthest (cosine
    /// distance) from its nearest centre so far; fewer when every vector
    /// coincides with a centre. `unit` must not be empty.
    fn farthest_first_centres(&self, k: usize) -> Option<Vec<Vector3<f64>>> {
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

    /// Lloyd iterations from `centres` (moved in place) until converged or
    /// `max_iterations` (at least one) ran: `labels` holds each unit
    /// vector's cluster; returns the clusters' sizes and the iterations run.
    fn lloyd(
        &mut self,
        centres: &mut [Vector3<f64>],
        max_iterations: usize,
    ) -> (Vec<usize>, usize) {
        let n = self.unit.len();
        let mut iterations = 0;
        let mut counts = vec![0usize; centres.len()];
        for _ in 0..max_iterations.max(1) {
            iterations += 1;
            let mut changed = 0usize;
            self.assign(centres);
            for (label, &best) in self.labels.iter_mut().zip(&self.best) {
                let best = best as usize;
                changed += usize::from(*label != best);
                *label = best;
            }
            let mut moved: f64 = 0.0;
            self.cluster_sums(centres.len());
            for ((c, count), &(sum, members)) in centres.iter_mut().zip(&mut counts).zip(&self.sums)
            {
                *count = members;
                if let Some(m) = sum.try_normalize(1e-12) {
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

    /// RMS angle, degrees, of the members of cluster `label` to `centre`
    /// (0 for an empty cluster).
    fn spread_deg(&self, label: usize, centre: &Vector3<f64>) -> f64 {
        let (mut sum_sq, mut count) = (0.0, 0usize);
        for (u, &l) in self.unit.iter().zip(&self.labels) {
            if l == label {
                let a = angle_between_deg(u, centre);
                sum_sq += a * a;
                count += 1;
            }
        }
        (sum_sq / count.max(1) as f64).sqrt()
    }

    /// The unit vectors of cluster `cluster` from the last call.
    pub fn members(&self, cluster: usize) -> impl Iterator<Item = &Vector3<f64>> + '_ {
        self.unit
            .iter()
            .zip(&self.labels)
            .filter(move |(_, &l)| l == cluster)
            .map(|(u, _)| u)
    }

    /// The unit vectors of the kept clusters of `clustering` (the last call's).
    pub fn kept_members<'a>(
        &'a self,
        clustering: &'a Clustering,
    ) -> impl Iterator<Item = &'a Vector3<f64>> + 'a {
        self.unit
            .iter()
            .zip(&self.labels)
            .filter(move |(_, l)| clustering.kept.contains(l))
            .map(|(u, _)| u)
    }

    /// For each vector of `normals` (the slice given to the last
    /// [`Self::cluster`] call, which returned `clustering`), in order:
    /// whether it belongs to a kept cluster (`false` for one the clustering
    /// ignored: not finite or zero).
    pub fn kept_flags<'a>(
        &'a self,
        normals: &'a [Vector3<f64>],
        clustering: &'a Clustering,
    ) -> impl Iterator<Item = bool> + 'a {
        let mut labels = self.labels.iter();
        normals.iter().map(move |n| {
            let usable = n.iter().all(|c| c.is_finite()) && n.try_normalize(1e-12).is_some();
            usable && labels.next().is_some_and(|l| clustering.kept.contains(l))
        })
    }

    fn load_f32(&mut self) {
        self.ux.clear();
        self.uy.clear();
        self.uz.clear();
        for u in &self.unit {
            self.ux.push(u.x as f32);
            self.uy.push(u.y as f32);
            self.uz.push(u.z as f32);
        }
    }

    /// The assignment step: `best[i]` is the centre with the largest dot
    /// product with normal `i` (the smallest cosine distance; ties go to
    /// the lower index).
    fn assign(&mut self, centres: &[Vector3<f64>]) {
        let n = self.ux.len();
        self.best_dot.clear();
        self.best_dot.resize(n, f32::NEG_INFINITY);
        self.best.clear();
        self.best.resize(n, 0);
        let (ux, uy, uz) = (&self.ux[..n], &self.uy[..n], &self.uz[..n]);
        let (best_dot, best) = (&mut self.best_dot[..n], &mut self.best[..n]);
        for (j, c) in centres.iter().enumerate() {
            let (cx, cy, cz) = (c.x as f32, c.y as f32, c.z as f32);
            for i in 0..n {
                let d = ux[i] * cx + uy[i] * cy + uz[i] * cz;
                // Branch-free (clusters interleave: a branch mispredicts).
                let mask = u32::from(d > best_dot[i]).wrapping_neg();
                best[i] = (best[i] & !mask) | (j as u32 & mask);
                best_dot[i] = best_dot[i].max(d);
            }
        }
    }

    /// Sum and size of every cluster after the assignment step, into
    /// `sums`: `f32` sums in 8 lanes (normal `i` in lane `i % 8`) over
    /// blocks of 256 normals, each block's lanes added up in `f64`; one
    /// pass over the normals for all clusters. The lanes and blocks are
    /// kept as they are because they fix the `f32` rounding of the sums,
    /// hence the centres and the results: a simpler loop (one running sum,
    /// other lanes or blocks) changes them.
    fn cluster_sums(&mut self, k: usize) {
        // Labels are centre indices; `get_mut` below would skip others.
        debug_assert!(self.best.iter().all(|&b| (b as usize) < k));
        self.sums.clear();
        self.sums.resize(k, (Vector3::zeros(), 0));
        self.lanes.clear();
        self.lanes.resize(k, LaneSums::default());
        let n = self.best.len();
        for start in (0..n).step_by(BLOCK) {
            let end = (start + BLOCK).min(n);
            self.lanes.fill(LaneSums::default());
            let whole = start + (end - start) / LANES * LANES;
            let labels = self.best[start..whole].as_chunks::<LANES>().0;
            let xs = self.ux[start..whole].as_chunks::<LANES>().0;
            let ys = self.uy[start..whole].as_chunks::<LANES>().0;
            let zs = self.uz[start..whole].as_chunks::<LANES>().0;
            for (((b, x), y), z) in labels.iter().zip(xs).zip(ys).zip(zs) {
                for l in 0..LANES {
                    if let Some(s) = self.lanes.get_mut(b[l] as usize) {
                        s.add(l, x[l], y[l], z[l]);
                    }
                }
            }
            for i in whole..end {
                if let Some(s) = self.lanes.get_mut(self.best[i] as usize) {
                    s.add(i - whole, self.ux[i], self.uy[i], self.uz[i]);
                }
            }
            for ((total, count), s) in self.sums.iter_mut().zip(&self.lanes) {
                let sum = |s: &[f32; LANES]| s.iter().map(|&v| f64::from(v)).sum::<f64>();
                *total += Vector3::new(sum(&s.x), sum(&s.y), sum(&s.z));
                *count += s.count.iter().sum::<u32>() as usize;
            }
        }
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

/// Cosine k-means (`cosine_kmeans.rs`).
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
        at_least("clusters", self.clusters, 1)?;
        at_least("max_iterations", self.max_iterations, 1)?;
        non_negative("merge_spread_ratio", self.merge_spread_ratio)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn jitter(rng: &mut ChaCha8Rng, n: Vector3<f64>, deg: f64) -> Vector3<f64> {
        let s = deg.to_radians();
        (n + Vector3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        ))
        .normalize()
    }

    #[test]
    fn two_well_separated_clusters_are_found() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let a = Vector3::new(0.0, -1.0, -0.3).normalize();
        let b = Vector3::new(0.0, -0.2, -1.0).normalize();
        let mut normals: Vec<Vector3<f64>> = (0..700).map(|_| jitter(&mut rng, a, 2.0)).collect();
        normals.extend((0..300).map(|_| jitter(&mut rng, b, 2.0)));
        normals.push(Vector3::repeat(f64::NAN));
        let mut km = CosineKmeans::new();
        let c = km.cluster(&normals, 2, 50, 0.0).unwrap();
        assert_eq!(c.centres.len(), 2);
        let mut counts = c.counts.clone();
        counts.sort_unstable();
        assert_eq!(counts, vec![300, 700]);
        assert!(angle_between_deg(&c.centres[c.dominant], &a) < 0.5);
        // Every dominant member is one of the 700 around a.
        assert!(km
            .members(c.dominant)
            .all(|m| angle_between_deg(m, &a) < 5.0));
        assert_eq!(km.members(c.dominant).count(), 700);
    }

    #[test]
    fn farthest_first_puts_an_outlier_in_its_own_cluster() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let a = Vector3::new(0.3, -0.9, -0.2).normalize();
        let mut normals: Vec<Vector3<f64>> = (0..500).map(|_| jitter(&mut rng, a, 1.0)).collect();
        let outliers = [
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.9, 0.1, 0.1).normalize(),
        ];
        normals.extend(outliers);
        let mut km = CosineKmeans::new();
        let c = km.cluster(&normals, 2, 50, 0.0).unwrap();
        assert_eq!(c.counts[c.dominant], 500);
        assert!(km
            .members(c.dominant)
            .all(|m| angle_between_deg(m, &a) < 3.0));
    }

    #[test]
    fn one_noisy_population_is_not_cut_in_half() {
        // A single isotropic population around `a` plus a far cluster: with
        // k = 3 k-means splits the population; merging restores it and the
        // kept mean is unbiased, while the far cluster is still dropped.
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let a = Vector3::new(0.0, -0.9, -0.4).normalize();
        let far = Vector3::new(0.0, 0.0, -1.0);
        let mut normals: Vec<Vector3<f64>> = (0..3000).map(|_| jitter(&mut rng, a, 3.0)).collect();
        normals.extend((0..200).map(|_| jitter(&mut rng, far, 1.0)));
        let mut km = CosineKmeans::new();
        let split = km.cluster(&normals, 3, 50, 0.0).unwrap();
        let biased: Vector3<f64> = km.members(split.dominant).sum();
        assert!(split.counts[split.dominant] < 2900, "{:?}", split.counts);
        assert!(angle_between_deg(&biased, &a) > 0.3);
        let merged = km.cluster(&normals, 3, 50, 2.5).unwrap();
        let kept: Vec<Vector3<f64>> = km.kept_members(&merged).copied().collect();
        assert_eq!(kept.len(), 3000, "{:?} {:?}", merged.counts, merged.kept);
        let mean: Vector3<f64> = kept.iter().sum();
        assert!(
            angle_between_deg(&mean, &a) < 0.1,
            "{}",
            angle_between_deg(&mean, &a)
        );
    }

    #[test]
    fn convergence_tolerance_is_a_hundredth_of_a_degree() {
        let expected = 1.0 - CONVERGED_DEG.to_radians().cos();
        assert!((CONVERGED_COSINE_DISTANCE - expected).abs() < 1e-3 * expected);
    }

    #[test]
    fn degenerate_inputs() {
        let mut km = CosineKmeans::new();
        assert!(km.cluster(&[], 2, 10, 2.5).is_none());
        assert!(km.cluster(&[Vector3::zeros()], 2, 10, 2.5).is_none());
        let same = vec![Vector3::z(); 10];
        let c = km.cluster(&same, 3, 10, 2.5).unwrap();
        assert_eq!(c.centres.len(), 1);
        assert_eq!(c.counts, vec![10]);
        assert!((cosine_distance(&Vector3::x(), &Vector3::y()) - 1.0).abs() < 1e-15);
    }
}
