//! The road ahead: the surface the robot will drive onto (or face) first.
//!
//! A candidate is a `ramp` or a `wall` (it joins the ground or a step, or
//! its foot is hidden) that
//!
//! - passes the inclined plane's own tests (`inclined.rs`): flat at the
//!   sensor's noise level, at least `selection.inclined_min_area_m2`,
//!   inclined and not facing down, its normal's horizontal part within
//!   `selection.max_heading_deg` of forward or backward;
//! - reaches into the robot's corridor: at least
//!   [`super::CORRIDOR_MIN_PIXELS`] inliers within
//!   `road.corridor_half_width_m` of the forward axis and
//!   `road.look_ahead_m` ahead.
//!
//! Among candidates with at least `selection.min_relative_support` of the
//! best-supported one's pixels, the road is the nearest: the smallest mean
//! forward distance of its inliers in the corridor (a mean, not the
//! nearest inlier, so that a stray pixel does not decide between two
//! pieces of one wall). Candidates at most [`SAME_SURFACE_M`] behind the
//! nearest with its slope (within `selection.parallel_tolerance_deg`) are
//! pieces of one surface (a wall RANSAC cut in two), and the largest of
//! them is the road: the most pixels measure the slope best. A wall beside
//! the path, a
//! board above the floor, pillows on a bed or a ramp off to the side are
//! never the road, however near.
//!
//! **A close call**: another candidate in the corridor at most
//! `road.close_choice_m` farther than the road (by the same mean) whose
//! slope differs from the road's by more than the parallel tolerance (so
//! the answer would differ had it been chosen): the
//! estimate's confidence says so (`close_choice`). The next riser of the
//! same staircase is parallel to the first and is no close call.

use slope_ipc_types::SurfaceRole;

use super::inclined::is_inclined_candidate;
use super::{GroundFrame, PlaneSummary, RoadConfig, SelectionConfig, Surface};

/// Candidates whose mean distance in the corridor lies within this of the
/// nearest's, at the same slope, are pieces of one surface, metres (a wall
/// RANSAC cut in two; the next riser of a staircase lies a tread, 0.25 m
/// or more, behind).
pub const SAME_SURFACE_M: f64 = 0.15;

/// The chosen road: an index into the frame's surfaces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Road {
    pub surface: usize,
    /// Another candidate at a different slope lies close behind it.
    pub close_choice: bool,
}

/// The other pieces of the road's surface among `surfaces` (indices): the
/// road's candidates (the module documentation) at most
/// [`SAME_SURFACE_M`] from it (by their mean distance in the corridor)
/// with its slope (within
/// `selection.parallel_tolerance_deg`) whose centroids lie within
/// [`PIECE_GAP_M`] of its plane: one wall RANSAC cut in two, measured
/// together (`estimator.rs`), so that the slope does not depend on where
/// the draw cut it.
pub fn road_pieces(
    surfaces: &[Surface],
    summaries: &[PlaneSummary],
    frame: &GroundFrame,
    selection: &SelectionConfig,
    road: &Road,
) -> Vec<usize> {
    let chosen = &surfaces[road.surface];
    road_candidates(surfaces, summaries, frame, selection)
        .into_iter()
        .filter(|&k| k != road.surface)
        .filter(|&k| {
            let s = &surfaces[k];
            (s.corridor_mean_m - chosen.corridor_mean_m).abs() <= SAME_SURFACE_M
                && (s.slope_deg - chosen.slope_deg).abs() <= selection.parallel_tolerance_deg
                && chosen
                    .plane
                    .signed_distance(&summaries[s.plane_index].centroid)
                    .abs()
                    <= PIECE_GAP_M
        })
        .collect()
}

/// A piece of the road's surface has its centroid within this of the
/// road's plane, metres.
pub const PIECE_GAP_M: f64 = 0.1;

/// The road's candidates among `surfaces` (the module documentation).
fn road_candidates(
    surfaces: &[Surface],
    summaries: &[PlaneSummary],
    frame: &GroundFrame,
    selection: &SelectionConfig,
) -> Vec<usize> {
    (0..surfaces.len())
        .filter(|&k| {
            let s = &surfaces[k];
            matches!(s.role, SurfaceRole::Ramp | SurfaceRole::Wall)
                && s.in_corridor
                && s.corridor_distance_m.is_finite()
                && is_inclined_candidate(
                    &summaries[s.plane_index],
                    &frame.up,
                    &frame.forward,
                    selection,
                )
        })
        .collect()
}

/// Chooses the road among `surfaces` (whose planes `summaries` describes).
pub fn choose_road(
    surfaces: &[Surface],
    summaries: &[PlaneSummary],
    frame: &GroundFrame,
    selection: &SelectionConfig,
    road: &RoadConfig,
) -> Option<Road> {
    let candidates = road_candidates(surfaces, summaries, frame, selection);
    let support = candidates.iter().map(|&k| surfaces[k].inliers).max()?;
    let supported: Vec<usize> = candidates
        .iter()
        .copied()
        .filter(|&k| surfaces[k].inliers as f64 >= selection.min_relative_support * support as f64)
        .collect();
    let by_distance = |&a: &usize, &b: &usize| {
        surfaces[a]
            .corridor_mean_m
            .total_cmp(&surfaces[b].corridor_mean_m)
            .then(a.cmp(&b))
    };
    let nearest = supported.iter().copied().min_by(by_distance)?;
    // Pieces of one surface (as near, as steep): the largest measures it.
    let same_surface = |k: usize| {
        let (a, b) = (&surfaces[k], &surfaces[nearest]);
        a.corridor_mean_m - b.corridor_mean_m <= SAME_SURFACE_M
            && (a.slope_deg - b.slope_deg).abs() <= selection.parallel_tolerance_deg
    };
    let nearest = supported
        .iter()
        .copied()
        .filter(|&k| same_surface(k))
        .max_by(|&a, &b| {
            surfaces[a]
                .inliers
                .cmp(&surfaces[b].inliers)
                .then(b.cmp(&a))
        })
        .unwrap_or(nearest);
    let chosen = &surfaces[nearest];
    let close_choice = candidates.iter().any(|&k| {
        let other = &surfaces[k];
        k != nearest
            && other.corridor_mean_m - chosen.corridor_mean_m <= road.close_choice_m
            && (other.slope_deg - chosen.slope_deg).abs() > selection.parallel_tolerance_deg
    });
    Some(Road {
        surface: nearest,
        close_choice,
    })
}
