//! The slope estimate every subscriber receives (`slope.SlopeEstimate.v2`).

use iceoryx2::prelude::ZeroCopySend;

/// What became of one frame.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EstimateStatus {
    /// A slope was measured; `slope_deg` and the planes are valid.
    Ok = 0,
    /// No ground plane was found and the mount gives no up vector.
    NoGround = 1,
    /// No inclined plane (ramp, wall) ahead was found.
    NoInclinedPlane = 2,
    /// Too few valid points to run the method.
    TooFewPoints = 3,
    /// The frame itself was malformed (size mismatch, empty).
    BadFrame = 4,
}

impl EstimateStatus {
    pub const ALL: [EstimateStatus; 5] = [
        Self::Ok,
        Self::NoGround,
        Self::NoInclinedPlane,
        Self::TooFewPoints,
        Self::BadFrame,
    ];

    pub fn from_raw(raw: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|s| *s as u32 == raw)
    }

    /// The name used in logs and JSON output.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ok => "ok",
            Self::NoGround => "no_ground",
            Self::NoInclinedPlane => "no_inclined_plane",
            Self::TooFewPoints => "too_few_points",
            Self::BadFrame => "bad_frame",
        }
    }
}

/// Which fit produced the estimate.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SlopeMethod {
    /// The paper's method: normals, cosine k-means, cumulative averaging.
    Paper = 0,
    /// Ordinary least squares z = ax + by + c on each plane's points.
    LeastSquares = 1,
    /// Total least squares (PCA) on each plane's RANSAC inliers.
    Tls = 2,
}

impl SlopeMethod {
    pub const ALL: [SlopeMethod; 3] = [Self::Paper, Self::LeastSquares, Self::Tls];

    pub fn from_raw(raw: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|m| *m as u32 == raw)
    }

    /// The name used on command lines and in JSON output.
    pub fn name(self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::LeastSquares => "least-squares",
            Self::Tls => "tls",
        }
    }
}

/// One slope estimate, published once per processed frame (version 2 of
/// the message).
///
/// Planes are `[a, b, c, d]` with `a x + b y + c z + d = 0` in the camera
/// frame, `(a, b, c)` a unit normal pointing up and out of the surface
/// (towards the camera side, so `d` is the camera's distance to the plane);
/// all zero when absent.
///
/// Version 2 keeps every field of version 1 at the same offset (the first
/// 160 bytes are the v1 layout) and appends the plane quality, the
/// confidence and the tracked slope. The layout has no implicit padding
/// (`ground_seen_to_m`, an `f32`, fills the one gap); the test `layout_is_pinned` pins the size
/// and every offset, for readers in other languages.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("slope.SlopeEstimate.v2")]
pub struct SlopeEstimate {
    /// The cloud's `frame_index`.
    pub frame_index: u64,
    /// The cloud's `capture_stamp_ns` (ns since the Unix epoch).
    pub capture_stamp_ns: u64,
    /// When this estimate was published (ns since the Unix epoch).
    pub publish_stamp_ns: u64,
    /// The cloud's `source_stamp_ns`.
    pub source_stamp_ns: u64,
    /// Clouds the estimator skipped so far because a newer one was waiting
    /// (or never saw: gaps in `frame_index`), cumulative.
    pub dropped_frames: u64,
    /// An [`EstimateStatus`] as its `u32` value.
    pub status: u32,
    /// A [`SlopeMethod`] as its `u32` value.
    pub method: u32,
    /// Signed slope, degrees: the angle between the inclined plane and the
    /// ground, positive uphill (the surface rises away from the camera),
    /// negative downhill. NaN unless `status` is ok.
    pub slope_deg: f64,
    /// Standard deviation of the averaged angle samples, degrees.
    pub slope_std_deg: f64,
    /// Distance from the camera to the inclined plane along the viewing
    /// direction (optical axis), metres; NaN when the axis does not meet it.
    pub distance_m: f64,
    /// `[a, b, c, d]` of the ground plane (camera frame, unit normal towards
    /// the camera, `d` its distance); all 0 without a measured ground. Also
    /// set with status `no_inclined_plane` (the floor ahead is flat: here
    /// it is, its TLS fit).
    pub ground_plane: [f64; 4],
    /// `[a, b, c, d]` of the inclined plane; all 0 without one.
    pub inclined_plane: [f64; 4],
    pub ground_inliers: u32,
    pub inclined_inliers: u32,
    /// Angle samples averaged into `slope_deg`.
    pub samples: u32,
    /// 1 when the ground normal came from the mount's up vector instead of a
    /// measured ground plane.
    pub ground_from_mount: u32,
    /// Time spent estimating this frame, microseconds.
    pub processing_us: u64,
    // ---- version 2 ----
    /// How far to trust `slope_deg`, 0..=1 (0 unless `status` is ok).
    pub confidence: f64,
    /// Why `confidence` is below 1: bits of [`crate::confidence`] (several
    /// may be set); see [`SlopeEstimate::confidence_reason_names`].
    pub confidence_reasons: u32,
    /// How far ahead the ground plane was seen, metres: the largest forward
    /// distance of a ground inlier from the camera. Short of the sensor's
    /// range (4-5 m on a Kinect v2) when the floor ends before a drop-off,
    /// which `no_inclined_plane` alone cannot tell from a flat floor. NaN
    /// without a measured ground plane; 0 from an estimator built before
    /// this field (it was `reserved`, always 0). `f32` to fill the gap
    /// before the next `f64` (no implicit padding).
    pub ground_seen_to_m: f32,
    /// RMS distance of the ground plane's inliers from the plane, metres;
    /// NaN without a measured ground plane.
    pub ground_rms_m: f64,
    /// RMS distance of the inclined plane's inliers from the plane, metres;
    /// NaN without an inclined plane.
    pub inclined_rms_m: f64,
    /// Surface the ground plane's inliers cover, square metres; NaN without
    /// a measured ground plane.
    pub ground_area_m2: f64,
    /// Surface the inclined plane's inliers cover, square metres; NaN
    /// without an inclined plane.
    pub inclined_area_m2: f64,
    /// The slope of the plane ahead followed over frames by the estimator,
    /// degrees, signed as `slope_deg`; NaN when there is no track (yet).
    pub tracked_slope_deg: f64,
    /// Standard deviation of `tracked_slope_deg`, degrees; NaN when there is
    /// no track.
    pub tracked_std_deg: f64,
    /// Frames accepted into the track since it (re)started; 0 without a
    /// track.
    pub tracked_frames: u32,
    /// 1 when this frame's estimate was accepted into the track, else 0.
    pub tracked_accepted: u32,
}

const _: () = assert!(core::mem::size_of::<SlopeEstimate>() == 232);

impl SlopeEstimate {
    /// The status, or `BadFrame` for a value this build does not know.
    pub fn status(&self) -> EstimateStatus {
        EstimateStatus::from_raw(self.status).unwrap_or(EstimateStatus::BadFrame)
    }

    pub fn method(&self) -> Option<SlopeMethod> {
        SlopeMethod::from_raw(self.method)
    }

    /// Capture-to-publish latency, milliseconds.
    pub fn latency_ms(&self) -> f64 {
        self.publish_stamp_ns.saturating_sub(self.capture_stamp_ns) as f64 / 1e6
    }

    /// The names of the bits set in `confidence_reasons`, in bit order
    /// (a bit this build does not know is named `bit_N`).
    pub fn confidence_reason_names(&self) -> impl Iterator<Item = std::borrow::Cow<'static, str>> {
        crate::confidence::names(self.confidence_reasons)
    }

    /// True when the estimator tracks a slope: `tracked_slope_deg` holds a
    /// value.
    pub fn has_tracked_slope(&self) -> bool {
        self.tracked_slope_deg.is_finite()
    }
}

impl Default for SlopeEstimate {
    fn default() -> Self {
        Self {
            frame_index: 0,
            capture_stamp_ns: 0,
            publish_stamp_ns: 0,
            source_stamp_ns: 0,
            dropped_frames: 0,
            status: EstimateStatus::BadFrame as u32,
            method: SlopeMethod::Paper as u32,
            slope_deg: f64::NAN,
            slope_std_deg: f64::NAN,
            distance_m: f64::NAN,
            ground_plane: [0.0; 4],
            inclined_plane: [0.0; 4],
            ground_inliers: 0,
            inclined_inliers: 0,
            samples: 0,
            ground_from_mount: 0,
            processing_us: 0,
            confidence: 0.0,
            confidence_reasons: 0,
            ground_seen_to_m: f32::NAN,
            ground_rms_m: f64::NAN,
            inclined_rms_m: f64::NAN,
            ground_area_m2: f64::NAN,
            inclined_area_m2: f64::NAN,
            tracked_slope_deg: f64::NAN,
            tracked_std_deg: f64::NAN,
            tracked_frames: 0,
            tracked_accepted: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use core::mem::{offset_of, size_of};

    use super::*;
    use crate::confidence;

    /// The size of a field, from a projection onto it.
    fn field_size<T, F>(_: fn(&T) -> &F) -> usize {
        size_of::<F>()
    }

    /// `(name, offset, size)` of every field, in declaration order.
    macro_rules! fields {
        ($($name:ident),* $(,)?) => {
            [$((
                stringify!($name),
                offset_of!(SlopeEstimate, $name),
                field_size(|e: &SlopeEstimate| &e.$name),
            )),*]
        };
    }

    /// The wire layout of `slope.SlopeEstimate.v2`. Readers in other
    /// languages are written against these numbers: a change here is a new
    /// message version, not an edit.
    #[test]
    fn layout_is_pinned() {
        // SAFETY: `type_name` is unsafe to implement (the implementer vouches
        // for the layout), not to call: it returns the pinned constant.
        let type_name = unsafe { <SlopeEstimate as ZeroCopySend>::type_name() };
        assert_eq!(type_name, "slope.SlopeEstimate.v2");
        assert_eq!(size_of::<SlopeEstimate>(), 232);
        assert_eq!(core::mem::align_of::<SlopeEstimate>(), 8);
        let expected: [(&str, usize, usize); 28] = [
            ("frame_index", 0, 8),
            ("capture_stamp_ns", 8, 8),
            ("publish_stamp_ns", 16, 8),
            ("source_stamp_ns", 24, 8),
            ("dropped_frames", 32, 8),
            ("status", 40, 4),
            ("method", 44, 4),
            ("slope_deg", 48, 8),
            ("slope_std_deg", 56, 8),
            ("distance_m", 64, 8),
            ("ground_plane", 72, 32),
            ("inclined_plane", 104, 32),
            ("ground_inliers", 136, 4),
            ("inclined_inliers", 140, 4),
            ("samples", 144, 4),
            ("ground_from_mount", 148, 4),
            ("processing_us", 152, 8),
            ("confidence", 160, 8),
            ("confidence_reasons", 168, 4),
            ("ground_seen_to_m", 172, 4),
            ("ground_rms_m", 176, 8),
            ("inclined_rms_m", 184, 8),
            ("ground_area_m2", 192, 8),
            ("inclined_area_m2", 200, 8),
            ("tracked_slope_deg", 208, 8),
            ("tracked_std_deg", 216, 8),
            ("tracked_frames", 224, 4),
            ("tracked_accepted", 228, 4),
        ];
        let actual = fields!(
            frame_index,
            capture_stamp_ns,
            publish_stamp_ns,
            source_stamp_ns,
            dropped_frames,
            status,
            method,
            slope_deg,
            slope_std_deg,
            distance_m,
            ground_plane,
            inclined_plane,
            ground_inliers,
            inclined_inliers,
            samples,
            ground_from_mount,
            processing_us,
            confidence,
            confidence_reasons,
            ground_seen_to_m,
            ground_rms_m,
            inclined_rms_m,
            ground_area_m2,
            inclined_area_m2,
            tracked_slope_deg,
            tracked_std_deg,
            tracked_frames,
            tracked_accepted,
        );
        assert_eq!(actual, expected);
        // No implicit padding: each field starts where the one before ends,
        // and the last one ends at the end of the struct.
        let mut end = 0;
        for (name, offset, size) in actual {
            assert_eq!(offset, end, "a gap before {name}");
            end = offset + size;
        }
        assert_eq!(end, size_of::<SlopeEstimate>());
    }

    /// The `Default` of every v2 field: nothing measured, nothing tracked.
    #[test]
    fn default_has_no_plane_no_confidence_and_no_track() {
        let e = SlopeEstimate::default();
        assert_eq!(e.status(), EstimateStatus::BadFrame);
        assert_eq!((e.confidence, e.confidence_reasons), (0.0, 0));
        for value in [
            e.ground_rms_m,
            e.inclined_rms_m,
            e.ground_area_m2,
            e.inclined_area_m2,
            e.tracked_slope_deg,
            e.tracked_std_deg,
            f64::from(e.ground_seen_to_m),
        ] {
            assert!(value.is_nan());
        }
        assert_eq!((e.tracked_frames, e.tracked_accepted), (0, 0));
        assert!(!e.has_tracked_slope());
        assert_eq!(e.confidence_reason_names().count(), 0);
    }

    #[test]
    fn confidence_reasons_are_named_in_bit_order_unknown_bits_too() {
        let e = SlopeEstimate {
            confidence: 0.4,
            confidence_reasons: confidence::SMALL_AREA | confidence::FEW_POINTS | 1 << 31,
            ..Default::default()
        };
        let names: Vec<_> = e.confidence_reason_names().collect();
        assert_eq!(names, ["few_points", "small_area", "bit_31"]);
    }

    #[test]
    fn status_round_trips_through_raw() {
        for s in EstimateStatus::ALL {
            assert_eq!(EstimateStatus::from_raw(s as u32), Some(s));
        }
        assert_eq!(EstimateStatus::from_raw(99), None);
        let e = SlopeEstimate {
            status: 99,
            ..Default::default()
        };
        assert_eq!(e.status(), EstimateStatus::BadFrame);
    }

    #[test]
    fn latency_is_publish_minus_capture() {
        let e = SlopeEstimate {
            capture_stamp_ns: 1_000_000_000,
            publish_stamp_ns: 1_012_500_000,
            ..Default::default()
        };
        assert!((e.latency_ms() - 12.5).abs() < 1e-9);
    }
}
