//! A cloud of the topic back into the depth and colour images of a
//! recording, and the recording.toml of a stream.

use slope_ipc_types::{CloudHeader, CloudPoint, CloudSource, Mount};
use slope_sensor::recording::{
    ColorImage, DepthImage, DepthInfo, MountInfo, RecordingMeta, TruthInfo,
};
use slope_sensor::source::SourceInfo;

/// Metres per depth count of recordings written from the topic.
pub const TOPIC_DEPTH_UNIT_M: f64 = 0.001;

fn mount_info(mount: &Mount) -> MountInfo {
    let known = |v: f64| v.is_finite().then_some(v);
    MountInfo {
        height_m: known(mount.height_m),
        pitch_deg: known(mount.pitch_deg),
        roll_deg: known(mount.roll_deg),
    }
}

/// The recording.toml of a stream.
pub fn meta_for(info: &SourceInfo) -> RecordingMeta {
    RecordingMeta {
        sensor: info.sensor.clone(),
        depth: DepthInfo {
            width: info.width,
            height: info.height,
            unit_m: info.unit_m,
            fx: info.intrinsics.fx,
            fy: info.intrinsics.fy,
            cx: info.intrinsics.cx,
            cy: info.intrinsics.cy,
        },
        mount: mount_info(&info.mount),
        truth: TruthInfo::default(),
    }
}

/// The sensor a recording of the topic names: the cloud header's, else
/// (a header that names none) `kinect2` for camera clouds and `replay` for
/// the rest.
pub fn sensor_of(header: &CloudHeader) -> &str {
    match (header.sensor_name(), CloudSource::from_raw(header.source)) {
        ("", Some(CloudSource::Camera)) => "kinect2",
        ("", _) => "replay",
        (name, _) => name,
    }
}

/// A cloud's depth in whole counts of `unit_m`: `round(z_m / unit_m)`;
/// 0 (no reading) for an invalid point and for depth that does not fit in
/// a u16 count, never a bogus saturated value.
#[inline]
pub fn depth_count(point: &CloudPoint, unit_m: f64) -> u16 {
    slope_sensor::recording::metres_to_count(f64::from(point.z_m), unit_m)
}

/// Rebuilds the depth (and colour) images of a received cloud.
pub fn cloud_to_images(
    header: &CloudHeader,
    points: &[CloudPoint],
    unit_m: f64,
    depth: &mut DepthImage,
    color: &mut Option<ColorImage>,
) {
    depth.width = header.width;
    depth.height = header.height;
    depth.data.clear();
    depth
        .data
        .extend(points.iter().map(|p| depth_count(p, unit_m)));
    if header.has_color != 0 {
        let image = color.get_or_insert_with(ColorImage::default);
        image.width = header.width;
        image.height = header.height;
        image.data.clear();
        image.data.extend(points.iter().map(|p| {
            let [_, r, g, b] = p.rgb.to_be_bytes();
            [r, g, b]
        }));
    } else {
        *color = None;
    }
}
