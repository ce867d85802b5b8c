//! Real floors bent into ramps of known angle: test data with a real
//! sensor's noise, dropouts and texture, and an exact truth.
//!
//! A real depth frame's floor is found by a robust fit (RANSAC over the
//! up-facing points of the lower image, least-squares refits on its
//! inliers; the recording's `[mount]` as a hint, else the camera's -y), a
//! hinge line is laid across the path `hinge_m` ahead (perpendicular to the
//! optical axis projected onto the floor), and everything beyond it is
//! rotated rigidly upward by `angle_deg` about the line, so that each point
//! keeps its height above the floor as its height above the ramp. The bent
//! points are rendered back into the depth image through a triangle mesh
//! with a z-buffer, in the recording's unit, with holes (0) where nothing
//! covers a pixel; the colour rides along. The truth is exact: the angle
//! between the ramp and the fitted floor is `angle_deg`.
//!
//! Everything beyond the line moves, not only the floor's inliers: what
//! stands on the floor beyond the hinge stands on the ramp afterwards (a
//! box, a person, the foot of a wall), as on a real ramp, instead of
//! floating above or sinking into it; a side wall along the path stays in
//! its own plane (the rotation's axis is its normal).
//!
//! Files: `organised.rs` (the depth image as points with normals),
//! `floor_fit.rs` (the floor), `hinge.rs` (the floor's frame and the
//! rotation), `mesh_render.rs` (the z-buffered re-render), `write.rs` (a
//! bent recording on disk), `cli.rs` (`slope-bend`).
//!
//! What such data does not reproduce: the noise of the bent part is the
//! noise of the floor as it was seen (at its old incidence angle and range),
//! not that of a ramp facing the camera; there is no multipath or mixed
//! pixels at the fold (a real concave fold adds both); the fold is sampled
//! as densely as the floor was, interpolated between readings where the
//! ramp covers more pixels than the floor did (its noise is then spatially
//! correlated over a few pixels), and holes open where the bend uncovers
//! what was behind the floor; a Kinect v1's disparity terraces and range
//! bias are carried to the ramp at their old ranges.
//!
//! ```no_run
//! use slope_synth::bend::{bend_recording, BendParams};
//! let bent = bend_recording("../shared/data/kv2-mine-tunnel-0".as_ref(), 0, &BendParams::new(5.0, 1.5))?;
//! assert_eq!(bent.truth_deg, 5.0);
//! # Ok::<(), slope_synth::BendError>(())
//! ```

pub mod cli;
pub mod floor_fit;
pub mod hinge;
pub mod mesh_render;
pub mod organised;
pub mod write;

use std::path::Path;

use nalgebra::Vector3;
use slope_sensor::recording::{ColorImage, DepthImage, Recording, RecordingMeta};

pub use floor_fit::inlier_band_m;
pub use hinge::{FloorCoordinates, FloorPlane, Hinge};
pub use mesh_render::{RenderStats, NO_SOURCE};
pub use write::{write_bent_recording, BendSummary};

use crate::error::BendError;
use floor_fit::{fit_floor, FloorSearch};
use organised::OrganisedCloud;

/// Fewer floor points than this beyond the hinge line: the floor does not
/// reach past it (no ramp); before it: no ground stays in view, so the
/// ramp's angle to the ground could not be seen.
pub const MIN_FLOOR_POINTS: usize = 200;

/// The normal cone of floor candidates around the mount's up vector (an
/// IMU agrees with the floor to a few degrees), degrees.
const CONE_WITH_MOUNT_DEG: f64 = 30.0;
/// Around the camera's -y when no mount is known: wide enough for a camera
/// pitched 50° down, still excluding a wall facing a level camera.
const CONE_WITHOUT_MOUNT_DEG: f64 = 60.0;

/// One frame of a recording, loaded: what [`bend_floor`] bends.
#[derive(Debug, Clone)]
pub struct DepthFrame {
    /// Where it came from, for errors: "DIR frame N".
    pub origin: String,
    /// The recording's metadata (intrinsics, unit, mount, sensor).
    pub meta: RecordingMeta,
    pub timestamp_ns: u64,
    pub depth: DepthImage,
    pub color: Option<ColorImage>,
}

impl DepthFrame {
    /// Frame number `frame` (0-based position in `frames.csv`) of the
    /// recording in `dir`.
    pub fn read(dir: &Path, frame: usize) -> Result<Self, BendError> {
        let recording = Recording::open(dir).map_err(|source| BendError::Read {
            dir: dir.to_path_buf(),
            source,
        })?;
        Self::from_recording(&recording, frame)
    }

    /// Frame number `frame` of an opened recording.
    pub fn from_recording(recording: &Recording, frame: usize) -> Result<Self, BendError> {
        let dir = recording.dir();
        let entry = recording
            .frames()
            .get(frame)
            .ok_or_else(|| BendError::NoSuchFrame {
                dir: dir.to_path_buf(),
                frame,
                frames: recording.frames().len(),
            })?;
        let read_error = |source| BendError::Read {
            dir: dir.to_path_buf(),
            source,
        };
        Ok(Self {
            origin: format!("{} frame {frame}", dir.display()),
            meta: recording.meta().clone(),
            timestamp_ns: entry.timestamp_ns,
            depth: recording.read_depth(entry).map_err(read_error)?,
            color: recording.read_color(entry).map_err(read_error)?,
        })
    }
}

/// How to bend.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BendParams {
    /// The ramp's angle to the floor, degrees, in (0, 90].
    pub angle_deg: f64,
    /// Distance of the hinge line ahead of the camera's foot on the floor,
    /// along the optical axis projected onto the floor, metres (> 0).
    pub hinge_m: f64,
    /// Seed of the floor fit's RANSAC (the same seed, the same bytes).
    pub seed: u64,
}

impl BendParams {
    /// `angle_deg` at `hinge_m`, seed 0.
    pub fn new(angle_deg: f64, hinge_m: f64) -> Self {
        Self {
            angle_deg,
            hinge_m,
            seed: 0,
        }
    }

    /// Refuses an angle outside (0, 90] or a hinge that is not a positive
    /// distance.
    pub fn check(&self) -> Result<(), BendError> {
        if !(self.angle_deg > 0.0 && self.angle_deg <= 90.0) {
            return Err(BendError::InvalidParameter {
                name: "angle_deg",
                value: self.angle_deg,
                reason: ANGLE_RANGE,
            });
        }
        if !(self.hinge_m > 0.0 && self.hinge_m.is_finite()) {
            return Err(BendError::InvalidParameter {
                name: "hinge_m",
                value: self.hinge_m,
                reason: HINGE_RANGE,
            });
        }
        Ok(())
    }
}

/// What an angle outside (0, 90] is told.
pub const ANGLE_RANGE: &str =
    "must be above 0 and at most 90 degrees (the floor is bent upward into a ramp)";
/// What a hinge distance that is not positive is told.
pub const HINGE_RANGE: &str = "must be a distance ahead above 0 metres";

/// Where a frame's floor is seen, along the path.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FloorExtent {
    /// Distance ahead of the nearest floor points (0.5th percentile), metres.
    pub from_m: f64,
    /// Distance ahead of the farthest (99.5th percentile), metres.
    pub reach_m: f64,
    /// Floor points before the hinge line (they stay: the ground).
    pub before_hinge: usize,
    /// Floor points beyond it (they become the ramp).
    pub beyond_hinge: usize,
}

/// A bent frame and its truth.
#[derive(Debug, Clone)]
pub struct BentFrame {
    /// The re-rendered depth image (the source's size and unit).
    pub depth: DepthImage,
    /// The colour carried along, when the source had colour.
    pub color: Option<ColorImage>,
    /// The source's metadata with `[truth] slope_deg` set to the angle
    /// (sensor, intrinsics and mount kept).
    pub meta: RecordingMeta,
    /// The exact angle between the ramp and the fitted floor, degrees.
    pub truth_deg: f64,
    /// The fitted floor, the hinge line and the rotation.
    pub hinge: Hinge,
    /// Where the floor was seen, before bending.
    pub floor: FloorExtent,
    /// The angle between the floor's own least-squares planes up to 1 m
    /// before and up to 1 m beyond the hinge line, before bending, degrees
    /// (`None` with fewer than [`MIN_FLOOR_POINTS`] on a side): how far the
    /// real floor is from flat there. The ramp is that far floor turned by
    /// the truth, so a plane fitted to the ramp meets the near floor at the
    /// truth give or take this much.
    pub floor_bend_deg: Option<f64>,
    /// Per output pixel (row-major), the source pixel its reading comes
    /// from: itself before the hinge, the nearest vertex of the bent
    /// triangle that covers it beyond; [`NO_SOURCE`] without a reading.
    pub source_pixel: Vec<u32>,
    pub stats: RenderStats,
}

/// Bends `frame`'s floor beyond `params.hinge_m` upward by
/// `params.angle_deg`. Refuses a frame without a floor, whose floor does
/// not reach past the hinge, or whose floor is first seen beyond it (no
/// ground would stay in view), each by [`MIN_FLOOR_POINTS`], naming the
/// frame.
pub fn bend_floor(frame: &DepthFrame, params: &BendParams) -> Result<BentFrame, BendError> {
    params.check()?;
    let info = frame.meta.depth;
    let pixels = info.width as usize * info.height as usize;
    if frame.depth.width != info.width
        || frame.depth.height != info.height
        || frame.depth.data.len() != pixels
    {
        return Err(BendError::BadFrame {
            origin: frame.origin.clone(),
            reason: format!(
                "the depth image is {} x {} ({} values), [depth] says {} x {}",
                frame.depth.width,
                frame.depth.height,
                frame.depth.data.len(),
                info.width,
                info.height
            ),
        });
    }
    let color = frame.color.as_ref().filter(|c| c.data.len() == pixels);
    if frame.color.is_some() && color.is_none() {
        return Err(BendError::BadFrame {
            origin: frame.origin.clone(),
            reason: "the colour image's size differs from the depth image's".into(),
        });
    }

    let cloud = OrganisedCloud::new(&frame.depth, &info);
    let search = match frame.meta.mount.to_mount().up_vector() {
        Some(up) => FloorSearch {
            hint_up: Vector3::from(up),
            cone_deg: CONE_WITH_MOUNT_DEG,
            seed: params.seed,
        },
        None => FloorSearch {
            hint_up: -Vector3::y(),
            cone_deg: CONE_WITHOUT_MOUNT_DEG,
            seed: params.seed,
        },
    };
    let floor = fit_floor(&cloud, &search).map_err(|failure| BendError::NoFloor {
        origin: frame.origin.clone(),
        reason: failure.to_string(),
    })?;
    let hinge = Hinge::new(floor, params.hinge_m, params.angle_deg).ok_or_else(|| {
        BendError::NoForward {
            origin: frame.origin.clone(),
        }
    })?;

    let extent = floor_extent(&cloud, &hinge);
    if extent.beyond_hinge < MIN_FLOOR_POINTS {
        return Err(BendError::FloorShort {
            origin: frame.origin.clone(),
            hinge_m: params.hinge_m,
            reach_m: extent.reach_m,
            beyond: extent.beyond_hinge,
            needed: MIN_FLOOR_POINTS,
        });
    }
    if extent.before_hinge < MIN_FLOOR_POINTS {
        return Err(BendError::NoGroundBeforeHinge {
            origin: frame.origin.clone(),
            hinge_m: params.hinge_m,
            from_m: extent.from_m,
            before: extent.before_hinge,
            needed: MIN_FLOOR_POINTS,
        });
    }

    let rendered = mesh_render::render_bent(&cloud, &frame.depth, color, &info, &hinge);
    let mut meta = frame.meta.clone();
    meta.truth.slope_deg = Some(params.angle_deg);
    tracing::debug!(
        origin = %frame.origin,
        up = ?floor.up,
        height_m = floor.height_m,
        rms_m = floor.rms_m,
        floor_from_m = extent.from_m,
        floor_reach_m = extent.reach_m,
        moved = rendered.stats.moved_points,
        hidden = rendered.stats.kept_pixels_hidden,
        "bent"
    );
    Ok(BentFrame {
        depth: rendered.depth,
        color: rendered.color,
        meta,
        truth_deg: params.angle_deg,
        hinge,
        floor: extent,
        floor_bend_deg: floor_bend_deg(&cloud, &hinge),
        source_pixel: rendered.source_pixel,
        stats: rendered.stats,
    })
}

/// Frame `frame` (0-based) of the recording in `dir`, bent: for tests in
/// other crates that want bent real floors in memory.
pub fn bend_recording(
    dir: &Path,
    frame: usize,
    params: &BendParams,
) -> Result<BentFrame, BendError> {
    bend_floor(&DepthFrame::read(dir, frame)?, params)
}

/// Where the floor is seen: from its nearest to its farthest point ahead
/// (0.5th and 99.5th percentiles of its points' distance ahead) and how many
/// of its points lie before and beyond the hinge. A floor point lies within
/// [`inlier_band_m`] of the plane and, where it has a normal, faces within
/// 45° of the floor's.
fn floor_extent(cloud: &OrganisedCloud, hinge: &Hinge) -> FloorExtent {
    let up = Vector3::from(hinge.floor.up);
    let cos_max = 45f64.to_radians().cos();
    let mut ahead: Vec<f64> = cloud
        .points
        .iter()
        .zip(&cloud.normals)
        .filter_map(|(p, n)| {
            let p = (*p)?;
            let c = hinge.coordinates(p.into());
            let on_plane = c.height_m.abs() <= inlier_band_m(p.z);
            let facing = n.is_none_or(|n| n.dot(&up) >= cos_max);
            (on_plane && facing).then_some(c.ahead_m)
        })
        .collect();
    if ahead.is_empty() {
        return FloorExtent::default();
    }
    ahead.sort_by(f64::total_cmp);
    let beyond = ahead.iter().filter(|&&a| a > hinge.hinge_m).count();
    let last = ahead.len() - 1;
    let at = |q: f64| ahead[((last as f64 * q).round() as usize).min(last)];
    FloorExtent {
        from_m: at(0.005),
        reach_m: at(0.995),
        before_hinge: ahead.len() - beyond,
        beyond_hinge: beyond,
    }
}

/// [`BentFrame::floor_bend_deg`]: the floor points (as in [`floor_extent`])
/// up to 1 m before and beyond the hinge, a least-squares plane each.
fn floor_bend_deg(cloud: &OrganisedCloud, hinge: &Hinge) -> Option<f64> {
    let up = Vector3::from(hinge.floor.up);
    let cos_max = 45f64.to_radians().cos();
    let (mut near, mut far) = (Vec::new(), Vec::new());
    for (p, n) in cloud.points.iter().zip(&cloud.normals) {
        let Some(p) = *p else { continue };
        let c = hinge.coordinates(p.into());
        if c.height_m.abs() > inlier_band_m(p.z) || n.is_some_and(|n| n.dot(&up) < cos_max) {
            continue;
        }
        let from_hinge = c.ahead_m - hinge.hinge_m;
        if (-1.0..0.0).contains(&from_hinge) {
            near.push(p);
        } else if (0.0..1.0).contains(&from_hinge) {
            far.push(p);
        }
    }
    if near.len() < MIN_FLOOR_POINTS || far.len() < MIN_FLOOR_POINTS {
        return None;
    }
    let (a, _) = floor_fit::least_squares_plane(&near, up)?;
    let (b, _) = floor_fit::least_squares_plane(&far, up)?;
    Some(a.angle(&b).to_degrees())
}
