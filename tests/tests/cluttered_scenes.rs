//! The estimator in cluttered scenes rendered by `slope-synth` (Kinect v2
//! sensor model, mount known): which planes it measures, and that clutter
//! never passes for a slope. In-process: the scene is written as a
//! recording, read back with the recording reader and estimated frame by
//! frame as `slope-estimator` does.

mod scene_render;

use scene_render::{estimates, estimates_with, scene_file};
use slope_pipeline::segmentation::Proposal;
use slope_pipeline::{Estimate, EstimateStatus, EstimatorConfig};

/// Every frame `ok` and within `tol` of the signed truth.
fn assert_measures(estimates: &[Estimate], truth: f64, tol: f64) {
    for (k, e) in estimates.iter().enumerate() {
        assert_eq!(e.status, EstimateStatus::Ok, "frame {k}: {e:?}");
        assert!(
            (e.slope_deg - truth).abs() <= tol,
            "frame {k}: {} vs {truth}",
            e.slope_deg
        );
    }
}

/// Every frame reports no inclined plane: no false ramp.
fn assert_no_ramp(estimates: &[Estimate]) {
    for (k, e) in estimates.iter().enumerate() {
        assert_eq!(
            e.status,
            EstimateStatus::NoInclinedPlane,
            "frame {k}: {e:?}"
        );
    }
}

/// Every frame has a ground: the plane measured, `height_m` below the
/// camera, or, where no ground plane was seen (a table hiding the floor),
/// the mount's (`ground_from_mount`). Never none, and never a plane at
/// another height (a table top).
fn assert_ground_at(estimates: &[Estimate], height_m: f64) {
    assert!(!estimates.is_empty(), "no frames");
    for (k, e) in estimates.iter().enumerate() {
        match e.ground {
            Some(g) => {
                assert!(!e.ground_from_mount, "frame {k}: {e:?}");
                assert!(
                    (g.coefficients[3] - height_m).abs() < 0.1,
                    "frame {k}: {g:?}"
                );
            }
            None => assert!(e.ground_from_mount, "frame {k}: no ground at all: {e:?}"),
        }
    }
}

/// Every frame reports a ground plane it measured, `height_m` below the
/// camera.
fn assert_ground_seen_at(estimates: &[Estimate], height_m: f64) {
    for (k, e) in estimates.iter().enumerate() {
        assert!(e.ground.is_some(), "frame {k}: no ground plane seen: {e:?}");
    }
    assert_ground_at(estimates, height_m);
}

/// A low, wide table hides most of the floor in front of a 16 degree ramp
/// 3 m ahead: the table top is not the ground (the mount's height says so),
/// and the ramp is measured.
#[test]
fn a_table_hiding_the_floor_is_not_the_ground() {
    let e = estimates("table", &scene_file("table_hides_floor.toml"));
    assert_measures(&e, 16.0, 0.5);
    assert_ground_at(&e, 1.0);
}

/// A bed-like block 0.6 m high with a bumpy fabric cover in front of a
/// camera 1.2 m high, the floor beside it: the soft side, flat within the
/// RANSAC band (pieces of it very nearly) but not at the sensor's noise
/// level, is no slope (without `max_noise_ratio` it was reported `ok` at
/// 89-95 degrees; without `inclined_min_area_m2` a 0.027 m^2 piece was),
/// and the ground reported is the floor, not the bed top.
#[test]
fn a_bed_s_soft_side_is_not_a_slope() {
    let e = estimates("bed", &scene_file("soft_block_bed.toml"));
    assert_no_ramp(&e);
    assert_ground_seen_at(&e, 1.2);
}

/// The bed with the sequential extraction (`segmentation.proposal =
/// "sequential"`, the option): its smooth facets, flat to 5 mm, are each a
/// plane, too small or too rough at the sensor's noise level for a slope;
/// with the default cell proposal each fitted plane floods its band over
/// the neighbouring facets and the soft side is one rough plane (the test
/// above).
#[test]
fn the_sequential_extraction_takes_a_bed_s_soft_side_for_no_slope() {
    let mut config = EstimatorConfig::default();
    config.segmentation.proposal = Proposal::Sequential;
    let e = estimates_with("bed-sequential", &scene_file("soft_block_bed.toml"), config);
    assert_no_ramp(&e);
    assert_ground_seen_at(&e, 1.2);
}

/// The same bed on the left, a 12 degree ramp ahead on the right: the
/// ramp is measured (the nearer fabric side is not flat at the sensor's
/// noise level), on the floor, not on the bed top.
#[test]
fn a_ramp_beside_a_bed_is_measured_on_the_floor() {
    let e = estimates("bed_ramp", &scene_file("bed_beside_ramp.toml"));
    assert_measures(&e, 12.0, 0.5);
    assert_ground_at(&e, 1.2);
}

/// A ceiling over a flat floor faces down: never a slope.
#[test]
fn a_ceiling_is_never_a_slope() {
    let e = estimates("ceiling", &scene_file("ceiling_flat.toml"));
    assert_no_ramp(&e);
}

#[test]
fn a_flat_floor_has_no_ramp() {
    let e = estimates("flat", "[mount]\nheight_m = 0.6\npitch_deg = -25.0\n");
    assert_no_ramp(&e);
    // The floor is still reported: flat, 0.6 m below the camera.
    assert_ground_seen_at(&e, 0.6);
}

#[test]
fn a_descending_ramp_is_negative() {
    let toml = "[mount]\nheight_m = 0.5\npitch_deg = -35.0\n\n[ramp]\ndirection = \"descending\"\nslope_deg = 8.0\ndistance_m = 1.2\n";
    let e = estimates("descending", toml);
    assert_measures(&e, -8.0, 0.5);
    assert_ground_at(&e, 0.5);
}

#[test]
fn a_shallow_ramp_three_metres_away_is_measured() {
    let toml =
        "[mount]\nheight_m = 0.6\npitch_deg = -15.0\n\n[ramp]\nslope_deg = 6.0\ndistance_m = 3.0\n";
    let e = estimates("shallow", toml);
    assert_measures(&e, 6.0, 0.5);
    assert_ground_at(&e, 0.6);
}
