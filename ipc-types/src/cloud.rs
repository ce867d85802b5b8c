//! The organised point cloud: a slice of [`CloudPoint`]s with a [`CloudHeader`].

use iceoryx2::prelude::ZeroCopySend;

/// One pixel of an organised cloud, in the camera frame (x right, y down,
/// z forward), metres. A pixel without a depth reading has NaN coordinates.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("slope.CloudPoint.v1")]
pub struct CloudPoint {
    pub x_m: f32,
    pub y_m: f32,
    pub z_m: f32,
    /// Colour packed as `0x00RRGGBB`; 0 when the source has no colour.
    pub rgb: u32,
}

const _: () = assert!(core::mem::size_of::<CloudPoint>() == 16);

impl CloudPoint {
    /// The point of a pixel with no depth reading.
    pub const INVALID: CloudPoint = CloudPoint {
        x_m: f32::NAN,
        y_m: f32::NAN,
        z_m: f32::NAN,
        rgb: 0,
    };

    /// True when the pixel had a depth reading.
    #[inline]
    pub fn is_valid(&self) -> bool {
        self.z_m.is_finite()
    }

    /// Packs 8-bit red, green and blue into [`CloudPoint::rgb`].
    #[inline]
    pub fn pack_rgb(r: u8, g: u8, b: u8) -> u32 {
        (u32::from(r) << 16) | (u32::from(g) << 8) | u32::from(b)
    }

    /// The coordinates as an array, metres.
    #[inline]
    pub fn xyz(&self) -> [f32; 3] {
        [self.x_m, self.y_m, self.z_m]
    }
}

impl Default for CloudPoint {
    fn default() -> Self {
        Self::INVALID
    }
}

/// Pinhole intrinsics of the (undistorted) depth image, pixels, with pixel
/// centres at integer coordinates (OpenCV convention, as in the recording
/// format): `x = (u - cx) * z / fx`, `y = (v - cy) * z / fy`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, ZeroCopySend)]
#[type_name("slope.Intrinsics.v1")]
pub struct Intrinsics {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

const _: () = assert!(core::mem::size_of::<Intrinsics>() == 32);

/// The camera's pose on the robot, as in the recording format's `[mount]`.
/// Each value is NaN when unknown.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("slope.Mount.v1")]
pub struct Mount {
    /// Optical centre above the ground the robot stands on, metres.
    pub height_m: f64,
    /// Rotation about the camera x axis; negative looks down.
    pub pitch_deg: f64,
    /// Rotation about the optical axis; positive dips the image's right side.
    pub roll_deg: f64,
}

const _: () = assert!(core::mem::size_of::<Mount>() == 24);

impl Mount {
    /// A mount about which nothing is known.
    pub const UNKNOWN: Mount = Mount {
        height_m: f64::NAN,
        pitch_deg: f64::NAN,
        roll_deg: f64::NAN,
    };

    /// The ground's upward unit normal in camera coordinates, when the pitch
    /// is known (a missing roll counts as 0):
    /// `up = (-sin r cos p, -cos r cos p, sin p)`.
    pub fn up_vector(&self) -> Option<[f64; 3]> {
        if !self.pitch_deg.is_finite() {
            return None;
        }
        let p = self.pitch_deg.to_radians();
        let r = if self.roll_deg.is_finite() {
            self.roll_deg.to_radians()
        } else {
            0.0
        };
        Some([-r.sin() * p.cos(), -r.cos() * p.cos(), p.sin()])
    }
}

impl Default for Mount {
    fn default() -> Self {
        Self::UNKNOWN
    }
}

/// Where a cloud came from.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CloudSource {
    Camera = 1,
    Replay = 2,
}

impl CloudSource {
    pub fn from_raw(raw: u32) -> Option<Self> {
        match raw {
            1 => Some(Self::Camera),
            2 => Some(Self::Replay),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Camera => "camera",
            Self::Replay => "replay",
        }
    }
}

/// The user header of every cloud sample.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("slope.CloudHeader.v1")]
pub struct CloudHeader {
    /// Frame counter of the source: the recording's `index`, or the camera's
    /// sequence number.
    pub frame_index: u64,
    /// When the frame was captured (camera) or emitted (replay), ns since the
    /// Unix epoch. Latencies are measured from here.
    pub capture_stamp_ns: u64,
    /// The frame's time in the source's own clock: the recording's
    /// `timestamp_ns`, or the device timestamp.
    pub source_stamp_ns: u64,
    pub width: u32,
    pub height: u32,
    pub intrinsics: Intrinsics,
    pub mount: Mount,
    /// A [`CloudSource`] as its `u32` value.
    pub source: u32,
    /// True (1) when the cloud carries colour in [`CloudPoint::rgb`].
    pub has_color: u32,
}

const _: () = assert!(core::mem::size_of::<CloudHeader>() == 96);

impl CloudHeader {
    /// Number of points the payload holds: `width * height`.
    pub fn point_count(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

impl Default for CloudHeader {
    fn default() -> Self {
        Self {
            frame_index: 0,
            capture_stamp_ns: 0,
            source_stamp_ns: 0,
            width: 0,
            height: 0,
            intrinsics: Intrinsics::default(),
            mount: Mount::UNKNOWN,
            source: CloudSource::Replay as u32,
            has_color: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn up_vector_matches_the_recording_spec() {
        let mount = Mount {
            height_m: 0.5,
            pitch_deg: -20.0,
            roll_deg: 0.0,
        };
        let up = mount.up_vector().unwrap();
        let p = (-20.0f64).to_radians();
        assert!((up[0]).abs() < 1e-12);
        assert!((up[1] + p.cos()).abs() < 1e-12);
        assert!((up[2] - p.sin()).abs() < 1e-12);
        let norm = (up[0] * up[0] + up[1] * up[1] + up[2] * up[2]).sqrt();
        assert!((norm - 1.0).abs() < 1e-12);
        // The stairs recording's IMU up vector [-0.00187, -0.89132, -0.45337].
        let stairs = Mount {
            height_m: f64::NAN,
            pitch_deg: -26.96,
            roll_deg: 0.12,
        };
        let up = stairs.up_vector().unwrap();
        assert!((up[0] + 0.00187).abs() < 1e-4, "{up:?}");
        assert!((up[1] + 0.89132).abs() < 1e-4, "{up:?}");
        assert!((up[2] + 0.45337).abs() < 1e-4, "{up:?}");
    }

    #[test]
    fn unknown_pitch_gives_no_up_vector() {
        assert!(Mount::UNKNOWN.up_vector().is_none());
    }

    #[test]
    fn rgb_packs_in_order() {
        assert_eq!(CloudPoint::pack_rgb(0x12, 0x34, 0x56), 0x0012_3456);
    }
}
