//! Pictures of what the estimator found: the depth image in grey, with the
//! pixels near the ground plane tinted red and those near the inclined plane
//! tinted blue (the colours of the paper's figures).
//!
//! [`render_planes`] is pure (cloud and planes in, RGB image out);
//! [`write_png`] is the only I/O.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::Context;
use slope_ipc_types::{CloudPoint, Mount};
use slope_sensor::recording::ColorImage;

/// Tint of the pixels on the ground plane.
pub const GROUND_TINT: [u8; 3] = [255, 0, 0];
/// Tint of the pixels on the inclined plane.
pub const INCLINED_TINT: [u8; 3] = [0, 0, 255];
/// Grey of the nearest depth reading (the farthest is [`FAR_GREY`]).
pub const NEAR_GREY: u8 = 235;
/// Grey of the farthest depth reading.
pub const FAR_GREY: u8 = 60;
/// Share of the tint in a tinted pixel (the rest is its grey, so that the
/// shape of the surface stays visible).
const TINT_WEIGHT: f32 = 0.65;
/// The grey scale spans these quantiles of the depths, so that a few far
/// outliers do not wash the picture out.
const GREY_QUANTILES: (f64, f64) = (0.02, 0.98);

/// The planes to tint, `[a, b, c, d]` with `a x + b y + c z + d = 0` and a
/// unit normal `(a, b, c)`, camera frame, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneOverlay {
    pub ground: Option<[f64; 4]>,
    pub inclined: Option<[f64; 4]>,
    /// A pixel whose point lies within this distance of a plane is tinted.
    pub tolerance_m: f64,
}

/// The ground plane the mount implies: up vector `n` (from pitch and roll)
/// and the optical centre `height_m` above the ground, so `n . p + h = 0`.
/// `None` when the pitch or the height is unknown.
pub fn mount_ground_plane(mount: &Mount) -> Option<[f64; 4]> {
    let [a, b, c] = mount.up_vector()?;
    mount
        .height_m
        .is_finite()
        .then_some([a, b, c, mount.height_m])
}

/// Renders an organised cloud of `width * height` points (row-major) as an
/// RGB image: depth in grey (near bright, far dark, no reading black), points
/// within `overlay.tolerance_m` of a plane tinted with its colour (the nearer
/// plane wins where both are close). A cloud of the wrong length gives black
/// pixels where points are missing; it never panics.
pub fn render_planes(
    points: &[CloudPoint],
    width: u32,
    height: u32,
    overlay: &PlaneOverlay,
) -> ColorImage {
    let mut image = ColorImage::new(width, height);
    let Some((near_m, far_m)) = depth_range(points) else {
        return image;
    };
    let span_m = (far_m - near_m).max(1e-6);
    let planes = [
        (overlay.ground, GROUND_TINT),
        (overlay.inclined, INCLINED_TINT),
    ];
    for (pixel, point) in image.data.iter_mut().zip(points) {
        if !point.is_valid() {
            continue;
        }
        let t = ((point.z_m - near_m) / span_m).clamp(0.0, 1.0);
        let grey = f32::from(NEAR_GREY) + t * (f32::from(FAR_GREY) - f32::from(NEAR_GREY));
        let p = [
            f64::from(point.x_m),
            f64::from(point.y_m),
            f64::from(point.z_m),
        ];
        let tint = planes
            .iter()
            .filter_map(|(plane, tint)| {
                let distance = plane_distance_m(&(*plane)?, &p);
                (distance <= overlay.tolerance_m).then_some((distance, *tint))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, tint)| tint);
        *pixel = match tint {
            Some(tint) => tint.map(|c| blend(grey, c)),
            None => [to_u8(grey); 3],
        };
    }
    image
}

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

/// Distance of `p` from the plane, metres (the normal is unit length).
fn plane_distance_m(plane: &[f64; 4], p: &[f64; 3]) -> f64 {
    (plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] + plane[3]).abs()
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

fn blend(grey: f32, tint: u8) -> u8 {
    to_u8((1.0 - TINT_WEIGHT) * grey + TINT_WEIGHT * f32::from(tint))
}

fn to_u8(value: f32) -> u8 {
    // Clamped to 0..=255 first, so the cast neither wraps nor saturates.
    value.round().clamp(0.0, 255.0) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(x: f32, y: f32, z: f32) -> CloudPoint {
        CloudPoint {
            x_m: x,
            y_m: y,
            z_m: z,
            rgb: 0,
        }
    }

    #[test]
    fn planes_are_tinted_and_depth_is_grey() {
        // Ground y = 0.5 (normal -y, towards a camera above it), a wall z = 3.
        let ground = [0.0, -1.0, 0.0, 0.5];
        let wall = [0.0, 0.0, -1.0, 3.0];
        let points = [
            point(0.0, 0.5, 1.0),   // on the ground, nearest
            point(0.0, 0.0, 3.0),   // on the wall, farthest
            point(0.0, 0.0, 2.0),   // on neither
            CloudPoint::INVALID,    // no reading
            point(0.0, 0.52, 3.01), // near both: the wall is nearer (1 cm vs 2 cm)
            point(0.0, 0.0, 1.0),   // on neither, nearest
        ];
        let overlay = PlaneOverlay {
            ground: Some(ground),
            inclined: Some(wall),
            tolerance_m: 0.03,
        };
        let image = render_planes(&points, 3, 2, &overlay);
        assert_eq!((image.width, image.height), (3, 2));
        let [r, g, b] = image.data[0];
        assert!(
            r > 200 && g == b && g < 100,
            "ground pixel {:?}",
            image.data[0]
        );
        let [r, g, b] = image.data[1];
        assert!(
            b > 150 && r == g && r < 50,
            "wall pixel {:?}",
            image.data[1]
        );
        assert_eq!(image.data[3], [0, 0, 0]);
        let [r, g, b] = image.data[4];
        assert!(
            b > 150 && r == g && r < 50,
            "pixel near both {:?}",
            image.data[4]
        );
        // Grey: the nearest untinted pixel is NEAR_GREY, a middle one between.
        assert_eq!(image.data[5], [NEAR_GREY; 3]);
        let mid = image.data[2][0];
        assert!(mid < NEAR_GREY && mid > FAR_GREY, "{mid}");
        assert!(image.data[2].iter().all(|&c| c == mid));
    }

    #[test]
    fn without_planes_or_readings_nothing_is_tinted() {
        let points = [point(0.0, 0.5, 1.0), point(0.0, 0.5, 2.0)];
        let overlay = PlaneOverlay {
            ground: None,
            inclined: None,
            tolerance_m: 0.03,
        };
        let image = render_planes(&points, 2, 1, &overlay);
        assert_eq!(image.data, vec![[NEAR_GREY; 3], [FAR_GREY; 3]]);
        let empty = render_planes(&[CloudPoint::INVALID; 4], 2, 2, &overlay);
        assert_eq!(empty.data, vec![[0; 3]; 4]);
        // A short cloud leaves the missing pixels black.
        let short = render_planes(&points[..1], 2, 1, &overlay);
        assert_eq!(short.data[1], [0; 3]);
    }

    #[test]
    fn mount_plane_holds_the_ground_under_the_camera() {
        let mount = Mount {
            height_m: 0.6,
            pitch_deg: -20.0,
            roll_deg: 0.0,
        };
        let plane = mount_ground_plane(&mount).unwrap();
        // The point 0.6 m straight below the camera, along -up.
        let up = mount.up_vector().unwrap();
        let below = [-0.6 * up[0], -0.6 * up[1], -0.6 * up[2]];
        assert!(plane_distance_m(&plane, &below) < 1e-12);
        // The camera itself is 0.6 m above it.
        assert!((plane_distance_m(&plane, &[0.0; 3]) - 0.6).abs() < 1e-12);
        let unknown_height = Mount {
            height_m: f64::NAN,
            ..mount
        };
        assert_eq!(mount_ground_plane(&unknown_height), None);
        assert_eq!(mount_ground_plane(&Mount::UNKNOWN), None);
    }
}
