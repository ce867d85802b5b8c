//! Writer -> reader round trips: metadata to the bit, depth to the count,
//! colour, per-frame truth, the exact bytes on disk, determinism, and the
//! writer's refusals.

use std::fs;
use std::path::{Path, PathBuf};

use slope_sensor::projection::Projector;
use slope_sensor::recording::{
    ColorImage, DepthImage, DepthInfo, MountInfo, PngCompression, Recording, RecordingError,
    RecordingMeta, RecordingWriter, TruthInfo,
};

fn meta(width: u32, height: u32) -> RecordingMeta {
    RecordingMeta {
        sensor: "synthetic".into(),
        depth: DepthInfo {
            width,
            height,
            unit_m: 0.0002,
            fx: 365.32,
            fy: 1.0 / 3.0 + 364.0,
            cx: 3.25,
            cy: 0.1 + 0.2,
        },
        mount: MountInfo {
            height_m: Some(0.5),
            pitch_deg: Some(-20.0),
            roll_deg: Some(1e-7),
        },
        truth: TruthInfo {
            slope_deg: Some(16.0),
        },
    }
}

/// Deterministic pseudo-random counts covering 0, 1, byte boundaries and the maximum.
fn depth_image(width: u32, height: u32, seed: u64) -> DepthImage {
    let mut state = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let data = (0..width as usize * height as usize)
        .map(|i| match i % 9 {
            0 => 0,
            1 => 1,
            2 => 255,
            3 => 256,
            4 => u16::MAX,
            _ => {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 48) as u16
            }
        })
        .collect();
    DepthImage {
        width,
        height,
        data,
    }
}

fn color_image(width: u32, height: u32, seed: u8) -> ColorImage {
    let data = (0..width as usize * height as usize)
        .map(|i| [i as u8, seed.wrapping_add((i * 7) as u8), 255 - (i as u8)])
        .collect();
    ColorImage {
        width,
        height,
        data,
    }
}

struct Written {
    depth: Vec<DepthImage>,
    color: Vec<Option<ColorImage>>,
}

/// Three frames: colour + per-frame truth; no colour, truth from [truth];
/// colour, equal timestamp, tricky truth.
fn write_sample(dir: &Path) -> Written {
    let meta = meta(7, 5);
    let depth: Vec<_> = (0..3).map(|k| depth_image(7, 5, k)).collect();
    let color = vec![Some(color_image(7, 5, 1)), None, Some(color_image(7, 5, 2))];
    let truths = [Some(12.5), None, Some(0.1 + 0.2)];
    let stamps = [0, 33_333_333, 33_333_333];
    let mut writer = RecordingWriter::create(dir, &meta, true).unwrap();
    for k in 0..3 {
        let index = writer
            .write_frame(stamps[k], &depth[k], color[k].as_ref(), truths[k])
            .unwrap();
        assert_eq!(index, k as u64);
    }
    assert_eq!(writer.finish().unwrap(), dir);
    Written { depth, color }
}

fn files_under(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                out.push((
                    path.strip_prefix(dir).unwrap().to_path_buf(),
                    fs::read(&path).unwrap(),
                ));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn everything_written_reads_back_exactly() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("rec");
    let written = write_sample(&dir);

    let rec = Recording::open(&dir).unwrap();
    assert_eq!(rec.dir(), dir);
    assert_eq!(rec.meta(), &meta(7, 5));
    assert_eq!(rec.meta().depth.cy.to_bits(), (0.1f64 + 0.2).to_bits());
    assert_eq!(rec.meta().mount.roll_deg, Some(1e-7));

    let frames = rec.frames();
    assert_eq!(frames.len(), 3);
    for (k, frame) in frames.iter().enumerate() {
        assert_eq!(frame.index, k as u64);
        assert_eq!(frame.row, k + 2);
        assert_eq!(frame.depth, PathBuf::from(format!("depth/{k:06}.png")));
        assert_eq!(rec.read_depth(frame).unwrap(), written.depth[k]);
        assert_eq!(rec.read_color(frame).unwrap(), written.color[k]);
    }
    assert_eq!(
        frames.iter().map(|f| f.timestamp_ns).collect::<Vec<_>>(),
        [0, 33_333_333, 33_333_333]
    );
    assert_eq!(frames[1].color, None);
    assert_eq!(frames[2].color, Some(PathBuf::from("color/000002.png")));

    // The per-frame column wins; an empty cell falls back to [truth].
    assert_eq!(rec.truth_deg(&frames[0]), Some(12.5));
    assert_eq!(rec.truth_deg(&frames[1]), Some(16.0));
    assert_eq!(
        rec.truth_deg(&frames[2]).map(f64::to_bits),
        Some((0.1f64 + 0.2).to_bits())
    );

    let intr = rec.intrinsics();
    assert_eq!(
        (intr.fx, intr.fy, intr.cx, intr.cy),
        (365.32, 1.0 / 3.0 + 364.0, 3.25, 0.1 + 0.2)
    );
    let mount = rec.mount();
    assert_eq!(
        (mount.height_m, mount.pitch_deg, mount.roll_deg),
        (0.5, -20.0, 1e-7)
    );
    assert_eq!(rec.projector(), Projector::new(7, 5, intr, 0.0002));
}

#[test]
fn frames_csv_and_pngs_are_as_the_spec_says() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("rec");
    let written = write_sample(&dir);

    let csv = fs::read_to_string(dir.join("frames.csv")).unwrap();
    assert_eq!(
        csv,
        "index,timestamp_ns,depth,color,slope_deg\n\
         0,0,depth/000000.png,color/000000.png,12.5\n\
         1,33333333,depth/000001.png,,\n\
         2,33333333,depth/000002.png,color/000002.png,0.30000000000000004\n"
    );
    let toml = fs::read_to_string(dir.join("recording.toml")).unwrap();
    assert!(
        toml.starts_with("format = \"slope-recording\"\nversion = 1\n"),
        "{toml}"
    );
    assert!(!dir.join("color/000001.png").exists());

    // Decode with the png crate itself: 16-bit grayscale, big-endian samples.
    let decoder = png::Decoder::new(std::io::BufReader::new(
        fs::File::open(dir.join("depth/000000.png")).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let info = reader.info();
    assert_eq!((info.width, info.height), (7, 5));
    assert_eq!(
        (info.color_type, info.bit_depth),
        (png::ColorType::Grayscale, png::BitDepth::Sixteen)
    );
    let mut bytes = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut bytes).unwrap();
    let expected: Vec<u8> = written.depth[0]
        .data
        .iter()
        .flat_map(|v| v.to_be_bytes())
        .collect();
    assert_eq!(bytes, expected);

    let decoder = png::Decoder::new(std::io::BufReader::new(
        fs::File::open(dir.join("color/000000.png")).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let info = reader.info();
    assert_eq!(
        (info.color_type, info.bit_depth),
        (png::ColorType::Rgb, png::BitDepth::Eight)
    );
    let mut bytes = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut bytes).unwrap();
    let expected: Vec<u8> = written.color[0]
        .as_ref()
        .unwrap()
        .data
        .iter()
        .flatten()
        .copied()
        .collect();
    assert_eq!(bytes, expected);
}

#[test]
fn same_input_gives_the_same_bytes() {
    let tmp = tempfile::tempdir().unwrap();
    write_sample(&tmp.path().join("a"));
    write_sample(&tmp.path().join("b"));
    let a = files_under(&tmp.path().join("a"));
    let b = files_under(&tmp.path().join("b"));
    assert_eq!(
        a.len(),
        7,
        "{:?}",
        a.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    assert_eq!(a, b);
}

#[test]
fn full_size_kinect_frames_survive_to_the_count() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("rec");
    let mut m = meta(512, 424);
    m.mount = MountInfo::default();
    m.truth = TruthInfo::default();
    let mut writer = RecordingWriter::create(&dir, &m, false).unwrap();
    let depth = depth_image(512, 424, 7);
    let color = color_image(512, 424, 9);
    writer.write_frame(5, &depth, Some(&color), None).unwrap();
    writer
        .write_frame(6, &depth_image(512, 424, 8), None, None)
        .unwrap();
    writer.finish().unwrap();

    let rec = Recording::open(&dir).unwrap();
    assert_eq!(rec.meta(), &m);
    let mount = rec.mount();
    assert!(mount.height_m.is_nan() && mount.pitch_deg.is_nan() && mount.roll_deg.is_nan());
    assert_eq!(rec.truth_deg(&rec.frames()[0]), None);
    assert_eq!(rec.read_depth(&rec.frames()[0]).unwrap(), depth);
    assert_eq!(rec.read_color(&rec.frames()[0]).unwrap(), Some(color));

    // read_depth_into reuses the buffer it is given.
    let mut image = DepthImage {
        width: 0,
        height: 0,
        data: Vec::with_capacity(512 * 424),
    };
    let before = image.data.as_ptr();
    rec.read_depth_into(&rec.frames()[1], &mut image).unwrap();
    assert_eq!(image, depth_image(512, 424, 8));
    assert_eq!(image.data.as_ptr(), before);
    rec.read_depth_into(&rec.frames()[0], &mut image).unwrap();
    assert_eq!(image, depth);
    assert_eq!(image.data.as_ptr(), before);
}

#[test]
fn every_compression_level_is_lossless() {
    let tmp = tempfile::tempdir().unwrap();
    let depth = depth_image(64, 48, 3);
    let color = color_image(64, 48, 4);
    let mut sizes = Vec::new();
    for level in [
        PngCompression::Fast,
        PngCompression::Balanced,
        PngCompression::High,
    ] {
        let dir = tmp.path().join(format!("{level:?}"));
        let mut writer = RecordingWriter::create(&dir, &meta(64, 48), false).unwrap();
        writer.set_compression(level);
        writer.write_frame(0, &depth, Some(&color), None).unwrap();
        writer.finish().unwrap();
        let rec = Recording::open(&dir).unwrap();
        assert_eq!(
            rec.read_depth(&rec.frames()[0]).unwrap(),
            depth,
            "{level:?}"
        );
        assert_eq!(
            rec.read_color(&rec.frames()[0]).unwrap(),
            Some(color.clone()),
            "{level:?}"
        );
        sizes.push(fs::metadata(dir.join("depth/000000.png")).unwrap().len());
    }
    assert!(sizes.iter().all(|&s| s > 0), "{sizes:?}");
}

#[test]
fn an_empty_recording_opens_with_no_frames() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("rec");
    RecordingWriter::create(&dir, &meta(7, 5), false)
        .unwrap()
        .finish()
        .unwrap();
    let rec = Recording::open(&dir).unwrap();
    assert!(rec.frames().is_empty());
    assert_eq!(
        fs::read_to_string(dir.join("frames.csv")).unwrap(),
        "index,timestamp_ns,depth,color\n"
    );
}

#[test]
fn the_writer_wants_an_empty_or_new_directory() {
    let tmp = tempfile::tempdir().unwrap();
    // An existing empty directory is fine.
    let empty = tmp.path().join("empty");
    fs::create_dir(&empty).unwrap();
    RecordingWriter::create(&empty, &meta(7, 5), false).unwrap();
    // Not empty any more.
    let err = RecordingWriter::create(&empty, &meta(7, 5), false).unwrap_err();
    assert!(
        matches!(&err, RecordingError::NotEmpty { path } if path == &empty),
        "{err}"
    );
    // A file.
    let file = tmp.path().join("file");
    fs::write(&file, "x").unwrap();
    let err = RecordingWriter::create(&file, &meta(7, 5), false).unwrap_err();
    assert!(matches!(err, RecordingError::NotEmpty { .. }), "{err}");
    // Nested, not yet existing.
    RecordingWriter::create(&tmp.path().join("a/b/c"), &meta(7, 5), false).unwrap();
}

#[test]
fn the_writer_refuses_metadata_a_reader_would_reject() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("rec");
    let mut bad = meta(7, 5);
    bad.depth.fx = 0.0;
    let err = RecordingWriter::create(&dir, &bad, false).unwrap_err();
    assert!(
        matches!(&err, RecordingError::InvalidKey { key, .. } if key == "depth.fx"),
        "{err}"
    );
    assert!(err.to_string().contains("recording.toml"), "{err}");
    assert!(!dir.exists(), "nothing is created for bad metadata");

    let mut bad = meta(0, 5);
    bad.depth.width = 0;
    let err = RecordingWriter::create(&dir, &bad, false).unwrap_err();
    assert!(
        matches!(&err, RecordingError::InvalidKey { key, .. } if key == "depth.width"),
        "{err}"
    );

    let mut bad = meta(7, 5);
    bad.mount.pitch_deg = Some(f64::NAN);
    let err = RecordingWriter::create(&dir, &bad, false).unwrap_err();
    assert!(
        matches!(&err, RecordingError::InvalidKey { key, .. } if key == "mount.pitch_deg"),
        "{err}"
    );
}

#[test]
fn the_writer_refuses_bad_frames_and_carries_on() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("rec");
    let mut writer = RecordingWriter::create(&dir, &meta(7, 5), false).unwrap();
    let good = depth_image(7, 5, 1);
    assert_eq!(writer.write_frame(100, &good, None, None).unwrap(), 0);

    let err = writer.write_frame(99, &good, None, None).unwrap_err();
    assert!(
        matches!(
            err,
            RecordingError::DecreasingTimestamp {
                row: 3,
                timestamp_ns: 99,
                previous: 100,
                ..
            }
        ),
        "{err}"
    );
    let err = writer.write_frame(100, &good, None, Some(5.0)).unwrap_err();
    assert!(
        matches!(err, RecordingError::NoTruthColumn { row: 3, .. }),
        "{err}"
    );
    let err = writer
        .write_frame(100, &depth_image(5, 7, 1), None, None)
        .unwrap_err();
    assert!(
        matches!(
            err,
            RecordingError::ImageSize {
                row: 3,
                found_width: 5,
                found_height: 7,
                width: 7,
                height: 5,
                ..
            }
        ),
        "{err}"
    );
    let mut short = good.clone();
    short.data.pop();
    let err = writer.write_frame(100, &short, None, None).unwrap_err();
    assert!(
        matches!(
            err,
            RecordingError::ImageData {
                expected: 35,
                found: 34,
                ..
            }
        ),
        "{err}"
    );
    let err = writer
        .write_frame(100, &good, Some(&color_image(7, 4, 0)), None)
        .unwrap_err();
    assert!(
        matches!(&err, RecordingError::ImageSize { image, .. } if image.ends_with("color/000001.png")),
        "{err}"
    );

    // Nothing of the refused frames reached the disk.
    assert!(!dir.join("depth/000001.png").exists());
    assert!(!dir.join("color").exists());
    assert_eq!(writer.frames_written(), 1);
    assert_eq!(writer.write_frame(100, &good, None, None).unwrap(), 1);
    writer.finish().unwrap();
    let rec = Recording::open(&dir).unwrap();
    assert_eq!(rec.frames().len(), 2);

    let mut writer = RecordingWriter::create(&tmp.path().join("truth"), &meta(7, 5), true).unwrap();
    let err = writer.write_frame(0, &good, None, Some(90.5)).unwrap_err();
    assert!(
        matches!(&err, RecordingError::BadRow { row: 2, reason, .. } if reason.contains("slope_deg")),
        "{err}"
    );
}

#[test]
fn csv_rows_are_flushed_as_frames_are_written() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("rec");
    let mut writer = RecordingWriter::create(&dir, &meta(7, 5), false).unwrap();
    writer
        .write_frame(0, &depth_image(7, 5, 1), None, None)
        .unwrap();
    // Readable before finish(): a recording cut short keeps its frames.
    let rec = Recording::open(&dir).unwrap();
    assert_eq!(rec.frames().len(), 1);
    assert_eq!(
        rec.read_depth(&rec.frames()[0]).unwrap(),
        depth_image(7, 5, 1)
    );
    drop(writer);
}
