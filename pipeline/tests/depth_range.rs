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

    // The range is the key's when it is set: the same frame is a plane again,
    // its points kept: the plane z = 65.535 m of the camera. Pitched 20
    // degrees down, the camera sees it more than 48 m ahead even in its
    // lowest row (65.5 m along the axis, 37.8 m below it at the image's
    // edge, 30 degrees off the axis): beyond the 8 m corridor, so no road.
    let mut wide = config;
    wide.outlier.depth_range_m = Some([0.1, 100.0]);
    let mut estimator = Estimator::new(wide);
    let e = estimator.estimate(&far.view());
    assert_eq!(e.status, EstimateStatus::NoInclinedPlane, "{e:?}");
    let measured = far.points.iter().filter(|p| p.is_valid()).count();
    let planes = estimator.inspection().planes;
    let plane = planes
        .iter()
        .max_by_key(|p| p.inliers.len())
        .expect("the kept points form a plane");
    assert!(
        plane.plane.normal.z.abs() > 1.0 - 1e-9 && (plane.plane.d.abs() - 65.535).abs() < 1e-3,
        "{:?}",
        plane.plane
    );
    assert!(
        plane.inliers.len() * 100 >= measured * 99,
        "{} of {measured} points in the plane",
        plane.inliers.len()
    );
}

/// Each sensor's own range: 9 m is beyond a Kinect v2 and within a Kinect v1.
#[test]
fn the_range_is_the_sensors() {
    let at_9_m = saturated(9.0);
    let run = |sensor: &str| {
        let config = EstimatorConfig::default().for_sensor(sensor);
        Estimator::new(config).estimate(&at_9_m.view())
    };
    assert_eq!(run("kinect2").status, EstimateStatus::TooFewPoints);
    // Within a Kinect v1's range the frame is the plane z = 9 m of the
    // camera, which is pitched 20 degrees down: a wall leaning back,
    // 90 - 20 = 70 degrees steep, facing the camera.
    let k1 = run("kinect1");
    assert_eq!(k1.status, EstimateStatus::Ok, "{k1:?}");
    assert!((k1.slope_deg - 70.0).abs() < 0.5, "{k1:?}");
    let inclined = k1.inclined.expect("the plane");
    let [a, b, c, d] = inclined.coefficients;
    assert!(
        a.abs() < 1e-6
            && b.abs() < 1e-6
            && (c.abs() - 1.0).abs() < 1e-9
            && (d.abs() - 9.0).abs() < 1e-3,
        "{inclined:?}"
    );
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
