//! Same seed, same bytes; another seed, other noise; clean output does not
//! depend on the seed at all.

use std::fs;
use std::ops::ControlFlow;
use std::path::Path;

use slope_sensor::recording::Recording;
use slope_synth::{write_recording, write_recording_with, Scene, SensorModel, WriteOptions};

/// Every file of a recording, relative path and bytes, sorted by path.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in fs::read_dir(&d).expect("readable dir") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let rel = path
                    .strip_prefix(dir)
                    .expect("inside")
                    .display()
                    .to_string();
                out.push((rel, fs::read(&path).expect("readable file")));
            }
        }
    }
    out.sort();
    out
}

fn render(model: &SensorModel, seed: u64) -> (tempfile::TempDir, Vec<(String, Vec<u8>)>) {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("rec");
    write_recording(&Scene::default_ramp(), model, 3, seed, &out).expect("written");
    let f = files(&out);
    (dir, f)
}

#[test]
fn same_seed_same_bytes_other_seed_other_noise() {
    let model = SensorModel::default();
    let (_a, first) = render(&model, 7);
    let (_b, again) = render(&model, 7);
    let (_c, other) = render(&model, 8);
    // recording.toml, frames.csv, 3 depth and 3 colour images.
    assert_eq!(first.len(), 8);
    assert_eq!(first, again, "same seed must give identical files");
    let depth_differs = first
        .iter()
        .zip(&other)
        .filter(|(a, b)| a.0.starts_with("depth") && a.1 != b.1)
        .count();
    assert_eq!(
        depth_differs, 3,
        "another seed must change every depth image"
    );
    // The metadata and the frame table do not depend on the seed.
    let text = |files: &[(String, Vec<u8>)], name: &str| {
        files
            .iter()
            .find(|f| f.0 == name)
            .map(|f| f.1.clone())
            .expect("present")
    };
    for name in ["recording.toml", "frames.csv"] {
        assert_eq!(text(&first, name), text(&other, name), "{name}");
    }
}

#[test]
fn clean_output_ignores_the_seed() {
    let (_a, first) = render(&SensorModel::clean(), 1);
    let (_b, other) = render(&SensorModel::clean(), 2);
    assert_eq!(first, other);
}

/// Stopped after frame 1 of 5 (what SIGINT does to `slope-synth`), the
/// recording is byte for byte the recording of exactly 2 frames: valid,
/// complete, with nothing of the frames not rendered.
#[test]
fn a_recording_stopped_early_is_the_recording_of_the_frames_written() {
    let model = SensorModel::default();
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("stopped");
    let mut seen = Vec::new();
    let summary = write_recording_with(
        &Scene::default_ramp(),
        &model,
        5,
        7,
        &out,
        WriteOptions::default(),
        |index| {
            seen.push(index);
            if index == 1 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        },
    )
    .expect("written");
    assert_eq!(seen, [0, 1]);
    assert_eq!((summary.frames, summary.frames_asked), (2, 5));
    assert!(summary.is_partial());
    assert!(summary.valid_fraction > 0.5, "{summary:?}");
    let recording = Recording::open(&out).expect("the stopped recording opens");
    assert_eq!(recording.frames().len(), 2);

    let full = dir.path().join("two");
    let complete = write_recording(&Scene::default_ramp(), &model, 2, 7, &full).expect("written");
    assert!(!complete.is_partial());
    assert_eq!(files(&out), files(&full));
}
