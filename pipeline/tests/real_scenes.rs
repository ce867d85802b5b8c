//! Every real frame in `shared/data` against its README's truth, at 16
//! seeds: the ground is the floor the camera stands over, no piece of the
//! floor is a step or a ramp, and the road (or none) is what the README
//! says. (`real_frames.rs` holds the slope's accuracy on the three frames
//! whose truth is an angle.) Skipped with a note when the data is absent;
//! CI sets SLOPE_REQUIRE_SHARED_DATA, which turns the skip into a failure.

mod common;

use slope_ipc_types::SurfaceRole;
use slope_pipeline::selection::RoadScene;
use slope_pipeline::{Estimate, EstimateStatus, Estimator, EstimatorConfig};

/// Seeds every frame is checked with.
const SEEDS: std::ops::Range<u64> = 0..16;

/// The frame's estimate at each seed, or `None` when the data is absent.
fn estimates(name: &str) -> Option<Vec<Estimate>> {
    let dir = common::shared_data(name)?;
    let rec = common::Recording::open(&dir).expect("recording");
    let frame = rec.frame(0).expect("frame 0");
    let config = EstimatorConfig::default().for_sensor(rec.sensor());
    Some(
        SEEDS
            .map(|seed| {
                Estimator::new(EstimatorConfig {
                    seed,
                    ..config.clone()
                })
                .estimate(&frame.view())
            })
            .collect(),
    )
}

fn scene(e: &Estimate) -> &RoadScene {
    e.scene.as_ref().expect("a scene (the ground was found)")
}

/// The ground is a seen plane (not the mount's) at every seed; with
/// `camera_height_m`, the camera is that high above it (the README's
/// figure, within `tolerance_m`).
fn assert_ground_is_the_floor(name: &str, all: &[Estimate], camera_height_m: Option<(f64, f64)>) {
    for (seed, e) in all.iter().enumerate() {
        let s = scene(e);
        let ground = &s.surfaces[0];
        assert_eq!(ground.role, SurfaceRole::Ground, "{name} seed {seed}");
        assert!(s.heights_known, "{name} seed {seed}");
        if let Some((height, tolerance)) = camera_height_m {
            let above = s.frame.ground.d.abs();
            assert!(
                (above - height).abs() <= tolerance,
                "{name} seed {seed}: camera {above:.2} m above the ground, README {height}"
            );
        }
    }
}

/// No surface of the frame is a ramp, and no step lies on the floor (a
/// step whose lowest inlier is within the join tolerance of the ground is
/// a piece of the floor): the frames of a level floor without ramps.
fn assert_no_floor_piece_is_structure(name: &str, all: &[Estimate]) {
    let tolerance = EstimatorConfig::default().road.join_tolerance_m;
    for (seed, e) in all.iter().enumerate() {
        for s in &scene(e).surfaces {
            assert_ne!(s.role, SurfaceRole::Ramp, "{name} seed {seed}: {s}");
            assert!(
                !(s.role == SurfaceRole::Step && s.lowest_m < tolerance),
                "{name} seed {seed}: a piece of the floor is a step: {s}"
            );
        }
    }
}

/// No road at any seed: the frame's corridor holds no ramp and no wall.
fn assert_no_road(name: &str, all: &[Estimate]) {
    for (seed, e) in all.iter().enumerate() {
        assert_eq!(
            e.status,
            EstimateStatus::NoInclinedPlane,
            "{name} seed {seed}: {:?}",
            scene(e).road_surface()
        );
    }
}

/// The same road at every seed: a wall, its slope within 0.5 degrees of
/// the seeds' median and within `max_error_deg` of 90.
fn assert_same_wall_at_every_seed(name: &str, all: &[Estimate], max_error_deg: f64) {
    let mut slopes: Vec<f64> = all.iter().map(|e| e.slope_deg.abs()).collect();
    slopes.sort_by(f64::total_cmp);
    let median = slopes[slopes.len() / 2];
    for (seed, e) in all.iter().enumerate() {
        assert_eq!(e.status, EstimateStatus::Ok, "{name} seed {seed}");
        let road = scene(e).road_surface().expect("a road");
        assert_eq!(road.role, SurfaceRole::Wall, "{name} seed {seed}");
        let slope = e.slope_deg.abs();
        assert!(
            (slope - median).abs() <= 0.5,
            "{name} seed {seed}: {slope:.2} against the seeds' median {median:.2}"
        );
        assert!(
            (slope - 90.0).abs() <= max_error_deg,
            "{name} seed {seed}: {slope:.2}"
        );
    }
}

/// A tiled tunnel, camera about 1.35 m up: the walkway is the ground (no
/// mount), the curved walls beside the path are no road.
#[test]
fn cape_tunnel_walkway_is_the_ground_and_there_is_no_road() {
    let Some(all) = estimates("cape-foot-tunnel") else {
        return;
    };
    assert_ground_is_the_floor("cape-foot-tunnel", &all, Some((1.35, 0.1)));
    assert_no_floor_piece_is_structure("cape-foot-tunnel", &all);
    assert_no_road("cape-foot-tunnel", &all);
}

/// A mine tunnel, a Kinect v2 0.82 m above a level floor: one ground, no
/// road.
#[test]
fn mine_tunnel_floor_is_one_ground_and_there_is_no_road() {
    let Some(all) = estimates("kv2-mine-tunnel-0") else {
        return;
    };
    assert_ground_is_the_floor("kv2-mine-tunnel-0", &all, Some((0.82, 0.05)));
    assert_no_floor_piece_is_structure("kv2-mine-tunnel-0", &all);
    assert_no_road("kv2-mine-tunnel-0", &all);
}

/// A corridor with five people: the floor is the ground, the strip of floor
/// between a person's legs is no ramp, people are no road.
#[test]
fn corridor_people_are_no_road_and_the_floor_is_whole() {
    let Some(all) = estimates("pcl-corridor-people") else {
        return;
    };
    assert_ground_is_the_floor("pcl-corridor-people", &all, None);
    assert_no_floor_piece_is_structure("pcl-corridor-people", &all);
    assert_no_road("pcl-corridor-people", &all);
}

/// A basement whose Kinect v1 bends the floor by up to 4 degrees: one
/// ground, no step and no ramp on it; the road is a wall at every seed,
/// within 3 degrees of 90 (the README's walls stand at 86.6-89.0 degrees to
/// the floor; the wall ahead, cut into pieces differently by each draw, is
/// measured on all of its pieces).
#[test]
fn basement_floor_is_one_ground_and_the_road_is_the_wall() {
    let Some(all) = estimates("nyu-basement") else {
        return;
    };
    assert_ground_is_the_floor("nyu-basement", &all, None);
    assert_no_floor_piece_is_structure("nyu-basement", &all);
    for (seed, e) in all.iter().enumerate() {
        assert_eq!(e.status, EstimateStatus::Ok, "nyu-basement seed {seed}");
        let road = scene(e).road_surface().expect("a road");
        assert_eq!(road.role, SurfaceRole::Wall, "nyu-basement seed {seed}");
        assert!(
            (e.slope_deg.abs() - 90.0).abs() <= 3.0,
            "nyu-basement seed {seed}: {:.2}",
            e.slope_deg
        );
    }
}

/// An office seen from 1.76 m: the floor is the ground, the desk top is
/// furniture (elevated), the board behind the desk is never stood on
/// through the desk (its foot is hidden by furniture), never a ramp.
#[test]
fn office_desk_floor_is_the_ground_and_the_desk_is_furniture() {
    let Some(all) = estimates("tum-office-desk") else {
        return;
    };
    assert_ground_is_the_floor("tum-office-desk", &all, Some((1.76, 0.1)));
    assert_no_floor_piece_is_structure("tum-office-desk", &all);
    for (seed, e) in all.iter().enumerate() {
        let s = scene(e);
        // The desk top: the largest level surface 0.6-0.9 m up.
        let desk = s
            .surfaces
            .iter()
            .filter(|d| d.tilt_deg() < 5.0 && d.lowest_m > 0.6 && d.highest_m < 0.9)
            .max_by_key(|d| d.inliers)
            .expect("the desk top");
        assert_eq!(desk.role, SurfaceRole::Elevated, "seed {seed}: {desk}");
        if let Some(road) = s.road_surface() {
            assert_eq!(road.role, SurfaceRole::Wall, "seed {seed}");
            assert_ne!(
                road.support,
                slope_ipc_types::SurfaceSupport::Hidden,
                "seed {seed}: the desk hides the board's foot: {road}"
            );
        }
    }
}

/// The three frames whose truth is an angle: the same wall at every seed,
/// within 2.5 degrees of 90 (their READMEs).
#[test]
fn angle_frames_keep_one_road_at_every_seed() {
    for name in [
        "kinect2-stairs-front",
        "kinect2-stairs-top",
        "kinect1-office",
    ] {
        let Some(all) = estimates(name) else {
            return;
        };
        assert_ground_is_the_floor(name, &all, None);
        assert_same_wall_at_every_seed(name, &all, 2.5);
    }
}

/// The office's Kinect v1 floor is one ground with no ramp on it.
#[test]
fn kinect1_office_floor_has_no_ramp() {
    let Some(all) = estimates("kinect1-office") else {
        return;
    };
    assert_no_floor_piece_is_structure("kinect1-office", &all);
}
