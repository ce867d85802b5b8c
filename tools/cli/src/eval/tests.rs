//! Unit tests of the summary, the JSON, the table and the flags.

use std::path::Path;

use clap::Parser;
use slope_ipc_types::{EstimateStatus, SlopeMethod};
use slope_pipeline::tracking::TrackedSlope;
use slope_pipeline::{Estimate, Estimator, EstimatorConfig, StageTimings};

use slope_sensor::publish::StopFlag;

use super::run::RenderNames;
use super::*;

fn ok_frame(index: u64, slope: f64, truth: Option<f64>, total_ms: f64) -> FrameResult {
    FrameResult {
        index,
        status: "ok",
        slope_deg: Some(slope),
        std_deg: Some(0.1),
        distance_m: Some(2.0),
        truth_deg: truth,
        ms: Some(Timings(StageTimings {
            total_ms,
            stages: vec![("outlier", total_ms / 2.0), ("ransac", total_ms / 4.0)],
        })),
        error: None,
        details: FrameDetails {
            confidence: Some(0.9),
            ..FrameDetails::default()
        },
    }
}

fn failed_frame(index: u64, status: EstimateStatus, ms: Option<f64>) -> FrameResult {
    FrameResult {
        index,
        status: status.name(),
        slope_deg: None,
        std_deg: None,
        distance_m: None,
        truth_deg: Some(10.0),
        ms: ms.map(|total_ms| {
            Timings(StageTimings {
                total_ms,
                stages: vec![("outlier", total_ms)],
            })
        }),
        error: None,
        details: FrameDetails::default(),
    }
}

#[test]
fn summary_compares_magnitudes_with_truth() {
    let frames = vec![
        ok_frame(0, -9.0, Some(10.0), 4.0),
        ok_frame(1, 12.0, Some(10.0), 8.0),
        ok_frame(2, 10.5, Some(10.0), 6.0),
        failed_frame(3, EstimateStatus::NoInclinedPlane, Some(1.0)),
        failed_frame(4, EstimateStatus::BadFrame, None),
    ];
    let report = MethodReport::new("r".into(), SlopeMethod::Paper, frames);
    let s = &report.summary;
    assert_eq!(report.truth_deg, Some(10.0));
    assert_eq!((s.frames, s.ok_frames), (5, 3));
    assert_eq!(s.median_slope_deg, Some(10.5));
    // |slope| = 9, 12, 10.5 -> median 10.5; error 0.5.
    assert_eq!(s.median_abs_slope_deg, Some(10.5));
    assert_eq!(s.abs_error_deg, Some(0.5));
    // Per-frame errors 1, 2, 0.5 -> median 1.
    assert_eq!(s.median_frame_error_deg, Some(1.0));
    // Totals 4, 8, 6, 1 (the unread frame has none) -> median 5.
    assert_eq!(s.median_ms, Some(5.0));
    // outlier: 2, 4, 3, 1 -> 2.5; ransac: 1, 2, 1.5 -> 1.5.
    assert_eq!(
        s.median_stage_ms.0,
        vec![("outlier".to_string(), 2.5), ("ransac".to_string(), 1.5)]
    );
    assert_eq!(s.not_ok.0, vec![("no_inclined_plane", 1), ("bad_frame", 1)]);
}

#[test]
fn low_confidence_counts_ok_frames_below_the_threshold() {
    let with_confidence = |index, confidence| {
        let mut frame = ok_frame(index, 10.0, None, 1.0);
        frame.details.confidence = confidence;
        frame
    };
    let frames = vec![
        with_confidence(0, Some(0.2)),
        with_confidence(1, Some(0.5)),
        with_confidence(2, Some(0.49)),
        with_confidence(3, None),
        // Not ok: counted under not_ok, not as low confidence.
        failed_frame(4, EstimateStatus::NoGround, Some(1.0)),
    ];
    let report = MethodReport::new("r".into(), SlopeMethod::Paper, frames);
    assert_eq!(report.summary.low_confidence_frames, 2);
    let table = table_rows(&report, 9);
    assert!(
        table.contains("low confidence (< 0.5): 2 of 4 ok frames"),
        "{table}"
    );
}

#[test]
fn details_carry_the_planes_confidence_and_track() {
    let estimate = Estimate {
        confidence: 0.3,
        confidence_reasons: slope_ipc_types::confidence::SMALL_AREA,
        tracked: Some(TrackedSlope {
            slope_deg: f64::NAN,
            std_deg: f64::NAN,
            frames: 0,
            accepted: false,
        }),
        ..ramp_estimate()
    };
    let frame = frame_result(4, Some(16.0), &estimate);
    let d = &frame.details;
    let (ground, inclined) = (estimate.ground.unwrap(), estimate.inclined.unwrap());
    assert_eq!(d.ground_plane, Some(ground.coefficients));
    assert_eq!(d.inclined_plane, Some(inclined.coefficients));
    assert_eq!(d.ground_inliers, Some(ground.inliers));
    assert_eq!(d.inclined_rms_m, Some(inclined.rms_m));
    assert_eq!(d.ground_area_m2, Some(ground.area_m2));
    assert_eq!(d.confidence, Some(0.3));
    assert_eq!(d.confidence_reasons, Some(vec!["small_area".into()]));
    assert_eq!(d.ground_from_mount, Some(false));
    let tracked = d.tracked.as_ref().unwrap();
    assert_eq!((tracked.slope_deg, tracked.frames), (None, 0));
    let json = serde_json::to_value(&frame).unwrap();
    assert_eq!(
        json["confidence_reasons"],
        serde_json::json!(["small_area"])
    );
    assert_eq!(
        json["tracked"],
        serde_json::json!({"slope_deg": null, "std_deg": null, "frames": 0, "accepted": false})
    );
    // Flattened: the details sit beside the v1 keys.
    assert!(json["ground_plane"].is_array() && json["details"].is_null());
}

/// An estimate of an analytic ramp.
fn ramp_estimate() -> Estimate {
    use slope_pipeline::fixtures::{Scene, SceneCloud};
    let mut estimator = Estimator::new(EstimatorConfig {
        method: SlopeMethod::Tls,
        ..EstimatorConfig::default()
    });
    let cloud = SceneCloud::kinect2(&Scene::ramp(16.0), 1);
    let estimate = estimator.estimate(&cloud.view());
    assert_eq!(estimate.status, EstimateStatus::Ok);
    estimate
}

#[test]
fn without_truth_or_ok_frames_the_numbers_are_absent() {
    let report = MethodReport::new(
        "r".into(),
        SlopeMethod::Tls,
        vec![ok_frame(0, 5.0, None, 1.0)],
    );
    assert_eq!(report.truth_deg, None);
    assert_eq!(report.summary.abs_error_deg, None);
    assert_eq!(report.summary.median_frame_error_deg, None);
    let failed = MethodReport::new(
        "r".into(),
        SlopeMethod::Tls,
        vec![failed_frame(0, EstimateStatus::NoGround, None)],
    );
    assert_eq!(failed.truth_deg, Some(10.0));
    assert_eq!(failed.summary.median_slope_deg, None);
    assert_eq!(failed.summary.abs_error_deg, None);
    assert_eq!(failed.summary.median_ms, None);
}

#[test]
fn per_frame_truth_gives_the_median_truth() {
    let frames = vec![
        ok_frame(0, 10.0, Some(10.0), 1.0),
        ok_frame(1, 21.0, Some(20.0), 1.0),
        ok_frame(2, 30.0, Some(30.0), 1.0),
        ok_frame(3, 40.0, Some(40.0), 1.0),
    ];
    let report = MethodReport::new("r".into(), SlopeMethod::Paper, frames);
    assert_eq!(report.truth_deg, Some(25.0));
    assert_eq!(report.summary.median_frame_error_deg, Some(0.0));
}

#[test]
fn json_has_the_documented_keys_in_order() {
    let report = MethodReport::new(
        "rec".into(),
        SlopeMethod::LeastSquares,
        vec![ok_frame(0, 5.0, None, 2.0)],
    );
    let text = serde_json::to_string(&report).unwrap();
    assert!(
        text.starts_with(
            "{\"recording\":\"rec\",\"method\":\"least-squares\",\"truth_deg\":null,\"estimates\":[{\"index\":0,\"status\":\"ok\",\"slope_deg\":5.0"
        ),
        "{text}"
    );
    assert!(
        text.contains("\"ms\":{\"total\":2.0,\"outlier\":1.0,\"ransac\":0.5}"),
        "{text}"
    );
}

#[test]
fn method_choices() {
    assert_eq!(method_choice_arg("all"), Ok(MethodChoice::All));
    assert_eq!(
        method_choice_arg("tls"),
        Ok(MethodChoice::One(SlopeMethod::Tls))
    );
    let err = method_choice_arg("magic").unwrap_err();
    assert!(err.contains("tls or all"), "{err}");
}

#[test]
fn render_names_are_unique() {
    let mut names = RenderNames::default();
    assert_eq!(names.claim(Path::new("a/ramp")), "ramp");
    assert_eq!(names.claim(Path::new("b/ramp")), "ramp-2");
    assert_eq!(names.claim(Path::new("b/wall/")), "wall");
}
#[test]
fn preset_paper_literal() {
    let args = EvalArgs::try_parse_from([
        "slope-eval",
        "rec",
        "--preset",
        "paper-literal",
        "--method",
        "tls",
        "--seed",
        "3",
    ])
    .unwrap();
    let expected = EstimatorConfig {
        method: SlopeMethod::Tls,
        seed: 3,
        ..EstimatorConfig::paper_literal()
    };
    assert_eq!(configs(&args, &StopFlag::new()).unwrap(), vec![expected]);
    let args = EvalArgs::try_parse_from(["slope-eval", "rec", "--preset", "default"]).unwrap();
    assert_eq!(
        configs(&args, &StopFlag::new()).unwrap(),
        vec![EstimatorConfig::default()]
    );
    for bad in [
        &["slope-eval", "rec", "--preset", "paper"][..],
        &[
            "slope-eval",
            "rec",
            "--preset",
            "default",
            "--config",
            "x.toml",
        ][..],
    ] {
        assert!(EvalArgs::try_parse_from(bad).is_err(), "{bad:?}");
    }
}
