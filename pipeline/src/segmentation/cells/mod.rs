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
//! 3. *Fit* (`fit.rs`): RANSAC over the region's sample points (three-point
//!    hypotheses, consensus, LO refits, adaptive count for
//!    `ransac.confidence`), then the TLS plane of its inliers; those sample
//!    cells are the plane's.
//! 4. *Boundary* (`boundary.rs`): the sample cells left between regions go
//!    to a neighbouring plane within its inlier distance.
//!
//! The labelling, junction relaxation and final TLS refit on every pixel
//! are the sequential segmentation's (`ransac_planes/labelling.rs`).
//! What it costs: one pass over a quarter of the pixels (the sums), one
//! eigen-decomposition per cell (about 3,400 cells of 8 px on a Kinect v2
//! frame), a flood over the cells, and a few dozen hypotheses per region
//! scored on at most 500 points; no extraction loop over the frame.

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
            sample_w: cells.width,
            sample_h: cells.height,
            stride,
            k,
            step: config.cell_point_step_px.max(1),
            rms_ratio: config.cell_rms_ratio,
        };
        p.grid.load(cloud, keep, layout, t);
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
            if found.len() >= ransac.max_planes.min(crate::ransac_planes::MAX_PLANES) {
                break;
            }
            let region = &regions[r];
            let region_cells = &p.regions.cells[region.start..region.end];
            let target = fit::FitTarget {
                label: found.len() as u16,
                t,
                min_cells,
            };
            if let Some(plane) = p.fit.fit(
                &mut cells,
                (region_cells, p.grid.width, k),
                target,
                ransac,
                rng,
            ) {
                found.push(plane);
            }
        }
        found
    }
}

#[cfg(test)]
mod tests;
