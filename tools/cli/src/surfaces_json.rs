//! The JSON form of a `Surfaces` message (`slope.Surfaces.v1`): one object
//! per frame ([`SurfacesJson`], `slope-echo --surfaces --json`, the MCAP
//! channel `/slope/surfaces`, the bridge's `<prefix>/surfaces`) and one
//! object per surface ([`SurfaceJson`], also `slope-eval --json`'s
//! `surfaces`). Surfaces keep the message's order (the largest first); NaN
//! values and absent planes are `null`, roles and supports are their names.

use serde::Serialize;
use slope_ipc_types::{surface_flags, EstimateStatus, SurfaceDescription, Surfaces, NO_SURFACE};

/// One surface in JSON.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SurfaceJson {
    /// `ground`, `step`, `ramp`, `wall`, `elevated`, `overhang` (`unknown`
    /// for a value this build does not know).
    pub role: &'static str,
    /// `none`, `ground`, `step`, `hidden`, `ramp` (or `unknown`).
    pub support: &'static str,
    /// Index (in this frame's `surfaces`) of the surface it stands on.
    pub supported_by: Option<u32>,
    /// True for the road ahead (the surface the estimate's slope is
    /// measured on).
    pub road: bool,
    pub inliers: u32,
    pub segments: u32,
    pub joins_ground: bool,
    pub in_corridor: bool,
    pub measurable: bool,
    pub slope_deg: Option<f64>,
    pub heading_deg: Option<f64>,
    pub distance_m: Option<f64>,
    pub far_m: Option<f64>,
    pub left_m: Option<f64>,
    pub right_m: Option<f64>,
    pub lowest_m: Option<f64>,
    pub highest_m: Option<f64>,
    pub area_m2: Option<f64>,
    pub rms_m: Option<f64>,
    pub noise_ratio: Option<f64>,
    /// `[a, b, c, d]`, camera frame.
    pub plane: Option<[f64; 4]>,
    /// Four corners `[x, y, z]`, camera frame, metres.
    pub outline: [[f32; 3]; 4],
}

/// Every surface of one frame in JSON.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SurfacesJson {
    pub frame: u64,
    /// Capture, ns since the Unix epoch.
    pub timestamp_ns: u64,
    pub publish_stamp_ns: u64,
    pub source_stamp_ns: u64,
    pub status: &'static str,
    /// Index of the road in `surfaces`, `null` without one.
    pub road: Option<u32>,
    pub ground_from_mount: bool,
    pub up: Option<[f64; 3]>,
    pub forward: Option<[f64; 3]>,
    pub ground_plane: Option<[f64; 4]>,
    pub corridor_half_width_m: Option<f64>,
    pub look_ahead_m: Option<f64>,
    pub surfaces: Vec<SurfaceJson>,
}

fn finite(value: f64) -> Option<f64> {
    value.is_finite().then_some(value)
}

fn finite_vector<const N: usize>(v: [f64; N]) -> Option<[f64; N]> {
    v.iter().all(|x| x.is_finite()).then_some(v)
}

/// A plane, `None` when absent (all zero) or not finite.
fn plane(coefficients: [f64; 4]) -> Option<[f64; 4]> {
    finite_vector(coefficients).filter(|c| *c != [0.0; 4])
}

impl SurfaceJson {
    /// One surface of a message; `road` says whether it is the message's
    /// road.
    pub fn of(s: &SurfaceDescription, road: bool) -> Self {
        Self {
            role: s.role().map_or("unknown", |r| r.name()),
            support: s.support().map_or("unknown", |r| r.name()),
            supported_by: (s.supported_by != NO_SURFACE).then_some(s.supported_by),
            road,
            inliers: s.inliers,
            segments: s.segments,
            joins_ground: s.joins_ground(),
            in_corridor: s.in_corridor(),
            measurable: s.flags & surface_flags::MEASURABLE != 0,
            slope_deg: finite(s.slope_deg),
            heading_deg: finite(s.heading_deg),
            distance_m: finite(s.distance_m),
            far_m: finite(s.far_m),
            left_m: finite(s.left_m),
            right_m: finite(s.right_m),
            lowest_m: finite(s.lowest_m),
            highest_m: finite(s.highest_m),
            area_m2: finite(s.area_m2),
            rms_m: finite(s.rms_m),
            noise_ratio: finite(s.noise_ratio),
            plane: plane(s.plane),
            outline: s.outline,
        }
    }

    /// The surfaces of a message, in its order.
    pub fn all(m: &Surfaces) -> Vec<Self> {
        let road = m.road_surface().map(|_| m.road as usize);
        m.present()
            .iter()
            .enumerate()
            .map(|(k, s)| Self::of(s, road == Some(k)))
            .collect()
    }
}

impl From<&Surfaces> for SurfacesJson {
    fn from(m: &Surfaces) -> Self {
        Self {
            frame: m.frame_index,
            timestamp_ns: m.capture_stamp_ns,
            publish_stamp_ns: m.publish_stamp_ns,
            source_stamp_ns: m.source_stamp_ns,
            status: EstimateStatus::from_raw(m.status).map_or("unknown", |s| s.name()),
            road: m.road_surface().map(|_| m.road),
            ground_from_mount: m.ground_from_mount != 0,
            up: finite_vector(m.up),
            forward: finite_vector(m.forward),
            ground_plane: plane(m.ground_plane),
            corridor_half_width_m: finite(m.corridor_half_width_m),
            look_ahead_m: finite(m.look_ahead_m),
            surfaces: SurfaceJson::all(m),
        }
    }
}

/// The readable form of a frame's surfaces (`slope-echo --surfaces`): a
/// header line, then one line per surface, the road marked `ROAD`.
pub fn surfaces_text(m: &Surfaces) -> String {
    let status = EstimateStatus::from_raw(m.status).map_or("unknown", |s| s.name());
    let mut text = format!(
        "frame {:>6}  {status}  {} surfaces",
        m.frame_index,
        m.present().len()
    );
    if m.ground_from_mount != 0 {
        text.push_str("  (ground: the mount's plane)");
    }
    for (k, s) in SurfaceJson::all(m).iter().enumerate() {
        text.push('\n');
        text.push_str(&surface_line(k, s));
    }
    text
}

/// `  1 ROAD ramp     on ground  slope +16.06° heading    0°  ahead 1.50..3.20 m  ...`
fn surface_line(k: usize, s: &SurfaceJson) -> String {
    let number = |v: Option<f64>, width: usize, digits: usize| match v {
        Some(v) => format!("{v:>width$.digits$}"),
        None => format!("{:>width$}", "-"),
    };
    let signed = |v: Option<f64>, digits: usize| match v {
        Some(v) => format!("{v:+7.digits$}"),
        None => format!("{:>7}", "-"),
    };
    format!(
        "  {k:>2} {} {:<8} on {:<6} slope {}° heading {}°  ahead {}..{} m  lateral {}..{} m  \
         height {}..{} m  area {} m²",
        if s.road { "ROAD" } else { "    " },
        s.role,
        s.support,
        signed(s.slope_deg, 2),
        number(s.heading_deg, 4, 0),
        number(s.distance_m, 5, 2),
        number(s.far_m, 5, 2),
        signed(s.left_m, 2),
        signed(s.right_m, 2),
        signed(s.lowest_m, 2),
        signed(s.highest_m, 2),
        number(s.area_m2, 5, 2),
    )
}

#[cfg(test)]
mod tests {
    use slope_ipc_types::{SurfaceRole, SurfaceSupport};

    use super::*;

    fn ramp() -> SurfaceDescription {
        SurfaceDescription {
            role: SurfaceRole::Ramp as u32,
            support: SurfaceSupport::Ground as u32,
            supported_by: 0,
            inliers: 9000,
            flags: surface_flags::IN_CORRIDOR | surface_flags::JOINS_GROUND,
            segments: 1,
            slope_deg: 16.0,
            heading_deg: 0.0,
            distance_m: 1.5,
            far_m: 2.5,
            left_m: -0.4,
            right_m: 0.4,
            lowest_m: 0.0,
            highest_m: 0.28,
            area_m2: 0.8,
            rms_m: 0.003,
            noise_ratio: 1.1,
            plane: [0.0, -0.7, -0.7, 1.2],
            outline: [[1.0, 2.0, 3.0]; 4],
        }
    }

    fn message() -> Surfaces {
        let mut m = Surfaces {
            frame_index: 12,
            status: EstimateStatus::Ok as u32,
            count: 2,
            road: 1,
            up: [0.0, -1.0, 0.0],
            forward: [0.0, 0.0, 1.0],
            ground_plane: [0.0, -0.94, 0.34, 0.5],
            corridor_half_width_m: 0.3,
            look_ahead_m: 3.0,
            ..Surfaces::default()
        };
        m.surfaces[0] = SurfaceDescription {
            role: SurfaceRole::Ground as u32,
            support: SurfaceSupport::None as u32,
            supported_by: NO_SURFACE,
            inliers: 40_000,
            flags: surface_flags::MEASURABLE | surface_flags::JOINS_GROUND,
            segments: 3,
            slope_deg: 0.0,
            heading_deg: f64::NAN,
            ..ramp()
        };
        m.surfaces[1] = ramp();
        m
    }

    #[test]
    fn every_present_surface_in_order_with_names_and_the_road_marked() {
        let value = serde_json::to_value(SurfacesJson::from(&message())).unwrap();
        assert_eq!(value["frame"], 12);
        assert_eq!(value["status"], "ok");
        assert_eq!(value["road"], 1);
        assert_eq!(value["corridor_half_width_m"], 0.3);
        let surfaces = value["surfaces"].as_array().unwrap();
        assert_eq!(surfaces.len(), 2, "only the first count");
        let (ground, ramp) = (&surfaces[0], &surfaces[1]);
        assert_eq!(
            (ground["role"].as_str(), ramp["role"].as_str()),
            (Some("ground"), Some("ramp"))
        );
        assert_eq!(ramp["support"], "ground");
        assert_eq!(ramp["supported_by"], 0);
        assert!(ground["supported_by"].is_null());
        assert_eq!(
            (ground["road"].as_bool(), ramp["road"].as_bool()),
            (Some(false), Some(true))
        );
        assert_eq!(ramp["in_corridor"], true);
        assert_eq!(ramp["measurable"], false);
        assert_eq!(ground["measurable"], true);
        assert_eq!(ramp["slope_deg"], 16.0);
        assert_eq!(ramp["left_m"], -0.4);
        assert!(ground["heading_deg"].is_null(), "NaN is null");
        assert_eq!(ground["segments"], 3);
        assert_eq!(ramp.as_object().unwrap().len(), 22);
        assert_eq!(value.as_object().unwrap().len(), 13);
    }

    #[test]
    fn the_text_has_a_line_per_surface_with_the_road_marked() {
        let text = surfaces_text(&message());
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3, "{text}");
        assert_eq!(lines[0], "frame     12  ok  2 surfaces");
        assert!(
            lines[1].starts_with("   0      ground   on none   slope   +0.00° heading    -°"),
            "{text}"
        );
        assert!(
            lines[2].starts_with("   1 ROAD ramp     on ground slope  +16.00° heading    0°"),
            "{text}"
        );
        assert!(
            lines[2].ends_with(
                "ahead  1.50.. 2.50 m  lateral   -0.40..  +0.40 m  height   +0.00..  +0.28 m  area  0.80 m²"
            ),
            "{text}"
        );
    }

    #[test]
    fn without_a_ground_the_frame_is_null_and_a_bad_road_index_is_no_road() {
        let mut m = message();
        m.road = 5; // beyond count
        let value = serde_json::to_value(SurfacesJson::from(&m)).unwrap();
        assert!(value["road"].is_null());
        assert!(value["surfaces"]
            .as_array()
            .unwrap()
            .iter()
            .all(|s| s["road"] == false));
        let empty = serde_json::to_value(SurfacesJson::from(&Surfaces::default())).unwrap();
        for key in ["up", "forward", "ground_plane", "look_ahead_m", "road"] {
            assert!(empty[key].is_null(), "{key}: {empty}");
        }
        assert_eq!(empty["surfaces"], serde_json::json!([]));
        assert_eq!(empty["status"], "bad_frame");
    }
}
