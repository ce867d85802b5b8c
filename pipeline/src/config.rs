//! [`EstimatorConfig`]: every parameter of the pipeline, with the paper's
//! values as defaults, read from TOML.
//!
//! ```toml
//! method = "paper"          # "paper" | "least-squares" | "tls"
//! seed = 0                  # seed of every random draw (RANSAC, averaging)
//!
//! [outlier]                 # statistical outlier removal (paper 2.1)
//! neighbours = 20           # m
//! std_ratio = 2.0           # alpha
//!
//! [ransac]                  # plane segmentation (paper 2.2, 3)
//! distance_threshold_m = 0.02
//!
//! [pass_through]            # paper 3.1
//! max_points = 10000
//!
//! [normals]                 # paper 2.3
//! neighbours = 100          # K
//!
//! [kmeans]                  # paper 3.1
//! clusters = 3
//!
//! [cumulative]              # paper 3.2
//! draws = 1000              # paper: 100
//!
//! [tracking]                # the slope followed over frames
//! window = 15
//! ```
//!
//! Every section and key is optional; `deny_unknown_fields` turns a typo into
//! an error that names the key.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use slope_ipc_types::SlopeMethod;

use crate::sensor_noise::NoiseModel;

pub use crate::tracking::TrackingConfig;

/// The method named on command lines and in config files:
/// `"paper" | "least-squares" | "tls"`.
pub fn parse_method(name: &str) -> Option<SlopeMethod> {
    SlopeMethod::ALL.into_iter().find(|m| m.name() == name)
}

/// Why a configuration was rejected.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("estimator config is not valid TOML or has an unknown key")]
    Parse(#[from] toml::de::Error),
    #[error("estimator config key `{key}` = {value}: {reason}")]
    Invalid {
        key: &'static str,
        value: String,
        reason: &'static str,
    },
}

/// All parameters of the estimator. `Default` holds the paper's values where
/// the paper gives one and documented choices elsewhere (pipeline README).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EstimatorConfig {
    /// Which fit turns the two planes into a slope.
    #[serde(
        serialize_with = "serialize_method",
        deserialize_with = "deserialize_method"
    )]
    pub method: SlopeMethod,
    /// Seed of every random draw; the same frame and config give the same
    /// estimate.
    pub seed: u64,
    pub outlier: OutlierConfig,
    pub ransac: RansacConfig,
    pub pass_through: PassThroughConfig,
    pub normals: NormalsConfig,
    pub kmeans: KmeansConfig,
    pub cumulative: CumulativeConfig,
    pub selection: SelectionConfig,
    pub tracking: TrackingConfig,
}

impl Default for EstimatorConfig {
    fn default() -> Self {
        Self {
            method: SlopeMethod::Paper,
            seed: 0,
            outlier: OutlierConfig::default(),
            ransac: RansacConfig::default(),
            pass_through: PassThroughConfig::default(),
            normals: NormalsConfig::default(),
            kmeans: KmeansConfig::default(),
            cumulative: CumulativeConfig::default(),
            selection: SelectionConfig::default(),
            tracking: TrackingConfig::default(),
        }
    }
}

/// Statistical outlier removal (`statistical_outlier.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutlierConfig {
    pub enabled: bool,
    /// m: neighbours whose mean distance is the point's statistic (paper: 20).
    pub neighbours: usize,
    /// alpha: drop points beyond mean + alpha * std (paper: 2).
    pub std_ratio: f64,
}

impl Default for OutlierConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            neighbours: 20,
            std_ratio: 2.0,
        }
    }
}

/// RANSAC plane segmentation (`ransac_planes.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RansacConfig {
    /// A point within this distance of a plane is an inlier, metres...
    pub distance_threshold_m: f64,
    /// ...or within this times its squared depth (metres per square metre),
    /// whichever is larger: depth noise and quantisation grow with the
    /// square of the depth (a Kinect v1 quantises 5 m to 7 cm terraces).
    pub distance_threshold_per_m2: f64,
    /// Hypotheses drawn per plane at most (fewer when `confidence` is reached).
    pub max_iterations: usize,
    /// Probability of drawing at least one all-inlier sample, which sets the
    /// adaptive iteration count.
    pub confidence: f64,
    /// Planes are found on every `sample_stride_px`-th pixel in both
    /// directions (the sample grid); at the end every pixel within the
    /// threshold goes to the nearest of the planes that took the sample
    /// points around it (its 3x3 sample cells).
    pub sample_stride_px: usize,
    /// A sample point whose local normal is further than this from the
    /// hypothesis' normal is not its inlier, degrees; 0 or >= 90 disables.
    pub normal_threshold_deg: f64,
    /// A plane's region on the sample grid must stand for at least this
    /// many pixels (`min_plane_points / stride^2` sample points), else its
    /// sample inliers are set aside as a failure (the 9th failure ends the
    /// search); planes with fewer pixels in the end are dropped.
    pub min_plane_points: usize,
    /// Stop when fewer than this fraction of the sample points is free
    /// (neither in a plane nor set aside by a failure).
    pub min_remaining_fraction: f64,
    /// Stop after this many planes (at most 65,535).
    pub max_planes: usize,
}

impl Default for RansacConfig {
    fn default() -> Self {
        Self {
            distance_threshold_m: 0.02,
            distance_threshold_per_m2: 0.003,
            max_iterations: 500,
            confidence: 0.999,
            sample_stride_px: 4,
            normal_threshold_deg: 30.0,
            min_plane_points: 800,
            min_remaining_fraction: 0.03,
            max_planes: 24,
        }
    }
}

/// Pass-through filter (`pass_through.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PassThroughConfig {
    /// A plane with more points is cut down to at most this many (paper: 10,000).
    pub max_points: usize,
}

impl Default for PassThroughConfig {
    fn default() -> Self {
        Self { max_points: 10_000 }
    }
}

/// Normal estimation (`normals.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NormalsConfig {
    /// K: neighbours of the local plane fit (paper: 100).
    pub neighbours: usize,
    /// Largest pixel window radius tried before the k-d tree takes over.
    pub max_window_radius_px: usize,
    /// Fit each neighbourhood for depth noise along the viewing ray
    /// (`C^-1 r`) instead of isotropic noise (the smallest eigenvector, as
    /// the paper); see `normals.rs`.
    pub ray_noise_correction: bool,
    /// Keep only the normals of interior points, whose smallest window
    /// holds K of the plane's points (border points see one side of their
    /// neighbourhood, and on real surfaces the mixed pixels and multipath of
    /// the edge); all normals when fewer than K or a tenth are interior.
    pub interior_only: bool,
    /// The neighbourhood spans at least this radius on the surface, metres
    /// (more than K points near the camera); 0 = K points only.
    pub min_patch_radius_m: f64,
    /// ...and at least this many times the RMS distance of the plane's
    /// RANSAC inliers from their TLS plane (depth noise, quantisation and
    /// roughness together): the noise bias of a local PCA normal is about
    /// `2 (sigma / r)^2` radians, 0.3 degrees at 20; 0 = off.
    pub patch_per_rms: f64,
}

impl Default for NormalsConfig {
    fn default() -> Self {
        Self {
            neighbours: 100,
            max_window_radius_px: 80,
            ray_noise_correction: false,
            interior_only: true,
            min_patch_radius_m: 0.1,
            patch_per_rms: 20.0,
        }
    }
}

impl NormalsConfig {
    /// This configuration for a plane whose RANSAC inliers lie `rms_m` (RMS)
    /// from their TLS plane: the patch radius grows to `patch_per_rms *
    /// rms_m` when that is larger than `min_patch_radius_m`.
    pub fn for_plane_noise(&self, rms_m: f64) -> NormalsConfig {
        let scaled = self.patch_per_rms * rms_m;
        NormalsConfig {
            min_patch_radius_m: if scaled.is_finite() {
                self.min_patch_radius_m.max(scaled)
            } else {
                self.min_patch_radius_m
            },
            ..self.clone()
        }
    }
}

/// Cosine k-means (`cosine_kmeans.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct KmeansConfig {
    /// Clusters per plane; the largest is kept.
    pub clusters: usize,
    pub max_iterations: usize,
    /// Clusters whose centre is within this many RMS spreads of the dominant
    /// cluster's centre are kept with it (one population k-means cut up);
    /// 0 keeps the dominant cluster only, as the paper.
    pub merge_spread_ratio: f64,
}

impl Default for KmeansConfig {
    fn default() -> Self {
        Self {
            clusters: 3,
            max_iterations: 30,
            merge_spread_ratio: 2.5,
        }
    }
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
    /// the unsigned angle of each pair, as the paper.
    pub about_axis: bool,
}

impl Default for CumulativeConfig {
    fn default() -> Self {
        Self {
            draws: 1000,
            about_axis: true,
        }
    }
}

/// Which plane is the ground and which the inclined plane (`selection/`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SelectionConfig {
    /// A plane is flat (a measurement surface) when the RMS of its inliers'
    /// distances, each divided by its RANSAC inlier threshold, is at most
    /// this: a flat surface scores its noise over the threshold (real
    /// Kinect floors and walls 0.1-0.3), a surface that fills the band
    /// evenly 0.58.
    pub max_relative_rms: f64,
    /// The sensor's noise model (`"kinect2"` or `"kinect1"`) that flatness
    /// is judged against. Unset: the recording's `sensor` decides where the
    /// frames come from a recording (`slope-eval`), else `"kinect2"` (the
    /// camera `slope-capture` drives).
    pub noise_model: Option<NoiseModel>,
    /// An inclined plane (the surface the slope is measured on) is flat when
    /// the RMS of its inliers' distances, in standard deviations of the
    /// noise model, is at most this (real Kinect v2 risers and walls 1.2-2.6,
    /// the Kinect v1 office walls 0.6-1.0 with their model; a bed's fabric
    /// side 3.8-5.8).
    pub max_noise_ratio: f64,
    /// An inclined plane covers at least this much surface, square metres
    /// (a 20 x 20 cm patch; real stair risers 0.07-0.14): smaller flat
    /// patches are clutter, or pieces RANSAC carved out of a rough surface,
    /// which look flatter the smaller they are.
    pub inclined_min_area_m2: f64,
    /// With a mount: a ground candidate's normal is within this of the
    /// mount's up vector, degrees.
    pub ground_max_tilt_deg: f64,
    /// Without a mount: a ground candidate's normal is within this of the
    /// camera's up (-y), degrees.
    pub unmounted_ground_max_tilt_deg: f64,
    /// The ground has at least this many pixels...
    pub ground_min_pixels: usize,
    /// ...and covers at least this much surface, square metres.
    pub ground_min_area_m2: f64,
    /// With a known mount height: the ground lies within this of it, metres;
    /// no level plane does: the mount's plane is the ground.
    pub ground_height_tolerance_m: f64,
    /// A level plane parallel to the ground whose centroid is within this of
    /// the ground plane is a piece of the ground, metres.
    pub coplanar_tolerance_m: f64,
    /// Planes whose normals are within this of each other are parallel
    /// (treads, floor, table tops; real treads and floors differ by up to
    /// 3.5 degrees as measured); an inclined plane differs from the ground
    /// by more, degrees.
    pub parallel_tolerance_deg: f64,
    /// An inclined plane's normal is at most this from the ground's: beyond
    /// 90 a surface faces down (a ceiling, an overhang), degrees.
    pub max_slope_deg: f64,
    /// An inclined plane's horizontal normal is within this of the forward
    /// axis (a ramp ahead or a wall faced), not beside the robot, degrees.
    pub max_heading_deg: f64,
    /// Among inclined candidates the nearest is taken unless it has fewer than
    /// this fraction of the best-supported candidate's inliers.
    pub min_relative_support: f64,
}

impl Default for SelectionConfig {
    fn default() -> Self {
        Self {
            max_relative_rms: 0.45,
            noise_model: None,
            max_noise_ratio: 3.5,
            inclined_min_area_m2: 0.04,
            ground_max_tilt_deg: 15.0,
            unmounted_ground_max_tilt_deg: 50.0,
            ground_min_pixels: 2000,
            ground_min_area_m2: 0.1,
            ground_height_tolerance_m: 0.15,
            coplanar_tolerance_m: 0.05,
            parallel_tolerance_deg: 4.0,
            max_slope_deg: 100.0,
            max_heading_deg: 50.0,
            min_relative_support: 0.25,
        }
    }
}

impl EstimatorConfig {
    /// This configuration for frames of the named sensor (a recording's
    /// `sensor`): an unset `selection.noise_model` becomes that sensor's
    /// ([`NoiseModel::for_sensor`]); a configured one is kept.
    pub fn for_sensor(mut self, sensor: &str) -> Self {
        self.selection
            .noise_model
            .get_or_insert(NoiseModel::for_sensor(sensor));
        self
    }

    /// Parses a TOML document; missing keys keep their defaults. The result
    /// is validated.
    pub fn from_toml_str(text: &str) -> Result<Self, ConfigError> {
        let config: Self = toml::from_str(text)?;
        config.validate()?;
        Ok(config)
    }

    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), ConfigError> {
        fn positive(key: &'static str, v: f64) -> Result<(), ConfigError> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(invalid(key, v, "must be a finite number > 0"))
            }
        }
        fn angle(key: &'static str, v: f64) -> Result<(), ConfigError> {
            if v.is_finite() && (0.0..=180.0).contains(&v) {
                Ok(())
            } else {
                Err(invalid(key, v, "must be an angle in 0..=180 degrees"))
            }
        }
        fn at_least(key: &'static str, v: usize, min: usize) -> Result<(), ConfigError> {
            if v >= min {
                Ok(())
            } else {
                Err(invalid(
                    key,
                    v,
                    if min == 1 {
                        "must be at least 1"
                    } else {
                        "is too small"
                    },
                ))
            }
        }
        fn fraction(key: &'static str, v: f64) -> Result<(), ConfigError> {
            if v.is_finite() && (0.0..=1.0).contains(&v) {
                Ok(())
            } else {
                Err(invalid(key, v, "must be in 0..=1"))
            }
        }
        at_least("outlier.neighbours", self.outlier.neighbours, 1)?;
        if self.outlier.neighbours > crate::statistical_outlier::MAX_NEIGHBOURS {
            return Err(invalid(
                "outlier.neighbours",
                self.outlier.neighbours,
                "must be at most 48 (the 7x7 pixel window)",
            ));
        }
        if !(self.outlier.std_ratio.is_finite() && self.outlier.std_ratio >= 0.0) {
            return Err(invalid(
                "outlier.std_ratio",
                self.outlier.std_ratio,
                "must be a finite number >= 0",
            ));
        }
        positive(
            "ransac.distance_threshold_m",
            self.ransac.distance_threshold_m,
        )?;
        if !(self.ransac.distance_threshold_per_m2.is_finite()
            && self.ransac.distance_threshold_per_m2 >= 0.0)
        {
            return Err(invalid(
                "ransac.distance_threshold_per_m2",
                self.ransac.distance_threshold_per_m2,
                "must be a finite number >= 0",
            ));
        }
        at_least("ransac.max_iterations", self.ransac.max_iterations, 1)?;
        if !(self.ransac.confidence > 0.0 && self.ransac.confidence < 1.0) {
            return Err(invalid(
                "ransac.confidence",
                self.ransac.confidence,
                "must be in the open interval (0, 1)",
            ));
        }
        at_least("ransac.sample_stride_px", self.ransac.sample_stride_px, 1)?;
        angle(
            "ransac.normal_threshold_deg",
            self.ransac.normal_threshold_deg,
        )?;
        at_least("ransac.min_plane_points", self.ransac.min_plane_points, 3)?;
        fraction(
            "ransac.min_remaining_fraction",
            self.ransac.min_remaining_fraction,
        )?;
        at_least("ransac.max_planes", self.ransac.max_planes, 1)?;
        if self.ransac.max_planes > crate::ransac_planes::MAX_PLANES {
            return Err(invalid(
                "ransac.max_planes",
                self.ransac.max_planes,
                "must be at most 65535",
            ));
        }
        at_least("pass_through.max_points", self.pass_through.max_points, 3)?;
        at_least("normals.neighbours", self.normals.neighbours, 3)?;
        at_least(
            "normals.max_window_radius_px",
            self.normals.max_window_radius_px,
            1,
        )?;
        for (key, value) in [
            (
                "normals.min_patch_radius_m",
                self.normals.min_patch_radius_m,
            ),
            ("normals.patch_per_rms", self.normals.patch_per_rms),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(invalid(key, value, "must be a finite number >= 0"));
            }
        }
        at_least("kmeans.clusters", self.kmeans.clusters, 1)?;
        at_least("kmeans.max_iterations", self.kmeans.max_iterations, 1)?;
        if !(self.kmeans.merge_spread_ratio.is_finite() && self.kmeans.merge_spread_ratio >= 0.0) {
            return Err(invalid(
                "kmeans.merge_spread_ratio",
                self.kmeans.merge_spread_ratio,
                "must be a finite number >= 0",
            ));
        }
        at_least("cumulative.draws", self.cumulative.draws, 1)?;
        let s = &self.selection;
        angle("selection.ground_max_tilt_deg", s.ground_max_tilt_deg)?;
        angle(
            "selection.unmounted_ground_max_tilt_deg",
            s.unmounted_ground_max_tilt_deg,
        )?;
        angle("selection.parallel_tolerance_deg", s.parallel_tolerance_deg)?;
        angle("selection.max_slope_deg", s.max_slope_deg)?;
        if s.max_slope_deg <= s.parallel_tolerance_deg {
            return Err(invalid(
                "selection.max_slope_deg",
                s.max_slope_deg,
                "must be larger than selection.parallel_tolerance_deg",
            ));
        }
        for (key, value) in [
            ("selection.max_relative_rms", s.max_relative_rms),
            ("selection.max_noise_ratio", s.max_noise_ratio),
            ("selection.inclined_min_area_m2", s.inclined_min_area_m2),
            ("selection.ground_min_area_m2", s.ground_min_area_m2),
            (
                "selection.ground_height_tolerance_m",
                s.ground_height_tolerance_m,
            ),
            ("selection.coplanar_tolerance_m", s.coplanar_tolerance_m),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(invalid(key, value, "must be a finite number >= 0"));
            }
        }
        angle("selection.max_heading_deg", s.max_heading_deg)?;
        fraction("selection.min_relative_support", s.min_relative_support)?;
        let t = &self.tracking;
        at_least("tracking.window", t.window, 1)?;
        at_least("tracking.reset_after", t.reset_after, 1)?;
        at_least("tracking.max_missed", t.max_missed, 1)?;
        fraction("tracking.min_confidence", t.min_confidence)?;
        for (key, value) in [
            ("tracking.gate_deg", t.gate_deg),
            ("tracking.gate_sigmas", t.gate_sigmas),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(invalid(key, value, "must be a finite number >= 0"));
            }
        }
        Ok(())
    }
}

fn invalid(key: &'static str, value: impl ToString, reason: &'static str) -> ConfigError {
    ConfigError::Invalid {
        key,
        value: value.to_string(),
        reason,
    }
}

fn serialize_method<S: Serializer>(method: &SlopeMethod, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(method.name())
}

fn deserialize_method<'de, D: Deserializer<'de>>(d: D) -> Result<SlopeMethod, D::Error> {
    let name = String::deserialize(d)?;
    parse_method(&name).ok_or_else(|| {
        serde::de::Error::custom(format!(
            "unknown method \"{name}\": expected \"paper\", \"least-squares\" or \"tls\""
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_papers() {
        let c = EstimatorConfig::default();
        assert_eq!(c.method, SlopeMethod::Paper);
        assert_eq!(c.outlier.neighbours, 20);
        assert_eq!(c.outlier.std_ratio, 2.0);
        assert_eq!(c.pass_through.max_points, 10_000);
        assert_eq!(c.normals.neighbours, 100);
        assert_eq!(c.cumulative.draws, 1000);
        c.validate().unwrap();
    }

    #[test]
    fn toml_overrides_and_keeps_defaults() {
        let c = EstimatorConfig::from_toml_str(
            "method = \"least-squares\"\nseed = 7\n[ransac]\ndistance_threshold_m = 0.01\n",
        )
        .unwrap();
        assert_eq!(c.method, SlopeMethod::LeastSquares);
        assert_eq!(c.seed, 7);
        assert_eq!(c.ransac.distance_threshold_m, 0.01);
        assert_eq!(
            c.ransac.max_iterations,
            RansacConfig::default().max_iterations
        );
        assert_eq!(c.normals, NormalsConfig::default());
        assert_eq!(
            EstimatorConfig::from_toml_str("").unwrap(),
            EstimatorConfig::default()
        );
    }

    #[test]
    fn round_trips_through_toml() {
        let mut c = EstimatorConfig {
            method: SlopeMethod::Tls,
            ..EstimatorConfig::default()
        };
        c.kmeans.clusters = 4;
        let text = toml::to_string(&c).unwrap();
        assert_eq!(EstimatorConfig::from_toml_str(&text).unwrap(), c);
    }

    #[test]
    fn patch_radius_follows_the_plane_noise() {
        let n = NormalsConfig::default();
        // 20 x 1 cm RMS = 20 cm; 20 x 1 mm is under the 10 cm minimum.
        assert!((n.for_plane_noise(0.01).min_patch_radius_m - 0.2).abs() < 1e-12);
        assert_eq!(n.for_plane_noise(0.001).min_patch_radius_m, 0.1);
        assert_eq!(n.for_plane_noise(f64::NAN).min_patch_radius_m, 0.1);
        let off = NormalsConfig {
            patch_per_rms: 0.0,
            ..NormalsConfig::default()
        };
        assert_eq!(off.for_plane_noise(0.05).min_patch_radius_m, 0.1);
        let e = EstimatorConfig::from_toml_str(
            "[normals]
patch_per_rms = -1
",
        )
        .unwrap_err();
        assert!(e.to_string().contains("normals.patch_per_rms"), "{e}");
    }

    #[test]
    fn unknown_keys_and_methods_are_errors() {
        let report = |text: &str| {
            let e = EstimatorConfig::from_toml_str(text).unwrap_err();
            slope_sensor::error_chain::ErrorChain(&e).to_string()
        };
        for (text, named) in [
            ("[ransac]\ndistance = 0.01\n", "distance"),
            ("method = \"magic\"\n", "magic"),
            ("[cumulative]\ndraws = 0\n", "cumulative.draws"),
            ("[ransac]\nconfidence = 1.0\n", "ransac.confidence"),
        ] {
            let e = report(text);
            assert!(e.contains(named), "{e}");
        }
        // The TOML detail is the cause, not repeated in the message.
        let e = EstimatorConfig::from_toml_str("[ransac]\ndistance = 0.01\n").unwrap_err();
        assert!(!e.to_string().contains("distance"), "{e}");
    }

    #[test]
    fn method_names() {
        assert_eq!(parse_method("paper"), Some(SlopeMethod::Paper));
        assert_eq!(
            parse_method("least-squares"),
            Some(SlopeMethod::LeastSquares)
        );
        assert_eq!(parse_method("tls"), Some(SlopeMethod::Tls));
        assert_eq!(parse_method("TLS"), None);
    }
}
