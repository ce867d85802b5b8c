//! Every segmented plane described in the robot's terms: a [`Surface`] in
//! the [`GroundFrame`], from one pass over (a sample of) its inliers.
//!
//! The ground's segments become one surface (the first); every other plane
//! one surface each. The figures: slope and heading of the plane relative
//! to the ground, the forward distance to its nearest and farthest inlier,
//! the lateral positions of its leftmost and rightmost inlier, the heights
//! of its lowest and highest inlier, the rectangle in its plane that holds
//! its inliers, and how much of it lies in the robot's corridor. Roles come
//! after (`roles.rs`), the road last (`road.rs`).
//!
//! The extremes come from the first and last inlier of each image row
//! the plane covers, found by a search in its (pixel-ordered) inliers, not
//! a walk over all of them: along a row a plane's points lie on one line,
//! where a linear function of the point (ahead, lateral, height, the
//! outline's coordinates) is monotone, so its extremes over the row are at
//! the row's ends, and over the plane at some row's ends (up to the
//! points' noise off the plane). How much of a plane lies in the corridor
//! comes from an evenly spaced sample of at most [`CORRIDOR_SAMPLES`]
//! inliers.

use nalgebra::Vector3;
use slope_ipc_types::{SurfaceRole, SurfaceSupport};

use super::quality::PooledQuality;
use super::{is_flat_at_noise_level, GroundFrame, PlaneSummary, RoadConfig, SelectionConfig};
use crate::cloud::CloudView;
use crate::plane_fit::Plane;
use crate::ransac_planes::SegmentedPlane;
use slope_ipc_types::CloudPoint;

/// A plane's share of the corridor is counted over at most about this
/// many of its inliers (every k-th in pixel order).
pub const CORRIDOR_SAMPLES: usize = 512;

/// A surface reaches into the corridor with at least this many inliers
/// there (a plane's stray edge pixel does not).
pub const CORRIDOR_MIN_PIXELS: usize = 50;

/// One surface in view.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// Index of its segmented plane (for the ground: its lowest segment).
    pub plane_index: usize,
    /// Segmented planes joined into it (the ground's segments; else 1).
    pub segments: usize,
    pub role: SurfaceRole,
    pub support: SurfaceSupport,
    /// Index (in the frame's surfaces) of the ground or step it stands on.
    pub supported_by: Option<usize>,
    /// It joins the ground, directly or through a chain of steps (or its
    /// foot is hidden: `support` says which).
    pub joins_ground: bool,
    /// At least [`CORRIDOR_MIN_PIXELS`] of its inliers lie in the corridor.
    pub in_corridor: bool,
    /// Flat at the sensor's noise level and large enough to measure a slope
    /// on (the selection's tests of an inclined plane).
    pub measurable: bool,
    /// Camera frame, unit normal towards the camera.
    pub plane: Plane,
    pub inliers: usize,
    /// Signed as the estimate's slope: + rising away from the robot.
    pub slope_deg: f64,
    /// Uphill direction from forward, degrees, + left; NaN when level.
    pub heading_deg: f64,
    pub distance_m: f64,
    pub far_m: f64,
    pub left_m: f64,
    pub right_m: f64,
    pub lowest_m: f64,
    pub highest_m: f64,
    pub area_m2: f64,
    pub rms_m: f64,
    pub noise_ratio: f64,
    /// Forward distance to its nearest inlier in the corridor; NaN when
    /// none is there.
    pub corridor_distance_m: f64,
    /// Mean forward distance of its inliers in the corridor; NaN when none
    /// is there.
    pub corridor_mean_m: f64,
    /// Corners of the rectangle in its plane holding its inliers, camera
    /// frame, in order around it.
    pub outline: [Vector3<f64>; 4],
}

impl Surface {
    /// Angle between its plane and the ground's, degrees, unsigned.
    pub fn tilt_deg(&self) -> f64 {
        self.slope_deg.abs()
    }
}

/// One line for logs and examples: role, support, slope, heading, extents,
/// heights, inliers, and whether it reaches into the corridor.
impl std::fmt::Display for Surface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:8} on {:6} slope {:7.2} heading {:7.1} ahead {:5.2}..{:5.2} \
             lateral {:6.2}..{:6.2} height {:5.2}..{:5.2} px {:6}{}",
            self.role.name(),
            self.support.name(),
            self.slope_deg,
            self.heading_deg,
            self.distance_m,
            self.far_m,
            self.left_m,
            self.right_m,
            self.lowest_m,
            self.highest_m,
            self.inliers,
            if self.in_corridor { " corridor" } else { "" },
        )
    }
}

/// The surfaces of every plane in `planes` over `frame`: the ground's
/// segments (`ground`, lowest first; empty for a ground from the mount)
/// joined into the first, then every other plane in index order but those
/// made of veil points ([`super::is_surface`]). Roles are
/// left `Elevated` and supports `None` for `roles.rs` to set (the ground's
/// role is `Ground`).
pub fn describe_surfaces(
    cloud: &CloudView<'_>,
    planes: &[SegmentedPlane],
    summaries: &[PlaneSummary],
    ground: &[usize],
    frame: &GroundFrame,
    selection: &SelectionConfig,
    road: &RoadConfig,
) -> Vec<Surface> {
    let mut surfaces = Vec::with_capacity(planes.len());
    if let Some(&lowest) = ground.first() {
        let lists: Vec<&[u32]> = ground
            .iter()
            .map(|&k| planes[k].inliers.as_slice())
            .collect();
        let mut pooled = PooledQuality::default();
        for &k in ground {
            pooled.add(
                planes[k].inliers.len(),
                planes[k].rms_m,
                &summaries[k].quality,
            );
        }
        let inliers = lists.iter().map(|l| l.len()).sum();
        let quality = pooled.quality(inliers);
        let mut s = describe(cloud, &lists, &planes[lowest].plane, frame, road);
        s.plane_index = lowest;
        s.segments = ground.len();
        s.role = SurfaceRole::Ground;
        s.joins_ground = true;
        s.slope_deg = 0.0;
        s.heading_deg = f64::NAN;
        (s.area_m2, s.rms_m, s.noise_ratio) = (quality.area_m2, quality.rms_m, quality.noise_ratio);
        surfaces.push(s);
    }
    for (k, plane) in planes.iter().enumerate() {
        // A plane of veil points is no surface at all.
        if ground.contains(&k) || !super::is_surface(&summaries[k]) {
            continue;
        }
        let mut s = describe(cloud, &[&plane.inliers], &plane.plane, frame, road);
        s.plane_index = k;
        let quality = &summaries[k].quality;
        (s.area_m2, s.rms_m, s.noise_ratio) = (quality.area_m2, quality.rms_m, quality.noise_ratio);
        s.measurable = is_flat_at_noise_level(&summaries[k], selection)
            && quality.area_m2 >= selection.inclined_min_area_m2;
        surfaces.push(s);
    }
    surfaces
}

/// One surface of `plane` over the inlier `lists` (pixel indices of
/// `cloud`); its role and support are left for `roles.rs`.
fn describe(
    cloud: &CloudView<'_>,
    lists: &[&[u32]],
    plane: &Plane,
    frame: &GroundFrame,
    road: &RoadConfig,
) -> Surface {
    let (level, fall) = plane_axes(plane, frame);
    let mut walk = Extents::new(frame, &level, &fall, road);
    let total: usize = lists.iter().map(|l| l.len()).sum();
    let stride = total.div_ceil(CORRIDOR_SAMPLES).max(1);
    for list in lists {
        walk.add_row_ends(cloud, list);
        walk.add_corridor(cloud, list, stride);
    }
    let tilt = frame.tilt_deg(&plane.normal);
    let range = |k: usize| (finite_or_nan(walk.min[k]), finite_or_nan(walk.max[k]));
    let ((near, far), (left, right), (lowest, highest)) =
        (range(AHEAD), range(LATERAL), range(HEIGHT));
    Surface {
        plane_index: 0,
        segments: 1,
        role: SurfaceRole::Elevated,
        support: SurfaceSupport::None,
        supported_by: None,
        joins_ground: false,
        in_corridor: walk.corridor_pixels * stride >= CORRIDOR_MIN_PIXELS,
        measurable: false,
        plane: *plane,
        inliers: total,
        slope_deg: super::slope_sign(&plane.normal, &frame.forward) * tilt,
        heading_deg: frame.heading_deg(&plane.normal),
        distance_m: near,
        far_m: far,
        left_m: left,
        right_m: right,
        lowest_m: lowest,
        highest_m: highest,
        area_m2: f64::NAN,
        rms_m: f64::NAN,
        noise_ratio: f64::NAN,
        corridor_distance_m: finite_or_nan(f64::from(walk.corridor_ahead)),
        corridor_mean_m: walk.corridor_sum / walk.corridor_pixels as f64,
        outline: walk.outline(plane, &level, &fall),
    }
}

/// Two unit directions in `plane`: along its level line (horizontal) and
/// up its fall line (`fall . up >= 0`); for a level plane, the robot's
/// right and forward projected into it.
pub fn plane_axes(plane: &Plane, frame: &GroundFrame) -> (Vector3<f64>, Vector3<f64>) {
    let n = plane.normal;
    let level = frame
        .up
        .cross(&n)
        .try_normalize(1e-6)
        .or_else(|| (frame.right - n * n.dot(&frame.right)).try_normalize(1e-9))
        .unwrap_or(frame.right);
    let fall = n.cross(&level);
    let fall = if fall.dot(&frame.up) < 0.0 {
        -fall
    } else {
        fall
    };
    (level, fall)
}

/// The coordinates [`Extents`] follows: ahead, lateral, height, along the
/// plane's level line, up its fall line.
const AHEAD: usize = 0;
const LATERAL: usize = 1;
const HEIGHT: usize = 2;
const ALONG: usize = 3;
const UP_FALL: usize = 4;

/// Running extremes of a surface's inliers, in `f32` (a point's
/// coordinates are `f32`; centimetres matter here, not micrometres).
struct Extents {
    /// Each coordinate is `axes[k] . p + offsets[k]`.
    axes: [[f32; 3]; 5],
    offsets: [f32; 5],
    min: [f64; 5],
    max: [f64; 5],
    half_width_m: f32,
    look_ahead_m: f32,
    corridor_pixels: usize,
    corridor_ahead: f32,
    corridor_sum: f64,
}

impl Extents {
    fn new(
        frame: &GroundFrame,
        level: &Vector3<f64>,
        fall: &Vector3<f64>,
        road: &RoadConfig,
    ) -> Self {
        let axis = |v: &Vector3<f64>| [v.x as f32, v.y as f32, v.z as f32];
        Self {
            axes: [
                axis(&frame.forward),
                axis(&frame.right),
                axis(&frame.ground.normal),
                axis(level),
                axis(fall),
            ],
            offsets: [0.0, 0.0, frame.ground.d as f32, 0.0, 0.0],
            min: [f64::INFINITY; 5],
            max: [f64::NEG_INFINITY; 5],
            half_width_m: road.corridor_half_width_m as f32,
            look_ahead_m: road.look_ahead_m as f32,
            corridor_pixels: 0,
            corridor_ahead: f32::INFINITY,
            corridor_sum: 0.0,
        }
    }

    /// The first and last of `inliers` (pixel indices of `cloud`, in
    /// pixel order) in every image row they cover. A row holds at most
    /// `width` of them, so its end is searched among the next `width`.
    fn add_row_ends(&mut self, cloud: &CloudView<'_>, inliers: &[u32]) {
        let width = cloud.width.max(1);
        let mut min = [f32::INFINITY; 5];
        let mut max = [f32::NEG_INFINITY; 5];
        let mut start = 0;
        let mut len = 1;
        while let Some(&first) = inliers.get(start) {
            let next_row = (first as usize / width + 1) * width;
            let window = &inliers[start..inliers.len().min(start + width)];
            // At least 1: `first` is in its own row (out of order input
            // still moves on). Rows of a plane change length little from
            // one to the next: the search starts at the last one's.
            len = partition_near(window, len, |p| (p as usize) < next_row).max(1);
            for pixel in [first, window[len - 1]] {
                if let Some(p) = cloud.points.get(pixel as usize) {
                    let c = self.coordinates(p);
                    for k in 0..5 {
                        // A NaN (no reading: never an inlier) changes nothing.
                        min[k] = min[k].min(c[k]);
                        max[k] = max[k].max(c[k]);
                    }
                }
            }
            start += len;
        }
        for k in 0..5 {
            self.min[k] = self.min[k].min(f64::from(min[k]));
            self.max[k] = self.max[k].max(f64::from(max[k]));
        }
    }

    /// Every `stride`-th of the `inliers` counted in the corridor.
    fn add_corridor(&mut self, cloud: &CloudView<'_>, inliers: &[u32], stride: usize) {
        let mut corridor_sum = 0.0f32;
        let [ahead, lateral] = [self.axes[AHEAD], self.axes[LATERAL]];
        for &pixel in inliers.iter().step_by(stride) {
            let Some(p) = cloud.points.get(pixel as usize) else {
                continue;
            };
            let a = ahead[0] * p.x_m + ahead[1] * p.y_m + ahead[2] * p.z_m;
            let l = lateral[0] * p.x_m + lateral[1] * p.y_m + lateral[2] * p.z_m;
            if l.abs() <= self.half_width_m && a > 0.0 && a <= self.look_ahead_m {
                self.corridor_pixels += 1;
                self.corridor_ahead = self.corridor_ahead.min(a);
                corridor_sum += a;
            }
        }
        self.corridor_sum += f64::from(corridor_sum);
    }

    /// The five coordinates of `p`.
    fn coordinates(&self, p: &CloudPoint) -> [f32; 5] {
        let mut c = [0.0f32; 5];
        for (k, c) in c.iter_mut().enumerate() {
            let a = &self.axes[k];
            *c = a[0] * p.x_m + a[1] * p.y_m + a[2] * p.z_m + self.offsets[k];
        }
        c
    }

    /// The rectangle of the extremes along `level` and `fall`, on `plane`.
    fn outline(
        &self,
        plane: &Plane,
        level: &Vector3<f64>,
        fall: &Vector3<f64>,
    ) -> [Vector3<f64>; 4] {
        let (s, t) = (
            (self.min[ALONG], self.max[ALONG]),
            (self.min[UP_FALL], self.max[UP_FALL]),
        );
        if !(s.0 <= s.1) {
            return [Vector3::repeat(f64::NAN); 4];
        }
        let foot = -plane.normal * plane.d;
        let corner = |s: f64, t: f64| foot + level * s + fall * t;
        [
            corner(s.0, t.0),
            corner(s.1, t.0),
            corner(s.1, t.1),
            corner(s.0, t.1),
        ]
    }
}

/// The number of leading elements of `items` for which `below` holds
/// (`below` true then false along `items`, as for
/// `slice::partition_point`), searched outwards from `hint` in steps that
/// double, so that an answer near `hint` costs a few reads close together
/// instead of a binary search over all of `items`.
fn partition_near(items: &[u32], hint: usize, below: impl Fn(u32) -> bool) -> usize {
    let n = items.len();
    let hint = hint.min(n);
    let count = |slice: &[u32]| slice.partition_point(|&p| below(p));
    if hint < n && below(items[hint]) {
        // The answer is past `hint`: items[..lo] all hold.
        let (mut lo, mut step) = (hint + 1, 1);
        loop {
            let probe = lo - 1 + step;
            if probe >= n {
                return lo + count(&items[lo..]);
            }
            if !below(items[probe]) {
                return lo + count(&items[lo..probe]);
            }
            (lo, step) = (probe + 1, step * 2);
        }
    }
    // The answer is at most `hint`: items[hi..] all fail.
    let (mut hi, mut step) = (hint, 1);
    loop {
        if hi < step {
            return count(&items[..hi]);
        }
        let probe = hi - step;
        if below(items[probe]) {
            return probe + 1 + count(&items[probe + 1..hi]);
        }
        (hi, step) = (probe, step * 2);
    }
}

/// `f64::INFINITY` (nothing seen) as NaN.
fn finite_or_nan(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        f64::NAN
    }
}

#[cfg(test)]
mod tests {
    use super::partition_near;

    /// Against `slice::partition_point` (the oracle), every hint, every
    /// split of lists with repeats.
    #[test]
    fn partition_near_is_partition_point_from_any_hint() {
        let lists: [&[u32]; 4] = [&[], &[5], &[1, 2, 2, 3, 7, 9, 9, 12], &[0, 0, 0, 4]];
        for items in lists {
            for split in 0..=13 {
                let below = |p: u32| p < split;
                let want = items.partition_point(|&p| below(p));
                for hint in 0..=items.len() + 2 {
                    assert_eq!(
                        partition_near(items, hint, below),
                        want,
                        "{items:?} {split} {hint}"
                    );
                }
            }
        }
    }
}
