//! Fuzzing the recording reader (property tests, in the default test run):
//! arbitrary bytes and structured mutations of a valid recording's
//! `recording.toml`, `frames.csv` and depth PNG. Every input gives a
//! recording or an error, never a panic, and what opens passes the checks
//! the reader promises. `SLOPE_FUZZ_CASES=N` runs N cases per property
//! instead of the defaults (README: "Fuzzing").

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use proptest::prelude::*;
use proptest::test_runner::Config;
use slope_sensor::cloud_checks::{check_intrinsics, check_unit_m};
use slope_sensor::recording::{
    DepthImage, DepthInfo, MountInfo, Recording, RecordingMeta, RecordingWriter, TruthInfo,
};

/// Cases per property: `SLOPE_FUZZ_CASES`, else `default`.
fn cases(default: u32) -> u32 {
    std::env::var("SLOPE_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(default)
}

fn config(default: u32) -> Config {
    Config {
        cases: cases(default),
        failure_persistence: None,
        ..Config::default()
    }
}

/// A valid recording of three 4 x 3 frames in `dir`.
fn base(dir: &Path) -> PathBuf {
    let rec = dir.join("rec");
    let meta = RecordingMeta {
        sensor: "synthetic".into(),
        depth: DepthInfo {
            width: 4,
            height: 3,
            unit_m: 0.001,
            fx: 365.0,
            fy: 365.0,
            cx: 1.5,
            cy: 1.0,
        },
        mount: MountInfo {
            height_m: Some(0.5),
            pitch_deg: Some(-20.0),
            roll_deg: None,
        },
        truth: TruthInfo {
            slope_deg: Some(16.0),
        },
    };
    let depth = DepthImage {
        width: 4,
        height: 3,
        data: (1000..1012).collect(),
    };
    let mut writer = RecordingWriter::create(&rec, &meta, false).expect("writer");
    for t in [0, 33_333_333, 66_666_666] {
        writer.write_frame(t, &depth, None, None).expect("frame");
    }
    writer.finish().expect("finished");
    rec
}

/// One edit of a file's bytes.
#[derive(Debug, Clone)]
enum Edit {
    /// Removes `len` bytes at `at`.
    Delete { at: usize, len: usize },
    /// Inserts bytes at `at`.
    Insert { at: usize, bytes: Vec<u8> },
    /// Overwrites the bytes at `at`.
    Overwrite { at: usize, bytes: Vec<u8> },
    /// Replaces the `nth` number in the text by a hostile one.
    Number { nth: usize, value: &'static str },
    /// Repeats line `nth`.
    DuplicateLine { nth: usize },
}

const HOSTILE_NUMBERS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "1e-300",
    "5e-324",
    "1e300",
    "18446744073709551615",
    "18446744073709551616",
    "-9223372036854775808",
    "4294967296",
    "65535",
    "100000",
    "0.0",
    "\"text\"",
    "[]",
    "{}",
];

fn edit() -> impl Strategy<Value = Edit> {
    let bytes = prop::collection::vec(any::<u8>(), 0..12);
    prop_oneof![
        (any::<usize>(), 0usize..16).prop_map(|(at, len)| Edit::Delete { at, len }),
        (any::<usize>(), bytes.clone()).prop_map(|(at, bytes)| Edit::Insert { at, bytes }),
        (any::<usize>(), bytes).prop_map(|(at, bytes)| Edit::Overwrite { at, bytes }),
        (any::<usize>(), prop::sample::select(HOSTILE_NUMBERS))
            .prop_map(|(nth, value)| Edit::Number { nth, value }),
        any::<usize>().prop_map(|nth| Edit::DuplicateLine { nth }),
    ]
}

fn apply(mut data: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for edit in edits {
        let len = data.len();
        match edit {
            Edit::Delete { at, len: n } => {
                let at = at % (len + 1);
                let end = (at + n).min(len);
                data.drain(at..end);
            }
            Edit::Insert { at, bytes } => {
                let at = at % (len + 1);
                data.splice(at..at, bytes.iter().copied());
            }
            Edit::Overwrite { at, bytes } => {
                let at = at % (len + 1);
                for (k, b) in bytes.iter().enumerate() {
                    if let Some(slot) = data.get_mut(at + k) {
                        *slot = *b;
                    }
                }
            }
            Edit::Number { nth, value } => data = replace_number(&data, *nth, value),
            Edit::DuplicateLine { nth } => {
                let lines: Vec<&[u8]> = data.split(|&b| b == b'\n').collect();
                let k = nth % lines.len();
                let mut out = Vec::with_capacity(len * 2);
                for (i, line) in lines.iter().enumerate() {
                    out.extend_from_slice(line);
                    out.push(b'\n');
                    if i == k {
                        out.extend_from_slice(line);
                        out.push(b'\n');
                    }
                }
                data = out;
            }
        }
    }
    data
}

/// `data` with its `nth` run of digits (modulo the count) replaced.
fn replace_number(data: &[u8], nth: usize, value: &str) -> Vec<u8> {
    let mut runs = Vec::new();
    let mut k = 0;
    while k < data.len() {
        if data[k].is_ascii_digit() {
            let start = k;
            while k < data.len() && (data[k].is_ascii_digit() || data[k] == b'.') {
                k += 1;
            }
            runs.push(start..k);
        } else {
            k += 1;
        }
    }
    if runs.is_empty() {
        return data.to_vec();
    }
    let run = runs[nth % runs.len()].clone();
    let mut out = data[..run.start].to_vec();
    out.extend_from_slice(value.as_bytes());
    out.extend_from_slice(&data[run.end..]);
    out
}

/// Opens `rec` and reads every frame: what opens is checked, nothing panics.
fn open_and_read(rec: &Path) {
    let Ok(recording) = Recording::open(rec) else {
        return;
    };
    let d = recording.meta().depth;
    assert!(d.width > 0 && d.height > 0);
    assert!(check_unit_m(d.unit_m).is_ok(), "{d:?}");
    assert!(
        check_intrinsics(&d.intrinsics(), d.width, d.height).is_ok(),
        "{d:?}"
    );
    assert!(recording.meta().mount.check().is_ok());
    for pair in recording.frames().windows(2) {
        assert!(pair[1].index > pair[0].index);
        assert!(pair[1].timestamp_ns >= pair[0].timestamp_ns);
    }
    if recording.check_points(1 << 16).is_err() {
        return;
    }
    for frame in recording.frames().iter().take(4) {
        if let Ok(image) = recording.read_depth(frame) {
            assert_eq!(image.data.len(), (d.width * d.height) as usize);
        }
        let _ = recording.read_color(frame);
    }
}

/// The base recording, written once (the writer syncs every file: too
/// slow to do per case).
fn shared_base() -> &'static Path {
    static BASE: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    &BASE
        .get_or_init(|| {
            let tmp = tempfile::tempdir().expect("temp dir");
            let rec = base(tmp.path());
            (tmp, rec)
        })
        .1
}

/// A fresh copy of the base recording with `file` replaced by `bytes`.
fn with_file(root: &Path, file: &str, bytes: &[u8]) -> PathBuf {
    let rec = root.join("rec");
    let from = shared_base();
    fs::create_dir_all(rec.join("depth")).expect("mkdir");
    for name in [
        "recording.toml",
        "frames.csv",
        "depth/000000.png",
        "depth/000001.png",
        "depth/000002.png",
    ] {
        fs::copy(from.join(name), rec.join(name)).expect("copy");
    }
    fs::write(rec.join(file), bytes).expect("write");
    rec
}

fn original(file: &str) -> Vec<u8> {
    fs::read(shared_base().join(file)).expect("read")
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn mutated_recording_toml_opens_or_is_refused(edits in prop::collection::vec(edit(), 1..6)) {
        let tmp = tempfile::tempdir().expect("temp dir");
        let bytes = apply(original("recording.toml"), &edits);
        open_and_read(&with_file(tmp.path(), "recording.toml", &bytes));
    }

    #[test]
    fn mutated_frames_csv_opens_or_is_refused(edits in prop::collection::vec(edit(), 1..6)) {
        let tmp = tempfile::tempdir().expect("temp dir");
        let bytes = apply(original("frames.csv"), &edits);
        open_and_read(&with_file(tmp.path(), "frames.csv", &bytes));
    }

    #[test]
    fn mutated_depth_png_decodes_or_is_refused(edits in prop::collection::vec(edit(), 1..4)) {
        let tmp = tempfile::tempdir().expect("temp dir");
        let png = original("depth/000000.png");
        let bytes = apply(png, &edits);
        open_and_read(&with_file(tmp.path(), "depth/000000.png", &bytes));
    }

    #[test]
    fn arbitrary_bytes_in_any_file_are_refused_or_read(
        file in prop::sample::select(&["recording.toml", "frames.csv", "depth/000001.png"][..]),
        bytes in prop::collection::vec(any::<u8>(), 0..512),
    ) {
        let tmp = tempfile::tempdir().expect("temp dir");
        open_and_read(&with_file(tmp.path(), file, &bytes));
    }
}

/// The mutations do reach the checks: a number made hostile in
/// recording.toml is refused (not every one: some land on a key where the
/// value is fine), which keeps the properties above from passing vacuously.
#[test]
fn hostile_numbers_in_recording_toml_are_refused() {
    let text = original("recording.toml");
    let tmp = tempfile::tempdir().expect("temp dir");
    let mut refused = 0;
    let mut tried = 0;
    for nth in 0..12 {
        for value in ["nan", "1e300", "-1", "5e-324"] {
            let root = tmp.path().join(format!("{nth}-{value}"));
            fs::create_dir(&root).expect("mkdir");
            let bytes = replace_number(&text, nth, value);
            tried += 1;
            refused +=
                usize::from(Recording::open(&with_file(&root, "recording.toml", &bytes)).is_err());
        }
    }
    assert!(refused * 2 > tried, "{refused} of {tried} refused");
}
