//! The assignment step on `f32` copies of the normals, and the clusters'
//! sums in fixed point, moved by the normals whose label changed.

use nalgebra::Vector3;

use super::CosineKmeans;

/// Units of the fixed-point sums: a unit vector's coordinates are held as
/// multiples of `2^-36` (1.5e-11, far below the normals' noise). A
/// cluster of 10,000 normals sums to at most `2^50` units: every sum is
/// exact in `i64` and in its `f64` conversion, so it does not depend on
/// the order the members were added in.
const FIXED_ONE: f64 = (1u64 << 36) as f64;

/// The label of a unit vector before the first assignment.
pub(super) const NO_LABEL: u32 = u32::MAX;

/// Labels compared a block at a time (the blocks without a change,
/// most of them after the first iterations, are skipped whole).
const LABEL_BLOCK: usize = 32;

impl CosineKmeans {
    /// The `f32` copies of `unit` that the assignment step reads, and its
    /// fixed-point copies (truncated) that the sums add.
    pub(super) fn load_copies(&mut self) {
        let unit = &self.unit;
        self.ux.clear();
        self.ux.extend(unit.iter().map(|u| u.x as f32));
        self.uy.clear();
        self.uy.extend(unit.iter().map(|u| u.y as f32));
        self.uz.clear();
        self.uz.extend(unit.iter().map(|u| u.z as f32));
        self.fixed.clear();
        let to_fixed = |c: f64| (c * FIXED_ONE) as i64;
        self.fixed.extend(
            unit.iter()
                .map(|u| [to_fixed(u.x), to_fixed(u.y), to_fixed(u.z)]),
        );
    }

    /// The assignment step: `best[i]` is the centre with the largest dot
    /// product with normal `i` (the smallest cosine distance; ties go to
    /// the lower index).
    pub(super) fn assign(&mut self, centres: &[Vector3<f64>]) {
        match centres.len() {
            2 => self.assign_at_once::<2>(centres),
            3 => self.assign_at_once::<3>(centres),
            4 => self.assign_at_once::<4>(centres),
            _ => self.assign_centre_by_centre(centres),
        }
    }

    /// [`Self::assign`] for `K` centres, all of them per normal in one pass
    /// (each normal loaded once, its best kept in registers): the same dot
    /// products compared in the same order as
    /// [`Self::assign_centre_by_centre`].
    pub(super) fn assign_at_once<const K: usize>(&mut self, centres: &[Vector3<f64>]) {
        let n = self.ux.len();
        let c: [[f32; 3]; K] = std::array::from_fn(|j| {
            [
                centres[j].x as f32,
                centres[j].y as f32,
                centres[j].z as f32,
            ]
        });
        let (ux, uy, uz) = (&self.ux[..n], &self.uy[..n], &self.uz[..n]);
        self.best.resize(n, 0);
        let best = &mut self.best[..n];
        for i in 0..n {
            let dot = |c: &[f32; 3]| ux[i] * c[0] + uy[i] * c[1] + uz[i] * c[2];
            let (mut best_dot, mut best_j) = (dot(&c[0]), 0u32);
            for (j, c) in (1..).zip(&c[1..]) {
                let d = dot(c);
                // Branch-free (clusters interleave: a branch mispredicts).
                let mask = u32::from(d > best_dot).wrapping_neg();
                best_j = (best_j & !mask) | (j & mask);
                best_dot = best_dot.max(d);
            }
            best[i] = best_j;
        }
    }

    /// [`Self::assign`] for any number of centres: one centre at a time
    /// over all normals.
    pub(super) fn assign_centre_by_centre(&mut self, centres: &[Vector3<f64>]) {
        let n = self.ux.len();
        let Some((first, others)) = centres.split_first() else {
            return;
        };
        let (ux, uy, uz) = (&self.ux[..n], &self.uy[..n], &self.uz[..n]);
        // The first centre sets every normal's best (no fill needed).
        let dot = |c: &Vector3<f64>| {
            let (cx, cy, cz) = (c.x as f32, c.y as f32, c.z as f32);
            move |i: usize| ux[i] * cx + uy[i] * cy + uz[i] * cz
        };
        let first = dot(first);
        self.best_dot.resize(n, 0.0);
        self.best.resize(n, 0);
        let (best_dot, best) = (&mut self.best_dot[..n], &mut self.best[..n]);
        for i in 0..n {
            best_dot[i] = first(i);
            best[i] = 0;
        }
        for (j, c) in (1..).zip(others) {
            let d_of = dot(c);
            for i in 0..n {
                let d = d_of(i);
                // Branch-free (clusters interleave: a branch mispredicts).
                let mask = u32::from(d > best_dot[i]).wrapping_neg();
                best[i] = (best[i] & !mask) | (j & mask);
                best_dot[i] = best_dot[i].max(d);
            }
        }
    }

    /// Empty sums for `k` clusters (before the first assignment, when no
    /// normal has a label).
    pub(super) fn clear_sums(&mut self, k: usize) {
        self.sums.clear();
        self.sums.resize(k, ([0; 3], 0));
    }

    /// Gives each normal the label of the last assignment step, moving
    /// those whose label changed from their old cluster's sum and size to
    /// the new one's; returns how many changed. The sums are exact, so
    /// they equal each cluster's sum over its members summed afresh.
    pub(super) fn move_labels(&mut self) -> usize {
        let mut changed = 0;
        let blocks = self.labels.chunks_mut(LABEL_BLOCK).zip(
            self.best
                .chunks(LABEL_BLOCK)
                .zip(self.fixed.chunks(LABEL_BLOCK)),
        );
        for (labels, (best, fixed)) in blocks {
            // Any label of the block changed (one OR of lanes).
            let differ = labels.iter().zip(best).fold(0, |d, (&l, &b)| d | (l ^ b));
            if differ == 0 {
                continue;
            }
            for ((label, &best), q) in labels.iter_mut().zip(best).zip(fixed) {
                if *label == best {
                    continue;
                }
                if let Some((sum, count)) = self.sums.get_mut(*label as usize) {
                    sum.iter_mut().zip(q).for_each(|(s, q)| *s -= q);
                    *count -= 1;
                }
                let (sum, count) = &mut self.sums[best as usize];
                sum.iter_mut().zip(q).for_each(|(s, q)| *s += q);
                *count += 1;
                *label = best;
                changed += 1;
            }
        }
        changed
    }

    /// Cluster `j`'s sum of unit vectors (to the fixed point's precision).
    pub(super) fn cluster_sum(&self, j: usize) -> Vector3<f64> {
        let s = self.sums[j].0;
        Vector3::new(s[0] as f64, s[1] as f64, s[2] as f64) / FIXED_ONE
    }
}
