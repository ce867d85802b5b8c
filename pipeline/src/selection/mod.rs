//! Which segmented planes are the ground and which the inclined plane; the
//! slope's sign and the distance to the inclined plane.
//!
//! Every plane's normal points towards the camera, so `d` in `n . x + d = 0`
//! is the camera's distance from the plane.
//!
//! 1. **Reference up.** With a mount (known pitch), the mount's up vector;
//!    without one, the camera's -y axis (an upright camera).
//! 2. **Flat planes only.** A plane whose inliers fill its RANSAC threshold
//!    band instead of hugging the plane (relative RMS above
//!    `max_relative_rms`: fabric, clutter, people) is not a measurement
//!    surface: it is neither ground nor inclined plane.
//! 3. **Ground** ([`ground`]): the lowest well-supported plane parallel to
//!    the level plane nearest the mount's up (or, without a mount, the one
//!    in front of the robot), at the mount's height when that is known,
//!    measured on all of its segments; else the mount's plane
//!    (`ground_from_mount`); else `NoGround`.
//! 4. **Forward.** The optical axis projected onto the ground.
//! 5. **Surfaces** ([`surfaces`], [`roles`]): every plane described in the
//!    ground frame (slope, heading, extents, heights) with a role: ground,
//!    step, ramp, wall, elevated, overhang.
//! 6. **The road** ([`road`]): the nearest ramp or wall in the robot's
//!    corridor that passes the inclined plane's tests ([`inclined`]: flat,
//!    large enough, inclined, not facing down, facing along forward); else
//!    `NoInclinedPlane`.
//! 7. **Sign.** Uphill (positive) when the inclined plane's normal points
//!    back towards the robot, downhill (negative) when it points forward.
//! 8. **Distance.** Along the optical axis to the inclined plane.
//!
//! The chosen planes' pixels (`segment.rs`): the inclined plane's, and the
//! ground's segments joined into one, their quality pooled
//! (`quality.rs`).

mod config;
pub mod floor;
pub mod ground;
mod ground_frame;
mod hidden_foot;
pub mod inclined;
pub mod quality;
pub mod road;
mod road_config;
pub mod roles;
mod scene;
mod segment;
pub mod surfaces;

use nalgebra::Vector3;
use slope_ipc_types::EstimateStatus;

use crate::cloud::CloudView;
use crate::plane_fit::Plane;
use crate::ransac_planes::{SegmentedPlane, Threshold};
use crate::sensor_noise::NoiseModel;

pub use config::SelectionConfig;
pub use ground::Ground;
pub use ground_frame::GroundFrame;
pub use hidden_foot::foot_is_hidden;
pub use inclined::{axis_distance, forward_direction, slope_sign};
pub use quality::{plane_quality, PlaneQuality};
pub use road::{choose_road, road_pieces, Road};
pub use road_config::RoadConfig;
pub use roles::assign_roles;
pub use scene::{survey_surfaces, RoadScene, SurveyInput};
pub(crate) use segment::{chosen_segments, PlaneSegment};
pub use surfaces::{describe_surfaces, plane_axes, Surface, CORRIDOR_MIN_PIXELS, CORRIDOR_SAMPLES};

/// The lowest rows of the image, as a share of its height, in which the
/// nearest floor is told from a surface beyond it
/// ([`PlaneSummary::bottom_band_pixels`]).
pub const BOTTOM_BAND_SHARE: f64 = 0.05;

/// What selection needs to know about a segmented plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneSummary {
    /// Normal towards the camera and offset.
    pub plane: Plane,
    /// Inlier pixels.
    pub inliers: usize,
    /// Inlier pixels in the bottom third of the image's rows.
    pub bottom_pixels: usize,
    /// Inlier pixels in the lowest [`BOTTOM_BAND_SHARE`] of the image's
    /// rows (the floor right before the robot).
    pub bottom_band_pixels: usize,
    /// How far down the image its lowest inliers reach, as a share of the
    /// image's rows (0 top, 1 bottom): the row of the inlier a hundredth of
    /// them from the last (stray pixels do not count); 0 for a plane
    /// without inliers.
    pub lowest_row: f64,
    pub centroid: Vector3<f64>,
    pub quality: PlaneQuality,
}

/// The chosen pair.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    pub ground: Ground,
    pub inclined: usize,
    /// Other pieces of the inclined plane's surface (plane indices; see
    /// [`road::road_pieces`]), measured with it; empty when chosen on the
    /// summaries alone.
    pub inclined_pieces: Vec<usize>,
    /// Ground normal used for the direction (unit, up): the lowest ground
    /// plane's, or the reference up for a ground from the mount.
    pub up: Vector3<f64>,
    /// The robot's forward direction (unit, perpendicular to `up`).
    pub forward: Vector3<f64>,
}

impl PlaneSummary {
    /// The summary of a segmented plane of `cloud`; `threshold` is the
    /// RANSAC inlier distance the plane was found with, `noise` the sensor's.
    pub fn of(
        cloud: &CloudView<'_>,
        plane: &SegmentedPlane,
        threshold: &Threshold,
        noise: NoiseModel,
    ) -> Self {
        let bottom_start = (cloud.height - cloud.height / 3) * cloud.width;
        let band_rows = (cloud.height as f64 * BOTTOM_BAND_SHARE).ceil() as usize;
        let band_start = cloud.height.saturating_sub(band_rows) * cloud.width;
        let below = |start: usize| {
            plane.inliers.len() - plane.inliers.partition_point(|&i| (i as usize) < start)
        };
        Self {
            plane: plane.plane,
            inliers: plane.inliers.len(),
            // Inliers are in pixel order: those of the bottom rows are a tail.
            bottom_pixels: below(bottom_start),
            bottom_band_pixels: below(band_start),
            lowest_row: lowest_row(&plane.inliers, cloud.width, cloud.height),
            centroid: plane.centroid,
            quality: plane_quality(cloud, &plane.plane, &plane.inliers, threshold, noise),
        }
    }
}

/// The row of the inlier a hundredth of `inliers` (pixel indices in pixel
/// order) from the last, as a share of `height` rows; 0 without inliers.
fn lowest_row(inliers: &[u32], width: usize, height: usize) -> f64 {
    let rank = inliers.len().saturating_sub(1 + inliers.len() / 100);
    inliers.get(rank).map_or(0.0, |&i| {
        (i as usize / width.max(1)) as f64 / height.saturating_sub(1).max(1) as f64
    })
}

/// At most this share of a surface's inliers are veil points (mixed
/// readings along a depth edge, `quality::is_veil_point`): a plane made
/// mostly of them (the streak of readings between a person's legs and the
/// floor behind) is no surface.
pub const MAX_VEIL_FRACTION: f64 = 0.5;

/// True when the plane is a surface at all: not made mostly of veil points.
pub fn is_surface(plane: &PlaneSummary) -> bool {
    plane.quality.veil_fraction <= MAX_VEIL_FRACTION
}

/// A level plane whose RMS is at most this many standard deviations of the
/// sensor's noise is flat enough to be the ground even when it fills its
/// RANSAC band (a Kinect v1 floor 3 m away, whose noise is as wide as the
/// band): what the sensor cannot tell from flat is flat. Only the ground:
/// a person's legs 3 m before a Kinect v1 are as flat at its noise level,
/// and must not become the road.
pub const GROUND_NOISE_RATIO: f64 = 1.5;

/// True when the plane is a surface flat within its RANSAC band: it does
/// not fill the band evenly (the test every plane passes, ground segments
/// included).
pub fn is_flat(plane: &PlaneSummary, config: &SelectionConfig) -> bool {
    is_surface(plane) && plane.quality.relative_rms <= config.max_relative_rms
}

/// The ground's flatness: flat within its RANSAC band ([`is_flat`]), or a
/// surface flat at the sensor's noise level (at most
/// [`GROUND_NOISE_RATIO`]).
pub fn is_flat_for_ground(plane: &PlaneSummary, config: &SelectionConfig) -> bool {
    is_flat(plane, config) || (is_surface(plane) && plane.quality.noise_ratio <= GROUND_NOISE_RATIO)
}

/// True when the plane is flat at the sensor's noise level as well (the
/// test the inclined plane passes: its normal is the measurement).
pub fn is_flat_at_noise_level(plane: &PlaneSummary, config: &SelectionConfig) -> bool {
    is_flat(plane, config) && plane.quality.noise_ratio <= config.max_noise_ratio
}

/// The ground alone (the first half of [`select_planes`]); `None`: no
/// level plane and no mount to fall back on.
pub fn select_ground(
    planes: &[PlaneSummary],
    mount_up: Option<Vector3<f64>>,
    mount_height_m: Option<f64>,
    config: &SelectionConfig,
) -> Option<Ground> {
    let mount_up = mount_up.and_then(|u| u.try_normalize(1e-12));
    let reference = mount_up.unwrap_or(-Vector3::y());
    let height = mount_height_m.filter(|h| h.is_finite() && *h > 0.0 && mount_up.is_some());
    ground::choose_ground(planes, &reference, height, mount_up.is_some(), config)
}

/// True when a mount is known and the floor the data shows disagrees with
/// the ground chosen by it: the nearest floor ([`ground::nearest_floor`]
/// among the flat planes within `unmounted_ground_max_tilt_deg` of the
/// mount's up) is not parallel (`parallel_tolerance_deg`) to the ground's
/// up (the mount's own, for a ground from the mount), is tilted more than
/// `ground_max_tilt_deg` from the mount's up, or, with a known mount
/// height, lies further than `ground_height_tolerance_m` from it.
/// The robot may be tilted on its mount, or the mount's figures wrong: the
/// estimate's confidence says so (`mount_mismatch`) instead of picking
/// silently.
pub fn mount_disagrees(
    planes: &[PlaneSummary],
    ground: &Ground,
    mount_up: Option<Vector3<f64>>,
    mount_height_m: Option<f64>,
    config: &SelectionConfig,
) -> bool {
    let Some(mount_up) = mount_up.and_then(|u| u.try_normalize(1e-12)) else {
        return false;
    };
    let level: Vec<usize> = (0..planes.len())
        .filter(|&k| {
            is_flat_for_ground(&planes[k], config)
                && crate::cloud::angle_between_deg(&planes[k].plane.normal, &mount_up)
                    <= config.unmounted_ground_max_tilt_deg
        })
        .collect();
    let Some(floor) = ground::nearest_floor(planes, &level, config) else {
        return false;
    };
    let floor = &planes[floor];
    let up = match ground {
        Ground::Planes(members) => match members.first().and_then(|&k| planes.get(k)) {
            Some(lowest) => lowest.plane.normal,
            None => return false,
        },
        Ground::Mount => mount_up,
    };
    let tilted =
        crate::cloud::angle_between_deg(&floor.plane.normal, &up) > config.parallel_tolerance_deg;
    let height = mount_height_m.filter(|h| h.is_finite() && *h > 0.0);
    let off_height = height.is_some_and(|h| {
        (-mount_up.dot(&floor.centroid) - h).abs() > config.ground_height_tolerance_m
    });
    tilted || off_height
}

/// Chooses ground and inclined plane from the planes' summaries alone:
/// the nearest forward-facing candidate (`inclined.rs`), which does not ask
/// whether it meets the ground or lies in the corridor. The estimator
/// chooses the road with [`survey_surfaces`] instead (it needs the
/// inliers); this rule stays for callers that have summaries only.
/// `mount_up` is the mount's up vector (known pitch), `mount_height_m` its
/// height above the ground (when known). The error is the status to report.
pub fn select_planes(
    planes: &[PlaneSummary],
    mount_up: Option<Vector3<f64>>,
    mount_height_m: Option<f64>,
    config: &SelectionConfig,
) -> Result<Selection, EstimateStatus> {
    let ground =
        select_ground(planes, mount_up, mount_height_m, config).ok_or(EstimateStatus::NoGround)?;
    select_inclined(planes, ground, mount_up, config)
        .map_err(|_ground| EstimateStatus::NoInclinedPlane)
}

/// The inclined plane over `ground` (the second half of
/// [`select_planes`]); without one, the error gives the ground back (a
/// flat floor ahead is still a measurement). A `Ground::Planes` whose first
/// (lowest) index is missing or not an index into `planes` has no inclined
/// plane either.
pub fn select_inclined(
    planes: &[PlaneSummary],
    ground: Ground,
    mount_up: Option<Vector3<f64>>,
    config: &SelectionConfig,
) -> Result<Selection, Ground> {
    let reference = mount_up
        .and_then(|u| u.try_normalize(1e-12))
        .unwrap_or(-Vector3::y());
    let up = match &ground {
        Ground::Planes(members) => match members.first().and_then(|&k| planes.get(k)) {
            Some(lowest) => lowest.plane.normal,
            // No lowest plane among `planes` (an empty list, an index out of
            // range): nothing to measure a slope against.
            None => return Err(ground),
        },
        Ground::Mount => reference,
    };
    let members: &[usize] = match &ground {
        Ground::Planes(members) => members,
        Ground::Mount => &[],
    };
    let forward = forward_direction(&up);
    match inclined::choose_inclined(planes, members, &up, &forward, config) {
        Some(inclined) => Ok(Selection {
            ground,
            inclined,
            inclined_pieces: Vec::new(),
            up,
            forward,
        }),
        None => Err(ground),
    }
}

#[cfg(test)]
mod tests;
