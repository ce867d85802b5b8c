//! The scene features for road-ahead tests, checked against analytic
//! geometry with `--clean` (every sensor effect off, millimetre depths):
//! panels (`[[panels]]`) at their ray/plane intersections and without a lip
//! where they stand on the floor, a sloped table top recovered by a plane
//! fit, a raised ramp foot (`[ramp] base_m`) at its height; the keys'
//! validation errors; and the scene files of `tests/scenes/` built with
//! them parse, render and keep their objects inside the field of view.

mod common;

use std::path::Path;

use common::{angle_deg, fit_plane, frame, scene_fixture, world_point, write_and_open, Frame};
use nalgebra::Vector3;
use slope_sensor::error_chain::ErrorChain;
use slope_synth::{
    parse_scene, raycast, BoxFace, Camera, CameraPose, GeometryImage, MountPose, Panel, Ramp,
    Scene, SensorModel, Surface, SurfaceKind, Table, World,
};

const SEED: u64 = 5;
const GROUND: Surface = Surface::single(SurfaceKind::Ground);

/// The scene files that exercise the road-ahead rules (issue 27).
const ROAD_SCENES: [(&str, f64); 7] = [
    ("ramp_wall_beside_path.toml", 16.0),
    ("board_before_ramp.toml", 16.0),
    ("sloped_table.toml", 16.0),
    ("curb_before_ramp.toml", 14.0),
    ("two_ramps_headings.toml", 12.0),
    ("ramp_foot_hidden.toml", 16.0),
    ("wall_behind_ramp.toml", 16.0),
];

fn panel_top(index: u16) -> Surface {
    Surface::new(SurfaceKind::Panel, index, BoxFace::Top as u8)
}

/// Writes one clean frame of `scene` and reads it back with its geometry.
fn clean_frame(scene: &Scene) -> Frame {
    let dir = tempfile::tempdir().expect("temp dir");
    let model = SensorModel::clean();
    let rec = write_and_open(scene, &model, 1, SEED, dir.path());
    frame(&rec, scene, &model, SEED, 0)
}

/// True when every pixel within `margin` of (u, v) sees `surface` (no depth
/// edge nearby: no flying or mixed pixels).
fn interior(geometry: &GeometryImage, u: u32, v: u32, surface: Surface, margin: u32) -> bool {
    let (u0, v0) = (u.saturating_sub(margin), v.saturating_sub(margin));
    (v0..=v + margin).all(|nv| {
        (u0..=u + margin).all(|nu| geometry.get(nu, nv).is_some_and(|o| o.surface == surface))
    })
}

/// A panel's plane and rectangle, computed here from its keys (not with
/// the simulator's own frame): lower-edge middle, across, up-slope and
/// normal unit vectors.
struct PanelOracle {
    origin: Vector3<f64>,
    across: Vector3<f64>,
    up_slope: Vector3<f64>,
    normal: Vector3<f64>,
    width_m: f64,
    length_m: f64,
}

impl PanelOracle {
    fn new(p: &Panel) -> Self {
        let (y, t) = (p.yaw_deg.to_radians(), p.tilt_deg.to_radians());
        Self {
            origin: Vector3::new(p.x_m, p.y_m, p.bottom_m),
            across: Vector3::new(y.cos(), y.sin(), 0.0),
            up_slope: Vector3::new(-y.sin() * t.cos(), y.cos() * t.cos(), t.sin()),
            normal: Vector3::new(y.sin() * t.sin(), -y.cos() * t.sin(), t.cos()),
            width_m: p.width_m,
            length_m: p.length_m,
        }
    }

    /// Ray parameter (depth) where the ray meets the top surface's plane,
    /// and whether that point lies `margin_m` inside the rectangle.
    fn intersect(&self, camera: &Camera, u: u32, v: u32, margin_m: f64) -> (f64, bool) {
        let ray = camera.ray(f64::from(u), f64::from(v));
        let t =
            self.normal.dot(&(self.origin - ray.origin.coords)) / self.normal.dot(&ray.direction);
        let d = ray.at(t).coords - self.origin;
        let (a, s) = (d.dot(&self.across), d.dot(&self.up_slope));
        let inside = a.abs() <= self.width_m / 2.0 - margin_m
            && (margin_m..=self.length_m - margin_m).contains(&s);
        (t, t > 0.0 && inside)
    }
}

/// A propped-up board (floating, yawed) and a free-standing wall at an
/// angle, apart so that neither hides the other.
fn two_panels() -> Scene {
    Scene {
        mount: MountPose {
            height_m: 1.0,
            ..MountPose::default()
        },
        panels: vec![
            Panel {
                x_m: 0.35,
                y_m: 1.7,
                bottom_m: 0.7,
                width_m: 0.6,
                length_m: 0.5,
                tilt_deg: 35.0,
                yaw_deg: 20.0,
                thickness_m: 0.02,
            },
            Panel {
                x_m: -0.7,
                y_m: 2.8,
                width_m: 0.9,
                length_m: 0.9,
                tilt_deg: 90.0,
                yaw_deg: -30.0,
                thickness_m: 0.05,
                ..Panel::default()
            },
        ],
        ..Scene::default()
    }
}

#[test]
fn panel_depth_is_the_ray_plane_intersection() {
    let scene = two_panels();
    let f = clean_frame(&scene);
    for (i, panel) in (0u16..).zip(&scene.panels) {
        let oracle = PanelOracle::new(panel);
        let (mut seen, mut crossing) = (0, 0);
        for v in 0..f.depth.height {
            for u in 0..f.depth.width {
                let raw = f.depth.get(u, v).unwrap_or(0);
                let label = f.geometry.get(u, v).map(|h| h.surface);
                let (t, inside) = oracle.intersect(&f.camera, u, v, 0.01);
                if label == Some(panel_top(i)) {
                    // Its depth is the plane's, to the millimetre's rounding.
                    seen += 1;
                    let (_, on_panel) = oracle.intersect(&f.camera, u, v, -1e-9);
                    assert!(on_panel, "panel {i} ({u}, {v}) outside its rectangle");
                    assert!(
                        (f64::from(raw) * 1e-3 - t).abs() <= 0.5e-3 + 1e-9,
                        "{raw} vs {t}"
                    );
                }
                if inside {
                    // Every ray through the rectangle (1 cm inside) sees it.
                    crossing += 1;
                    assert_eq!(label, Some(panel_top(i)), "panel {i} ({u}, {v})");
                }
            }
        }
        assert!(
            crossing > 2000 && seen >= crossing,
            "panel {i}: {seen} seen, {crossing} crossing"
        );
    }
}

#[test]
fn panel_on_the_floor_meets_it_without_a_lip() {
    let scene = Scene {
        panels: vec![Panel {
            y_m: 2.0,
            width_m: 1.0,
            length_m: 1.0,
            tilt_deg: 20.0,
            thickness_m: 0.05,
            ..Panel::default()
        }],
        ..Scene::default()
    };
    let f = clean_frame(&scene);
    let mut columns = 0;
    for u in 0..f.depth.width {
        // Up the column: floor, then the panel's top surface, nothing between.
        let labels: Vec<_> = (0..f.depth.height)
            .rev()
            .map(|v| (v, f.geometry.get(u, v).map(|h| h.surface)))
            .collect();
        let Some(k) = labels.iter().position(|(_, s)| *s == Some(panel_top(0))) else {
            continue;
        };
        assert!(k > 0 && labels[k - 1].1 == Some(GROUND), "column {u}");
        let (below, above) = (labels[k - 1].0, labels[k].0);
        let z = |v: u32| f64::from(f.depth.get(u, v).unwrap_or(0)) * 1e-3;
        let (pb, pa) = (
            world_point(&f.camera, u, below, z(below)),
            world_point(&f.camera, u, above, z(above)),
        );
        if pa.x.abs() > 0.45 {
            continue; // the column meets the panel's side, not its lower edge
        }
        // Floor up to the lower edge (y = 2), then the top surface starting
        // at floor height: within a row's footprint (2.2 cm on the floor at
        // 2 m), and far below the 5 cm a lip of the slab would show.
        assert!(
            pb.z.abs() < 1e-3 && (1.97..=2.002).contains(&pb.y),
            "column {u}: {pb:?}"
        );
        assert!(
            (1.998..2.02).contains(&pa.y) && pa.z < 0.008,
            "column {u}: {pa:?}"
        );
        columns += 1;
    }
    assert!(columns > 100, "{columns} columns see the join");
    let lip =
        f.geometry.pixels.iter().flatten().filter(|h| {
            h.surface.kind == SurfaceKind::Panel && h.surface.face != BoxFace::Top as u8
        });
    assert_eq!(
        lip.count(),
        0,
        "only the top surface of a leaning panel shows"
    );
}

#[test]
fn sloped_table_top_fits_its_tilted_plane() {
    let scene = scene_fixture("sloped_table.toml");
    let table = scene.tables[0];
    assert_eq!(table.tilt_deg, 12.0);
    let top = Surface::new(SurfaceKind::Table, 0, BoxFace::Top as u8);
    let t = table.tilt_deg.to_radians();
    let expected = Vector3::new(0.0, -t.sin(), t.cos());
    let centre = Vector3::new(table.x_m, table.y_m, table.top_m);
    for model in [SensorModel::clean(), SensorModel::default()] {
        let dir = tempfile::tempdir().expect("temp dir");
        let rec = write_and_open(&scene, &model, 1, SEED, dir.path());
        let f = frame(&rec, &scene, &model, SEED, 0);
        let points: Vec<_> = (0..f.depth.height)
            .flat_map(|v| (0..f.depth.width).map(move |u| (u, v)))
            .filter(|&(u, v)| interior(&f.geometry, u, v, top, 2))
            .filter_map(|(u, v)| {
                let raw = f.depth.get(u, v).unwrap_or(0);
                (raw != 0).then(|| world_point(&f.camera, u, v, f64::from(raw) * 1e-3))
            })
            .filter(|p| (p - centre).dot(&Vector3::x()).abs() < 0.45)
            .collect();
        assert!(points.len() > 3000, "{} table-top readings", points.len());
        let plane = fit_plane(&points);
        let off = angle_deg(&plane.normal, &expected);
        let through_centre = (plane.normal.dot(&centre) - plane.offset).abs();
        let clean = model == SensorModel::clean();
        let (angle_tol, offset_tol) = if clean { (0.01, 0.001) } else { (0.2, 0.003) };
        assert!(off < angle_tol, "normal {off}° off");
        assert!(
            through_centre < offset_tol,
            "{through_centre} m from the top's centre"
        );
        let slope = angle_deg(&plane.normal, &Vector3::z());
        assert!((slope - 12.0).abs() < angle_tol, "top slopes {slope}°");
    }
}

#[test]
fn raised_ramp_foot_stands_base_m_above_the_ground() {
    // The curb scene without its curb: the ramp's own riser shows.
    let mut scene = scene_fixture("curb_before_ramp.toml");
    scene.boxes.clear();
    let ramp = scene.ramp.expect("a ramp");
    assert_eq!(ramp.base_m, 0.1);
    let f = clean_frame(&scene);
    let (mut ramp_points, mut riser_points) = (Vec::new(), Vec::new());
    for v in 0..f.depth.height {
        for u in 0..f.depth.width {
            let raw = f.depth.get(u, v).unwrap_or(0);
            let Some(hit) = f.geometry.get(u, v).filter(|_| raw != 0) else {
                continue;
            };
            let p = world_point(&f.camera, u, v, f64::from(raw) * 1e-3);
            match (hit.surface.kind, hit.surface.face) {
                (SurfaceKind::Ramp, _) => ramp_points.push(p),
                (SurfaceKind::RampBack, 2) => riser_points.push(p),
                _ => {}
            }
        }
    }
    // The slope: 14°, through the raised foot line (y = 2.2, z = 0.1); its
    // lowest readings at the foot's height.
    let plane = fit_plane(&ramp_points);
    assert!((angle_deg(&plane.normal, &Vector3::z()) - 14.0).abs() < 0.01);
    let foot = Vector3::new(0.0, ramp.distance_m, ramp.base_m);
    assert!((plane.normal.dot(&foot) - plane.offset).abs() < 0.001);
    let lowest = ramp_points
        .iter()
        .map(|p| p.z)
        .fold(f64::INFINITY, f64::min);
    assert!(
        (0.0995..0.11).contains(&lowest),
        "lowest ramp reading at {lowest} m"
    );
    // The riser: vertical, at the foot line, from the floor to base_m.
    assert!(
        riser_points.len() > 200,
        "{} riser readings",
        riser_points.len()
    );
    for p in &riser_points {
        assert!(
            (p.y - 2.2).abs() < 0.0015 && (-0.001..=0.101).contains(&p.z),
            "{p:?}"
        );
    }
    // With the curb, the curb's top meets the ramp's foot: no riser shows.
    let with_curb = clean_frame(&scene_fixture("curb_before_ramp.toml"));
    let riser = Surface::new(SurfaceKind::RampBack, 0, 2);
    assert!(!with_curb
        .geometry
        .pixels
        .iter()
        .flatten()
        .any(|h| h.surface == riser));
}

#[test]
fn new_keys_default_to_todays_scenes() {
    let file = parse_scene("[ramp]\n[[tables]]\n", Path::new("d.toml")).expect("valid");
    assert_eq!(file.scene.ramp, Some(Ramp::default()));
    assert_eq!(file.scene.ramp.map(|r| r.base_m), Some(0.0));
    assert_eq!(file.scene.tables[0].tilt_deg, 0.0);
    assert_eq!(file.scene.tables[0], Table::default());
    assert!(file.scene.panels.is_empty());
    let panel = parse_scene("[[panels]]\n", Path::new("p.toml")).expect("valid");
    assert_eq!(panel.scene.panels, vec![Panel::default()]);
}

#[test]
fn validation_errors_name_the_key() {
    for (text, key) in [
        ("[[panels]]\ntilt_deg = 91.0\n", "panels[0].tilt_deg"),
        (
            "[[panels]]\n[[panels]]\nbottom_m = -0.1\n",
            "panels[1].bottom_m",
        ),
        ("[[panels]]\nwidth_m = 0.0\n", "panels[0].width_m"),
        ("[[panels]]\nlength_m = inf\n", "panels[0].length_m"),
        ("[[panels]]\nthickness_m = -0.01\n", "panels[0].thickness_m"),
        ("[[panels]]\nyaw_deg = nan\n", "panels[0].yaw_deg"),
        ("[[tables]]\ntilt_deg = 50.0\n", "tables[0].tilt_deg"),
        (
            "[[tables]]\ntilt_deg = 30.0\ntop_m = 0.2\n",
            "tables[0].top_m",
        ),
        ("[ramp]\nbase_m = -0.1\n", "ramp.base_m"),
        (
            "[ramp]\ndirection = \"descending\"\nbase_m = 0.1\n",
            "ramp.base_m",
        ),
    ] {
        let err = parse_scene(text, Path::new("k.toml")).expect_err(text);
        let message = ErrorChain(&err).to_string();
        assert!(
            message.contains(key) && message.contains("k.toml") && message.contains("must"),
            "{text}: {message}"
        );
    }
    let err =
        parse_scene("[[panels]]\nheight_m = 1.0\n", Path::new("k.toml")).expect_err("unknown key");
    assert!(ErrorChain(&err).to_string().contains("height_m"), "{err}");
}

/// Pixels of the objects (not the floor, nor the ramp's sides and back)
/// this close to the image border mean an object is not well inside the
/// field of view.
const BORDER_PX: u32 = 8;

#[test]
fn road_scenes_parse_render_and_stay_in_view() {
    for (name, truth) in ROAD_SCENES {
        let scene = scene_fixture(name);
        assert_eq!(scene.truth_slope_deg(), Some(truth), "{name}");
        let m = &scene.mount;
        let camera = Camera {
            model: scene.camera,
            pose: CameraPose::new(m.height_m, m.pitch_deg, m.roll_deg, 0.0, 0.0),
        };
        let world = World::build(&scene);
        let geometry = raycast(&world, &camera);
        let (w, h) = (geometry.width, geometry.height);
        let mut counts = std::collections::BTreeMap::new();
        for v in 0..h {
            for u in 0..w {
                let Some(hit) = geometry.get(u, v) else {
                    continue;
                };
                let object = matches!(
                    hit.surface.kind,
                    SurfaceKind::Ramp
                        | SurfaceKind::Panel
                        | SurfaceKind::Box
                        | SurfaceKind::Table
                        | SurfaceKind::TableLeg
                );
                let near_border =
                    u < BORDER_PX || v < BORDER_PX || u >= w - BORDER_PX || v >= h - BORDER_PX;
                assert!(
                    !(object && near_border),
                    "{name}: {:?} at ({u}, {v})",
                    hit.surface
                );
                if (0.5..=4.5).contains(&hit.z_m) {
                    *counts
                        .entry((hit.surface.kind, hit.surface.index))
                        .or_insert(0) += 1;
                }
            }
        }
        let count = |kind, index| counts.get(&(kind, index)).copied().unwrap_or(0);
        assert!(count(SurfaceKind::Ramp, 0) > 2000, "{name}: {counts:?}");
        assert!(count(SurfaceKind::Ground, 0) > 10_000, "{name}: {counts:?}");
        for i in (0u16..).take(scene.panels.len()) {
            assert!(count(SurfaceKind::Panel, i) > 1000, "{name}: {counts:?}");
        }
        for i in (0u16..).take(scene.boxes.len()) {
            assert!(count(SurfaceKind::Box, i) > 1000, "{name}: {counts:?}");
        }
        for i in (0u16..).take(scene.tables.len()) {
            assert!(count(SurfaceKind::Table, i) > 1000, "{name}: {counts:?}");
        }
        // And through the sensor model, as a recording.
        let dir = tempfile::tempdir().expect("temp dir");
        let rec = write_and_open(&scene, &SensorModel::default(), 1, SEED, dir.path());
        assert_eq!(rec.meta().truth.slope_deg, Some(truth), "{name}");
    }
}
