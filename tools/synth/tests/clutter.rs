//! Clutter (tables, ceilings, soft blocks) through the real recording
//! writer: each surface is where the scene says (world coordinates of the
//! readings, through the frame's exact camera), tables hide the floor, soft
//! faces are rough and plain faces flat, and the truth stays the ramp's.
//! The scenes of `tests/scenes/` render sensibly.

mod common;

use std::collections::BTreeMap;

use common::{fit_plane, frame, scene_fixture, world_point, write_and_open, Frame};
use nalgebra::Vector3;
use slope_sensor::recording::Recording;
use slope_synth::{
    raycast, BoxFace, Camera, CameraPose, Ceiling, GeometryImage, GroundBox, MountPose, Scene,
    SensorModel, Surface, SurfaceKind, World,
};
use tempfile::TempDir;

const SEED: u64 = 3;
const TABLE_TOP: Surface = Surface::new(SurfaceKind::Table, 0, BoxFace::Top as u8);
const GROUND: Surface = Surface::single(SurfaceKind::Ground);
const SOFT_NEAR: Surface = Surface::new(SurfaceKind::SoftBlock, 0, BoxFace::Near as u8);
const SOFT_TOP: Surface = Surface::new(SurfaceKind::SoftBlock, 0, BoxFace::Top as u8);

/// A written recording (kept on disk while this lives) and one frame of it.
struct Rendered {
    dir: TempDir,
    rec: Recording,
    frame: Frame,
}

fn render(scene: &Scene, model: &SensorModel, frames: u64, index: u64) -> Rendered {
    let dir = tempfile::tempdir().expect("temp dir");
    let rec = write_and_open(scene, model, frames, SEED, dir.path());
    let frame = frame(&rec, scene, model, SEED, index);
    Rendered { dir, rec, frame }
}

/// True when every pixel within `margin` of (u, v) sees the same surface
/// (no depth edge nearby: no flying or mislabelled pixels).
fn interior(geometry: &GeometryImage, u: u32, v: u32, margin: u32) -> bool {
    let Some(me) = geometry.get(u, v) else {
        return false;
    };
    let (u0, v0) = (u.saturating_sub(margin), v.saturating_sub(margin));
    (v0..=v + margin).all(|nv| {
        (u0..=u + margin).all(|nu| {
            geometry
                .get(nu, nv)
                .is_some_and(|o| o.surface == me.surface)
        })
    })
}

/// World points of the readings whose exact ray meets `surface`, at least
/// `margin` pixels from any other surface.
fn world_points(r: &Rendered, surface: Surface, margin: u32) -> Vec<Vector3<f64>> {
    let f = &r.frame;
    let unit = r.rec.meta().depth.unit_m;
    let mut points = Vec::new();
    for v in 0..f.depth.height {
        for u in 0..f.depth.width {
            let raw = f.depth.get(u, v).unwrap_or(0);
            let seen = f.geometry.get(u, v).map(|h| h.surface);
            if raw != 0 && seen == Some(surface) && interior(&f.geometry, u, v, margin) {
                points.push(world_point(&f.camera, u, v, f64::from(raw) * unit));
            }
        }
    }
    points
}

fn nominal_camera(scene: &Scene) -> Camera {
    let m = &scene.mount;
    Camera {
        model: scene.camera,
        pose: CameraPose::new(m.height_m, m.pitch_deg, m.roll_deg, 0.0, 0.0),
    }
}

/// Pixels per surface within the Kinect's range, in the exact geometry.
fn in_range_counts(geometry: &GeometryImage) -> BTreeMap<Surface, usize> {
    let mut counts = BTreeMap::new();
    for hit in geometry.pixels.iter().flatten() {
        if (0.5..=4.5).contains(&hit.z_m) {
            *counts.entry(hit.surface).or_default() += 1;
        }
    }
    counts
}

fn kind_count(counts: &BTreeMap<Surface, usize>, kind: SurfaceKind) -> usize {
    counts
        .iter()
        .filter(|(s, _)| s.kind == kind)
        .map(|(_, n)| n)
        .sum()
}

#[test]
fn table_top_readings_lie_at_top_height() {
    let scene = scene_fixture("table_hides_floor.toml");
    let top_m = scene.tables[0].top_m;
    // Clean: every reading within the millimetre rounding of the depth.
    let clean = render(&scene, &SensorModel::clean(), 1, 0);
    let points = world_points(&clean, TABLE_TOP, 0);
    assert!(points.len() > 50_000, "{} table-top readings", points.len());
    for p in &points {
        assert!(
            (p.z - top_m).abs() < 1e-3,
            "table-top reading at z = {}",
            p.z
        );
    }
    // With the sensor model: horizontal, at the top's height, within noise.
    let noisy = render(&scene, &SensorModel::default(), 2, 1);
    let points = world_points(&noisy, TABLE_TOP, 3);
    let plane = fit_plane(&points);
    let tilt = common::angle_deg(&plane.normal, &Vector3::z());
    let height = plane.offset / plane.normal.z;
    eprintln!(
        "noisy table top: {} points, tilt {tilt:.4}°, height {height:.4} m, rms {:.2} mm",
        points.len(),
        plane.rms_m * 1e3
    );
    assert!(tilt < 0.1, "tilt {tilt}°");
    assert!((height - top_m).abs() < 2e-3, "height {height}");
    assert!(plane.rms_m < 5e-3, "rms {}", plane.rms_m);
}

#[test]
fn table_hides_the_floor_but_not_the_ramp() {
    let scene = scene_fixture("table_hides_floor.toml");
    let table = scene.tables[0];
    let camera = nominal_camera(&scene);
    let with = raycast(&World::build(&scene), &camera);
    let without = raycast(
        &World::build(&Scene {
            tables: Vec::new(),
            ..scene.clone()
        }),
        &camera,
    );
    let (with_counts, without_counts) = (in_range_counts(&with), in_range_counts(&without));
    let floor_with = kind_count(&with_counts, SurfaceKind::Ground);
    let floor_without = kind_count(&without_counts, SurfaceKind::Ground);
    let ramp_with = kind_count(&with_counts, SurfaceKind::Ramp);
    eprintln!(
        "floor in range: {floor_with} with the table, {floor_without} without; ramp {ramp_with}"
    );
    assert!(floor_with * 10 < floor_without);
    assert!(ramp_with > 5_000, "ramp {ramp_with}");

    // Oracle: every ray that crosses the plane z = top_m inside the top's
    // footprint (the camera is above it) meets the top exactly there.
    assert!(camera.pose.position.z > table.top_m && table.yaw_deg == 0.0);
    let mut covered = 0;
    for v in 0..camera.model.height {
        for u in 0..camera.model.width {
            let ray = camera.ray(f64::from(u), f64::from(v));
            if ray.direction.z >= 0.0 {
                continue;
            }
            let t = (table.top_m - ray.origin.z) / ray.direction.z;
            let p = ray.at(t);
            let inside = (p.x - table.x_m).abs() < table.size_m[0] / 2.0 - 1e-6
                && (p.y - table.y_m).abs() < table.size_m[1] / 2.0 - 1e-6;
            if !inside {
                continue;
            }
            let hit = with.get(u, v).expect("the top is hit");
            assert_eq!(hit.surface, TABLE_TOP, "({u}, {v})");
            assert!(
                (hit.z_m - t).abs() < 1e-9 * t,
                "({u}, {v}): {} vs {t}",
                hit.z_m
            );
            covered += 1;
        }
    }
    assert!(covered > 100_000, "{covered} pixels over the top");
}

#[test]
fn ceiling_lies_at_its_height_and_flat_scene_has_no_truth() {
    let scene = scene_fixture("ceiling_flat.toml");
    let height_m = scene.ceiling.expect("has a ceiling").height_m;
    let r = render(&scene, &SensorModel::clean(), 1, 0);
    assert_eq!(r.rec.meta().truth.slope_deg, None);
    let toml = std::fs::read_to_string(r.dir.path().join("recording.toml")).expect("readable");
    assert!(!toml.contains("[truth]"), "{toml}");
    let underside = Surface::new(SurfaceKind::Ceiling, 0, BoxFace::Bottom as u8);
    for (surface, z_m, least) in [(underside, height_m, 10_000), (GROUND, 0.0, 50_000)] {
        let points = world_points(&r, surface, 0);
        assert!(points.len() > least, "{surface:?}: {}", points.len());
        for p in &points {
            assert!(
                (p.z - z_m).abs() < 1e-3,
                "{surface:?} reading at z = {}",
                p.z
            );
        }
        assert!(fit_plane(&points).rms_m < 0.5e-3);
    }
}

#[test]
fn overhang_spans_only_its_range() {
    let scene = Scene {
        mount: MountPose {
            height_m: 1.0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            ..MountPose::default()
        },
        ceiling: Some(Ceiling {
            height_m: 1.6,
            from_m: 1.5,
            to_m: 3.0,
        }),
        ..Scene::default()
    };
    let r = render(&scene, &SensorModel::clean(), 1, 0);
    let face = |f: BoxFace| Surface::new(SurfaceKind::Ceiling, 0, f as u8);
    let underside = world_points(&r, face(BoxFace::Bottom), 0);
    assert!(underside.len() > 5_000, "underside {}", underside.len());
    for p in &underside {
        assert!(
            (p.z - 1.6).abs() < 1e-3 && (1.499..=3.001).contains(&p.y),
            "{p:?}"
        );
    }
    let near_end = world_points(&r, face(BoxFace::Near), 0);
    assert!(near_end.len() > 1_000, "near end {}", near_end.len());
    for p in &near_end {
        assert!((p.y - 1.5).abs() < 1e-3 && p.z > 1.6 - 1e-3, "{p:?}");
    }
    // Rays that rise but pass under the far end see open sky.
    let camera = &r.frame.camera;
    let mut sky = 0;
    let u = camera.model.width / 2;
    for v in 0..camera.model.height {
        let ray = camera.ray(f64::from(u), f64::from(v));
        let rise_at_far_end = ray.direction.z * (3.0 - ray.origin.y) / ray.direction.y;
        if ray.direction.z > 0.0 && ray.origin.z + rise_at_far_end < 1.6 - 1e-6 {
            assert!(r.frame.geometry.get(u, v).is_none(), "row {v}");
            sky += 1;
        }
    }
    assert!(sky > 20, "{sky} sky rows");
}

#[test]
fn soft_block_faces_are_rough_and_plain_faces_flat() {
    let scene = scene_fixture("soft_block_bed.toml");
    let block = scene.soft_blocks[0];
    let near_y = block.y_m - block.size_m[1] / 2.0;
    let clean = render(&scene, &SensorModel::clean(), 1, 0);
    for (surface, coordinate, nominal) in [(SOFT_NEAR, 1, near_y), (SOFT_TOP, 2, block.size_m[2])] {
        let points = world_points(&clean, surface, 3);
        let plane = fit_plane(&points);
        eprintln!(
            "clean soft {surface:?}: {} points, rms {:.2} mm",
            points.len(),
            plane.rms_m * 1e3
        );
        assert!(points.len() > 3_000);
        assert!(plane.rms_m >= 0.01, "rms {}", plane.rms_m);
        // Bumps stay within the roughness of the undisplaced face.
        for p in &points {
            let off = (p[coordinate] - nominal).abs();
            assert!(off <= block.roughness_m + 1e-3, "{surface:?} {off} m off");
        }
    }
    // With the sensor model the side is still rough.
    let noisy = render(&scene, &SensorModel::default(), 1, 0);
    let rms = fit_plane(&world_points(&noisy, SOFT_NEAR, 3)).rms_m;
    eprintln!("noisy soft near face: rms {:.2} mm", rms * 1e3);
    assert!(rms >= 0.01, "rms {rms}");

    // The same block without bumps, and a plain box in its place: planes.
    let mut smooth = scene.clone();
    smooth.soft_blocks[0].roughness_m = 0.0;
    let boxed = Scene {
        soft_blocks: Vec::new(),
        boxes: vec![GroundBox {
            x_m: block.x_m,
            y_m: block.y_m,
            size_m: block.size_m,
            yaw_deg: block.yaw_deg,
        }],
        ..scene.clone()
    };
    let box_near = Surface::new(SurfaceKind::Box, 0, BoxFace::Near as u8);
    for (scene, surface) in [
        (&smooth, SOFT_NEAR),
        (&smooth, SOFT_TOP),
        (&boxed, box_near),
    ] {
        let points = world_points(&render(scene, &SensorModel::clean(), 1, 0), surface, 3);
        let rms = fit_plane(&points).rms_m;
        eprintln!(
            "clean flat {surface:?}: {} points, rms {:.3} mm",
            points.len(),
            rms * 1e3
        );
        assert!(points.len() > 3_000);
        assert!(rms < 3e-3, "{surface:?}: rms {rms}");
    }
}

#[test]
fn scene_files_render_sensibly() {
    let model = SensorModel::default();
    for (name, truth) in [
        ("table_hides_floor.toml", Some(16.0)),
        ("soft_block_bed.toml", None),
        ("ceiling_flat.toml", None),
    ] {
        let scene = scene_fixture(name);
        let r = render(&scene, &model, 2, 1);
        assert_eq!(r.rec.meta().truth.slope_deg, truth, "{name}");
        let f = &r.frame;
        let readings: Vec<u16> = f.depth.data.iter().copied().filter(|&d| d != 0).collect();
        let (near, far) = (readings.iter().min(), readings.iter().max());
        let mut per_kind: BTreeMap<SurfaceKind, usize> = BTreeMap::new();
        for (d, hit) in f.depth.data.iter().zip(&f.geometry.pixels) {
            if let (true, Some(hit)) = (*d != 0, hit) {
                *per_kind.entry(hit.surface.kind).or_default() += 1;
            }
        }
        eprintln!(
            "{name}: {} readings, depth {near:?}..{far:?} mm, {per_kind:?}",
            readings.len()
        );
        assert!(near >= Some(&500) && far <= Some(&4500), "{name}");
        let share = |kind| per_kind.get(&kind).copied().unwrap_or(0) as f64 / 217_088.0;
        match name {
            "table_hides_floor.toml" => {
                assert!(share(SurfaceKind::Table) > 0.5);
                assert!(share(SurfaceKind::Ground) < 0.05);
                assert!(share(SurfaceKind::Ramp) > 0.03);
            }
            "soft_block_bed.toml" => {
                assert!(share(SurfaceKind::SoftBlock) > 0.2);
                assert!(share(SurfaceKind::Ground) > 0.3);
                // The floor shows on both sides of the block.
                let block = scene.soft_blocks[0];
                let beside = |side: f64| {
                    world_points(&r, GROUND, 0)
                        .iter()
                        .filter(|p| side * (p.x - block.x_m) > block.size_m[0] / 2.0 + 0.1)
                        .filter(|p| (p.y - block.y_m).abs() < block.size_m[1] / 2.0)
                        .count()
                };
                assert!(beside(-1.0) > 2_000 && beside(1.0) > 2_000, "{name}");
            }
            _ => {
                assert!(share(SurfaceKind::Ceiling) > 0.05);
                assert!(share(SurfaceKind::Ground) > 0.3);
            }
        }
    }
}
