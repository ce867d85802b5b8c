//! The role of every surface: what it is to a robot driving on the ground.
//!
//! Angles are to the ground's normal (`tilt`); heights above the ground;
//! "meets" is defined below. In order:
//!
//! 1. **`ground`**: the ground plane and its coplanar segments (`ground.rs`).
//! 2. **`overhang`**: tilt above `selection.max_slope_deg` (the surface
//!    faces down: a ceiling, a table's underside).
//! 3. **`step`**: level (tilt at most `selection.parallel_tolerance_deg`),
//!    and its height differs from the ground's, or from a step's, by at
//!    most `road.max_step_rise_m` (up or down: a curb, a threshold, a
//!    tread), its footprint (for a step below it) within `max_step_rise_m +
//!    join_tolerance_m` of that surface's; the ground goes on where it is
//!    not seen (its far rows, seen at a grazing angle, are the outlier
//!    filter's first victims), so its footprint is not asked. A level surface that meets the top or bottom edge of
//!    a ramp (within `join_tolerance_m` of it in height) is a step too: the
//!    ramp's landing. Steps chain: each tread stands on the one below.
//! 4. **`ramp`** / **`wall`**: inclined (tilt above the parallel tolerance,
//!    up to `max_slope_deg`) and meeting the ground or a step: some of its
//!    inliers come within `join_tolerance_m` of that surface's height
//!    (its lowest inliers for a surface rising from it, its highest for
//!    one falling from it), its footprint next to a step's as a step's. A `ramp` is tilted at most `road.max_ramp_deg`, a `wall`
//!    more (an obstacle, a riser: a staircase's risers each stand on the
//!    tread below).
//! 5. An inclined surface that meets nothing but whose foot is hidden
//!    behind something nearer (`hidden_foot.rs`; a surface rising away from
//!    the robot or to a side, not one falling away) is a `ramp` or `wall`
//!    whose support is `hidden`: it may stand on the ground out of sight.
//!    Only surfaces that could be the road (flat at the noise level and
//!    large enough) are looked at. A surface resting on furniture (its
//!    lowest inlier at or above an `elevated` level surface's height, less
//!    `join_tolerance_m`, its footprint overlapping that surface's: pillows
//!    on a bed, a box on a table, a board rising behind a desk) is not: it
//!    stays `elevated`. A ramp seen under a table's top, below its height,
//!    does not rest on it, and its foot may be hidden by it.
//! 6. **`elevated`**: everything else: a surface that joins neither the
//!    ground nor a step (a table, a bed, a shelf, a board): never the road.
//!
//! Surfaces are joined in rounds until none joins any more, so that a
//! chain (a staircase, a ramp on a curb, a landing) is followed up from
//! the ground whatever the planes' order.

use slope_ipc_types::{SurfaceRole, SurfaceSupport};

use super::{foot_is_hidden, GroundFrame, RoadConfig, SelectionConfig, Surface};
use crate::cloud::CloudView;
use crate::ransac_planes::SegmentedPlane;

/// Sets the role, support and `joins_ground` of every surface but the
/// ground (which `describe_surfaces` put first, when one was seen).
pub fn assign_roles(
    surfaces: &mut [Surface],
    cloud: &CloudView<'_>,
    planes: &[SegmentedPlane],
    frame: &GroundFrame,
    selection: &SelectionConfig,
    road: &RoadConfig,
) {
    let kind = |s: &Surface| Kind::of(s, selection);
    for s in surfaces
        .iter_mut()
        .filter(|s| s.role != SurfaceRole::Ground)
    {
        if kind(s) == Kind::FacingDown {
            s.role = SurfaceRole::Overhang;
        }
    }
    join_in_rounds(surfaces, selection, road);
    let furniture: Vec<Furniture> = surfaces
        .iter()
        .filter(|s| {
            s.role == SurfaceRole::Elevated && s.tilt_deg() <= selection.parallel_tolerance_deg
        })
        .map(|s| Furniture {
            ahead: (s.distance_m, s.far_m),
            lateral: (s.left_m, s.right_m),
            height_m: 0.5 * (s.lowest_m + s.highest_m),
        })
        .collect();
    for s in surfaces.iter_mut() {
        if s.role != SurfaceRole::Elevated || s.support != SurfaceSupport::None {
            continue;
        }
        // Only a surface that could be the road (flat and large enough),
        // not resting on furniture, is worth the look.
        if kind(s) == Kind::Inclined
            && s.measurable
            && !rests_on(s, &furniture, road.join_tolerance_m)
            && foot_is_hidden(
                cloud,
                &planes[s.plane_index].inliers,
                s,
                frame,
                road.join_tolerance_m,
            )
        {
            s.role = inclined_role(s, road);
            s.support = SurfaceSupport::Hidden;
            s.joins_ground = true;
        }
    }
}

/// A level surface that stands on nothing seen (a table, a bed, a desk
/// top): its footprint (forward and lateral extents) and its height above
/// the ground, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Furniture {
    ahead: (f64, f64),
    lateral: (f64, f64),
    height_m: f64,
}

/// True when `s` rests on a piece of `furniture`: its lowest inlier is at
/// or above the furniture's height (less `tol_m`) and its footprint overlaps
/// the furniture's (within `tol_m`).
fn rests_on(s: &Surface, furniture: &[Furniture], tol_m: f64) -> bool {
    let overlaps =
        |(a0, a1): (f64, f64), (b0, b1): (f64, f64)| a0 <= b1 + tol_m && b0 <= a1 + tol_m;
    furniture.iter().any(|f| {
        s.lowest_m >= f.height_m - tol_m
            && overlaps((s.distance_m, s.far_m), f.ahead)
            && overlaps((s.left_m, s.right_m), f.lateral)
    })
}

/// What a surface's tilt makes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// Within the sensor's floor bend at its distance: level.
    Level,
    /// Beyond the floor bend but within `parallel_tolerance_deg`: a gentle
    /// ramp where it rises out of the surface it meets, else a level
    /// surface (a tread a little tilted).
    Gentle,
    Inclined,
    FacingDown,
}

impl Kind {
    fn of(s: &Surface, selection: &SelectionConfig) -> Self {
        let tilt = s.tilt_deg();
        let bend = floor_bend_at(s, selection);
        if tilt <= bend.min(selection.parallel_tolerance_deg) {
            Kind::Level
        } else if tilt <= selection.parallel_tolerance_deg {
            Kind::Gentle
        } else if tilt <= selection.max_slope_deg {
            Kind::Inclined
        } else {
            Kind::FacingDown
        }
    }
}

/// The sensor's floor bend (`sensor_noise.rs`) at the middle of `s`'s
/// forward extent, degrees: a ramp is tilted beyond it.
pub fn floor_bend_at(s: &Surface, selection: &SelectionConfig) -> f64 {
    super::floor::bend_at(s, selection.noise_model.unwrap_or_default())
}

/// A surface something else can stand on: its height band and footprint.
#[derive(Debug, Clone, Copy)]
struct Support {
    /// Index in the surfaces; `None` for the mount's ground (no plane).
    index: Option<usize>,
    role: SurfaceRole,
    lowest_m: f64,
    highest_m: f64,
    /// Forward and lateral extent; unbounded for the mount's ground.
    ahead: (f64, f64),
    lateral: (f64, f64),
}

impl Support {
    fn of(k: usize, s: &Surface) -> Self {
        Self {
            index: Some(k),
            role: s.role,
            lowest_m: s.lowest_m,
            highest_m: s.highest_m,
            ahead: (s.distance_m, s.far_m),
            lateral: (s.left_m, s.right_m),
        }
    }

    /// The ground from the mount: everywhere at height 0.
    fn mount() -> Self {
        let all = (f64::NEG_INFINITY, f64::INFINITY);
        Self {
            index: None,
            role: SurfaceRole::Ground,
            lowest_m: 0.0,
            highest_m: 0.0,
            ahead: all,
            lateral: all,
        }
    }

    /// The height of a level support (the middle of its band).
    fn level_height(&self) -> f64 {
        0.5 * (self.lowest_m + self.highest_m)
    }

    /// The gap between its footprint and `s`'s, metres (0 when they overlap).
    fn gap_to(&self, s: &Surface) -> f64 {
        let gap = |(a0, a1): (f64, f64), (b0, b1): (f64, f64)| (a0 - b1).max(b0 - a1).max(0.0);
        gap(self.ahead, (s.distance_m, s.far_m)).hypot(gap(self.lateral, (s.left_m, s.right_m)))
    }
}

/// Joins surfaces to the ground, steps and ramps in rounds until no more
/// join (at most one round per surface).
fn join_in_rounds(surfaces: &mut [Surface], selection: &SelectionConfig, road: &RoadConfig) {
    let mut supports: Vec<Support> =
        match surfaces.iter().position(|s| s.role == SurfaceRole::Ground) {
            Some(g) => vec![Support::of(g, &surfaces[g])],
            None => vec![Support::mount()],
        };
    for _round in 0..surfaces.len() {
        let mut joined = false;
        for (k, s) in surfaces.iter_mut().enumerate() {
            if s.role != SurfaceRole::Elevated || s.support != SurfaceSupport::None {
                continue;
            }
            let Some(on) = supports
                .iter()
                .find(|u| meets(s, u, selection, road))
                .copied()
            else {
                continue;
            };
            s.role = match Kind::of(s, selection) {
                Kind::Level => SurfaceRole::Step,
                Kind::Gentle if !rises_from(s, &on, road) => SurfaceRole::Step,
                _ => inclined_role(s, road),
            };
            s.support = match on.role {
                SurfaceRole::Ground => SurfaceSupport::Ground,
                SurfaceRole::Ramp => SurfaceSupport::Ramp,
                _ => SurfaceSupport::Step,
            };
            s.supported_by = on.index;
            s.joins_ground = true;
            if matches!(s.role, SurfaceRole::Step | SurfaceRole::Ramp) {
                supports.push(Support::of(k, s));
            }
            joined = true;
        }
        if !joined {
            break;
        }
    }
}

/// `ramp` up to `max_ramp_deg`, else `wall`.
fn inclined_role(s: &Surface, road: &RoadConfig) -> SurfaceRole {
    if s.tilt_deg() <= road.max_ramp_deg {
        SurfaceRole::Ramp
    } else {
        SurfaceRole::Wall
    }
}

/// True when `s` meets the support `u` (rules 3 and 4 of the module).
fn meets(s: &Surface, u: &Support, selection: &SelectionConfig, road: &RoadConfig) -> bool {
    let tol = road.join_tolerance_m;
    // The ground goes on where it is not seen (its far rows, seen at a
    // grazing angle, are the sparsest and the outlier filter's first
    // victims): only a step or a ramp must be seen next to `s`.
    if u.role != SurfaceRole::Ground && u.gap_to(s) > road.max_step_rise_m + tol {
        return false;
    }
    match Kind::of(s, selection) {
        Kind::Level => meets_as_level(s, u, road),
        Kind::Gentle => rises_from(s, u, road) || meets_as_level(s, u, road),
        Kind::Inclined => rises_from(s, u, road),
        Kind::FacingDown => false,
    }
}

/// A level `s` meets `u`: a ramp's top or bottom edge at its height, or a
/// rise from a level `u` of at most `max_step_rise_m`.
fn meets_as_level(s: &Surface, u: &Support, road: &RoadConfig) -> bool {
    let tol = road.join_tolerance_m;
    let h = 0.5 * (s.lowest_m + s.highest_m);
    if u.role == SurfaceRole::Ramp {
        return (h - u.highest_m).abs() <= tol || (h - u.lowest_m).abs() <= tol;
    }
    (h - u.level_height()).abs() <= road.max_step_rise_m + tol
}

/// An inclined `s` rises from (or falls to) the level `u` (the ground or a
/// step): its inliers reach `u`'s height within `join_tolerance_m`.
fn rises_from(s: &Surface, u: &Support, road: &RoadConfig) -> bool {
    let tol = road.join_tolerance_m;
    let h = u.level_height();
    matches!(u.role, SurfaceRole::Ground | SurfaceRole::Step)
        && s.lowest_m - h <= tol
        && s.highest_m - h >= -tol
}
