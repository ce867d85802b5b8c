//! `slope-record --format mcap` beside a running chain (replay ->
//! estimator): the MCAP file holds, per recorded cloud, its depth image and
//! its cloud, and one estimate per frame stamped with that frame's capture
//! time, so that Foxglove shows them together, each followed by its
//! frame's surfaces at the same stamp.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Duration;

use serde_json::Value;
use slope_integration_tests::{replay_frames, unique_prefix, Proc};

#[test]
fn an_mcap_recording_holds_each_frame_its_estimate_and_its_surfaces() {
    let prefix = unique_prefix("record-mcap");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("run.mcap");
    let _estimator = Proc::spawn("slope-estimator", ["--service-prefix", &prefix])
        .assert_ready("estimator ready");
    let mut record = Proc::spawn(
        "slope-record",
        [
            out.to_str().expect("utf-8 path"),
            "--format",
            "mcap",
            "--service-prefix",
            &prefix,
            "--idle-timeout-s",
            "2",
        ],
    )
    .assert_ready("recording the cloud topic");
    let frames = 6u64;
    let mut replay = replay_frames(&prefix, "ramp16", 4.0, frames, 2);
    replay.assert_exits_zero_within(Duration::from_secs(60));
    record.assert_exits_zero_within(Duration::from_secs(30));

    let bytes = std::fs::read(&out).expect("the MCAP file");
    let mut stamps: BTreeMap<String, BTreeSet<u64>> = BTreeMap::new();
    let mut estimates = Vec::new();
    let mut surfaces = BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).expect("an MCAP file") {
        let message = message.expect("a message");
        let topic = message.channel.topic.clone();
        stamps
            .entry(topic.clone())
            .or_default()
            .insert(message.log_time);
        if topic == "/slope/estimate" {
            let e: Value = serde_json::from_slice(&message.data).expect("JSON");
            assert_eq!(e["timestamp_ns"].as_u64(), Some(message.log_time), "{e}");
            estimates.push(e);
        } else if topic == "/slope/surfaces" {
            let s: Value = serde_json::from_slice(&message.data).expect("JSON");
            assert_eq!(s["timestamp_ns"].as_u64(), Some(message.log_time), "{s}");
            surfaces.insert(message.log_time, s);
        }
    }
    let depth = &stamps["/slope/depth"];
    assert_eq!(depth.len() as u64, frames);
    assert_eq!(&stamps["/slope/cloud"], depth);
    // One estimate per frame (the estimator may supersede a frame on a
    // loaded machine: it then counts it), each at its frame's stamp.
    let dropped = estimates
        .last()
        .and_then(|e| e["dropped_frames"].as_u64())
        .unwrap_or(0);
    assert_eq!(estimates.len() as u64 + dropped, frames, "{estimates:?}");
    assert!(stamps["/slope/estimate"].is_subset(depth));
    for e in &estimates {
        assert_eq!(e["schema"], "slope.estimate.json/1");
        assert_eq!(e["status"], "ok", "{e}");
        // The frame's surfaces: the same frame, a ramp road whose slope is
        // the estimate's (the road's RANSAC plane, which the fit refines:
        // within 0.25 degrees, as tests/surfaces.rs bounds it).
        let stamp = e["timestamp_ns"].as_u64().expect("stamp");
        let s = surfaces
            .get(&stamp)
            .unwrap_or_else(|| panic!("no surfaces for the estimate {e}"));
        assert_eq!(s["schema"], "slope.surfaces.json/1");
        assert_eq!(s["frame"], e["frame"], "{s}");
        let road = &s["surfaces"][s["road"].as_u64().expect("a road") as usize];
        assert_eq!(road["role"], "ramp", "{s}");
        let (found, wanted) = (road["slope_deg"].as_f64(), e["slope_deg"].as_f64());
        assert!(
            (found.expect("road slope") - wanted.expect("slope")).abs() < 0.25,
            "{found:?} vs {wanted:?}"
        );
    }
    assert_eq!(
        surfaces.len(),
        estimates.len(),
        "one surfaces message an estimate"
    );
}
