//! The cell-grid plane proposal (CAPE-style, Proenca and Gao, IROS 2018;
//! PEAC, Feng et al., ICRA 2014): planes are proposed from small planar
//! cells of the organised cloud instead of sampled points, and each
//! proposed region's plane is then fitted by the paper's RANSAC over the
//! region's own points.
//!
//! 1. *Cells* (`grid.rs`): blocks of `cell_size_px` pixels (whole sample
//!    cells), each with the moments of every `cell_point_step_px`-th
//!    kept pixel; a cell is planar when at least half of those pixels are
//!    measured and their RMS distance from their TLS plane is at most
//!    `cell_rms_ratio` times the inlier distance at the centroid.
//! 2. *Regions* (`grow.rs`): planar cells, most planar first, seed
//!    regions that grow over 4-connected planar cells whose normal is
//!    within `merge_angle_deg` of the region's and whose centroid is within
//!    the inlier distance of the region's plane (refitted from the summed
//!    moments each time the region doubles). A region must hold
//!    `ransac.min_plane_points` pixels.
//! 3. *Fit* (`fit.rs`), largest region first: RANSAC over the region's
//!    free sample points (three-point hypotheses, consensus, LO refits, at
//!    least 32 hypotheses and the adaptive count for `ransac.confidence`),
//!    then the TLS plane of its inliers.
//! 4. *Surface* (`boundary.rs`): the fitted plane floods its band on the
//!    sample grid (free cells 8-connected to the region's inliers within
//!    the inlier distance, distance only, refitted between layers as the
//!    surface doubles), then floods once more from its surface's TLS
//!    plane. The flood takes the non-planar cells along the region's
//!    edges and the neighbouring regions on the same plane (the facets of
//!    a rough surface, a bed's fabric side, whose cell normals differ by
//!    more than the merge angle): a plane is then, as in the sequential
//!    extraction, the connected band of its inliers. A region whose cells
//!    earlier planes took (all but fewer than `min_plane_points / stride^2`
//!    cells) is no plane.
//! 5. *Merge*: a plane within 1 degree of an earlier one with 90 % of its
//!    cells within that plane's inlier distance joins it (two pieces of a
//!    ramp parted by a table standing on it).
//!
//! After the proposal, the free sample points within the inlier distance
//! of a proposed plane are dropped, and the sequential extraction
//! (`ransac_planes/`) runs on what is left: thin structures on which no
//! cell is planar (a table's legs and edge). The labelling, junction
//! relaxation and final TLS refit on every pixel are the sequential
//! segmentation's (`ransac_planes/labelling.rs`).
//!
//! The sample grid and the cells are their own mirror image (the sample
//! points counted from the nearer image edge, the cells grouped from both
//! edges: `grid.rs`), so a mirrored frame gives the mirrored regions.
//!
//! What it costs (`Estimator::run` on stairs-front, callgrind): the cells
//! 5.0 M, region growing 2.0 M, the fits and floods 11.8 M, the extraction
//! over what is left 5.2 M, the labelling 30 M (BENCHMARKS.md).

use rand_chacha::ChaCha8Rng;

use crate::cloud::CloudView;
use crate::plane_fit::Plane;
use crate::ransac_planes::{PlaneProposal, RansacConfig, SampleCells, Threshold};

use super::SegmentationConfig;

mod boundary;
mod fit;
mod grid;
mod grow;

use grid::{CellGrid, CellLayout};
use grow::Regions;

/// The buffers of the cell-grid proposal.
#[derive(Debug, Default, Clone)]
pub struct CellProposal {
    grid: CellGrid,
    regions: Regions,
    fit: fit::RegionFit,
    /// Regions by size, largest first.
    order: Vec<usize>,
}

impl CellProposal {
    pub fn new() -> Self {
        Self::default()
    }

    /// This proposal with the cell grid's parameters, as a
    /// [`PlaneProposal`].
    pub fn configured<'a>(&'a mut self, config: &'a SegmentationConfig) -> ConfiguredCells<'a> {
        ConfiguredCells {
            proposal: self,
            config,
        }
    }
}

/// A [`CellProposal`] with its parameters.
#[derive(Debug)]
pub struct ConfiguredCells<'a> {
    proposal: &'a mut CellProposal,
    config: &'a SegmentationConfig,
}

impl PlaneProposal for ConfiguredCells<'_> {
    fn propose(
        &mut self,
        cloud: &CloudView<'_>,
        keep: &[bool],
        mut cells: SampleCells<'_>,
        ransac: &RansacConfig,
        rng: &mut ChaCha8Rng,
    ) -> Vec<Plane> {
        let (p, config) = (&mut *self.proposal, self.config);
        let t = Threshold::of(ransac);
        let stride = cells.stride.max(1);
        let k = (config.cell_size_px as f64 / stride as f64)
            .round()
            .max(1.0) as usize;
        let layout = CellLayout {
            columns: cells.columns,
            rows: cells.rows,
            stride,
            k,
            step: config.cell_point_step_px.max(1),
            rms_ratio: config.cell_rms_ratio,
        };
        p.grid.load(cloud, keep, layout, t, cells.workers);
        let step2 = (layout.step * layout.step) as f64;
        let min_points = ransac.min_plane_points as f64 / step2;
        let cos_merge = config.merge_angle_deg.to_radians().cos();
        p.regions.grow(&p.grid, cos_merge, t, min_points);
        p.order.clear();
        p.order.extend(0..p.regions.regions.len());
        let regions = &p.regions.regions;
        p.order.sort_by(|&a, &b| {
            regions[b].sums[0]
                .total_cmp(&regions[a].sums[0])
                .then(a.cmp(&b))
        });
        let s2 = (stride * stride) as f64;
        let min_cells = ((ransac.min_plane_points as f64 / s2).ceil() as usize).max(3);
        let mut found = Vec::new();
        for &r in &p.order {
            if found.len() >= ransac.plane_cap(crate::segmentation::Proposal::Cells.max_planes()) {
                break;
            }
            let region = &regions[r];
            let region_cells = &p.regions.cells[region.start..region.end];
            let target = fit::FitTarget {
                label: found.len() as u16,
                t,
                min_cells,
            };
            if let Some(plane) = p
                .fit
                .fit(&mut cells, (region_cells, &p.grid), target, ransac, rng)
            {
                match coplanar_with(&found, &plane, p.fit.taken(), &cells, t) {
                    Some(j) => {
                        for &c in p.fit.taken() {
                            cells.labels[c as usize] = j;
                        }
                    }
                    None => found.push(plane),
                }
            }
        }
        found
    }
}

/// The first of `found` that `plane` (whose sample cells are `taken`)
/// lies on: normals within [`COPLANAR_DEG`], and [`COPLANAR_SHARE`] of
/// the cells within the inlier distance of it. Two pieces of one plane
/// that an obstacle parts (a ramp seen beside a table and under it) are
/// then one plane, as in CAPE's merging of regions on one plane.
fn coplanar_with(
    found: &[Plane],
    plane: &Plane,
    taken: &[u32],
    cells: &SampleCells<'_>,
    t: Threshold,
) -> Option<u16> {
    let cos = COPLANAR_DEG.to_radians().cos();
    found
        .iter()
        .position(|f| {
            f.normal.dot(&plane.normal).abs() >= cos && {
                let on = taken
                    .iter()
                    .filter(|&&c| {
                        let q = &cells.points[c as usize];
                        f.signed_distance(q).abs() <= t.at(q)
                    })
                    .count();
                on as f64 >= COPLANAR_SHARE * taken.len() as f64
            }
        })
        .map(|j| j as u16)
}

/// Planes whose normals are within this many degrees may be one plane.
const COPLANAR_DEG: f64 = 1.0;
/// The share of a plane's sample cells within the inlier distance of an
/// earlier plane that makes it part of that plane.
const COPLANAR_SHARE: f64 = 0.9;

#[cfg(test)]
mod tests;
