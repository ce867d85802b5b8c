//! Shared helpers of the integration tests: write a recording to a temporary
//! directory, read it back, reproduce each frame's exact camera and
//! geometry, and fit planes.

#![allow(dead_code)]

use std::path::Path;

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use slope_sensor::recording::{DepthImage, PngCompression, Recording};
use slope_synth::{
    frame_camera, frame_rng, raycast, write_recording_with, Camera, GeometryImage, Scene,
    SensorModel, World, WriteOptions,
};

/// Writes `frames` frames (depth only, fast compression) into `dir` and
/// opens the result.
pub fn write_and_open(
    scene: &Scene,
    model: &SensorModel,
    frames: u64,
    seed: u64,
    dir: &Path,
) -> Recording {
    let options = WriteOptions {
        color: false,
        compression: PngCompression::Fast,
    };
    write_recording_with(scene, model, frames, seed, dir, options, |_| {
        std::ops::ControlFlow::Continue(())
    })
    .expect("recording written");
    Recording::open(dir).expect("recording readable")
}

/// One frame as written, with the exact camera and geometry it was
/// rendered from (reproduced from the seed).
pub struct Frame {
    pub depth: DepthImage,
    pub camera: Camera,
    pub geometry: GeometryImage,
}

/// Reads frame `index` back and reproduces its exact geometry.
pub fn frame(rec: &Recording, scene: &Scene, model: &SensorModel, seed: u64, index: u64) -> Frame {
    let entry = &rec.frames()[usize::try_from(index).expect("small index")];
    let depth = rec.read_depth(entry).expect("depth readable");
    let mut rng = frame_rng(seed, index);
    let camera = frame_camera(scene, model, index, &mut rng);
    let geometry = raycast(&World::build(scene), &camera);
    Frame {
        depth,
        camera,
        geometry,
    }
}

/// Back-projects pixel (u, v) with depth `z_m` using the recording's own
/// intrinsics (as the estimator would).
pub fn back_project(rec: &Recording, u: u32, v: u32, z_m: f64) -> Vector3<f64> {
    let d = &rec.meta().depth;
    Vector3::new(
        (f64::from(u) - d.cx) * z_m / d.fx,
        (f64::from(v) - d.cy) * z_m / d.fy,
        z_m,
    )
}

/// A total-least-squares plane: unit normal and offset (`n . p = offset`).
#[derive(Debug, Clone, Copy)]
pub struct Plane {
    pub normal: Vector3<f64>,
    pub offset: f64,
    pub rms_m: f64,
}

/// Fits a plane to points by TLS: the normal is the eigenvector of the
/// smallest eigenvalue of the scatter matrix about the centroid.
pub fn fit_plane(points: &[Vector3<f64>]) -> Plane {
    assert!(points.len() >= 3);
    let n = points.len() as f64;
    let centroid = points.iter().sum::<Vector3<f64>>() / n;
    let mut scatter = Matrix3::zeros();
    for p in points {
        let d = p - centroid;
        scatter += d * d.transpose();
    }
    let eig = SymmetricEigen::new(scatter);
    let (k, smallest) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .expect("three eigenvalues");
    let normal = eig.eigenvectors.column(k).into_owned().normalize();
    Plane {
        normal,
        offset: normal.dot(&centroid),
        rms_m: (smallest / n).max(0.0).sqrt(),
    }
}

/// Angle between two planes' normals (unsigned), degrees.
pub fn angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    (a.dot(b).abs() / (a.norm() * b.norm()))
        .min(1.0)
        .acos()
        .to_degrees()
}

/// The world point of pixel (u, v) at depth `z_m` seen by `camera` (the
/// exact camera of its frame).
pub fn world_point(camera: &Camera, u: u32, v: u32, z_m: f64) -> Vector3<f64> {
    camera.ray(f64::from(u), f64::from(v)).at(z_m).coords
}

/// A scene file shipped in `tests/scenes/`.
pub fn scene_fixture(name: &str) -> Scene {
    let path: std::path::PathBuf = [env!("CARGO_MANIFEST_DIR"), "tests", "scenes", name]
        .iter()
        .collect();
    slope_synth::load_scene_file(&path)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .scene
}
