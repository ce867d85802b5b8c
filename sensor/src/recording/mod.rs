//! Recordings on disk: the directory layout of
//! `shared/spec/recording-format.md` (version 1), read by [`Recording`] and
//! written by [`RecordingWriter`].
//!
//! ```text
//! recording/
//!   recording.toml      metadata            -> RecordingMeta   (meta.rs)
//!   frames.csv          one row per frame   -> [FrameEntry]     (reader.rs)
//!   depth/000000.png    16-bit grayscale    -> DepthImage
//!   color/000000.png    8-bit RGB, optional -> ColorImage
//! ```
//!
//! [`Recording::open`] validates `recording.toml` and `frames.csv` up front;
//! images are decoded (and checked against `[depth]`) only when a frame is
//! read, so that a replay can skip one bad frame instead of refusing the
//! whole recording. Every error names the file, and the row or key where
//! there is one ([`RecordingError`]).
//!
//! Files: `meta.rs` (metadata types, TOML parsing and formatting, pure),
//! `reader.rs` (frames.csv parsing, [`Recording`], PNG decoding),
//! `writer.rs` ([`RecordingWriter`], PNG encoding), `error.rs`.

mod error;
mod meta;
mod reader;
mod writer;

pub use error::RecordingError;
pub use meta::{
    DepthInfo, MountInfo, MountRange, RecordingMeta, TruthInfo, FORMAT_NAME, FORMAT_VERSION,
};
pub use reader::{FrameEntry, Recording};
pub use writer::{PngCompression, RecordingWriter};

/// File name of the metadata inside a recording directory.
pub const META_FILE: &str = "recording.toml";
/// File name of the frame table inside a recording directory.
pub const FRAMES_FILE: &str = "frames.csv";
/// Folder of the depth images inside a recording directory.
pub const DEPTH_DIR: &str = "depth";
/// Folder of the colour images inside a recording directory.
pub const COLOR_DIR: &str = "color";

/// A depth image: raw counts (multiply by `unit_m` for metres along the
/// optical axis; 0 = no reading), row-major, `width * height` values.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct DepthImage {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u16>,
}

impl DepthImage {
    /// An image of zeros (no readings).
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            data: vec![0; pixel_count(width, height)],
        }
    }

    /// The raw count at column `u`, row `v`; `None` outside the image.
    pub fn get(&self, u: u32, v: u32) -> Option<u16> {
        pixel_index(self.width, self.height, u, v).and_then(|i| self.data.get(i).copied())
    }
}

/// A colour image registered to the depth image: RGB, row-major,
/// `width * height` pixels.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ColorImage {
    pub width: u32,
    pub height: u32,
    pub data: Vec<[u8; 3]>,
}

impl ColorImage {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            data: vec![[0; 3]; pixel_count(width, height)],
        }
    }

    /// The colour at column `u`, row `v`; `None` outside the image.
    pub fn get(&self, u: u32, v: u32) -> Option<[u8; 3]> {
        pixel_index(self.width, self.height, u, v).and_then(|i| self.data.get(i).copied())
    }
}

fn pixel_count(width: u32, height: u32) -> usize {
    width as usize * height as usize
}

fn pixel_index(width: u32, height: u32, u: u32, v: u32) -> Option<usize> {
    (u < width && v < height).then(|| v as usize * width as usize + u as usize)
}

/// A depth in metres as a raw depth count of a recording with `unit_m`
/// metres per count: `round(depth_m / unit_m)`, or 0 (no reading) for
/// anything that is not a count in 1..=65535 (NaN, zero or negative, or
/// beyond the 16-bit range). Every writer of depth counts (the simulator,
/// the recorder) uses this one rule.
pub fn metres_to_count(depth_m: f64, unit_m: f64) -> u16 {
    let count = (depth_m / unit_m).round();
    if (1.0..=f64::from(u16::MAX)).contains(&count) {
        // A whole number in 1..=65535 after the check: the cast is exact.
        count as u16
    } else {
        0
    }
}

/// The metadata of a tiny recording for unit tests: `width` x `height`
/// pixels of 1 mm counts, focal lengths of 1 px, no mount, no truth.
#[cfg(test)]
pub(crate) fn test_meta(width: u32, height: u32) -> RecordingMeta {
    RecordingMeta {
        sensor: "test".into(),
        depth: DepthInfo {
            width,
            height,
            unit_m: 0.001,
            fx: 1.0,
            fy: 1.0,
            cx: 0.5,
            cy: 0.5,
        },
        mount: MountInfo {
            height_m: None,
            pitch_deg: None,
            roll_deg: None,
        },
        truth: TruthInfo { slope_deg: None },
    }
}

#[cfg(test)]
mod count_tests {
    use super::metres_to_count;

    #[test]
    fn counts_round_to_nearest_and_out_of_range_is_no_reading() {
        assert_eq!(metres_to_count(1.2344, 0.001), 1234);
        assert_eq!(metres_to_count(1.2346, 0.001), 1235);
        assert_eq!(metres_to_count(0.0004, 0.001), 0);
        assert_eq!(metres_to_count(-1.0, 0.001), 0);
        assert_eq!(metres_to_count(f64::NAN, 0.001), 0);
        assert_eq!(metres_to_count(f64::INFINITY, 0.001), 0);
        assert_eq!(metres_to_count(65.535, 0.001), 65535);
        assert_eq!(metres_to_count(65.6, 0.001), 0);
        assert_eq!(metres_to_count(1.0, 0.0002), 5000);
    }
}
