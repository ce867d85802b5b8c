//! Every surface the estimator saw in a frame, with its role, and which one
//! is the road ahead (`slope.Surfaces.v1` on `<prefix>/surfaces`).
//!
//! Published once per frame beside the `SlopeEstimate` of the same frame
//! (same `frame_index` and stamps). Positions are in the **ground frame**:
//! heights up from the ground plane, distances along the robot's forward
//! direction (the optical axis projected onto the ground), lateral
//! positions to the robot's right (negative: left), all measured from the
//! camera's optical centre projected onto the ground. `up`, `forward` and
//! `ground_plane` give that frame in camera coordinates (x right, y down,
//! z forward), so a subscriber can place the camera-frame `plane` and
//! `outline` of each surface.

use iceoryx2::prelude::ZeroCopySend;

/// Surfaces one message carries (the largest first; the road is always
/// among them).
pub const MAX_SURFACES: usize = 16;

/// `road` (and `supported_by`) when there is none.
pub const NO_SURFACE: u32 = u32::MAX;

/// What a surface is to the robot.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SurfaceRole {
    /// The support plane the robot stands on (all its coplanar segments).
    Ground = 0,
    /// Level, at most a stair's rise above the ground or above another
    /// step: a curb, a threshold, a tread.
    Step = 1,
    /// Inclined within the drivable range and joining the ground or a step.
    Ramp = 2,
    /// Steeper than a ramp and joining the ground or a step: an obstacle,
    /// a riser.
    Wall = 3,
    /// Joins neither the ground nor a step (a table, a bed, a shelf, a
    /// board): never the road.
    Elevated = 4,
    /// Faces down (a ceiling, the underside of a table).
    Overhang = 5,
}

impl SurfaceRole {
    pub const ALL: [SurfaceRole; 6] = [
        Self::Ground,
        Self::Step,
        Self::Ramp,
        Self::Wall,
        Self::Elevated,
        Self::Overhang,
    ];

    pub fn from_raw(raw: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|r| *r as u32 == raw)
    }

    /// The name used in logs and JSON output.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ground => "ground",
            Self::Step => "step",
            Self::Ramp => "ramp",
            Self::Wall => "wall",
            Self::Elevated => "elevated",
            Self::Overhang => "overhang",
        }
    }
}

/// What a surface stands on.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SurfaceSupport {
    /// Nothing: it joins neither the ground nor a step (or it is the
    /// ground itself).
    None = 0,
    /// Its lowest inliers meet the ground.
    Ground = 1,
    /// Its lowest inliers meet a step (`supported_by` says which).
    Step = 2,
    /// Its foot is hidden behind something nearer (a box in front of a
    /// ramp's foot): where its plane would meet the surface below, the
    /// camera sees something in front of it, never past it.
    Hidden = 3,
    /// It meets the top or bottom edge of a ramp (`supported_by`): the
    /// ramp's landing.
    Ramp = 4,
}

impl SurfaceSupport {
    pub const ALL: [SurfaceSupport; 5] = [
        Self::None,
        Self::Ground,
        Self::Step,
        Self::Hidden,
        Self::Ramp,
    ];

    pub fn from_raw(raw: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|s| *s as u32 == raw)
    }

    /// The name used in logs and JSON output.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Ground => "ground",
            Self::Step => "step",
            Self::Hidden => "hidden",
            Self::Ramp => "ramp",
        }
    }
}

/// Bits of [`SurfaceDescription::flags`].
pub mod surface_flags {
    /// Some of its inliers lie in the robot's corridor (within the
    /// corridor's half-width of the forward axis, within the look-ahead).
    pub const IN_CORRIDOR: u32 = 1 << 0;
    /// Flat at the sensor's noise level and large enough to measure a slope
    /// on (what the road must be).
    pub const MEASURABLE: u32 = 1 << 1;
    /// It joins the ground, directly or through a chain of steps.
    pub const JOINS_GROUND: u32 = 1 << 2;
}

/// One surface, in the ground frame (see the module documentation).
///
/// 192 bytes, no implicit padding (`layout_is_pinned`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("slope.SurfaceDescription.v1")]
pub struct SurfaceDescription {
    /// A [`SurfaceRole`] as its `u32` value.
    pub role: u32,
    /// A [`SurfaceSupport`] as its `u32` value.
    pub support: u32,
    /// The index (in this message) of the surface it stands on: the ground,
    /// a step or (for a landing) a ramp; [`NO_SURFACE`] when it stands on
    /// nothing seen (or the ground is the mount's plane).
    pub supported_by: u32,
    /// Inlier pixels.
    pub inliers: u32,
    /// Bits of [`surface_flags`].
    pub flags: u32,
    /// RANSAC planes joined into this surface (the ground's segments; 1
    /// for every other surface).
    pub segments: u32,
    /// Angle to the ground, degrees, signed as the estimate's `slope_deg`:
    /// positive when its normal points back towards the robot (it rises
    /// away from it), negative when it falls away; 0 for the ground.
    pub slope_deg: f64,
    /// Heading of its uphill direction (the horizontal direction its
    /// surface rises towards), degrees from forward, positive to the left,
    /// in (-180, 180]: 0 rises straight ahead, 180 falls straight ahead,
    /// 90 rises to the left. NaN for a level surface (no fall line).
    pub heading_deg: f64,
    /// Forward distance to its nearest inlier, metres.
    pub distance_m: f64,
    /// Forward distance to its farthest inlier, metres.
    pub far_m: f64,
    /// Lateral position of its leftmost inlier, metres (positive right, so
    /// negative left of the forward axis).
    pub left_m: f64,
    /// Lateral position of its rightmost inlier, metres (positive right).
    pub right_m: f64,
    /// Height of its lowest inlier above the ground, metres.
    pub lowest_m: f64,
    /// Height of its highest inlier above the ground, metres.
    pub highest_m: f64,
    /// Surface its inliers cover, square metres.
    pub area_m2: f64,
    /// RMS distance of its inliers from its plane, metres.
    pub rms_m: f64,
    /// RMS distance of its inliers in standard deviations of the sensor's
    /// noise (about 1 for a flat surface).
    pub noise_ratio: f64,
    /// `[a, b, c, d]` in the camera frame, unit normal towards the camera.
    pub plane: [f64; 4],
    /// Corners of the rectangle in its plane that holds its inliers (edges
    /// along its level and fall-line directions), camera frame, metres, in
    /// order around the rectangle.
    pub outline: [[f32; 3]; 4],
}

const _: () = assert!(core::mem::size_of::<SurfaceDescription>() == 192);

/// Every surface of one frame (version 1).
///
/// 3216 bytes, no implicit padding (`layout_is_pinned`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("slope.Surfaces.v1")]
pub struct Surfaces {
    /// The cloud's `frame_index`, as in the frame's `SlopeEstimate`.
    pub frame_index: u64,
    /// The cloud's `capture_stamp_ns` (ns since the Unix epoch).
    pub capture_stamp_ns: u64,
    /// When this message was published (ns since the Unix epoch).
    pub publish_stamp_ns: u64,
    /// The cloud's `source_stamp_ns`.
    pub source_stamp_ns: u64,
    /// The frame's `EstimateStatus` as its `u32` value.
    pub status: u32,
    /// Surfaces in `surfaces` (the rest are zero).
    pub count: u32,
    /// Index in `surfaces` of the road ahead (the surface the estimate's
    /// slope is measured on), or [`NO_SURFACE`].
    pub road: u32,
    /// 1 when the ground is the mount's plane (no ground plane was seen;
    /// then no surface has the role `ground`).
    pub ground_from_mount: u32,
    /// The ground's up direction in the camera frame (unit); NaN without a
    /// ground.
    pub up: [f64; 3],
    /// The robot's forward direction in the camera frame (unit,
    /// perpendicular to `up`); NaN without a ground.
    pub forward: [f64; 3],
    /// `[a, b, c, d]` of the ground that heights are measured from (the
    /// ground plane, or the mount's), camera frame; 0 without a ground.
    pub ground_plane: [f64; 4],
    /// Half-width of the robot's corridor, metres (the road is chosen
    /// among surfaces that reach into it).
    pub corridor_half_width_m: f64,
    /// How far ahead the corridor reaches, metres.
    pub look_ahead_m: f64,
    pub surfaces: [SurfaceDescription; MAX_SURFACES],
}

const _: () = assert!(core::mem::size_of::<Surfaces>() == 3216);

impl SurfaceDescription {
    /// An empty slot: nothing seen.
    pub const EMPTY: SurfaceDescription = SurfaceDescription {
        role: SurfaceRole::Elevated as u32,
        support: SurfaceSupport::None as u32,
        supported_by: NO_SURFACE,
        inliers: 0,
        flags: 0,
        segments: 0,
        slope_deg: f64::NAN,
        heading_deg: f64::NAN,
        distance_m: f64::NAN,
        far_m: f64::NAN,
        left_m: f64::NAN,
        right_m: f64::NAN,
        lowest_m: f64::NAN,
        highest_m: f64::NAN,
        area_m2: f64::NAN,
        rms_m: f64::NAN,
        noise_ratio: f64::NAN,
        plane: [0.0; 4],
        outline: [[0.0; 3]; 4],
    };

    /// The role, or `None` for a value this build does not know.
    pub fn role(&self) -> Option<SurfaceRole> {
        SurfaceRole::from_raw(self.role)
    }

    /// What it stands on, or `None` for a value this build does not know.
    pub fn support(&self) -> Option<SurfaceSupport> {
        SurfaceSupport::from_raw(self.support)
    }

    /// True when it joins the ground, directly or through steps.
    pub fn joins_ground(&self) -> bool {
        self.flags & surface_flags::JOINS_GROUND != 0
    }

    /// True when some of its inliers lie in the robot's corridor.
    pub fn in_corridor(&self) -> bool {
        self.flags & surface_flags::IN_CORRIDOR != 0
    }
}

impl Default for SurfaceDescription {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Surfaces {
    /// The surfaces present (the first `count`, at most [`MAX_SURFACES`]).
    pub fn present(&self) -> &[SurfaceDescription] {
        &self.surfaces[..(self.count as usize).min(MAX_SURFACES)]
    }

    /// The road ahead, when one was chosen (and its index is valid).
    pub fn road_surface(&self) -> Option<&SurfaceDescription> {
        self.present().get(usize::try_from(self.road).ok()?)
    }
}

impl Default for Surfaces {
    fn default() -> Self {
        Self {
            frame_index: 0,
            capture_stamp_ns: 0,
            publish_stamp_ns: 0,
            source_stamp_ns: 0,
            status: crate::EstimateStatus::BadFrame as u32,
            count: 0,
            road: NO_SURFACE,
            ground_from_mount: 0,
            up: [f64::NAN; 3],
            forward: [f64::NAN; 3],
            ground_plane: [0.0; 4],
            corridor_half_width_m: f64::NAN,
            look_ahead_m: f64::NAN,
            surfaces: [SurfaceDescription::EMPTY; MAX_SURFACES],
        }
    }
}

#[cfg(test)]
mod tests {
    use core::mem::size_of;

    use super::*;
    use crate::layout::{surface_description, surfaces, FieldLayout};

    /// No gap between fields, and the last ends at the end of the struct.
    fn assert_packed(fields: &[FieldLayout], size: usize) {
        let mut end = 0;
        for f in fields {
            assert_eq!(f.offset, end, "a gap before {}", f.name);
            end = f.offset + f.size;
        }
        assert_eq!(end, size);
    }

    /// The wire layouts of `slope.Surfaces.v1` and its surfaces: readers in
    /// other languages are written against these numbers.
    #[test]
    fn layout_is_pinned() {
        // SAFETY: `type_name` is unsafe to implement, not to call: it
        // returns the pinned constant.
        let names = unsafe {
            (
                <Surfaces as ZeroCopySend>::type_name(),
                <SurfaceDescription as ZeroCopySend>::type_name(),
            )
        };
        assert_eq!(names, ("slope.Surfaces.v1", "slope.SurfaceDescription.v1"));
        assert_eq!(core::mem::align_of::<Surfaces>(), 8);
        let s = surface_description();
        assert_packed(&s, size_of::<SurfaceDescription>());
        let offsets: Vec<_> = s.iter().map(|f| (f.name, f.offset)).collect();
        assert_eq!(
            offsets,
            [
                ("role", 0),
                ("support", 4),
                ("supported_by", 8),
                ("inliers", 12),
                ("flags", 16),
                ("segments", 20),
                ("slope_deg", 24),
                ("heading_deg", 32),
                ("distance_m", 40),
                ("far_m", 48),
                ("left_m", 56),
                ("right_m", 64),
                ("lowest_m", 72),
                ("highest_m", 80),
                ("area_m2", 88),
                ("rms_m", 96),
                ("noise_ratio", 104),
                ("plane", 112),
                ("outline", 144),
            ]
        );
        let m = surfaces();
        assert_packed(&m, size_of::<Surfaces>());
        let offsets: Vec<_> = m.iter().map(|f| (f.name, f.offset)).collect();
        assert_eq!(
            offsets,
            [
                ("frame_index", 0),
                ("capture_stamp_ns", 8),
                ("publish_stamp_ns", 16),
                ("source_stamp_ns", 24),
                ("status", 32),
                ("count", 36),
                ("road", 40),
                ("ground_from_mount", 44),
                ("up", 48),
                ("forward", 72),
                ("ground_plane", 96),
                ("corridor_half_width_m", 128),
                ("look_ahead_m", 136),
                ("surfaces", 144),
            ]
        );
    }

    #[test]
    fn roles_and_supports_round_trip_and_unknown_values_are_none() {
        for r in SurfaceRole::ALL {
            assert_eq!(SurfaceRole::from_raw(r as u32), Some(r));
        }
        for s in SurfaceSupport::ALL {
            assert_eq!(SurfaceSupport::from_raw(s as u32), Some(s));
        }
        let odd = SurfaceDescription {
            role: 17,
            support: 9,
            ..SurfaceDescription::EMPTY
        };
        assert_eq!((odd.role(), odd.support()), (None, None));
    }

    #[test]
    fn present_and_road_respect_count() {
        let mut m = Surfaces {
            count: 2,
            road: 1,
            ..Surfaces::default()
        };
        m.surfaces[1].inliers = 42;
        assert_eq!(m.present().len(), 2);
        assert_eq!(m.road_surface().map(|s| s.inliers), Some(42));
        m.road = 2; // beyond count
        assert!(m.road_surface().is_none());
        m.road = NO_SURFACE;
        assert!(m.road_surface().is_none());
        m.count = 99; // a lying count is capped
        assert_eq!(m.present().len(), MAX_SURFACES);
    }
}
