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
//!
//! **Range bias.** Beside its noise, a real depth sensor bends a flat floor:
//! a plane fitted to a piece of the floor seen far away is tilted against
//! the floor seen near, and lies a little above or below it. Each model
//! states how far, as bounds that grow with depth ([`NoiseModel::floor_bend_deg`],
//! [`NoiseModel::floor_height_bias_m`]). The selection joins a level piece
//! within these bounds to the ground instead of calling it a step or a ramp,
//! and a ramp must be tilted beyond the bend at its distance. Measured on the
//! real frames of `shared/data` (the pipeline README, "Range bias", gives the
//! figures and the commands): a Kinect v2 floor's pieces 0.6-1.9 degrees
//! apart and within 2 cm of the near floor to 4.5 m; Kinect v1 (structured
//! light) pieces up to 3.6 degrees at 2 m and 4.3 at 3 m and beyond, within
//! 2 cm to 5.5 m and 6 cm at 6.5 m. `slope-synth` simulates a Kinect v2 with
//! no bias unless told (`--range-bias`).

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

    /// The largest angle between a piece of a flat floor whose centre lies
    /// `z_m` metres ahead of the camera (along the optical axis) and the
    /// floor seen near, degrees: the range bias's bend plus the tilt that
    /// the sensor's depth structure (Kinect v1's disparity terraces) gives
    /// a small piece's plane.
    ///
    /// - Kinect v2: `1.0 + 0.3 z` (1.3 at 1 m, 2.2 at 4 m): the real
    ///   Kinect v2 floors' pieces lie 0.6-1.9 apart.
    /// - Kinect v1: `4.0` up to 3 m, then `4.0 + 0.5 (z - 3)`: pieces 2.2-3.6
    ///   from their floor at 2-3 m, up to 4.3 beyond.
    pub fn floor_bend_deg(self, z_m: f64) -> f64 {
        let z = z_m.max(0.0);
        match self {
            Self::Kinect2 => 1.0 + 0.3 * z,
            Self::Kinect1 => 4.0 + 0.5 * (z - 3.0).max(0.0),
        }
    }

    /// How far above or below the near floor's plane a flat floor seen
    /// `z_m` metres ahead may lie, metres (the median height of the floor's
    /// points at that depth): Kinect v2 `0.005 z` (5 mm a metre), Kinect v1
    /// `0.01 z`.
    pub fn floor_height_bias_m(self, z_m: f64) -> f64 {
        let z = z_m.max(0.0);
        match self {
            Self::Kinect2 => 0.005 * z,
            Self::Kinect1 => 0.01 * z,
        }
    }

    /// How far a flat floor's point seen `z_m` metres ahead (its extremes
    /// among a piece's points) may lie from the near floor's plane, metres:
    /// the height bias and two standard deviations of the noise at the
    /// point (taken at a grazing 75 degrees, the floor a few metres ahead
    /// of a camera a metre up).
    pub fn floor_band_m(self, z_m: f64) -> f64 {
        self.floor_height_bias_m(z_m) + 2.0 * self.sigma_m(z_m, 75f64.to_radians())
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

    /// The range bias's bounds at hand-computed points, growing with depth.
    #[test]
    fn the_range_bias_grows_with_depth_as_stated() {
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(close(NoiseModel::Kinect2.floor_bend_deg(1.0), 1.3));
        assert!(close(NoiseModel::Kinect2.floor_bend_deg(4.0), 2.2));
        assert!(close(NoiseModel::Kinect1.floor_bend_deg(2.0), 4.0));
        assert!(close(NoiseModel::Kinect1.floor_bend_deg(5.0), 5.0));
        assert!(close(NoiseModel::Kinect2.floor_height_bias_m(4.0), 0.02));
        assert!(close(NoiseModel::Kinect1.floor_height_bias_m(4.0), 0.04));
        // The band: the height bias and two deviations at 75 degrees.
        let sigma = NoiseModel::Kinect1.sigma_m(3.0, 75f64.to_radians());
        assert!(close(
            NoiseModel::Kinect1.floor_band_m(3.0),
            0.03 + 2.0 * sigma
        ));
        for model in [NoiseModel::Kinect2, NoiseModel::Kinect1] {
            for z in [0.5, 1.0, 2.0, 4.0, 6.0] {
                assert!(model.floor_bend_deg(z + 1.0) >= model.floor_bend_deg(z));
                assert!(model.floor_band_m(z + 1.0) > model.floor_band_m(z));
            }
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
