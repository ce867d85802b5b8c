//! Frames as libfreenect2 hands them out, and the checks every frame passes
//! before it is converted: the layout libfreenect2 documents, the buffer
//! sizes the registration needs, depth values its arithmetic can take.
//! Pure: a [`FrameView`] of caller-owned bytes needs no device and no
//! library (the device layer makes them from libfreenect2's frames).

// Without the `kinect2` feature the checks the device layer makes are
// called by the tests only.
#![cfg_attr(not(feature = "kinect2"), allow(dead_code))]

use super::error::Kinect2Error;
use super::params::{DEPTH_HEIGHT, DEPTH_PIXELS, DEPTH_WIDTH};

/// Pixel layout of a frame (`libfreenect2::Frame::Format`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameFormat {
    Invalid,
    Raw,
    Float,
    Bgrx,
    Rgbx,
    Gray,
    Unknown(u32),
}

impl FrameFormat {
    /// The codes of `libfreenect2::Frame::Format` (the shim's
    /// `f2s_frame_format`; the device layer checks them against it at
    /// compile time).
    pub const INVALID_CODE: u32 = 0;
    pub const RAW_CODE: u32 = 1;
    pub const FLOAT_CODE: u32 = 2;
    pub const BGRX_CODE: u32 = 4;
    pub const RGBX_CODE: u32 = 5;
    pub const GRAY_CODE: u32 = 6;

    /// The format of libfreenect2's code `code`.
    pub fn from_code(code: u32) -> Self {
        match code {
            Self::INVALID_CODE => Self::Invalid,
            Self::RAW_CODE => Self::Raw,
            Self::FLOAT_CODE => Self::Float,
            Self::BGRX_CODE => Self::Bgrx,
            Self::RGBX_CODE => Self::Rgbx,
            Self::GRAY_CODE => Self::Gray,
            _ => Self::Unknown(code),
        }
    }

    /// libfreenect2's code of the format.
    pub fn code(self) -> u32 {
        match self {
            Self::Invalid => Self::INVALID_CODE,
            Self::Raw => Self::RAW_CODE,
            Self::Float => Self::FLOAT_CODE,
            Self::Bgrx => Self::BGRX_CODE,
            Self::Rgbx => Self::RGBX_CODE,
            Self::Gray => Self::GRAY_CODE,
            Self::Unknown(code) => code,
        }
    }
}

/// What the device says about a frame besides its pixels.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FrameMetadata {
    /// 0 when libfreenect2 decoded the frame without error.
    pub status: u32,
    /// Device time, units of 0.125 ms (wraps after about 6 days).
    pub timestamp: u32,
    /// The device's frame sequence number.
    pub sequence: u32,
    pub exposure: f32,
    pub gain: f32,
    pub gamma: f32,
}

/// A read-only view of one frame: pixels owned by libfreenect2 (borrowed
/// from a frame set) or by the caller ([`FrameView::from_bytes`]).
#[derive(Debug, Clone, Copy)]
pub struct FrameView<'a> {
    width: usize,
    height: usize,
    bytes_per_pixel: usize,
    format: FrameFormat,
    metadata: FrameMetadata,
    data: &'a [u8],
}

impl<'a> FrameView<'a> {
    /// A view of caller-owned pixels (e.g. a stored frame, or a test image);
    /// `None` when `data` is not `width * height * bytes_per_pixel` long.
    pub fn from_bytes(
        width: usize,
        height: usize,
        bytes_per_pixel: usize,
        format: FrameFormat,
        data: &'a [u8],
    ) -> Option<Self> {
        let len = width.checked_mul(height)?.checked_mul(bytes_per_pixel)?;
        if data.len() != len {
            return None;
        }
        Some(Self {
            width,
            height,
            bytes_per_pixel,
            format,
            metadata: FrameMetadata::default(),
            data,
        })
    }

    /// The same view with the device's `metadata`.
    pub fn with_metadata(self, metadata: FrameMetadata) -> Self {
        Self { metadata, ..self }
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    pub fn bytes_per_pixel(&self) -> usize {
        self.bytes_per_pixel
    }

    pub fn format(&self) -> FrameFormat {
        self.format
    }

    /// Status, stamps and exposure as the device reported them.
    pub fn metadata(&self) -> FrameMetadata {
        self.metadata
    }

    /// 0 when libfreenect2 decoded the frame without error.
    pub fn status(&self) -> u32 {
        self.metadata.status
    }

    /// Device time, units of 0.125 ms (wraps after about 6 days).
    pub fn timestamp(&self) -> u32 {
        self.metadata.timestamp
    }

    /// The device's frame sequence number.
    pub fn sequence(&self) -> u32 {
        self.metadata.sequence
    }

    /// The pixels, `width * height * bytes_per_pixel` bytes.
    pub fn data(&self) -> &'a [u8] {
        self.data
    }
}

/// Fails unless `view` is `width x height` 4-byte pixels (what the
/// registration reads).
pub(crate) fn check_view(
    view: &FrameView<'_>,
    width: usize,
    height: usize,
    what: &str,
) -> Result<(), Kinect2Error> {
    if view.width() == width && view.height() == height && view.bytes_per_pixel() == 4 {
        Ok(())
    } else {
        Err(Kinect2Error::BadImageSize {
            expected: format!("a {width} x {height} x 4 {what} frame"),
            got: format!(
                "{} x {} x {}",
                view.width(),
                view.height(),
                view.bytes_per_pixel()
            ),
        })
    }
}

/// Fails unless a buffer of `len` pixels holds a whole depth image.
pub(crate) fn check_len(len: usize, what: &str) -> Result<(), Kinect2Error> {
    if len == DEPTH_PIXELS {
        Ok(())
    } else {
        Err(Kinect2Error::BadImageSize {
            expected: format!(
                "a {DEPTH_WIDTH} x {DEPTH_HEIGHT} {what} buffer ({DEPTH_PIXELS} pixels)"
            ),
            got: format!("{len} pixels"),
        })
    }
}

/// Fails unless `view` is `width x height` 4-byte pixels in a format `ok`
/// accepts: a layout libfreenect2 does not document (e.g. colour that is
/// still JPEG) is an error of the device `serial`.
pub(crate) fn check_layout(
    serial: &str,
    view: &FrameView<'_>,
    width: usize,
    height: usize,
    what: &str,
    ok: impl Fn(FrameFormat) -> bool,
) -> Result<(), Kinect2Error> {
    if view.width() == width
        && view.height() == height
        && view.bytes_per_pixel() == 4
        && ok(view.format())
    {
        return Ok(());
    }
    Err(Kinect2Error::UnexpectedFrame {
        serial: serial.to_string(),
        what: format!(
            "{what} frame of {} x {} x {} bytes in format {:?}, expected {width} x {height} x 4 \
             (is libfreenect2's colour decoding built in?)",
            view.width(),
            view.height(),
            view.bytes_per_pixel(),
            view.format()
        ),
    })
}

/// Depth (float mm) that libfreenect2's registration handles safely: NaN,
/// +infinity and positive values below 1 mm (far below the sensor's range)
/// would reach an unchecked float-to-int conversion, so they count as no
/// reading (0). Borrowed unchanged when every value is fine.
pub(crate) fn sanitized_depth<'a>(
    depth: &FrameView<'a>,
    scratch: &'a mut Vec<u8>,
) -> Result<FrameView<'a>, Kinect2Error> {
    let unsafe_value = |z: f32| z.is_nan() || z == f32::INFINITY || (z > 0.0 && z < 1.0);
    let data = depth.data();
    if !data
        .chunks_exact(4)
        .any(|b| unsafe_value(f32::from_ne_bytes([b[0], b[1], b[2], b[3]])))
    {
        return Ok(*depth);
    }
    scratch.clear();
    scratch.extend(data.chunks_exact(4).flat_map(|b| {
        let z = f32::from_ne_bytes([b[0], b[1], b[2], b[3]]);
        if unsafe_value(z) { 0.0f32 } else { z }.to_ne_bytes()
    }));
    FrameView::from_bytes(
        depth.width(),
        depth.height(),
        depth.bytes_per_pixel(),
        depth.format(),
        scratch,
    )
    .map(|view| view.with_metadata(depth.metadata()))
    .ok_or_else(|| Kinect2Error::BadImageSize {
        expected: "a depth frame of 4-byte pixels".to_string(),
        got: format!("{} bytes", data.len()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinect2::{COLOR_HEIGHT, COLOR_WIDTH};

    #[test]
    fn unsafe_depth_values_become_no_reading() {
        let values = [1500.0f32, f32::NAN, f32::INFINITY, 0.25, -3.0, 0.0, 1.0];
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_ne_bytes()).collect();
        let view =
            FrameView::from_bytes(values.len(), 1, 4, FrameFormat::Float, &bytes).expect("view");
        let mut scratch = Vec::new();
        let clean = sanitized_depth(&view, &mut scratch).expect("sanitised");
        let got: Vec<f32> = clean
            .data()
            .chunks_exact(4)
            .map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        assert_eq!(got, vec![1500.0, 0.0, 0.0, 0.0, -3.0, 0.0, 1.0]);
        // Clean depth is passed through without a copy.
        let fine: Vec<u8> = [800.0f32, 0.0]
            .iter()
            .flat_map(|v| v.to_ne_bytes())
            .collect();
        let view = FrameView::from_bytes(2, 1, 4, FrameFormat::Float, &fine).expect("view");
        let mut scratch = Vec::new();
        let same = sanitized_depth(&view, &mut scratch).expect("unchanged");
        assert_eq!(same.data().as_ptr(), fine.as_ptr());
        assert!(scratch.is_empty());
    }

    /// Every documented format survives its code, and an undocumented code
    /// is kept as it came.
    #[test]
    fn formats_and_their_codes_correspond() {
        for format in [
            FrameFormat::Invalid,
            FrameFormat::Raw,
            FrameFormat::Float,
            FrameFormat::Bgrx,
            FrameFormat::Rgbx,
            FrameFormat::Gray,
        ] {
            assert_eq!(FrameFormat::from_code(format.code()), format);
        }
        assert_eq!(FrameFormat::from_code(3), FrameFormat::Unknown(3));
        assert_eq!(FrameFormat::Unknown(3).code(), 3);
    }

    /// A view holds exactly `width * height * bytes_per_pixel` bytes; the
    /// registration's checks name what they expected and what came.
    #[test]
    fn misshapen_frames_and_buffers_are_refused() {
        let small = vec![0u8; 4 * 10 * 10];
        assert!(FrameView::from_bytes(10, 10, 4, FrameFormat::Float, &small[1..]).is_none());
        assert!(FrameView::from_bytes(usize::MAX, 2, 4, FrameFormat::Float, &small).is_none());
        let view = FrameView::from_bytes(10, 10, 4, FrameFormat::Float, &small).expect("view");
        match check_view(&view, DEPTH_WIDTH, DEPTH_HEIGHT, "depth") {
            Err(Kinect2Error::BadImageSize { expected, got }) => {
                assert_eq!(expected, "a 512 x 424 x 4 depth frame");
                assert_eq!(got, "10 x 10 x 4");
            }
            other => panic!("expected BadImageSize, got {other:?}"),
        }
        check_len(DEPTH_PIXELS, "undistorted depth").expect("a whole image");
        match check_len(DEPTH_PIXELS - 1, "undistorted depth") {
            Err(Kinect2Error::BadImageSize { got, .. }) => {
                assert_eq!(got, format!("{} pixels", DEPTH_PIXELS - 1));
            }
            other => panic!("expected BadImageSize, got {other:?}"),
        }
    }

    /// Colour that is still JPEG (libfreenect2 without its decoder) is an
    /// error naming the device, the image and its layout.
    #[test]
    fn an_undocumented_layout_is_an_error_of_the_device() {
        let jpeg = vec![0u8; 3 * 4];
        let view = FrameView::from_bytes(4, 1, 3, FrameFormat::Raw, &jpeg).expect("view");
        let colour_ok = |f| f == FrameFormat::Bgrx || f == FrameFormat::Rgbx;
        match check_layout(
            "011054343347",
            &view,
            COLOR_WIDTH,
            COLOR_HEIGHT,
            "colour",
            colour_ok,
        ) {
            Err(err @ Kinect2Error::UnexpectedFrame { .. }) => {
                let message = err.to_string();
                assert!(
                    message.starts_with("Kinect v2 011054343347: colour frame of 4 x 1 x 3")
                        && message.contains("Raw")
                        && message.contains("expected 1920 x 1080 x 4"),
                    "{message}"
                );
            }
            other => panic!("expected UnexpectedFrame, got {other:?}"),
        }
        let bgrx = vec![0u8; COLOR_WIDTH * COLOR_HEIGHT * 4];
        let view = FrameView::from_bytes(COLOR_WIDTH, COLOR_HEIGHT, 4, FrameFormat::Bgrx, &bgrx)
            .expect("view");
        check_layout("1", &view, COLOR_WIDTH, COLOR_HEIGHT, "colour", colour_ok)
            .expect("a documented layout");
    }
}
