//! Segmentation on rendered scenes.
use super::sample::central_difference_normal;
use super::*;
use crate::cloud::angle_between_deg;
use crate::cloud::to_vec3;
use crate::fixtures::{Scene, SceneCloud};
use rand::SeedableRng;

/// The planes of `cloud`'s valid points.
fn segment_cloud(cloud: &SceneCloud, cfg: &RansacConfig, seed: u64) -> Vec<SegmentedPlane> {
    let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
    PlaneSegmenter::new()
        .segment(
            &cloud.view(),
            &keep,
            cfg,
            &mut ChaCha8Rng::seed_from_u64(seed),
        )
        .to_vec()
}

fn segment(scene: &Scene, sigma: f64) -> (SceneCloud, Vec<SegmentedPlane>) {
    let cloud = SceneCloud::render(scene, 256, 212, sigma, 2);
    let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
    let mut seg = PlaneSegmenter::new();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let cfg = RansacConfig {
        min_plane_points: 200,
        ..RansacConfig::default()
    };
    let planes = seg.segment(&cloud.view(), &keep, &cfg, &mut rng).to_vec();
    (cloud, planes)
}

#[test]
fn finds_ground_and_ramp_of_exact_geometry() {
    let scene = Scene::ramp(16.0);
    let (cloud, planes) = segment(&scene, 0.0);
    assert!(planes.len() >= 2, "{}", planes.len());
    let up = scene.to_camera(&Vector3::z());
    let ramp = scene.to_camera(&scene.surfaces[1].normal);
    let ground = planes
        .iter()
        .find(|p| angle_between_deg(&p.plane.normal, &up) < 0.01);
    let incl = planes
        .iter()
        .find(|p| angle_between_deg(&p.plane.normal, &ramp) < 0.01);
    let (ground, incl) = (ground.expect("ground"), incl.expect("ramp"));
    // Ground: n.p + d = 0 with d = camera height.
    assert!((ground.plane.d - 0.5).abs() < 1e-4, "{}", ground.plane.d);
    // Every measured point belongs to exactly one of the two.
    let measured = cloud.points.iter().filter(|p| p.is_valid()).count();
    assert_eq!(ground.inliers.len() + incl.inliers.len(), measured);
    for &i in &ground.inliers {
        let p = to_vec3(&cloud.points[i as usize]);
        assert!(
            ground.plane.signed_distance(&p).abs() <= incl.plane.signed_distance(&p).abs() + 1e-9
        );
    }
}

#[test]
fn noisy_planes_keep_their_orientation() {
    let scene = Scene::ramp_between_walls(12.5);
    let (_, planes) = segment(&scene, 0.0015);
    let ramp = scene.to_camera(&scene.surfaces[1].normal);
    let up = scene.to_camera(&Vector3::z());
    assert!(planes
        .iter()
        .any(|p| angle_between_deg(&p.plane.normal, &ramp) < 0.3));
    assert!(planes
        .iter()
        .any(|p| angle_between_deg(&p.plane.normal, &up) < 0.3));
    for wall in [&scene.surfaces[2], &scene.surfaces[3]] {
        let n = scene.to_camera(&wall.normal);
        assert!(
            planes
                .iter()
                .any(|p| angle_between_deg(&p.plane.normal, &n) < 1.0),
            "wall {n:?} not found"
        );
    }
    for p in &planes {
        assert!(p.plane.d >= 0.0, "normal must face the camera");
    }
}

#[test]
fn a_plane_is_one_connected_region() {
    // A wall 2 m ahead split by a 12-pixel gap without readings into a
    // wide left piece and a narrow right piece: the same plane equation,
    // but two regions; the first plane is the wide piece alone, the
    // second the narrow one, and no pixel is in both.
    let scene = Scene::wall_facing(2.0);
    let mut cloud = SceneCloud::render(&scene, 256, 212, 0.001, 3);
    let (w, gap) = (cloud.width, 160..172);
    for (i, p) in cloud.points.iter_mut().enumerate() {
        if gap.contains(&(i % w)) {
            *p = slope_ipc_types::CloudPoint::INVALID;
        }
    }
    let cfg = RansacConfig {
        min_plane_points: 200,
        ..RansacConfig::default()
    };
    let planes = segment_cloud(&cloud, &cfg, 1);
    assert_eq!(planes.len(), 2, "{planes:?}");
    let left = |p: &SegmentedPlane| p.inliers.iter().all(|&i| (i as usize % w) < gap.start);
    let right = |p: &SegmentedPlane| p.inliers.iter().all(|&i| (i as usize % w) >= gap.end);
    assert!(left(&planes[0]) && right(&planes[1]));
    let measured = cloud.points.iter().filter(|p| p.is_valid()).count();
    assert_eq!(planes[0].inliers.len() + planes[1].inliers.len(), measured);
    for p in &planes {
        assert!(angle_between_deg(&p.plane.normal, &Vector3::new(0.0, 0.0, -1.0)) < 0.5);
        assert!(p.rms_m < 0.01, "{}", p.rms_m);
    }
}

#[test]
fn tiny_images_and_oversized_strides_give_no_plane_and_no_panic() {
    let scene = Scene::ramp(16.0);
    for (w, h) in [(1, 1), (2, 2), (3, 1), (1, 7)] {
        let cloud = SceneCloud::render(&scene, w, h, 0.0, 1);
        let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
        for stride in [1, 2, 4, 5, 1000, usize::MAX] {
            let cfg = RansacConfig {
                sample_stride_px: stride,
                min_plane_points: 3,
                ..RansacConfig::default()
            };
            let mut seg = PlaneSegmenter::new();
            let planes = seg.segment(
                &cloud.view(),
                &keep,
                &cfg,
                &mut ChaCha8Rng::seed_from_u64(0),
            );
            // At most 4 measured pixels: too few for the normal gate's
            // 6-pixel neighbourhoods, so no hypothesis and no plane.
            assert!(planes.is_empty(), "{w}x{h} stride {stride}: {planes:?}");
        }
    }
    // A full frame with a stride larger than the image.
    let cloud = SceneCloud::render(&scene, 128, 106, 0.0, 1);
    let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
    let cfg = RansacConfig {
        sample_stride_px: 848,
        ..RansacConfig::default()
    };
    assert!(PlaneSegmenter::new()
        .segment(
            &cloud.view(),
            &keep,
            &cfg,
            &mut ChaCha8Rng::seed_from_u64(0)
        )
        .is_empty());
}

/// Each plane's pixel box is its inliers' bounding box, and every inlier
/// has a reading at a depth other than 0 (the promise the pass-through and
/// the normals take the box on): finite points at depth 0 on the largest
/// plane, kept by the caller, are no inliers.
#[test]
fn each_planes_pixel_box_bounds_its_inliers_and_every_inlier_is_a_reading() {
    let scene = Scene::ramp(16.0);
    let mut cloud = SceneCloud::kinect2(&scene, 4);
    let w = cloud.width;
    let keep = vec![true; cloud.points.len()];
    let cfg = RansacConfig::default();
    let segment = |cloud: &SceneCloud| {
        PlaneSegmenter::new()
            .segment(
                &cloud.view(),
                &keep,
                &cfg,
                &mut ChaCha8Rng::seed_from_u64(3),
            )
            .to_vec()
    };
    // Every 97th pixel of the largest plane moved onto it at depth 0.
    let largest = segment(&cloud).swap_remove(0);
    let (n, d) = (largest.plane.normal, largest.plane.d);
    let zero_depth: Vec<u32> = largest.inliers.iter().step_by(97).copied().collect();
    for &i in &zero_depth {
        let p = &mut cloud.points[i as usize];
        p.z_m = 0.0;
        p.y_m = (-(d + n.x * f64::from(p.x_m)) / n.y) as f32;
        assert!(largest.plane.signed_distance(&to_vec3(p)).abs() < 1e-6);
    }
    assert!(zero_depth.len() > 300, "{}", zero_depth.len());
    let planes = segment(&cloud);
    assert!(planes.len() >= 2, "{}", planes.len());
    let mut labelled = 0;
    for plane in &planes {
        assert!(plane.inliers.windows(2).all(|p| p[0] < p[1]));
        let mut b = crate::cloud::PixelBox::EMPTY;
        for &i in &plane.inliers {
            let (i, p) = (i as usize, &cloud.points[i as usize]);
            assert!(
                crate::cloud::is_measured(p) && p.z_m != 0.0,
                "pixel {i}: {p:?}"
            );
            b.add_run(i / w, i % w, i % w);
        }
        assert_eq!(plane.pixel_box, Some(b));
        labelled += plane.inliers.len();
    }
    // Most pixels are labelled.
    assert!(labelled * 10 > cloud.points.len() * 8, "{labelled}");
}

#[test]
fn junction_pixels_go_to_the_nearer_plane_on_a_shallow_ramp() {
    // A 5 degree ramp: the 30 degree normal gate cannot tell the ground
    // from the ramp, so the plane found first reaches into the other
    // along their junction; after segmentation no pixel may be nearer
    // (and within the threshold) to another plane than to its own,
    // beyond what the final refit moves.
    let scene = Scene::ramp(5.0);
    let cloud = SceneCloud::kinect2(&scene, 2);
    let cfg = RansacConfig::default();
    let planes = segment_cloud(&cloud, &cfg, 1);
    assert!(planes.len() >= 2, "{}", planes.len());
    let t = Threshold::of(&cfg);
    // Per plane: pixels nearer (and within the threshold of) another
    // plane than their own.
    let misplaced: Vec<usize> = planes
        .iter()
        .enumerate()
        .map(|(k, plane)| {
            plane
                .inliers
                .iter()
                .filter(|&&i| {
                    let p = to_vec3(&cloud.points[i as usize]);
                    let own = plane.plane.signed_distance(&p).abs();
                    planes.iter().enumerate().any(|(j, o)| {
                        let d = o.plane.signed_distance(&p).abs();
                        j != k && d < own && d <= t.at(&p)
                    })
                })
                .count()
        })
        .collect();
    // What is left comes from the refit after labelling and falls on
    // both sides alike; the first plane keeping its neighbour's strip
    // is one-sided (before the cell relaxation: [3494, 0] here).
    let (a, b) = (misplaced[0], misplaced[1]);
    assert!(
        a.max(b) <= 4 * a.min(b) + 100,
        "one-sided: {misplaced:?} of {:?}",
        planes.iter().map(|p| p.inliers.len()).collect::<Vec<_>>()
    );
    let total: usize = planes.iter().map(|p| p.inliers.len()).sum();
    assert!(a + b < total / 50, "{misplaced:?} of {total}");
}

#[test]
fn central_difference_normals_are_exact_on_planes_and_refuse_edges() {
    // A 16 degree ramp without noise: every sample point with its four
    // neighbours on one plane gets that plane's normal, facing the
    // camera; at the image border and across the ground/ramp crease
    // the difference is refused or still on a plane.
    let scene = Scene::ramp(16.0);
    let cloud = SceneCloud::render_with_intrinsics(&scene, 128, 106, 90.0, 0.0, 1);
    let view = cloud.view();
    let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
    let normals = [
        scene.to_camera(&Vector3::z()),
        scene.to_camera(&scene.surfaces[1].normal),
    ];
    let mut exact = 0;
    for v in 0..cloud.height {
        for u in 0..cloud.width {
            let Some(n) = central_difference_normal(&view, &keep, u, v, 2) else {
                continue;
            };
            assert!(u >= 2 && v >= 2 && u + 2 < cloud.width && v + 2 < cloud.height);
            let p = to_vec3(&cloud.points[v * cloud.width + u]);
            assert!(n.dot(&p) < 0.0, "faces the camera");
            if normals.iter().any(|m| angle_between_deg(&n, m) < 0.05) {
                exact += 1;
            }
        }
    }
    // All but the 2-pixel image border and the rows along the crease
    // (f32 coordinates: exact to a few thousandths of a degree).
    let measured = keep.iter().filter(|&&k| k).count();
    assert!(exact * 100 > measured * 85, "{exact} of {measured}");
    // A point whose neighbour is a metre behind it (a depth edge).
    let mut edged = cloud.points.clone();
    let (u, v) = (64, 80);
    edged[v * cloud.width + u + 2].z_m += 1.0;
    let edged_view = CloudView {
        points: &edged,
        ..cloud.view()
    };
    assert!(central_difference_normal(&edged_view, &keep, u, v, 2).is_none());
}

#[test]
fn empty_input_gives_no_plane() {
    let scene = Scene::ramp(5.0);
    let cloud = SceneCloud::render(&scene, 32, 24, 0.0, 1);
    let keep = vec![false; cloud.points.len()];
    let mut seg = PlaneSegmenter::new();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    assert!(seg
        .segment(&cloud.view(), &keep, &RansacConfig::default(), &mut rng)
        .is_empty());
    assert!(seg
        .segment(&cloud.view(), &[], &RansacConfig::default(), &mut rng)
        .is_empty());
}

/// The free points of `grid` with their cells, in order.
fn free_points(grid: &super::sample::SampleGrid) -> Vec<(u32, Vector3<f64>)> {
    (0..grid.points.len())
        .map(|j| (grid.points.tag[j], grid.points.point(j)))
        .collect()
}

/// Removes the free points flagged in `gone` (by their cells with
/// `by_cells`) and checks that exactly the others remain, in order, with
/// their cells renumbered.
fn remove_and_check(grid: &mut super::sample::SampleGrid, gone: &[bool], by_cells: bool) {
    use super::sample::NO_SAMPLE;
    let before = free_points(grid);
    if by_cells {
        let cells: Vec<u32> = before
            .iter()
            .zip(gone)
            .filter(|(_, &g)| g)
            .map(|(&(cell, _), _)| cell)
            .collect();
        assert!(cells.windows(2).all(|w| w[0] < w[1]));
        grid.remove_cells(&cells);
    } else {
        grid.remove(gone);
    }
    let expected: Vec<_> = before
        .iter()
        .zip(gone)
        .filter(|(_, &g)| !g)
        .map(|(p, _)| *p)
        .collect();
    let after = free_points(grid);
    assert_eq!(after, expected);
    for (j, &(cell, _)) in after.iter().enumerate() {
        assert_eq!(grid.coarse[cell as usize], j as u32);
    }
    let free = grid.coarse.iter().filter(|&&c| c != NO_SAMPLE).count();
    assert_eq!(free, after.len());
}

/// Removing sample points, by runs (few removed) or point by point (many),
/// by flags or by cells, keeps exactly the other points in order and
/// renumbers their cells.
#[test]
fn removing_sample_points_keeps_the_others_in_order() {
    use super::sample::SampleGrid;
    let cloud = SceneCloud::render(&Scene::ramp(16.0), 128, 106, 0.0, 2);
    let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
    let config = RansacConfig::default();
    let cos_gate = Some(config.normal_threshold_deg.to_radians().cos());
    let mut grid = SampleGrid::default();
    grid.load(&cloud.view(), &keep, &config, cos_gate, None);
    let n = grid.points.len();
    assert!(n > 400, "{n}");
    // Flags point j of `len` when j % step == at.
    let every = |len: usize, step: usize, at: usize| -> Vec<bool> {
        (0..len).map(|j| j % step == at).collect()
    };
    // Nothing; a few points (long runs, moved whole); one in five from
    // point 0 on (short runs, point by point); one in seven by their cells;
    // every other point (the kept points copied).
    for (step, at, by_cells) in [
        (1, 1, false),
        (97, 1, false),
        (5, 0, false),
        (7, 3, true),
        (2, 1, false),
    ] {
        let gone = every(grid.points.len(), step, at);
        remove_and_check(&mut grid, &gone, by_cells);
    }
    // The last point only, then every point.
    let m = grid.points.len();
    assert!(m > 100, "{m}");
    remove_and_check(&mut grid, &every(m, m, m - 1), false);
    remove_and_check(&mut grid, &every(m - 1, 1, 0), false);
    assert_eq!(grid.points.len(), 0);
}

/// A pool of `threads` plain workers, for the banded passes.
fn pool_of(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

/// The sample grid loaded in bands on 2 and 3 threads (4 and 6 bands, the
/// last shorter) holds the points of the one-thread load, in the same
/// order, with the same normals, gates and cells.
#[test]
fn a_banded_sample_load_gives_the_points_of_one_thread() {
    use super::sample::SampleGrid;
    let mut cloud = SceneCloud::render(&Scene::ramp(16.0), 512, 424, 0.004, 3);
    // Holes: a band with no measured pixel, and scattered misses.
    for (i, p) in cloud.points.iter_mut().enumerate() {
        if (100 * 512..140 * 512).contains(&i) || i % 37 == 0 {
            p.z_m = f32::NAN;
        }
    }
    let keep: Vec<bool> = (0..cloud.points.len()).map(|i| i % 11 != 0).collect();
    let config = RansacConfig::default();
    let cos_gate = Some(config.normal_threshold_deg.to_radians().cos());
    let loaded = |pool: Option<&rayon::ThreadPool>| {
        let mut grid = SampleGrid::default();
        grid.load(&cloud.view(), &keep, &config, cos_gate, pool);
        let normals: Vec<_> = (0..grid.points.len())
            .map(|j| grid.points.normal(j))
            .collect();
        let cells: Vec<_> = grid
            .cell_point
            .iter()
            .map(|p| p.map(f64::to_bits))
            .collect();
        (free_points(&grid), normals, grid.coarse.clone(), cells)
    };
    let one = loaded(None);
    assert!(one.0.len() > 5000, "{}", one.0.len());
    assert!(one.1.iter().filter(|n| n.is_some()).count() > 4000);
    for threads in [2, 3] {
        let pool = pool_of(threads);
        assert!(loaded(Some(&pool)) == one, "{threads} threads");
    }
}
