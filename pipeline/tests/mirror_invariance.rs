//! Metamorphic test: a frame and its left-right mirror image (rows reversed,
//! `cx -> W - 1 - cx`, roll negated) show the same planes, so the slope must
//! not change. Every real frame in `shared/data` and a set of simulated
//! scenes, each as given and mirrored: the paper method at every seed
//! 0-63 within 1.5 degrees of the truth, and the medians over the seeds of
//! the frame and its mirror image within 0.3 degrees of each other; the
//! baselines at the default seed within 1.5 degrees.

mod common;

use common::{mirror_cloud, Frame, Recording, View};
use slope_pipeline::fixtures::{Scene, SceneCloud};
use slope_pipeline::{EstimateStatus, Estimator, EstimatorConfig, SlopeMethod};

/// Seeds the paper method is checked with.
const SEEDS: std::ops::Range<u64> = 0..64;
/// Every estimate within this of the truth, degrees.
const MAX_ERROR_DEG: f64 = 1.5;
/// Medians of a frame and its mirror image within this, degrees.
const MAX_MIRROR_GAP_DEG: f64 = 0.3;

fn slope(frame: &Frame, method: SlopeMethod, seed: u64) -> Result<f64, String> {
    let mut est = Estimator::new(
        EstimatorConfig {
            method,
            seed,
            ..EstimatorConfig::default()
        }
        .for_sensor(&frame.sensor),
    );
    let e = est.estimate(&frame.view());
    if e.status == EstimateStatus::Ok {
        Ok(e.slope_deg.abs())
    } else {
        Err(format!("status {:?}", e.status))
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Checks one frame as given and mirrored; returns the failures.
fn check(name: &str, frames: [Frame; 2], truth_deg: f64) -> Vec<String> {
    let mut failures = Vec::new();
    let mut medians = [0.0; 2];
    for (frame, view) in frames.iter().zip(View::BOTH) {
        let mut slopes = Vec::new();
        for seed in SEEDS {
            match slope(frame, SlopeMethod::Paper, seed) {
                Ok(s) => {
                    if (s - truth_deg).abs() > MAX_ERROR_DEG {
                        failures.push(format!("{name} {} seed {seed}: {s:.2}", view.name()));
                    }
                    slopes.push(s);
                }
                Err(e) => failures.push(format!("{name} {} seed {seed}: {e}", view.name())),
            }
        }
        let (lo, hi) = slopes
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &s| {
                (a.min(s), b.max(s))
            });
        medians[view as usize] = if slopes.is_empty() {
            f64::NAN
        } else {
            median(slopes)
        };
        println!(
            "{name} {}: paper median {:.2}, range {lo:.2}-{hi:.2} over {} seeds (truth {truth_deg})",
            view.name(),
            medians[view as usize],
            SEEDS.end
        );
        for method in [SlopeMethod::LeastSquares, SlopeMethod::Tls] {
            match slope(frame, method, 0) {
                Ok(s) if (s - truth_deg).abs() <= MAX_ERROR_DEG => {}
                Ok(s) => failures.push(format!("{name} {} {}: {s:.2}", view.name(), method.name())),
                Err(e) => failures.push(format!("{name} {} {}: {e}", view.name(), method.name())),
            }
        }
    }
    let gap = (medians[0] - medians[1]).abs();
    if gap.is_nan() || gap > MAX_MIRROR_GAP_DEG {
        failures.push(format!(
            "{name}: medians {:.2} vs {:.2} mirrored",
            medians[0], medians[1]
        ));
    }
    failures
}

fn assert_none(failures: Vec<String>) {
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn check_shared(name: &str) {
    let Some(dir) = common::shared_data(name) else {
        return;
    };
    let rec = Recording::open(&dir).expect("recording");
    let truth = rec.truth_slope_deg.expect("[truth] slope_deg");
    let frames = View::BOTH.map(|v| rec.frame_as(0, v).expect("frame 0"));
    assert_none(check(name, frames, truth));
}

fn simulated(scene: &Scene, seed: u64) -> [Frame; 2] {
    let cloud = SceneCloud::kinect2(scene, seed);
    let (points, intrinsics, mount) =
        mirror_cloud(&cloud.points, cloud.width, cloud.intrinsics, cloud.mount);
    let given = Frame {
        points: cloud.points.clone(),
        width: cloud.width,
        height: cloud.height,
        intrinsics: cloud.intrinsics,
        mount: cloud.mount,
        sensor: "synthetic".into(),
    };
    let mirrored = Frame {
        points,
        intrinsics,
        mount,
        ..given.clone()
    };
    [given, mirrored]
}

#[test]
fn stairs_front_mirrored() {
    check_shared("kinect2-stairs-front");
}

#[test]
fn stairs_top_mirrored() {
    check_shared("kinect2-stairs-top");
}

#[test]
fn office_mirrored() {
    check_shared("kinect1-office");
}

#[test]
fn simulated_scenes_mirrored() {
    let scenes = [
        (
            "ramp 5 deg, roll 4",
            Scene::ramp_at(5.0, 2.0, 0.5, -20.0, 4.0),
        ),
        (
            "ramp 16 deg, roll -3",
            Scene::ramp_at(16.0, 1.5, 0.6, -25.0, -3.0),
        ),
        ("ramp 47 deg", Scene::ramp(47.0)),
        ("wall, roll 5", Scene::ramp_at(90.0, 2.5, 0.4, -15.0, 5.0)),
        (
            "ramp 12.5 deg between walls",
            Scene::ramp_between_walls(12.5),
        ),
        (
            "downhill 10 deg, roll 2",
            Scene::ramp_at(-10.0, 1.5, 0.5, -30.0, 2.0),
        ),
    ];
    let mut failures = Vec::new();
    for (k, (name, scene)) in scenes.iter().enumerate() {
        failures.extend(check(
            name,
            simulated(scene, k as u64),
            scene.truth_slope_deg.abs(),
        ));
    }
    assert_none(failures);
}
