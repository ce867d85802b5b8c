//! Which topics an import reads: the depth images, their camera info,
//! the registered colour images and `/tf_static`, by type (and name), or
//! as `--depth-topic`, `--info-topic` and `--color-topic` say.

use crate::bag::TopicInfo;

pub const IMAGE: &str = "sensor_msgs/Image";
pub const COMPRESSED_IMAGE: &str = "sensor_msgs/CompressedImage";
pub const CAMERA_INFO: &str = "sensor_msgs/CameraInfo";
pub const TF_MESSAGE: &str = "tf2_msgs/TFMessage";
pub const TF_STATIC: &str = "/tf_static";

/// How the depth topic's images come.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthKind {
    /// `sensor_msgs/Image` (16UC1, mono16, 32FC1).
    Raw,
    /// `sensor_msgs/CompressedImage` (compressedDepth).
    Compressed,
}

/// The topics an import reads.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Chosen {
    pub depth: String,
    pub kind: DepthKind,
    pub info: String,
    /// The registered colour images (`sensor_msgs/Image` of the depth
    /// image's size), when there are.
    pub color: Option<String>,
    /// `/tf_static`, when the bag has it as `tf2_msgs/TFMessage`.
    pub tf_static: Option<String>,
}

/// The topics asked for on the command line.
#[derive(Debug, Clone, Copy, Default)]
pub struct Wanted<'a> {
    pub depth: Option<&'a str>,
    pub info: Option<&'a str>,
    pub color: Option<&'a str>,
    /// `--no-color`: no colour topic, not even one named.
    pub no_color: bool,
}

/// Why no topics could be chosen.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum TopicError {
    #[error("the bag has no depth topic (an image topic whose name contains 'depth'); its image topics: {0}; choose one with --depth-topic")]
    NoDepth(String),
    #[error("the bag has several depth topics: {0}; choose one with --depth-topic")]
    SeveralDepth(String),
    #[error("--depth-topic {topic}: {reason}")]
    BadDepth { topic: String, reason: String },
    #[error(
        "the bag has no camera info (sensor_msgs/CameraInfo) topic; the intrinsics come from it"
    )]
    NoInfo,
    #[error("the bag has several camera info topics: {0}; choose one with --info-topic")]
    SeveralInfo(String),
    #[error("--info-topic {topic}: {reason}")]
    BadInfo { topic: String, reason: String },
    #[error("--color-topic {topic}: {reason}")]
    BadColor { topic: String, reason: String },
}

fn names(topics: &[&TopicInfo]) -> String {
    if topics.is_empty() {
        return "none".to_string();
    }
    topics
        .iter()
        .map(|t| format!("{} ({})", t.name, t.message_type))
        .collect::<Vec<_>>()
        .join(", ")
}

fn kind_of(topic: &TopicInfo) -> Option<DepthKind> {
    match topic.plain_type().as_str() {
        IMAGE => Some(DepthKind::Raw),
        COMPRESSED_IMAGE => Some(DepthKind::Compressed),
        _ => None,
    }
}

/// The namespace of an image topic: without its last name, and without a
/// transport's (`/compressed`, `/compressedDepth`) before that.
fn namespace(topic: &str) -> &str {
    let mut topic = topic;
    for transport in ["/compressedDepth", "/compressed"] {
        if let Some(base) = topic.strip_suffix(transport) {
            topic = base;
            break;
        }
    }
    topic.rsplit_once('/').map_or("", |(ns, _)| ns)
}

/// The depth topic: `--depth-topic`, else the one image topic whose name
/// contains "depth" (an uncompressed one before compressed ones).
fn choose_depth(
    topics: &[TopicInfo],
    wanted: Option<&str>,
) -> Result<(String, DepthKind), TopicError> {
    if let Some(wanted) = wanted {
        let topic =
            topics
                .iter()
                .find(|t| t.name == wanted)
                .ok_or_else(|| TopicError::BadDepth {
                    topic: wanted.to_string(),
                    reason: "not in the bag (--list shows its topics)".to_string(),
                })?;
        let kind = kind_of(topic).ok_or_else(|| TopicError::BadDepth {
            topic: wanted.to_string(),
            reason: format!(
                "its type is {}, not {IMAGE} or {COMPRESSED_IMAGE}",
                topic.message_type
            ),
        })?;
        return Ok((topic.name.clone(), kind));
    }
    let images: Vec<&TopicInfo> = topics.iter().filter(|t| kind_of(t).is_some()).collect();
    let depth: Vec<&TopicInfo> = images
        .iter()
        .copied()
        .filter(|t| t.name.to_ascii_lowercase().contains("depth"))
        .collect();
    let raw: Vec<&TopicInfo> = depth
        .iter()
        .copied()
        .filter(|t| kind_of(t) == Some(DepthKind::Raw))
        .collect();
    let pick = if raw.is_empty() { &depth } else { &raw };
    match pick.as_slice() {
        [] => Err(TopicError::NoDepth(names(&images))),
        [one] => Ok((one.name.clone(), kind_of(one).unwrap_or(DepthKind::Raw))),
        several => Err(TopicError::SeveralDepth(names(several))),
    }
}

/// The camera info topic: `--info-topic`, else the only one, else the one
/// in the depth topic's namespace.
fn choose_info(
    topics: &[TopicInfo],
    wanted: Option<&str>,
    depth: &str,
) -> Result<String, TopicError> {
    let is_info = |t: &TopicInfo| t.plain_type() == CAMERA_INFO;
    if let Some(wanted) = wanted {
        let topic =
            topics
                .iter()
                .find(|t| t.name == wanted)
                .ok_or_else(|| TopicError::BadInfo {
                    topic: wanted.to_string(),
                    reason: "not in the bag (--list shows its topics)".to_string(),
                })?;
        if !is_info(topic) {
            return Err(TopicError::BadInfo {
                topic: wanted.to_string(),
                reason: format!("its type is {}, not {CAMERA_INFO}", topic.message_type),
            });
        }
        return Ok(topic.name.clone());
    }
    let infos: Vec<&TopicInfo> = topics.iter().filter(|t| is_info(t)).collect();
    match infos.as_slice() {
        [] => Err(TopicError::NoInfo),
        [one] => Ok(one.name.clone()),
        several => {
            let beside: Vec<&TopicInfo> = several
                .iter()
                .copied()
                .filter(|t| namespace(&t.name) == namespace(depth))
                .collect();
            match beside.as_slice() {
                [one] => Ok(one.name.clone()),
                _ => Err(TopicError::SeveralInfo(names(several))),
            }
        }
    }
}

/// The colour topic: `--color-topic`, else the one uncompressed image
/// topic beside the depth topic whose name says colour (`color`, `rgb`);
/// none with `--no-color` or when there is not exactly one.
fn choose_color(
    topics: &[TopicInfo],
    wanted: &Wanted<'_>,
    depth: &str,
) -> Result<Option<String>, TopicError> {
    if wanted.no_color {
        return Ok(None);
    }
    if let Some(name) = wanted.color {
        let topic = topics
            .iter()
            .find(|t| t.name == name)
            .ok_or_else(|| TopicError::BadColor {
                topic: name.to_string(),
                reason: "not in the bag (--list shows its topics)".to_string(),
            })?;
        if kind_of(topic) != Some(DepthKind::Raw) {
            return Err(TopicError::BadColor {
                topic: name.to_string(),
                reason: format!("its type is {}, not {IMAGE}", topic.message_type),
            });
        }
        return Ok(Some(topic.name.clone()));
    }
    let colour: Vec<&TopicInfo> = topics
        .iter()
        .filter(|t| t.name != depth && kind_of(t) == Some(DepthKind::Raw))
        .filter(|t| namespace(&t.name) == namespace(depth))
        .filter(|t| {
            let name = t.name.to_ascii_lowercase();
            name.contains("color") || name.contains("colour") || name.contains("rgb")
        })
        .collect();
    Ok(match colour.as_slice() {
        [one] => Some(one.name.clone()),
        _ => None,
    })
}

/// The topics an import of a bag with `topics` reads.
pub fn choose(topics: &[TopicInfo], wanted: &Wanted<'_>) -> Result<Chosen, TopicError> {
    let (depth, kind) = choose_depth(topics, wanted.depth)?;
    let info = choose_info(topics, wanted.info, &depth)?;
    let color = choose_color(topics, wanted, &depth)?;
    let tf_static = topics
        .iter()
        .find(|t| t.name == TF_STATIC && t.plain_type() == TF_MESSAGE)
        .map(|t| t.name.clone());
    Ok(Chosen {
        depth,
        kind,
        info,
        color,
        tf_static,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn topic(name: &str, ty: &str) -> TopicInfo {
        TopicInfo {
            name: name.to_string(),
            message_type: ty.to_string(),
            count: Some(1),
        }
    }

    fn kinect2_bridge() -> Vec<TopicInfo> {
        vec![
            topic("/kinect2/sd/image_color_rect", "sensor_msgs/Image"),
            topic("/kinect2/sd/image_depth_rect", "sensor_msgs/Image"),
            topic(
                "/kinect2/sd/image_depth_rect/compressed",
                "sensor_msgs/CompressedImage",
            ),
            topic("/kinect2/sd/camera_info", "sensor_msgs/CameraInfo"),
            topic("/kinect2/hd/camera_info", "sensor_msgs/CameraInfo"),
            topic("/tf_static", "tf2_msgs/TFMessage"),
        ]
    }

    #[test]
    fn a_kinect2_bridge_bag_gives_the_sd_depth_and_its_camera_info() {
        let chosen = choose(&kinect2_bridge(), &Wanted::default()).unwrap();
        assert_eq!(chosen.depth, "/kinect2/sd/image_depth_rect");
        assert_eq!(
            chosen.color.as_deref(),
            Some("/kinect2/sd/image_color_rect")
        );
        assert_eq!(chosen.kind, DepthKind::Raw);
        assert_eq!(chosen.info, "/kinect2/sd/camera_info");
        assert_eq!(chosen.tf_static.as_deref(), Some("/tf_static"));
        let wanted = Wanted {
            depth: Some("/kinect2/sd/image_depth_rect/compressed"),
            no_color: true,
            ..Wanted::default()
        };
        let compressed = choose(&kinect2_bridge(), &wanted).unwrap();
        assert_eq!(compressed.color, None);
        assert_eq!(compressed.kind, DepthKind::Compressed);
        assert_eq!(compressed.info, "/kinect2/sd/camera_info");
    }

    #[test]
    fn ros2_type_names_count_too() {
        let topics = vec![
            topic("/camera/depth/image_raw", "sensor_msgs/msg/Image"),
            topic("/camera/depth/camera_info", "sensor_msgs/msg/CameraInfo"),
        ];
        let chosen = choose(&topics, &Wanted::default()).unwrap();
        assert_eq!(chosen.depth, "/camera/depth/image_raw");
        assert_eq!(chosen.color, None);
        assert_eq!(chosen.tf_static, None);
    }

    #[test]
    fn missing_or_ambiguous_topics_are_named() {
        let colour = vec![
            topic("/rgb", "sensor_msgs/Image"),
            topic("/info", "sensor_msgs/CameraInfo"),
        ];
        assert_eq!(
            choose(&colour, &Wanted::default()),
            Err(TopicError::NoDepth("/rgb (sensor_msgs/Image)".to_string()))
        );
        let two = vec![
            topic("/a/depth", "sensor_msgs/Image"),
            topic("/b/depth", "sensor_msgs/Image"),
        ];
        assert!(matches!(
            choose(&two, &Wanted::default()),
            Err(TopicError::SeveralDepth(_))
        ));
        let no_info = vec![topic("/a/depth", "sensor_msgs/Image")];
        assert_eq!(
            choose(&no_info, &Wanted::default()),
            Err(TopicError::NoInfo)
        );
        let wanted = Wanted {
            depth: Some("/kinect2/sd/camera_info"),
            ..Wanted::default()
        };
        let err = choose(&kinect2_bridge(), &wanted).unwrap_err();
        assert!(err.to_string().contains("not sensor_msgs/Image"), "{err}");
    }
}
