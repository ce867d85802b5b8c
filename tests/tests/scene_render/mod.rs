//! Renders `slope-synth` scenes (Kinect v2 sensor model) and estimates
//! every frame in-process as `slope-estimator` does: the scene is written
//! as a recording, read back with the recording reader and estimated
//! frame by frame. Shared by the scene tests.

#![allow(dead_code)]

use std::path::Path;

use slope_ipc_types::CloudPoint;
use slope_pipeline::{Estimate, Estimator, EstimatorConfig, FrameInfo};
use slope_sensor::recording::Recording;
use slope_synth::{parse_scene, write_recording};

/// Frames rendered of each scene.
pub const FRAMES: u64 = 4;

/// Renders `toml` (a slope-synth scene) and estimates every frame.
pub fn estimates(name: &str, toml: &str) -> Vec<Estimate> {
    estimates_with(name, toml, EstimatorConfig::default())
}

/// [`estimates`] with the estimator configured by `config`.
pub fn estimates_with(name: &str, toml: &str, config: EstimatorConfig) -> Vec<Estimate> {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join(name);
    let file = parse_scene(toml, Path::new(name)).unwrap_or_else(|e| panic!("{e}"));
    let model = file.sensor.unwrap_or_default();
    write_recording(&file.scene, &model, FRAMES, 5, &out).unwrap_or_else(|e| panic!("{e}"));
    let rec = Recording::open(&out).unwrap_or_else(|e| panic!("{e}"));
    let projector = rec.projector();
    let mut points = vec![CloudPoint::INVALID; projector.len()];
    let mut est = Estimator::new(config);
    rec.frames()
        .iter()
        .map(|entry| {
            let depth = rec.read_depth(entry).unwrap_or_else(|e| panic!("{e}"));
            projector.project_into(&depth.data, None, &mut points);
            let view = slope_pipeline::CloudView {
                points: &points,
                width: projector.width() as usize,
                height: projector.height() as usize,
                intrinsics: projector.intrinsics(),
                mount: rec.mount(),
            };
            let e = est.estimate_frame(
                &view,
                FrameInfo {
                    index: entry.index,
                    stamp_ns: entry.timestamp_ns,
                },
            );
            println!(
                "{name} frame {}: {} {:.2} deg, confidence {:.2}, ground {:?} from mount {}",
                entry.index,
                e.status.name(),
                e.slope_deg,
                e.confidence,
                e.ground.map(|g| g.coefficients),
                e.ground_from_mount
            );
            e
        })
        .collect()
}

pub fn scene_file(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tools/synth/tests/scenes")
        .join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
