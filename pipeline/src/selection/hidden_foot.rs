//! Is an inclined surface's foot hidden, or is there a visible gap below it?
//!
//! A surface whose lowest inliers stay above the ground may still stand on
//! it: a box in front of a ramp hides the ramp's foot. What tells the two
//! apart is what the camera sees where the surface's plane, continued down
//! its fall line, would meet the ground. From the lowest inlier of each of
//! [`FOOT_BINS`] strips across the surface, [`MARCH_STEPS`] points are
//! placed on the plane's continuation down to the ground; at each one's
//! pixel the measured depth is
//!
//! - **farther** than the continuation (beyond `join_tolerance_m`): the
//!   camera sees past where the surface would be, so nothing is there (a
//!   board or a table top floating over the floor);
//! - **nearer**: something in front hides it (a box before a ramp);
//! - about the same: the surface goes on (pixels RANSAC gave to no plane).
//!
//! The foot is hidden when at least [`MIN_HIDDEN`] points are hidden and at
//! most a fifth as many are seen past. Points outside the image or without
//! a reading count for neither.
//!
//! Only a surface that rises away from the robot can stand on the ground
//! out of sight in front of it: its foot is its near edge, the one the
//! robot drives onto. A surface falling away (its uphill direction more
//! than [`MAX_FOOT_TURN_DEG`] from forward: it descends from its near
//! edge) would meet the ground beyond itself, and its near edge, the one
//! the robot reaches first, is in the air: a bump on a bed's cover whose
//! continuation runs under the bed's top is hidden, but no road. The rule
//! is for surfaces tilted less than [`FOOT_TURN_MAX_TILT_DEG`]: the uphill
//! direction of a wall is the noise of its normal (a riser at 90.1 degrees
//! "rises" backwards), so walls keep the test of their continuation alone.

use nalgebra::Vector3;

use super::{plane_axes, GroundFrame, Surface};
use crate::cloud::CloudView;

/// Strips across the surface whose lowest inliers are marched from.
pub const FOOT_BINS: usize = 5;
/// Points placed on the continuation of each strip's foot.
pub const MARCH_STEPS: usize = 8;
/// The lowest inliers are looked for among at most about this many.
pub const FOOT_SAMPLES: usize = 512;
/// Hidden points needed to call a foot hidden.
pub const MIN_HIDDEN: usize = 3;
/// The continuation is followed at most this far down the fall line,
/// metres.
const MAX_MARCH_M: f64 = 3.0;
/// A surface's uphill direction must be within this of forward (degrees,
/// either side) for its foot to be looked for: a ramp ahead or to the
/// side, not one falling away.
pub const MAX_FOOT_TURN_DEG: f64 = 120.0;
/// [`MAX_FOOT_TURN_DEG`] applies to surfaces tilted less than this,
/// degrees (the uphill direction of a steeper one is its normal's noise).
pub const FOOT_TURN_MAX_TILT_DEG: f64 = 80.0;

/// True when the foot of `surface` (whose inliers are `inliers`, pixel
/// indices of `cloud`) is hidden behind something nearer, never seen past.
/// `margin_m` is how far a depth may differ from the continuation and
/// still be on it.
pub fn foot_is_hidden(
    cloud: &CloudView<'_>,
    inliers: &[u32],
    surface: &Surface,
    frame: &GroundFrame,
    margin_m: f64,
) -> bool {
    let (level, fall) = plane_axes(&surface.plane, frame);
    let rise_per_m = fall.dot(&frame.up);
    if rise_per_m < 0.05 {
        // Nearly level: its continuation never reaches the ground nearby.
        return false;
    }
    // `rise_per_m` is the sine of the surface's tilt.
    if rise_per_m < FOOT_TURN_MAX_TILT_DEG.to_radians().sin() {
        let uphill = (fall - frame.up * rise_per_m).normalize();
        if uphill.dot(&frame.forward) < MAX_FOOT_TURN_DEG.to_radians().cos() {
            // Falling away from the robot: its foot is beyond it.
            return false;
        }
    }
    let mut counts = Counts::default();
    for foot in lowest_per_strip(cloud, inliers, frame, &level)
        .into_iter()
        .flatten()
    {
        let length = (frame.height(&foot) / rise_per_m).min(MAX_MARCH_M);
        if !(length > 0.0) {
            continue;
        }
        for k in 1..=MARCH_STEPS {
            let q = foot - fall * (length * k as f64 / MARCH_STEPS as f64);
            counts.add(seen_at(cloud, &q, margin_m));
        }
    }
    counts.hidden >= MIN_HIDDEN && counts.past * 5 <= counts.hidden
}

/// What the camera sees at a point of the continuation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Seen {
    /// A reading beyond the point: nothing is there.
    Past,
    /// A reading in front of the point: it is hidden.
    Hidden,
    /// A reading at the point, or none (out of view, no depth).
    Other,
}

#[derive(Debug, Default)]
struct Counts {
    past: usize,
    hidden: usize,
}

impl Counts {
    fn add(&mut self, seen: Seen) {
        match seen {
            Seen::Past => self.past += 1,
            Seen::Hidden => self.hidden += 1,
            Seen::Other => {}
        }
    }
}

/// The measured depth at the pixel of `q` against `q`'s own depth.
fn seen_at(cloud: &CloudView<'_>, q: &Vector3<f64>, margin_m: f64) -> Seen {
    let Some(pixel) = pixel_of(cloud, q) else {
        return Seen::Other;
    };
    let Some(m) = cloud.point(pixel) else {
        return Seen::Other;
    };
    if m.z > q.z + margin_m {
        Seen::Past
    } else if m.z < q.z - margin_m {
        Seen::Hidden
    } else {
        Seen::Other
    }
}

/// The pixel index a camera-frame point projects to, if in the image.
fn pixel_of(cloud: &CloudView<'_>, q: &Vector3<f64>) -> Option<usize> {
    if !(q.z > 0.0) {
        return None;
    }
    let k = &cloud.intrinsics;
    let u = (k.fx * q.x / q.z + k.cx).round();
    let v = (k.fy * q.y / q.z + k.cy).round();
    let inside = |c: f64, n: usize| c >= 0.0 && c < n as f64;
    (inside(u, cloud.width) && inside(v, cloud.height))
        .then(|| v as usize * cloud.width + u as usize)
}

/// The lowest inlier (a sample of at most [`FOOT_SAMPLES`]) in each of
/// [`FOOT_BINS`] equal strips along the surface's level direction.
fn lowest_per_strip(
    cloud: &CloudView<'_>,
    inliers: &[u32],
    frame: &GroundFrame,
    level: &Vector3<f64>,
) -> [Option<Vector3<f64>>; FOOT_BINS] {
    let stride = inliers.len().div_ceil(FOOT_SAMPLES).max(1);
    let points = || {
        inliers
            .iter()
            .step_by(stride)
            .filter_map(|&i| cloud.point(i as usize))
    };
    let (lo, hi) = points().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
        let s = level.dot(&p);
        (lo.min(s), hi.max(s))
    });
    let mut lowest: [Option<(f64, Vector3<f64>)>; FOOT_BINS] = [None; FOOT_BINS];
    let span = (hi - lo).max(1e-9);
    for p in points() {
        let bin = (((level.dot(&p) - lo) / span * FOOT_BINS as f64) as usize).min(FOOT_BINS - 1);
        let h = frame.height(&p);
        if lowest[bin].is_none_or(|(best, _)| h < best) {
            lowest[bin] = Some((h, p));
        }
    }
    lowest.map(|b| b.map(|(_, p)| p))
}
