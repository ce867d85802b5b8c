//! [`SelectionConfig`]: what makes a plane the ground or the inclined plane.

use serde::{Deserialize, Serialize};

use crate::sensor_noise::NoiseModel;
use crate::validate::{angle, check, fraction, non_negative, InvalidValue};

/// Which plane is the ground and which the inclined plane.
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
    /// the Kinect v1 office walls 0.4-1.0 with their model; a bed's fabric
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

impl SelectionConfig {
    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), InvalidValue> {
        angle("ground_max_tilt_deg", self.ground_max_tilt_deg)?;
        angle(
            "unmounted_ground_max_tilt_deg",
            self.unmounted_ground_max_tilt_deg,
        )?;
        angle("parallel_tolerance_deg", self.parallel_tolerance_deg)?;
        angle("max_slope_deg", self.max_slope_deg)?;
        check(
            self.max_slope_deg > self.parallel_tolerance_deg,
            "max_slope_deg",
            self.max_slope_deg,
            "must be larger than selection.parallel_tolerance_deg",
        )?;
        for (key, value) in [
            ("max_relative_rms", self.max_relative_rms),
            ("max_noise_ratio", self.max_noise_ratio),
            ("inclined_min_area_m2", self.inclined_min_area_m2),
            ("ground_min_area_m2", self.ground_min_area_m2),
            ("ground_height_tolerance_m", self.ground_height_tolerance_m),
            ("coplanar_tolerance_m", self.coplanar_tolerance_m),
        ] {
            non_negative(key, value)?;
        }
        angle("max_heading_deg", self.max_heading_deg)?;
        fraction("min_relative_support", self.min_relative_support)
    }
}
