//! `Estimator::inspection`: what the pictures and exports are drawn from.
//! On a simulated 16° ramp the roles name the planes the estimate was
//! measured on, the sampled normals lie on those planes and are mostly
//! kept, and a frame that fails early leaves no stale roles behind.

use slope_pipeline::fixtures::{Scene, SceneCloud};
use slope_pipeline::{CloudView, Estimator, EstimatorConfig, FrameInfo};

fn frame(index: u64) -> FrameInfo {
    FrameInfo { index, stamp_ns: 0 }
}

#[test]
fn the_inspection_shows_the_planes_and_normals_the_estimate_used() {
    let cloud = SceneCloud::kinect2(&Scene::ramp(16.0), 3);
    let mut estimator = Estimator::new(EstimatorConfig::default());
    estimator.set_inspect(true);
    let estimate = estimator.estimate_frame(&cloud.view(), frame(0));
    assert!(
        (estimate.slope_deg - 16.0).abs() < 0.5,
        "{}",
        estimate.slope_deg
    );
    let seen = estimator.inspection();
    let inclined = seen.inclined.expect("an inclined plane");
    assert!(!seen.ground.is_empty());
    assert!(!seen.ground.contains(&inclined));
    // The roles' inlier counts are the estimate's.
    let planes = seen.planes;
    let ground_inliers: usize = seen.ground.iter().map(|&k| planes[k].inliers.len()).sum();
    assert_eq!(
        Some(ground_inliers as u32),
        estimate.ground.map(|g| g.inliers)
    );
    assert_eq!(
        Some(planes[inclined].inliers.len() as u32),
        estimate.inclined.map(|p| p.inliers)
    );
    // Every sampled normal sits on a pixel of its plane; most are kept,
    // and the kept ones of the inclined plane point along its normal.
    let on = |k: usize, pixel: u32| planes[k].inliers.binary_search(&pixel).is_ok();
    let n = planes[inclined].plane.normal;
    let (mut kept, mut total) = (0, 0);
    for s in seen.normals {
        total += 1;
        kept += usize::from(s.kept);
        if s.inclined {
            assert!(on(inclined, s.pixel), "{s:?}");
            if s.kept {
                let cos = f64::from(s.normal[0]) * n.x
                    + f64::from(s.normal[1]) * n.y
                    + f64::from(s.normal[2]) * n.z;
                assert!(cos.abs() > 0.95, "{s:?}");
            }
        } else {
            assert!(seen.ground.iter().any(|&k| on(k, s.pixel)), "{s:?}");
        }
    }
    assert!(total > 5_000, "{total}");
    // k-means keeps the normals within about half a degree of a clean
    // plane's normal and the tail beyond when its cluster merges (2.5
    // spreads): 74-85 % of them here.
    assert!(kept * 10 > total * 7, "{kept} of {total} kept");

    // A malformed frame: no roles, no normals left from the last frame.
    let bad = CloudView {
        points: &cloud.points[..10],
        ..cloud.view()
    };
    estimator.estimate_frame(&bad, frame(1));
    let seen = estimator.inspection();
    assert!(seen.ground.is_empty() && seen.inclined.is_none() && seen.normals.is_empty());

    // Without set_inspect the normals are not kept.
    let mut plain = Estimator::new(EstimatorConfig::default());
    plain.estimate_frame(&cloud.view(), frame(0));
    assert!(plain.inspection().normals.is_empty());
    assert!(plain.inspection().inclined.is_some());
}
