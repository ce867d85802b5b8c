//! Boundary refinement on the sample grid: the cells the proposal left
//! between regions (non-planar cells along edges, cells of the regions
//! too small to keep) go to a plane of an 8-connected neighbour when their
//! sample point is within that plane's inlier distance, breadth first
//! from every plane's cells at once. The labelling then gives each such
//! cell's pixels to the nearest plane around them
//! (`ransac_planes/labelling.rs`), as it does the region cells'.

use std::collections::VecDeque;

use crate::plane_fit::Plane;
use crate::ransac_planes::{SampleCells, Threshold, NO_PLANE};

/// Grows the labels of `cells` into the unlabelled sample cells, distance
/// only (a plane takes at most a threshold-wide strip of a surface it
/// meets at an angle).
pub(super) fn grow_labels(
    cells: &mut SampleCells<'_>,
    planes: &[Plane],
    t: Threshold,
    queue: &mut VecDeque<u32>,
) {
    let (w, h) = (cells.width, cells.height);
    queue.clear();
    queue.extend((0..cells.labels.len() as u32).filter(|&c| cells.labels[c as usize] != NO_PLANE));
    while let Some(c) = queue.pop_front() {
        let c = c as usize;
        let label = cells.labels[c];
        let plane = &planes[label as usize];
        let (cu, cv) = (c % w, c / w);
        for row in cv.saturating_sub(1)..(cv + 2).min(h) {
            for q in row * w + cu.saturating_sub(1)..row * w + (cu + 2).min(w) {
                if cells.labels[q] != NO_PLANE {
                    continue;
                }
                let p = cells.points[q];
                if p.x.is_finite() && plane.signed_distance(&p).abs() <= t.at(&p) {
                    cells.labels[q] = label;
                    queue.push_back(q as u32);
                }
            }
        }
    }
}
