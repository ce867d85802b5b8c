//! Stage 6, cumulative averaging (paper 3.2): the angle between a random
//! inclined-plane normal and a random ground normal, averaged over `draws`
//! (100) draws; the spread of the draws is reported with the mean.
//!
//! The paper writes the angle as `arctan(n_i . n_j / |n_i||n_j|)`, a typo
//! (that is the arctangent of a cosine); we use `atan2(|a x b|, a . b)`,
//! which is exact at every angle. Draws come from the estimator's seeded
//! generator, so the same frame and configuration give the same answer.

use nalgebra::Vector3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::cloud::angle_between_deg;

/// Mean and spread of the averaged angles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngleSummary {
    pub mean_deg: f64,
    /// Standard deviation of the individual draws.
    pub std_deg: f64,
    pub samples: u32,
}

/// Averages `draws` angles between random members of `inclined` and
/// `ground`. `None` when either set is empty or `draws` is 0.
pub fn cumulative_angle(
    inclined: &[Vector3<f64>],
    ground: &[Vector3<f64>],
    draws: usize,
    rng: &mut ChaCha8Rng,
) -> Option<AngleSummary> {
    if inclined.is_empty() || ground.is_empty() || draws == 0 {
        return None;
    }
    let (mut sum, mut sum_sq) = (0.0, 0.0);
    for _ in 0..draws {
        let a = &inclined[rng.random_range(0..inclined.len())];
        let b = &ground[rng.random_range(0..ground.len())];
        let theta = angle_between_deg(a, b);
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
        let s = cumulative_angle(&ramp, &ground, 100, &mut rng).unwrap();
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
        let s = cumulative_angle(&incl, &ground, 20_000, &mut rng).unwrap();
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
        let a = cumulative_angle(&r, &g, 100, &mut ChaCha8Rng::seed_from_u64(5));
        let b = cumulative_angle(&r, &g, 100, &mut ChaCha8Rng::seed_from_u64(5));
        assert_eq!(a, b);
        assert!(cumulative_angle(&[], &g, 100, &mut ChaCha8Rng::seed_from_u64(5)).is_none());
        assert!(cumulative_angle(&r, &g, 0, &mut ChaCha8Rng::seed_from_u64(5)).is_none());
    }
}
