//! The Kinect v2 sensor model: which errors the simulator adds to the exact
//! geometry, and how large they are. Sources and reasoning are in the crate
//! README ("Sensor model"). Every effect can be switched off on its own;
//! [`SensorModel::clean`] switches them all off.

use std::f64::consts::FRAC_PI_2;

use serde::{Deserialize, Serialize};

use crate::error::SceneError;

/// Parameters of the simulated sensor errors (the `[sensor]` table of a
/// scene file). Booleans enable an effect; a size or probability of 0
/// disables it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorModel {
    /// Axial (depth) noise after Fankhauser et al. 2015, see [`axial_sigma_m`].
    pub axial_noise: bool,
    /// Standard deviation of the lateral jitter of depth edges, pixels.
    pub lateral_noise_px: f64,
    /// Probability that a pixel at a depth discontinuity becomes a flying
    /// pixel (a depth between the two sides).
    pub flying_pixel_probability: f64,
    /// Smallest depth jump between neighbouring pixels of different surfaces
    /// that counts as a discontinuity, metres.
    pub flying_pixel_jump_m: f64,
    /// Multipath bias at a concave junction (ground meets ramp, wall or
    /// box), metres, added to the depth (measured too far).
    pub multipath_bias_m: f64,
    /// Distance from the junction at which the bias has fallen to 1/e, metres.
    pub multipath_decay_m: f64,
    /// Drop readings outside [`min_range_m`, `max_range_m`] (depth along the
    /// optical axis).
    pub range_limits: bool,
    pub min_range_m: f64,
    pub max_range_m: f64,
    /// Drop readings at grazing incidence: none below
    /// `grazing_dropout_start_deg`, all above `grazing_dropout_full_deg`,
    /// linear in between.
    pub grazing_dropout: bool,
    pub grazing_dropout_start_deg: f64,
    pub grazing_dropout_full_deg: f64,
    /// Probability that any reading is dropped at random.
    pub random_dropout_probability: f64,
    /// Per-frame pose jitter (vibration), standard deviations.
    pub jitter_pitch_deg: f64,
    pub jitter_roll_deg: f64,
    pub jitter_yaw_deg: f64,
    pub jitter_height_m: f64,
    /// The sensor's range bias: a depth error that grows with depth and
    /// bends a flat floor (`"none"`, `"kinect2"`, `"kinect1"`; see
    /// [`RangeBias`]). Default none.
    pub range_bias: RangeBias,
}

impl SensorModel {
    /// A realistic Kinect v2 on a small robot (the default).
    pub const KINECT2: SensorModel = SensorModel {
        axial_noise: true,
        lateral_noise_px: 0.5,
        flying_pixel_probability: 0.5,
        flying_pixel_jump_m: 0.05,
        multipath_bias_m: 0.01,
        multipath_decay_m: 0.1,
        range_limits: true,
        min_range_m: 0.5,
        max_range_m: 4.5,
        grazing_dropout: true,
        grazing_dropout_start_deg: 75.0,
        grazing_dropout_full_deg: 88.0,
        random_dropout_probability: 0.002,
        jitter_pitch_deg: 0.2,
        jitter_roll_deg: 0.2,
        jitter_yaw_deg: 0.1,
        jitter_height_m: 0.002,
        range_bias: RangeBias::None,
    };

    /// Exact geometry: every effect off. Only the quantisation to the
    /// recording's depth unit remains (and depths beyond the 16-bit range,
    /// 65.535 m at 1 mm, read as 0).
    pub fn clean() -> Self {
        Self {
            axial_noise: false,
            lateral_noise_px: 0.0,
            flying_pixel_probability: 0.0,
            multipath_bias_m: 0.0,
            range_limits: false,
            grazing_dropout: false,
            random_dropout_probability: 0.0,
            jitter_pitch_deg: 0.0,
            jitter_roll_deg: 0.0,
            jitter_yaw_deg: 0.0,
            jitter_height_m: 0.0,
            ..Self::KINECT2
        }
    }

    /// True when the model adds no error at all.
    pub fn is_clean(&self) -> bool {
        !self.axial_noise
            && self.lateral_noise_px == 0.0
            && self.flying_pixel_probability == 0.0
            && self.multipath_bias_m == 0.0
            && !self.range_limits
            && !self.grazing_dropout
            && self.random_dropout_probability == 0.0
            && !self.has_jitter()
            && self.range_bias == RangeBias::None
    }

    /// True when the camera pose varies from frame to frame.
    pub fn has_jitter(&self) -> bool {
        self.jitter_pitch_deg != 0.0
            || self.jitter_roll_deg != 0.0
            || self.jitter_yaw_deg != 0.0
            || self.jitter_height_m != 0.0
    }

    /// Probability that a reading at incidence angle `theta_rad` (between
    /// the ray and the surface normal) is lost; 0 when grazing dropout is off.
    pub fn grazing_dropout_probability(&self, theta_rad: f64) -> f64 {
        if !self.grazing_dropout {
            return 0.0;
        }
        let start = self.grazing_dropout_start_deg.to_radians();
        let full = self.grazing_dropout_full_deg.to_radians();
        if theta_rad <= start {
            0.0
        } else if theta_rad >= full {
            1.0
        } else {
            (theta_rad - start) / (full - start)
        }
    }

    /// Checks every value; the error names the key.
    pub fn validate(&self) -> Result<(), SceneError> {
        let non_negative = [
            ("sensor.lateral_noise_px", self.lateral_noise_px),
            ("sensor.flying_pixel_jump_m", self.flying_pixel_jump_m),
            ("sensor.multipath_bias_m", self.multipath_bias_m),
            ("sensor.min_range_m", self.min_range_m),
            ("sensor.jitter_pitch_deg", self.jitter_pitch_deg),
            ("sensor.jitter_roll_deg", self.jitter_roll_deg),
            ("sensor.jitter_yaw_deg", self.jitter_yaw_deg),
            ("sensor.jitter_height_m", self.jitter_height_m),
        ];
        for (key, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(invalid(key, "must be a finite number >= 0"));
            }
        }
        for (key, p) in [
            (
                "sensor.flying_pixel_probability",
                self.flying_pixel_probability,
            ),
            (
                "sensor.random_dropout_probability",
                self.random_dropout_probability,
            ),
        ] {
            if !(0.0..=1.0).contains(&p) {
                return Err(invalid(key, "must lie in [0, 1]"));
            }
        }
        if !(self.multipath_decay_m.is_finite() && self.multipath_decay_m > 0.0) {
            return Err(invalid("sensor.multipath_decay_m", "must be > 0"));
        }
        if !(self.max_range_m.is_finite() && self.max_range_m > self.min_range_m) {
            return Err(invalid(
                "sensor.max_range_m",
                "must be greater than min_range_m",
            ));
        }
        let (start, full) = (
            self.grazing_dropout_start_deg,
            self.grazing_dropout_full_deg,
        );
        if !(start.is_finite() && full.is_finite() && 0.0 <= start && start < full && full <= 90.0)
        {
            return Err(invalid(
                "sensor.grazing_dropout_full_deg",
                "need 0 <= grazing_dropout_start_deg < grazing_dropout_full_deg <= 90",
            ));
        }
        Ok(())
    }
}

impl Default for SensorModel {
    fn default() -> Self {
        Self::KINECT2
    }
}

fn invalid(key: &str, reason: &str) -> SceneError {
    SceneError::InvalidKey {
        key: key.to_string(),
        reason: reason.to_string(),
    }
}

/// A depth sensor's range bias: every reading lies a little too far (or
/// too near) along its ray, by an amount that grows with depth, so a flat
/// floor seen far away lies below (or above) the floor under the camera.
///
/// The model: a point at true depth `z` (along the optical axis) is read
/// at `z' = z + k z^2`, moved along its own ray (every coordinate scaled by
/// `1 + k z`). Seen from a camera `h` above a flat floor, a floor point at
/// depth `z` is then read `k z h` below the floor (its height below the
/// camera scales by `1 + k z`). With `k = c / h`, `c` the coefficient of
/// the pipeline's `NoiseModel::floor_height_bias_m` (`c z`: Kinect v2
/// `c = 0.005`, Kinect v1 `c = 0.01`), the floor at depth `z` lies exactly
/// that bound, `c z`, below the true floor (a test in
/// `tests/tests/real_scene_rules.rs` ties the coefficients to the
/// pipeline's). Since the offset is linear in depth, the floor stays nearly
/// a plane, turned by about `c cos(pitch)` radians (Kinect v1 at 30°
/// down: 0.50°) against the true floor: the height bound is reached, the
/// bend bound (`NoiseModel::floor_bend_deg`, 1.3-2.2° and 4°) is not; the
/// bend between pieces of the floor near and far is a few hundredths of a
/// degree (the `k^2` term). `k` depends on the camera's height in each
/// frame: the bias is made for the scene, not a property of the sensor
/// alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum RangeBias {
    /// No range bias (the default: every recording before the bias existed).
    #[default]
    None,
    /// The Kinect v2 (time of flight) bound: 5 mm per metre of depth.
    Kinect2,
    /// The Kinect v1 (structured light) bound: 10 mm per metre of depth,
    /// the largest.
    Kinect1,
}

impl RangeBias {
    /// `c`: how far below the true floor a flat floor seen at depth `z`
    /// is read, per metre of depth (the pipeline's
    /// `NoiseModel::floor_height_bias_m(z) / z`).
    pub fn height_bias_per_m(self) -> f64 {
        match self {
            Self::None => 0.0,
            Self::Kinect2 => 0.005,
            Self::Kinect1 => 0.01,
        }
    }

    /// How far below the true floor a flat floor seen `z_m` ahead (depth
    /// along the optical axis) is read, metres: `c z`.
    pub fn floor_height_bias_m(self, z_m: f64) -> f64 {
        self.height_bias_per_m() * z_m.max(0.0)
    }

    /// `k = c / h` of a camera `camera_height_m` above the floor, per metre.
    pub fn depth_coefficient_per_m(self, camera_height_m: f64) -> f64 {
        if camera_height_m > 0.0 {
            self.height_bias_per_m() / camera_height_m
        } else {
            0.0
        }
    }

    /// The depth read for a true depth `z_m` by a camera `camera_height_m`
    /// above the floor: `z + k z^2`.
    pub fn biased_depth_m(self, z_m: f64, camera_height_m: f64) -> f64 {
        let k = self.depth_coefficient_per_m(camera_height_m);
        z_m + k * z_m * z_m
    }

    /// The name in a scene file and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Kinect2 => "kinect2",
            Self::Kinect1 => "kinect1",
        }
    }
}

/// Largest incidence angle the noise formula is evaluated at (it diverges
/// at 90°); steeper readings are normally dropped as grazing anyway.
const MAX_NOISE_INCIDENCE_RAD: f64 = 89.0 * std::f64::consts::PI / 180.0;

/// Axial noise of the Kinect v2, one standard deviation in metres, at depth
/// `z_m` and incidence angle `theta_rad` (Fankhauser et al. 2015):
/// `sigma_z = 1.5 - 0.5 z + 0.3 z^2 + 0.1 z^1.5 theta^2 / (pi/2 - theta)^2`
/// millimetres, z in metres. `theta` is clamped to 89°.
pub fn axial_sigma_m(z_m: f64, theta_rad: f64) -> f64 {
    let theta = theta_rad.clamp(0.0, MAX_NOISE_INCIDENCE_RAD);
    let angle_term = theta * theta / ((FRAC_PI_2 - theta) * (FRAC_PI_2 - theta));
    let sigma_mm = 1.5 - 0.5 * z_m + 0.3 * z_m * z_m + 0.1 * z_m.powf(1.5) * angle_term;
    sigma_mm * 1e-3
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigma_matches_the_published_formula_at_hand_computed_points() {
        // z = 1: 1.5 - 0.5 + 0.3 = 1.3 mm; z = 2: 1.5 - 1 + 1.2 = 1.7 mm;
        // z = 3: 1.5 - 1.5 + 2.7 = 2.7 mm (fronto-parallel).
        assert!((axial_sigma_m(1.0, 0.0) - 1.3e-3).abs() < 1e-12);
        assert!((axial_sigma_m(2.0, 0.0) - 1.7e-3).abs() < 1e-12);
        assert!((axial_sigma_m(3.0, 0.0) - 2.7e-3).abs() < 1e-12);
        // theta = pi/4: theta^2 / (pi/2 - theta)^2 = 1, so z = 1 adds 0.1 mm.
        let s = axial_sigma_m(1.0, std::f64::consts::FRAC_PI_4);
        assert!((s - 1.4e-3).abs() < 1e-12);
        // Grows with angle, finite at 90°.
        assert!(axial_sigma_m(2.0, 1.2) > axial_sigma_m(2.0, 0.6));
        assert!(axial_sigma_m(2.0, FRAC_PI_2).is_finite());
    }

    #[test]
    fn clean_is_clean_and_default_is_not() {
        assert!(SensorModel::clean().is_clean());
        assert!(!SensorModel::default().is_clean());
        assert!(SensorModel::clean().validate().is_ok());
        assert!(SensorModel::default().validate().is_ok());
    }

    #[test]
    fn grazing_dropout_ramps_linearly() {
        let m = SensorModel::default();
        assert_eq!(m.grazing_dropout_probability(70f64.to_radians()), 0.0);
        assert_eq!(m.grazing_dropout_probability(89f64.to_radians()), 1.0);
        let mid = m.grazing_dropout_probability(81.5f64.to_radians());
        assert!((mid - 0.5).abs() < 1e-9);
        assert_eq!(SensorModel::clean().grazing_dropout_probability(1.5), 0.0);
    }

    #[test]
    fn range_bias_puts_the_floor_c_z_below_the_truth() {
        // A floor point at depth z seen from height h: its height below the
        // camera scales with the depth, h (1 + k z) = h + c z.
        for bias in [RangeBias::Kinect2, RangeBias::Kinect1] {
            for (h, z) in [(0.5, 1.0), (1.2, 3.0), (1.35, 4.5)] {
                let scale = bias.biased_depth_m(z, h) / z;
                let below = h * scale - h;
                assert!((below - bias.floor_height_bias_m(z)).abs() < 1e-12);
            }
        }
        assert_eq!(RangeBias::None.biased_depth_m(2.0, 1.0), 2.0);
        assert!((RangeBias::Kinect1.floor_height_bias_m(3.0) - 0.03).abs() < 1e-15);
        assert!((RangeBias::Kinect2.floor_height_bias_m(3.0) - 0.015).abs() < 1e-15);
        assert!(!SensorModel {
            range_bias: RangeBias::Kinect2,
            ..SensorModel::clean()
        }
        .is_clean());
    }

    #[test]
    fn invalid_values_name_their_key() {
        let m = SensorModel {
            flying_pixel_probability: 1.5,
            ..SensorModel::default()
        };
        let err = m.validate().expect_err("probability > 1");
        assert!(err.to_string().contains("flying_pixel_probability"));
        let m = SensorModel {
            max_range_m: 0.1,
            ..SensorModel::default()
        };
        assert!(m.validate().is_err());
    }
}
