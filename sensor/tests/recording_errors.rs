//! Every error the spec asks a reader to report, on broken recordings
//! written into temporary directories: the right variant, naming the file
//! and the row or key.

use std::fs;
use std::path::{Path, PathBuf};

use slope_sensor::recording::{
    ColorImage, DepthImage, DepthInfo, MountInfo, Recording, RecordingError, RecordingMeta,
    RecordingWriter, TruthInfo,
};

const W: u32 = 4;
const H: u32 = 3;

/// A valid recording of two frames (colour on the first) in `tmp/rec`.
fn base(tmp: &tempfile::TempDir) -> PathBuf {
    let dir = tmp.path().join("rec");
    let meta = RecordingMeta {
        sensor: "synthetic".into(),
        depth: DepthInfo {
            width: W,
            height: H,
            unit_m: 0.001,
            fx: 365.0,
            fy: 365.0,
            cx: 1.5,
            cy: 1.0,
        },
        mount: MountInfo::default(),
        truth: TruthInfo {
            slope_deg: Some(16.0),
        },
    };
    let depth = DepthImage {
        width: W,
        height: H,
        data: (1..=(W * H) as u16).collect(),
    };
    let color = ColorImage {
        width: W,
        height: H,
        data: vec![[1, 2, 3]; (W * H) as usize],
    };
    let mut writer = RecordingWriter::create(&dir, &meta, false).unwrap();
    writer.write_frame(0, &depth, Some(&color), None).unwrap();
    writer.write_frame(10, &depth, None, None).unwrap();
    writer.finish().unwrap();
    dir
}

fn edit(dir: &Path, file: &str, from: &str, to: &str) {
    let path = dir.join(file);
    let text = fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "{from:?} not in {text}");
    fs::write(&path, text.replacen(from, to, 1)).unwrap();
}

fn open_err(dir: &Path) -> RecordingError {
    match Recording::open(dir) {
        Ok(_) => panic!("{} opened although it is broken", dir.display()),
        Err(e) => e,
    }
}

fn assert_names(err: &RecordingError, parts: &[&str]) {
    let text = err.to_string();
    for part in parts {
        assert!(text.contains(part), "{text:?} does not name {part:?}");
    }
}

fn png_bytes(width: u32, height: u32, color: png::ColorType, depth: png::BitDepth) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(color);
    encoder.set_depth(depth);
    let samples = color.samples() * (depth as usize).div_ceil(8);
    let data = vec![7u8; width as usize * height as usize * samples];
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(&data).unwrap();
    writer.finish().unwrap();
    out
}

// ---------------------------------------------------------------- recording.toml

#[test]
fn missing_files_are_named() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    fs::remove_file(dir.join("frames.csv")).unwrap();
    let err = open_err(&dir);
    assert!(
        matches!(&err, RecordingError::Read { path, .. } if path.ends_with("frames.csv")),
        "{err}"
    );
    assert_names(&err, &["frames.csv"]);

    // Without recording.toml it is no recording at all: the error says so
    // and names the directory.
    fs::remove_file(dir.join("recording.toml")).unwrap();
    let err = open_err(&dir);
    assert!(
        matches!(&err, RecordingError::NotARecording { dir: d } if *d == dir),
        "{err}"
    );
    assert_names(&err, &["recording.toml", "not a recording directory"]);

    let missing = tmp.path().join("no-such-recording");
    let err = open_err(&missing);
    assert!(matches!(err, RecordingError::NotARecording { .. }), "{err}");
}

#[test]
fn unreadable_toml_is_reported() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    edit(&dir, "recording.toml", "[depth]", "[depth");
    let err = open_err(&dir);
    assert!(
        matches!(err, RecordingError::Toml { at: Some(_), .. }),
        "{err}"
    );
    assert_names(&err, &["recording.toml", "not valid TOML: "]);
    // One line: the parser's message, not its source snippet.
    assert!(!err.to_string().contains('\n'), "{err}");
}

#[test]
fn wrong_format_and_unknown_version_are_rejected() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    edit(
        &dir,
        "recording.toml",
        "\"slope-recording\"",
        "\"tum-rgbd\"",
    );
    let err = open_err(&dir);
    assert!(
        matches!(&err, RecordingError::WrongFormat { found, .. } if found == "tum-rgbd"),
        "{err}"
    );
    assert_names(&err, &["recording.toml", "tum-rgbd"]);

    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    edit(&dir, "recording.toml", "version = 1", "version = 2");
    let err = open_err(&dir);
    assert!(
        matches!(err, RecordingError::UnknownVersion { found: 2, .. }),
        "{err}"
    );
    assert_names(&err, &["recording.toml", "version"]);

    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    edit(&dir, "recording.toml", "version = 1", "version = \"1\"");
    let err = open_err(&dir);
    assert!(
        matches!(&err, RecordingError::InvalidKey { key, .. } if key == "version"),
        "{err}"
    );
}

#[test]
fn missing_required_keys_are_named() {
    let cases = [
        ("format = \"slope-recording\"\n", "format"),
        ("version = 1\n", "version"),
        ("fx = 365.0\n", "depth.fx"),
        ("fy = 365.0\n", "depth.fy"),
        ("cx = 1.5\n", "depth.cx"),
        ("cy = 1.0\n", "depth.cy"),
        ("unit_m = 0.001\n", "depth.unit_m"),
        ("width = 4\n", "depth.width"),
        ("height = 3\n", "depth.height"),
    ];
    for (line, key) in cases {
        let tmp = tempfile::tempdir().unwrap();
        let dir = base(&tmp);
        edit(&dir, "recording.toml", line, "");
        let err = open_err(&dir);
        assert!(
            matches!(&err, RecordingError::MissingKey { key: k, .. } if k == key),
            "{key}: {err}"
        );
        assert_names(&err, &["recording.toml", key]);
    }
    // The whole [depth] table.
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    let text = fs::read_to_string(dir.join("recording.toml")).unwrap();
    let start = text.find("[depth]").unwrap();
    let end = text[start..].find("\n\n").map_or(text.len(), |e| start + e);
    fs::write(
        dir.join("recording.toml"),
        format!("{}{}", &text[..start], &text[end..]),
    )
    .unwrap();
    let err = open_err(&dir);
    assert!(
        matches!(&err, RecordingError::MissingKey { key, .. } if key == "depth"),
        "{err}"
    );
}

#[test]
fn impossible_values_are_named() {
    let cases = [
        ("width = 4", "width = 0", "depth.width"),
        ("width = 4", "width = -4", "depth.width"),
        ("height = 3", "height = 0", "depth.height"),
        ("unit_m = 0.001", "unit_m = -0.001", "depth.unit_m"),
        ("unit_m = 0.001", "unit_m = 0.0", "depth.unit_m"),
        ("fx = 365.0", "fx = 0.0", "depth.fx"),
        ("fy = 365.0", "fy = -365.0", "depth.fy"),
        ("fy = 365.0", "fy = nan", "depth.fy"),
        ("cx = 1.5", "cx = inf", "depth.cx"),
        ("fx = 365.0", "fx = \"365\"", "depth.fx"),
        ("slope_deg = 16.0", "slope_deg = 120.0", "truth.slope_deg"),
        ("[depth]", "depth = 3\n[other]", "depth"),
    ];
    for (from, to, key) in cases {
        let tmp = tempfile::tempdir().unwrap();
        let dir = base(&tmp);
        edit(&dir, "recording.toml", from, to);
        let err = open_err(&dir);
        assert!(
            matches!(&err, RecordingError::InvalidKey { key: k, .. } if k == key),
            "{to}: {err}"
        );
        assert_names(&err, &["recording.toml", key]);
    }
}

#[test]
fn unknown_keys_are_ignored() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    edit(
        &dir,
        "recording.toml",
        "version = 1",
        "version = 1\nrecorded_by = \"slope-record 0.1\"\n[extra]\nanything = [1, 2]",
    );
    edit(
        &dir,
        "recording.toml",
        "[depth]",
        "[depth]\nmodel = \"pinhole\"",
    );
    let rec = Recording::open(&dir).unwrap();
    assert_eq!(rec.meta().depth.width, W);
    assert_eq!(rec.frames().len(), 2);
}

// ---------------------------------------------------------------- frames.csv

fn write_csv(dir: &Path, text: &str) {
    fs::write(dir.join("frames.csv"), text).unwrap();
}

#[test]
fn missing_columns_are_named() {
    for column in ["index", "timestamp_ns", "depth"] {
        let tmp = tempfile::tempdir().unwrap();
        let dir = base(&tmp);
        let header = "index,timestamp_ns,depth,color".replace(column, "other");
        write_csv(&dir, &format!("{header}\n0,0,depth/000000.png,\n"));
        let err = open_err(&dir);
        assert!(
            matches!(&err, RecordingError::MissingColumn { column: c, .. } if *c == column),
            "{err}"
        );
        assert_names(&err, &["frames.csv", column]);
    }
    // An empty frames.csv: the message says what the first line holds.
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    write_csv(&dir, "");
    let err = open_err(&dir);
    assert_names(&err, &["frames.csv", "index,timestamp_ns,depth,color"]);
}

#[test]
fn malformed_rows_are_named() {
    let cases = [
        "0,0,depth/000000.png\n",
        "0,0,depth/000000.png,,extra\n",
        "x,0,depth/000000.png,\n",
        "-1,0,depth/000000.png,\n",
        "0,1.5,depth/000000.png,\n",
        "0,,depth/000000.png,\n",
    ];
    for bad in cases {
        let tmp = tempfile::tempdir().unwrap();
        let dir = base(&tmp);
        write_csv(&dir, &format!("index,timestamp_ns,depth,color\n{bad}"));
        let err = open_err(&dir);
        assert!(
            matches!(err, RecordingError::BadRow { row: 2, .. }),
            "{bad}: {err}"
        );
        assert_names(&err, &["frames.csv", "line 2"]);
    }
    // A bad per-frame truth cell, on line 3.
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    for bad in ["abc", "-3", "91"] {
        write_csv(
            &dir,
            &format!("index,timestamp_ns,depth,color,slope_deg\n0,0,depth/000000.png,,5\n1,1,depth/000001.png,,{bad}\n"),
        );
        let err = open_err(&dir);
        assert!(
            matches!(err, RecordingError::BadRow { row: 3, .. }),
            "{bad}: {err}"
        );
        assert_names(&err, &["frames.csv", "line 3", "slope_deg"]);
    }
}

#[test]
fn index_must_increase_strictly() {
    for second in ["0", "5"] {
        let tmp = tempfile::tempdir().unwrap();
        let dir = base(&tmp);
        write_csv(
            &dir,
            &format!(
                "index,timestamp_ns,depth,color\n5,0,depth/000000.png,\n{second},10,depth/000001.png,\n"
            ),
        );
        let err = open_err(&dir);
        assert!(
            matches!(
                err,
                RecordingError::NonIncreasingIndex {
                    row: 3,
                    previous: 5,
                    ..
                }
            ),
            "{err}"
        );
        assert_names(&err, &["frames.csv", "line 3"]);
    }
    // Gaps are fine.
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    write_csv(
        &dir,
        "index,timestamp_ns,depth,color\n3,0,depth/000000.png,\n9,0,depth/000001.png,\n",
    );
    let rec = Recording::open(&dir).unwrap();
    assert_eq!(
        rec.frames().iter().map(|f| f.index).collect::<Vec<_>>(),
        [3, 9]
    );
}

#[test]
fn timestamps_must_not_decrease() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    write_csv(
        &dir,
        "index,timestamp_ns,depth,color\n0,10,depth/000000.png,\n1,10,depth/000001.png,\n2,9,depth/000001.png,\n",
    );
    let err = open_err(&dir);
    assert!(
        matches!(
            err,
            RecordingError::DecreasingTimestamp {
                row: 4,
                timestamp_ns: 9,
                previous: 10,
                ..
            }
        ),
        "{err}"
    );
    assert_names(&err, &["frames.csv", "line 4"]);
}

#[test]
fn paths_must_stay_inside_the_recording() {
    let cases = [
        ("/etc/passwd", "absolute"),
        ("../elsewhere/000000.png", "leaves the recording directory"),
        ("depth/../../x.png", "leaves the recording directory"),
        ("", "empty"),
    ];
    for (value, reason) in cases {
        let tmp = tempfile::tempdir().unwrap();
        let dir = base(&tmp);
        write_csv(
            &dir,
            &format!("index,timestamp_ns,depth,color\n0,0,\"{value}\",\n"),
        );
        let err = open_err(&dir);
        assert!(
            matches!(err, RecordingError::BadRow { row: 2, .. }),
            "{value}: {err}"
        );
        assert_names(&err, &["frames.csv", "line 2", "column `depth`", reason]);
    }
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    write_csv(
        &dir,
        "index,timestamp_ns,depth,color\n0,0,depth/000000.png,/tmp/c.png\n",
    );
    let err = open_err(&dir);
    assert!(
        matches!(err, RecordingError::BadRow { row: 2, .. }),
        "{err}"
    );
    assert_names(&err, &["column `color`", "/tmp/c.png", "absolute"]);

    // `..` that stays inside is fine.
    write_csv(
        &dir,
        "index,timestamp_ns,depth,color\n0,0,./color/../depth/000001.png,\n",
    );
    let rec = Recording::open(&dir).unwrap();
    assert_eq!(rec.frames()[0].depth, PathBuf::from("depth/000001.png"));
    rec.read_depth(&rec.frames()[0]).unwrap();
}

// ---------------------------------------------------------------- images (at read time)

#[test]
fn a_missing_image_names_file_and_row() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    fs::remove_file(dir.join("depth/000001.png")).unwrap();
    let rec = Recording::open(&dir).unwrap();
    rec.read_depth(&rec.frames()[0]).unwrap();
    let err = rec.read_depth(&rec.frames()[1]).unwrap_err();
    assert!(
        matches!(&err, RecordingError::ImageRead { row: 3, image, .. } if image.ends_with("depth/000001.png")),
        "{err}"
    );
    assert_names(&err, &["frames.csv", "line 3", "000001.png"]);
    assert_eq!(err.row(), Some(3));

    fs::remove_file(dir.join("color/000000.png")).unwrap();
    let err = rec.read_color(&rec.frames()[0]).unwrap_err();
    assert!(
        matches!(err, RecordingError::ImageRead { row: 2, .. }),
        "{err}"
    );
    assert_eq!(rec.read_color(&rec.frames()[1]).unwrap(), None);
}

#[test]
fn an_undecodable_image_names_file_and_row() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    let good = fs::read(dir.join("depth/000000.png")).unwrap();
    fs::write(dir.join("depth/000000.png"), b"not a png at all").unwrap();
    // Truncated in the middle of the image data.
    fs::write(dir.join("depth/000001.png"), &good[..good.len() - 20]).unwrap();
    let rec = Recording::open(&dir).unwrap();
    for (k, frame) in rec.frames().iter().enumerate() {
        let err = rec.read_depth(frame).unwrap_err();
        assert!(matches!(err, RecordingError::ImageDecode { .. }), "{err}");
        assert_eq!(err.row(), Some(k + 2));
        assert_names(
            &err,
            &[
                "frames.csv",
                &format!("line {}", k + 2),
                &format!("{k:06}.png"),
            ],
        );
    }
    fs::write(dir.join("color/000000.png"), b"\x89PNG\r\n\x1a\n garbage").unwrap();
    let err = rec.read_color(&rec.frames()[0]).unwrap_err();
    assert!(
        matches!(err, RecordingError::ImageDecode { row: 2, .. }),
        "{err}"
    );
}

#[test]
fn wrong_bit_depth_or_colour_type_is_rejected() {
    use png::{BitDepth, ColorType};
    let depth_cases = [
        (ColorType::Grayscale, BitDepth::Eight),
        (ColorType::Rgb, BitDepth::Sixteen),
        (ColorType::GrayscaleAlpha, BitDepth::Sixteen),
    ];
    for (color, depth) in depth_cases {
        let tmp = tempfile::tempdir().unwrap();
        let dir = base(&tmp);
        fs::write(dir.join("depth/000000.png"), png_bytes(W, H, color, depth)).unwrap();
        let rec = Recording::open(&dir).unwrap();
        let err = rec.read_depth(&rec.frames()[0]).unwrap_err();
        assert!(
            matches!(err, RecordingError::ImageFormat { row: 2, .. }),
            "{err}"
        );
        assert_names(
            &err,
            &["frames.csv", "line 2", "000000.png", "16-bit Grayscale"],
        );
    }
    let color_cases = [
        (ColorType::Rgb, BitDepth::Sixteen),
        (ColorType::Rgba, BitDepth::Eight),
        (ColorType::Grayscale, BitDepth::Eight),
    ];
    for (color, depth) in color_cases {
        let tmp = tempfile::tempdir().unwrap();
        let dir = base(&tmp);
        fs::write(dir.join("color/000000.png"), png_bytes(W, H, color, depth)).unwrap();
        let rec = Recording::open(&dir).unwrap();
        let err = rec.read_color(&rec.frames()[0]).unwrap_err();
        assert!(
            matches!(err, RecordingError::ImageFormat { row: 2, .. }),
            "{err}"
        );
        assert_names(&err, &["8-bit Rgb"]);
    }
}

#[test]
fn an_image_of_the_wrong_size_is_rejected() {
    use png::{BitDepth, ColorType};
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    fs::write(
        dir.join("depth/000001.png"),
        png_bytes(W + 1, H, ColorType::Grayscale, BitDepth::Sixteen),
    )
    .unwrap();
    fs::write(
        dir.join("color/000000.png"),
        png_bytes(W, H - 1, ColorType::Rgb, BitDepth::Eight),
    )
    .unwrap();
    let rec = Recording::open(&dir).unwrap();
    let err = rec.read_depth(&rec.frames()[1]).unwrap_err();
    assert!(
        matches!(
            err,
            RecordingError::ImageSize {
                row: 3,
                found_width: 5,
                found_height: 3,
                width: 4,
                height: 3,
                ..
            }
        ),
        "{err}"
    );
    assert_names(&err, &["frames.csv", "line 3", "000001.png", "5x3", "4x3"]);
    let err = rec.read_color(&rec.frames()[0]).unwrap_err();
    assert!(
        matches!(
            err,
            RecordingError::ImageSize {
                row: 2,
                found_height: 2,
                ..
            }
        ),
        "{err}"
    );

    // A failed read_depth_into does not poison the buffer for the next frame.
    let mut image = DepthImage::default();
    assert!(rec.read_depth_into(&rec.frames()[1], &mut image).is_err());
    rec.read_depth_into(&rec.frames()[0], &mut image).unwrap();
    assert_eq!(image.data, (1..=(W * H) as u16).collect::<Vec<_>>());
}

#[test]
fn a_frame_larger_than_the_limit_is_refused_before_any_allocation() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    let recording = Recording::open(&dir).unwrap();
    assert_eq!(recording.check_points(12).unwrap(), 12);
    let err = recording.check_points(11).unwrap_err();
    assert!(matches!(err, RecordingError::TooManyPoints { .. }), "{err}");
    assert_names(
        &err,
        &["recording.toml", "4 x 3", "12 points", "limit is 11"],
    );

    // A typing error in [depth] opens (images are checked when read) but
    // is refused by the check, not by an allocation failure.
    edit(&dir, "recording.toml", "width = 4", "width = 100000");
    edit(&dir, "recording.toml", "height = 3", "height = 100000");
    let recording = Recording::open(&dir).unwrap();
    let err = recording
        .check_points(slope_ipc_types::DEFAULT_MAX_CLOUD_POINTS)
        .unwrap_err();
    assert_names(
        &err,
        &["100000 x 100000", "10000000000 points", "limit is 1048576"],
    );
}

fn mkfifo(path: &Path) {
    let made = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .expect("mkfifo runs");
    assert!(made.success(), "mkfifo {}", path.display());
}

/// The chain of `err`, its causes joined by ": ".
fn chain(err: &RecordingError) -> String {
    let mut text = err.to_string();
    let mut source = std::error::Error::source(err);
    while let Some(cause) = source {
        text.push_str(&format!(": {cause}"));
        source = cause.source();
    }
    text
}

/// `work` on a thread, its result if it ends within 10 s (a blocked open
/// fails the test instead of hanging it).
fn within_deadline<T: Send + 'static>(work: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || tx.send(work()));
    rx.recv_timeout(std::time::Duration::from_secs(10))
        .expect("blocked for 10 s")
}

/// A FIFO where recording.toml, frames.csv or an image belongs blocked the
/// open forever (no writer comes); each is refused at once, naming the
/// file and what it is.
#[test]
fn fifos_are_refused_instead_of_blocking() {
    for file in ["recording.toml", "frames.csv"] {
        let tmp = tempfile::tempdir().unwrap();
        let dir = base(&tmp);
        fs::remove_file(dir.join(file)).unwrap();
        mkfifo(&dir.join(file));
        let opened = dir.clone();
        let err = within_deadline(move || Recording::open(&opened).map(drop)).unwrap_err();
        assert!(matches!(err, RecordingError::Read { .. }), "{err:?}");
        let text = chain(&err);
        assert!(
            text.contains(file) && text.contains("it is a FIFO, not a regular file"),
            "{text}"
        );
    }
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    let recording = Recording::open(&dir).unwrap();
    let frame = recording.frames()[0].clone();
    fs::remove_file(dir.join(&frame.depth)).unwrap();
    mkfifo(&dir.join(&frame.depth));
    let err = within_deadline(move || recording.read_depth(&frame).map(drop)).unwrap_err();
    assert!(
        matches!(err, RecordingError::ImageRead { row: 2, .. }),
        "{err:?}"
    );
    assert!(chain(&err).contains("it is a FIFO"), "{}", chain(&err));
}

/// A directory where recording.toml or a depth image belongs said "no
/// recording.toml" and "cannot decode": now what it is.
#[test]
fn directories_in_place_of_files_are_named_as_such() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    fs::remove_file(dir.join("recording.toml")).unwrap();
    fs::create_dir(dir.join("recording.toml")).unwrap();
    let err = open_err(&dir);
    let text = chain(&err);
    assert!(
        text.contains("recording.toml: it is a directory, not a regular file"),
        "{text}"
    );
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    let recording = Recording::open(&dir).unwrap();
    let frame = &recording.frames()[1];
    fs::remove_file(dir.join(&frame.depth)).unwrap();
    fs::create_dir(dir.join(&frame.depth)).unwrap();
    let err = recording.read_depth(frame).unwrap_err();
    let text = chain(&err);
    assert!(
        matches!(err, RecordingError::ImageRead { row: 3, .. })
            && text.contains("it is a directory, not a regular file"),
        "{text}"
    );
}

/// A frames.csv past the cap is refused by its size, without reading it
/// whole; bytes that are not UTF-8 in recording.toml are named as such
/// (they were "out of memory" for /dev/urandom).
#[test]
fn oversized_and_non_utf8_files_are_refused_by_what_they_are() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    let csv = fs::OpenOptions::new()
        .write(true)
        .open(dir.join("frames.csv"))
        .unwrap();
    // Sparse: no disk space is used.
    csv.set_len(slope_sensor::input_file::MAX_FRAME_TABLE_BYTES + 1)
        .unwrap();
    let text = chain(&open_err(&dir));
    assert!(text.contains("more than the 268435456 read"), "{text}");

    let tmp = tempfile::tempdir().unwrap();
    let dir = base(&tmp);
    let mut toml = fs::read(dir.join("recording.toml")).unwrap();
    toml.extend_from_slice(b"\n# \xff\xfe\n");
    fs::write(dir.join("recording.toml"), toml).unwrap();
    let text = chain(&open_err(&dir));
    assert!(text.contains("it is not UTF-8 text"), "{text}");
}
