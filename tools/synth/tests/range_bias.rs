//! The range bias (`[sensor] range_bias`, `--range-bias`) is really in the
//! recording: a clean flat floor read through it lies `c z` below the truth
//! at depth `z` (Kinect v2 `c = 0.005`, Kinect v1 `c = 0.01`), measured on
//! every floor reading and on planes fitted to the floor near (1.0-1.5 m)
//! and far (3.5-4.5 m). The coefficients are tied to the pipeline's
//! `NoiseModel::floor_height_bias_m` in `tests/tests/real_scene_rules.rs`.

mod common;

use common::{angle_deg, fit_plane, frame, write_and_open};
use nalgebra::Vector3;
use slope_synth::{MountPose, RangeBias, Scene, SensorModel};

const HEIGHT_M: f64 = 1.2;
const PITCH_DEG: f64 = -30.0;

/// The floor's readings of a clean flat floor read with `bias`: (true depth,
/// world point as read).
fn floor_readings(bias: RangeBias) -> Vec<(f64, Vector3<f64>)> {
    let scene = Scene {
        mount: MountPose {
            height_m: HEIGHT_M,
            pitch_deg: PITCH_DEG,
            ..MountPose::default()
        },
        ..Scene::default()
    };
    let model = SensorModel {
        range_bias: bias,
        ..SensorModel::clean()
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let rec = write_and_open(&scene, &model, 1, 0, dir.path());
    let f = frame(&rec, &scene, &model, 0, 0);
    let width = f.depth.width;
    let k = bias.depth_coefficient_per_m(HEIGHT_M);
    let mut out = Vec::new();
    for (i, &count) in f.depth.data.iter().enumerate() {
        if count == 0 {
            continue;
        }
        let (u, v) = (i as u32 % width, i as u32 / width);
        let z_read = f64::from(count) * 1e-3;
        // The true depth: the root of z + k z^2 = z_read.
        let z_true = if k == 0.0 {
            z_read
        } else {
            ((1.0 + 4.0 * k * z_read).sqrt() - 1.0) / (2.0 * k)
        };
        let exact = f.geometry.get(u, v).expect("a reading has a hit");
        assert!(
            (exact.z_m - z_true).abs() < 1e-3,
            "pixel ({u}, {v}): read {z_read}, true {}",
            exact.z_m
        );
        out.push((z_true, common::world_point(&f.camera, u, v, z_read)));
    }
    out
}

/// The plane of the readings whose true depth lies in `[from, to)`.
fn piece(readings: &[(f64, Vector3<f64>)], from: f64, to: f64) -> (common::Plane, f64) {
    let points: Vec<_> = readings
        .iter()
        .filter(|(z, _)| (from..to).contains(z))
        .map(|(_, p)| *p)
        .collect();
    assert!(
        points.len() > 1000,
        "{} points in {from}-{to} m",
        points.len()
    );
    let centroid_height = points.iter().map(|p| p.z).sum::<f64>() / points.len() as f64;
    (fit_plane(&points), centroid_height)
}

#[test]
fn a_biased_floor_lies_c_z_below_the_truth_near_and_far() {
    let up = Vector3::z();
    let (sp, cp) = PITCH_DEG.to_radians().sin_cos();
    for bias in [RangeBias::None, RangeBias::Kinect2, RangeBias::Kinect1] {
        let c = bias.height_bias_per_m();
        let readings = floor_readings(bias);
        // Every reading: its height is -c z (to the millimetre's rounding
        // along the ray, at most 0.5 mm).
        let worst = readings
            .iter()
            .map(|(z, p)| (p.z + bias.floor_height_bias_m(*z)).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.6e-3, "{}: {worst} m off c z", bias.name());
        // Near and far pieces: the far one is c z below, and both are the
        // same plane turned by atan(c cos p / (1 + c sin p)) against the
        // truth; the bend between them stays far below the pipeline's
        // floor_bend_deg (1.0 + 0.3 z, 4.0).
        let (near, near_height) = piece(&readings, 1.0, 1.5);
        let (far, far_height) = piece(&readings, 3.5, 4.5);
        let tilt = (c * cp / (1.0 + c * sp)).atan().to_degrees();
        let bend = angle_deg(&near.normal, &far.normal);
        println!(
            "{}: near {near_height:.4} m, far {far_height:.4} m, tilt near {:.3} far {:.3} (model {tilt:.3}), bend {bend:.3} deg",
            bias.name(),
            angle_deg(&near.normal, &up),
            angle_deg(&far.normal, &up)
        );
        for (plane, name) in [(&near, "near"), (&far, "far")] {
            assert!(
                (angle_deg(&plane.normal, &up) - tilt).abs() < 0.05,
                "{} {name}: {plane:?}",
                bias.name()
            );
        }
        assert!(bend < 0.05, "{}: bend {bend}", bias.name());
        // The pieces' mean heights: c times their mean true depth below.
        for (from, to, height) in [(1.0, 1.5, near_height), (3.5, 4.5, far_height)] {
            let depths: Vec<f64> = readings
                .iter()
                .map(|(z, _)| *z)
                .filter(|z| (from..to).contains(z))
                .collect();
            let mean_z = depths.iter().sum::<f64>() / depths.len() as f64;
            assert!(
                (height + c * mean_z).abs() < 0.5e-3,
                "{}: {height} at {mean_z} m",
                bias.name()
            );
        }
        if bias == RangeBias::Kinect1 {
            // 4 m ahead: 4 cm below the truth.
            assert!(far_height < -0.035 && far_height > -0.045, "{far_height}");
        }
    }
}

#[test]
fn no_bias_leaves_the_recording_unchanged() {
    let scene = Scene::default_ramp();
    let dir = tempfile::tempdir().expect("temp dir");
    let explicit = SensorModel {
        range_bias: RangeBias::None,
        ..SensorModel::default()
    };
    let a = write_and_open(&scene, &SensorModel::default(), 2, 3, &dir.path().join("a"));
    let b = write_and_open(&scene, &explicit, 2, 3, &dir.path().join("b"));
    for (fa, fb) in a.frames().iter().zip(b.frames()) {
        assert_eq!(
            a.read_depth(fa).expect("a").data,
            b.read_depth(fb).expect("b").data
        );
    }
}

#[test]
fn a_scene_file_sets_the_bias_and_can_leave_the_mount_out() {
    let file = slope_synth::parse_scene(
        "[mount]\nrecorded = false\n[sensor]\nrange_bias = \"kinect1\"\n",
        "s.toml".as_ref(),
    )
    .expect("valid");
    assert_eq!(
        file.sensor.expect("a sensor table").range_bias,
        RangeBias::Kinect1
    );
    let meta = slope_synth::recording_meta(&file.scene);
    assert_eq!(meta.mount, Default::default());
    let err = slope_synth::parse_scene("[sensor]\nrange_bias = \"kinect3\"\n", "s.toml".as_ref())
        .expect_err("unknown bias");
    assert!(err.to_string().contains("s.toml"), "{err}");
}
