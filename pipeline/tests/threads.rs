//! `threads`: the estimate of a frame is the same, bit for bit, on one
//! thread and on several (the two planes' stages 3-5 run at once, each on
//! its own buffers); on the real frames (skipped with a note when absent),
//! the bundled ramp16 recording and simulated ramps, every method, a few
//! seeds, and over a stream of frames (tracking).

mod common;

use std::path::Path;

use slope_pipeline::fixtures::{Scene, SceneCloud};
use slope_pipeline::{CloudView, Estimate, Estimator, EstimatorConfig, FrameInfo, SlopeMethod};

/// The fields of an estimate that must not depend on the thread count
/// (all but the timings).
fn answer(e: &Estimate) -> String {
    let mut e = e.clone();
    e.timings = Default::default();
    format!("{e:?}")
}

fn check(name: &str, view: &CloudView<'_>, sensor: &str) {
    for method in SlopeMethod::ALL {
        for seed in 0..3 {
            let config = |threads| {
                EstimatorConfig {
                    method,
                    seed,
                    threads,
                    ..EstimatorConfig::default()
                }
                .for_sensor(sensor)
            };
            let mut one = Estimator::new(config(1));
            let mut two = Estimator::new(config(2));
            for k in 0..2 {
                let frame = FrameInfo {
                    index: k,
                    stamp_ns: k * 33_333_333,
                };
                let (a, b) = (
                    one.estimate_frame(view, frame),
                    two.estimate_frame(view, frame),
                );
                assert_eq!(
                    a.slope_deg.to_bits(),
                    b.slope_deg.to_bits(),
                    "{name} {method:?} seed {seed}"
                );
                assert_eq!(answer(&a), answer(&b), "{name} {method:?} seed {seed}");
            }
        }
    }
}

#[test]
fn two_threads_give_the_same_estimate_bit_for_bit() {
    for name in [
        "kinect2-stairs-front",
        "kinect2-stairs-top",
        "kinect1-office",
    ] {
        if let Some(dir) = common::shared_data(name) {
            let rec = common::Recording::open(&dir).expect("recording");
            let frame = rec.frame(0).expect("frame 0");
            check(name, &frame.view(), rec.sensor());
        }
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/recordings/ramp16");
    let rec = common::Recording::open(&dir).expect("ramp16");
    let frame = rec.frame(0).expect("frame 0");
    check("ramp16", &frame.view(), rec.sensor());
    for slope in [5.0, 47.0] {
        let cloud = SceneCloud::kinect2(&Scene::ramp(slope), 3);
        check(&format!("ramp {slope}"), &cloud.view(), "synthetic");
    }
}

#[test]
fn threads_out_of_range_are_refused_by_key() {
    for bad in [0, 65] {
        let text = format!("threads = {bad}\n");
        let err = EstimatorConfig::from_toml_str(&text).expect_err("refused");
        assert!(format!("{err:#}").contains("threads"), "{err:#}");
    }
    let ok = EstimatorConfig::from_toml_str("threads = 2\n").expect("2 threads");
    assert_eq!(ok.threads, 2);
}
