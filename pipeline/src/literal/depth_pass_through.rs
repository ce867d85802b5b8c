//! Stage 3 as we read the paper: a pass-through filter on the depth axis.
//!
//! The paper says only that a plane of more than 10,000 points is cut by a
//! pass-through filter "until the count falls below 10,000" (its 12,405-
//! point ramp). A pass-through (PCL's `PassThrough`) keeps the points whose
//! one coordinate lies in a range. We infer **the camera's z axis (depth),
//! range `[0, z_max]` with `z_max` the depth of the 10,000th nearest point**:
//! z is the field PCL's pass-through examples and Kinect pipelines cut
//! (`setFilterFieldName("z")`), the paper's cut is chosen by a count, and
//! the near end is the one to keep (Kinect depth noise grows as z^2, so
//! the far points are the worst). Points at equal depth are taken in pixel
//! order. The kept points are returned in pixel order. Our replacement is
//! the surface-uniform subsample in `pass_through.rs`.

use serde::{Deserialize, Serialize};
use slope_ipc_types::CloudPoint;

/// How a plane of more than `max_points` points is cut
/// (`pass_through.mode`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PassThroughMode {
    /// Uniform over the plane's surface; normals see all its points
    /// (`pass_through.rs`, ours).
    #[default]
    SurfaceUniform,
    /// The nearest `max_points` along the depth axis; normals see only
    /// those (the paper, as we read it).
    Depth,
}

/// Reusable buffers of the depth pass-through.
#[derive(Debug, Default, Clone)]
pub struct DepthPassThrough {
    by_depth: Vec<(f32, u32)>,
    kept: Vec<u32>,
}

impl DepthPassThrough {
    pub fn new() -> Self {
        Self::default()
    }

    /// The at most `max_points` nearest (smallest z) of `members` (pixel
    /// indices into `points`) with a reading, in pixel order.
    pub fn filter(&mut self, points: &[CloudPoint], members: &[u32], max_points: usize) -> &[u32] {
        self.by_depth.clear();
        self.by_depth.extend(members.iter().filter_map(|&i| {
            points
                .get(i as usize)
                .filter(|p| p.x_m.is_finite() && p.y_m.is_finite() && p.z_m.is_finite())
                .map(|p| (p.z_m, i))
        }));
        if self.by_depth.len() > max_points {
            let by = |a: &(f32, u32), b: &(f32, u32)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
            if max_points > 0 {
                self.by_depth.select_nth_unstable_by(max_points - 1, by);
            }
            self.by_depth.truncate(max_points);
        }
        self.kept.clear();
        self.kept.extend(self.by_depth.iter().map(|&(_, i)| i));
        self.kept.sort_unstable();
        self.kept.dedup();
        &self.kept
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_the_nearest_in_pixel_order() {
        // Depths 10, 9, ..., 1 m at pixels 0..10, one pixel without a reading.
        let mut points: Vec<CloudPoint> = (0..10)
            .map(|k| CloudPoint {
                x_m: 0.0,
                y_m: 0.0,
                z_m: 10.0 - k as f32,
                rgb: 0,
            })
            .collect();
        points[9] = CloudPoint::INVALID;
        let members: Vec<u32> = (0..10).collect();
        let mut pt = DepthPassThrough::new();
        // Nearest four with a reading: 2, 3, 4, 5 m at pixels 8, 7, 6, 5.
        assert_eq!(pt.filter(&points, &members, 4), &[5, 6, 7, 8]);
        // Fewer than the cap: every measured member.
        assert_eq!(pt.filter(&points, &members, 100).len(), 9);
        // Ties in depth go by pixel order.
        let flat = vec![points[0]; 6];
        assert_eq!(pt.filter(&flat, &[5, 1, 3, 0, 2, 4], 3), &[0, 1, 2]);
    }
}
