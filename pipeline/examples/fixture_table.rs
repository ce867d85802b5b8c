//! Prints the estimate of every method on the analytic fixture scenes
//! (ramps of 5..60 degrees, a 90 degree wall, uphill and downhill, with and
//! without side walls) and the per-stage timings.
//!
//! `cargo run --release -p slope-pipeline --example fixture_table`

use slope_pipeline::fixtures::{Scene, SceneCloud};
use slope_pipeline::{Estimator, EstimatorConfig, SlopeMethod};

fn main() {
    let frames: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(3);
    for method in SlopeMethod::ALL {
        let mut est = Estimator::new(EstimatorConfig {
            method,
            ..EstimatorConfig::default()
        });
        println!("method {}", method.name());
        for (name, scene) in [
            ("5", Scene::ramp(5.0)),
            ("12.5", Scene::ramp(12.5)),
            ("16", Scene::ramp(16.0)),
            ("30", Scene::ramp(30.0)),
            ("47", Scene::ramp(47.0)),
            ("60", Scene::ramp(60.0)),
            ("90 wall", Scene::ramp(90.0)),
            ("-12.5", Scene::ramp_at(-12.5, 1.2, 0.8, -30.0, 0.0)),
            ("16 walls", Scene::ramp_between_walls(16.0)),
        ] {
            let mut slopes = Vec::new();
            let mut total = 0.0;
            let mut stages: Vec<(&'static str, f64)> = Vec::new();
            let mut status = String::new();
            for seed in 0..frames {
                let cloud = SceneCloud::kinect2(&scene, seed as u64);
                let e = est.estimate(&cloud.view());
                status = format!(
                    "{:?} d={:.2}/{:.2}",
                    e.status, e.distance_m, cloud.truth_distance_m
                );
                slopes.push(e.slope_deg);
                total += e.timings.total_ms;
                for (n, ms) in &e.timings.stages {
                    match stages.iter_mut().find(|(m, _)| m == n) {
                        Some((_, t)) => *t += ms,
                        None => stages.push((n, *ms)),
                    }
                }
            }
            slopes.sort_by(f64::total_cmp);
            let median = slopes[slopes.len() / 2];
            let st: Vec<String> = stages
                .iter()
                .map(|(n, ms)| format!("{n} {:.1}", ms / frames as f64))
                .collect();
            println!(
                "  {name:>9}: median {median:8.3} err {:+.3}  {status}  total {:.1} ms [{}]",
                median - scene.truth_slope_deg,
                total / frames as f64,
                st.join(", ")
            );
        }
    }
}
