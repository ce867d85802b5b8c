//! Depths outside the sensor's range are no reading: a saturated frame
//! (every pixel the largest count, 65.535 m) was a plane, `ok` at 70
//! degrees with confidence 0.70.

use slope_pipeline::fixtures::{Scene, SceneCloud};
use slope_pipeline::sensor_noise::NoiseModel;
use slope_pipeline::{EstimateStatus, Estimator, EstimatorConfig};

/// The ramp's cloud with every reading pushed along its ray to
/// `depth_m`: what a frame of one raw count everywhere projects to.
fn saturated(depth_m: f32) -> SceneCloud {
    let mut cloud = SceneCloud::kinect2(&Scene::ramp(16.0), 1);
    for p in cloud.points.iter_mut().filter(|p| p.is_valid()) {
        let scale = depth_m / p.z_m;
        (p.x_m, p.y_m, p.z_m) = (p.x_m * scale, p.y_m * scale, depth_m);
    }
    cloud
}

#[test]
fn a_frame_beyond_the_sensors_range_has_too_few_points() {
    let config = EstimatorConfig::default().for_sensor("kinect2");
    let ramp = SceneCloud::kinect2(&Scene::ramp(16.0), 1);
    let good = Estimator::new(config.clone()).estimate(&ramp.view());
    assert_eq!(good.status, EstimateStatus::Ok);
    assert!((good.slope_deg - 16.0).abs() < 0.5, "{good:?}");

    let far = saturated(65.535);
    let e = Estimator::new(config.clone()).estimate(&far.view());
    assert_eq!(e.status, EstimateStatus::TooFewPoints, "{e:?}");

    // The range is the key's when it is set: the same frame is a plane again.
    let mut wide = config;
    wide.outlier.depth_range_m = Some([0.1, 100.0]);
    let e = Estimator::new(wide).estimate(&far.view());
    assert_ne!(e.status, EstimateStatus::TooFewPoints, "{e:?}");
}

/// Each sensor's own range: 9 m is beyond a Kinect v2 and within a Kinect v1.
#[test]
fn the_range_is_the_sensors() {
    let at_9_m = saturated(9.0);
    let run = |sensor: &str| {
        let config = EstimatorConfig::default().for_sensor(sensor);
        Estimator::new(config).estimate(&at_9_m.view()).status
    };
    assert_eq!(run("kinect2"), EstimateStatus::TooFewPoints);
    assert_ne!(run("kinect1"), EstimateStatus::TooFewPoints);
    assert_eq!(NoiseModel::Kinect2.depth_range_m(), (0.5, 8.0));
    assert_eq!(NoiseModel::Kinect1.depth_range_m(), (0.4, 10.0));
}

#[test]
fn a_range_that_is_not_near_below_far_is_refused() {
    for range in [
        [2.0, 1.0],
        [-1.0, 4.0],
        [0.5, f64::INFINITY],
        [f64::NAN, 4.0],
    ] {
        let mut config = EstimatorConfig::default();
        config.outlier.depth_range_m = Some(range);
        let err = config.validate().expect_err("refused");
        assert!(err.to_string().contains("outlier.depth_range_m"), "{err}");
    }
}
