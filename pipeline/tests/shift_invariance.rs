//! Metamorphic test: a frame shifted by one pixel (a column with no
//! readings added at its left edge, `cx + 1`) shows the same planes, so
//! the slope must not change much. The sample points of the image's left
//! half then fall one pixel further left on the scene
//! (`ransac_planes/sample_axis.rs` counts them from the nearer edge), and
//! the planes' borders with them. Every real frame in `shared/data`: the
//! medians over seeds 0-15 of the frame and of the shifted frame within
//! 0.4 degrees of each other (measured: 0.07-0.08 on the stair frames,
//! 0.28 on the office, whose wall is in the left half; 0.05-0.07 and 0.24
//! over seeds 0-63).

mod common;

use common::{Frame, Recording};
use slope_ipc_types::CloudPoint;
use slope_pipeline::{EstimateStatus, Estimator, EstimatorConfig};

/// Seeds the paper method is run with.
const SEEDS: std::ops::Range<u64> = 0..16;
/// Medians of a frame and its shifted copy within this, degrees.
const MAX_SHIFT_GAP_DEG: f64 = 0.4;

/// `frame` with a column of no readings before each row.
fn shifted(frame: &Frame) -> Frame {
    let mut points = Vec::with_capacity((frame.width + 1) * frame.height);
    for row in frame.points.chunks_exact(frame.width) {
        points.push(CloudPoint::INVALID);
        points.extend_from_slice(row);
    }
    let mut intrinsics = frame.intrinsics;
    intrinsics.cx += 1.0;
    Frame {
        points,
        width: frame.width + 1,
        intrinsics,
        ..frame.clone()
    }
}

/// The median of the paper method's slopes over [`SEEDS`].
fn median_slope(frame: &Frame) -> f64 {
    let mut slopes: Vec<f64> = SEEDS
        .map(|seed| {
            let config = EstimatorConfig {
                seed,
                ..EstimatorConfig::default()
            }
            .for_sensor(&frame.sensor);
            let e = Estimator::new(config).estimate(&frame.view());
            assert_eq!(e.status, EstimateStatus::Ok, "seed {seed}: {e:?}");
            e.slope_deg.abs()
        })
        .collect();
    slopes.sort_by(f64::total_cmp);
    0.5 * (slopes[SEEDS.end as usize / 2 - 1] + slopes[SEEDS.end as usize / 2])
}

fn check_shared(name: &str) {
    let Some(dir) = common::shared_data(name) else {
        return;
    };
    let rec = Recording::open(&dir).expect("recording");
    let frame = rec.frame(0).expect("frame 0");
    let (given, moved) = (median_slope(&frame), median_slope(&shifted(&frame)));
    println!("{name}: median {given:.3}, shifted one pixel {moved:.3}");
    assert!(
        (given - moved).abs() <= MAX_SHIFT_GAP_DEG,
        "{name}: median {given:.3}, shifted one pixel {moved:.3}"
    );
}

#[test]
fn stairs_front_shifted() {
    check_shared("kinect2-stairs-front");
}

#[test]
fn stairs_top_shifted() {
    check_shared("kinect2-stairs-top");
}

#[test]
fn office_shifted() {
    check_shared("kinect1-office");
}
