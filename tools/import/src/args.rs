//! The command line of `slope-import` ([`ImportArgs`]).

use std::path::PathBuf;

use clap::Parser;
use slope_tools::cli::LogArgs;
use slope_tools::mount_args::MountArgs;

#[derive(Debug, Parser)]
#[command(
    name = "slope-import",
    override_usage = "slope-import [OPTIONS] <BAG> --output <DIR>\n       slope-import <BAG> --list",
    version,
    about = "Import a ROS 1 or ROS 2 bag of a depth camera (a Kinect v2's kinect2_bridge) as a recording",
    long_about = "Reads BAG: a ROS 1 bag (.bag), a ROS 2 bag directory (metadata.yaml with .mcap or \
.db3 files) or one ROS 2 .mcap or .db3 file, and writes the recording directory -o DIR that \
slope-replay, slope-eval and slope-convert read: the depth images in millimetres (sensor_msgs/Image \
16UC1 or mono16 as they are, 32FC1 metres rounded to the millimetre, sensor_msgs/CompressedImage \
compressedDepth PNG decoded), the intrinsics from the camera info's K with the image size, the \
header stamps as timestamps, frames.csv in order.

The depth topic is the one image topic whose name contains 'depth', the camera info the one \
sensor_msgs/CameraInfo topic (or the one beside the depth topic); --depth-topic and --info-topic \
choose when there are several, --list shows them. The mount (height, pitch, roll) comes from \
/tf_static, the transform from --base-frame to the depth image's frame, when the bag has one; \
--mount-* flags override it, key by key.

A bag that stops early (cut short, or a recorder that died) is read up to where its data stops: \
the recording keeps those frames, the error says where it stopped, and the exit status is 1. \
SIGINT or SIGTERM stops the import after the frame under way, with a valid recording of the \
frames so far (exit status 0).",
    after_help = "Examples:
  slope-import kinect.bag --list                           # topics, types, counts
  slope-import kinect.bag -o rec                           # ROS 1, the mount from /tf_static
  slope-import ros2_bag/ -o rec --every 3 --start 10 --duration 20
  slope-import ros2_bag/ -o rec --depth-topic /kinect2/sd/image_depth_rect/compressed \\
      --mount-height-m 0.5 --mount-pitch-deg -20
  slope-eval rec                                           # then evaluate it"
)]
pub struct ImportArgs {
    /// The bag: a ROS 1 .bag, a ROS 2 bag directory, or a ROS 2 .mcap or
    /// .db3 file.
    pub bag: PathBuf,

    /// The recording directory to create (new, or empty).
    #[arg(
        short = 'o',
        long = "output",
        value_name = "DIR",
        required_unless_present = "list"
    )]
    pub output: Option<PathBuf>,

    /// Print the bag's topics (type, message count) and which ones an
    /// import would take, then exit.
    #[arg(long, conflicts_with = "output")]
    pub list: bool,

    /// The depth topic (sensor_msgs/Image or compressedDepth
    /// sensor_msgs/CompressedImage).
    #[arg(long, value_name = "TOPIC")]
    pub depth_topic: Option<String>,

    /// The camera info topic (sensor_msgs/CameraInfo).
    #[arg(long, value_name = "TOPIC")]
    pub info_topic: Option<String>,

    /// The registered colour images (sensor_msgs/Image rgb8 or bgr8 of the
    /// depth image's size, the same stamps); default: the one image topic
    /// beside the depth topic named for colour (color, rgb), if there is one.
    #[arg(long, value_name = "TOPIC", conflicts_with = "no_color")]
    pub color_topic: Option<String>,

    /// Import no colour.
    #[arg(long)]
    pub no_color: bool,

    /// The robot's frame in /tf_static that the camera's mount is measured
    /// from (its z axis up, its origin on the ground).
    #[arg(long, value_name = "FRAME", default_value = "base_link")]
    pub base_frame: String,

    /// The camera's mount: overrides /tf_static, key by key.
    #[command(flatten)]
    pub mount: MountArgs,

    /// recording.toml's `sensor` (it chooses the estimator's noise model).
    #[arg(long, value_name = "NAME", default_value = "kinect2")]
    pub sensor: String,

    /// Skip the first S seconds of depth images (from the first one's
    /// stamp).
    #[arg(long, value_name = "S", value_parser = seconds)]
    pub start: Option<f64>,

    /// Import S seconds of depth images (from --start).
    #[arg(long, value_name = "S", value_parser = seconds)]
    pub duration: Option<f64>,

    /// Import every Nth depth image (of those from --start).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = every)]
    pub every: u64,

    #[command(flatten)]
    pub log: LogArgs,
}

impl ImportArgs {
    /// The topics the command line asks for.
    pub fn wanted(&self) -> crate::topics::Wanted<'_> {
        crate::topics::Wanted {
            depth: self.depth_topic.as_deref(),
            info: self.info_topic.as_deref(),
            color: self.color_topic.as_deref(),
            no_color: self.no_color,
        }
    }
}

fn seconds(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(s) if s.is_finite() && s >= 0.0 => Ok(s),
        _ => Err(format!("'{text}' is not a number of seconds (0 or more)")),
    }
}

fn every(text: &str) -> Result<u64, String> {
    match text.trim().parse::<u64>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!("'{text}' is not a whole number of at least 1")),
    }
}
