//! Region growing on the cell grid (as CAPE, Proenca and Gao 2018): planar
//! cells, best first, each seed grows over its 4-connected planar
//! neighbours whose normal is within the merge angle of the region's and
//! whose centroid is within the inlier distance of the region's plane. The
//! region's plane is refitted from its summed moments each time the region
//! doubles, so a noisy seed does not set the region's plane.

use super::grid::{add_sums, CellGrid, RawSums, SumsPlane};
use crate::ransac_planes::Threshold;

/// `region_of` a cell in no region.
pub(super) const NO_REGION: u32 = u32::MAX;

/// One grown region.
#[derive(Debug, Clone)]
pub(super) struct Region {
    /// Its cells: `cells[start..end]` of [`Regions::cells`].
    pub start: usize,
    pub end: usize,
    pub sums: RawSums,
}

/// The regions of a frame and their buffers.
#[derive(Debug, Default, Clone)]
pub(super) struct Regions {
    pub regions: Vec<Region>,
    /// The cells of every region, region after region.
    pub cells: Vec<u32>,
    /// Per cell: its region, or [`NO_REGION`].
    pub region_of: Vec<u32>,
    seeds: Vec<u32>,
}

impl Regions {
    /// Grows the regions of `grid`, keeping those of at least `min_points`
    /// summed points.
    pub fn grow(&mut self, grid: &CellGrid, cos_merge: f64, t: Threshold, min_points: f64) {
        self.regions.clear();
        self.cells.clear();
        self.region_of.clear();
        self.region_of.resize(grid.planar.len(), NO_REGION);
        self.seeds.clear();
        self.seeds
            .extend((0..grid.planar.len() as u32).filter(|&c| grid.planar[c as usize].is_some()));
        // Best first; equally planar cells in raster order.
        self.seeds.sort_by(|&a, &b| {
            grid.badness[a as usize]
                .total_cmp(&grid.badness[b as usize])
                .then(a.cmp(&b))
        });
        for j in 0..self.seeds.len() {
            let seed = self.seeds[j];
            if self.region_of[seed as usize] != NO_REGION {
                continue;
            }
            let Some(plane) = grid.planar[seed as usize] else {
                continue;
            };
            let label = self.regions.len() as u32;
            let region = self.flood(grid, (seed, plane), label, cos_merge, t);
            if region.sums[0] >= min_points {
                self.regions.push(region);
            } else {
                // Too small: its cells are free for no one (seeds later in
                // the order are not grown into them either).
                for &c in &self.cells[region.start..] {
                    self.region_of[c as usize] = NO_REGION - 1;
                }
                self.cells.truncate(region.start);
            }
        }
        for r in &mut self.region_of {
            if *r == NO_REGION - 1 {
                *r = NO_REGION;
            }
        }
    }

    /// Floods the region of `seed` (a planar cell, with its plane; label
    /// `label`), breadth first; its cells are appended to `cells`.
    fn flood(
        &mut self,
        grid: &CellGrid,
        (seed, mut plane): (u32, SumsPlane),
        label: u32,
        cos_merge: f64,
        t: Threshold,
    ) -> Region {
        let start = self.cells.len();
        let (w, h) = (grid.width, grid.height);
        let mut sums = grid.sums[seed as usize];
        let mut fitted_at = 1;
        self.region_of[seed as usize] = label;
        self.cells.push(seed);
        let mut head = start;
        while head < self.cells.len() {
            let c = self.cells[head] as usize;
            head += 1;
            let (cu, cv) = (c % w, c / w);
            let neighbours = [
                (cu > 0).then(|| c - 1),
                (cu + 1 < w).then(|| c + 1),
                (cv > 0).then(|| c - w),
                (cv + 1 < h).then(|| c + w),
            ];
            for q in neighbours.into_iter().flatten() {
                if self.region_of[q] != NO_REGION {
                    continue;
                }
                let Some(cell) = &grid.planar[q] else {
                    continue;
                };
                if cell.normal.dot(&plane.normal) < cos_merge
                    || plane.distance(&cell.centroid).abs() > t.at(&cell.centroid)
                {
                    continue;
                }
                self.region_of[q] = label;
                self.cells.push(q as u32);
                add_sums(&mut sums, &grid.sums[q]);
                let size = self.cells.len() - start;
                if size >= 2 * fitted_at {
                    if let Some(refit) = SumsPlane::of(&sums) {
                        plane = refit;
                    }
                    fitted_at = size;
                }
            }
        }
        Region {
            start,
            end: self.cells.len(),
            sums,
        }
    }
}
