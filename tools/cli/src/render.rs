//! Picture basics shared by the overlays: the depth image in grey, the
//! colours of the ground (red) and inclined plane (blue), after the paper's
//! figures, and the palette of the surface roles; [`write_png`] is the only
//! I/O.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::Context;
use slope_ipc_types::{CloudPoint, SurfaceRole};
use slope_sensor::recording::ColorImage;

/// Colour of the ground plane.
pub const GROUND_TINT: [u8; 3] = [255, 0, 0];
/// Colour of the inclined plane.
pub const INCLINED_TINT: [u8; 3] = [0, 0, 255];
/// Colour of each surface role in the overlay, in [`SurfaceRole::ALL`]'s
/// order: ground red, step orange, ramp blue, wall brown, elevated teal,
/// overhang violet (each dark enough for white text on it).
pub const ROLE_COLOURS: [[u8; 3]; 6] = [
    [220, 40, 40],
    [225, 130, 0],
    [30, 80, 255],
    [140, 75, 30],
    [0, 145, 135],
    [110, 60, 170],
];
/// Colour of a segmented plane that no surface holds (the frame had no
/// ground, so no roles).
pub const UNCLASSIFIED: [u8; 3] = [150, 150, 150];
/// Colour of the road's outline.
pub const ROAD_OUTLINE: [u8; 3] = [255, 0, 255];
/// Colour of the corridor's edges on the ground.
pub const CORRIDOR_LINE: [u8; 3] = [0, 255, 255];

/// The overlay colour of `role`.
pub fn role_colour(role: SurfaceRole) -> [u8; 3] {
    ROLE_COLOURS[role as usize]
}

/// Grey of the nearest depth reading (the farthest is [`FAR_GREY`]).
pub const NEAR_GREY: u8 = 235;
/// Grey of the farthest depth reading.
pub const FAR_GREY: u8 = 60;
/// The grey scale spans these quantiles of the depths, so that a few far
/// outliers do not wash the picture out.
const GREY_QUANTILES: (f64, f64) = (0.02, 0.98);

/// The depth of each of the `width * height` points as grey (near bright,
/// far dark, no reading black), row-major.
pub fn grey_levels(points: &[CloudPoint], width: u32, height: u32) -> Vec<[u8; 3]> {
    let n = width as usize * height as usize;
    let mut out = vec![[0u8; 3]; n];
    let Some((near_m, far_m)) = depth_range(points) else {
        return out;
    };
    let span_m = (far_m - near_m).max(1e-6);
    for (pixel, point) in out.iter_mut().zip(points) {
        if point.is_valid() {
            let t = ((point.z_m - near_m) / span_m).clamp(0.0, 1.0);
            let grey = f32::from(NEAR_GREY) + t * (f32::from(FAR_GREY) - f32::from(NEAR_GREY));
            *pixel = [to_u8(grey); 3];
        }
    }
    out
}

/// Writes `image` as an 8-bit RGB PNG.
pub fn write_png(path: &Path, image: &ColorImage) -> anyhow::Result<()> {
    let file = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), image.width, image.height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder
        .write_header()
        .with_context(|| format!("cannot write {}", path.display()))?;
    let bytes: Vec<u8> = image.data.iter().flatten().copied().collect();
    writer
        .write_image_data(&bytes)
        .with_context(|| format!("cannot write {}", path.display()))?;
    writer
        .finish()
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// The depths at the grey-scale quantiles; `None` without any reading.
fn depth_range(points: &[CloudPoint]) -> Option<(f32, f32)> {
    let mut depths: Vec<f32> = points
        .iter()
        .filter(|p| p.is_valid())
        .map(|p| p.z_m)
        .collect();
    if depths.is_empty() {
        return None;
    }
    let last = depths.len() - 1;
    let at = |q: f64| ((last as f64) * q).round() as usize;
    let (lo, hi) = (at(GREY_QUANTILES.0), at(GREY_QUANTILES.1));
    let near = *depths.select_nth_unstable_by(lo, f32::total_cmp).1;
    let far = *depths.select_nth_unstable_by(hi, f32::total_cmp).1;
    Some((near, far))
}

fn to_u8(value: f32) -> u8 {
    // Clamped to 0..=255 first, so the cast neither wraps nor saturates.
    value.round().clamp(0.0, 255.0) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(z: f32) -> CloudPoint {
        CloudPoint {
            x_m: 0.0,
            y_m: 0.0,
            z_m: z,
            rgb: 0,
        }
    }

    #[test]
    fn depth_is_grey_near_bright_far_dark_missing_black() {
        let points = [point(1.0), point(2.0), CloudPoint::INVALID, point(3.0)];
        let grey = grey_levels(&points, 2, 2);
        assert_eq!(grey[0], [NEAR_GREY; 3]);
        assert_eq!(grey[3], [FAR_GREY; 3]);
        assert_eq!(grey[2], [0; 3]);
        let mid = grey[1][0];
        assert!(mid < NEAR_GREY && mid > FAR_GREY, "{mid}");
        assert!(grey[1].iter().all(|&c| c == mid));
        // No readings, or a short cloud: black, never a panic.
        assert_eq!(
            grey_levels(&[CloudPoint::INVALID; 4], 2, 2),
            vec![[0; 3]; 4]
        );
        assert_eq!(grey_levels(&points[..1], 2, 1)[1], [0; 3]);
    }

    #[test]
    fn a_png_is_written_and_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.png");
        let image = ColorImage {
            width: 2,
            height: 1,
            data: vec![[1, 2, 3], [250, 128, 0]],
        };
        write_png(&path, &image).unwrap();
        let decoder = png::Decoder::new(std::io::BufReader::new(File::open(&path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (2, 1));
        assert_eq!(&buf[..6], &[1, 2, 3, 250, 128, 0]);
        assert!(write_png(&dir.path().join("no/such/dir.png"), &image).is_err());
    }
}
