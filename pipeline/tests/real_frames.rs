//! The real frames in `shared/data` (two Kinect v2 stair views, one Kinect
//! v1 office): riser vs tread/floor and wall vs floor are 90 degrees as
//! built; a correct estimator is within 2.5 degrees (each README). Every
//! method must hold that at the default seed. Over seeds 0..=7 (RANSAC
//! hypotheses and the cumulative draws change with the seed) the paper
//! method's median must hold it too and every single seed must stay within
//! 3 degrees: single seeds reach 2.5-2.7 degrees on stairs-front and office
//! today (a known weakness, see the pipeline README), which this test keeps
//! from getting worse. Skipped with a note when the data is absent.

mod common;

use slope_pipeline::{EstimateStatus, Estimator, EstimatorConfig, SlopeMethod};

/// Seeds the paper method is checked with.
const SEEDS: std::ops::RangeInclusive<u64> = 0..=7;

fn measure(name: &str, method: SlopeMethod, seed: u64) -> Option<f64> {
    let dir = common::shared_data(name)?;
    let rec = common::Recording::open(&dir).expect("recording");
    let frame = rec.frame(0).expect("frame 0");
    let mut est = Estimator::new(EstimatorConfig {
        method,
        seed,
        ..EstimatorConfig::default()
    });
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

/// Largest error of the paper method at any one seed.
const SINGLE_SEED_BAR_DEG: f64 = 3.0;

/// Every method at the default seed; the paper method over all seeds.
fn check_all(name: &str) {
    for method in SlopeMethod::ALL {
        check(name, method, 0);
    }
    let mut slopes: Vec<f64> = SEEDS
        .filter_map(|seed| measure(name, SlopeMethod::Paper, seed))
        .collect();
    if slopes.is_empty() {
        return;
    }
    for slope in &slopes {
        assert!(
            (slope - 90.0).abs() <= SINGLE_SEED_BAR_DEG,
            "{name} paper: a seed gave {slope} (all: {slopes:?})"
        );
    }
    slopes.sort_by(f64::total_cmp);
    let median = (slopes[slopes.len() / 2] + slopes[(slopes.len() - 1) / 2]) / 2.0;
    assert!(
        (median - 90.0).abs() <= 2.5,
        "{name} paper: median over seeds {median} (all: {slopes:?})"
    );
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
