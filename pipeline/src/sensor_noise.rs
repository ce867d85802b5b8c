//! How noisy a depth reading is, by sensor: the yardstick for "flat at the
//! sensor's noise level" (`selection/quality.rs`).
//!
//! Two published models, one standard deviation of the axial (depth) error
//! at depth `z` (metres) and incidence angle `theta` (between the ray and
//! the surface normal):
//!
//! - **Kinect v2** (time of flight, Fankhauser et al. 2015):
//!   `1.5 - 0.5 z + 0.3 z^2 + 0.1 z^1.5 theta^2 / (pi/2 - theta)^2` mm.
//!   `slope-synth` simulates the same model.
//! - **Kinect v1** (structured light, Nguyen et al. 2012):
//!   `1.2 + 1.9 (z - 0.4)^2 + 0.1 z^-0.5 theta^2 / (pi/2 - theta)^2` mm:
//!   the error grows with the square of the depth (disparity quantisation).
//!
//! `theta` is clamped to 89° (both formulas diverge at 90°).

use std::f64::consts::FRAC_PI_2;

use serde::{Deserialize, Serialize};

const MAX_INCIDENCE_RAD: f64 = 89.0 * std::f64::consts::PI / 180.0;

/// A depth sensor's noise model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NoiseModel {
    /// Kinect v2 and other time-of-flight cameras of its class.
    #[default]
    Kinect2,
    /// Kinect v1, Asus Xtion and other structured-light cameras.
    Kinect1,
}

impl NoiseModel {
    /// The model for a recording's free-text `sensor` name: structured-light
    /// names (`kinect1`, `tum`, `xtion`, `primesense`) get
    /// [`NoiseModel::Kinect1`], everything else (`kinect2`, `synthetic`,
    /// unknown names) [`NoiseModel::Kinect2`].
    pub fn for_sensor(name: &str) -> Self {
        let name = name.to_ascii_lowercase();
        let structured_light = ["kinect1", "tum", "xtion", "primesense"];
        if structured_light.iter().any(|s| name.contains(s)) {
            Self::Kinect1
        } else {
            Self::Kinect2
        }
    }

    /// The model's name as configured.
    pub fn name(self) -> &'static str {
        match self {
            Self::Kinect2 => "kinect2",
            Self::Kinect1 => "kinect1",
        }
    }

    /// The depths the sensor reads at all, metres along the optical axis:
    /// a depth outside is no reading (a saturated or broken pixel, 65.5 m
    /// of a raw 65535). Kinect v2: 0.5 m (libfreenect2's minimum) to 8 m
    /// (its time-of-flight range with libfreenect2's `max_depth_m` raised
    /// from 4.5 m); Kinect v1: 0.4 m (near mode) to 10 m (the farthest
    /// disparity it reports). `outlier.depth_range_m` overrides it.
    pub fn depth_range_m(self) -> (f64, f64) {
        match self {
            Self::Kinect2 => (0.5, 8.0),
            Self::Kinect1 => (0.4, 10.0),
        }
    }

    /// One standard deviation of the depth error at depth `z_m` and
    /// incidence angle `theta_rad`, metres.
    #[inline]
    pub fn sigma_m(self, z_m: f64, theta_rad: f64) -> f64 {
        let theta = theta_rad.clamp(0.0, MAX_INCIDENCE_RAD);
        let angle_term = theta * theta / ((FRAC_PI_2 - theta) * (FRAC_PI_2 - theta));
        let z = z_m.max(0.0);
        let mm = match self {
            // z^1.5 as z sqrt(z): the same to an ulp, a tenth of powf's
            // instructions (plane quality takes it for every sampled point).
            Self::Kinect2 => 1.5 - 0.5 * z + 0.3 * z * z + 0.1 * z * z.sqrt() * angle_term,
            Self::Kinect1 => 1.2 + 1.9 * (z - 0.4).powi(2) + 0.1 / z.max(0.1).sqrt() * angle_term,
        };
        mm * 1e-3
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_4;

    #[test]
    fn kinect2_matches_the_published_formula_at_hand_computed_points() {
        // z = 1: 1.5 - 0.5 + 0.3 = 1.3 mm; z = 3: 1.5 - 1.5 + 2.7 = 2.7 mm.
        assert!((NoiseModel::Kinect2.sigma_m(1.0, 0.0) - 1.3e-3).abs() < 1e-12);
        assert!((NoiseModel::Kinect2.sigma_m(3.0, 0.0) - 2.7e-3).abs() < 1e-12);
        // theta = pi/4 makes the angle term 1: z = 1 adds 0.1 mm.
        assert!((NoiseModel::Kinect2.sigma_m(1.0, FRAC_PI_4) - 1.4e-3).abs() < 1e-12);
    }

    #[test]
    fn kinect1_grows_with_the_square_of_depth() {
        // z = 0.4: 1.2 mm; z = 3.4: 1.2 + 1.9 * 9 = 18.3 mm.
        assert!((NoiseModel::Kinect1.sigma_m(0.4, 0.0) - 1.2e-3).abs() < 1e-12);
        assert!((NoiseModel::Kinect1.sigma_m(3.4, 0.0) - 18.3e-3).abs() < 1e-12);
        // z = 4, theta = pi/4: + 0.1 / 2 = 0.05 mm.
        let at_4 = 1.2 + 1.9 * 3.6 * 3.6 + 0.05;
        assert!((NoiseModel::Kinect1.sigma_m(4.0, FRAC_PI_4) - at_4 * 1e-3).abs() < 1e-12);
    }

    #[test]
    fn grazing_readings_are_noisier_but_finite() {
        for model in [NoiseModel::Kinect2, NoiseModel::Kinect1] {
            assert!(model.sigma_m(2.0, 1.2) > model.sigma_m(2.0, 0.6));
            assert!(model.sigma_m(2.0, FRAC_PI_2).is_finite());
        }
    }

    #[test]
    fn a_recordings_sensor_name_picks_the_model() {
        assert_eq!(NoiseModel::for_sensor("kinect1"), NoiseModel::Kinect1);
        assert_eq!(NoiseModel::for_sensor("TUM fr1"), NoiseModel::Kinect1);
        assert_eq!(NoiseModel::for_sensor("kinect2"), NoiseModel::Kinect2);
        assert_eq!(NoiseModel::for_sensor("synthetic"), NoiseModel::Kinect2);
        assert_eq!(NoiseModel::for_sensor(""), NoiseModel::Kinect2);
    }
}
