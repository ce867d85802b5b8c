//! Pieces of the floor that the sensor bends: surfaces that are the ground
//! seen further away, joined to the ground's surface (one floor, one
//! surface) instead of standing on it as steps or ramps.
//!
//! A real depth sensor bends a flat floor a little (its range bias,
//! `sensor_noise.rs`), and RANSAC cuts the bent floor into planes a few
//! degrees apart: a far piece, a piece between a person's legs, the floor
//! of the next room. What tells such a piece from a step or a ramp is not
//! its plane's tilt (a narrow piece's tilt is its fit's noise) but its
//! heights: every inlier of a floor piece lies within the floor's band of
//! the ground plane, where a step stands above it (a rise) and a ramp
//! climbs out of it. The band at `z` metres ahead is `road.join_tolerance_m`
//! plus the sensor's [`NoiseModel::floor_band_m`] (its height bias and two
//! standard deviations of its noise at a grazing angle), taken at the
//! piece's far end, where it is widest.
//!
//! A piece must also be tilted at most twice the sensor's floor bend at
//! the middle of its extent (a narrow piece's plane is tilted by its fit's
//! noise: a strip of floor between a person's legs, 6.3 degrees off on a
//! Kinect v1 whose bend there is 4.1; the foot of a wall and the visible
//! top of a ramp falling away lie in the band too, but are tilted further)
//! and be seen ahead of the robot.

use slope_ipc_types::SurfaceRole;

use super::{RoadConfig, Surface};
use crate::sensor_noise::NoiseModel;

/// The indices (in `surfaces`) of the surfaces that are pieces of the
/// ground's floor ([`is_floor_piece`]); none without a ground surface.
pub fn floor_pieces(surfaces: &[Surface], noise: NoiseModel, road: &RoadConfig) -> Vec<usize> {
    if !surfaces.iter().any(|s| s.role == SurfaceRole::Ground) {
        return Vec::new();
    }
    (0..surfaces.len())
        .filter(|&k| surfaces[k].role != SurfaceRole::Ground)
        .filter(|&k| is_floor_piece(&surfaces[k], noise, road))
        .collect()
}

/// True when every inlier of `s` lies within the floor's band of the
/// ground (heights measured from the ground plane), `s` is tilted at most
/// twice the floor bend at the middle of its extent and its far end is
/// ahead of the robot.
pub fn is_floor_piece(s: &Surface, noise: NoiseModel, road: &RoadConfig) -> bool {
    let bend = bend_at(s, noise);
    if !(s.far_m > 0.0) || !(s.tilt_deg() <= 2.0 * bend) {
        return false;
    }
    let band = road.join_tolerance_m + noise.floor_band_m(s.far_m);
    s.lowest_m >= -band && s.highest_m <= band
}

/// `noise`'s floor bend at the middle of `s`'s forward extent, degrees.
pub fn bend_at(s: &Surface, noise: NoiseModel) -> f64 {
    noise.floor_bend_deg(0.5 * (s.distance_m + s.far_m))
}
