//! Stage 3, pass-through filter (paper 3.1): a plane with more than
//! `max_points` (10,000) points is cut down by keeping only the points inside
//! a range along one axis.
//!
//! **Axis and range.** The paper names neither. We filter along the camera's
//! optical axis (depth z) and keep the range `[z_min, z_cut]` nearest the
//! camera, with `z_cut` the depth of the `max_points`-th nearest point (ties
//! broken by pixel order, so exactly `max_points` remain). Kinect depth noise
//! grows with the square of the depth, so the nearest part of a plane is its
//! best-measured part, and a contiguous slab keeps every point's
//! neighbourhood intact for the normal estimation (a random or strided
//! subsample would thin it). The cut is an O(n) selection, not a sort.

use slope_ipc_types::CloudPoint;

/// The range a pass-through kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassThroughRange {
    /// Kept depth range along the optical axis, metres (both NaN when the
    /// input was empty).
    pub z_min_m: f64,
    pub z_max_m: f64,
    /// True when points were removed.
    pub cut: bool,
}

/// Reusable buffers of the filter.
#[derive(Debug, Default, Clone)]
pub struct PassThrough {
    keyed: Vec<(f32, u32)>,
    kept: Vec<u32>,
}

impl PassThrough {
    pub fn new() -> Self {
        Self::default()
    }

    /// Keeps at most `max_points` of `members` (pixel indices into `points`)
    /// nearest the camera along z. Members without a reading are dropped.
    /// Returns the kept indices (in pixel order) and the range.
    pub fn filter(
        &mut self,
        points: &[CloudPoint],
        members: &[u32],
        max_points: usize,
    ) -> (&[u32], PassThroughRange) {
        self.keyed.clear();
        for &i in members {
            if let Some(p) = points.get(i as usize) {
                if p.z_m.is_finite() && p.x_m.is_finite() && p.y_m.is_finite() {
                    self.keyed.push((p.z_m, i));
                }
            }
        }
        let cut = self.keyed.len() > max_points;
        if cut {
            let by_depth = |a: &(f32, u32), b: &(f32, u32)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
            if max_points == 0 {
                self.keyed.clear();
            } else {
                self.keyed.select_nth_unstable_by(max_points - 1, by_depth);
                self.keyed.truncate(max_points);
            }
        }
        let (mut lo, mut hi) = (f64::NAN, f64::NAN);
        for &(z, _) in &self.keyed {
            let z = f64::from(z);
            lo = if lo.is_nan() { z } else { lo.min(z) };
            hi = if hi.is_nan() { z } else { hi.max(z) };
        }
        self.kept.clear();
        self.kept.extend(self.keyed.iter().map(|&(_, i)| i));
        self.kept.sort_unstable();
        (
            &self.kept,
            PassThroughRange {
                z_min_m: lo,
                z_max_m: hi,
                cut,
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points_at_depths(depths: &[f32]) -> Vec<CloudPoint> {
        depths
            .iter()
            .map(|&z| CloudPoint { x_m: 0.0, y_m: 0.0, z_m: z, rgb: 0 })
            .collect()
    }

    #[test]
    fn keeps_the_nearest_slab_exactly() {
        // Depths 0..100 shuffled deterministically.
        let depths: Vec<f32> = (0..100).map(|i| ((i * 37) % 100) as f32 * 0.01 + 1.0).collect();
        let pts = points_at_depths(&depths);
        let members: Vec<u32> = (0..100).collect();
        let mut pt = PassThrough::new();
        let (kept, range) = pt.filter(&pts, &members, 30);
        assert_eq!(kept.len(), 30);
        assert!(range.cut);
        assert!((range.z_min_m - 1.0).abs() < 1e-6);
        assert!((range.z_max_m - 1.29).abs() < 1e-5);
        // Brute force: the kept set is exactly the 30 smallest depths.
        let mut sorted: Vec<(f32, u32)> = members.iter().map(|&i| (depths[i as usize], i)).collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut want: Vec<u32> = sorted[..30].iter().map(|x| x.1).collect();
        want.sort_unstable();
        assert_eq!(kept, &want[..]);
    }

    #[test]
    fn small_planes_pass_unchanged_and_ties_are_capped() {
        let pts = points_at_depths(&[2.0; 50]);
        let members: Vec<u32> = (0..50).collect();
        let mut pt = PassThrough::new();
        let (kept, range) = pt.filter(&pts, &members, 50);
        assert_eq!(kept.len(), 50);
        assert!(!range.cut);
        let (kept, range) = pt.filter(&pts, &members, 20);
        assert_eq!(kept.len(), 20);
        assert!(range.cut);
        let mut bad = pts.clone();
        bad[3] = CloudPoint::INVALID;
        let (kept, _) = pt.filter(&bad, &[3, 4, 999], 10);
        assert_eq!(kept, &[4]);
    }
}
