//! Bending a perfect plane: the simulator's clean flat floor, bent by θ at
//! a hinge, is the simulator's clean ramp of slope θ whose foot is the
//! hinge (pixel for pixel, to the millimetre's rounding), and plane fits of
//! the bent frame give θ. Also: refusals name the frame and say why.

mod common;

use common::{angle_deg, fit_plane, write_and_open};
use nalgebra::Vector3;
use slope_sensor::recording::{DepthImage, Recording};
use slope_synth::bend::{bend_floor, BendParams, BentFrame, DepthFrame};
use slope_synth::{BendError, Ramp, Scene, SensorModel};

const HINGE_M: f64 = 1.5;

/// A clean recording (one frame) of `scene` in a temporary directory.
fn clean(scene: &Scene) -> (tempfile::TempDir, Recording) {
    let dir = tempfile::tempdir().expect("temp dir");
    let rec = write_and_open(scene, &SensorModel::clean(), 1, 0, dir.path());
    (dir, rec)
}

fn flat_scene() -> Scene {
    let mut scene = Scene::default_ramp();
    scene.ramp = None;
    scene.mount.height_m = 0.8;
    scene
}

fn ramp_scene(slope_deg: f64) -> Scene {
    let mut scene = flat_scene();
    scene.ramp = Some(Ramp {
        slope_deg,
        distance_m: HINGE_M,
        width_m: f64::INFINITY,
        length_m: f64::INFINITY,
        landing_m: 0.0,
        ..Ramp::default()
    });
    scene
}

fn points(depth: &DepthImage, rec: &Recording) -> Vec<Option<Vector3<f64>>> {
    let d = rec.meta().depth;
    depth
        .data
        .iter()
        .enumerate()
        .map(|(i, &count)| {
            (count != 0).then(|| {
                let (u, v) = ((i % d.width as usize) as f64, (i / d.width as usize) as f64);
                let z = f64::from(count) * d.unit_m;
                Vector3::new((u - d.cx) * z / d.fx, (v - d.cy) * z / d.fy, z)
            })
        })
        .collect()
}

fn bend(rec: &Recording, angle_deg: f64) -> BentFrame {
    let frame = DepthFrame::from_recording(rec, 0).expect("frame 0");
    bend_floor(&frame, &BendParams::new(angle_deg, HINGE_M)).expect("bent")
}

#[test]
fn a_bent_perfect_plane_is_the_simulators_ramp() {
    let (_flat_dir, flat) = clean(&flat_scene());
    for angle in [4.0, 16.0, 40.0] {
        let bent = bend(&flat, angle);
        let (_ramp_dir, ramp) = clean(&ramp_scene(angle));
        let expected = ramp
            .read_depth(&ramp.frames()[0])
            .expect("ramp depth readable");
        // The fitted floor is the simulator's: 0.8 m below, up = the mount's.
        let floor = bent.hinge.floor;
        let up = flat.mount().up_vector().expect("a mount");
        assert!((floor.height_m - 0.8).abs() < 2e-4, "{floor:?}");
        assert!(angle_deg(&Vector3::from(floor.up), &Vector3::from(up)) < 0.01);

        let d = flat.meta().depth;
        let (mut compared, mut worst, mut missing, mut extra) = (0, 0i32, 0, 0);
        for (i, (&got, &want)) in bent.depth.data.iter().zip(&expected.data).enumerate() {
            // Within 6 m (the mesh connects the floor's rows that far and
            // farther), away from the image border.
            let (u, v) = (i % d.width as usize, i / d.width as usize);
            let inner = u > 1 && v > 1 && u + 2 < d.width as usize && v + 2 < d.height as usize;
            if !inner || want == 0 || want > 6000 {
                if want == 0 && got != 0 && inner {
                    extra += 1;
                }
                continue;
            }
            if got == 0 {
                missing += 1;
                continue;
            }
            compared += 1;
            worst = worst.max((i32::from(got) - i32::from(want)).abs());
        }
        println!(
            "{angle}°: {compared} pixels compared, worst {worst} mm, {missing} holes, {extra} extra"
        );
        assert!(compared > 50_000, "{compared}");
        // Millimetre rounding of the source and of the output (the mesh's
        // triangles join rounded points): 1 count at most (measured: 1).
        assert!(worst <= 1, "{angle}°: worst difference {worst} mm");
        assert!(missing == 0, "{angle}°: {missing} holes in the ramp");
        assert!(
            extra == 0,
            "{angle}°: {extra} readings where the ramp shows none"
        );

        // Plane fits of the bent frame: the near floor and the ramp.
        let pts = points(&bent.depth, &flat);
        let (mut near, mut up_ramp) = (Vec::new(), Vec::new());
        for p in pts.iter().flatten() {
            let c = bent.hinge.coordinates((*p).into());
            let r = bent.hinge.ramp_coordinates((*p).into());
            if (0.6..1.4).contains(&c.ahead_m) && c.height_m.abs() < 0.01 {
                near.push(*p);
            } else if (0.1..2.0).contains(&r.ahead_m) && r.height_m.abs() < 0.01 {
                up_ramp.push(*p);
            }
        }
        assert!(near.len() > 5000 && up_ramp.len() > 5000);
        let measured = angle_deg(&fit_plane(&near).normal, &fit_plane(&up_ramp).normal);
        println!("{angle}°: measured {measured:.4}°");
        // Measured: 0.002° at 4°, 0.004° at 16°, 0.006° at 40° (the fitted
        // floor is 0.001° off the simulator's, from millimetre rounding).
        assert!(
            (measured - angle).abs() < 0.01,
            "{angle}°: the planes are {measured}° apart"
        );
        assert_eq!(bent.truth_deg, angle);
        assert_eq!(bent.meta.truth.slope_deg, Some(angle));
    }
}

#[test]
fn points_before_the_hinge_are_unchanged_and_the_same_seed_gives_the_same_bytes() {
    let (_dir, flat) = clean(&flat_scene());
    let source = flat.read_depth(&flat.frames()[0]).expect("depth");
    let bent = bend(&flat, 12.0);
    let pts = points(&source, &flat);
    let mut kept = 0;
    for (i, p) in pts.iter().enumerate() {
        if let Some(p) = p {
            if !bent.hinge.is_beyond((*p).into()) {
                kept += 1;
                assert_eq!(bent.depth.data[i], source.data[i], "pixel {i}");
            }
        }
    }
    assert!(kept > 40_000, "{kept}");
    assert_eq!(bent.stats.kept_pixels_hidden, 0);
    assert_eq!(bend(&flat, 12.0).depth, bent.depth);
}

#[test]
fn refusals_name_the_frame_and_why() {
    // A floor that ends before the hinge: a wall 1.2 m ahead.
    let (dir, wall) = clean(&{
        let mut s = ramp_scene(90.0);
        if let Some(r) = s.ramp.as_mut() {
            r.distance_m = 1.2;
            r.length_m = 3.0;
        }
        s
    });
    let frame = DepthFrame::from_recording(&wall, 0).expect("frame");
    let err = bend_floor(&frame, &BendParams::new(5.0, 1.5)).expect_err("no floor past 1.5 m");
    assert!(matches!(err, BendError::FloorShort { .. }), "{err}");
    let text = err.to_string();
    assert!(
        text.contains(&dir.path().display().to_string()) && text.contains("frame 0"),
        "{text}"
    );
    assert!(
        text.contains("1.5 m") && text.contains("--hinge-m"),
        "{text}"
    );

    // No floor at all: a camera looking straight at the wall.
    let mut scene = ramp_scene(90.0);
    scene.mount.pitch_deg = 0.0;
    scene.mount.height_m = 1.0;
    if let Some(r) = scene.ramp.as_mut() {
        r.distance_m = 0.8;
        r.length_m = 5.0;
    }
    let (_dir, facing) = clean(&scene);
    let frame = DepthFrame::from_recording(&facing, 0).expect("frame");
    let err = bend_floor(&frame, &BendParams::new(5.0, 1.5)).expect_err("no floor");
    assert!(
        matches!(
            err,
            BendError::NoFloor { .. } | BendError::FloorShort { .. }
        ),
        "{err}"
    );

    let (_dir, flat) = clean(&flat_scene());
    let frame = DepthFrame::from_recording(&flat, 0).expect("frame");
    for (angle, hinge) in [
        (0.0, 1.5),
        (-5.0, 1.5),
        (91.0, 1.5),
        (5.0, 0.0),
        (5.0, f64::NAN),
    ] {
        let err = bend_floor(&frame, &BendParams::new(angle, hinge)).expect_err("bad parameter");
        assert!(matches!(err, BendError::InvalidParameter { .. }), "{err}");
    }
    let err = DepthFrame::from_recording(&flat, 3).expect_err("one frame only");
    assert!(err.to_string().contains("no frame 3"), "{err}");
}

#[test]
fn the_program_writes_a_bent_recording_and_refuses_a_short_floor() {
    let (src_dir, _flat) = clean(&{
        let mut s = flat_scene();
        s.mount.pitch_deg = -25.0;
        s
    });
    // Two frames: both bent.
    let two = tempfile::tempdir().expect("temp dir");
    write_and_open(&flat_scene(), &SensorModel::clean(), 2, 0, two.path());
    let out_root = tempfile::tempdir().expect("temp dir");
    let out = out_root.path().join("ramp8");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_slope-bend"))
        .arg(two.path())
        .args(["--angle-deg", "8", "--hinge-m", "1.5", "-q", "-o"])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let rec = Recording::open(&out).expect("the bent recording opens");
    assert_eq!(rec.frames().len(), 2);
    assert_eq!(rec.meta().truth.slope_deg, Some(8.0));
    assert!(out.join("bend.toml").is_file());

    // The floor of a camera 0.8 m up ends at the image's top long before 60 m.
    let refused = out_root.path().join("refused");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_slope-bend"))
        .arg(src_dir.path())
        .args(["--angle-deg", "5", "--hinge-m", "80", "-o"])
        .arg(&refused)
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains(&src_dir.path().display().to_string())
            && stderr.contains("does not reach past the hinge at 80 m"),
        "{stderr}"
    );
    assert!(!refused.exists(), "nothing written for a refused frame");

    let help = std::process::Command::new(env!("CARGO_BIN_EXE_slope-bend"))
        .arg("--help")
        .output()
        .expect("runs");
    let text = String::from_utf8_lossy(&help.stdout);
    assert!(
        text.contains("Examples:") && text.contains("--angle-deg"),
        "{text}"
    );
}
