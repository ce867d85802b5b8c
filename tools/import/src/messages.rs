//! The messages an import reads, decoded from either serialisation into
//! the ROS 2 structs of [`slope_tools::ros2_messages`]: CDR with the `cdr`
//! crate, ROS 1 with `serde_rosmsg` into the ROS 1 layouts below (a
//! `seq` in the header, `uint32` seconds) and then converted.

use serde::de::DeserializeOwned;
use serde::Deserialize;
use slope_tools::ros2_messages::{
    from_cdr, CameraInfo, CompressedImage, Header, Image, RegionOfInterest, TfMessage, Time,
    Transform, TransformStamped,
};

use crate::bag::Serialization;

/// A message that does not decode as its type.
#[derive(Debug, thiserror::Error)]
#[error("a {message_type} message does not decode: {reason}")]
pub struct DecodeError {
    pub message_type: &'static str,
    pub reason: String,
}

/// A message type the import reads, in both serialisations.
pub trait Decode: Sized {
    const TYPE: &'static str;
    /// The ROS 1 layout, converted into `Self`.
    type Ros1: DeserializeOwned + Into<Self>;

    fn decode(data: &[u8], serialization: Serialization) -> Result<Self, DecodeError>
    where
        Self: DeserializeOwned,
    {
        let error = |reason: String| DecodeError {
            message_type: Self::TYPE,
            reason,
        };
        match serialization {
            Serialization::Cdr => from_cdr(data).map_err(|e| error(e.to_string())),
            Serialization::Ros1 => {
                let length = u32::try_from(data.len()).map_err(|_| error("over 4 GiB".into()))?;
                let mut deserializer =
                    serde_rosmsg::de::Deserializer::new(std::io::Cursor::new(data), length);
                Self::Ros1::deserialize(&mut deserializer)
                    .map(Into::into)
                    .map_err(|e| error(e.to_string()))
            }
        }
    }
}

#[derive(Debug, Deserialize)]
pub struct Ros1Time {
    sec: u32,
    nsec: u32,
}

#[derive(Debug, Deserialize)]
pub struct Ros1Header {
    _seq: u32,
    stamp: Ros1Time,
    frame_id: String,
}

impl From<Ros1Header> for Header {
    fn from(h: Ros1Header) -> Self {
        Header {
            stamp: Time {
                // ROS 1 seconds are unsigned; beyond i32 (2038) they saturate.
                sec: i32::try_from(h.stamp.sec).unwrap_or(i32::MAX),
                nanosec: h.stamp.nsec,
            },
            frame_id: h.frame_id,
        }
    }
}

#[derive(Debug, Deserialize)]
pub struct Ros1Image {
    header: Ros1Header,
    height: u32,
    width: u32,
    encoding: String,
    is_bigendian: u8,
    step: u32,
    #[serde(with = "serde_bytes")]
    data: Vec<u8>,
}

impl From<Ros1Image> for Image {
    fn from(m: Ros1Image) -> Self {
        Image {
            header: m.header.into(),
            height: m.height,
            width: m.width,
            encoding: m.encoding,
            is_bigendian: m.is_bigendian,
            step: m.step,
            data: m.data,
        }
    }
}

impl Decode for Image {
    const TYPE: &'static str = "sensor_msgs/Image";
    type Ros1 = Ros1Image;
}

#[derive(Debug, Deserialize)]
pub struct Ros1CompressedImage {
    header: Ros1Header,
    format: String,
    #[serde(with = "serde_bytes")]
    data: Vec<u8>,
}

impl From<Ros1CompressedImage> for CompressedImage {
    fn from(m: Ros1CompressedImage) -> Self {
        CompressedImage {
            header: m.header.into(),
            format: m.format,
            data: m.data,
        }
    }
}

impl Decode for CompressedImage {
    const TYPE: &'static str = "sensor_msgs/CompressedImage";
    type Ros1 = Ros1CompressedImage;
}

#[derive(Debug, Deserialize)]
pub struct Ros1CameraInfo {
    header: Ros1Header,
    height: u32,
    width: u32,
    distortion_model: String,
    d: Vec<f64>,
    k: [f64; 9],
    r: [f64; 9],
    p: [f64; 12],
    binning_x: u32,
    binning_y: u32,
    roi: RegionOfInterest,
}

impl From<Ros1CameraInfo> for CameraInfo {
    fn from(m: Ros1CameraInfo) -> Self {
        CameraInfo {
            header: m.header.into(),
            height: m.height,
            width: m.width,
            distortion_model: m.distortion_model,
            d: m.d,
            k: m.k,
            r: m.r,
            p: m.p,
            binning_x: m.binning_x,
            binning_y: m.binning_y,
            roi: m.roi,
        }
    }
}

impl Decode for CameraInfo {
    const TYPE: &'static str = "sensor_msgs/CameraInfo";
    type Ros1 = Ros1CameraInfo;
}

#[derive(Debug, Deserialize)]
pub struct Ros1TransformStamped {
    header: Ros1Header,
    child_frame_id: String,
    transform: Transform,
}

#[derive(Debug, Deserialize)]
pub struct Ros1TfMessage {
    transforms: Vec<Ros1TransformStamped>,
}

impl From<Ros1TfMessage> for TfMessage {
    fn from(m: Ros1TfMessage) -> Self {
        TfMessage {
            transforms: m
                .transforms
                .into_iter()
                .map(|t| TransformStamped {
                    header: t.header.into(),
                    child_frame_id: t.child_frame_id,
                    transform: t.transform,
                })
                .collect(),
        }
    }
}

impl Decode for TfMessage {
    const TYPE: &'static str = "tf2_msgs/TFMessage";
    type Ros1 = Ros1TfMessage;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ROS 1 `std_msgs/Header` followed by `tail`, serialised by hand
    /// (little-endian, strings and arrays with a u32 length).
    fn ros1_header(tail: &[u8]) -> Vec<u8> {
        let mut data = Vec::new();
        data.extend(7u32.to_le_bytes());
        data.extend(1_700_000_000u32.to_le_bytes());
        data.extend(250u32.to_le_bytes());
        data.extend(3u32.to_le_bytes());
        data.extend(b"cam");
        data.extend(tail);
        data
    }

    #[test]
    fn a_ros1_image_decodes_with_its_header() {
        let mut tail = Vec::new();
        tail.extend(1u32.to_le_bytes()); // height
        tail.extend(2u32.to_le_bytes()); // width
        tail.extend(5u32.to_le_bytes());
        tail.extend(b"16UC1");
        tail.push(0); // is_bigendian
        tail.extend(4u32.to_le_bytes()); // step
        tail.extend(4u32.to_le_bytes());
        tail.extend([1, 2, 3, 4]);
        let image = Image::decode(&ros1_header(&tail), Serialization::Ros1).unwrap();
        assert_eq!(
            image.header.stamp,
            Time {
                sec: 1_700_000_000,
                nanosec: 250
            }
        );
        assert_eq!(image.header.frame_id, "cam");
        assert_eq!((image.width, image.height, image.step), (2, 1, 4));
        assert_eq!(image.encoding, "16UC1");
        assert_eq!(image.data, [1, 2, 3, 4]);
    }

    #[test]
    fn a_cut_message_is_an_error_naming_its_type() {
        let err = Image::decode(&ros1_header(&[1, 0]), Serialization::Ros1).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("a sensor_msgs/Image message does not decode"),
            "{err}"
        );
        let err = CameraInfo::decode(&[0, 1, 0, 0, 9], Serialization::Cdr).unwrap_err();
        assert!(err.to_string().contains("sensor_msgs/CameraInfo"), "{err}");
    }
}
