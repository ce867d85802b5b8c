//! [`RoadScene`]: every surface of a frame with its role, and the road,
//! from the ground and the segmented planes (`survey_surfaces`).

use nalgebra::Vector3;
use slope_ipc_types::{SurfaceRole, SurfaceSupport};

use super::floor::floor_pieces;
use super::{
    assign_roles, choose_road, describe_surfaces, Ground, GroundFrame, PlaneSummary, Road,
    RoadConfig, SelectionConfig, Surface,
};
use crate::cloud::CloudView;
use crate::ransac_planes::SegmentedPlane;

/// What the estimator saw of the scene in one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct RoadScene {
    pub frame: GroundFrame,
    /// The ground first (when a ground plane was seen), then every other
    /// plane in segmentation order.
    pub surfaces: Vec<Surface>,
    /// The segmented planes the ground's surface is made of: its coplanar
    /// segments (the ground measured), then the floor pieces joined to it
    /// (`floor.rs`); empty for a ground from the mount.
    pub ground_planes: Vec<usize>,
    pub road: Option<Road>,
    /// True when heights above the ground are known (a ground plane was
    /// seen, or the mount's height is known).
    pub heights_known: bool,
    pub corridor_half_width_m: f64,
    pub look_ahead_m: f64,
}

impl RoadScene {
    /// The road's surface.
    pub fn road_surface(&self) -> Option<&Surface> {
        self.road.and_then(|r| self.surfaces.get(r.surface))
    }
}

/// What the survey needs beside the planes.
#[derive(Debug, Clone, Copy)]
pub struct SurveyInput<'a> {
    pub cloud: &'a CloudView<'a>,
    pub planes: &'a [SegmentedPlane],
    pub summaries: &'a [PlaneSummary],
    /// The mount's up vector (unit) and height, when known.
    pub mount_up: Option<Vector3<f64>>,
    pub mount_height_m: Option<f64>,
}

/// Every surface over `ground`, its role, and the road.
///
/// With a ground from the mount whose height is unknown, heights cannot be
/// measured: level surfaces stay `elevated` (nothing tells a step from a
/// table) and every inclined one counts as standing on the ground out of
/// sight (support `hidden`), so that the road is the nearest ramp or wall
/// in the corridor.
pub fn survey_surfaces(
    input: &SurveyInput<'_>,
    ground: &Ground,
    selection: &SelectionConfig,
    road: &RoadConfig,
) -> Option<RoadScene> {
    let (frame, members) = match ground {
        Ground::Planes(members) => {
            let lowest = input.summaries.get(*members.first()?)?;
            (GroundFrame::over(lowest.plane), members.as_slice())
        }
        Ground::Mount => {
            let up = input
                .mount_up
                .and_then(|u| u.try_normalize(1e-12))
                .unwrap_or(-Vector3::y());
            let height = input.mount_height_m.filter(|h| h.is_finite() && *h > 0.0);
            (
                GroundFrame::of_mount(up, height.unwrap_or(f64::NAN)),
                &[][..],
            )
        }
    };
    let heights_known = frame.ground.d.is_finite();
    let describe = |members: &[usize]| {
        describe_surfaces(
            input.cloud,
            input.planes,
            input.summaries,
            members,
            &frame,
            selection,
            road,
        )
    };
    let mut surfaces = describe(members);
    let noise = selection.noise_model.unwrap_or_default();
    let pieces = floor_pieces(&surfaces, noise, road);
    let mut ground_planes = members.to_vec();
    if !pieces.is_empty() {
        // One floor, one surface: the pieces join the ground's segments.
        ground_planes.extend(pieces.iter().map(|&k| surfaces[k].plane_index));
        surfaces = describe(&ground_planes);
    }
    if heights_known {
        assign_roles(
            &mut surfaces,
            input.cloud,
            input.planes,
            &frame,
            selection,
            road,
        );
    } else {
        assume_inclined_surfaces_stand(&mut surfaces, selection, road);
    }
    let chosen = choose_road(&surfaces, input.summaries, &frame, selection, road);
    Some(RoadScene {
        frame,
        surfaces,
        ground_planes,
        road: chosen,
        heights_known,
        corridor_half_width_m: road.corridor_half_width_m,
        look_ahead_m: road.look_ahead_m,
    })
}

/// Without heights: inclined surfaces are ramps or walls standing out of
/// sight, surfaces facing down overhangs, the rest elevated.
fn assume_inclined_surfaces_stand(
    surfaces: &mut [Surface],
    selection: &SelectionConfig,
    road: &RoadConfig,
) {
    for s in surfaces.iter_mut() {
        let tilt = s.tilt_deg();
        if tilt > selection.max_slope_deg {
            s.role = SurfaceRole::Overhang;
        } else if tilt > super::roles::floor_bend_at(s, selection) {
            s.role = if tilt <= road.max_ramp_deg {
                SurfaceRole::Ramp
            } else {
                SurfaceRole::Wall
            };
            s.support = SurfaceSupport::Hidden;
            s.joins_ground = true;
        }
    }
}
