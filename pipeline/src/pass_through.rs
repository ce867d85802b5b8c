//! Stage 3, pass-through filter (paper 3.1): a plane with more than
//! `max_points` (10,000) points is cut down by keeping only the points inside
//! a range along one axis.
//!
//! **Axis and range.** The paper names neither. We filter along the
//! elevation of each point's viewing ray, `y / z` (the image row, as the
//! cloud is organised), and keep the band of exactly `max_points` points
//! centred (in rank) on the plane's median elevation: as many points above
//! the median as below it (ties broken by pixel order).
//!
//! - *Why not depth or height?* Depth noise moves a point along its ray, so
//!   every metric coordinate (x, y, z) carries the noise, and cutting a range
//!   of a noisy coordinate keeps the points whose noise pushed them inside:
//!   near the cut the kept points are biased towards the range, which tilts
//!   the surface they describe (1 degree on a wall band on `slope-synth`
//!   recordings). The ray's direction `y / z` carries no depth noise, so the
//!   cut selects pixels, not noise.
//! - *Which band?* A plane's first and last rows are where it meets other
//!   planes (a ramp's foot, where multipath and mixed pixels bend the
//!   measured surface) or ends in clutter, so the inclined plane keeps its
//!   middle band. The ground keeps its bottom band (`Band::Lower`): the
//!   floor right in front of the robot, as far as it gets from the junction
//!   with the plane ahead (on the real stair frame the band at the riser's
//!   foot is bent by several degrees) and measured at the shortest range. A contiguous band also keeps every point's neighbourhood intact
//!   for the normal estimation (a random or strided subsample would thin it).
//!
//! The cut is two O(n) selections, not a sort.

use slope_ipc_types::CloudPoint;

/// The range a pass-through kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassThroughRange {
    /// Kept range of the ray elevation `y / z` (both NaN when the input was
    /// empty).
    pub min_elevation: f64,
    pub max_elevation: f64,
    /// True when points were removed.
    pub cut: bool,
}

/// Which band of rows a cut plane keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Band {
    /// Centred on the median elevation (the inclined plane).
    Middle,
    /// Centred on the elevation with three quarters of the points above it
    /// (the ground: nearer the robot and away from the junction with the
    /// plane ahead, without reaching the image's bottom edge).
    Lower,
    /// A uniform subsample of the whole plane (every `n / max_points`-th
    /// point in pixel order), for normals whose neighbourhoods come from the
    /// whole plane ([`crate::normals::NormalEstimator::estimate_with_support`]).
    Spread,
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

    /// Keeps at most `max_points` of `members` (pixel indices into `points`):
    /// the band of ray elevations `y / z` at `band`. Members without a
    /// reading are dropped. Returns the kept indices (in pixel order) and
    /// the range.
    pub fn filter(
        &mut self,
        points: &[CloudPoint],
        members: &[u32],
        max_points: usize,
        band: Band,
    ) -> (&[u32], PassThroughRange) {
        self.keyed.clear();
        for &i in members {
            if let Some(p) = points.get(i as usize) {
                if p.z_m.is_finite() && p.x_m.is_finite() && p.y_m.is_finite() && p.z_m != 0.0 {
                    self.keyed.push((p.y_m / p.z_m, i));
                }
            }
        }
        let cut = self.keyed.len() > max_points;
        if cut {
            let by_depth = |a: &(f32, u32), b: &(f32, u32)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
            if max_points == 0 {
                self.keyed.clear();
            } else if band == Band::Spread {
                // Every (n / max_points)-th member in pixel order: a uniform
                // subsample of the whole plane.
                let n = self.keyed.len();
                self.keyed.sort_unstable_by_key(|&(_, i)| i);
                for k in 0..max_points {
                    self.keyed[k] = self.keyed[k * n / max_points];
                }
                self.keyed.truncate(max_points);
            } else {
                let lo = match band {
                    Band::Middle => (self.keyed.len() - max_points) / 2,
                    Band::Lower => (self.keyed.len() - max_points) * 3 / 4,
                    Band::Spread => 0,
                };
                if lo > 0 {
                    self.keyed.select_nth_unstable_by(lo, by_depth);
                }
                let upper = &mut self.keyed[lo..];
                upper.select_nth_unstable_by(max_points - 1, by_depth);
                self.keyed.drain(..lo);
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
                min_elevation: lo,
                max_elevation: hi,
                cut,
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points at 2 m depth whose rays have the given elevations `y / z`.
    fn points_at_elevations(elevations: &[f32]) -> Vec<CloudPoint> {
        elevations
            .iter()
            .map(|&e| CloudPoint {
                x_m: 0.1,
                y_m: 2.0 * e,
                z_m: 2.0,
                rgb: 0,
            })
            .collect()
    }

    #[test]
    fn keeps_the_median_band_exactly() {
        // Elevations 0..1 shuffled deterministically.
        let depths: Vec<f32> = (0..100).map(|i| ((i * 37) % 100) as f32 * 0.01).collect();
        let pts = points_at_elevations(&depths);
        let members: Vec<u32> = (0..100).collect();
        let mut pt = PassThrough::new();
        let (kept, range) = pt.filter(&pts, &members, 30, Band::Middle);
        assert_eq!(kept.len(), 30);
        assert!(range.cut);
        // 100 points, 30 kept: ranks 35..65, elevations 0.35..0.64.
        assert!((range.min_elevation - 0.35).abs() < 1e-6, "{range:?}");
        assert!((range.max_elevation - 0.64).abs() < 1e-5, "{range:?}");
        // Brute force: the kept set is exactly ranks 35..65 of a full sort.
        // Noise along the rays (any depth) changes nothing.
        let mut noisy = pts.clone();
        for (k, p) in noisy.iter_mut().enumerate() {
            let s = 1.0 + 0.01 * (k % 7) as f32;
            p.x_m *= s;
            p.y_m *= s;
            p.z_m *= s;
        }
        let mut pt2 = PassThrough::new();
        assert_eq!(pt2.filter(&noisy, &members, 30, Band::Middle).0, kept);
        let mut sorted: Vec<(f32, u32)> =
            members.iter().map(|&i| (depths[i as usize], i)).collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut want: Vec<u32> = sorted[35..65].iter().map(|x| x.1).collect();
        want.sort_unstable();
        assert_eq!(kept, &want[..]);
        // The lower band: 70 points left out, 52 of them above.
        let mut pt3 = PassThrough::new();
        let (bottom, _) = pt3.filter(&pts, &members, 30, Band::Lower);
        let mut want_bottom: Vec<u32> = sorted[52..82].iter().map(|x| x.1).collect();
        want_bottom.sort_unstable();
        assert_eq!(bottom, &want_bottom[..]);
        // The spread: every (100 / 30)-th member in pixel order.
        let mut pt4 = PassThrough::new();
        let (spread, range) = pt4.filter(&pts, &members, 30, Band::Spread);
        let want_spread: Vec<u32> = (0..30).map(|k| k * 100 / 30).collect();
        assert_eq!(spread, &want_spread[..]);
        assert!(range.cut);
    }

    #[test]
    fn small_planes_pass_unchanged_and_ties_are_capped() {
        let pts = points_at_elevations(&[2.0; 50]);
        let members: Vec<u32> = (0..50).collect();
        let mut pt = PassThrough::new();
        let (kept, range) = pt.filter(&pts, &members, 50, Band::Middle);
        assert_eq!(kept.len(), 50);
        assert!(!range.cut);
        let (kept, range) = pt.filter(&pts, &members, 20, Band::Lower);
        assert_eq!(kept.len(), 20);
        assert!(range.cut);
        let mut bad = pts.clone();
        bad[3] = CloudPoint::INVALID;
        let (kept, _) = pt.filter(&bad, &[3, 4, 999], 10, Band::Middle);
        assert_eq!(kept, &[4]);
    }
}
