//! Stage 4 as the paper runs it (PCL's `NormalEstimation` with
//! `setKSearch(100)`): each point's normal is the smallest eigenvector of
//! the covariance `1/K sum (p - mean)(p - mean)^T` of exactly its K nearest
//! neighbours (the point itself included, as PCL), found with a k-d tree
//! (kiddo) over the plane's points, oriented towards the viewpoint
//! (`n . (V - p) > 0`). With `min_patch_radius_m > 0` (one of our changes,
//! normally with `normals.rs`'s windows) the neighbourhood is every point
//! within that radius when they are more than K. `interior_only` does not
//! apply here (a k-d tree neighbourhood has no "first window").

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::cloud::CloudView;
use crate::normals::{orient, NormalsConfig};
use crate::plane_fit::smallest_eigenvector;

/// Where a point's normal takes its neighbours from
/// (`normals.neighbourhood`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NormalsNeighbourhood {
    /// The smallest pixel window with at least K of the plane's points,
    /// from summed-area tables (`normals.rs`, ours).
    #[default]
    Window,
    /// Exactly the K nearest points from a k-d tree (the paper).
    KdTree,
}

/// Reusable buffers of the k-d tree normals.
#[derive(Debug, Default, Clone)]
pub struct KnnNormalEstimator {
    entries: Vec<[f64; 3]>,
    normals: Vec<Vector3<f64>>,
}

impl KnnNormalEstimator {
    pub fn new() -> Self {
        Self::default()
    }

    /// Normals of `members` (pixel indices into `cloud`), each from its K
    /// nearest points among `support`; aligned with `members`, NaN where a
    /// point has no reading or a degenerate neighbourhood.
    pub fn estimate(
        &mut self,
        cloud: &CloudView<'_>,
        members: &[u32],
        support: &[u32],
        config: &NormalsConfig,
        viewpoint: &Vector3<f64>,
    ) -> &[Vector3<f64>] {
        let nan = Vector3::repeat(f64::NAN);
        self.normals.clear();
        self.normals.resize(members.len(), nan);
        self.entries.clear();
        self.entries.extend(
            support
                .iter()
                .filter_map(|&i| cloud.point(i as usize))
                .map(|p| [p.x, p.y, p.z]),
        );
        let k = config.neighbours.max(3).min(self.entries.len());
        let (Some(k_nz), Ok(tree)) = (
            std::num::NonZero::new(k).filter(|_| k >= 3),
            ImmutableKdTree::<f64, 3>::new_from_slice(&self.entries),
        ) else {
            return &self.normals;
        };
        let r2 = config.min_patch_radius_m.powi(2);
        let mut neighbours: Vec<usize> = Vec::new();
        for (slot, &pixel) in members.iter().enumerate() {
            let Some(p) = cloud.point(pixel as usize) else {
                continue;
            };
            let query = [p.x, p.y, p.z];
            neighbours.clear();
            if r2 > 0.0 {
                let within = tree
                    .query(&query)
                    .within::<SquaredEuclidean<f64>>(r2)
                    .execute();
                neighbours.extend(within.iter().map(|n| n.item as usize));
            }
            if neighbours.len() < k {
                neighbours.clear();
                let nn = tree
                    .query(&query)
                    .nearest_n::<SquaredEuclidean<f64>>(k_nz)
                    .execute();
                neighbours.extend(nn.iter().map(|n| n.item as usize));
            }
            if let Some(n) = pca_normal(&self.entries, &neighbours) {
                self.normals[slot] = orient(n, &p, viewpoint);
            }
        }
        &self.normals
    }
}

/// The smallest eigenvector of the covariance of `points[indices]`; `None`
/// when the middle eigenvalue vanishes too (the points lie on a line).
fn pca_normal(points: &[[f64; 3]], indices: &[usize]) -> Option<Vector3<f64>> {
    if indices.len() < 3 {
        return None;
    }
    let v = |i: usize| Vector3::from(points[i]);
    let mean = indices.iter().map(|&i| v(i)).sum::<Vector3<f64>>() / indices.len() as f64;
    let mut cov = Matrix3::zeros();
    for &i in indices {
        let q = v(i) - mean;
        cov += q * q.transpose();
    }
    cov /= indices.len() as f64;
    let (n, smallest) = smallest_eigenvector(&cov)?;
    // The other two eigenvalues sum to trace - smallest; the middle one is
    // at most the largest, so a middle eigenvalue of 0 leaves
    // `|cov|^2 = largest^2`, i.e. the Frobenius norm equals the trace.
    let trace = cov.trace();
    let rest = trace - smallest;
    let frobenius2 = cov.norm_squared() - smallest * smallest;
    (rest > 0.0 && frobenius2 < rest * rest * (1.0 - 1e-9)).then_some(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::{Scene, SceneCloud};
    use nalgebra::SymmetricEigen;

    /// Oracle: the K nearest by a full sort of all distances, covariance,
    /// nalgebra's symmetric eigen-decomposition; `None` when the K-th and
    /// the (K+1)-th distance tie (the K nearest are not one set).
    fn brute_force_normal(
        points: &[Vector3<f64>],
        p: &Vector3<f64>,
        k: usize,
    ) -> Option<Vector3<f64>> {
        let mut by_distance: Vec<&Vector3<f64>> = points.iter().collect();
        by_distance.sort_by(|a, b| (*a - p).norm_squared().total_cmp(&(*b - p).norm_squared()));
        let d2 = |q: &Vector3<f64>| (q - p).norm_squared();
        if d2(by_distance[k - 1]) == d2(by_distance[k]) {
            return None;
        }
        let nearest = &by_distance[..k];
        let mean = nearest.iter().copied().sum::<Vector3<f64>>() / k as f64;
        let cov = nearest
            .iter()
            .map(|q| (*q - mean) * (*q - mean).transpose())
            .sum::<Matrix3<f64>>()
            / k as f64;
        let eig = SymmetricEigen::new(cov);
        let i = eig.eigenvalues.imin();
        let n = eig.eigenvectors.column(i).into_owned();
        Some(orient(n, p, &Vector3::zeros()))
    }

    /// Every normal of a noisy ramp scene (both surfaces, their junction
    /// included) equals the brute-force kNN + PCA normal to 1e-9, except
    /// where millimetre depths make the 100th and 101st distances tie
    /// exactly (1 point of 1728 here; either is a right answer).
    #[test]
    fn equals_brute_force_knn_pca() {
        let cloud = SceneCloud::render(&Scene::ramp(16.0), 48, 36, 0.003, 4);
        let view = cloud.view();
        let members: Vec<u32> = (0..cloud.points.len() as u32)
            .filter(|&i| cloud.points[i as usize].is_valid())
            .collect();
        let points: Vec<Vector3<f64>> = members
            .iter()
            .filter_map(|&i| view.point(i as usize))
            .collect();
        let config = NormalsConfig {
            neighbours: 100,
            min_patch_radius_m: 0.0,
            ..NormalsConfig::default()
        };
        let mut est = KnnNormalEstimator::new();
        let normals = est.estimate(&view, &members, &members, &config, &Vector3::zeros());
        assert_eq!(normals.len(), members.len());
        let mut ties = 0;
        for (n, p) in normals.iter().zip(&points) {
            assert!(n.dot(&(-p)) > 0.0, "towards the camera");
            match brute_force_normal(&points, p, 100) {
                Some(oracle) => assert!((n - oracle).norm() < 1e-9, "{n:?} vs {oracle:?}"),
                None => ties += 1,
            }
        }
        assert!(ties <= 5, "{ties} ties");
    }

    /// Normals for a sparse subset take their neighbours from the support;
    /// with a patch radius wider than the K-patch, every point within it.
    #[test]
    fn support_and_patch_radius() {
        let cloud = SceneCloud::render(&Scene::wall_facing(2.0), 60, 40, 0.0, 0);
        let view = cloud.view();
        let all: Vec<u32> = (0..2400).collect();
        let members = [30 * 60 + 30, 20 * 60 + 10];
        let mut est = KnnNormalEstimator::new();
        let flat = NormalsConfig {
            neighbours: 20,
            min_patch_radius_m: 0.1,
            ..NormalsConfig::default()
        };
        let normals = est
            .estimate(&view, &members, &all, &flat, &Vector3::zeros())
            .to_vec();
        for n in normals {
            // The wall faces the camera: normal -z (towards the origin).
            assert!((n - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-3, "{n:?}");
        }
        // A support of one row: collinear, no normal.
        let row: Vec<u32> = (0..60).collect();
        let n = est.estimate(&view, &[5], &row, &flat, &Vector3::zeros())[0];
        assert!(n.x.is_nan(), "{n:?}");
    }
}
