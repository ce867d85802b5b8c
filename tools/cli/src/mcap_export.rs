//! MCAP files (the log format of Foxglove and ROS 2 bags), written with the
//! `mcap` crate: per frame the depth image as `foxglove.RawImage`, the
//! cloud as `foxglove.PointCloud` and, when there is one, the estimate as
//! JSON (`slope.estimate.json/1`, the keys of `slope-echo --json`). Every
//! channel is JSON-encoded with a JSON Schema (Foxglove's own schemas for
//! its types, bytes as base64), so Foxglove opens the file as it is.
//!
//! | topic | schema | per frame |
//! |---|---|---|
//! | `/slope/depth` | `foxglove.RawImage` (`16UC1`, millimetres) | always |
//! | `/slope/cloud` | `foxglove.PointCloud` (x y z float32, rgb packed uint32) | always |
//! | `/slope/estimate` | `slope.estimate.json/1` | when estimated |
//! | `/slope/surfaces` | `slope.surfaces.json/1` (the keys of `slope-echo --surfaces --json`) | when estimated by `slope-convert` |
//!
//! A metadata record `slope.recording` ([`RECORDING_METADATA`]) names the
//! sensor (recording.toml's `sensor`, the cloud header's for `slope-record`)
//! with the depth image's size and intrinsics and, where known, the mount.
//!
//! The chunks are compressed with zstd by default ([`McapCompression`]:
//! `--mcap-compression` of `slope-record` and `slope-convert`); Foxglove and
//! the `mcap` readers decompress them as they read.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::Context;
use base64::Engine;
use serde_json::json;
use slope_ipc_types::{CloudPoint, SlopeEstimate, Surfaces};
use slope_sensor::recording::RecordingMeta;

use crate::echo::EstimateJson;
use crate::surfaces_json::SurfacesJson;
use crate::unfinished_files::UnfinishedFile;

pub const DEPTH_TOPIC: &str = "/slope/depth";
pub const CLOUD_TOPIC: &str = "/slope/cloud";
pub const ESTIMATE_TOPIC: &str = "/slope/estimate";
/// The camera's frame id in every message.
pub const FRAME_ID: &str = "slope_camera";
/// Topic of the surfaces messages.
pub const SURFACES_TOPIC: &str = "/slope/surfaces";
/// `schema` of the surfaces messages.
pub const SURFACES_SCHEMA: &str = "slope.surfaces.json/1";

/// `schema` of the estimate messages.
pub const ESTIMATE_SCHEMA: &str = "slope.estimate.json/1";
/// Name of the metadata record that describes the recording
/// ([`recording_metadata`]).
pub const RECORDING_METADATA: &str = "slope.recording";

const TIME_SCHEMA: &str = r#"{"type":"object","properties":{"sec":{"type":"integer","minimum":0},"nsec":{"type":"integer","minimum":0}}}"#;

/// Foxglove's `foxglove.RawImage` as JSON Schema.
fn raw_image_schema() -> String {
    json!({
        "title": "foxglove.RawImage",
        "description": "A raw image",
        "type": "object",
        "properties": {
            "timestamp": serde_json::from_str::<serde_json::Value>(TIME_SCHEMA).unwrap_or_default(),
            "frame_id": {"type": "string"},
            "width": {"type": "integer", "minimum": 0},
            "height": {"type": "integer", "minimum": 0},
            "encoding": {"type": "string"},
            "step": {"type": "integer", "minimum": 0},
            "data": {"type": "string", "contentEncoding": "base64"}
        }
    })
    .to_string()
}

/// Foxglove's `foxglove.PointCloud` as JSON Schema.
fn point_cloud_schema() -> String {
    let vector = json!({"type": "object", "properties": {
        "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}});
    let quaternion = json!({"type": "object", "properties": {
        "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"},
        "w": {"type": "number"}}});
    json!({
        "title": "foxglove.PointCloud",
        "description": "A collection of N-dimensional points",
        "type": "object",
        "properties": {
            "timestamp": serde_json::from_str::<serde_json::Value>(TIME_SCHEMA).unwrap_or_default(),
            "frame_id": {"type": "string"},
            "pose": {"type": "object", "properties": {"position": vector, "orientation": quaternion}},
            "point_stride": {"type": "integer", "minimum": 0},
            "fields": {"type": "array", "items": {"type": "object", "properties": {
                "name": {"type": "string"},
                "offset": {"type": "integer", "minimum": 0},
                "type": {"type": "integer", "description": "foxglove.NumericType: 1 UINT8, 2 INT8, 3 UINT16, 4 INT16, 5 UINT32, 6 INT32, 7 FLOAT32, 8 FLOAT64"}
            }}},
            "data": {"type": "string", "contentEncoding": "base64"}
        }
    })
    .to_string()
}

/// The estimate's JSON Schema: an object with `schema` and the keys of
/// `slope-echo --json` (documented in tools/cli/README.md).
fn estimate_schema() -> String {
    let number = json!({"type": ["number", "null"]});
    let plane = json!({"type": ["array", "null"], "items": {"type": "number"}});
    json!({
        "title": ESTIMATE_SCHEMA,
        "description": "One slope estimate: the keys of slope-echo --json",
        "type": "object",
        "properties": {
            "schema": {"type": "string", "const": ESTIMATE_SCHEMA},
            "frame": {"type": "integer"},
            "timestamp_ns": {"type": "integer"},
            "status": {"type": "string"},
            "method": {"type": "string"},
            "slope_deg": number, "std_deg": number, "distance_m": number,
            "confidence": {"type": "number"},
            "confidence_reasons": {"type": "array", "items": {"type": "string"}},
            "tracked_slope_deg": number, "tracked_std_deg": number,
            "ground_plane": plane, "inclined_plane": plane,
            "ground_seen_to_m": number
        },
        "additionalProperties": true
    })
    .to_string()
}

/// The surfaces' JSON Schema: an object with `schema` and the keys of
/// `slope-echo --surfaces --json` (documented in tools/cli/README.md).
fn surfaces_schema() -> String {
    let number = json!({"type": ["number", "null"]});
    let vector = json!({"type": ["array", "null"], "items": {"type": "number"}});
    json!({
        "title": SURFACES_SCHEMA,
        "description": "Every surface of one frame: the keys of slope-echo --surfaces --json",
        "type": "object",
        "properties": {
            "schema": {"type": "string", "const": SURFACES_SCHEMA},
            "frame": {"type": "integer"},
            "timestamp_ns": {"type": "integer"},
            "status": {"type": "string"},
            "road": {"type": ["integer", "null"]},
            "up": vector, "forward": vector, "ground_plane": vector,
            "surfaces": {"type": "array", "items": {
                "type": "object",
                "properties": {
                    "role": {"type": "string"}, "support": {"type": "string"},
                    "road": {"type": "boolean"}, "inliers": {"type": "integer"},
                    "slope_deg": number, "heading_deg": number,
                    "distance_m": number, "far_m": number,
                    "left_m": number, "right_m": number,
                    "lowest_m": number, "highest_m": number, "area_m2": number,
                    "plane": vector
                },
                "additionalProperties": true
            }}
        },
        "additionalProperties": true
    })
    .to_string()
}

/// The `slope.recording` metadata of a recording: `sensor`, the depth
/// image's `width` and `height` (pixels), its intrinsics `fx`, `fy`, `cx`,
/// `cy` (pixels) and, each when known, `mount_height_m`, `mount_pitch_deg`
/// and `mount_roll_deg`. MCAP metadata values are text: numbers are
/// written as Rust prints them (they parse back to the same value).
pub fn recording_metadata(meta: &RecordingMeta) -> BTreeMap<String, String> {
    let depth = &meta.depth;
    let mut values = BTreeMap::from([
        ("sensor".to_string(), meta.sensor.clone()),
        ("width".to_string(), depth.width.to_string()),
        ("height".to_string(), depth.height.to_string()),
        ("fx".to_string(), depth.fx.to_string()),
        ("fy".to_string(), depth.fy.to_string()),
        ("cx".to_string(), depth.cx.to_string()),
        ("cy".to_string(), depth.cy.to_string()),
    ]);
    let mount = &meta.mount;
    for (key, value) in [
        ("mount_height_m", mount.height_m),
        ("mount_pitch_deg", mount.pitch_deg),
        ("mount_roll_deg", mount.roll_deg),
    ] {
        if let Some(value) = value {
            values.insert(key.to_string(), value.to_string());
        }
    }
    values
}

/// `{"sec": .., "nsec": ..}` of a stamp in ns.
fn time_json(stamp_ns: u64) -> serde_json::Value {
    json!({"sec": stamp_ns / 1_000_000_000, "nsec": stamp_ns % 1_000_000_000})
}

/// The JSON object `value` (an object with at least one key) with one more
/// key, `data`, holding `bytes` in base64.
fn json_with_data(value: &serde_json::Value, bytes: &[u8]) -> serde_json::Result<Vec<u8>> {
    let mut json = serde_json::to_vec(value)?;
    if json.last() != Some(&b'}') || json.len() < 3 {
        return Err(serde::ser::Error::custom(
            "a message is an object with keys",
        ));
    }
    json.pop();
    json.extend_from_slice(b",\"data\":\"");
    let start = json.len();
    json.resize(
        start + base64::encoded_len(bytes.len(), true).unwrap_or(0),
        0,
    );
    let written = base64::engine::general_purpose::STANDARD
        .encode_slice(bytes, &mut json[start..])
        .map_err(serde::ser::Error::custom)?;
    json.truncate(start + written);
    json.extend_from_slice(b"\"}");
    Ok(json)
}

/// How the chunks of an MCAP file are compressed (`--mcap-compression`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum McapCompression {
    /// Zstandard: the smallest file (about 1.7 MB a Kinect v2 frame).
    #[default]
    Zstd,
    /// LZ4: about 2.3 MB a Kinect v2 frame; quicker to read back.
    Lz4,
    /// Uncompressed: about 4.4 MB a Kinect v2 frame.
    None,
}

impl McapCompression {
    /// The `mcap` crate's chunk compression and its level: zstd's fastest
    /// (1: about 7 % larger than its default 3 and about 27 % quicker in
    /// `zstd -b` on these frames), lz4's default (0).
    pub(crate) fn chunk_compression(self) -> (Option<mcap::Compression>, u32) {
        match self {
            Self::Zstd => (Some(mcap::Compression::Zstd), 1),
            Self::Lz4 => (Some(mcap::Compression::Lz4), 0),
            Self::None => (None, 0),
        }
    }
}

/// One frame to write.
#[derive(Debug, Clone, Copy)]
pub struct McapFrame<'a> {
    pub stamp_ns: u64,
    pub width: u32,
    pub height: u32,
    /// Depth counts, row-major, and the metres per count.
    pub depth: &'a [u16],
    pub depth_unit_m: f64,
    pub points: &'a [CloudPoint],
    pub estimate: Option<&'a SlopeEstimate>,
    pub surfaces: Option<&'a Surfaces>,
}

/// An MCAP file being written.
pub struct McapExporter {
    writer: mcap::Writer<BufWriter<File>>,
    depth: u16,
    cloud: u16,
    estimate: u16,
    surfaces: u16,
    sequence: u32,
    path: String,
    /// With [`McapExporter::create_replacing`]: the temporary file being
    /// written and the path it becomes on [`McapExporter::finish`].
    pending: Option<Replacement>,
}

/// Why `dir`, which an output file should go into, cannot take it: it is
/// something else than a directory, or there is nothing there.
pub fn not_a_directory(dir: &Path) -> String {
    match std::fs::metadata(dir) {
        Ok(_) => format!("{} is not a directory (a file is there)", dir.display()),
        Err(_) => format!("the directory {} does not exist", dir.display()),
    }
}

/// A temporary file that becomes `path` once finished; registered so that
/// a second signal removes it ([`crate::unfinished_files`]).
struct Replacement {
    temp: tempfile::TempPath,
    path: PathBuf,
    unfinished: UnfinishedFile,
}

impl McapExporter {
    /// Creates `path` with the three channels and the metadata of
    /// `recording`, and writes into it as it goes (`slope-record`: what was
    /// written before a crash stays on disk).
    pub fn create(
        path: &Path,
        compression: McapCompression,
        recording: &RecordingMeta,
    ) -> anyhow::Result<Self> {
        let name = path.display().to_string();
        let file = File::create(path).with_context(|| format!("cannot create {name}"))?;
        Self::with_file(file, name, compression, None)?.with_metadata(recording)
    }

    /// Writes into a temporary file beside `path` that [`Self::finish`]
    /// renames over `path` (`slope-convert`): until then a file already at
    /// `path` is untouched, and a run that fails leaves nothing behind (the
    /// temporary file is removed when the exporter is dropped). A `path`
    /// that is a directory, or whose directory does not exist, is refused
    /// here, before anything is converted, not at the final rename.
    pub fn create_replacing(
        path: &Path,
        compression: McapCompression,
        recording: &RecordingMeta,
    ) -> anyhow::Result<Self> {
        let name = path.display().to_string();
        let dir = match path.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => dir,
            _ => Path::new("."),
        };
        if path.is_dir() {
            anyhow::bail!(
                "cannot write {name}: it is a directory; give a file name, e.g. -o {}",
                path.join("out.mcap").display()
            );
        }
        if !dir.is_dir() {
            anyhow::bail!("cannot write {name}: {}", not_a_directory(dir));
        }
        let prefix = format!(
            ".{}.",
            path.file_name().unwrap_or_default().to_string_lossy()
        );
        // 0o666 less the umask, as File::create gives (tempfile's default
        // is 0o600).
        #[cfg(unix)]
        let permissions = {
            use std::os::unix::fs::PermissionsExt;
            std::fs::Permissions::from_mode(0o666)
        };
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".part");
        #[cfg(unix)]
        builder.permissions(permissions);
        let (temp, unfinished) =
            UnfinishedFile::create(|| builder.tempfile_in(dir)).with_context(|| {
                format!(
                    "cannot create a temporary file for {name} in {}",
                    dir.display()
                )
            })?;
        let (file, temp) = temp.into_parts();
        let replacement = Replacement {
            temp,
            path: path.to_path_buf(),
            unfinished,
        };
        Self::with_file(file, name, compression, Some(replacement))?.with_metadata(recording)
    }

    /// Writes the `slope.recording` metadata record of `recording`.
    fn with_metadata(mut self, recording: &RecordingMeta) -> anyhow::Result<Self> {
        let metadata = mcap::records::Metadata {
            name: RECORDING_METADATA.to_string(),
            metadata: recording_metadata(recording),
        };
        self.writer
            .write_metadata(&metadata)
            .with_context(|| format!("cannot write the metadata into {}", self.path))?;
        Ok(self)
    }

    /// Writes the header and the three channels into `file`.
    fn with_file(
        file: File,
        name: String,
        compression: McapCompression,
        pending: Option<Replacement>,
    ) -> anyhow::Result<Self> {
        let (chunk_compression, level) = compression.chunk_compression();
        let mut writer = mcap::WriteOptions::new()
            .compression(chunk_compression)
            .compression_level(level)
            .create(BufWriter::new(file))
            .with_context(|| format!("cannot write {name}"))?;
        let none = BTreeMap::new();
        let mut channel = |schema: &str, data: String, topic: &str| -> anyhow::Result<u16> {
            let id = writer
                .add_schema(schema, "jsonschema", data.as_bytes())
                .with_context(|| format!("cannot write the schema {schema} into {name}"))?;
            writer
                .add_channel(id, topic, "json", &none)
                .with_context(|| format!("cannot write the channel {topic} into {name}"))
        };
        let depth = channel("foxglove.RawImage", raw_image_schema(), DEPTH_TOPIC)?;
        let cloud = channel("foxglove.PointCloud", point_cloud_schema(), CLOUD_TOPIC)?;
        let estimate = channel(ESTIMATE_SCHEMA, estimate_schema(), ESTIMATE_TOPIC)?;
        let surfaces = channel(SURFACES_SCHEMA, surfaces_schema(), SURFACES_TOPIC)?;
        Ok(Self {
            writer,
            depth,
            cloud,
            estimate,
            surfaces,
            sequence: 0,
            path: name,
            pending,
        })
    }

    /// Writes one frame's messages.
    pub fn write(&mut self, frame: &McapFrame<'_>) -> anyhow::Result<()> {
        let stamp = time_json(frame.stamp_ns);
        // 16UC1 is millimetres by convention: other units are converted.
        let mm_per_count = frame.depth_unit_m * 1000.0;
        let depth_bytes: Vec<u8> = frame
            .depth
            .iter()
            .map(|&d| {
                (f64::from(d) * mm_per_count)
                    .round()
                    .min(f64::from(u16::MAX)) as u16
            })
            .flat_map(u16::to_le_bytes)
            .collect();
        let image = json!({
            "timestamp": stamp,
            "frame_id": FRAME_ID,
            "width": frame.width,
            "height": frame.height,
            "encoding": "16UC1",
            "step": frame.width * 2,
        });
        self.put_with_data(self.depth, frame.stamp_ns, &image, &depth_bytes)?;

        let mut cloud_bytes = Vec::with_capacity(frame.points.len() * 16);
        for p in frame.points.iter().filter(|p| p.is_valid()) {
            for v in [p.x_m, p.y_m, p.z_m] {
                cloud_bytes.extend_from_slice(&v.to_le_bytes());
            }
            cloud_bytes.extend_from_slice(&p.rgb.to_le_bytes());
        }
        let cloud = json!({
            "timestamp": stamp,
            "frame_id": FRAME_ID,
            "pose": {"position": {"x": 0, "y": 0, "z": 0},
                     "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}},
            "point_stride": 16,
            "fields": [
                {"name": "x", "offset": 0, "type": 7},
                {"name": "y", "offset": 4, "type": 7},
                {"name": "z", "offset": 8, "type": 7},
                {"name": "rgb", "offset": 12, "type": 5}
            ],
        });
        self.put_with_data(self.cloud, frame.stamp_ns, &cloud, &cloud_bytes)?;

        if let Some(estimate) = frame.estimate {
            self.write_estimate(estimate)?;
        }
        if let Some(surfaces) = frame.surfaces {
            self.write_surfaces(surfaces)?;
        }
        Ok(())
    }

    /// Writes a frame's surfaces, stamped with its capture time.
    pub fn write_surfaces(&mut self, surfaces: &Surfaces) -> anyhow::Result<()> {
        let mut value = serde_json::to_value(SurfacesJson::from(surfaces))
            .context("cannot write the surfaces as JSON")?;
        if let Some(object) = value.as_object_mut() {
            object.insert("schema".to_string(), json!(SURFACES_SCHEMA));
        }
        self.put(self.surfaces, surfaces.capture_stamp_ns, &value)
    }

    /// Writes an estimate, stamped with its frame's capture time (so that
    /// it lines up with the frame's depth and cloud).
    pub fn write_estimate(&mut self, estimate: &SlopeEstimate) -> anyhow::Result<()> {
        let mut value = serde_json::to_value(EstimateJson::from(estimate))
            .context("cannot write an estimate as JSON")?;
        if let Some(object) = value.as_object_mut() {
            object.insert("schema".to_string(), json!(ESTIMATE_SCHEMA));
        }
        self.put(self.estimate, estimate.capture_stamp_ns, &value)
    }

    fn put(
        &mut self,
        channel: u16,
        stamp_ns: u64,
        value: &serde_json::Value,
    ) -> anyhow::Result<()> {
        let data = serde_json::to_vec(value).context("cannot write a message as JSON")?;
        self.put_bytes(channel, stamp_ns, &data)
    }

    /// Writes the JSON object `value` with a `data` key holding `bytes` in
    /// base64, which is spliced in as it is encoded: base64 needs no JSON
    /// escapes, and serializing megabytes of it through `serde_json`
    /// (which looks at every byte for one) cost as much as encoding it.
    fn put_with_data(
        &mut self,
        channel: u16,
        stamp_ns: u64,
        value: &serde_json::Value,
        bytes: &[u8],
    ) -> anyhow::Result<()> {
        let data = json_with_data(value, bytes).context("cannot write a message as JSON")?;
        self.put_bytes(channel, stamp_ns, &data)
    }

    fn put_bytes(&mut self, channel: u16, stamp_ns: u64, data: &[u8]) -> anyhow::Result<()> {
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: self.sequence,
            log_time: stamp_ns,
            publish_time: stamp_ns,
        };
        self.sequence = self.sequence.wrapping_add(1);
        self.writer
            .write_to_known_channel(&header, data)
            .with_context(|| format!("cannot write a message into {}", self.path))
    }

    /// Writes the summary and closes the file (and, after
    /// [`Self::create_replacing`], renames it over its path).
    pub fn finish(mut self) -> anyhow::Result<()> {
        self.writer
            .finish()
            .with_context(|| format!("cannot finish {}", self.path))?;
        let file = self
            .writer
            .into_inner()
            .into_inner()
            .map_err(std::io::IntoInnerError::into_error)
            .with_context(|| format!("cannot finish {}", self.path))?;
        if let Some(Replacement {
            temp,
            path,
            unfinished,
        }) = self.pending
        {
            file.sync_all()
                .with_context(|| format!("cannot finish {}", self.path))?;
            unfinished
                .finish_with(|| temp.persist(&path))
                .map_err(|e| e.error)
                .with_context(|| format!("cannot rename the finished file to {}", self.path))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spliced message is the object with `data` added, as
    /// `serde_json` writes it (the oracle), for payloads of every length
    /// modulo 3 (base64 padding) and bytes of every value.
    #[test]
    fn a_spliced_data_key_is_the_json_serde_would_write() {
        let b64 = base64::engine::general_purpose::STANDARD;
        let value = json!({"frame_id": "slope_camera", "width": 3, "nested": {"a": [1, 2]}});
        for len in [0usize, 1, 2, 3, 4, 5, 255, 256, 1000] {
            let bytes: Vec<u8> = (0..len).map(|k| (k * 37 % 256) as u8).collect();
            let spliced = json_with_data(&value, &bytes).expect("json");
            let mut want = value.clone();
            want["data"] = json!(b64.encode(&bytes));
            let got: serde_json::Value = serde_json::from_slice(&spliced).expect("valid JSON");
            assert_eq!(got, want, "{len} bytes");
        }
        assert!(json_with_data(&json!({}), b"x").is_err());
        assert!(json_with_data(&json!([1]), b"x").is_err());
    }
}
