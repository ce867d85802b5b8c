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
//! normals, which the compiler vectorises: with 2-4 centres (the default
//! is 3) all of them per normal in one pass, the normal loaded once and
//! its best kept in registers; with more, one centre at a time over all
//! normals. Each cluster's sum is kept in fixed point (`i64` multiples
//! of `2^-36` of the `f64` unit vectors), exact whatever the order of its
//! additions, so the update step moves only the normals whose label
//! changed (found a block of 32 labels at a time) from one sum to the
//! other (after the first iteration a few percent of them) instead of
//! summing every cluster afresh, and gets the same sums; centres and spreads stay `f64`. Normals of one plane
//! differ from their centres by degrees, dot products by 1e-2 to 1e-4,
//! against `f32` rounding of 6e-8: a label can change only for a normal
//! equidistant from two centres to that precision.
//!
//! One concern per file: `init.rs` (the initial centres, farthest first),
//! `lloyd.rs` (the Lloyd iterations and when they have converged),
//! `assign.rs` (the `f32` assignment step and the fixed-point cluster sums),
//! `dominant.rs` (the dominant cluster, its spread, and the clusters merged
//! into it), `config.rs` (the parameters), `tests.rs`.

mod assign;
mod config;
mod dominant;
mod init;
mod lloyd;

use nalgebra::Vector3;

pub use config::KmeansConfig;
pub use lloyd::CONVERGED_DEG;

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
    /// Each unit vector's cluster (`NO_LABEL` before the first
    /// assignment), as the assignment step writes it.
    labels: Vec<u32>,
    /// `f32` copies of `unit`'s coordinates, and per normal the best dot
    /// product and centre of the assignment step.
    ux: Vec<f32>,
    uy: Vec<f32>,
    uz: Vec<f32>,
    best_dot: Vec<f32>,
    best: Vec<u32>,
    /// `unit` in fixed point (`assign.rs`), and per cluster the sum of its
    /// members in fixed point and their count.
    fixed: Vec<[i64; 3]>,
    sums: Vec<([i64; 3], usize)>,
}

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
        self.labels.clear();
        self.labels.resize(n, assign::NO_LABEL);
        self.load_copies();
        let (counts, iterations) = self.lloyd(&mut centres, max_iterations);
        Some(self.keep_dominant(centres, counts, iterations, merge_spread_ratio))
    }

    /// `unit`: the finite, non-zero vectors of `normals`, normalised.
    fn load_units(&mut self, normals: &[Vector3<f64>]) {
        self.unit.clear();
        self.unit.reserve(normals.len());
        self.unit.extend(
            normals
                .iter()
                .filter(|n| n.iter().all(|c| c.is_finite()))
                .filter_map(|n| n.try_normalize(1e-12)),
        );
    }

    /// The unit vectors of cluster `cluster` from the last call.
    pub fn members(&self, cluster: usize) -> impl Iterator<Item = &Vector3<f64>> + '_ {
        self.unit
            .iter()
            .zip(&self.labels)
            .filter(move |(_, &l)| l as usize == cluster)
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
            .filter(move |(_, &l)| clustering.kept.contains(&(l as usize)))
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
            usable
                && labels
                    .next()
                    .is_some_and(|&l| clustering.kept.contains(&(l as usize)))
        })
    }
}

#[cfg(test)]
mod tests;
