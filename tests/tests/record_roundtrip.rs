//! `slope-record` from the cloud topic of `slope-replay` gives back the
//! source recording: depth to the millimetre (here: exactly, count for
//! count), colour, intrinsics, mount, timestamps and the sensor's name. Real processes over
//! iceoryx2, each test under its own service prefix.

use std::path::Path;

use slope_integration_tests::{deadline, shared_data, unique_prefix, Proc};
use slope_sensor::recording::{
    ColorImage, DepthImage, DepthInfo, MountInfo, Recording, RecordingMeta, RecordingWriter,
    TruthInfo,
};

/// A small recording with depth over the sensor's whole range (and beyond),
/// holes, colour and a mount, said to be from a Kinect v1: neither of the
/// names the recorder falls back to ("kinect2" for a camera, "replay").
fn write_source(dir: &Path) {
    let (width, height) = (160u32, 120u32);
    let meta = RecordingMeta {
        sensor: "kinect1".into(),
        depth: DepthInfo {
            width,
            height,
            unit_m: 0.001,
            fx: 140.3,
            fy: 139.7,
            cx: 79.3,
            cy: 61.8,
        },
        mount: MountInfo {
            height_m: Some(0.5),
            pitch_deg: Some(-20.0),
            roll_deg: Some(1.5),
        },
        truth: TruthInfo::default(),
    };
    let mut writer = RecordingWriter::create(dir, &meta, false).expect("source writer");
    for frame in 0..6u32 {
        let mut depth = DepthImage::new(width, height);
        let mut color = ColorImage::new(width, height);
        for (i, (d, c)) in depth.data.iter_mut().zip(color.data.iter_mut()).enumerate() {
            let i = i as u32;
            *d = if (i + frame).is_multiple_of(17) {
                0
            } else {
                // 0.3 m .. 12.3 m, every millimetre value class represented.
                (300 + (i * 7919 + frame * 104_729) % 12_000) as u16
            };
            *c = [(i % 251) as u8, (frame * 40) as u8, (i / 251 % 256) as u8];
        }
        let stamp = u64::from(frame) * 33_333_333;
        writer
            .write_frame(stamp, &depth, Some(&color), None)
            .expect("source frame");
    }
    writer.finish().expect("source finish");
}

/// Records the topic while replaying `source`, returns the recorder's output dir.
fn record_replay_of(source: &Path, out: &Path, test: &str) {
    let prefix = unique_prefix(test);
    let out_arg = out.to_str().expect("utf-8 temp path");
    let mut recorder = Proc::spawn(
        "slope-record",
        [
            out_arg,
            "--service-prefix",
            &prefix,
            "--idle-timeout-s",
            "3",
            "--wait-timeout-s",
            "60",
        ],
    );
    let ready = recorder.wait_stderr("recording the cloud topic", deadline(30.0));
    assert!(ready.is_some(), "{}", recorder.diagnostics());

    let mut replay = Proc::spawn(
        "slope-replay",
        [
            source.to_str().expect("utf-8 path"),
            "--service-prefix",
            &prefix,
            "--wait-subscribers",
            "1",
            "--wait-timeout-s",
            "30",
            // Slow enough that the recorder (PNG encoding) never falls behind.
            "--rate",
            "10",
        ],
    );
    let replayed = replay.wait_exit(deadline(60.0));
    let replay_diag = replay.diagnostics();
    let replayed = replayed.unwrap_or_else(|| panic!("slope-replay did not finish\n{replay_diag}"));
    assert!(replayed.success(), "slope-replay failed\n{replay_diag}");

    let recorded = recorder.wait_exit(deadline(30.0));
    let diag = recorder.diagnostics();
    let recorded = recorded.unwrap_or_else(|| panic!("slope-record did not finish\n{diag}"));
    assert!(recorded.success(), "slope-record failed\n{diag}");
    assert!(
        !diag.contains("clouds were missed"),
        "the recorder missed clouds; the comparison would be meaningless\n{diag}"
    );
}

fn assert_same_recording(source: &Path, copy: &Path) {
    let src = Recording::open(source).expect("source opens");
    let dst = Recording::open(copy).expect("the recorded copy opens");
    assert_eq!(dst.frames().len(), src.frames().len(), "frame count");
    assert_eq!(dst.meta().depth, src.meta().depth, "[depth]");
    assert_eq!(dst.meta().mount, src.meta().mount, "[mount]");
    assert_eq!(dst.meta().sensor, src.meta().sensor, "sensor");
    let first_src = src.frames()[0].timestamp_ns;
    for (a, b) in src.frames().iter().zip(dst.frames()) {
        assert_eq!(
            b.timestamp_ns,
            a.timestamp_ns - first_src,
            "timestamp of frame {}",
            a.index
        );
        let (da, db) = (
            src.read_depth(a).expect("source depth"),
            dst.read_depth(b).expect("copied depth"),
        );
        let differing = da.data.iter().zip(&db.data).filter(|(x, y)| x != y).count();
        assert_eq!(
            differing, 0,
            "frame {}: {differing} depth pixels differ",
            a.index
        );
        // A point without depth carries no colour in the cloud, so the copy
        // has colour exactly where there is depth, and black elsewhere.
        let (ca, cb) = (
            src.read_color(a).expect("source colour"),
            dst.read_color(b).expect("copied colour"),
        );
        match (ca, cb) {
            (None, None) => {}
            (Some(ca), Some(cb)) => {
                assert_eq!((cb.width, cb.height), (ca.width, ca.height));
                let wrong = da
                    .data
                    .iter()
                    .zip(ca.data.iter().zip(&cb.data))
                    .filter(|(&d, (x, y))| if d == 0 { **y != [0, 0, 0] } else { x != y })
                    .count();
                assert_eq!(wrong, 0, "frame {}: {wrong} colour pixels differ", a.index);
            }
            (ca, cb) => panic!(
                "frame {}: source has colour {}, copy has colour {}",
                a.index,
                ca.is_some(),
                cb.is_some()
            ),
        }
    }
}

#[test]
fn recording_the_topic_of_a_replay_gives_back_the_recording() {
    let work = tempfile::tempdir().expect("tempdir");
    let source = work.path().join("source");
    write_source(&source);
    let copy = work.path().join("copy");
    record_replay_of(&source, &copy, "record-synthetic");
    assert_same_recording(&source, &copy);
}

#[test]
fn recording_a_replayed_kinect_frame_keeps_its_depth_to_the_millimetre() {
    let Some(source) = shared_data("kinect2-stairs-front") else {
        return;
    };
    let work = tempfile::tempdir().expect("tempdir");
    let copy = work.path().join("copy");
    record_replay_of(&source, &copy, "record-kinect");
    assert_same_recording(&source, &copy);
    // The copy replays again: its own recording.toml is valid for slope-replay.
    let again = Recording::open(&copy).expect("copy opens");
    assert!(again.read_depth(&again.frames()[0]).is_ok());
}
