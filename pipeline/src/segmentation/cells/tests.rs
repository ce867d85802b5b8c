//! The cell-grid segmentation on rendered scenes, against the scenes'
//! own geometry.
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::cloud::{angle_between_deg, to_vec3};
use crate::fixtures::{Scene, SceneCloud, Surface};
use crate::ransac_planes::{RansacConfig, SegmentedPlane, Threshold};
use crate::segmentation::{Proposal, Segmentation, SegmentationConfig};

/// The cell-grid design's parameters.
fn cells() -> SegmentationConfig {
    SegmentationConfig {
        proposal: Proposal::Cells,
        ..SegmentationConfig::default()
    }
}

fn segment(cloud: &SceneCloud, ransac: &RansacConfig) -> Vec<SegmentedPlane> {
    let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    Segmentation::new()
        .segment(&cloud.view(), &keep, ransac, &cells(), &mut rng)
        .to_vec()
}

/// `steps` steps of `rise_m` x `run_m` from 1.5 m ahead, seen from 0.6 m
/// up, pitched 25 degrees down; surfaces: the floor, then riser, tread...
fn stairs(steps: usize, rise_m: f64, run_m: f64) -> Scene {
    const BIG: f64 = 1e6;
    let foot = 1.5;
    let mut scene = Scene::ramp_at(0.0, foot, 0.6, -25.0, 0.0);
    scene.surfaces.truncate(1);
    scene.surfaces[0].max.y = foot;
    for s in 0..steps {
        let y = foot + s as f64 * run_m;
        let z = s as f64 * rise_m;
        scene.surfaces.push(Surface {
            normal: -Vector3::y(),
            point: Vector3::new(0.0, y, z),
            min: Vector3::new(-BIG, y - 1e-9, z),
            max: Vector3::new(BIG, y + 1e-9, z + rise_m),
        });
        scene.surfaces.push(Surface {
            normal: Vector3::z(),
            point: Vector3::new(0.0, y, z + rise_m),
            min: Vector3::new(-BIG, y, z + rise_m - 1e-9),
            max: Vector3::new(BIG, y + run_m, z + rise_m + 1e-9),
        });
    }
    scene
}

#[test]
fn finds_ground_and_ramp_of_exact_geometry_and_labels_every_point() {
    let scene = Scene::ramp(16.0);
    let cloud = SceneCloud::render(&scene, 256, 212, 0.0, 2);
    let cfg = RansacConfig {
        min_plane_points: 200,
        ..RansacConfig::default()
    };
    let planes = segment(&cloud, &cfg);
    let up = scene.to_camera(&Vector3::z());
    let ramp = scene.to_camera(&scene.surfaces[1].normal);
    let find = |n: &Vector3<f64>| {
        planes
            .iter()
            .find(|p| angle_between_deg(&p.plane.normal, n) < 0.01)
    };
    let (ground, incl) = (find(&up).expect("ground"), find(&ramp).expect("ramp"));
    assert!((ground.plane.d - 0.5).abs() < 1e-4, "{}", ground.plane.d);
    let measured = cloud.points.iter().filter(|p| p.is_valid()).count();
    assert_eq!(ground.inliers.len() + incl.inliers.len(), measured);
}

#[test]
fn every_inlier_is_within_the_threshold_of_its_plane_and_in_one_plane() {
    let scene = stairs(4, 0.17, 0.28);
    let cloud = SceneCloud::kinect2(&scene, 3);
    let cfg = RansacConfig::default();
    let planes = segment(&cloud, &cfg);
    let t = Threshold::of(&cfg);
    let mut owner = vec![usize::MAX; cloud.points.len()];
    // The floor, four risers and the two treads seen from above (the
    // third is 9 cm under the camera, the fourth above it).
    assert!(planes.len() >= 7, "{} planes", planes.len());
    for (k, plane) in planes.iter().enumerate() {
        assert!(plane.inliers.is_sorted());
        assert!(plane.inliers.len() >= cfg.min_plane_points);
        // Labelled within the threshold of the plane before its final TLS
        // refit on those pixels, which moves it by a fraction of it.
        let mut within = 0;
        for &i in &plane.inliers {
            let p = to_vec3(&cloud.points[i as usize]);
            let d = plane.plane.signed_distance(&p).abs();
            assert!(d <= 1.5 * t.at(&p), "plane {k}: {d}");
            within += usize::from(d <= t.at(&p));
            assert_eq!(owner[i as usize], usize::MAX, "pixel {i} in two planes");
            owner[i as usize] = k;
        }
        assert!(within as f64 >= 0.99 * plane.inliers.len() as f64);
    }
}

#[test]
fn finds_every_stair_riser_a_few_cells_tall() {
    // 17 cm risers 1.5-2.4 m away: 25-40 px tall on a Kinect v2, three to
    // five 8 px cells.
    let scene = stairs(4, 0.17, 0.28);
    let cloud = SceneCloud::kinect2(&scene, 1);
    let planes = segment(&cloud, &RansacConfig::default());
    let riser_normal = scene.to_camera(&-Vector3::y());
    let up = scene.to_camera(&Vector3::z());
    for (s, riser) in scene.surfaces.iter().skip(1).step_by(2).enumerate() {
        // The riser's plane in the camera frame: n . p + d = 0.
        let centre = (riser.min + riser.max) / 2.0;
        let centre = Vector3::new(0.0, centre.y, centre.z);
        let c = scene.to_camera(&(centre - scene.camera_centre()));
        let found = planes.iter().find(|p| {
            angle_between_deg(&p.plane.normal, &riser_normal) < 2.0
                && p.plane.signed_distance(&c).abs() < 0.02
        });
        assert!(
            found.is_some(),
            "riser {s} not found among {} planes",
            planes.len()
        );
    }
    let floor = planes
        .iter()
        .find(|p| angle_between_deg(&p.plane.normal, &up) < 1.0 && (p.plane.d - 0.6).abs() < 0.02);
    assert!(floor.is_some(), "no floor");
}

#[test]
fn noisy_ramps_keep_their_orientation() {
    for slope in [5.0, 16.0, 47.0] {
        let scene = Scene::ramp(slope);
        let cloud = SceneCloud::kinect2(&scene, 7);
        let planes = segment(&cloud, &RansacConfig::default());
        let ramp = scene.to_camera(&scene.surfaces[1].normal);
        let up = scene.to_camera(&Vector3::z());
        for n in [up, ramp] {
            let best = planes
                .iter()
                .map(|p| angle_between_deg(&p.plane.normal, &n))
                .fold(f64::INFINITY, f64::min);
            assert!(best < 0.5, "slope {slope}: {best} deg off");
        }
    }
}

#[test]
fn empty_and_tiny_input_give_no_plane_and_no_panic() {
    for (w, h) in [(0, 0), (1, 1), (3, 2), (9, 9)] {
        let scene = Scene::ramp(16.0);
        let cloud = SceneCloud::render(&scene, w.max(1), h.max(1), 0.0, 2);
        let mut keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
        if w == 0 {
            keep.clear();
        }
        let planes = Segmentation::new()
            .segment(
                &cloud.view(),
                &keep,
                &RansacConfig::default(),
                &cells(),
                &mut ChaCha8Rng::seed_from_u64(0),
            )
            .len();
        assert_eq!(planes, 0, "{w}x{h}");
    }
}

/// Brute force over axis lengths and cell sides: every sample cell is in
/// exactly one cell, the cells are runs of at most `k` sample cells in
/// order, and the grouping is its own mirror image.
#[test]
fn cells_group_sample_cells_from_both_ends_as_their_own_mirror_image() {
    use super::grid::CellAxis;
    for n in 0..40usize {
        for k in 1..6usize {
            let mut axis = CellAxis::default();
            axis.build(n, k);
            let cells = axis.len();
            assert_eq!(axis.of_sample.len(), n);
            assert_eq!(axis.start.last().copied(), Some(n as u32));
            for c in 0..cells {
                let run = axis.samples(c);
                assert!(!run.is_empty() && run.len() <= k, "n {n} k {k} cell {c}");
                assert!(run.clone().all(|j| axis.of_sample[j] as usize == c));
            }
            for j in 0..n {
                let mirrored = axis.of_sample[n - 1 - j] as usize;
                assert_eq!(
                    mirrored,
                    cells - 1 - axis.of_sample[j] as usize,
                    "n {n} k {k}"
                );
            }
            if n % (2 * k) == 0 {
                assert!((0..n).all(|j| axis.of_sample[j] as usize == j / k));
            }
        }
    }
}

/// The cells summed in bands on 2 and 3 threads have the sums, planes and
/// verdicts of the one-thread load, bit for bit; and every kept,
/// measured pixel on the summed rows and columns is counted once.
#[test]
fn banded_cell_sums_are_the_one_thread_sums_bit_for_bit() {
    use super::grid::{CellGrid, CellLayout};
    use crate::cloud::is_measured;
    use crate::ransac_planes::SampleAxis;
    let mut cloud = SceneCloud::render(&stairs(4, 0.17, 0.28), 512, 424, 0.004, 5);
    for p in cloud.points.iter_mut().step_by(29) {
        p.z_m = f32::NAN;
    }
    let keep: Vec<bool> = (0..cloud.points.len()).map(|i| i % 13 != 0).collect();
    let (mut columns, mut rows) = (SampleAxis::default(), SampleAxis::default());
    columns.build(512, 4);
    rows.build(424, 4);
    let layout = CellLayout {
        columns: &columns,
        rows: &rows,
        stride: 4,
        k: 2,
        step: 2,
        rms_ratio: 0.5,
    };
    let t = Threshold::of(&RansacConfig::default());
    let load = |pool: Option<&rayon::ThreadPool>| {
        let mut grid = CellGrid::default();
        grid.load(&cloud.view(), &keep, layout, t, pool);
        let sums: Vec<Vec<u64>> = grid
            .sums
            .iter()
            .map(|s| s.iter().map(|x| x.to_bits()).collect())
            .collect();
        let planar: Vec<_> = grid
            .planar
            .iter()
            .map(|p| p.map(|p| (p.normal.map(f64::to_bits), p.d.to_bits())))
            .collect();
        let badness: Vec<u64> = grid.badness.iter().map(|b| b.to_bits()).collect();
        (sums, planar, badness)
    };
    let one = load(None);
    let w = 512usize;
    let on_grid = |u: usize| u.min(w - 1 - u).is_multiple_of(2);
    let summed = (0..cloud.points.len())
        .filter(|&i| (i / w).is_multiple_of(2) && on_grid(i % w))
        .filter(|&i| keep[i] && is_measured(&cloud.points[i]))
        .count();
    let counted: f64 = one.0.iter().map(|s| f64::from_bits(s[0])).sum();
    assert_eq!(counted, summed as f64);
    assert!(one.1.iter().filter(|p| p.is_some()).count() > 100);
    for threads in [2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        assert!(load(Some(&pool)) == one, "{threads} threads");
    }
}
