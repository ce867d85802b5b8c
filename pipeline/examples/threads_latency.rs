//! The latency of a frame on one thread against `THREADS` (default 2),
//! interleaved: each round runs every frame on both estimators, one after
//! the other, the order swapped every round, so that a machine whose speed
//! drifts slows both alike. Prints, per recording, the median over rounds
//! and frames of each latency and of their ratio (paper method, default
//! configuration for the recording's sensor, or `CONFIG='<toml>'`), and
//! checks that both give the same slope, bit for bit.
//!
//! `cargo run --release -p slope-pipeline --example threads_latency -- DIR...`
//! (`ROUNDS=n`, default 21; `THREADS=n`; `STAGES=1` adds each stage's
//! median lap)

#[path = "../tests/common/mod.rs"]
mod common;

use std::path::Path;
use std::time::Instant;

use slope_pipeline::{Estimator, EstimatorConfig};

fn env_or(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
        .max(1)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let rounds = env_or("ROUNDS", 21);
    let threads = env_or("THREADS", 2);
    let base = match std::env::var("CONFIG") {
        Ok(text) => EstimatorConfig::from_toml_str(&text).expect("CONFIG"),
        Err(_) => EstimatorConfig::default(),
    };
    println!(
        "{:<44} {:>9} {:>9} {:>7}",
        "recording",
        "1 thr ms",
        format!("{threads} thr ms"),
        "ratio"
    );
    for dir in std::env::args().skip(1) {
        let rec = match common::Recording::open(Path::new(&dir)) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("{e}");
                continue;
            }
        };
        let config = |threads| {
            EstimatorConfig {
                threads,
                ..base.clone()
            }
            .for_sensor(rec.sensor())
        };
        let mut estimators = [Estimator::new(config(1)), Estimator::new(config(threads))];
        let frames: Vec<_> = (0..rec.len())
            .map(|k| rec.frame(k).expect("frame"))
            .collect();
        let (mut one, mut many, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
        let mut stage_lists: [std::collections::BTreeMap<&str, Vec<f64>>; 2] = Default::default();
        for round in 0..rounds {
            for frame in &frames {
                let view = frame.view();
                let mut ms = [0.0; 2];
                let mut slopes = [0.0f64; 2];
                for k in [round % 2, 1 - round % 2] {
                    let t = Instant::now();
                    let e = estimators[k].estimate(&view);
                    ms[k] = t.elapsed().as_secs_f64() * 1e3;
                    slopes[k] = e.slope_deg;
                    if round > 0 {
                        for &(name, stage_ms) in &e.timings.stages {
                            stage_lists[k].entry(name).or_default().push(stage_ms);
                        }
                    }
                }
                assert_eq!(
                    slopes[0].to_bits(),
                    slopes[1].to_bits(),
                    "{dir}: slopes differ"
                );
                // The first round warms the buffers.
                if round > 0 {
                    one.push(ms[0]);
                    many.push(ms[1]);
                    ratio.push(ms[1] / ms[0]);
                }
            }
        }
        if one.is_empty() {
            eprintln!("{dir}: ROUNDS must be at least 2");
            continue;
        }
        println!(
            "{dir:<44} {:>9.2} {:>9.2} {:>7.2}",
            median(&mut one),
            median(&mut many),
            median(&mut ratio)
        );
        if std::env::var_os("STAGES").is_some() {
            for (k, lists) in stage_lists.iter_mut().enumerate() {
                let line: Vec<String> = lists
                    .iter_mut()
                    .map(|(name, v)| format!("{name} {:.2}", median(v)))
                    .collect();
                println!("  {} thread(s): {}", [1, threads][k], line.join(", "));
            }
        }
    }
}
