//! The real frames in `shared/data` (two Kinect v2 stair views, one Kinect
//! v1 office): riser vs tread/floor and wall vs floor are 90 degrees as
//! built; a correct estimator is within 2.5 degrees (each README). Every
//! method must hold that at the default seed, and the paper method at every
//! seed of `SEEDS` (RANSAC hypotheses and the cumulative draws change with
//! the seed). Skipped with a note when the data is absent (CI sets
//! SLOPE_REQUIRE_SHARED_DATA, which turns the skip into a failure).

mod common;

use slope_pipeline::{EstimateStatus, Estimator, EstimatorConfig, SlopeMethod};

/// Seeds the paper method is checked with.
const SEEDS: std::ops::RangeInclusive<u64> = 0..=15;

fn measure(name: &str, method: SlopeMethod, seed: u64) -> Option<f64> {
    let dir = common::shared_data(name)?;
    let rec = common::Recording::open(&dir).expect("recording");
    let frame = rec.frame(0).expect("frame 0");
    let mut est = Estimator::new(
        EstimatorConfig {
            method,
            seed,
            ..EstimatorConfig::default()
        }
        .for_sensor(rec.sensor()),
    );
    let e = est.estimate(&frame.view());
    assert_eq!(
        e.status,
        EstimateStatus::Ok,
        "{name} {} seed {seed}: {e:?}",
        method.name()
    );
    assert!(e.inclined.is_some());
    println!(
        "{name} {} seed {seed}: {:.2} deg (std {:.2}, {:.1} ms)",
        method.name(),
        e.slope_deg,
        e.slope_std_deg,
        e.timings.total_ms
    );
    Some(e.slope_deg.abs())
}

fn check(name: &str, method: SlopeMethod, seed: u64) {
    if let Some(slope) = measure(name, method, seed) {
        assert!(
            (slope - 90.0).abs() <= 2.5,
            "{name} {} seed {seed}: {slope}",
            method.name()
        );
    }
}

/// Every method at the default seed; the paper method at every seed.
fn check_all(name: &str) {
    for method in SlopeMethod::ALL {
        check(name, method, 0);
    }
    for seed in SEEDS.skip(1) {
        check(name, SlopeMethod::Paper, seed);
    }
}

#[test]
fn stairs_front_riser_vs_floor_is_90_deg() {
    check_all("kinect2-stairs-front");
}

#[test]
fn stairs_top_riser_vs_tread_is_90_deg() {
    check_all("kinect2-stairs-top");
}

#[test]
fn office_wall_vs_floor_is_90_deg() {
    check_all("kinect1-office");
}
