//! A plane is one connected surface: the largest 8-connected region of its
//! sample inliers on the sample grid. The search costs in proportion to the
//! inliers, not to the grid: seeds are the inliers' cells, each region's
//! cells get the region's label as it is flooded, and the largest region's
//! cells are collected from the seeds (in raster order, so sorted).

use super::points::Gate;
use super::PlaneSegmenter;
use crate::plane_fit::{fit_tls, MomentSums, Plane};

/// `coarse_label` of a cell that is not (or no longer) an unvisited inlier.
const DONE: u32 = 0;
/// `coarse_label` of an inlier cell not yet flooded.
const INLIER: u32 = 1;
/// `coarse_label` of the cells of the first region flooded (the next one
/// `FIRST_REGION + 1`, and so on).
const FIRST_REGION: u32 = 2;

impl PlaneSegmenter {
    /// Fills `region` with the coarse cells of the largest 8-connected
    /// region (on the sample grid) of the free sample inliers of `plane`
    /// (the first found in raster order among equally large ones); returns
    /// the TLS plane of that region's sample points.
    pub(super) fn largest_sample_region(&mut self, plane: &Plane, gate: Gate) -> Option<Plane> {
        let grid = &self.sample;
        let (cw, ch) = (grid.coarse_w, grid.coarse_h);
        grid.points.inlier_flags(plane, gate, &mut self.flags);
        // Every label is DONE after a search, so the grid is reset only
        // when its size changes.
        if self.coarse_label.len() != cw * ch {
            self.coarse_label.clear();
            self.coarse_label.resize(cw * ch, DONE);
        }
        // Free points are in raster order, so their cells are too.
        self.seeds.clear();
        for (j, &flag) in self.flags.iter().enumerate() {
            if flag {
                let c = grid.cell_of(j);
                self.coarse_label[c] = INLIER;
                self.seeds.push(c as u32);
            }
        }
        let largest = self.flood_components();
        let grid = &self.sample;
        // The seeds are in raster order: the region's cells come out
        // sorted; every label is DONE again.
        self.region.clear();
        for &c in &self.seeds {
            let label = &mut self.coarse_label[c as usize];
            if *label == largest {
                self.region.push(c);
            }
            *label = DONE;
        }
        // About the first point: the same sums as `Moments::add` (which
        // takes its first point as origin), without its per-point checks
        // (sample points are finite).
        let point = |c: u32| grid.points.point(grid.coarse[c as usize] as usize);
        let first = point(*self.region.first()?);
        let mut sums = MomentSums::about(first);
        for &c in &self.region {
            let p = point(c);
            sums.add(p.x, p.y, p.z);
        }
        fit_tls(&sums.moments())
    }

    /// Floods the 8-connected regions of the seeds' cells (`INLIER`),
    /// labelling each region's cells with its own label; returns the label
    /// of the largest (the first flooded among equally large ones).
    fn flood_components(&mut self) -> u32 {
        let (cw, ch) = (self.sample.coarse_w, self.sample.coarse_h);
        let mut largest = (0usize, DONE);
        let mut label = FIRST_REGION - 1;
        for &seed in &self.seeds {
            if self.coarse_label[seed as usize] != INLIER {
                continue;
            }
            label += 1;
            self.coarse_label[seed as usize] = label;
            self.stack.clear();
            self.stack.push(seed);
            let mut size = 0;
            while let Some(c) = self.stack.pop() {
                size += 1;
                // The 3x3 cells around `c` (`cell_neighbourhood`, unrolled
                // by rows: the region's cells, not their order, matter).
                let (cu, cv) = (c as usize % cw, c as usize / cw);
                let (u0, u1) = (cu.saturating_sub(1), (cu + 2).min(cw));
                for r in cv.saturating_sub(1)..(cv + 2).min(ch) {
                    for q in r * cw + u0..r * cw + u1 {
                        if self.coarse_label[q] == INLIER {
                            self.coarse_label[q] = label;
                            self.stack.push(q as u32);
                        }
                    }
                }
            }
            if size > largest.0 {
                largest = (size, label);
            }
        }
        largest.1
    }
}
