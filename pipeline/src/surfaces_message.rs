//! An [`Estimate`]'s surfaces written into the `Surfaces` message
//! (`slope.Surfaces.v1`): at most [`MAX_SURFACES`], the largest first, the
//! road always among them.

use slope_ipc_types::{surface_flags, SurfaceDescription, Surfaces, MAX_SURFACES, NO_SURFACE};

use crate::estimate::Estimate;
use crate::selection::{RoadScene, Surface};

impl Estimate {
    /// Fills the estimate's fields of `msg` (not the stamps or frame index,
    /// which belong to the caller): status, the ground frame, the corridor
    /// and the surfaces. Without surfaces (no ground, a failed frame) the
    /// count is 0, the road none, the frame NaN.
    pub fn write_surfaces(&self, msg: &mut Surfaces) {
        msg.status = self.status as u32;
        msg.count = 0;
        msg.road = NO_SURFACE;
        msg.ground_from_mount = 0;
        msg.up = [f64::NAN; 3];
        msg.forward = [f64::NAN; 3];
        msg.ground_plane = [0.0; 4];
        msg.corridor_half_width_m = f64::NAN;
        msg.look_ahead_m = f64::NAN;
        msg.surfaces = [SurfaceDescription::EMPTY; MAX_SURFACES];
        let Some(scene) = &self.scene else {
            return;
        };
        msg.up = scene.frame.up.into();
        msg.forward = scene.frame.forward.into();
        msg.ground_plane = scene.frame.ground.coefficients();
        msg.corridor_half_width_m = scene.corridor_half_width_m;
        msg.look_ahead_m = scene.look_ahead_m;
        msg.ground_from_mount = u32::from(
            !scene
                .surfaces
                .iter()
                .any(|s| s.role == slope_ipc_types::SurfaceRole::Ground),
        );
        let order = message_order(scene);
        let slot_of = |k: usize| order.iter().position(|&o| o == k);
        for (slot, &k) in order.iter().enumerate() {
            let s = &scene.surfaces[k];
            let supported_by = s.supported_by.and_then(slot_of);
            msg.surfaces[slot] = describe(s, supported_by);
        }
        msg.count = order.len() as u32;
        msg.road = scene
            .road
            .and_then(|r| slot_of(r.surface))
            .map_or(NO_SURFACE, |slot| slot as u32);
    }
}

/// The surfaces a message carries, as indices into `scene.surfaces`: the
/// [`MAX_SURFACES`] with the most inliers (ties: the earlier), largest
/// first, the road in place of the last when it is not among them.
pub fn message_order(scene: &RoadScene) -> Vec<usize> {
    let mut order: Vec<usize> = (0..scene.surfaces.len()).collect();
    order.sort_by(|&a, &b| {
        scene.surfaces[b]
            .inliers
            .cmp(&scene.surfaces[a].inliers)
            .then(a.cmp(&b))
    });
    order.truncate(MAX_SURFACES);
    if let Some(road) = scene.road {
        if !order.contains(&road.surface) {
            if let Some(last) = order.last_mut() {
                *last = road.surface;
            }
        }
    }
    order
}

/// One surface in the message's terms.
fn describe(s: &Surface, supported_by: Option<usize>) -> SurfaceDescription {
    let mut flags = 0;
    for (on, bit) in [
        (s.in_corridor, surface_flags::IN_CORRIDOR),
        (s.measurable, surface_flags::MEASURABLE),
        (s.joins_ground, surface_flags::JOINS_GROUND),
    ] {
        if on {
            flags |= bit;
        }
    }
    SurfaceDescription {
        role: s.role as u32,
        support: s.support as u32,
        supported_by: supported_by.map_or(NO_SURFACE, |k| k as u32),
        inliers: u32::try_from(s.inliers).unwrap_or(u32::MAX),
        flags,
        segments: u32::try_from(s.segments).unwrap_or(u32::MAX),
        slope_deg: s.slope_deg,
        heading_deg: s.heading_deg,
        distance_m: s.distance_m,
        far_m: s.far_m,
        left_m: s.left_m,
        right_m: s.right_m,
        lowest_m: s.lowest_m,
        highest_m: s.highest_m,
        area_m2: s.area_m2,
        rms_m: s.rms_m,
        noise_ratio: s.noise_ratio,
        plane: s.plane.coefficients(),
        outline: s.outline.map(|c| [c.x as f32, c.y as f32, c.z as f32]),
    }
}
