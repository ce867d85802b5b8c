//! The k-d tree fallback: the exact K nearest neighbours of the points no
//! pixel window could serve.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::Vector3;

use super::{moments, normal_from_sums, orient, NormalEstimator, CHANNELS};
use crate::cloud::CloudView;

impl NormalEstimator {
    /// Exact K nearest neighbours from a k-d tree for the points the windows
    /// could not serve; returns how many stayed undefined.
    pub(super) fn tree_normals(
        &mut self,
        cloud: &CloudView<'_>,
        members: &[u32],
        support: &[u32],
        k: usize,
        viewpoint: &Vector3<f64>,
        noise_scale: f64,
    ) -> usize {
        let mut entries: Vec<[f64; 3]> = Vec::with_capacity(support.len());
        let mut entry_point: Vec<Vector3<f64>> = Vec::with_capacity(support.len());
        for &pixel in support {
            if let Some(p) = cloud.point(pixel as usize) {
                entries.push([p.x, p.y, p.z]);
                entry_point.push(p);
            }
        }
        let (Some(k_nz), Ok(tree)) = (
            std::num::NonZero::new(k.min(entries.len())),
            ImmutableKdTree::<f64, 3>::new_from_slice(&entries),
        ) else {
            return self.fallback.len();
        };
        let mut undefined = 0;
        for &slot in &self.fallback {
            let Some(p) = cloud.point(members[slot] as usize) else {
                undefined += 1;
                continue;
            };
            let nn = tree
                .query(&[p.x, p.y, p.z])
                .nearest_n::<SquaredEuclidean<f64>>(k_nz)
                .execute();
            let mut m = [0.0; CHANNELS];
            for n in &nn {
                let Some(q) = entry_point.get(n.item as usize) else {
                    continue;
                };
                let q = q - p;
                let row = moments(&q);
                for (mc, r) in m.iter_mut().zip(row) {
                    *mc += r;
                }
            }
            match normal_from_sums(&m, &p, noise_scale, cloud.focal_px()) {
                Some(n) => self.normals[slot] = orient(n, &p, viewpoint),
                None => undefined += 1,
            }
        }
        undefined
    }
}
