//! What `slope-eval` and `slope-convert` write besides numbers, read back
//! with the same crates that wrote them: overlays every Nth frame, the PLY
//! cloud (its label counts are the inlier counts the report gives), the
//! plot over the frames, and the MCAP file (channels, schemas, one message
//! per frame and topic).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::process::Command;

use base64::Engine;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};
use serde_json::Value;

const EVAL: &str = env!("CARGO_BIN_EXE_slope-eval");
const CONVERT: &str = env!("CARGO_BIN_EXE_slope-convert");

fn ramp16() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/recordings/ramp16")
}

fn run(bin: &str, args: &[&str]) -> String {
    let out = Command::new(bin)
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .expect("run");
    assert!(
        out.status.success(),
        "{bin} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8")
}

/// A conversion that fails (here: the recording does not exist) leaves a
/// previous output file as it was and no temporary file beside it.
#[test]
fn a_failed_conversion_keeps_the_previous_output() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("ramp16.mcap");
    std::fs::write(&out, b"the previous conversion").expect("write");
    let missing = dir.path().join("no-such-recording");
    let result = Command::new(CONVERT)
        .args([
            missing.to_str().expect("utf-8"),
            "-o",
            out.to_str().expect("utf-8"),
        ])
        .env_remove("RUST_LOG")
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success(), "{stderr}");
    assert!(stderr.contains("no-such-recording"), "{stderr}");
    assert_eq!(
        std::fs::read(&out).expect("the previous file"),
        b"the previous conversion"
    );
    let entries = std::fs::read_dir(dir.path()).expect("dir").count();
    assert_eq!(entries, 1, "only the previous file");
    // A recording none of whose frames can be read (its depth images are
    // missing) is a failure too: the previous output is not replaced by an
    // empty one (it was, with status 0).
    let unreadable = dir.path().join("unreadable");
    std::fs::create_dir(&unreadable).expect("mkdir");
    for file in ["recording.toml", "frames.csv"] {
        std::fs::copy(ramp16().join(file), unreadable.join(file)).expect("copy");
    }
    let (code, stderr) = convert(&[
        unreadable.to_str().expect("utf-8"),
        "-o",
        out.to_str().expect("utf-8"),
    ]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("no frame of") && stderr.contains("30 bad frame(s)"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read(&out).expect("the previous file"),
        b"the previous conversion"
    );
    let entries = std::fs::read_dir(dir.path()).expect("dir").count();
    assert_eq!(entries, 2, "the previous file and the recording");
}

fn png_size(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(BufReader::new(File::open(path).expect("png")));
    let mut reader = decoder.read_info().expect("png header");
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("png data");
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

#[test]
fn every_nth_frame_gets_an_overlay_and_a_ply_that_match_the_report() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (pictures, clouds, plots) = (
        dir.path().join("png"),
        dir.path().join("ply"),
        dir.path().join("plot"),
    );
    let recording = ramp16();
    let stdout = run(
        EVAL,
        &[
            recording.to_str().expect("utf-8"),
            "--max-frames",
            "6",
            "--render-every",
            "3",
            "--render",
            pictures.to_str().expect("utf-8"),
            "--export-ply",
            clouds.to_str().expect("utf-8"),
            "--plot",
            plots.to_str().expect("utf-8"),
            "--json",
            "-q",
        ],
    );
    let report: Value =
        serde_json::from_str(stdout.lines().next().expect("a report")).expect("JSON");
    let mut pngs: Vec<_> = std::fs::read_dir(&pictures)
        .expect("png dir")
        .flatten()
        .map(|e| e.file_name())
        .collect();
    pngs.sort();
    assert_eq!(
        pngs,
        [
            "ramp16-paper-frame000000.png",
            "ramp16-paper-frame000003.png"
        ]
    );
    for index in [0u64, 3] {
        let (w, h, _) = png_size(&pictures.join(format!("ramp16-paper-frame{index:06}.png")));
        assert_eq!(w, 1024);
        assert!(h > 848);
        let estimate = &report["estimates"][index as usize];
        assert_eq!(estimate["index"], index);
        let path = clouds.join(format!("ramp16-paper-frame{index:06}.ply"));
        let ply = Parser::<DefaultElement>::new()
            .read_ply(&mut BufReader::new(File::open(&path).expect("ply")))
            .expect("a readable PLY");
        let vertices = &ply.payload["vertex"];
        let mut roles = BTreeMap::new();
        for v in vertices {
            let Some(Property::UChar(role)) = v.get("role") else {
                panic!("no role: {v:?}");
            };
            *roles.entry(*role).or_insert(0u64) += 1;
            for key in ["x", "y", "z", "nx", "ny", "nz"] {
                assert!(matches!(v.get(key), Some(Property::Float(_))), "{key}");
            }
        }
        // Ground (1) and inclined (2) points are the inliers the report counts.
        assert_eq!(
            roles.get(&1).copied(),
            estimate["ground_inliers"].as_u64(),
            "{roles:?}"
        );
        assert_eq!(
            roles.get(&2).copied(),
            estimate["inclined_inliers"].as_u64(),
            "{roles:?}"
        );
        assert!(vertices.len() > 150_000, "{}", vertices.len());
    }
    // The plot: one picture for the recording, with the paper method's
    // colour in it.
    let (w, h, rgb) = png_size(&plots.join("ramp16-plot.png"));
    assert_eq!((w, h), (1100, 760));
    let blue = rgb.chunks_exact(3).filter(|p| *p == [30, 90, 200]).count();
    assert!(blue > 200, "{blue} pixels of the paper method's colour");
}

/// The plot of every method on ramp16 (the reviewer's repro): each
/// method's colour is seen in the slope chart (least-squares was hidden
/// under tls) and in the legend column to its right, which is white but
/// for the legend (no grid: the chart does not reach under it).
#[test]
fn the_plot_of_every_method_shows_each_beside_its_legend() {
    let dir = tempfile::tempdir().expect("temp dir");
    let recording = ramp16();
    run(
        EVAL,
        &[
            recording.to_str().expect("utf-8"),
            "--method",
            "all",
            "--max-frames",
            "10",
            "--plot",
            dir.path().to_str().expect("utf-8"),
            "-q",
        ],
    );
    let (w, h, rgb) = png_size(&dir.path().join("ramp16-plot.png"));
    let (w, h) = (w as usize, h as usize);
    let column = w - slope_tools::plot::LEGEND_WIDTH as usize;
    let slope_panel = (h as f64 * 0.62) as usize;
    let at = |x: usize, y: usize| {
        [
            rgb[3 * (y * w + x)],
            rgb[3 * (y * w + x) + 1],
            rgb[3 * (y * w + x) + 2],
        ]
    };
    let count = |xs: std::ops::Range<usize>, colour: [u8; 3]| {
        (0..slope_panel)
            .flat_map(|y| xs.clone().map(move |x| (x, y)))
            .filter(|&(x, y)| at(x, y) == colour)
            .count()
    };
    for (name, colour) in [
        ("paper", [30, 90, 200]),
        ("least-squares", [220, 120, 20]),
        ("tls", [40, 150, 60]),
    ] {
        let in_chart = count(0..column, colour);
        let in_legend = count(column..w, colour);
        assert!(in_chart > 10 * 15, "{name}: {in_chart} pixels in the chart");
        assert!(in_legend > 40, "{name}: {in_legend} pixels in the legend");
    }
    // The legend column has no grid line: a row of it below the legend
    // and its notes is white.
    let last = slope_panel - 20;
    assert!((column..w).all(|x| at(x, last) == [255, 255, 255]));
}

/// `slope-convert` and its status and stderr.
fn convert(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(CONVERT)
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .expect("run");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A `[depth]` of 100000 x 100000 (a typing error) is refused by name
/// before any cloud is allocated (it was: an abort, status 134) and before
/// the output is created.
#[test]
fn a_frame_size_beyond_the_limit_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rec = dir.path().join("huge");
    std::fs::create_dir(&rec).expect("mkdir");
    let toml = std::fs::read_to_string(ramp16().join("recording.toml")).expect("toml");
    let toml = toml
        .replace("width = 512", "width = 100000")
        .replace("height = 424", "height = 100000");
    std::fs::write(rec.join("recording.toml"), toml).expect("write");
    std::fs::write(
        rec.join("frames.csv"),
        "index,timestamp_ns,depth,color\n0,0,depth/000000.png,\n",
    )
    .expect("write");
    let out = dir.path().join("huge.mcap");
    let (code, stderr) = convert(&[
        rec.to_str().expect("utf-8"),
        "-o",
        out.to_str().expect("utf-8"),
    ]);
    assert_eq!(code, Some(1), "{stderr}");
    for part in [
        "recording.toml",
        "100000 x 100000",
        "10000000000 points",
        "--max-points",
    ] {
        assert!(stderr.contains(part), "{part}: {stderr}");
    }
    assert!(!out.exists());
}

/// A recording whose frames.csv has its header only is refused as by
/// slope-replay (it was converted into an empty MCAP, status 0).
#[test]
fn a_recording_without_frames_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rec = dir.path().join("empty");
    std::fs::create_dir(&rec).expect("mkdir");
    std::fs::copy(ramp16().join("recording.toml"), rec.join("recording.toml")).expect("copy");
    std::fs::write(rec.join("frames.csv"), "index,timestamp_ns,depth,color\n").expect("write");
    let out = dir.path().join("empty.mcap");
    let (code, stderr) = convert(&[
        rec.to_str().expect("utf-8"),
        "-o",
        out.to_str().expect("utf-8"),
    ]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("its frames.csv lists no frames") && stderr.contains("empty"),
        "{stderr}"
    );
    assert!(!out.exists());
}

/// An output that is a directory, or in a directory that does not exist,
/// is refused before anything is converted (a directory was refused only
/// by the final rename: "Is a directory", after the whole conversion).
#[test]
fn an_output_that_cannot_be_written_is_refused_up_front() {
    let dir = tempfile::tempdir().expect("temp dir");
    let recording = ramp16();
    let rec = recording.to_str().expect("utf-8");
    let (code, stderr) = convert(&[rec, "-o", dir.path().to_str().expect("utf-8")]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("it is a directory"), "{stderr}");
    assert!(!stderr.contains("converted"), "{stderr}");
    let missing = dir.path().join("no-such-dir/out.mcap");
    let (code, stderr) = convert(&[rec, "-o", missing.to_str().expect("utf-8")]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("no-such-dir") && stderr.contains("does not exist"),
        "{stderr}"
    );
    let entries = std::fs::read_dir(dir.path()).expect("dir").count();
    assert_eq!(entries, 0, "no temporary file left");
    // Under a regular file: said to be one, not "does not exist".
    let file = dir.path().join("FILE");
    std::fs::write(&file, b"x").expect("file");
    let (code, stderr) = convert(&[rec, "-o", file.join("out.mcap").to_str().expect("utf-8")]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("FILE is not a directory (a file is there)"),
        "{stderr}"
    );
}

/// A colour image that cannot be read is a warning: the frame is still
/// converted, its points with rgb 0.
#[test]
fn an_unreadable_colour_image_is_a_counted_warning() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rec = dir.path().join("ramp");
    std::fs::create_dir(&rec).expect("mkdir");
    for file in ["recording.toml", "frames.csv"] {
        std::fs::copy(ramp16().join(file), rec.join(file)).expect("copy");
    }
    for sub in ["depth", "color"] {
        std::fs::create_dir(rec.join(sub)).expect("mkdir");
        std::fs::copy(
            ramp16().join(sub).join("000000.png"),
            rec.join(sub).join("000000.png"),
        )
        .expect("copy");
    }
    std::fs::write(rec.join("color/000000.png"), b"not a png").expect("write");
    let out = dir.path().join("ramp.mcap");
    let (code, stderr) = convert(&[
        rec.to_str().expect("utf-8"),
        "-o",
        out.to_str().expect("utf-8"),
        "--max-frames",
        "1",
        "--no-estimates",
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stderr.contains("converting without colour") && stderr.contains("color/000000.png"),
        "{stderr}"
    );
    assert!(
        stderr.contains("1 frame(s) converted without colour"),
        "{stderr}"
    );
    // The frame's cloud is there, one point per measured pixel of its
    // depth image, every one with rgb 0.
    let bytes = std::fs::read(&out).expect("mcap file");
    let mut clouds = Vec::new();
    let mut depths = Vec::new();
    for message in mcap::MessageStream::new(&bytes).expect("an MCAP file") {
        let message = message.expect("a message");
        let value: Value = serde_json::from_slice(&message.data).expect("JSON message");
        match message.channel.topic.as_str() {
            "/slope/cloud" => clouds.push(value),
            "/slope/depth" => depths.push(value),
            _ => {}
        }
    }
    assert_eq!((clouds.len(), depths.len()), (1, 1));
    let b64 = base64::engine::general_purpose::STANDARD;
    let depth = b64
        .decode(depths[0]["data"].as_str().expect("data"))
        .expect("base64");
    let measured = depth.chunks_exact(2).filter(|d| d != &[0, 0]).count();
    assert!(measured > 0, "the depth image has readings");
    let points = b64
        .decode(clouds[0]["data"].as_str().expect("data"))
        .expect("base64");
    assert_eq!(
        points.len(),
        measured * 16,
        "one 16-byte point per measured pixel"
    );
    let rgb: Vec<u32> = points
        .chunks_exact(16)
        .map(|p| u32::from_le_bytes([p[12], p[13], p[14], p[15]]))
        .collect();
    assert!(rgb.iter().all(|&c| c == 0), "a point with colour");
}

#[test]
fn a_converted_recording_has_one_message_per_frame_and_topic() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("ramp16.mcap");
    let recording = ramp16();
    run(
        CONVERT,
        &[
            recording.to_str().expect("utf-8"),
            out.to_str().expect("utf-8"),
            "--max-frames",
            "4",
            "-q",
        ],
    );
    let bytes = std::fs::read(&out).expect("mcap file");
    let mut per_topic: BTreeMap<String, Vec<Value>> = BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).expect("an MCAP file") {
        let message = message.expect("a message");
        let channel = &message.channel;
        assert_eq!(channel.message_encoding, "json");
        let schema = channel.schema.as_ref().expect("a schema");
        assert_eq!(schema.encoding, "jsonschema");
        let expected = match channel.topic.as_str() {
            "/slope/depth" => "foxglove.RawImage",
            "/slope/cloud" => "foxglove.PointCloud",
            "/slope/estimate" => "slope.estimate.json/1",
            "/slope/surfaces" => "slope.surfaces.json/1",
            other => panic!("unexpected topic {other}"),
        };
        assert_eq!(schema.name, expected);
        let value: Value = serde_json::from_slice(&message.data).expect("JSON message");
        per_topic
            .entry(channel.topic.clone())
            .or_default()
            .push(value);
    }
    for topic in [
        "/slope/depth",
        "/slope/cloud",
        "/slope/estimate",
        "/slope/surfaces",
    ] {
        assert_eq!(per_topic[topic].len(), 4, "{topic}");
    }
    let b64 = base64::engine::general_purpose::STANDARD;
    let image = &per_topic["/slope/depth"][0];
    assert_eq!(
        (image["width"].as_u64(), image["height"].as_u64()),
        (Some(512), Some(424))
    );
    assert_eq!(image["encoding"], "16UC1");
    let depth = b64
        .decode(image["data"].as_str().expect("data"))
        .expect("base64");
    assert_eq!(depth.len(), 512 * 424 * 2);
    let cloud = &per_topic["/slope/cloud"][0];
    let points = b64
        .decode(cloud["data"].as_str().expect("data"))
        .expect("base64");
    let measured = depth.chunks_exact(2).filter(|d| d != &[0, 0]).count();
    assert_eq!(
        points.len(),
        measured * 16,
        "one 16-byte point per measured pixel"
    );
    // ramp16 has colour images: the points carry them (rgb was 0 for all).
    let rgb: Vec<u32> = points
        .chunks_exact(16)
        .map(|p| u32::from_le_bytes([p[12], p[13], p[14], p[15]]))
        .collect();
    let coloured = rgb.iter().filter(|&&c| c != 0).count();
    assert!(
        coloured * 10 > rgb.len() * 9,
        "{coloured} of {} points coloured",
        rgb.len()
    );
    for (k, e) in per_topic["/slope/estimate"].iter().enumerate() {
        assert_eq!(e["schema"], "slope.estimate.json/1");
        assert_eq!(e["frame"], k as u64);
        assert_eq!(e["status"], "ok", "{e}");
        assert!(
            (e["slope_deg"].as_f64().expect("slope") - 16.0).abs() < 1.0,
            "{e}"
        );
        let s = &per_topic["/slope/surfaces"][k];
        assert_eq!(s["schema"], "slope.surfaces.json/1");
        assert_eq!(
            (&s["frame"], &s["timestamp_ns"]),
            (&e["frame"], &e["timestamp_ns"])
        );
        let road = &s["surfaces"][s["road"].as_u64().expect("a road") as usize];
        assert_eq!(
            (&road["road"], &road["role"]),
            (&Value::Bool(true), &Value::from("ramp"))
        );
        let (found, wanted) = (road["slope_deg"].as_f64(), e["slope_deg"].as_f64());
        assert!(
            (found.expect("road slope") - wanted.expect("slope")).abs() < 0.25,
            "{s}"
        );
    }
}

/// A message read back: its topic, log time and payload.
type Message = (String, u64, Vec<u8>);

/// Every message of `path`, in file order, and the compression of each
/// chunk (from the summary's chunk indexes).
fn messages_and_chunks(path: &Path) -> (Vec<Message>, Vec<String>) {
    let bytes = std::fs::read(path).expect("mcap file");
    let messages = mcap::MessageStream::new(&bytes)
        .expect("an MCAP file")
        .map(|message| {
            let message = message.expect("a message");
            let topic = message.channel.topic.clone();
            (topic, message.log_time, message.data.into_owned())
        })
        .collect();
    let summary = mcap::Summary::read(&bytes)
        .expect("a summary")
        .expect("a finished file");
    let chunks = summary
        .chunk_indexes
        .iter()
        .map(|chunk| chunk.compression.clone())
        .collect();
    (messages, chunks)
}

/// Compressed chunks (zstd, the default, and lz4) read back with the `mcap`
/// crate's reader as the uncompressed file: the same messages, byte for
/// byte, in a smaller file.
#[test]
fn compressed_mcap_files_hold_the_same_messages() {
    let dir = tempfile::tempdir().expect("temp dir");
    let recording = ramp16();
    let convert_to = |name: &str, compression: Option<&str>| {
        let out = dir.path().join(name);
        let mut args = vec![
            recording.to_str().expect("utf-8"),
            "-o",
            out.to_str().expect("utf-8"),
            "--max-frames",
            "3",
            "--no-estimates",
            "-q",
        ];
        if let Some(compression) = compression {
            args.extend(["--mcap-compression", compression]);
        }
        run(CONVERT, &args);
        let size = std::fs::metadata(&out).expect("output").len();
        let (messages, chunks) = messages_and_chunks(&out);
        (size, messages, chunks)
    };
    let (plain_size, plain, chunks) = convert_to("none.mcap", Some("none"));
    assert!(chunks.iter().all(String::is_empty), "{chunks:?}");
    assert_eq!(plain.len(), 6, "a depth image and a cloud per frame");
    for (name, compression, expected) in [
        ("default.mcap", None, "zstd"),
        ("lz4.mcap", Some("lz4"), "lz4"),
    ] {
        let (size, messages, chunks) = convert_to(name, compression);
        assert!(
            !chunks.is_empty() && chunks.iter().all(|c| c == expected),
            "{name}: {chunks:?}"
        );
        assert!(
            size * 10 < plain_size * 7,
            "{name}: {size} of {plain_size} bytes"
        );
        assert_eq!(messages.len(), plain.len(), "{name}");
        for (message, original) in messages.iter().zip(&plain) {
            assert_eq!((&message.0, message.1), (&original.0, original.1), "{name}");
            assert!(
                message.2 == original.2,
                "{name}: a payload of {} differs",
                message.0
            );
        }
    }
}

/// The `slope.recording` metadata records of the MCAP file at `path`.
fn recording_metadata(path: &Path) -> Vec<BTreeMap<String, String>> {
    let bytes = std::fs::read(path).expect("mcap file");
    let summary = mcap::Summary::read(&bytes)
        .expect("a summary")
        .expect("a finished file");
    summary
        .metadata_indexes
        .iter()
        .map(|index| mcap::read::metadata(&bytes, index).expect("a metadata record"))
        .filter(|metadata| metadata.name == "slope.recording")
        .map(|metadata| metadata.metadata)
        .collect()
}

/// The converted file names the recording's sensor, and gives its depth
/// image's size, intrinsics and mount, as recording.toml has them.
#[test]
fn a_converted_recording_names_its_sensor() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("ramp16.mcap");
    let recording = ramp16();
    run(
        CONVERT,
        &[
            recording.to_str().expect("utf-8"),
            "-o",
            out.to_str().expect("utf-8"),
            "--max-frames",
            "1",
            "--no-estimates",
            "-q",
        ],
    );
    let records = recording_metadata(&out);
    assert_eq!(records.len(), 1, "{records:?}");
    let expected = [
        ("sensor", "synthetic"),
        ("width", "512"),
        ("height", "424"),
        ("fx", "365"),
        ("fy", "365"),
        ("cx", "255.5"),
        ("cy", "211.5"),
        ("mount_height_m", "0.5"),
        ("mount_pitch_deg", "-20"),
        ("mount_roll_deg", "0"),
    ];
    let expected: BTreeMap<String, String> = expected
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    assert_eq!(records[0], expected);
}
