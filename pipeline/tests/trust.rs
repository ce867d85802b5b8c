//! Trusting the estimate over frames: per-frame random draws, tracking
//! through corrupted frames on an approach, and no upward bias on small
//! angles with noisy normals (analytic scenes, `fixtures`).

use slope_pipeline::fixtures::{Scene, SceneCloud};
use slope_pipeline::{EstimateStatus, Estimator, EstimatorConfig, FrameInfo};

fn frame(index: u64) -> FrameInfo {
    FrameInfo {
        index,
        stamp_ns: index * 33_333_333,
    }
}

/// The same seed and frame give the same estimate; another frame index
/// draws other samples (a bad draw on a static scene does not repeat).
#[test]
fn random_draws_depend_on_the_seed_and_the_frame() {
    let cloud = SceneCloud::kinect2(&Scene::ramp(16.0), 3);
    let view = cloud.view();
    let run = |index: u64| {
        let mut e = Estimator::new(EstimatorConfig::default());
        e.estimate_frame(&view, frame(index))
    };
    let (a, b, c) = (run(7), run(7), run(8));
    assert_eq!(a.slope_deg.to_bits(), b.slope_deg.to_bits());
    assert_ne!(a.slope_deg.to_bits(), c.slope_deg.to_bits());
    assert!((a.slope_deg - c.slope_deg).abs() < 0.2, "{a:?} {c:?}");
    // Frame 0 of a stream is the single-frame estimate.
    let mut e = Estimator::new(EstimatorConfig::default());
    assert_eq!(
        e.estimate(&view).slope_deg.to_bits(),
        run(0).slope_deg.to_bits()
    );
}

/// A robot drives towards a 16 degree ramp (its foot from 3.0 m to 1.2 m);
/// every fourth frame is corrupted (a glitch frame showing a 35 degree
/// surface, or a frame without readings). The raw estimates jump; the
/// tracked slope stays within 0.3 degrees of the truth from the third
/// frame on.
#[test]
fn the_tracked_slope_ignores_corrupted_frames_on_an_approach() {
    let mut est = Estimator::new(EstimatorConfig::default());
    let frames = 24;
    let mut worst_raw: f64 = 0.0;
    for k in 0..frames {
        let foot = 3.0 - 1.8 * k as f64 / (frames - 1) as f64;
        let mut cloud = SceneCloud::kinect2(&Scene::ramp_at(16.0, foot, 0.5, -20.0, 0.0), k);
        match k % 8 {
            3 => {
                cloud = SceneCloud::kinect2(&Scene::ramp_at(35.0, foot, 0.5, -20.0, 0.0), k);
            }
            7 => cloud.points.iter_mut().for_each(|p| p.z_m = f32::NAN),
            _ => {}
        }
        let e = est.estimate_frame(&cloud.view(), frame(k));
        if e.status == EstimateStatus::Ok {
            worst_raw = worst_raw.max((e.slope_deg - 16.0).abs());
        }
        let tracked = e.tracked.expect("estimate_frame tracks");
        println!(
            "frame {k}: raw {:.2} ({:?}) tracked {:.2} +- {:.2} over {} frames, accepted {}",
            e.slope_deg,
            e.status,
            tracked.slope_deg,
            tracked.std_deg,
            tracked.frames,
            tracked.accepted
        );
        if k >= 2 {
            assert!(
                (tracked.slope_deg - 16.0).abs() <= 0.3,
                "frame {k}: {tracked:?}"
            );
            assert!(tracked.std_deg > 0.0 && tracked.std_deg < 0.3);
        }
        assert_eq!(tracked.accepted, k % 8 != 3 && k % 8 != 7, "frame {k}");
    }
    assert!(worst_raw > 10.0, "the corrupted frames did not corrupt");
}

/// A robot tracks a 16 degree ramp, then its stream breaks (a replay
/// starts again at frame 0, or the camera pauses for 2 s) and a 35 degree
/// ramp is ahead: the tracked slope is the new ramp's at once. Had the
/// stream continued, that frame would have been rejected as an outlier of
/// the old track.
#[test]
fn a_new_stream_does_not_inherit_the_tracked_slope() {
    let ramp =
        |truth: f64, k: u64| SceneCloud::kinect2(&Scene::ramp_at(truth, 2.0, 0.5, -20.0, 0.0), k);
    let tracking_16 = || {
        let mut est = Estimator::new(EstimatorConfig::default());
        for k in 10..13 {
            let e = est.estimate_frame(&ramp(16.0, k).view(), frame(k));
            let tracked = e.tracked.expect("estimate_frame tracks");
            assert!((tracked.slope_deg - 16.0).abs() < 0.3, "{tracked:?}");
        }
        est
    };
    let steeper = ramp(35.0, 13);
    let continued = tracking_16().estimate_frame(&steeper.view(), frame(13));
    let tracked = continued.tracked.expect("tracks");
    assert!(
        !tracked.accepted && (tracked.slope_deg - 16.0).abs() < 0.3,
        "{tracked:?}"
    );
    let paused = FrameInfo {
        stamp_ns: frame(13).stamp_ns + 2_000_000_000,
        ..frame(13)
    };
    for info in [frame(0), paused] {
        let e = tracking_16().estimate_frame(&steeper.view(), info);
        let tracked = e.tracked.expect("tracks");
        assert!((e.slope_deg - 35.0).abs() < 0.5, "{e:?}");
        assert!(
            tracked.accepted && tracked.frames == 1,
            "{info:?}: {tracked:?}"
        );
        assert_eq!(tracked.slope_deg, e.slope_deg);
    }
}

/// Noisier frames than a Kinect v2 (depth noise 6 mm at 1 m, growing with
/// z^2) of shallow ramps: the median over frames stays within 0.2 degrees of
/// the truth. (The upward bias of unsigned pair angles, which the angles
/// about the rotation axis remove, is shown on normals with a 3 degree
/// spread in `cumulative_angle.rs`.) A 3 degree ramp is beyond the Kinect
/// v2's floor bend where it lies (`sensor_noise.rs`: 2.2 degrees at 4 m)
/// and measured; a 1.5 degree one is within it and reported as
/// `no_inclined_plane`.
#[test]
fn small_angles_stay_within_0_2_deg_on_noisy_frames() {
    let mut est = Estimator::new(EstimatorConfig::default());
    for truth in [5.0, 6.0, 8.0] {
        let scene = Scene::ramp_at(truth, 1.5, 0.5, -20.0, 0.0);
        let mut slopes: Vec<f64> = (0..5)
            .map(|seed| {
                let cloud = SceneCloud::render(&scene, 512, 424, 0.006, seed);
                let e = est.estimate_frame(&cloud.view(), frame(seed));
                assert_eq!(e.status, EstimateStatus::Ok, "{truth}: {e:?}");
                e.slope_deg
            })
            .collect();
        slopes.sort_by(f64::total_cmp);
        let median = slopes[2];
        println!("{truth} deg: median {median:.3} over 5 frames");
        assert!((median - truth).abs() < 0.2, "{truth}: {median}");
    }
    let mut gentle = |truth: f64, index: u64| {
        let cloud = SceneCloud::render(
            &Scene::ramp_at(truth, 1.5, 0.5, -20.0, 0.0),
            512,
            424,
            0.006,
            0,
        );
        est.estimate_frame(&cloud.view(), frame(index))
    };
    let e = gentle(3.0, 9);
    assert_eq!(e.status, EstimateStatus::Ok, "{e:?}");
    assert!((e.slope_deg - 3.0).abs() < 0.3, "{}", e.slope_deg);
    let e = gentle(1.5, 10);
    assert_eq!(e.status, EstimateStatus::NoInclinedPlane, "{e:?}");
}
