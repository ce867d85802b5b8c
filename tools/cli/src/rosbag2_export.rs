//! ROS 2 bags (`--format rosbag2` of `slope-convert` and `slope-record`):
//! a directory with `metadata.yaml` and one MCAP file (`<dir>_0.mcap`, the
//! `mcap` storage of rosbag2), every channel `cdr`-encoded with a
//! `ros2msg` schema ([`crate::ros2_messages`]), so that `ros2 bag play`,
//! `ros2 bag info` and the `rosbags` Python package read it.
//!
//! | topic | type | per frame |
//! |---|---|---|
//! | `/slope/depth` | `sensor_msgs/msg/Image` (`16UC1`, millimetres) | always |
//! | `/slope/camera_info` | `sensor_msgs/msg/CameraInfo` (`K`, `P`; no distortion) | always |
//! | `/slope/estimate` | `slope_msgs/msg/SlopeEstimate` (`ros2/slope_msgs`) | when estimated |
//! | `/tf_static` | `tf2_msgs/msg/TFMessage`: `base_link` to `slope_camera` | once, when the mount's height and pitch are known |
//!
//! Each message is logged at its frame's capture stamp. `metadata.yaml`
//! (version 5, Humble's; later releases read it too) is written
//! when the bag is finished; a bag cut short (a crash of `slope-record`)
//! holds its MCAP file without it (`ros2 bag reindex` makes it again).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::Context;
use serde::Serialize;
use slope_ipc_types::SlopeEstimate;
use slope_sensor::recording::RecordingMeta;

use crate::mcap_export::{McapCompression, McapFrame, DEPTH_TOPIC, ESTIMATE_TOPIC, FRAME_ID};
use crate::mount_transform::mount_to_transform;
use crate::ros2_messages::{
    to_cdr, CameraInfo, Header, Image, MessageType, SlopeEstimateMsg, TfMessage, Time,
    TransformStamped,
};
use crate::unfinished_files::UnfinishedFile;

pub const CAMERA_INFO_TOPIC: &str = "/slope/camera_info";
pub const TF_STATIC_TOPIC: &str = "/tf_static";
/// The robot's frame that `/tf_static` places the camera in.
pub const BASE_FRAME: &str = "base_link";
/// The `metadata.yaml` version written.
pub const METADATA_VERSION: u32 = 5;

/// One channel of the bag: its id, topic, type and message count.
struct Channel {
    id: u16,
    topic: &'static str,
    message_type: MessageType,
    count: u64,
}

/// A rosbag2 directory being written.
pub struct Rosbag2Exporter {
    writer: mcap::Writer<BufWriter<File>>,
    depth: Channel,
    camera_info: Channel,
    estimate: Channel,
    tf_static: Channel,
    sequence: u32,
    /// The smallest and largest log time written, ns.
    span: Option<(u64, u64)>,
    meta: RecordingMeta,
    dir: PathBuf,
    file_name: String,
    /// With `replacing`: the temporary MCAP file renamed into place when
    /// finished (a second signal removes it).
    pending: Option<(tempfile::TempPath, UnfinishedFile)>,
    /// Last, so that it is dropped after the temporary file is removed.
    created: CreatedDir,
}

/// The bag directory while it is written, when this run made it: removed
/// when the bag is dropped unfinished and the directory is empty (a run
/// that failed leaves nothing behind).
struct CreatedDir(Option<PathBuf>);

impl Drop for CreatedDir {
    fn drop(&mut self) {
        if let Some(dir) = self.0.take() {
            // Only an empty directory goes: remove_dir refuses any other.
            let _ = std::fs::remove_dir(dir);
        }
    }
}

/// The directory a bag goes into: new, or an empty directory; its parent
/// must exist. True when it was made here.
fn prepare_dir(dir: &Path) -> anyhow::Result<bool> {
    let name = dir.display();
    if dir.exists() {
        let empty = dir.is_dir()
            && std::fs::read_dir(dir)
                .with_context(|| format!("cannot read {name}"))?
                .next()
                .is_none();
        if !empty {
            anyhow::bail!(
                "{name} exists and is not an empty directory; a rosbag2 bag is a directory of its \
                 own: give a new name"
            );
        }
        return Ok(false);
    }
    let parent = match dir.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        anyhow::bail!(
            "cannot write {name}: the directory {} does not exist",
            parent.display()
        );
    }
    std::fs::create_dir(dir).with_context(|| format!("cannot create {name}"))?;
    Ok(true)
}

impl Rosbag2Exporter {
    /// Creates the bag directory `dir` (new or empty) with its MCAP file,
    /// the channels, and `/tf_static` when `meta`'s mount is known. With
    /// `replacing` (`slope-convert`) the MCAP file is written under a
    /// temporary name and renamed when finished; without it
    /// (`slope-record`) it is written in place as it goes.
    pub fn create(
        dir: &Path,
        compression: McapCompression,
        meta: &RecordingMeta,
        replacing: bool,
    ) -> anyhow::Result<Self> {
        let created = CreatedDir(prepare_dir(dir)?.then(|| dir.to_path_buf()));
        let stem = dir
            .file_name()
            .map_or_else(|| "bag".to_string(), |n| n.to_string_lossy().into_owned());
        let file_name = format!("{stem}_0.mcap");
        let path = dir.join(&file_name);
        let (file, pending) = if replacing {
            let (temp, unfinished) = UnfinishedFile::create(|| {
                tempfile::Builder::new()
                    .prefix(&format!(".{file_name}."))
                    .suffix(".part")
                    .tempfile_in(dir)
            })
            .with_context(|| format!("cannot create a temporary file in {}", dir.display()))?;
            let (file, temp) = temp.into_parts();
            (file, Some((temp, unfinished)))
        } else {
            let file =
                File::create(&path).with_context(|| format!("cannot create {}", path.display()))?;
            (file, None)
        };
        let mut exporter =
            Self::with_file(file, compression, meta, dir, file_name, pending, created)?;
        exporter.write_tf_static()?;
        Ok(exporter)
    }

    fn with_file(
        file: File,
        compression: McapCompression,
        meta: &RecordingMeta,
        dir: &Path,
        file_name: String,
        pending: Option<(tempfile::TempPath, UnfinishedFile)>,
        created: CreatedDir,
    ) -> anyhow::Result<Self> {
        let name = dir.join(&file_name).display().to_string();
        let (chunk_compression, level) = compression.chunk_compression();
        let mut writer = mcap::WriteOptions::new()
            .compression(chunk_compression)
            .compression_level(level)
            .profile("ros2")
            .create(BufWriter::new(file))
            .with_context(|| format!("cannot write {name}"))?;
        let none = BTreeMap::new();
        let mut channel = |topic: &'static str, message_type: MessageType| {
            let schema = writer
                .add_schema(
                    message_type.name(),
                    "ros2msg",
                    message_type.schema().as_bytes(),
                )
                .with_context(|| {
                    format!(
                        "cannot write the schema {} into {name}",
                        message_type.name()
                    )
                })?;
            let id = writer
                .add_channel(schema, topic, "cdr", &none)
                .with_context(|| format!("cannot write the channel {topic} into {name}"))?;
            anyhow::Ok(Channel {
                id,
                topic,
                message_type,
                count: 0,
            })
        };
        let depth = channel(DEPTH_TOPIC, MessageType::Image)?;
        let camera_info = channel(CAMERA_INFO_TOPIC, MessageType::CameraInfo)?;
        let estimate = channel(ESTIMATE_TOPIC, MessageType::SlopeEstimate)?;
        let tf_static = channel(TF_STATIC_TOPIC, MessageType::TfMessage)?;
        Ok(Self {
            writer,
            depth,
            camera_info,
            estimate,
            tf_static,
            sequence: 0,
            span: None,
            meta: meta.clone(),
            dir: dir.to_path_buf(),
            file_name,
            pending,
            created,
        })
    }

    /// `/tf_static` with the camera in `base_link`, when the mount says
    /// where (at stamp 0: it holds for the whole bag).
    fn write_tf_static(&mut self) -> anyhow::Result<()> {
        let Some(transform) = mount_to_transform(&self.meta.mount) else {
            return Ok(());
        };
        let message = TfMessage {
            transforms: vec![TransformStamped {
                header: Header {
                    stamp: Time::default(),
                    frame_id: BASE_FRAME.to_string(),
                },
                child_frame_id: FRAME_ID.to_string(),
                transform,
            }],
        };
        self.put(Which::TfStatic, 0, &message)
    }

    /// Writes one frame's depth image and camera info (and its estimate).
    pub fn write(&mut self, frame: &McapFrame<'_>) -> anyhow::Result<()> {
        let header = Header {
            stamp: Time::from_ns(frame.stamp_ns),
            frame_id: FRAME_ID.to_string(),
        };
        // 16UC1 is millimetres by convention: other units are converted.
        let mm_per_count = frame.depth_unit_m * 1000.0;
        let data: Vec<u8> = frame
            .depth
            .iter()
            .map(|&d| {
                (f64::from(d) * mm_per_count)
                    .round()
                    .min(f64::from(u16::MAX)) as u16
            })
            .flat_map(u16::to_le_bytes)
            .collect();
        let image = Image {
            header: header.clone(),
            height: frame.height,
            width: frame.width,
            encoding: "16UC1".to_string(),
            is_bigendian: 0,
            step: frame.width * 2,
            data,
        };
        self.put(Which::Depth, frame.stamp_ns, &image)?;
        let depth = &self.meta.depth;
        let info = CameraInfo::pinhole(
            header,
            frame.width,
            frame.height,
            depth.fx,
            depth.fy,
            depth.cx,
            depth.cy,
        );
        self.put(Which::CameraInfo, frame.stamp_ns, &info)?;
        if let Some(estimate) = frame.estimate {
            self.write_estimate(estimate)?;
        }
        Ok(())
    }

    /// Writes an estimate, logged at its frame's capture stamp.
    pub fn write_estimate(&mut self, estimate: &SlopeEstimate) -> anyhow::Result<()> {
        let message = SlopeEstimateMsg::new(estimate, FRAME_ID);
        self.put(Which::Estimate, estimate.capture_stamp_ns, &message)
    }

    fn channel(&mut self, which: Which) -> &mut Channel {
        match which {
            Which::Depth => &mut self.depth,
            Which::CameraInfo => &mut self.camera_info,
            Which::Estimate => &mut self.estimate,
            Which::TfStatic => &mut self.tf_static,
        }
    }

    fn put<T: Serialize>(
        &mut self,
        which: Which,
        stamp_ns: u64,
        message: &T,
    ) -> anyhow::Result<()> {
        let channel = self.channel(which);
        let data = to_cdr(message).map_err(|e| {
            anyhow::anyhow!("cannot write a {} as CDR: {e}", channel.message_type.name())
        })?;
        channel.count += 1;
        let header = mcap::records::MessageHeader {
            channel_id: channel.id,
            sequence: self.sequence,
            log_time: stamp_ns,
            publish_time: stamp_ns,
        };
        self.sequence = self.sequence.wrapping_add(1);
        self.span = Some(match self.span {
            Some((first, last)) => (first.min(stamp_ns), last.max(stamp_ns)),
            None => (stamp_ns, stamp_ns),
        });
        let name = self.dir.join(&self.file_name);
        self.writer
            .write_to_known_channel(&header, &data)
            .with_context(|| format!("cannot write a message into {}", name.display()))
    }

    /// Finishes the MCAP file (renaming it into place after a `replacing`
    /// create) and writes `metadata.yaml`.
    pub fn finish(mut self) -> anyhow::Result<()> {
        // Finished or failed, the bag's directory stays from here on.
        self.created.0 = None;
        let path = self.dir.join(&self.file_name);
        let name = path.display().to_string();
        self.writer
            .finish()
            .with_context(|| format!("cannot finish {name}"))?;
        let metadata = self.metadata_yaml()?;
        let file = self
            .writer
            .into_inner()
            .into_inner()
            .map_err(std::io::IntoInnerError::into_error)
            .with_context(|| format!("cannot finish {name}"))?;
        if let Some((temp, unfinished)) = self.pending {
            file.sync_all()
                .with_context(|| format!("cannot finish {name}"))?;
            unfinished
                .finish_with(|| temp.persist(&path))
                .map_err(|e| e.error)
                .with_context(|| format!("cannot rename the finished file to {name}"))?;
        }
        let meta_path = self.dir.join("metadata.yaml");
        std::fs::write(&meta_path, metadata)
            .with_context(|| format!("cannot write {}", meta_path.display()))
    }

    /// `metadata.yaml` of the bag as written so far.
    fn metadata_yaml(&self) -> anyhow::Result<String> {
        let (start, end) = self.span.unwrap_or((0, 0));
        let channels = [
            &self.depth,
            &self.camera_info,
            &self.estimate,
            &self.tf_static,
        ];
        let message_count: u64 = channels.iter().map(|c| c.count).sum();
        let topics = channels
            .iter()
            .map(|c| TopicWithCount {
                topic_metadata: TopicMetadata {
                    name: c.topic.to_string(),
                    message_type: c.message_type.name().to_string(),
                    serialization_format: "cdr".to_string(),
                    offered_qos_profiles: String::new(),
                },
                message_count: c.count,
            })
            .collect();
        let info = BagInformation {
            version: METADATA_VERSION,
            storage_identifier: "mcap".to_string(),
            duration: Nanoseconds {
                nanoseconds: end - start,
            },
            starting_time: SinceEpoch {
                nanoseconds_since_epoch: start,
            },
            message_count,
            topics_with_message_count: topics,
            compression_format: String::new(),
            compression_mode: String::new(),
            relative_file_paths: vec![self.file_name.clone()],
            files: vec![FileInformation {
                path: self.file_name.clone(),
                starting_time: SinceEpoch {
                    nanoseconds_since_epoch: start,
                },
                duration: Nanoseconds {
                    nanoseconds: end - start,
                },
                message_count,
            }],
        };
        serde_yaml::to_string(&Metadata {
            rosbag2_bagfile_information: info,
        })
        .context("cannot write metadata.yaml")
    }
}

#[derive(Debug, Clone, Copy)]
enum Which {
    Depth,
    CameraInfo,
    Estimate,
    TfStatic,
}

/// `metadata.yaml`, as rosbag2 writes it (version 5).
#[derive(Serialize)]
struct Metadata {
    rosbag2_bagfile_information: BagInformation,
}

#[derive(Serialize)]
struct BagInformation {
    version: u32,
    storage_identifier: String,
    duration: Nanoseconds,
    starting_time: SinceEpoch,
    message_count: u64,
    topics_with_message_count: Vec<TopicWithCount>,
    compression_format: String,
    compression_mode: String,
    relative_file_paths: Vec<String>,
    files: Vec<FileInformation>,
}

#[derive(Serialize)]
struct Nanoseconds {
    nanoseconds: u64,
}

#[derive(Serialize)]
struct SinceEpoch {
    nanoseconds_since_epoch: u64,
}

#[derive(Serialize)]
struct TopicWithCount {
    topic_metadata: TopicMetadata,
    message_count: u64,
}

#[derive(Serialize)]
struct TopicMetadata {
    name: String,
    #[serde(rename = "type")]
    message_type: String,
    serialization_format: String,
    offered_qos_profiles: String,
}

#[derive(Serialize)]
struct FileInformation {
    path: String,
    starting_time: SinceEpoch,
    duration: Nanoseconds,
    message_count: u64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use slope_sensor::recording::{DepthInfo, MountInfo, TruthInfo};

    fn meta() -> RecordingMeta {
        RecordingMeta {
            sensor: "synthetic".to_string(),
            depth: DepthInfo {
                width: 2,
                height: 1,
                unit_m: 0.001,
                fx: 365.0,
                fy: 365.0,
                cx: 0.5,
                cy: 0.0,
            },
            mount: MountInfo {
                height_m: Some(0.5),
                pitch_deg: Some(-20.0),
                roll_deg: None,
            },
            truth: TruthInfo::default(),
        }
    }

    #[test]
    fn an_unfinished_bag_leaves_no_directory_and_a_finished_one_its_two_files() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("bag");
        let bag = Rosbag2Exporter::create(&dir, McapCompression::Zstd, &meta(), true).unwrap();
        drop(bag);
        assert!(!dir.exists(), "an unfinished bag's directory is removed");

        let mut bag = Rosbag2Exporter::create(&dir, McapCompression::None, &meta(), true).unwrap();
        let estimate = SlopeEstimate {
            capture_stamp_ns: 7,
            ..SlopeEstimate::default()
        };
        bag.write(&McapFrame {
            stamp_ns: 7,
            width: 2,
            height: 1,
            depth: &[1500, 0],
            depth_unit_m: 0.001,
            points: &[],
            estimate: Some(&estimate),
            surfaces: None,
        })
        .unwrap();
        bag.finish().unwrap();
        let mut names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["bag_0.mcap", "metadata.yaml"]);
        let bytes = std::fs::read(dir.join("bag_0.mcap")).unwrap();
        let mut seen = Vec::new();
        for message in mcap::MessageStream::new(&bytes).unwrap() {
            let message = message.unwrap();
            let schema = message.channel.schema.as_ref().unwrap();
            assert_eq!(schema.encoding, "ros2msg");
            assert_eq!(message.channel.message_encoding, "cdr");
            seen.push((
                message.channel.topic.clone(),
                schema.name.clone(),
                message.log_time,
            ));
        }
        assert_eq!(
            seen,
            [
                (
                    "/tf_static".to_string(),
                    "tf2_msgs/msg/TFMessage".to_string(),
                    0
                ),
                (
                    "/slope/depth".to_string(),
                    "sensor_msgs/msg/Image".to_string(),
                    7
                ),
                (
                    "/slope/camera_info".to_string(),
                    "sensor_msgs/msg/CameraInfo".to_string(),
                    7
                ),
                (
                    "/slope/estimate".to_string(),
                    "slope_msgs/msg/SlopeEstimate".to_string(),
                    7
                ),
            ]
        );
        let yaml = std::fs::read_to_string(dir.join("metadata.yaml")).unwrap();
        assert!(yaml.contains("message_count: 4"), "{yaml}");
        assert!(yaml.contains("storage_identifier: mcap"), "{yaml}");
    }
}
