//! Stage 6, cumulative averaging (paper 3.2): the angle between a random
//! inclined-plane normal and a random ground normal, averaged over `draws`
//! (100) draws; the spread of the draws is reported with the mean.
//!
//! The paper writes the angle as `arctan(n_i . n_j / |n_i||n_j|)`, a typo
//! (that is the arctangent of a cosine); we use `atan2(|a x b|, a . b)`,
//! which is exact at every angle. Draws come from the estimator's seeded
//! generator, so the same frame and configuration give the same answer.
//!
//! **Spread bias.** An unsigned angle between two noisy normals is never
//! negative, so its mean exceeds the angle between the planes by about
//! `(s_i^2 + s_g^2) / (2 theta)` (the normals' angular spreads across the
//! plane of the two mean normals), and by up to `sqrt(s_i^2 + s_g^2)` as
//! theta -> 0: a few degrees of spread put a 5 degree ramp 1-2 degrees
//! too steep. With an `axis` (the unit rotation axis from the ground's mean
//! normal to the inclined plane's, [`rotation_axis`]) each pair's angle is
//! measured *about that axis*, signed: both normals are projected onto the
//! plane perpendicular to it and the angle is
//! `atan2(axis . (g' x i'), g' . i')`. The spread across that plane drops
//! out and the spread within it averages to zero, so the mean is unbiased
//! at every angle; still the average of one angle per random pair.

use nalgebra::Vector3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::cloud::angle_between_deg;
use crate::validate::{count_in, InvalidValue};
use serde::{Deserialize, Serialize};

/// Mean and spread of the averaged angles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngleSummary {
    pub mean_deg: f64,
    /// Standard deviation of the individual draws.
    pub std_deg: f64,
    pub samples: u32,
}

/// The unit axis that turns `ground` into `inclined` (`ground x inclined`),
/// `None` when they are parallel.
pub fn rotation_axis(ground: &Vector3<f64>, inclined: &Vector3<f64>) -> Option<Vector3<f64>> {
    ground.cross(inclined).try_normalize(1e-9)
}

/// The angle from `g` to `i` about `axis` (signed, degrees): both projected
/// onto the plane perpendicular to `axis`.
fn angle_about_deg(g: &Vector3<f64>, i: &Vector3<f64>, axis: &Vector3<f64>) -> f64 {
    let gp = g - axis * axis.dot(g);
    let ip = i - axis * axis.dot(i);
    axis.dot(&gp.cross(&ip)).atan2(gp.dot(&ip)).to_degrees()
}

/// Averages `draws` angles between random members of `inclined` and
/// `ground`: unsigned, or about `axis` when given (see the module doc).
/// `None` when either set is empty or `draws` is 0.
pub fn cumulative_angle(
    inclined: &[Vector3<f64>],
    ground: &[Vector3<f64>],
    draws: usize,
    axis: Option<&Vector3<f64>>,
    rng: &mut ChaCha8Rng,
) -> Option<AngleSummary> {
    if inclined.is_empty() || ground.is_empty() || draws == 0 {
        return None;
    }
    let (mut sum, mut sum_sq) = (0.0, 0.0);
    for _ in 0..draws {
        let a = &inclined[rng.random_range(0..inclined.len())];
        let b = &ground[rng.random_range(0..ground.len())];
        let theta = match axis {
            Some(axis) => angle_about_deg(b, a, axis),
            None => angle_between_deg(a, b),
        };
        sum += theta;
        sum_sq += theta * theta;
    }
    let n = draws as f64;
    let mean = sum / n;
    Some(AngleSummary {
        mean_deg: mean,
        std_deg: (sum_sq / n - mean * mean).max(0.0).sqrt(),
        samples: u32::try_from(draws).unwrap_or(u32::MAX),
    })
}

/// Cumulative averaging (`cumulative_angle.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CumulativeConfig {
    /// Random normal pairs averaged. The paper uses 100; on real Kinect
    /// frames the per-point normals spread by ~10 degrees, which leaves a
    /// random error of 10/sqrt(100) = 1 degree at 100 draws, so the default
    /// is 1000 (0.3 degrees, 25 microseconds).
    pub draws: usize,
    /// Measure each pair's angle about the rotation axis between the two
    /// planes' mean normals (signed), which removes the upward bias of
    /// unsigned angles between noisy normals (`cumulative_angle.rs`); false:
    /// the unsigned angle of each pair, as the paper (the default: with the
    /// noise-scaled patch the bias is thousandths of a degree, and the
    /// ablation in the pipeline README shows no gain).
    pub about_axis: bool,
}

impl Default for CumulativeConfig {
    fn default() -> Self {
        Self {
            draws: 1000,
            about_axis: false,
        }
    }
}

impl CumulativeConfig {
    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), InvalidValue> {
        count_in("draws", self.draws, 1, 1_000_000)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn angle_of_known_normals() {
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let t = 16f64.to_radians();
        let ground = [Vector3::new(0.0, -1.0, 0.0)];
        let ramp = [Vector3::new(0.0, -t.cos(), -t.sin())];
        let s = cumulative_angle(&ramp, &ground, 100, None, &mut rng).unwrap();
        assert!((s.mean_deg - 16.0).abs() < 1e-12);
        assert!(s.std_deg < 1e-6);
        assert_eq!(s.samples, 100);
    }

    #[test]
    fn mean_and_spread_match_an_exhaustive_average() {
        // Two inclined normals at 10 and 20 degrees from the single ground
        // normal: the mean over many draws tends to 15, the spread to 5.
        let ground = [Vector3::z()];
        let at = |d: f64| Vector3::new(d.to_radians().sin(), 0.0, d.to_radians().cos());
        let incl = [at(10.0), at(20.0)];
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let s = cumulative_angle(&incl, &ground, 20_000, None, &mut rng).unwrap();
        assert!((s.mean_deg - 15.0).abs() < 0.1, "{s:?}");
        assert!((s.std_deg - 5.0).abs() < 0.05, "{s:?}");
    }

    #[test]
    fn same_seed_same_answer_and_empty_sets() {
        let g: Vec<_> = (0..10)
            .map(|i| Vector3::new(0.01 * i as f64, 0.0, 1.0))
            .collect();
        let r: Vec<_> = (0..10)
            .map(|i| Vector3::new(1.0, 0.02 * i as f64, 0.5))
            .collect();
        let a = cumulative_angle(&r, &g, 100, None, &mut ChaCha8Rng::seed_from_u64(5));
        let b = cumulative_angle(&r, &g, 100, None, &mut ChaCha8Rng::seed_from_u64(5));
        assert_eq!(a, b);
        assert!(cumulative_angle(&[], &g, 100, None, &mut ChaCha8Rng::seed_from_u64(5)).is_none());
        assert!(cumulative_angle(&r, &g, 0, None, &mut ChaCha8Rng::seed_from_u64(5)).is_none());
    }

    /// Normals spread by 3 degrees around a ground and a 5 degree ramp: the
    /// unsigned pair mean is biased up by more than a degree, the mean about
    /// the rotation axis is not (and both agree on a 60 degree ramp).
    #[test]
    fn angles_about_the_axis_remove_the_spread_bias() {
        use rand_distr::{Distribution, Normal};
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let noise = Normal::new(0.0, 3f64.to_radians()).unwrap();
        let mut spread = |n: Vector3<f64>| -> Vec<Vector3<f64>> {
            let u = n.cross(&Vector3::x()).normalize();
            let v = n.cross(&u);
            (0..5000)
                .map(|_| (n + u * noise.sample(&mut rng) + v * noise.sample(&mut rng)).normalize())
                .collect()
        };
        for truth in [5.0f64, 60.0] {
            let t = truth.to_radians();
            let g_mean = Vector3::new(0.0, -1.0, 0.0);
            let i_mean = Vector3::new(0.0, -t.cos(), -t.sin());
            let ground = spread(g_mean);
            let incl = spread(i_mean);
            let mean = |v: &[Vector3<f64>]| v.iter().sum::<Vector3<f64>>().normalize();
            let axis = rotation_axis(&mean(&ground), &mean(&incl)).unwrap();
            let mut draw = ChaCha8Rng::seed_from_u64(4);
            let plain = cumulative_angle(&incl, &ground, 200_000, None, &mut draw).unwrap();
            let about = cumulative_angle(&incl, &ground, 200_000, Some(&axis), &mut draw).unwrap();
            assert!((about.mean_deg - truth).abs() < 0.1, "{truth}: {about:?}");
            if truth < 10.0 {
                assert!(plain.mean_deg - truth > 1.0, "{truth}: {plain:?}");
            } else {
                assert!((plain.mean_deg - truth).abs() < 0.2, "{truth}: {plain:?}");
            }
        }
    }
}
