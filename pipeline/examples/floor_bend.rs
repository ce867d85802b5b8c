//! Measures how a depth sensor bends a flat floor: the floor of a frame cut
//! into bands of depth, a plane fitted to each band, and each band's angle
//! to (and height off) the plane of the nearest band. The figures behind
//! each sensor's range bias (`pipeline/src/sensor_noise.rs`).
//!
//! `cargo run --release -p slope-pipeline --example floor_bend -- DIR [FRAME]`
//!
//! 1. The floor: the plane with the most points of the image's bottom half
//!    within 3 cm, among 2,000 seeded draws of three such points whose
//!    normal is within 60 degrees of the camera's up (-y); then refitted
//!    (least squares) on the points within 3 cm of it, twice.
//! 2. Floor points: within `BAND_M` of that plane (wide enough to hold a
//!    floor bent by a few degrees over a few metres).
//! 3. Bands of 0.5 m of depth from the nearest floor point: a least-squares
//!    plane per band with at least 300 points (refitted on the points within
//!    3 cm of its first fit, so that a wall's foot does not tilt it).
//! 4. Each band against the nearest band's plane: the angle between the
//!    two planes' normals and the height of the band's centroid above the
//!    near plane.

#[path = "../tests/common/mod.rs"]
mod common;

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slope_pipeline::cloud::angle_between_deg;
use slope_pipeline::plane_fit::{Moments, Plane};

const BAND_M: f64 = 0.15;
const BIN_M: f64 = 0.5;
const MIN_BIN_POINTS: usize = 300;
/// The reference floor: the nearest this many metres of depth.
const NEAR_M: f64 = 1.0;

fn main() {
    let mut args = std::env::args().skip(1);
    let dir = args.next().expect("recording directory");
    let k: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(0);
    let rec = common::Recording::open(std::path::Path::new(&dir)).expect("recording");
    let frame = rec.frame(k).expect("frame");
    let points: Vec<Vector3<f64>> = frame
        .points
        .iter()
        .map(|p| Vector3::new(p.x_m as f64, p.y_m as f64, p.z_m as f64))
        .collect();
    let bottom = &points[points.len() / 2..];
    let bottom: Vec<Vector3<f64>> = bottom.iter().copied().filter(|p| p.z > 0.0).collect();
    let Some(floor) = ransac_floor(&bottom) else {
        println!("{dir}: no floor found");
        return;
    };
    let floor_points: Vec<Vector3<f64>> = points
        .iter()
        .copied()
        .filter(|p| p.z > 0.0 && floor.signed_distance(p).abs() <= BAND_M)
        .collect();
    let z_min = floor_points
        .iter()
        .map(|p| p.z)
        .fold(f64::INFINITY, f64::min);
    let near_points: Vec<Vector3<f64>> = floor_points
        .iter()
        .copied()
        .filter(|p| p.z < z_min + NEAR_M && floor.signed_distance(p).abs() <= 0.03)
        .collect();
    let (Some(near_plane), Some(near_centre)) = (fit(&near_points), centroid(&near_points)) else {
        println!("{dir}: no near floor");
        return;
    };
    println!(
        "{dir} ({}): camera {:.2} m above the floor; reference: the floor at {:.1}-{:.1} m",
        rec.sensor(),
        near_plane.d.abs(),
        z_min,
        z_min + NEAR_M
    );
    for b in 0..20 {
        let lo = z_min + b as f64 * BIN_M;
        let mut heights: Vec<f64> = Vec::new();
        let mut sum = Vector3::zeros();
        for p in floor_points
            .iter()
            .filter(|p| p.z >= lo && p.z < lo + BIN_M)
        {
            heights.push(near_plane.signed_distance(p));
            sum += p;
        }
        if heights.len() < MIN_BIN_POINTS {
            continue;
        }
        heights.sort_by(f64::total_cmp);
        let median = heights[heights.len() / 2];
        let centre = sum / heights.len() as f64;
        let along = centre - near_centre;
        let run = (along - near_plane.normal * near_plane.normal.dot(&along)).norm();
        println!(
            "  z {:4.1}-{:4.1} m  {:6} points  height {:+6.3} m  {:4.2} m from the reference: bend {:5.2} deg",
            lo,
            lo + BIN_M,
            heights.len(),
            median,
            run,
            median.atan2(run).to_degrees().abs(),
        );
    }
}

/// A seeded RANSAC for the floor among `points` (see the module doc).
fn ransac_floor(points: &[Vector3<f64>]) -> Option<Plane> {
    if points.len() < 3 {
        return None;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let up = -Vector3::y();
    let mut best: Option<(usize, Plane)> = None;
    for _ in 0..2000 {
        let [a, b, c] = [(); 3].map(|_| points[rng.random_range(0..points.len())]);
        let Some(plane) = Plane::from_three_points(&a, &b, &c) else {
            continue;
        };
        if angle_between_deg(&plane.normal, &up).min(angle_between_deg(&-plane.normal, &up)) > 60.0
        {
            continue;
        }
        let count = points
            .iter()
            .filter(|p| plane.signed_distance(p).abs() <= 0.03)
            .count();
        if best.is_none_or(|(n, _)| count > n) {
            best = Some((count, plane));
        }
    }
    let mut plane = best?.1;
    for _ in 0..2 {
        let near: Vec<_> = points
            .iter()
            .copied()
            .filter(|p| plane.signed_distance(p).abs() <= 0.03)
            .collect();
        plane = fit(&near)?;
    }
    Some(plane.oriented_towards(&Vector3::zeros()))
}

/// The least-squares plane of `points`, its normal towards the camera.
fn fit(points: &[Vector3<f64>]) -> Option<Plane> {
    let mut m = Moments::new();
    for p in points {
        m.add(p);
    }
    let mean = m.mean()?;
    let cov = m.covariance()?;
    let eigen = cov.symmetric_eigen();
    let k = eigen.eigenvalues.imin();
    let normal = eigen.eigenvectors.column(k).into_owned();
    Some(Plane::from_point_normal(&mean, &normal)?.oriented_towards(&Vector3::zeros()))
}

fn centroid(points: &[Vector3<f64>]) -> Option<Vector3<f64>> {
    (!points.is_empty()).then(|| points.iter().sum::<Vector3<f64>>() / points.len() as f64)
}
