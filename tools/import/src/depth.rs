//! Depth images of a bag as a recording's millimetre counts: `16UC1` (and
//! `mono16`) as they are, `32FC1` metres rounded to the millimetre (NaN,
//! 0 and depth beyond 65.535 m: no reading), and `compressedDepth`.
//!
//! `compressedDepth` (ROS's `compressed_depth_image_transport`) is a
//! 12-byte `ConfigHeader` (`int32 format`: 0 inverse depth, 1 PNG, 2 RVL;
//! `float32 depthParam[2]`, the quantisation of 32FC1 images) followed by
//! a PNG: the 16-bit millimetres themselves for a `16UC1` image, the
//! quantised inverse depth `q = depthParam[0] / (depth_m - depthParam[1])`
//! for a `32FC1` one (see `compressed_depth_image_transport/src/codec.cpp`
//! and `compression_common.h` in ros-perception/image_transport_plugins).
//! The PNG is decoded with the `png` crate; RVL is refused by name.

use slope_sensor::recording::{metres_to_count, DepthImage};
use slope_tools::ros2_messages::{CompressedImage, Image};

/// Metres per count of an imported recording.
pub const UNIT_M: f64 = 0.001;

/// Why a depth image cannot be imported.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum DepthError {
    #[error("unsupported depth encoding '{0}' (supported: 16UC1, mono16, 32FC1, and compressedDepth PNG)")]
    Encoding(String),
    #[error("the image is empty ({width} x {height})")]
    Empty { width: u32, height: u32 },
    #[error("the image's data holds {got} bytes, {width} x {height} {encoding} with step {step} needs {needed}")]
    Size {
        width: u32,
        height: u32,
        encoding: String,
        step: u32,
        got: usize,
        needed: usize,
    },
    #[error("compressedDepth: {0}")]
    Compressed(String),
}

/// The bytes per pixel of a depth encoding, or why it is not one.
fn bytes_per_pixel(encoding: &str) -> Result<usize, DepthError> {
    match encoding {
        "16UC1" | "mono16" => Ok(2),
        "32FC1" => Ok(4),
        other => Err(DepthError::Encoding(other.to_string())),
    }
}

/// The depth of an uncompressed `Image`, into `out`.
pub fn image_to_depth(image: &Image, out: &mut DepthImage) -> Result<(), DepthError> {
    let bpp = bytes_per_pixel(&image.encoding)?;
    let (width, height) = (image.width, image.height);
    if width == 0 || height == 0 {
        return Err(DepthError::Empty { width, height });
    }
    let row = width as usize * bpp;
    let step = image.step as usize;
    let needed = step.max(row) * (height as usize - 1) + row;
    if step < row || image.data.len() < needed {
        return Err(DepthError::Size {
            width,
            height,
            encoding: image.encoding.clone(),
            step: image.step,
            got: image.data.len(),
            needed,
        });
    }
    out.width = width;
    out.height = height;
    out.data.clear();
    out.data.reserve(width as usize * height as usize);
    let big = image.is_bigendian != 0;
    for v in 0..height as usize {
        let line = &image.data[v * step..v * step + row];
        if bpp == 2 {
            out.data.extend(line.chunks_exact(2).map(|b| {
                let b = [b[0], b[1]];
                if big {
                    u16::from_be_bytes(b)
                } else {
                    u16::from_le_bytes(b)
                }
            }));
        } else {
            out.data.extend(line.chunks_exact(4).map(|b| {
                let b = [b[0], b[1], b[2], b[3]];
                let m = if big {
                    f32::from_be_bytes(b)
                } else {
                    f32::from_le_bytes(b)
                };
                metres_to_count(f64::from(m), UNIT_M)
            }));
        }
    }
    Ok(())
}

/// The `ConfigHeader` of a `compressedDepth` image.
const CONFIG_HEADER_LEN: usize = 12;

/// The depth of a `compressedDepth` `CompressedImage`, into `out`.
pub fn compressed_to_depth(
    image: &CompressedImage,
    out: &mut DepthImage,
) -> Result<(), DepthError> {
    // "16UC1; compressedDepth png" (or without the codec, before Humble).
    let mut parts = image.format.split(';').map(str::trim);
    let encoding = parts.next().unwrap_or_default().to_string();
    let rest: Vec<&str> = parts.collect();
    if !rest.iter().any(|p| p.starts_with("compressedDepth")) {
        return Err(DepthError::Encoding(format!(
            "{} (a CompressedImage that is not compressedDepth: colour, not depth?)",
            image.format
        )));
    }
    if rest.iter().any(|p| p.contains("rvl")) {
        return Err(DepthError::Encoding(format!("{} (RVL)", image.format)));
    }
    let header = image.data.get(..CONFIG_HEADER_LEN).ok_or_else(|| {
        DepthError::Compressed(format!(
            "{} bytes, shorter than its 12-byte header",
            image.data.len()
        ))
    })?;
    let word = |i: usize| [header[i], header[i + 1], header[i + 2], header[i + 3]];
    let format = i32::from_le_bytes(word(0));
    let quant_a = f32::from_le_bytes(word(4));
    let quant_b = f32::from_le_bytes(word(8));
    if format == 2 {
        return Err(DepthError::Encoding(format!("{} (RVL)", image.format)));
    }
    let decoder = png::Decoder::new(std::io::Cursor::new(&image.data[CONFIG_HEADER_LEN..]));
    let mut reader = decoder
        .read_info()
        .map_err(|e| DepthError::Compressed(format!("its PNG does not decode: {e}")))?;
    let info = reader.info();
    let (width, height) = (info.width, info.height);
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Sixteen {
        return Err(DepthError::Compressed(format!(
            "its PNG is {:?} {:?}, not 16-bit grey",
            info.color_type, info.bit_depth
        )));
    }
    let mut buf = vec![0; reader.output_buffer_size().unwrap_or(0)];
    reader
        .next_frame(&mut buf)
        .map_err(|e| DepthError::Compressed(format!("its PNG does not decode: {e}")))?;
    if width == 0 || height == 0 {
        return Err(DepthError::Empty { width, height });
    }
    out.width = width;
    out.height = height;
    out.data.clear();
    // PNG samples are big-endian.
    let samples = buf
        .chunks_exact(2)
        .map(|b| u16::from_be_bytes([b[0], b[1]]));
    match encoding.as_str() {
        "16UC1" | "mono16" => out.data.extend(samples),
        "32FC1" => out.data.extend(samples.map(|q| {
            if q == 0 {
                0
            } else {
                let m = f64::from(quant_a) / f64::from(q) + f64::from(quant_b);
                metres_to_count(m, UNIT_M)
            }
        })),
        other => return Err(DepthError::Encoding(format!("{other} (compressedDepth)"))),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use slope_tools::ros2_messages::Header;

    fn image(encoding: &str, width: u32, height: u32, step: u32, data: Vec<u8>) -> Image {
        Image {
            header: Header::default(),
            height,
            width,
            encoding: encoding.to_string(),
            is_bigendian: 0,
            step,
            data,
        }
    }

    #[test]
    fn metres_become_millimetres_and_nan_no_reading() {
        let values = [1.2345f32, f32::NAN, 0.0, 70.0];
        let data = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let mut out = DepthImage::default();
        image_to_depth(&image("32FC1", 2, 2, 8, data), &mut out).unwrap();
        assert_eq!(out.data, [1235, 0, 0, 0]);
    }

    #[test]
    fn rows_with_padding_are_cut_to_the_width() {
        // 2 x 2 16UC1 with a step of 6: 2 bytes of padding per row.
        let data = vec![1, 0, 2, 0, 9, 9, 3, 0, 4, 0, 9, 9];
        let mut out = DepthImage::default();
        image_to_depth(&image("16UC1", 2, 2, 6, data), &mut out).unwrap();
        assert_eq!(out.data, [1, 2, 3, 4]);
    }

    #[test]
    fn a_wrong_encoding_size_or_empty_image_is_named() {
        let mut out = DepthImage::default();
        let err = image_to_depth(&image("rgb8", 1, 1, 3, vec![0; 3]), &mut out).unwrap_err();
        assert!(err.to_string().contains("'rgb8'"), "{err}");
        let err = image_to_depth(&image("16UC1", 0, 0, 0, vec![]), &mut out).unwrap_err();
        assert_eq!(
            err,
            DepthError::Empty {
                width: 0,
                height: 0
            }
        );
        let err = image_to_depth(&image("16UC1", 4, 2, 8, vec![0; 10]), &mut out).unwrap_err();
        assert!(
            matches!(
                err,
                DepthError::Size {
                    got: 10,
                    needed: 16,
                    ..
                }
            ),
            "{err}"
        );
    }

    /// A compressedDepth image of `mm` (1 row), as the ROS plugin makes it.
    fn compressed(format: &str, header: [u8; 12], samples: &[u16]) -> CompressedImage {
        let mut png_bytes = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut png_bytes, samples.len() as u32, 1);
            encoder.set_color(png::ColorType::Grayscale);
            encoder.set_depth(png::BitDepth::Sixteen);
            let mut writer = encoder.write_header().unwrap();
            let data: Vec<u8> = samples.iter().flat_map(|s| s.to_be_bytes()).collect();
            writer.write_image_data(&data).unwrap();
        }
        let mut data = header.to_vec();
        data.extend(png_bytes);
        CompressedImage {
            header: Header::default(),
            format: format.to_string(),
            data,
        }
    }

    #[test]
    fn compressed_depth_16uc1_is_its_png() {
        let mut header = [0u8; 12];
        header[..4].copy_from_slice(&1i32.to_le_bytes());
        let image = compressed("16UC1; compressedDepth png", header, &[0, 1500, 65535]);
        let mut out = DepthImage::default();
        compressed_to_depth(&image, &mut out).unwrap();
        assert_eq!((out.width, out.height), (3, 1));
        assert_eq!(out.data, [0, 1500, 65535]);
    }

    #[test]
    fn compressed_depth_32fc1_is_its_inverse_depth() {
        // depth = a / q + b: a = 1000, b = 0.5; q = 1000 gives 1.5 m.
        let mut header = [0u8; 12];
        header[..4].copy_from_slice(&0i32.to_le_bytes());
        header[4..8].copy_from_slice(&1000f32.to_le_bytes());
        header[8..].copy_from_slice(&0.5f32.to_le_bytes());
        let image = compressed("32FC1; compressedDepth", header, &[1000, 0, 500]);
        let mut out = DepthImage::default();
        compressed_to_depth(&image, &mut out).unwrap();
        assert_eq!(out.data, [1500, 0, 2500]);
    }

    #[test]
    fn colour_and_rvl_are_refused_by_name() {
        let mut out = DepthImage::default();
        let jpeg = CompressedImage {
            format: "bgr8; jpeg compressed bgr8".to_string(),
            ..CompressedImage::default()
        };
        let err = compressed_to_depth(&jpeg, &mut out).unwrap_err();
        assert!(err.to_string().contains("jpeg"), "{err}");
        let rvl = CompressedImage {
            format: "16UC1; compressedDepth rvl".to_string(),
            ..CompressedImage::default()
        };
        assert!(compressed_to_depth(&rvl, &mut out)
            .unwrap_err()
            .to_string()
            .contains("RVL"));
    }
}
