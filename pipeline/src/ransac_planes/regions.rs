//! A plane is one connected surface: the largest 8-connected region of its
//! sample inliers on the sample grid. The search costs in proportion to the
//! inliers, not to the grid: seeds are the inliers' cells, and each region's
//! cells are collected as it is flooded.

use super::points::Gate;
use super::PlaneSegmenter;
use crate::plane_fit::{fit_tls, Moments, Plane};

/// `coarse_label` of a cell that is not (or no longer) an unvisited inlier.
const DONE: u32 = 0;
/// `coarse_label` of an inlier cell not yet flooded.
const INLIER: u32 = 1;

impl PlaneSegmenter {
    /// Fills `region` with the coarse cells of the largest 8-connected
    /// region (on the sample grid) of the free sample inliers of `plane`
    /// (the first found in raster order among equally large ones); returns
    /// the TLS plane of that region's sample points.
    pub(super) fn largest_sample_region(&mut self, plane: &Plane, gate: Gate) -> Option<Plane> {
        let grid = &self.sample;
        let (cw, ch) = (grid.coarse_w, grid.coarse_h);
        grid.points.inlier_flags(plane, gate, &mut self.flags);
        self.coarse_label.clear();
        self.coarse_label.resize(cw * ch, DONE);
        // Free points are in raster order, so their cells are too.
        self.seeds.clear();
        for (j, &flag) in self.flags.iter().enumerate() {
            if flag {
                let c = grid.cell_of(j);
                self.coarse_label[c] = INLIER;
                self.seeds.push(c as u32);
            }
        }
        self.region.clear();
        self.flooded.clear();
        for &seed in &self.seeds {
            if self.coarse_label[seed as usize] != INLIER {
                continue;
            }
            self.flooded.clear();
            self.coarse_label[seed as usize] = DONE;
            self.stack.clear();
            self.stack.push(seed);
            while let Some(c) = self.stack.pop() {
                self.flooded.push(c);
                // The 3x3 cells around `c` (`cell_neighbourhood`, unrolled
                // by rows: the region's cells, not their order, matter).
                let (cu, cv) = (c as usize % cw, c as usize / cw);
                let (u0, u1) = (cu.saturating_sub(1), (cu + 2).min(cw));
                for r in cv.saturating_sub(1)..(cv + 2).min(ch) {
                    for q in r * cw + u0..r * cw + u1 {
                        if self.coarse_label[q] == INLIER {
                            self.coarse_label[q] = DONE;
                            self.stack.push(q as u32);
                        }
                    }
                }
            }
            if self.flooded.len() > self.region.len() {
                std::mem::swap(&mut self.region, &mut self.flooded);
            }
        }
        self.region.sort_unstable();
        let mut moments = Moments::new();
        for &c in &self.region {
            moments.add(&grid.points.point(grid.coarse[c as usize] as usize));
        }
        fit_tls(&moments)
    }
}
