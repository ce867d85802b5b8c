//! A fitted plane's surface on the sample grid: the free sample cells
//! 8-connected to its region's inliers whose point is within its inlier
//! distance (distance only), as the sequential extraction's plane is the
//! largest connected region of its inliers (`ransac_planes/regions.rs`).
//! The flood crosses cell borders and the regions not fitted yet: the
//! non-planar cells along a region's edges, and the neighbouring regions
//! of the same plane (the facets of a rough surface, whose cell normals
//! differ by more than the merge angle but whose points lie within the
//! band), join the plane that reaches them first, largest region first.
//! The labelling then gives each cell's pixels to the nearest plane around
//! them (`ransac_planes/labelling.rs`).

use crate::plane_fit::{fit_tls, Moments, Plane};
use crate::ransac_planes::{SampleCells, Threshold, NO_PLANE};

/// Labels `label` every free sample cell of `cells` connected to `seeds`
/// (cells already labelled `label`) within the inlier distance of
/// `plane`; appends the cells it labels to `taken`. The set does not
/// depend on the order of `seeds`: it is every free cell of the band
/// connected to one of them.
pub(super) fn flood_band(
    cells: &mut SampleCells<'_>,
    plane: &Plane,
    label: u16,
    t: Threshold,
    (seeds, taken): (&[u32], &mut Vec<u32>),
) {
    let (w, h) = (cells.width, cells.height);
    let start = taken.len();
    taken.extend_from_slice(seeds);
    let mut plane = *plane;
    let mut moments = Moments::new();
    for &c in seeds {
        moments.add(&cells.points[c as usize]);
    }
    let mut fitted_at = seeds.len().max(1);
    // Breadth first, a layer at a time: a layer is every free cell of the
    // band next to the layer before, whatever the order within it, and the
    // plane is refitted between layers once the surface has doubled.
    let (mut head, mut layer_end) = (start, taken.len());
    while head < taken.len() {
        if head == layer_end {
            layer_end = taken.len();
            if taken.len() - start >= 2 * fitted_at {
                if let Some(refit) = fit_tls(&moments) {
                    plane = refit;
                }
                fitted_at = taken.len() - start;
            }
        }
        let c = taken[head] as usize;
        head += 1;
        let (cu, cv) = (c % w, c / w);
        for row in cv.saturating_sub(1)..(cv + 2).min(h) {
            for q in row * w + cu.saturating_sub(1)..row * w + (cu + 2).min(w) {
                if cells.labels[q] != NO_PLANE {
                    continue;
                }
                let p = cells.points[q];
                if p.x.is_finite() && plane.signed_distance(&p).abs() <= t.at(&p) {
                    cells.labels[q] = label;
                    taken.push(q as u32);
                    moments.add(&p);
                }
            }
        }
    }
}
