//! The organised point cloud: a slice of [`CloudPoint`]s with a [`CloudHeader`].

use iceoryx2::prelude::ZeroCopySend;

use crate::text::{text_of, write_text};

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

/// Bytes of [`CloudHeader::sensor`] (UTF-8, NUL-padded).
pub const SENSOR_NAME_LEN: usize = 32;

/// The user header of every cloud sample.
///
/// `#[repr(C)]`, 128 bytes, 8-byte aligned, no implicit padding: every
/// field starts at a multiple of its alignment and the `u32` pairs fill
/// whole 8-byte words. The test `layout_is_pinned` pins the offsets (the
/// table in the crate's README). Version 2 appended [`CloudHeader::sensor`]
/// to the 96 bytes of version 1.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("slope.CloudHeader.v2")]
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
    /// The name of the sensor that took the frame, as a recording's
    /// `sensor` (`kinect2`, `kinect1`, `synthetic`, ...): UTF-8, NUL-padded,
    /// all NUL when unknown. Read it with [`CloudHeader::sensor_name`].
    pub sensor: [u8; SENSOR_NAME_LEN],
}

const _: () = assert!(core::mem::size_of::<CloudHeader>() == 128);

impl CloudHeader {
    /// Number of points the payload holds: `width * height`.
    pub fn point_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The sensor's name (empty when unknown). Tolerant of any bytes: the
    /// name ends at the first NUL, or at the end of the array, or where
    /// invalid UTF-8 starts.
    pub fn sensor_name(&self) -> &str {
        text_of(&self.sensor)
    }

    /// Sets the sensor's name, cut to [`SENSOR_NAME_LEN`] bytes at a
    /// character boundary.
    pub fn set_sensor_name(&mut self, name: &str) {
        self.sensor = Self::sensor_field(name);
    }

    /// The [`CloudHeader::sensor`] field for `name`: its first
    /// [`SENSOR_NAME_LEN`] bytes (whole characters), NUL-padded.
    pub fn sensor_field(name: &str) -> [u8; SENSOR_NAME_LEN] {
        let mut field = [0; SENSOR_NAME_LEN];
        write_text(&mut field, name);
        field
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
            sensor: [0; SENSOR_NAME_LEN],
        }
    }
}

#[cfg(test)]
mod tests {
    use core::mem::{offset_of, size_of};

    use super::*;

    /// The wire layout of `slope.CloudHeader.v2`: a change is a new version.
    #[test]
    fn layout_is_pinned() {
        // SAFETY: `type_name` is unsafe to implement, not to call: it
        // returns the pinned constant.
        let type_name = unsafe { <CloudHeader as ZeroCopySend>::type_name() };
        assert_eq!(type_name, "slope.CloudHeader.v2");
        let expected = [
            ("frame_index", offset_of!(CloudHeader, frame_index), 0),
            (
                "capture_stamp_ns",
                offset_of!(CloudHeader, capture_stamp_ns),
                8,
            ),
            (
                "source_stamp_ns",
                offset_of!(CloudHeader, source_stamp_ns),
                16,
            ),
            ("width", offset_of!(CloudHeader, width), 24),
            ("height", offset_of!(CloudHeader, height), 28),
            ("intrinsics", offset_of!(CloudHeader, intrinsics), 32),
            ("mount", offset_of!(CloudHeader, mount), 64),
            ("source", offset_of!(CloudHeader, source), 88),
            ("has_color", offset_of!(CloudHeader, has_color), 92),
            ("sensor", offset_of!(CloudHeader, sensor), 96),
        ];
        for (name, actual, pinned) in expected {
            assert_eq!(actual, pinned, "{name}");
        }
        assert_eq!(96 + SENSOR_NAME_LEN, size_of::<CloudHeader>());
        assert_eq!(core::mem::align_of::<CloudHeader>(), 8);
    }

    #[test]
    fn sensor_names_round_trip() {
        let mut header = CloudHeader::default();
        assert_eq!(header.sensor_name(), "", "unknown by default");
        header.set_sensor_name("kinect1");
        assert_eq!(header.sensor_name(), "kinect1");
        assert_eq!(&header.sensor[..8], b"kinect1\0");
        // A shorter name replaces a longer one entirely.
        header.set_sensor_name("tum");
        assert_eq!(header.sensor_name(), "tum");
        assert!(header.sensor[3..].iter().all(|&b| b == 0));
        header.set_sensor_name("");
        assert_eq!(header.sensor, [0; SENSOR_NAME_LEN]);
    }

    #[test]
    fn a_long_sensor_name_is_cut_at_a_character_boundary() {
        // 31 ASCII bytes, then 'é' (two bytes) would end at byte 33: cut
        // before it, not inside it.
        let name = format!("{}é-and-more", "k".repeat(SENSOR_NAME_LEN - 1));
        let field = CloudHeader::sensor_field(&name);
        let header = CloudHeader {
            sensor: field,
            ..CloudHeader::default()
        };
        assert_eq!(header.sensor_name(), "k".repeat(SENSOR_NAME_LEN - 1));
        assert_eq!(field[SENSOR_NAME_LEN - 1], 0);
        // Exactly 32 bytes fill the array: no NUL, and all of it is the name.
        let full = "é".repeat(SENSOR_NAME_LEN / 2);
        let header = CloudHeader {
            sensor: CloudHeader::sensor_field(&full),
            ..CloudHeader::default()
        };
        assert!(header.sensor.iter().all(|&b| b != 0));
        assert_eq!(header.sensor_name(), full);
        // Three-byte characters: 10 fit (30 bytes), the 11th does not.
        let header = CloudHeader {
            sensor: CloudHeader::sensor_field(&"€".repeat(11)),
            ..CloudHeader::default()
        };
        assert_eq!(header.sensor_name(), "€".repeat(10));
        assert_eq!(header.sensor[30..], [0, 0]);
    }

    #[test]
    fn a_sensor_name_of_bad_bytes_reads_up_to_them() {
        let mut sensor = [b'x'; SENSOR_NAME_LEN];
        sensor[..6].copy_from_slice(b"kinect");
        // An unfinished two-byte sequence, then a stray continuation byte.
        sensor[6] = 0xC3;
        sensor[7] = b'!';
        sensor[8] = 0x80;
        let header = CloudHeader {
            sensor,
            ..CloudHeader::default()
        };
        assert_eq!(header.sensor_name(), "kinect");
        let header = CloudHeader {
            sensor: [0xFF; SENSOR_NAME_LEN],
            ..CloudHeader::default()
        };
        assert_eq!(header.sensor_name(), "");
        // No NUL and all valid: the whole array.
        let header = CloudHeader {
            sensor: [b'a'; SENSOR_NAME_LEN],
            ..CloudHeader::default()
        };
        assert_eq!(header.sensor_name(), "a".repeat(SENSOR_NAME_LEN));
    }

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
