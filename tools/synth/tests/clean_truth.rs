//! With every sensor effect off, the written depth images are the exact
//! geometry up to millimetre quantisation, so the truth in recording.toml
//! must be recoverable: a TLS plane fit of each surface (pixels labelled by
//! re-casting their rays) gives the configured angles within 0.01°, the
//! ground's normal is the `[mount]` up vector and its distance the mount height.

mod common;

use std::collections::BTreeMap;

use common::{angle_deg, back_project, fit_plane, frame, write_and_open, Plane};
use nalgebra::Vector3;
use slope_synth::{
    quantise, BoxFace, GroundBox, MountPose, Ramp, Scene, SensorModel, SideWall, SlopeDirection,
    Surface, SurfaceKind,
};

const TOLERANCE_DEG: f64 = 0.01;
/// Fewest pixels a surface needs to be fitted.
const MIN_PIXELS: usize = 2_000;

/// Writes a clean recording of `scene`, checks its metadata, and fits every
/// surface of the frames `check_frames`; returns the planes of the last one.
fn clean_planes(scene: &Scene, frames: u64, check_frames: &[u64]) -> BTreeMap<Surface, Plane> {
    let dir = tempfile::tempdir().expect("temp dir");
    let model = SensorModel::clean();
    let rec = write_and_open(scene, &model, frames, 5, dir.path());
    let meta = rec.meta();
    assert_eq!(meta.truth.slope_deg, scene.ramp.map(|r| r.slope_deg));
    assert_eq!(meta.mount.height_m, Some(scene.mount.height_m));
    assert_eq!(meta.mount.pitch_deg, Some(scene.mount.pitch_deg));
    assert_eq!(meta.mount.roll_deg, Some(scene.mount.roll_deg));
    assert_eq!(rec.frames().len() as u64, frames);
    let up = rec.mount().up_vector().expect("pitch in the metadata");
    let up = Vector3::new(up[0], up[1], up[2]);

    let mut planes = BTreeMap::new();
    for &index in check_frames {
        let f = frame(&rec, scene, &model, 5, index);
        let mut points: BTreeMap<Surface, Vec<Vector3<f64>>> = BTreeMap::new();
        for v in 0..f.depth.height {
            for u in 0..f.depth.width {
                let raw = f.depth.get(u, v).expect("inside");
                let exact = f.geometry.get(u, v);
                // Clean: a reading exactly where the geometry has one (and
                // it fits in 16 bits).
                assert_eq!(raw, exact.map_or(0, |e| quantise(e.z_m)), "({u}, {v})");
                let Some(hit) = exact else { continue };
                if raw == 0 {
                    continue;
                }
                let z = f64::from(raw) * rec.meta().depth.unit_m;
                assert!(
                    (z - hit.z_m).abs() <= 0.0005 + 1e-12,
                    "quantisation at ({u}, {v})"
                );
                points
                    .entry(hit.surface)
                    .or_default()
                    .push(back_project(&rec, u, v, z));
            }
        }
        planes = points
            .iter()
            .filter(|(_, p)| p.len() >= MIN_PIXELS)
            .map(|(s, p)| (*s, fit_plane(p)))
            .collect();
        let ground = planes
            .get(&Surface::single(SurfaceKind::Ground))
            .expect("the ground is in view");
        // The ground is the plane `up . p = -height`.
        let tilt = angle_deg(&ground.normal, &up);
        assert!(
            tilt < TOLERANCE_DEG,
            "frame {index}: ground vs [mount] up: {tilt}°"
        );
        let height = ground.offset.abs();
        assert!(
            (height - scene.mount.height_m).abs() < 1e-3,
            "frame {index}: ground at {height} m"
        );
        for (surface, plane) in &planes {
            // Rounding to 1 mm leaves at most 0.5 mm off each plane.
            assert!(plane.rms_m < 0.5e-3, "{surface:?}: rms {} m", plane.rms_m);
        }
    }
    planes
}

fn angle_to_ground(planes: &BTreeMap<Surface, Plane>, surface: Surface) -> f64 {
    let ground = &planes[&Surface::single(SurfaceKind::Ground)];
    let plane = planes
        .get(&surface)
        .unwrap_or_else(|| panic!("{surface:?} not in view: {:?}", planes.keys()));
    angle_deg(&ground.normal, &plane.normal)
}

fn assert_angle(found: f64, expected: f64, what: &str) {
    eprintln!("{what}: fitted {found:.6}°, configured {expected}°");
    assert!(
        (found - expected).abs() < TOLERANCE_DEG,
        "{what}: fitted {found:.5}°, configured {expected}°"
    );
}

const RAMP: Surface = Surface::single(SurfaceKind::Ramp);
const LANDING: Surface = Surface::single(SurfaceKind::Landing);

#[test]
fn default_scene_ramp_angle_is_exact() {
    let planes = clean_planes(&Scene::default_ramp(), 2, &[0, 1]);
    assert_angle(angle_to_ground(&planes, RAMP), 16.0, "default ramp");
}

#[test]
fn ascending_ramp_with_landing_roll_and_motion() {
    let scene = Scene {
        mount: MountPose {
            height_m: 0.8,
            pitch_deg: -30.0,
            roll_deg: 4.0,
            ..MountPose::default()
        },
        ramp: Some(Ramp {
            slope_deg: 10.0,
            distance_m: 1.2,
            length_m: 1.5,
            landing_m: 3.0,
            width_m: f64::INFINITY,
            ..Ramp::default()
        }),
        motion: slope_synth::Motion { speed_mps: 0.6 },
        ..Scene::default()
    };
    // The camera moves 0.1 m forward over 6 frames: check first and last.
    let planes = clean_planes(&scene, 6, &[0, 5]);
    assert_angle(angle_to_ground(&planes, RAMP), 10.0, "ramp");
    assert_angle(angle_to_ground(&planes, LANDING), 0.0, "landing");
}

#[test]
fn descending_slope_and_lower_landing() {
    let scene = Scene {
        mount: MountPose {
            height_m: 0.8,
            pitch_deg: -45.0,
            roll_deg: -2.0,
            ..MountPose::default()
        },
        ramp: Some(Ramp {
            direction: SlopeDirection::Descending,
            slope_deg: 12.0,
            distance_m: 1.0,
            length_m: 1.0,
            width_m: f64::INFINITY,
            ..Ramp::default()
        }),
        ..Scene::default()
    };
    let planes = clean_planes(&scene, 1, &[0]);
    assert_angle(angle_to_ground(&planes, RAMP), 12.0, "descending ramp");
    assert_angle(angle_to_ground(&planes, LANDING), 0.0, "lower landing");
    // The lower landing lies `length * sin(slope)` below the ground.
    let drop =
        planes[&LANDING].offset.abs() - planes[&Surface::single(SurfaceKind::Ground)].offset.abs();
    assert!(
        (drop - 12f64.to_radians().sin()).abs() < 1e-3,
        "drop {drop}"
    );
}

#[test]
fn yawed_wall_is_perpendicular() {
    let scene = Scene {
        mount: MountPose {
            height_m: 0.6,
            pitch_deg: -10.0,
            roll_deg: -3.0,
            ..MountPose::default()
        },
        ramp: Some(Ramp {
            slope_deg: 90.0,
            distance_m: 2.0,
            length_m: 2.0,
            landing_m: 0.0,
            width_m: f64::INFINITY,
            yaw_deg: 25.0,
            ..Ramp::default()
        }),
        ..Scene::default()
    };
    let planes = clean_planes(&scene, 1, &[0]);
    assert_angle(angle_to_ground(&planes, RAMP), 90.0, "wall");
}

#[test]
fn yawed_ramp_with_side_walls_and_box() {
    let scene = Scene {
        mount: MountPose {
            height_m: 0.5,
            pitch_deg: -22.0,
            roll_deg: 1.5,
            ..MountPose::default()
        },
        ramp: Some(Ramp {
            slope_deg: 30.0,
            distance_m: 1.8,
            width_m: 2.0,
            yaw_deg: -20.0,
            offset_m: 0.3,
            ..Ramp::default()
        }),
        walls: vec![
            SideWall {
                x_m: -1.2,
                ..SideWall::default()
            },
            SideWall {
                x_m: 0.8,
                from_m: 1.0,
                to_m: 1.7,
                height_m: 0.3,
                ..SideWall::default()
            },
        ],
        boxes: vec![GroundBox {
            x_m: -0.5,
            y_m: 1.1,
            size_m: [0.3, 0.3, 0.4],
            yaw_deg: 30.0,
        }],
        ..Scene::default()
    };
    let planes = clean_planes(&scene, 1, &[0]);
    assert_angle(angle_to_ground(&planes, RAMP), 30.0, "yawed ramp");
    for index in 0..2 {
        let wall = Surface::new(SurfaceKind::Wall, index, BoxFace::Inner as u8);
        assert_angle(angle_to_ground(&planes, wall), 90.0, "side wall");
    }
}

#[test]
fn flat_floor_without_ramp_is_exact_and_has_no_truth() {
    let scene = Scene {
        mount: MountPose {
            height_m: 0.9,
            pitch_deg: -28.0,
            roll_deg: 2.0,
            ..MountPose::default()
        },
        ..Scene::default()
    };
    // clean_planes checks the ground against [mount] and the missing truth.
    let planes = clean_planes(&scene, 1, &[0]);
    assert_eq!(
        planes.keys().collect::<Vec<_>>(),
        [&Surface::single(SurfaceKind::Ground)]
    );
}

#[test]
fn shallow_ramp_three_metres_away() {
    let scene = Scene {
        ramp: Some(Ramp {
            slope_deg: 5.0,
            distance_m: 3.0,
            ..Ramp::default()
        }),
        ..Scene::default()
    };
    let planes = clean_planes(&scene, 1, &[0]);
    assert_angle(angle_to_ground(&planes, RAMP), 5.0, "shallow ramp at 3 m");
}

#[test]
fn table_over_the_floor_leaves_the_truth_and_ramp_angle() {
    let scene = common::scene_fixture("table_hides_floor.toml");
    let planes = clean_planes(&scene, 1, &[0]);
    assert_angle(angle_to_ground(&planes, RAMP), 16.0, "ramp behind a table");
    let top = Surface::new(SurfaceKind::Table, 0, BoxFace::Top as u8);
    assert_angle(angle_to_ground(&planes, top), 0.0, "table top");
}
