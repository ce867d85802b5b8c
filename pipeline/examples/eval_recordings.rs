//! Runs the estimator over recordings and prints, per recording and method,
//! the median slope, its error against `[truth]`, the smallest and largest
//! slope, the median of the frames' slope spreads (`slope_std_deg`) and the
//! mean stage timings; the statuses of the frames that are not `ok`.
//!
//! `cargo run --release -p slope-pipeline --example eval_recordings -- DIR...`
//! (`METHODS=paper,tls`, `CONFIG='<toml>'`, `REPEAT=n` runs each frame n
//! times and reports the median timings, `SURFACES=1` prints every
//! frame's surfaces and their roles, `MIRRORED=1` mirrors every frame
//! left-right as `tests/mirror_invariance.rs` does)

#[path = "../tests/common/mod.rs"]
mod common;

use std::path::Path;

use slope_pipeline::{Estimate, Estimator, EstimatorConfig, SlopeMethod};

fn main() {
    let dirs: Vec<String> = std::env::args().skip(1).collect();
    let repeat = repeat_from_env();
    for method in methods_from_env() {
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
            let run = run_recording(&mut est, &rec, repeat);
            print_row(method, dir, rec.truth_slope_deg, &run);
        }
    }
}

/// `METHODS=paper,tls`: the methods to run (unknown names skipped); all
/// of them without the variable.
fn methods_from_env() -> Vec<SlopeMethod> {
    match std::env::var("METHODS") {
        Ok(m) => m
            .split(',')
            .filter_map(slope_pipeline::parse_method)
            .collect(),
        Err(_) => SlopeMethod::ALL.to_vec(),
    }
}

/// `REPEAT=n`: how many times each frame runs (at least once).
fn repeat_from_env() -> usize {
    std::env::var("REPEAT")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(1)
        .max(1)
}

/// What one method did over one recording.
#[derive(Default)]
struct RecordingRun {
    /// The finite slopes, in frame order (sorted by [`print_row`]).
    slopes: Vec<f64>,
    /// The spread of each finite slope.
    stds: Vec<f64>,
    /// Per stage, in first-seen order, the sum over frames of its median ms.
    stages: Vec<(&'static str, f64)>,
    /// The sum over frames of the median total ms.
    total_ms: f64,
    /// Each frame's status name.
    statuses: Vec<&'static str>,
    frames: usize,
}

/// Runs `est` over every frame of `rec`, each frame `repeat` times.
fn run_recording(est: &mut Estimator, rec: &common::Recording, repeat: usize) -> RecordingRun {
    let mut run = RecordingRun {
        frames: rec.len(),
        ..RecordingRun::default()
    };
    for k in 0..run.frames {
        let view = if std::env::var_os("MIRRORED").is_some() {
            common::View::Mirrored
        } else {
            common::View::AsRecorded
        };
        let frame = rec.frame_as(k, view).expect("frame");
        // REPEAT=n: run each frame n times (warm buffers) and take
        // each timing's median; the estimate is the same every time.
        let runs: Vec<_> = (0..repeat).map(|_| est.estimate(&frame.view())).collect();
        let e = &runs[0];
        if std::env::var_os("SURFACES").is_some() {
            for s in e.scene.iter().flat_map(|scene| &scene.surfaces) {
                println!("frame {k}: {s}");
            }
        }
        run.statuses.push(e.status.name());
        if e.slope_deg.is_finite() {
            run.slopes.push(e.slope_deg);
            run.stds.push(e.slope_std_deg);
        }
        add_median_timings(&mut run, &runs);
    }
    run
}

/// The median over `runs` of `pick`.
fn median_ms(runs: &[Estimate], pick: &dyn Fn(&Estimate) -> f64) -> f64 {
    let mut v: Vec<f64> = runs.iter().map(pick).collect();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Adds one frame's median total and per-stage timings over its `runs`.
fn add_median_timings(run: &mut RecordingRun, runs: &[Estimate]) {
    run.total_ms += median_ms(runs, &|r| r.timings.total_ms);
    for (name, _) in &runs[0].timings.stages {
        let ms = median_ms(runs, &|r| {
            r.timings
                .stages
                .iter()
                .find(|(m, _)| m == name)
                .map_or(0.0, |(_, t)| *t)
        });
        match run.stages.iter_mut().find(|(m, _)| m == name) {
            Some((_, t)) => *t += ms,
            None => run.stages.push((name, ms)),
        }
    }
}

/// Prints one line: median slope, its error against `truth`, the ok count,
/// the slope range, the median spread and the mean timings.
fn print_row(method: SlopeMethod, dir: &str, truth: Option<f64>, run: &RecordingRun) {
    let mut slopes = run.slopes.clone();
    slopes.sort_by(f64::total_cmp);
    let median = slopes.get(slopes.len() / 2).copied().unwrap_or(f64::NAN);
    let mut stds = run.stds.clone();
    stds.sort_by(f64::total_cmp);
    let median_std = stds.get(stds.len() / 2).copied().unwrap_or(f64::NAN);
    let truth = truth.unwrap_or(f64::NAN);
    let ok = run.statuses.iter().filter(|s| **s == "ok").count();
    let n = run.frames;
    let st: Vec<String> = run
        .stages
        .iter()
        .map(|(s, ms)| format!("{s} {:.2}", ms / n as f64))
        .collect();
    let mut failed: Vec<&str> = run
        .statuses
        .iter()
        .copied()
        .filter(|s| *s != "ok")
        .collect();
    failed.dedup();
    if !failed.is_empty() {
        println!("{} {dir}: not ok: {}", method.name(), failed.join(", "));
    }
    println!(
        "{:<14} {:<40} median {:8.3} |err| {:6.3} ok {ok}/{n} min {:.2} max {:.2} median std {:.2}  {:.1} ms [{}]",
        method.name(),
        dir,
        median,
        (median.abs() - truth).abs(),
        slopes.first().copied().unwrap_or(f64::NAN),
        slopes.last().copied().unwrap_or(f64::NAN),
        median_std,
        run.total_ms / n as f64,
        st.join(", ")
    );
}
