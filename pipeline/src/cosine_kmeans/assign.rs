//! The assignment step on `f32` copies of the normals, and the one-pass
//! sums of every cluster that the update step takes its centres from.

use nalgebra::Vector3;

use super::CosineKmeans;

/// Lanes of the update step's `f32` sums. With `BLOCK`, it sets their
/// rounding, so changing either changes the results.
const LANES: usize = 8;
/// Normals per block of `f32` lane sums in the update step.
const BLOCK: usize = 256;

/// One cluster's `f32` sums and sizes of one block, lane by lane.
#[derive(Debug, Default, Clone, Copy)]
pub(super) struct LaneSums {
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

impl CosineKmeans {
    pub(super) fn load_f32(&mut self) {
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
    pub(super) fn assign(&mut self, centres: &[Vector3<f64>]) {
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
    pub(super) fn cluster_sums(&mut self, k: usize) {
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
}
