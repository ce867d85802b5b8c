//! An [`Estimate`] written into the `SlopeEstimate` message subscribers
//! receive (`slope.SlopeEstimate.v2`).

use slope_ipc_types::SlopeEstimate;

use crate::estimate::Estimate;

impl Estimate {
    /// Fills the estimate's fields of `msg` (not the stamps, frame index or
    /// drop counter, which belong to the caller). An absent plane leaves its
    /// coefficients and inliers 0 and its RMS and area NaN (and, for the
    /// ground, how far it was seen); an absent track
    /// leaves the tracked slope and spread NaN and its counts 0.
    pub fn write_message(&self, msg: &mut SlopeEstimate) {
        msg.status = self.status as u32;
        msg.method = self.method as u32;
        msg.slope_deg = self.slope_deg;
        msg.slope_std_deg = self.slope_std_deg;
        msg.distance_m = self.distance_m;
        msg.ground_plane = self.ground.map_or([0.0; 4], |p| p.coefficients);
        msg.inclined_plane = self.inclined.map_or([0.0; 4], |p| p.coefficients);
        msg.ground_inliers = self.ground.map_or(0, |p| p.inliers);
        msg.inclined_inliers = self.inclined.map_or(0, |p| p.inliers);
        msg.samples = self.samples;
        msg.ground_from_mount = u32::from(self.ground_from_mount);
        msg.processing_us = (self.timings.total_ms * 1000.0).round().max(0.0) as u64;
        msg.confidence = self.confidence;
        msg.confidence_reasons = self.confidence_reasons;
        msg.ground_seen_to_m = self.ground_seen_to_m as f32;
        msg.ground_rms_m = self.ground.map_or(f64::NAN, |p| p.rms_m);
        msg.inclined_rms_m = self.inclined.map_or(f64::NAN, |p| p.rms_m);
        msg.ground_area_m2 = self.ground.map_or(f64::NAN, |p| p.area_m2);
        msg.inclined_area_m2 = self.inclined.map_or(f64::NAN, |p| p.area_m2);
        msg.tracked_slope_deg = self.tracked.map_or(f64::NAN, |t| t.slope_deg);
        msg.tracked_std_deg = self.tracked.map_or(f64::NAN, |t| t.std_deg);
        msg.tracked_frames = self.tracked.map_or(0, |t| t.frames);
        msg.tracked_accepted = self.tracked.map_or(0, |t| u32::from(t.accepted));
    }
}

#[cfg(test)]
mod tests {
    use slope_ipc_types::{confidence, EstimateStatus, SlopeMethod};

    use super::*;
    use crate::fixtures::{Scene, SceneCloud};
    use crate::tracking::TrackedSlope;
    use crate::{Estimator, EstimatorConfig};

    /// A real estimate of a ramp (so that the test follows new fields of
    /// `Estimate`), with every field the message carries set to a
    /// recognisable value.
    fn estimate() -> Estimate {
        let mut estimator = Estimator::new(EstimatorConfig {
            method: SlopeMethod::Tls,
            ..EstimatorConfig::default()
        });
        let mut e = estimator.estimate(&SceneCloud::kinect2(&Scene::ramp(16.0), 1).view());
        assert_eq!(e.status, EstimateStatus::Ok, "{e:?}");
        e.slope_deg = -12.5;
        e.slope_std_deg = 0.25;
        e.samples = 1;
        e.distance_m = 1.75;
        let ground = e.ground.as_mut().expect("a ground plane");
        ground.coefficients = [0.0, -0.94, 0.34, 0.5];
        ground.inliers = 40_000;
        ground.rms_m = 0.002;
        ground.area_m2 = 3.5;
        let inclined = e.inclined.as_mut().expect("an inclined plane");
        inclined.coefficients = [0.0, -0.7, -0.7, 1.2];
        inclined.inliers = 9_000;
        inclined.rms_m = 0.004;
        inclined.area_m2 = 0.8;
        e.ground_from_mount = false;
        e.ground_seen_to_m = 4.25;
        e.confidence = 0.75;
        e.confidence_reasons = confidence::FEW_POINTS | confidence::NEAR_BORDER;
        e.tracked = Some(TrackedSlope {
            slope_deg: -12.25,
            std_deg: 0.125,
            frames: 7,
            accepted: true,
        });
        e.timings.total_ms = 12.3456;
        e
    }

    #[test]
    fn every_field_reaches_the_message() {
        let e = estimate();
        let mut msg = SlopeEstimate {
            frame_index: 42,
            capture_stamp_ns: 7,
            dropped_frames: 3,
            ..SlopeEstimate::default()
        };
        e.write_message(&mut msg);
        // The caller's fields are left alone.
        assert_eq!(
            (msg.frame_index, msg.capture_stamp_ns, msg.dropped_frames),
            (42, 7, 3)
        );
        assert_eq!(msg.status(), EstimateStatus::Ok);
        assert_eq!(msg.method(), Some(SlopeMethod::Tls));
        assert_eq!(
            (msg.slope_deg, msg.slope_std_deg, msg.distance_m),
            (-12.5, 0.25, 1.75)
        );
        assert_eq!(msg.samples, 1);
        assert_eq!(msg.processing_us, 12_346);
        let (ground, inclined) = (e.ground.unwrap(), e.inclined.unwrap());
        assert_eq!(msg.ground_plane, ground.coefficients);
        assert_eq!(msg.inclined_plane, inclined.coefficients);
        assert_eq!((msg.ground_inliers, msg.inclined_inliers), (40_000, 9_000));
        assert_eq!((msg.ground_rms_m, msg.inclined_rms_m), (0.002, 0.004));
        assert_eq!((msg.ground_area_m2, msg.inclined_area_m2), (3.5, 0.8));
        assert_eq!(msg.ground_from_mount, 0);
        assert_eq!(msg.confidence, 0.75);
        let reasons: Vec<_> = msg.confidence_reason_names().collect();
        assert_eq!(reasons, ["few_points", "near_border"]);
        assert_eq!(msg.ground_seen_to_m, 4.25);
        assert_eq!(
            (msg.tracked_slope_deg, msg.tracked_std_deg),
            (-12.25, 0.125)
        );
        assert_eq!((msg.tracked_frames, msg.tracked_accepted), (7, 1));
    }

    #[test]
    fn absent_planes_and_track_are_zero_and_nan() {
        let e = Estimate {
            status: EstimateStatus::NoInclinedPlane,
            ground: None,
            inclined: None,
            ground_from_mount: true,
            ground_seen_to_m: f64::NAN,
            confidence: 0.0,
            confidence_reasons: confidence::GROUND_FROM_MOUNT,
            tracked: None,
            ..estimate()
        };
        // Start from a message full of another frame's values.
        let mut msg = SlopeEstimate::default();
        estimate().write_message(&mut msg);
        e.write_message(&mut msg);
        assert_eq!(msg.status(), EstimateStatus::NoInclinedPlane);
        assert_eq!((msg.ground_plane, msg.inclined_plane), ([0.0; 4], [0.0; 4]));
        assert_eq!((msg.ground_inliers, msg.inclined_inliers), (0, 0));
        for value in [
            msg.ground_rms_m,
            msg.inclined_rms_m,
            msg.ground_area_m2,
            msg.inclined_area_m2,
            msg.tracked_slope_deg,
            msg.tracked_std_deg,
            f64::from(msg.ground_seen_to_m),
        ] {
            assert!(value.is_nan());
        }
        assert_eq!((msg.tracked_frames, msg.tracked_accepted), (0, 0));
        assert_eq!(msg.ground_from_mount, 1);
        assert_eq!(msg.confidence, 0.0);
        assert_eq!(
            msg.confidence_reason_names().collect::<Vec<_>>(),
            ["ground_from_mount"]
        );
    }
}
