//! Prints every surface the estimator saw in frames of a recording, with
//! its role, what it stands on and its figures in the ground frame, and
//! which is the road.
//!
//! `cargo run --release -p slope-pipeline --example surfaces -- DIR [FRAME] [SEEDS]`
//! (FRAME default 0; SEEDS: how many seeds from 0, default 1; `MIRROR=1`
//! mirrors the frame left-right; `CONFIG=toml` runs with that estimator
//! config)

#[path = "../tests/common/mod.rs"]
mod common;

use slope_pipeline::{Estimate, Estimator, EstimatorConfig, FrameInfo};

fn main() {
    let mut args = std::env::args().skip(1);
    let dir = args.next().expect("recording directory");
    let k: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(0);
    let seeds: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    let rec = common::Recording::open(std::path::Path::new(&dir)).expect("recording");
    let view = if std::env::var_os("MIRROR").is_some() {
        common::View::Mirrored
    } else {
        common::View::AsRecorded
    };
    let frame = rec.frame_as(k, view).expect("frame");
    let config = match std::env::var("CONFIG") {
        Ok(text) => EstimatorConfig::from_toml_str(&text).expect("CONFIG"),
        Err(_) => EstimatorConfig::default(),
    }
    .for_sensor(rec.sensor());
    for seed in 0..seeds {
        let mut estimator = Estimator::new(EstimatorConfig {
            seed,
            ..config.clone()
        });
        let e = estimator.estimate_frame(&frame.view(), FrameInfo::default());
        print_estimate(seed, &e);
    }
}

fn print_estimate(seed: u64, e: &Estimate) {
    println!(
        "seed {seed}: {} {:.2} deg, confidence {:.2} {:?}",
        e.status.name(),
        e.slope_deg,
        e.confidence,
        slope_ipc_types::confidence::names(e.confidence_reasons).collect::<Vec<_>>()
    );
    let Some(scene) = &e.scene else {
        return;
    };
    for (k, s) in scene.surfaces.iter().enumerate() {
        let road = if scene.road.map(|r| r.surface) == Some(k) {
            " <- road"
        } else {
            ""
        };
        println!(
            "  {k:2} plane {:2}: {s} area {:5.2} noise {:4.1}{}{road}",
            s.plane_index,
            s.area_m2,
            s.noise_ratio,
            if s.measurable { " measurable" } else { "" },
        );
    }
}
