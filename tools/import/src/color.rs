//! The registered colour stream: `rgb8`/`bgr8` (`rgba8`/`bgra8`) images of
//! the depth image's size, matched to depth images by header stamp.
//! Colour images wait here (the last [`MAX_WAITING`]) for their depth
//! image, and a depth image waits for its colour at most
//! [`MAX_DEPTH_WAIT`] depth images (then it is written without).

use std::collections::VecDeque;

use slope_sensor::recording::ColorImage;
use slope_tools::ros2_messages::Image;

/// Colour images kept waiting for the depth image of their stamp.
pub const MAX_WAITING: usize = 30;
/// Depth images that may come after one before it is written without
/// colour.
pub const MAX_DEPTH_WAIT: usize = 3;

/// A colour image as RGB pixels, or why it is none.
pub fn image_to_color(image: &Image) -> Result<ColorImage, String> {
    let (channels, bgr) = match image.encoding.as_str() {
        "rgb8" => (3, false),
        "bgr8" => (3, true),
        "rgba8" => (4, false),
        "bgra8" => (4, true),
        other => {
            return Err(format!(
                "unsupported colour encoding '{other}' (rgb8, bgr8, rgba8, bgra8)"
            ))
        }
    };
    let (width, height) = (image.width as usize, image.height as usize);
    let row = width * channels;
    let step = image.step as usize;
    if width == 0 || height == 0 || step < row || image.data.len() < step * (height - 1) + row {
        return Err(format!(
            "a {}x{} {} image with step {} cannot hold {} bytes of data",
            width,
            height,
            image.encoding,
            step,
            image.data.len()
        ));
    }
    let mut data = Vec::with_capacity(width * height);
    for v in 0..height {
        let line = &image.data[v * step..v * step + row];
        data.extend(line.chunks_exact(channels).map(|p| {
            if bgr {
                [p[2], p[1], p[0]]
            } else {
                [p[0], p[1], p[2]]
            }
        }));
    }
    Ok(ColorImage {
        width: image.width,
        height: image.height,
        data,
    })
}

/// Colour images not yet matched to a depth image, by stamp.
#[derive(Debug, Default)]
pub struct WaitingColors {
    images: VecDeque<(u64, ColorImage)>,
}

impl WaitingColors {
    /// Keeps `color` (stamped `stamp_ns`) for its depth image.
    pub fn push(&mut self, stamp_ns: u64, color: ColorImage) {
        if self.images.len() == MAX_WAITING {
            self.images.pop_front();
        }
        self.images.push_back((stamp_ns, color));
    }

    /// The colour image stamped `stamp_ns`, if one waits.
    pub fn take(&mut self, stamp_ns: u64) -> Option<ColorImage> {
        let at = self.images.iter().position(|(s, _)| *s == stamp_ns)?;
        self.images.remove(at).map(|(_, c)| c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use slope_tools::ros2_messages::Header;

    #[test]
    fn bgr_becomes_rgb_and_padding_goes() {
        let image = Image {
            header: Header::default(),
            height: 1,
            width: 2,
            encoding: "bgr8".to_string(),
            is_bigendian: 0,
            step: 8,
            data: vec![1, 2, 3, 4, 5, 6, 0, 0],
        };
        assert_eq!(image_to_color(&image).unwrap().data, [[3, 2, 1], [6, 5, 4]]);
        let mono = Image {
            encoding: "mono8".to_string(),
            ..image
        };
        assert!(image_to_color(&mono).unwrap_err().contains("'mono8'"));
    }

    #[test]
    fn a_waiting_colour_is_found_by_its_stamp_and_the_oldest_goes_first() {
        let mut waiting = WaitingColors::default();
        for stamp in 0..=MAX_WAITING as u64 {
            waiting.push(stamp, ColorImage::new(1, 1));
        }
        assert!(waiting.take(0).is_none(), "the oldest was dropped");
        assert!(waiting.take(5).is_some());
        assert!(waiting.take(5).is_none());
    }
}
