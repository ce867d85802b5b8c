//! The road ahead on analytic scenes (`fixtures`: bounded planes ray-cast
//! through Kinect v2 intrinsics with its depth noise): every surface gets
//! its role, and the estimate measures the ramp or wall the robot would
//! drive onto, not the nearest plane facing it. Each scene is one a
//! nearest-plane rule gets wrong (the wall beside the path, the board
//! above the floor, the sloped table top, the ramp off to the side), or a
//! chain the roles must follow (a staircase, a ramp on a curb, a ramp
//! whose foot a box hides).

use nalgebra::Vector3;
use slope_ipc_types::{SurfaceRole, SurfaceSupport};
use slope_pipeline::fixtures::{Scene, SceneCloud, Surface as Plane};
use slope_pipeline::selection::{RoadScene, Surface};
use slope_pipeline::{Estimate, EstimateStatus, Estimator, EstimatorConfig};

const BIG: f64 = 1e6;

/// A bounded plane: unit `normal` (pointing up or towards the camera),
/// through `point`, clipped to the box `min..max` (world: x right, y
/// forward, z up).
fn plane(normal: [f64; 3], point: [f64; 3], min: [f64; 3], max: [f64; 3]) -> Plane {
    Plane {
        normal: Vector3::from(normal).normalize(),
        point: Vector3::from(point),
        min: Vector3::from(min),
        max: Vector3::from(max),
    }
}

/// The floor, up to `to_m` ahead.
fn floor(to_m: f64) -> Plane {
    plane(
        [0.0, 0.0, 1.0],
        [0.0; 3],
        [-BIG, -BIG, -BIG],
        [BIG, to_m, BIG],
    )
}

/// A ramp of `slope_deg` rising straight ahead from `foot_m`, its foot
/// `base_m` above the floor, `half_width_m` either side of the centre line.
fn ramp(slope_deg: f64, foot_m: f64, base_m: f64, half_width_m: f64) -> Plane {
    let t = slope_deg.to_radians();
    plane(
        [0.0, -t.sin(), t.cos()],
        [0.0, foot_m, base_m],
        [-half_width_m, foot_m, base_m],
        [half_width_m, BIG, base_m + 0.8],
    )
}

/// A vertical face across the path at `y_m`, from `z0` to `z1`.
fn riser(y_m: f64, z0: f64, z1: f64, half_width_m: f64) -> Plane {
    plane(
        [0.0, -1.0, 0.0],
        [0.0, y_m, 0.0],
        [-half_width_m, y_m - 0.01, z0],
        [half_width_m, y_m + 0.01, z1],
    )
}

/// A level slab top at `z_m` from `y0` to `y1`.
fn tread(z_m: f64, y0: f64, y1: f64, half_width_m: f64) -> Plane {
    plane(
        [0.0, 0.0, 1.0],
        [0.0, 0.0, z_m],
        [-half_width_m, y0, z_m - 0.01],
        [half_width_m, y1, z_m + 0.01],
    )
}

fn scene(height_m: f64, pitch_deg: f64, truth: f64, surfaces: Vec<Plane>) -> Scene {
    Scene {
        camera_height_m: height_m,
        pitch_deg,
        roll_deg: 0.0,
        surfaces,
        truth_slope_deg: truth,
        truth_distance_m: f64::NAN,
    }
}

/// The estimates of three noisy renderings of `scene` (seeds 0-2).
fn estimates(scene: &Scene) -> Vec<Estimate> {
    let mut est = Estimator::new(EstimatorConfig::default());
    (0..3)
        .map(|seed| {
            let cloud = SceneCloud::kinect2(scene, seed);
            let e = est.estimate(&cloud.view());
            print_scene(seed, &e);
            e
        })
        .collect()
}

fn print_scene(seed: u64, e: &Estimate) {
    println!(
        "seed {seed}: {} {:.2} deg, confidence {:.2}",
        e.status.name(),
        e.slope_deg,
        e.confidence
    );
    if let Some(scene) = &e.scene {
        for (k, s) in scene.surfaces.iter().enumerate() {
            let road = if scene.road.map(|r| r.surface) == Some(k) {
                " <- road"
            } else {
                ""
            };
            println!("  {k}: {s}{road}");
        }
    }
}

fn surfaces(e: &Estimate) -> &RoadScene {
    e.scene.as_ref().expect("a ground, so surfaces")
}

/// The surfaces whose plane is tilted `tilt_deg` (within 2 degrees) from
/// the ground and whose nearest point is `ahead_m` (within `tol_m`) ahead.
fn find(e: &Estimate, tilt_deg: f64, ahead_m: f64, tol_m: f64) -> Vec<&Surface> {
    surfaces(e)
        .surfaces
        .iter()
        .filter(|s| (s.tilt_deg() - tilt_deg).abs() < 2.0 && (s.distance_m - ahead_m).abs() < tol_m)
        .collect()
}

/// The one surface `find` finds.
fn the(e: &Estimate, tilt_deg: f64, ahead_m: f64, tol_m: f64) -> &Surface {
    let found = find(e, tilt_deg, ahead_m, tol_m);
    assert_eq!(
        found.len(),
        1,
        "one surface at {tilt_deg} deg, {ahead_m} m: {found:#?}"
    );
    found[0]
}

fn road(e: &Estimate) -> &Surface {
    surfaces(e).road_surface().expect("a road")
}

fn assert_ok_within(e: &Estimate, truth: f64, tol: f64) {
    assert_eq!(e.status, EstimateStatus::Ok, "{e:?}");
    assert!(
        (e.slope_deg - truth).abs() <= tol,
        "{} vs {truth}",
        e.slope_deg
    );
}

/// A wall to the right of the path, turned 45 degrees to face the robot,
/// nearer than the ramp ahead: a wall joining the ground, outside the
/// corridor; the ramp is the road.
#[test]
fn a_wall_beside_the_path_is_not_the_road() {
    let wall = plane(
        [-1.0, -1.0, 0.0],
        [1.0, 1.5, 0.0],
        [0.6, 1.4, 0.0],
        [1.1, 1.9, 1.0],
    );
    let s = scene(
        0.5,
        -20.0,
        16.0,
        vec![floor(2.5), ramp(16.0, 2.5, 0.0, 0.6), wall],
    );
    for e in estimates(&s) {
        assert_ok_within(&e, 16.0, 0.5);
        let w = the(&e, 90.0, 1.5, 0.2);
        assert_eq!(
            (w.role, w.support),
            (SurfaceRole::Wall, SurfaceSupport::Ground)
        );
        assert!(!w.in_corridor && w.left_m > 0.5, "{w:?}");
        assert!((w.heading_deg.abs() - 45.0).abs() < 3.0, "{w:?}");
        let r = road(&e);
        assert_eq!(
            (r.role, r.support),
            (SurfaceRole::Ramp, SurfaceSupport::Ground)
        );
        assert!(
            (r.distance_m - 2.5).abs() < 0.1 && r.heading_deg.abs() < 2.0,
            "{r:?}"
        );
        assert!(r.lowest_m.abs() < 0.05, "{r:?}");
    }
}

/// A board tilted 35 degrees whose lower edge floats 0.7 m above the floor,
/// nearer than the ramp: elevated (the camera sees the floor past where
/// its plane would come down), never the road.
#[test]
fn a_board_above_the_floor_is_elevated() {
    let t = 35f64.to_radians();
    let board = plane(
        [0.0, -t.sin(), t.cos()],
        [0.0, 1.8, 0.7],
        [-0.5, 1.8, 0.7],
        [0.5, 1.8 + 0.5 * t.cos(), 0.7 + 0.5 * t.sin()],
    );
    let s = scene(
        1.2,
        -30.0,
        16.0,
        vec![floor(3.0), ramp(16.0, 3.0, 0.0, 0.8), board],
    );
    for e in estimates(&s) {
        assert_ok_within(&e, 16.0, 0.5);
        let b = the(&e, 35.0, 1.8, 0.15);
        assert_eq!(
            (b.role, b.support),
            (SurfaceRole::Elevated, SurfaceSupport::None)
        );
        assert!(!b.joins_ground && (b.lowest_m - 0.7).abs() < 0.05, "{b:?}");
        assert_eq!(road(&e).role, SurfaceRole::Ramp);
    }
}

/// A table top tilted 12 degrees, 0.65-0.75 m up, and nothing else ahead:
/// elevated, so the floor ahead is flat (`no_inclined_plane`).
#[test]
fn a_sloped_table_top_is_elevated_and_no_road() {
    let t = 12f64.to_radians();
    let top = plane(
        [0.0, -t.sin(), t.cos()],
        [0.0, 1.5, 0.65],
        [-0.5, 1.5, 0.6],
        [0.5, 2.0, 0.8],
    );
    let s = scene(1.0, -30.0, f64::NAN, vec![floor(BIG), top]);
    for e in estimates(&s) {
        assert_eq!(e.status, EstimateStatus::NoInclinedPlane, "{e:?}");
        assert!(e.ground.is_some());
        let top = the(&e, 12.0, 1.5, 0.15);
        assert_eq!(top.role, SurfaceRole::Elevated, "{top:?}");
        assert!(surfaces(&e).road.is_none());
    }
}

/// Three steps (rise 0.17 m, tread 0.4 m) from 1.6 m ahead, seen from 1.2 m
/// up: each riser a wall standing on the tread below (the first on the
/// floor), each tread a step; the first riser is the road (90 degrees).
#[test]
fn a_staircase_is_a_chain_of_steps_and_risers() {
    let (start, rise, run, w) = (1.6, 0.17, 0.4, 0.8);
    let mut planes = vec![floor(start)];
    for k in 0..3 {
        let (y, z) = (start + run * k as f64, rise * k as f64);
        planes.push(riser(y, z, z + rise, w));
        planes.push(tread(z + rise, y, y + run, w));
    }
    let s = scene(1.2, -35.0, 90.0, planes);
    for e in estimates(&s) {
        assert_ok_within(&e, 90.0, 1.5);
        let first = road(&e);
        assert_eq!(
            (first.role, first.support),
            (SurfaceRole::Wall, SurfaceSupport::Ground)
        );
        assert!((first.distance_m - start).abs() < 0.05, "{first:?}");
        let scene = surfaces(&e);
        // Segmentation finds the first tread in every frame, the higher
        // (farther, thinner) ones not always: a riser whose tread below was
        // not found has its foot hidden (the tread's pixels are nearer
        // than its plane continued down).
        let mut tread_below = None;
        for k in 0..3 {
            let (y, z) = (start + run * k as f64, rise * k as f64);
            let riser = find(&e, 90.0, y, 0.06);
            assert!(k > 0 || riser.len() == 1, "the first riser: {riser:?}");
            if let Some(riser) = riser.first() {
                assert_eq!(riser.role, SurfaceRole::Wall, "riser {k}: {riser:?}");
                let on = riser.supported_by.map(|i| &scene.surfaces[i]);
                match (k, tread_below) {
                    (0, _) => assert_eq!(riser.support, SurfaceSupport::Ground),
                    (_, Some(below)) => {
                        assert_eq!(riser.support, SurfaceSupport::Step, "riser {k}: {riser:?}");
                        assert_eq!(on, Some(below), "riser {k} stands on the tread below");
                    }
                    (_, None) => assert_eq!(riser.support, SurfaceSupport::Hidden),
                }
            }
            let tread = find(&e, 0.0, y, 0.06);
            assert!(k > 0 || tread.len() == 1, "the first tread: {tread:?}");
            tread_below = tread.first().copied();
            if let Some(tread) = tread_below {
                assert_eq!(tread.role, SurfaceRole::Step, "tread {k}: {tread:?}");
                assert!(
                    (tread.lowest_m - (z + rise)).abs() < 0.03,
                    "tread {k}: {tread:?}"
                );
            }
        }
    }
}

/// A curb 0.1 m high from 1.5 m, and a 14 degree ramp rising from its top
/// at 2.5 m: the curb's top is a step on the floor, the ramp stands on the
/// step (its foot is 0.1 m above the floor: without the chain it would be
/// elevated).
#[test]
fn a_ramp_on_a_curb_stands_on_the_step() {
    let s = scene(
        1.0,
        -30.0,
        14.0,
        vec![
            floor(1.5),
            riser(1.5, 0.0, 0.1, 1.0),
            tread(0.1, 1.5, 2.5, 1.0),
            ramp(14.0, 2.5, 0.1, 0.8),
        ],
    );
    for e in estimates(&s) {
        let scene = surfaces(&e);
        let top = the(&e, 0.0, 1.5, 0.06);
        assert_eq!(
            (top.role, top.support),
            (SurfaceRole::Step, SurfaceSupport::Ground)
        );
        let r = the(&e, 14.0, 2.5, 0.1);
        assert_eq!(
            (r.role, r.support),
            (SurfaceRole::Ramp, SurfaceSupport::Step),
            "{r:?}"
        );
        let on = r.supported_by.map(|i| &scene.surfaces[i]);
        assert!(
            on.is_some_and(|t| (t.lowest_m - 0.1).abs() < 0.03),
            "{on:?}"
        );
        // The road: the curb's face when segmentation found it (a wall on
        // the floor, nearer), else the ramp.
        let road = road(&e);
        assert!(
            (road.role == SurfaceRole::Wall && (road.distance_m - 1.5).abs() < 0.05)
                || std::ptr::eq(road, r),
            "{road:?}"
        );
    }
}

/// A box 0.4 m high in front of a ramp hides the ramp's foot: the ramp
/// still stands (support `hidden`); the box's face is a wall on the floor
/// and, nearer in the corridor, the road.
#[test]
fn a_ramp_whose_foot_a_box_hides_still_stands() {
    let s = scene(
        1.0,
        -30.0,
        16.0,
        vec![
            floor(BIG),
            riser(2.0, 0.0, 0.4, 0.8),
            tread(0.4, 2.0, 2.4, 0.8),
            ramp(16.0, 2.5, 0.0, 0.6),
        ],
    );
    for e in estimates(&s) {
        // Seen over the box's back edge from 1 m up: from 3.2 m ahead, 0.2 m up.
        let r = the(&e, 16.0, 3.2, 0.3);
        assert_eq!(
            (r.role, r.support),
            (SurfaceRole::Ramp, SurfaceSupport::Hidden),
            "{r:?}"
        );
        assert!(r.joins_ground && r.lowest_m > 0.12, "{r:?}");
        // The box's top, when segmentation finds it, is no step (0.4 m up).
        for top in find(&e, 0.0, 2.0, 0.06) {
            assert_eq!(top.role, SurfaceRole::Elevated, "{top:?}");
        }
        let face = road(&e);
        assert_eq!(
            (face.role, face.support),
            (SurfaceRole::Wall, SurfaceSupport::Ground)
        );
        assert_ok_within(&e, 90.0, 1.5);
    }
}

/// A box 0.6 m high from 1.5 to 3.5 m ahead whose top begins with a strip
/// falling away by 12 degrees (0.4 m deep, 8.5 cm down, then back up: like
/// a bump on a bed's cover), seen from 1.2 m up: the strip's continuation runs under
/// the box's top, hidden, but the strip falls away from the robot, so its
/// near edge is in the air and it is elevated, no ramp with a hidden foot.
/// The box's front face, a wall on the floor, is the road.
#[test]
fn a_surface_falling_away_on_a_box_is_elevated_though_its_continuation_is_hidden() {
    let t = 12f64.to_radians();
    let drop = 0.4 * t.tan();
    let strip = plane(
        [0.0, t.sin(), t.cos()],
        [0.0, 1.5, 0.6],
        [-0.6, 1.5, 0.6 - drop - 0.01],
        [0.6, 1.9, 0.61],
    );
    let s = scene(
        1.2,
        -30.0,
        90.0,
        vec![
            floor(BIG),
            riser(1.5, 0.0, 0.6, 0.6),
            strip,
            riser(1.9, 0.6 - drop - 0.01, 0.6, 0.6),
            tread(0.6, 1.9, 3.5, 0.6),
            riser(3.5, 0.0, 0.6, 0.6),
        ],
    );
    for e in estimates(&s) {
        let strip = the(&e, 12.0, 1.5, 0.15);
        assert_eq!(
            (strip.role, strip.support, strip.joins_ground),
            (SurfaceRole::Elevated, SurfaceSupport::None, false),
            "{strip:?}"
        );
        assert!(strip.slope_deg < 0.0 && strip.measurable, "{strip:?}");
        let face = road(&e);
        assert_eq!(
            (face.role, face.support),
            (SurfaceRole::Wall, SurfaceSupport::Ground)
        );
        assert_ok_within(&e, 90.0, 1.5);
    }
}

/// A 12 degree ramp straight ahead at 2.5 m, and a 20 degree ramp off to the
/// left, nearer, rising 40 degrees left of forward: both ramps on the floor,
/// only the first in the corridor, so it is the road.
#[test]
fn of_two_ramps_the_one_in_the_corridor_is_the_road() {
    let (t, h) = (20f64.to_radians(), 40f64.to_radians());
    let uphill = Vector3::new(-h.sin(), h.cos(), 0.0);
    let normal = Vector3::z() * t.cos() - uphill * t.sin();
    let side = plane(
        normal.into(),
        [-1.2, 1.3, 0.0],
        [-1.7, 1.3, 0.0],
        [-0.7, 2.4, 0.5],
    );
    let s = scene(
        0.8,
        -25.0,
        12.0,
        vec![floor(2.5), ramp(12.0, 2.5, 0.0, 0.6), side],
    );
    for e in estimates(&s) {
        assert_ok_within(&e, 12.0, 0.5);
        let other = the(&e, 20.0, 1.3, 0.3);
        assert_eq!(
            (other.role, other.support),
            (SurfaceRole::Ramp, SurfaceSupport::Ground)
        );
        assert!(
            !other.in_corridor && (other.heading_deg - 40.0).abs() < 3.0,
            "{other:?}"
        );
        assert!(road(&e).heading_deg.abs() < 2.0);
    }
}
