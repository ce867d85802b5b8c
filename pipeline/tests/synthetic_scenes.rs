//! End-to-end accuracy and robustness of the estimator on analytic scenes
//! (ground + ramp planes ray-cast through Kinect v2 intrinsics with the
//! Kinect v2 depth noise model and millimetre depth, `fixtures`).

use slope_ipc_types::{CloudPoint, Intrinsics, Mount, SlopeEstimate};
use slope_pipeline::fixtures::{Scene, SceneCloud};
use slope_pipeline::{CloudView, EstimateStatus, Estimator, EstimatorConfig, SlopeMethod};

fn estimator(method: SlopeMethod) -> Estimator {
    Estimator::new(EstimatorConfig {
        method,
        ..EstimatorConfig::default()
    })
}

/// Median slope over three noisy frames of `scene`, and the last estimate.
fn median_slope(est: &mut Estimator, scene: &Scene) -> (f64, slope_pipeline::Estimate) {
    let mut slopes = Vec::new();
    let mut last = None;
    for seed in 0..3 {
        let cloud = SceneCloud::kinect2(scene, seed);
        let e = est.estimate(&cloud.view());
        assert_eq!(e.status, EstimateStatus::Ok, "{e:?}");
        slopes.push(e.slope_deg);
        last = Some(e);
    }
    slopes.sort_by(f64::total_cmp);
    (slopes[1], last.expect("three frames"))
}

#[test]
fn every_method_measures_the_paper_slopes_within_0_3_deg() {
    for method in SlopeMethod::ALL {
        let mut est = estimator(method);
        for truth in [5.0, 12.5, 16.0, 30.0, 47.0, 60.0, 90.0] {
            let scene = Scene::ramp(truth);
            let (median, e) = median_slope(&mut est, &scene);
            assert!(
                (median - truth).abs() <= 0.3,
                "{}: {truth} deg ramp measured {median}",
                method.name()
            );
            // The distance to the inclined plane along the optical axis.
            assert!(
                (e.distance_m - scene.truth_distance_m).abs() < 0.05,
                "{}: distance {} vs {}",
                method.name(),
                e.distance_m,
                scene.truth_distance_m
            );
            assert!(!e.ground_from_mount);
            assert!(e.ground.is_some() && e.inclined.is_some());
            // The paper method's spread is that of its angle samples; a
            // baseline's single fit has none (never a spread of 0).
            if method == SlopeMethod::Paper {
                assert!(e.slope_std_deg > 0.0 && e.samples == 1000, "{e:?}");
            } else {
                assert!(e.slope_std_deg.is_nan() && e.samples == 1, "{e:?}");
            }
        }
    }
}

#[test]
fn a_ramp_between_side_walls_is_measured_as_the_ramp() {
    let mut est = estimator(SlopeMethod::Paper);
    let (median, _) = median_slope(&mut est, &Scene::ramp_between_walls(16.0));
    assert!((median - 16.0).abs() <= 0.3, "{median}");
}

#[test]
fn downhill_is_negative_and_uphill_positive() {
    let mut est = estimator(SlopeMethod::Paper);
    let down = Scene::ramp_at(-12.5, 1.2, 0.8, -30.0, 0.0);
    let (median, _) = median_slope(&mut est, &down);
    assert!((median + 12.5).abs() <= 0.3, "{median}");
    let up = Scene::ramp_at(12.5, 1.2, 0.8, -30.0, 4.0);
    let (median, _) = median_slope(&mut est, &up);
    assert!((median - 12.5).abs() <= 0.3, "{median}");
}

#[test]
fn without_a_mount_the_ground_is_found_from_geometry() {
    let mut est = estimator(SlopeMethod::Paper);
    let mut cloud = SceneCloud::kinect2(&Scene::ramp(16.0), 1);
    cloud.mount = Mount::UNKNOWN;
    let e = est.estimate(&cloud.view());
    assert_eq!(e.status, EstimateStatus::Ok);
    assert!((e.slope_deg - 16.0).abs() <= 0.5, "{}", e.slope_deg);
    assert!(!e.ground_from_mount);
}

#[test]
fn without_a_ground_plane_the_mount_is_the_reference() {
    // A level camera facing a wall: no ground in view.
    let mut est = estimator(SlopeMethod::Paper);
    let cloud = SceneCloud::kinect2(&Scene::wall_facing(2.0), 1);
    let e = est.estimate(&cloud.view());
    assert_eq!(e.status, EstimateStatus::Ok, "{e:?}");
    assert!(e.ground_from_mount);
    assert!(e.ground.is_none());
    assert!((e.slope_deg - 90.0).abs() <= 0.3, "{}", e.slope_deg);
    assert!((e.distance_m - 2.0).abs() < 0.02, "{}", e.distance_m);
    // And without a mount there is nothing to measure against.
    let mut unmounted = cloud.clone();
    unmounted.mount = Mount::UNKNOWN;
    assert_eq!(
        est.estimate(&unmounted.view()).status,
        EstimateStatus::NoGround
    );
}

#[test]
fn the_same_frame_and_config_give_the_same_answer() {
    let cloud = SceneCloud::kinect2(&Scene::ramp(30.0), 4);
    let mut a = estimator(SlopeMethod::Paper);
    let mut b = estimator(SlopeMethod::Paper);
    let first = a.estimate(&cloud.view());
    // A different frame in between must not change the next answer.
    a.estimate(&SceneCloud::kinect2(&Scene::ramp(5.0), 9).view());
    let again = a.estimate(&cloud.view());
    let fresh = b.estimate(&cloud.view());
    for e in [&again, &fresh] {
        assert_eq!(e.slope_deg.to_bits(), first.slope_deg.to_bits());
        assert_eq!(e.slope_std_deg.to_bits(), first.slope_std_deg.to_bits());
        assert_eq!(e.inclined, first.inclined);
    }
}

#[test]
fn malformed_and_empty_frames_never_panic() {
    let mut est = estimator(SlopeMethod::Paper);
    let intrinsics = Intrinsics {
        fx: 365.0,
        fy: 365.0,
        cx: 255.5,
        cy: 211.5,
    };
    let points = vec![CloudPoint::INVALID; 100];
    let view = |points: &'static [CloudPoint], w, h| CloudView {
        points,
        width: w,
        height: h,
        intrinsics,
        mount: Mount::UNKNOWN,
    };
    let leaked: &'static [CloudPoint] = Box::leak(points.into_boxed_slice());
    assert_eq!(
        est.estimate(&view(leaked, 10, 11)).status,
        EstimateStatus::BadFrame
    );
    assert_eq!(
        est.estimate(&view(leaked, 0, 0)).status,
        EstimateStatus::BadFrame
    );
    assert_eq!(
        est.estimate(&view(&[], 0, 5)).status,
        EstimateStatus::BadFrame
    );
    assert_eq!(
        est.estimate(&view(leaked, 10, 10)).status,
        EstimateStatus::TooFewPoints
    );
    // Garbage: infinities, NaN in one coordinate only, huge and zero values,
    // zero intrinsics.
    let mut cloud = SceneCloud::kinect2(&Scene::ramp(16.0), 2);
    for (i, p) in cloud.points.iter_mut().enumerate() {
        match i % 97 {
            0 => p.x_m = f32::NAN,
            1 => p.z_m = f32::INFINITY,
            2 => {
                *p = CloudPoint {
                    x_m: 1e30,
                    y_m: -1e30,
                    z_m: 1e30,
                    rgb: 0,
                }
            }
            3 => {
                *p = CloudPoint {
                    x_m: 0.0,
                    y_m: 0.0,
                    z_m: 0.0,
                    rgb: 0,
                }
            }
            _ => {}
        }
    }
    for method in SlopeMethod::ALL {
        let mut est = estimator(method);
        let e = est.estimate(&cloud.view());
        assert_eq!(e.status, EstimateStatus::Ok, "{}: {e:?}", method.name());
        assert!((e.slope_deg - 16.0).abs() < 1.0, "{}", e.slope_deg);
        // Zero intrinsics only size the neighbourhoods (the focal length
        // falls back to 1 px, `CloudView::focal_px`): the points are the
        // same, so the same ramp is found, within the same degree.
        let mut broken = cloud.view();
        broken.intrinsics = Intrinsics::default();
        let e = est.estimate(&broken);
        assert_eq!(e.status, EstimateStatus::Ok, "{}: {e:?}", method.name());
        assert!(
            (e.slope_deg - 16.0).abs() < 1.0,
            "{}: {}",
            method.name(),
            e.slope_deg
        );
    }
}

#[test]
fn the_message_carries_the_estimate() {
    let mut est = estimator(SlopeMethod::Paper);
    let cloud = SceneCloud::kinect2(&Scene::ramp(16.0), 1);
    let e = est.estimate(&cloud.view());
    let mut msg = SlopeEstimate::default();
    e.write_message(&mut msg);
    assert_eq!(msg.status(), EstimateStatus::Ok);
    assert_eq!(msg.method(), Some(SlopeMethod::Paper));
    assert_eq!(msg.slope_deg, e.slope_deg);
    assert_eq!(msg.samples, e.samples);
    assert_eq!(msg.samples, 1000);
    assert_eq!(msg.ground_plane, e.ground.expect("ground").coefficients);
    assert_eq!(msg.inclined_inliers, e.inclined.expect("inclined").inliers);
    assert_eq!(msg.ground_from_mount, 0);
    assert!(msg.processing_us > 0);
    // Stage timings are in pipeline order and add up to at most the total.
    let names: Vec<&str> = e.timings.stages.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names,
        [
            "outlier",
            "ransac",
            "selection",
            "surfaces",
            "pass_through",
            "normals",
            "kmeans",
            "cumulative",
            "confidence"
        ]
    );
    let sum: f64 = e.timings.stages.iter().map(|(_, ms)| ms).sum();
    assert!(sum <= e.timings.total_ms + 1e-6);
    // Normals face the camera: d > 0.
    assert!(msg.ground_plane[3] > 0.0 && msg.inclined_plane[3] > 0.0);
}
