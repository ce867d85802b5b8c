//! `/slope/markers`: a `visualization_msgs/msg/MarkerArray` per frame for
//! rviz2, from the frame's surfaces and estimate, in the camera frame:
//!
//! | ns | id | marker |
//! |---|---|---|
//! | – | 0 | `DELETEALL`: the previous frame's markers go |
//! | `surfaces` | k | surface k's outline filled (`TRIANGLE_LIST`, two triangles), in its role's colour (the overlay's, [`slope_tools::render::ROLE_COLOURS`]), alpha [`SURFACE_ALPHA`] |
//! | `road` | 0 | the road's outline (`LINE_STRIP`, closed), magenta ([`slope_tools::render::ROAD_OUTLINE`]), [`ROAD_LINE_WIDTH_M`] wide |
//! | `slope` | 0 | `TEXT_VIEW_FACING` over the road's centre (else 1 m ahead): `16.0°`, or the status without a slope |

use serde::{Deserialize, Serialize};
use slope_ipc_types::{EstimateStatus, SlopeEstimate, SurfaceDescription, Surfaces};
use slope_tools::render::{role_colour, ROAD_OUTLINE, UNCLASSIFIED};
use slope_tools::ros2_messages::{CompressedImage, Header, Quaternion, Time, Vector3};

/// `visualization_msgs/msg/Marker` types and actions used.
pub const LINE_STRIP: i32 = 4;
pub const TEXT_VIEW_FACING: i32 = 9;
pub const TRIANGLE_LIST: i32 = 11;
pub const ADD: i32 = 0;
pub const DELETEALL: i32 = 3;

/// Opacity of the filled surfaces (the cloud behind them stays visible).
pub const SURFACE_ALPHA: f32 = 0.6;
/// Width of the road's outline, metres.
pub const ROAD_LINE_WIDTH_M: f64 = 0.02;
/// Height of the slope's text, metres.
pub const TEXT_HEIGHT_M: f64 = 0.15;
/// The text stands this far above the road's centre (towards the camera's
/// up, -y), metres.
pub const TEXT_LIFT_M: f64 = 0.1;

/// `geometry_msgs/msg/Point`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// `geometry_msgs/msg/Pose`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub position: Point,
    pub orientation: Quaternion,
}

/// `std_msgs/msg/ColorRGBA`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ColorRgba {
    pub r: f32,
    pub g: f32,
    pub b: f32,
    pub a: f32,
}

/// `builtin_interfaces/msg/Duration`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Duration {
    pub sec: i32,
    pub nanosec: u32,
}

/// `visualization_msgs/msg/UVCoordinate`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct UvCoordinate {
    pub u: f32,
    pub v: f32,
}

/// `visualization_msgs/msg/MeshFile`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshFile {
    pub filename: String,
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/Marker` (as in ROS 2 Humble and Jazzy: with
/// the texture and mesh_file fields).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    pub header: Header,
    pub ns: String,
    pub id: i32,
    #[serde(rename = "type")]
    pub kind: i32,
    pub action: i32,
    pub pose: Pose,
    pub scale: Vector3,
    pub color: ColorRgba,
    pub lifetime: Duration,
    pub frame_locked: bool,
    pub points: Vec<Point>,
    pub colors: Vec<ColorRgba>,
    pub texture_resource: String,
    pub texture: CompressedImage,
    pub uv_coordinates: Vec<UvCoordinate>,
    pub text: String,
    pub mesh_resource: String,
    pub mesh_file: MeshFile,
    pub mesh_use_embedded_materials: bool,
}

/// `visualization_msgs/msg/MarkerArray`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MarkerArray {
    pub markers: Vec<Marker>,
}

/// An 8-bit colour as ROS's 0..1 floats.
pub fn colour([r, g, b]: [u8; 3], a: f32) -> ColorRgba {
    let f = |c: u8| f32::from(c) / 255.0;
    ColorRgba {
        r: f(r),
        g: f(g),
        b: f(b),
        a,
    }
}

fn corners(s: &SurfaceDescription) -> [Point; 4] {
    s.outline.map(|[x, y, z]| Point {
        x: f64::from(x),
        y: f64::from(y),
        z: f64::from(z),
    })
}

/// The markers of a frame: `surfaces`, and `estimate` when it is the
/// same frame's (for the text), in the camera frame `frame_id`.
pub fn markers(
    surfaces: &Surfaces,
    estimate: Option<&SlopeEstimate>,
    frame_id: &str,
) -> MarkerArray {
    let header = Header {
        stamp: Time::from_ns(surfaces.capture_stamp_ns),
        frame_id: frame_id.to_string(),
    };
    let base = Marker {
        header: header.clone(),
        pose: Pose {
            orientation: Quaternion {
                w: 1.0,
                ..Quaternion::default()
            },
            ..Pose::default()
        },
        scale: Vector3 {
            x: 1.0,
            y: 1.0,
            z: 1.0,
        },
        action: ADD,
        ..Marker::default()
    };
    let mut out = vec![Marker {
        action: DELETEALL,
        ..base.clone()
    }];
    for (k, s) in surfaces.present().iter().enumerate() {
        let [a, b, c, d] = corners(s);
        out.push(Marker {
            ns: "surfaces".into(),
            id: k as i32,
            kind: TRIANGLE_LIST,
            color: colour(s.role().map_or(UNCLASSIFIED, role_colour), SURFACE_ALPHA),
            points: vec![a, b, c, a, c, d],
            ..base.clone()
        });
    }
    let road = surfaces.road_surface();
    if let Some(road) = road {
        let [a, b, c, d] = corners(road);
        out.push(Marker {
            ns: "road".into(),
            kind: LINE_STRIP,
            scale: Vector3 {
                x: ROAD_LINE_WIDTH_M,
                y: 0.0,
                z: 0.0,
            },
            color: colour(ROAD_OUTLINE, 1.0),
            points: vec![a, b, c, d, a],
            ..base.clone()
        });
    }
    let at = road.map_or(
        Point {
            x: 0.0,
            y: 0.0,
            z: 1.0,
        },
        |r| {
            let c = corners(r);
            Point {
                x: c.iter().map(|p| p.x).sum::<f64>() / 4.0,
                y: c.iter().map(|p| p.y).sum::<f64>() / 4.0 - TEXT_LIFT_M,
                z: c.iter().map(|p| p.z).sum::<f64>() / 4.0,
            }
        },
    );
    out.push(Marker {
        ns: "slope".into(),
        kind: TEXT_VIEW_FACING,
        pose: Pose {
            position: at,
            ..base.pose
        },
        scale: Vector3 {
            x: 0.0,
            y: 0.0,
            z: TEXT_HEIGHT_M,
        },
        color: colour([255, 255, 255], 1.0),
        text: slope_text(surfaces, estimate),
        ..base
    });
    MarkerArray { markers: out }
}

/// `16.0°` from the estimate of the same frame, else the road's slope;
/// the status when there is no slope.
pub fn slope_text(surfaces: &Surfaces, estimate: Option<&SlopeEstimate>) -> String {
    let estimate = estimate.filter(|e| e.frame_index == surfaces.frame_index);
    let slope = match estimate {
        Some(e) => (e.status() == EstimateStatus::Ok).then_some(e.slope_deg),
        None => surfaces.road_surface().map(|r| r.slope_deg),
    };
    match slope.filter(|s| s.is_finite()) {
        Some(slope) => format!("{slope:.1}°"),
        None => {
            let status = EstimateStatus::from_raw(surfaces.status).map_or("unknown", |s| s.name());
            format!("no slope ({status})")
        }
    }
}

#[cfg(test)]
mod tests {
    use slope_ipc_types::{SurfaceRole, NO_SURFACE};
    use slope_tools::ros2_messages::{from_cdr, to_cdr};

    use super::*;

    fn frame() -> Surfaces {
        let mut m = Surfaces {
            frame_index: 3,
            capture_stamp_ns: 2_000_000_001,
            status: EstimateStatus::Ok as u32,
            count: 2,
            road: 1,
            ..Surfaces::default()
        };
        m.surfaces[0].role = SurfaceRole::Ground as u32;
        m.surfaces[0].outline = [
            [-1.0, 0.5, 0.5],
            [1.0, 0.5, 0.5],
            [1.0, 0.25, 1.5],
            [-1.0, 0.25, 1.5],
        ];
        m.surfaces[1].role = SurfaceRole::Ramp as u32;
        m.surfaces[1].slope_deg = 15.5;
        m.surfaces[1].outline = [
            [-0.5, 0.25, 1.5],
            [0.5, 0.25, 1.5],
            [0.5, -0.25, 2.5],
            [-0.5, -0.25, 2.5],
        ];
        m
    }

    #[test]
    fn each_surface_is_filled_in_its_role_colour_and_the_road_outlined_with_the_slope() {
        let estimate = SlopeEstimate {
            frame_index: 3,
            status: EstimateStatus::Ok as u32,
            slope_deg: 16.04,
            ..SlopeEstimate::default()
        };
        let array = markers(&frame(), Some(&estimate), "cam");
        let m = &array.markers;
        assert_eq!(m.len(), 5, "deleteall, two surfaces, the road, the text");
        assert_eq!(m[0].action, DELETEALL);
        let ramp = &m[2];
        assert_eq!(
            (ramp.ns.as_str(), ramp.id, ramp.kind),
            ("surfaces", 1, TRIANGLE_LIST)
        );
        // Blue (30, 80, 255): the overlay's ramp.
        assert_eq!(
            ramp.color,
            colour(role_colour(SurfaceRole::Ramp), SURFACE_ALPHA)
        );
        assert_eq!(ramp.color.b, 1.0);
        assert_eq!(ramp.points.len(), 6);
        assert_eq!(
            ramp.points[0],
            Point {
                x: -0.5,
                y: 0.25,
                z: 1.5
            }
        );
        assert_eq!(
            ramp.points[5],
            Point {
                x: -0.5,
                y: -0.25,
                z: 2.5
            }
        );
        assert_eq!(
            m[1].color,
            colour(role_colour(SurfaceRole::Ground), SURFACE_ALPHA)
        );
        let road = &m[3];
        assert_eq!((road.kind, road.points.len()), (LINE_STRIP, 5));
        assert_eq!(road.points[0], road.points[4]);
        assert_eq!(
            road.points[2],
            Point {
                x: 0.5,
                y: -0.25,
                z: 2.5
            }
        );
        let text = &m[4];
        assert_eq!((text.kind, text.text.as_str()), (TEXT_VIEW_FACING, "16.0°"));
        let at = text.pose.position;
        assert_eq!((at.x, at.y, at.z), (0.0, -TEXT_LIFT_M, 2.0));
        assert!(m
            .iter()
            .all(|k| k.header.frame_id == "cam" && k.header.stamp.nanosec == 1));
        let back: MarkerArray = from_cdr(&to_cdr(&array).unwrap()).unwrap();
        assert_eq!(back, array);
    }

    #[test]
    fn without_a_road_or_slope_the_text_says_why() {
        let mut m = frame();
        m.road = NO_SURFACE;
        m.status = EstimateStatus::NoInclinedPlane as u32;
        let array = markers(&m, None, "cam");
        assert_eq!(array.markers.len(), 4, "no road outline");
        let text = array.markers.last().unwrap();
        assert_eq!(text.text, "no slope (no_inclined_plane)");
        assert_eq!(
            text.pose.position,
            Point {
                x: 0.0,
                y: 0.0,
                z: 1.0
            }
        );
        // Another frame's estimate is not used: the road's slope instead.
        let other = SlopeEstimate {
            frame_index: 2,
            slope_deg: 9.0,
            ..SlopeEstimate::default()
        };
        assert_eq!(slope_text(&frame(), Some(&other)), "15.5°");
    }
}
