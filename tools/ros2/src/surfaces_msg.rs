//! `slope_msgs/msg/Surfaces` and `slope_msgs/msg/Surface`
//! (`ros2/slope_msgs/msg/`) as serde structs in the order of their `.msg`
//! files (all CDR needs), and the message of a `Surfaces` (`slope.Surfaces.v1`):
//! every present surface, its fields as they are (NaN stays NaN), the
//! camera frame's `frame_id` and the capture stamp in the header.

use serde::{Deserialize, Serialize};
use slope_ipc_types::{SurfaceDescription, Surfaces};
use slope_tools::ros2_messages::{Header, Time};

/// `slope_msgs/msg/Surface.msg` as shipped in `ros2/slope_msgs`.
pub const SURFACE_MSG: &str = include_str!("../../../ros2/slope_msgs/msg/Surface.msg");
/// `slope_msgs/msg/Surfaces.msg` as shipped in `ros2/slope_msgs`.
pub const SURFACES_MSG: &str = include_str!("../../../ros2/slope_msgs/msg/Surfaces.msg");

/// `geometry_msgs/msg/Point32`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Point32 {
    pub x: f32,
    pub y: f32,
    pub z: f32,
}

/// `slope_msgs/msg/Surface`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SurfaceMsg {
    pub role: u32,
    pub support: u32,
    pub supported_by: u32,
    pub inliers: u32,
    pub flags: u32,
    pub segments: u32,
    pub slope_deg: f64,
    pub heading_deg: f64,
    pub distance_m: f64,
    pub far_m: f64,
    pub left_m: f64,
    pub right_m: f64,
    pub lowest_m: f64,
    pub highest_m: f64,
    pub area_m2: f64,
    pub rms_m: f64,
    pub noise_ratio: f64,
    pub plane: [f64; 4],
    pub outline: [Point32; 4],
}

/// `slope_msgs/msg/Surfaces`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SurfacesMsg {
    pub header: Header,
    pub frame_index: u64,
    pub capture_stamp_ns: u64,
    pub publish_stamp_ns: u64,
    pub source_stamp_ns: u64,
    pub status: u32,
    pub road: u32,
    pub ground_from_mount: u32,
    pub up: [f64; 3],
    pub forward: [f64; 3],
    pub ground_plane: [f64; 4],
    pub corridor_half_width_m: f64,
    pub look_ahead_m: f64,
    pub surfaces: Vec<SurfaceMsg>,
}

impl SurfaceMsg {
    pub fn new(s: &SurfaceDescription) -> Self {
        Self {
            role: s.role,
            support: s.support,
            supported_by: s.supported_by,
            inliers: s.inliers,
            flags: s.flags,
            segments: s.segments,
            slope_deg: s.slope_deg,
            heading_deg: s.heading_deg,
            distance_m: s.distance_m,
            far_m: s.far_m,
            left_m: s.left_m,
            right_m: s.right_m,
            lowest_m: s.lowest_m,
            highest_m: s.highest_m,
            area_m2: s.area_m2,
            rms_m: s.rms_m,
            noise_ratio: s.noise_ratio,
            plane: s.plane,
            outline: s.outline.map(|[x, y, z]| Point32 { x, y, z }),
        }
    }
}

impl SurfacesMsg {
    /// The message of `m` in the camera frame `frame_id`: its present
    /// surfaces (the first `count`), `road` as it is.
    pub fn new(m: &Surfaces, frame_id: &str) -> Self {
        Self {
            header: Header {
                stamp: Time::from_ns(m.capture_stamp_ns),
                frame_id: frame_id.to_string(),
            },
            frame_index: m.frame_index,
            capture_stamp_ns: m.capture_stamp_ns,
            publish_stamp_ns: m.publish_stamp_ns,
            source_stamp_ns: m.source_stamp_ns,
            status: m.status,
            road: m.road,
            ground_from_mount: m.ground_from_mount,
            up: m.up,
            forward: m.forward,
            ground_plane: m.ground_plane,
            corridor_half_width_m: m.corridor_half_width_m,
            look_ahead_m: m.look_ahead_m,
            surfaces: m.present().iter().map(SurfaceMsg::new).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use slope_ipc_types::layout;
    use slope_ipc_types::{surface_flags, SurfaceRole, SurfaceSupport, NO_SURFACE};
    use slope_tools::ros2_messages::{from_cdr, msg_fields, to_cdr};

    use super::*;

    /// `NAME=value` of every constant.
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
    fn the_msg_files_have_every_field_of_the_ipc_messages_in_order() {
        let surface: Vec<String> = msg_fields(SURFACE_MSG)
            .into_iter()
            .map(|(_, n)| n)
            .collect();
        let ipc: Vec<&str> = layout::surface_description()
            .iter()
            .map(|f| f.name)
            .collect();
        assert_eq!(surface, ipc);
        let surfaces = msg_fields(SURFACES_MSG);
        assert_eq!(surfaces[0], ("std_msgs/Header".into(), "header".into()));
        assert_eq!(
            surfaces.last().unwrap(),
            &("Surface[]".into(), "surfaces".into())
        );
        // `count` is the sequence's length.
        let names: Vec<&str> = surfaces[1..].iter().map(|(_, n)| n.as_str()).collect();
        let ipc: Vec<&str> = layout::surfaces()
            .iter()
            .map(|f| f.name)
            .filter(|n| *n != "count")
            .collect();
        assert_eq!(names, ipc);
    }

    #[test]
    fn the_msg_constants_are_the_roles_supports_and_flags() {
        let mut expected: Vec<(String, u32)> = Vec::new();
        for role in SurfaceRole::ALL {
            expected.push((format!("ROLE_{}", role.name().to_uppercase()), role as u32));
        }
        for support in SurfaceSupport::ALL {
            let name = support.name().to_uppercase();
            expected.push((format!("SUPPORT_{name}"), support as u32));
        }
        for (name, bit) in [
            ("IN_CORRIDOR", surface_flags::IN_CORRIDOR),
            ("MEASURABLE", surface_flags::MEASURABLE),
            ("JOINS_GROUND", surface_flags::JOINS_GROUND),
        ] {
            expected.push((format!("FLAG_{name}"), bit));
        }
        expected.push(("NO_SURFACE".into(), NO_SURFACE));
        assert_eq!(constants(SURFACE_MSG), expected);
        assert!(constants(SURFACES_MSG).is_empty());
    }

    #[test]
    fn only_the_present_surfaces_go_out_and_round_trip_through_cdr() {
        let mut m = Surfaces {
            frame_index: 4,
            capture_stamp_ns: 1_700_000_000_250_000_000,
            count: 2,
            road: 1,
            ..Surfaces::default()
        };
        m.surfaces[1].role = SurfaceRole::Ramp as u32;
        m.surfaces[1].slope_deg = 16.0;
        m.surfaces[1].outline[2] = [0.5, 0.25, 2.0];
        let message = SurfacesMsg::new(&m, "cam");
        assert_eq!(message.surfaces.len(), 2);
        assert_eq!(message.header.stamp.nanosec, 250_000_000);
        let back: SurfacesMsg = from_cdr(&to_cdr(&message).unwrap()).unwrap();
        assert_eq!(back.road, 1);
        assert_eq!(back.surfaces[1].slope_deg, 16.0);
        assert_eq!(
            back.surfaces[1].outline[2],
            Point32 {
                x: 0.5,
                y: 0.25,
                z: 2.0
            }
        );
        assert!(back.surfaces[0].slope_deg.is_nan());
        assert!(back.up[0].is_nan());
    }
}
