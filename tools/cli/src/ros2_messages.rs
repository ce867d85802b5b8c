//! The ROS 2 messages of a rosbag2 export (and of `slope-import`'s ROS 2
//! bags) as serde structs, and their definitions as rosbag2 stores them
//! (`ros2msg`: the message's `.msg` text, then each type it uses after a
//! line of 80 `=` and `MSG: <type>`, as `ros2 bag record` writes them).
//!
//! The structs list the fields in the order of their `.msg` files, which
//! is all CDR needs: the `cdr` crate writes and reads them (the 4-byte
//! encapsulation header, little-endian, with CDR's alignment), the field
//! names are only for us. `slope_msgs/msg/SlopeEstimate` is
//! `ros2/slope_msgs/msg/SlopeEstimate.msg`, included here as it is.

use serde::{Deserialize, Serialize};
use slope_ipc_types::SlopeEstimate;

/// `builtin_interfaces/msg/Time`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Time {
    pub sec: i32,
    pub nanosec: u32,
}

impl Time {
    /// A stamp in ns since the Unix epoch; seconds beyond `i32` (the year
    /// 2038) saturate.
    pub fn from_ns(stamp_ns: u64) -> Self {
        Self {
            sec: i32::try_from(stamp_ns / 1_000_000_000).unwrap_or(i32::MAX),
            // Below 1e9: fits.
            nanosec: (stamp_ns % 1_000_000_000) as u32,
        }
    }

    /// ns since the Unix epoch; `None` before it.
    pub fn to_ns(self) -> Option<u64> {
        let sec = u64::try_from(self.sec).ok()?;
        Some(sec * 1_000_000_000 + u64::from(self.nanosec))
    }
}

/// `std_msgs/msg/Header`.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Header {
    pub stamp: Time,
    pub frame_id: String,
}

/// `sensor_msgs/msg/Image`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Image {
    pub header: Header,
    pub height: u32,
    pub width: u32,
    pub encoding: String,
    pub is_bigendian: u8,
    pub step: u32,
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}

/// `sensor_msgs/msg/CompressedImage`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CompressedImage {
    pub header: Header,
    pub format: String,
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}

/// `sensor_msgs/msg/RegionOfInterest`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RegionOfInterest {
    pub x_offset: u32,
    pub y_offset: u32,
    pub height: u32,
    pub width: u32,
    pub do_rectify: bool,
}

/// `sensor_msgs/msg/CameraInfo`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CameraInfo {
    pub header: Header,
    pub height: u32,
    pub width: u32,
    pub distortion_model: String,
    pub d: Vec<f64>,
    pub k: [f64; 9],
    pub r: [f64; 9],
    pub p: [f64; 12],
    pub binning_x: u32,
    pub binning_y: u32,
    pub roi: RegionOfInterest,
}

impl CameraInfo {
    /// The camera info of an undistorted (rectified) pinhole image:
    /// `plumb_bob` with zero distortion, `K` and `P` from the intrinsics
    /// (pixel centres at integer coordinates, as in ROS and in a
    /// recording), `R` the identity.
    pub fn pinhole(
        header: Header,
        width: u32,
        height: u32,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
    ) -> Self {
        Self {
            header,
            height,
            width,
            distortion_model: "plumb_bob".to_string(),
            d: vec![0.0; 5],
            k: [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
            r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            p: [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
            binning_x: 0,
            binning_y: 0,
            roi: RegionOfInterest::default(),
        }
    }
}

/// `geometry_msgs/msg/Vector3`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

/// `geometry_msgs/msg/Transform`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    pub translation: Vector3,
    pub rotation: Quaternion,
}

/// `geometry_msgs/msg/TransformStamped`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped {
    pub header: Header,
    pub child_frame_id: String,
    pub transform: Transform,
}

/// `tf2_msgs/msg/TFMessage` (`/tf_static`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TfMessage {
    pub transforms: Vec<TransformStamped>,
}

/// `slope_msgs/msg/SlopeEstimate`: a `std_msgs/Header` (stamp: the
/// capture stamp, frame id: the camera's) and every field of
/// `slope.SlopeEstimate.v2`, in its order.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SlopeEstimateMsg {
    pub header: Header,
    pub frame_index: u64,
    pub capture_stamp_ns: u64,
    pub publish_stamp_ns: u64,
    pub source_stamp_ns: u64,
    pub dropped_frames: u64,
    pub status: u32,
    pub method: u32,
    pub slope_deg: f64,
    pub slope_std_deg: f64,
    pub distance_m: f64,
    pub ground_plane: [f64; 4],
    pub inclined_plane: [f64; 4],
    pub ground_inliers: u32,
    pub inclined_inliers: u32,
    pub samples: u32,
    pub ground_from_mount: u32,
    pub processing_us: u64,
    pub confidence: f64,
    pub confidence_reasons: u32,
    pub ground_seen_to_m: f32,
    pub ground_rms_m: f64,
    pub inclined_rms_m: f64,
    pub ground_area_m2: f64,
    pub inclined_area_m2: f64,
    pub tracked_slope_deg: f64,
    pub tracked_std_deg: f64,
    pub tracked_frames: u32,
    pub tracked_accepted: u32,
}

impl SlopeEstimateMsg {
    /// The message of `estimate`, in the camera frame `frame_id`.
    pub fn new(estimate: &SlopeEstimate, frame_id: &str) -> Self {
        let e = estimate;
        Self {
            header: Header {
                stamp: Time::from_ns(e.capture_stamp_ns),
                frame_id: frame_id.to_string(),
            },
            frame_index: e.frame_index,
            capture_stamp_ns: e.capture_stamp_ns,
            publish_stamp_ns: e.publish_stamp_ns,
            source_stamp_ns: e.source_stamp_ns,
            dropped_frames: e.dropped_frames,
            status: e.status,
            method: e.method,
            slope_deg: e.slope_deg,
            slope_std_deg: e.slope_std_deg,
            distance_m: e.distance_m,
            ground_plane: e.ground_plane,
            inclined_plane: e.inclined_plane,
            ground_inliers: e.ground_inliers,
            inclined_inliers: e.inclined_inliers,
            samples: e.samples,
            ground_from_mount: e.ground_from_mount,
            processing_us: e.processing_us,
            confidence: e.confidence,
            confidence_reasons: e.confidence_reasons,
            ground_seen_to_m: e.ground_seen_to_m,
            ground_rms_m: e.ground_rms_m,
            inclined_rms_m: e.inclined_rms_m,
            ground_area_m2: e.ground_area_m2,
            inclined_area_m2: e.inclined_area_m2,
            tracked_slope_deg: e.tracked_slope_deg,
            tracked_std_deg: e.tracked_std_deg,
            tracked_frames: e.tracked_frames,
            tracked_accepted: e.tracked_accepted,
        }
    }
}

/// Serialises a message as CDR, little-endian, with its encapsulation
/// header (what a ROS 2 bag holds).
pub fn to_cdr<T: Serialize>(message: &T) -> Result<Vec<u8>, cdr::Error> {
    cdr::serialize::<_, _, cdr::CdrLe>(message, cdr::Infinite)
}

/// Reads a CDR message (either byte order, after its encapsulation
/// header).
pub fn from_cdr<T: serde::de::DeserializeOwned>(data: &[u8]) -> Result<T, cdr::Error> {
    cdr::deserialize(data)
}

/// `slope_msgs/msg/SlopeEstimate` as shipped in `ros2/slope_msgs`.
pub const SLOPE_ESTIMATE_MSG: &str = include_str!("../../../ros2/slope_msgs/msg/SlopeEstimate.msg");

const SEPARATOR: &str =
    "================================================================================";

const TIME_MSG: &str = "int32 sec\nuint32 nanosec\n";
const HEADER_MSG: &str = "builtin_interfaces/Time stamp\nstring frame_id\n";
const IMAGE_MSG: &str = "std_msgs/Header header\nuint32 height\nuint32 width\n\
string encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n";
const ROI_MSG: &str =
    "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n";
const CAMERA_INFO_MSG: &str = "std_msgs/Header header\nuint32 height\nuint32 width\n\
string distortion_model\nfloat64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\n\
uint32 binning_x\nuint32 binning_y\nsensor_msgs/RegionOfInterest roi\n";
const VECTOR3_MSG: &str = "float64 x\nfloat64 y\nfloat64 z\n";
const QUATERNION_MSG: &str = "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";
const TRANSFORM_MSG: &str =
    "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n";
const TRANSFORM_STAMPED_MSG: &str =
    "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n";
const TF_MESSAGE_MSG: &str = "geometry_msgs/TransformStamped[] transforms\n";

/// The `ros2msg` text of `main` and the types it uses (`(name, text)`,
/// each once, in the order they first appear).
fn definition(main: &str, uses: &[(&str, &str)]) -> String {
    let mut text = main.to_string();
    for (name, body) in uses {
        text.push_str(&format!("{SEPARATOR}\nMSG: {name}\n{body}"));
    }
    text
}

/// A message type a rosbag2 export writes: its name and `ros2msg` schema.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MessageType {
    Image,
    CameraInfo,
    TfMessage,
    SlopeEstimate,
}

impl MessageType {
    /// The type's name as ROS 2 spells it (`sensor_msgs/msg/Image`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Image => "sensor_msgs/msg/Image",
            Self::CameraInfo => "sensor_msgs/msg/CameraInfo",
            Self::TfMessage => "tf2_msgs/msg/TFMessage",
            Self::SlopeEstimate => "slope_msgs/msg/SlopeEstimate",
        }
    }

    /// The `ros2msg` schema: the message's definition and those it uses.
    pub fn schema(self) -> String {
        let header = ("std_msgs/Header", HEADER_MSG);
        let time = ("builtin_interfaces/Time", TIME_MSG);
        match self {
            Self::Image => definition(IMAGE_MSG, &[header, time]),
            Self::CameraInfo => definition(
                CAMERA_INFO_MSG,
                &[header, time, ("sensor_msgs/RegionOfInterest", ROI_MSG)],
            ),
            Self::TfMessage => definition(
                TF_MESSAGE_MSG,
                &[
                    ("geometry_msgs/TransformStamped", TRANSFORM_STAMPED_MSG),
                    header,
                    time,
                    ("geometry_msgs/Transform", TRANSFORM_MSG),
                    ("geometry_msgs/Vector3", VECTOR3_MSG),
                    ("geometry_msgs/Quaternion", QUATERNION_MSG),
                ],
            ),
            Self::SlopeEstimate => definition(SLOPE_ESTIMATE_MSG, &[header, time]),
        }
    }
}

/// The field lines of a `.msg` text as `(type, name)`: comments, constants
/// and blank lines left out (the tests hold our `.msg` files to the
/// messages they describe).
pub fn msg_fields(text: &str) -> Vec<(String, String)> {
    text.lines()
        .map(|line| line.split('#').next().unwrap_or("").trim())
        .filter(|line| !line.is_empty() && !line.contains('='))
        .map(|line| {
            let mut words = line.split_whitespace();
            let ty = words.next().unwrap_or("").to_string();
            let name = words.next().unwrap_or("").to_string();
            (ty, name)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use slope_ipc_types::layout;

    /// The size of one value of a `.msg` type (`float64[4]`: 32).
    fn size_of_type(ty: &str) -> usize {
        let (base, count) = match ty.split_once('[') {
            Some((base, rest)) => (base, rest.trim_end_matches(']').parse().unwrap()),
            None => (ty, 1),
        };
        let one = match base {
            "uint64" | "int64" | "float64" => 8,
            "uint32" | "int32" | "float32" => 4,
            other => panic!("unexpected type {other}"),
        };
        one * count
    }

    #[test]
    fn the_msg_file_has_every_field_of_the_estimate_in_order() {
        let msg = msg_fields(SLOPE_ESTIMATE_MSG);
        assert_eq!(msg[0], ("std_msgs/Header".into(), "header".into()));
        let rust = layout::slope_estimate();
        let names: Vec<&str> = msg[1..].iter().map(|(_, n)| n.as_str()).collect();
        let rust_names: Vec<&str> = rust.iter().map(|f| f.name).collect();
        assert_eq!(names, rust_names);
        for ((ty, name), field) in msg[1..].iter().zip(&rust) {
            assert_eq!(size_of_type(ty), field.size, "{name}: {ty}");
        }
    }

    /// `NAME=value` of every constant of a `.msg` text.
    fn constants(text: &str) -> Vec<(String, u32)> {
        text.lines()
            .map(|line| line.split('#').next().unwrap_or("").trim())
            .filter_map(|line| line.split_once('='))
            .map(|(left, value)| {
                let name = left.split_whitespace().last().unwrap_or("").to_string();
                (name, value.trim().parse().unwrap())
            })
            .collect()
    }

    #[test]
    fn the_msg_constants_are_the_statuses_methods_and_reasons() {
        use slope_ipc_types::{confidence, EstimateStatus, SlopeMethod};
        let mut expected: Vec<(String, u32)> = Vec::new();
        for status in EstimateStatus::ALL {
            expected.push((
                format!("STATUS_{}", status.name().to_uppercase()),
                status as u32,
            ));
        }
        for method in SlopeMethod::ALL {
            let name = method.name().replace('-', "_").to_uppercase();
            expected.push((format!("METHOD_{name}"), method as u32));
        }
        for (bit, name) in confidence::ALL {
            expected.push((format!("REASON_{}", name.to_uppercase()), bit));
        }
        assert_eq!(constants(SLOPE_ESTIMATE_MSG), expected);
    }

    #[test]
    fn an_estimate_round_trips_through_cdr() {
        let estimate = SlopeEstimate {
            frame_index: 7,
            capture_stamp_ns: 1_700_000_000_123_456_789,
            slope_deg: 16.25,
            ground_seen_to_m: 3.5,
            tracked_frames: 4,
            ..SlopeEstimate::default()
        };
        let message = SlopeEstimateMsg::new(&estimate, "slope_camera");
        let bytes = to_cdr(&message).unwrap();
        // CDR_LE's encapsulation header.
        assert_eq!(&bytes[..4], &[0, 1, 0, 0]);
        let back: SlopeEstimateMsg = from_cdr(&bytes).unwrap();
        assert_eq!(
            back.header.stamp,
            Time {
                sec: 1_700_000_000,
                nanosec: 123_456_789
            }
        );
        assert_eq!(back.frame_index, 7);
        assert_eq!(back.slope_deg, 16.25);
        assert_eq!(back.ground_seen_to_m, 3.5);
        assert_eq!(back.tracked_frames, 4);
        assert!(back.distance_m.is_nan());
    }
}
