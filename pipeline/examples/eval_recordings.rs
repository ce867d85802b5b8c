//! Runs the estimator over recordings and prints, per recording and method,
//! the median slope, its error against `[truth]`, the smallest and largest
//! slope, the median of the frames' slope spreads (`slope_std_deg`) and the
//! mean stage timings.
//!
//! `cargo run --release -p slope-pipeline --example eval_recordings -- DIR...`
//! (`METHODS=paper,tls`, `CONFIG='<toml>'`, `REPEAT=n` runs each frame n
//! times and reports the median timings)

#[path = "../tests/common/mod.rs"]
mod common;

use std::path::Path;

use slope_pipeline::{Estimator, EstimatorConfig, SlopeMethod};

fn main() {
    let dirs: Vec<String> = std::env::args().skip(1).collect();
    let methods: Vec<SlopeMethod> = match std::env::var("METHODS") {
        Ok(m) => m
            .split(',')
            .filter_map(slope_pipeline::parse_method)
            .collect(),
        Err(_) => SlopeMethod::ALL.to_vec(),
    };
    let repeat: usize = std::env::var("REPEAT")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(1)
        .max(1);
    for method in methods {
        let base = match std::env::var("CONFIG") {
            Ok(text) => EstimatorConfig::from_toml_str(&text).expect("CONFIG"),
            Err(_) => EstimatorConfig::default(),
        };
        for dir in &dirs {
            let rec = match common::Recording::open(Path::new(dir)) {
                Ok(r) => r,
                Err(e) => {
                    eprintln!("{e}");
                    continue;
                }
            };
            let config = EstimatorConfig {
                method,
                ..base.clone()
            };
            let mut est = Estimator::new(config.for_sensor(rec.sensor()));
            let mut slopes = Vec::new();
            let mut stds = Vec::new();
            let mut stages: Vec<(&'static str, f64)> = Vec::new();
            let mut total = 0.0;
            let mut statuses = Vec::new();
            let n = rec.len();
            for k in 0..n {
                let frame = rec.frame(k).expect("frame");
                // REPEAT=n: run each frame n times (warm buffers) and take
                // each timing's median; the estimate is the same every time.
                let runs: Vec<_> = (0..repeat).map(|_| est.estimate(&frame.view())).collect();
                let e = &runs[0];
                statuses.push(e.status.name());
                if e.slope_deg.is_finite() {
                    slopes.push(e.slope_deg);
                    stds.push(e.slope_std_deg);
                }
                let median_ms = |pick: &dyn Fn(&slope_pipeline::Estimate) -> f64| {
                    let mut v: Vec<f64> = runs.iter().map(pick).collect();
                    v.sort_by(f64::total_cmp);
                    v[v.len() / 2]
                };
                total += median_ms(&|r| r.timings.total_ms);
                for (name, _) in &e.timings.stages {
                    let ms = median_ms(&|r| {
                        r.timings
                            .stages
                            .iter()
                            .find(|(m, _)| m == name)
                            .map_or(0.0, |(_, t)| *t)
                    });
                    match stages.iter_mut().find(|(m, _)| m == name) {
                        Some((_, t)) => *t += ms,
                        None => stages.push((name, ms)),
                    }
                }
            }
            slopes.sort_by(f64::total_cmp);
            let median = slopes.get(slopes.len() / 2).copied().unwrap_or(f64::NAN);
            stds.sort_by(f64::total_cmp);
            let median_std = stds.get(stds.len() / 2).copied().unwrap_or(f64::NAN);
            let truth = rec.truth_slope_deg.unwrap_or(f64::NAN);
            let ok = statuses.iter().filter(|s| **s == "ok").count();
            let st: Vec<String> = stages
                .iter()
                .map(|(s, ms)| format!("{s} {:.1}", ms / n as f64))
                .collect();
            println!(
                "{:<14} {:<40} median {:8.3} |err| {:6.3} ok {ok}/{n} min {:.2} max {:.2} median std {:.2}  {:.1} ms [{}]",
                method.name(),
                dir,
                median,
                (median.abs() - truth).abs(),
                slopes.first().copied().unwrap_or(f64::NAN),
                slopes.last().copied().unwrap_or(f64::NAN),
                median_std,
                total / n as f64,
                st.join(", ")
            );
        }
    }
}
