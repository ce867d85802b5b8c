//! How to run the Kinect v2 and what happened to its stream: the settings
//! `Kinect2Source` (feature `kinect2`) takes and the counters it
//! keeps. Pure, so that programs check their settings without the library.

use std::time::Duration;

use slope_ipc_types::Mount;

use super::choice::{DeviceSelector, Pipeline};
use super::params::DepthConfig;

/// How to run the Kinect v2.
#[derive(Debug, Clone, PartialEq)]
pub struct Kinect2Options {
    pub device: DeviceSelector,
    pub pipeline: Pipeline,
    /// OpenCL/CUDA device id; `None` for libfreenect2's default.
    pub gpu_device: Option<u32>,
    pub depth: DepthConfig,
    /// Also stream colour and register it to the depth image.
    pub color: bool,
    /// Drop colour pixels hidden behind nearer depth (libfreenect2's
    /// registration filter).
    pub registration_filter: bool,
    /// The camera's pose on the robot, passed on with every cloud.
    pub mount: Mount,
    /// Keep retrying when no device is connected instead of failing.
    pub wait_for_device: bool,
    /// No frame for this long means the device is lost: reconnect.
    pub frame_timeout: Duration,
    /// First wait between reconnection attempts; doubles up to
    /// `max_backoff`.
    pub min_backoff: Duration,
    pub max_backoff: Duration,
}

impl Default for Kinect2Options {
    fn default() -> Self {
        Self {
            device: DeviceSelector::First,
            pipeline: Pipeline::Default,
            gpu_device: None,
            depth: DepthConfig::default(),
            color: true,
            registration_filter: true,
            mount: Mount::UNKNOWN,
            wait_for_device: false,
            frame_timeout: Duration::from_secs(3),
            min_backoff: Duration::from_millis(500),
            max_backoff: Duration::from_secs(10),
        }
    }
}

/// What happened to the stream so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CaptureStats {
    /// Frame sets delivered as frames.
    pub frames: u64,
    /// Frame sets skipped because a frame had a non-zero status.
    pub bad_status: u64,
    /// Frame sets skipped because a frame was missing or misshapen.
    pub malformed: u64,
    /// Times the device was declared lost (no frame within the timeout).
    pub lost: u64,
    /// Successful reopenings after a loss.
    pub reconnects: u64,
    /// Failed attempts to (re)open a device.
    pub failed_opens: u64,
}

/// The sensor name of the Kinect v2's frames (a recording's `sensor`, a
/// cloud header's `sensor`).
pub const SENSOR_NAME: &str = "kinect2";
