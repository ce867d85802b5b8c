//! The unit tests of `slope-record`.

use std::path::Path;

use slope_ipc_types::{CloudHeader, CloudPoint, CloudSource, Intrinsics, Mount};
use slope_sensor::projection::Projector;
use slope_sensor::publish::StopFlag;
use slope_sensor::recording::{DepthImage, Recording, RecordingWriter};
use slope_sensor::source::{FrameSource, RecordingSource, SourceInfo};

use super::sink::Sink;
use super::timeline::Timeline;
use super::*;
use crate::cli::OutputArgs;

#[test]
fn an_output_named_mcap_is_an_mcap_file_unless_told_otherwise() {
    let format = |args: &[&str]| {
        RecordArgs::try_parse_checked_from(["slope-record"].iter().chain(args))
            .expect("valid arguments")
            .format()
    };
    assert_eq!(format(&["-o", "new.mcap"]), RecordFormat::Mcap);
    assert_eq!(format(&["run.MCAP"]), RecordFormat::Mcap);
    assert_eq!(format(&["-o", "scene1"]), RecordFormat::Recording);
    assert_eq!(format(&["-o", "x", "--format", "mcap"]), RecordFormat::Mcap);
    let told = ["-o", "new.mcap", "--format", "recording"];
    assert_eq!(format(&told), RecordFormat::Recording);
}

#[test]
fn depth_from_a_projected_cloud_is_the_original_to_the_count() {
    let intrinsics = Intrinsics {
        fx: 365.3,
        fy: 365.3,
        cx: 254.7,
        cy: 208.6,
    };
    let (width, height) = (64u32, 48u32);
    let projector = Projector::new(width, height, intrinsics, 0.001);
    let original: Vec<u16> = (0..width * height)
        .map(|i| {
            if i.is_multiple_of(13) {
                0
            } else {
                400 + ((i * 7919) % 11_000) as u16
            }
        })
        .collect();
    let points: Vec<CloudPoint> = original
        .iter()
        .enumerate()
        .map(|(i, &d)| projector.point(i, d, CloudPoint::pack_rgb(1, 2, (i % 256) as u8)))
        .collect();
    let header = CloudHeader {
        width,
        height,
        intrinsics,
        has_color: 1,
        ..CloudHeader::default()
    };
    let mut depth = DepthImage::default();
    let mut color = None;
    cloud_to_images(&header, &points, 0.001, &mut depth, &mut color);
    assert_eq!(depth.data, original);
    let color = color.expect("colour");
    // A point without depth carries no colour.
    for (i, (rgb, d)) in color.data.iter().zip(&original).enumerate() {
        let expected = if *d == 0 {
            [0, 0, 0]
        } else {
            [1, 2, (i % 256) as u8]
        };
        assert_eq!(*rgb, expected, "pixel {i}");
    }
}

#[test]
fn recording_a_source_reproduces_it() {
    let Some(src) = slope_test_support::shared_data("kinect2-stairs-front") else {
        return;
    };
    let recording = Recording::open(&src).expect("source recording");
    let expected = recording.read_depth(&recording.frames()[0]).expect("depth");
    let mut source = RecordingSource::new(recording, false);
    let out = tempfile::tempdir().expect("tempdir");
    let dir = out.path().join("copy");
    let mut writer =
        RecordingWriter::create(&dir, &meta_for(source.info()), false).expect("writer");
    let stats = record_source(
        &mut source,
        &mut writer,
        &RecordLimits::default(),
        &StopFlag::new(),
    )
    .expect("record");
    writer.finish().expect("finish");
    assert_eq!(stats.written, 1);
    let copy = Recording::open(&dir).expect("copy");
    assert_eq!(copy.intrinsics(), source.info().intrinsics);
    assert_eq!(copy.read_depth(&copy.frames()[0]).expect("depth"), expected);
}

#[test]
fn the_recorded_sensor_is_the_headers_else_the_source_kind() {
    let mut header = CloudHeader {
        source: CloudSource::Replay as u32,
        ..CloudHeader::default()
    };
    assert_eq!(sensor_of(&header), "replay");
    header.set_sensor_name("kinect1");
    assert_eq!(sensor_of(&header), "kinect1");
    header.source = CloudSource::Camera as u32;
    assert_eq!(sensor_of(&header), "kinect1");
    header.set_sensor_name("");
    assert_eq!(sensor_of(&header), "kinect2");
}

#[test]
fn timestamps_start_at_zero_and_continue_across_a_jump_back() {
    let mut timeline = Timeline::new();
    assert_eq!(timeline.stamp(1_000), 0);
    assert_eq!(timeline.stamp(34_000), 33_000);
    // Back in time: one previous interval on, not frozen.
    assert_eq!(timeline.stamp(20_000), 66_000);
    // Then following the source again from there.
    assert_eq!(timeline.stamp(70_000), 116_000);
    assert_eq!(timeline.stamp(70_000), 116_000);
    assert_eq!(timeline.stamp(u64::MAX), u64::MAX);
    assert_eq!(timeline.stamp(0), u64::MAX);
}

#[test]
fn depth_that_a_count_cannot_hold_is_no_reading() {
    let at = |z_m: f32| CloudPoint {
        x_m: 0.0,
        y_m: 0.0,
        z_m,
        rgb: 0,
    };
    assert_eq!(depth_count(&at(1.2344), 0.001), 1234);
    assert_eq!(depth_count(&at(65.535), 0.001), 65_535);
    assert_eq!(depth_count(&at(65.6), 0.001), 0);
    assert_eq!(depth_count(&at(1e30), 0.001), 0);
    assert_eq!(depth_count(&at(-1.0), 0.001), 0);
    assert_eq!(depth_count(&at(0.0004), 0.001), 0);
    assert_eq!(depth_count(&CloudPoint::INVALID, 0.001), 0);
}

#[test]
fn the_output_directory_is_checked_before_waiting() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let fresh = tmp.path().join("a/b");
    // A missing parent (a typing error) is refused, and nothing made.
    let message = prepare_out_dir(&fresh).expect_err("no a/").to_string();
    assert!(
        message.contains("the directory") && message.contains("does not exist"),
        "{message}"
    );
    assert!(!tmp.path().join("a").exists());
    // A parent that is a file is said to be one ("does not exist" misled).
    std::fs::write(tmp.path().join("file"), b"x").expect("file");
    let message = prepare_out_dir(&tmp.path().join("file/rec"))
        .expect_err("under a file")
        .to_string();
    assert!(
        message.contains("file is not a directory (a file is there)"),
        "{message}"
    );
    std::fs::create_dir(tmp.path().join("a")).expect("mkdir a");
    assert!(prepare_out_dir(&fresh).expect("created"));
    assert!(fresh.is_dir());
    assert!(!prepare_out_dir(&fresh).expect("empty is fine"));
    std::fs::write(fresh.join("x"), b"x").expect("file");
    let message = prepare_out_dir(&fresh).expect_err("not empty").to_string();
    assert!(message.contains("not empty"), "{message}");
    assert!(prepare_out_dir(&fresh.join("x")).is_err());
}

/// A recording that failed says what is left: its first frame failed
/// (a full disk), so the directory it made is removed; or the frames
/// before the failure, readable.
#[test]
fn a_failed_recording_says_what_it_left() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("rec");
    let info = SourceInfo {
        width: 2,
        height: 2,
        intrinsics: Intrinsics {
            fx: 1.0,
            fy: 1.0,
            cx: 0.5,
            cy: 0.5,
        },
        unit_m: 0.001,
        mount: Mount::UNKNOWN,
        source: CloudSource::Replay,
        has_color: false,
        sensor: "kinect2".into(),
    };
    // Its recording.toml and frames.csv header, no frame.
    RecordingWriter::create(&dir, &meta_for(&info), false).expect("create");
    let failure = || anyhow::anyhow!("cannot write frame 0: No space left on device");
    let message = format!("{:#}", explain_failure(failure(), &dir, true));
    assert!(message.contains("no frame was recorded; ") && message.contains("was removed"));
    assert!(message.contains("No space left on device"), "{message}");
    assert!(!dir.exists());

    let mut writer = RecordingWriter::create(&dir, &meta_for(&info), false).expect("again");
    let depth = DepthImage {
        width: 2,
        height: 2,
        data: vec![1000; 4],
    };
    for stamp in [0, 1] {
        writer
            .write_frame(stamp, &depth, None, None)
            .expect("frame");
    }
    let message = format!("{:#}", explain_failure(failure(), &dir, true));
    assert!(
        message.contains("holds the 2 frame(s) recorded before"),
        "{message}"
    );
    assert!(dir.join("frames.csv").is_file());
    // A directory the user gave (not made here) is left as it is.
    drop(writer);
    let message = format!("{:#}", explain_failure(failure(), tmp.path(), false));
    assert_eq!(message, "cannot write frame 0: No space left on device");
}

/// `--format mcap` stores the sensor of the clouds (the header's) and
/// their intrinsics as the file's `slope.recording` metadata.
#[test]
fn an_mcap_recording_names_its_sensor() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("run.mcap");
    let args = RecordArgs::try_parse_checked_from(["slope-record", out.to_str().expect("utf-8")])
        .expect("args");
    let info = SourceInfo {
        width: 4,
        height: 3,
        intrinsics: Intrinsics {
            fx: 365.25,
            fy: 366.0,
            cx: 1.5,
            cy: 1.0,
        },
        unit_m: TOPIC_DEPTH_UNIT_M,
        mount: Mount::UNKNOWN,
        source: CloudSource::Camera,
        has_color: false,
        sensor: "kinect1".into(),
    };
    Sink::create(&args, &info)
        .expect("sink")
        .finish(&out)
        .expect("finish");
    let bytes = std::fs::read(&out).expect("the MCAP file");
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("a finished file");
    let [index] = &summary.metadata_indexes[..] else {
        panic!("one metadata record: {:?}", summary.metadata_indexes);
    };
    let metadata = mcap::read::metadata(&bytes, index).expect("metadata");
    assert_eq!(metadata.name, "slope.recording");
    let value = |key: &str| metadata.metadata.get(key).map(String::as_str);
    assert_eq!(value("sensor"), Some("kinect1"));
    assert_eq!((value("width"), value("height")), (Some("4"), Some("3")));
    assert_eq!((value("fx"), value("fy")), (Some("365.25"), Some("366")));
    assert_eq!((value("cx"), value("cy")), (Some("1.5"), Some("1")));
    assert_eq!(
        value("mount_pitch_deg"),
        None,
        "an unknown mount is left out"
    );
}

#[test]
fn zero_frames_is_refused_and_the_pipeline_is_parsed_early() {
    let parse = |args: &[&str]| {
        RecordArgs::try_parse_checked_from(
            std::iter::once("slope-record").chain(args.iter().copied()),
        )
    };
    let kind = |args: &[&str]| parse(args).expect_err("refused").kind();
    assert_eq!(
        kind(&["out", "--max-frames", "0"]),
        clap::error::ErrorKind::ValueValidation
    );
    let zero = parse(&["out", "--max-frames", "0"]).expect_err("refused");
    assert!(
        zero.to_string().contains(crate::cli::MAX_FRAMES_ZERO),
        "{zero}"
    );
    assert!(parse(&["out", "--max-frames", "1"]).is_ok());
    let flag = parse(&["-o", "out1"]).expect("-o");
    assert_eq!(flag.out_dir(), Path::new("out1"));
    let positional = parse(&["out2"]).expect("positional");
    assert_eq!(positional.out_dir(), Path::new("out2"));
    assert_eq!(
        kind(&[]),
        clap::error::ErrorKind::MissingRequiredArgument,
        "no output"
    );
    assert_eq!(
        kind(&["-o", "a", "b"]),
        clap::error::ErrorKind::ArgumentConflict,
        "two outputs"
    );
    #[cfg(feature = "kinect2")]
    {
        assert_eq!(
            kind(&["out", "--pipeline", "vulkan"]),
            clap::error::ErrorKind::ValueValidation
        );
        let args = parse(&["out", "--pipeline", "cpu"]).expect("args");
        assert_eq!(args.pipeline, Some(slope_sensor::kinect2::Pipeline::Cpu));
    }
}
