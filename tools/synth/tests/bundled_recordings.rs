//! The recordings bundled in tests/recordings/ are what slope-synth makes
//! with the commands in tests/recordings/make.sh: re-render some of their
//! frames in memory and compare every depth count and colour.

use std::path::PathBuf;

use slope_sensor::recording::Recording;
use slope_synth::{
    frame_camera, frame_rng, raycast, recording_meta, render_depth, shading::shade, Scene,
    SensorModel, World,
};

fn bundled(name: &str) -> Recording {
    let dir: PathBuf = [
        env!("CARGO_MANIFEST_DIR"),
        "..",
        "..",
        "tests",
        "recordings",
        name,
    ]
    .iter()
    .collect();
    Recording::open(&dir).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn check(name: &str, model: &SensorModel, seed: u64, frames: usize) {
    let rec = bundled(name);
    // `--slope 16 --distance 1.5 --mount-height-m 0.5 --mount-pitch-deg -20` is the default ramp scene.
    let scene = Scene::default_ramp();
    assert_eq!(rec.meta(), &recording_meta(&scene), "{name}: metadata");
    assert_eq!(rec.frames().len(), frames, "{name}: frame count");
    let world = World::build(&scene);
    for index in [0, frames - 1] {
        let entry = &rec.frames()[index];
        let k = index as u64;
        let mut rng = frame_rng(seed, k);
        let camera = frame_camera(&scene, model, k, &mut rng);
        let geometry = raycast(&world, &camera);
        let depth = render_depth(&geometry, &world, model, &camera, &mut rng);
        let stored = rec.read_depth(entry).expect("depth readable");
        assert!(
            depth == stored,
            "{name}: depth of frame {index} differs from a fresh render"
        );
        let color = rec
            .read_color(entry)
            .expect("colour readable")
            .expect("has colour");
        assert!(
            shade(&geometry) == color,
            "{name}: colour of frame {index} differs"
        );
    }
}

#[test]
fn ramp16_is_reproducible() {
    check("ramp16", &SensorModel::default(), 7, 30);
}

#[test]
fn ramp16_clean_is_reproducible() {
    check("ramp16-clean", &SensorModel::clean(), 7, 10);
}
