//! Depth image to organised point cloud, with the recording format's pinhole
//! model (pixel centres at integer coordinates):
//! `z = raw * unit_m`, `x = (u - cx) * z / fx`, `y = (v - cy) * z / fy`.
//!
//! [`Projector`] precomputes the per-column `(u - cx) / fx`, the per-row
//! `(v - cy) / fy` and `z` for every one of the 65536 depth counts (NaN for
//! 0, no reading), so projecting a pixel is a table look-up and two
//! multiplications, with no branch: NaN times a ray is NaN, so a pixel
//! without depth comes out as [`CloudPoint::INVALID`] by itself. A whole
//! Kinect v2 frame then takes about as long as writing its 3.5 MB
//! (`cargo bench -p slope-sensor --bench projection`).
//!
//! It is used for the zero-copy write into shared memory
//! ([`Projector::project_into`] on the loaned sample's uninitialised slice)
//! and offline (the same function on a `Vec`, or [`Projector::point`], one
//! pixel at a time).

use core::fmt;
use core::mem::MaybeUninit;

use slope_ipc_types::{CloudPoint, Intrinsics};

/// Number of raw depth counts: a `u16` indexes the z table without a check.
const DEPTH_COUNTS: usize = 1 << 16;

/// Where [`Projector::project_into`] puts a point: an initialised cloud, or
/// a loaned shared-memory sample that is not initialised yet.
pub trait PointSlot {
    fn set(&mut self, point: CloudPoint);
}

impl PointSlot for CloudPoint {
    #[inline]
    fn set(&mut self, point: CloudPoint) {
        *self = point;
    }
}

impl PointSlot for MaybeUninit<CloudPoint> {
    #[inline]
    fn set(&mut self, point: CloudPoint) {
        self.write(point);
    }
}

/// Projects the depth images of one camera (size, intrinsics, depth unit).
#[derive(Clone)]
pub struct Projector {
    width: u32,
    height: u32,
    intrinsics: Intrinsics,
    unit_m: f64,
    /// `(u - cx) / fx` for each column `u`.
    ray_x: Vec<f32>,
    /// `(v - cy) / fy` for each row `v`.
    ray_y: Vec<f32>,
    /// `z` in metres for each raw depth count, NaN for 0 (no reading).
    depth_m: Box<[f32; DEPTH_COUNTS]>,
}

/// The tables follow from the other fields (and hold NaN), so neither
/// equality nor `Debug` looks at them.
impl PartialEq for Projector {
    fn eq(&self, other: &Self) -> bool {
        (self.width, self.height, self.intrinsics, self.unit_m)
            == (other.width, other.height, other.intrinsics, other.unit_m)
    }
}

impl fmt::Debug for Projector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Projector")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("intrinsics", &self.intrinsics)
            .field("unit_m", &self.unit_m)
            .finish_non_exhaustive()
    }
}

impl Projector {
    /// A projector for `width` x `height` images with `unit_m` metres per
    /// depth count. `fx` and `fy` must be non-zero (recordings guarantee
    /// it); otherwise every point comes out non-finite.
    pub fn new(width: u32, height: u32, intrinsics: Intrinsics, unit_m: f64) -> Self {
        let ray_x = (0..width)
            .map(|u| ((f64::from(u) - intrinsics.cx) / intrinsics.fx) as f32)
            .collect();
        let ray_y = (0..height)
            .map(|v| ((f64::from(v) - intrinsics.cy) / intrinsics.fy) as f32)
            .collect();
        // z in f64 then rounded once, so that e.g. 1000 * 0.001 is exactly 1.0.
        let depth_m: Vec<f32> = (0..=u16::MAX)
            .map(|raw| match raw {
                0 => f32::NAN,
                _ => (f64::from(raw) * unit_m) as f32,
            })
            .collect();
        let depth_m = depth_m
            .into_boxed_slice()
            .try_into()
            .expect("0..=u16::MAX has DEPTH_COUNTS values");
        Self {
            width,
            height,
            intrinsics,
            unit_m,
            ray_x,
            ray_y,
            depth_m,
        }
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    pub fn intrinsics(&self) -> Intrinsics {
        self.intrinsics
    }

    /// Metres per depth count.
    pub fn unit_m(&self) -> f64 {
        self.unit_m
    }

    /// Pixels per image, `width * height`.
    pub fn len(&self) -> usize {
        self.ray_x.len() * self.ray_y.len()
    }

    /// True for a 0 x N or N x 0 image.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The point of row-major pixel `index` with raw depth count `depth_raw` (0 = no reading -> CloudPoint::INVALID).
    ///
    /// `rgb` is packed as by [`CloudPoint::pack_rgb`]. An `index` outside
    /// the image also gives [`CloudPoint::INVALID`].
    #[inline]
    pub fn point(&self, index: usize, depth_raw: u16, rgb: u32) -> CloudPoint {
        let width = self.ray_x.len();
        if depth_raw == 0 || width == 0 {
            return CloudPoint::INVALID;
        }
        match (self.ray_x.get(index % width), self.ray_y.get(index / width)) {
            (Some(&ray_x), Some(&ray_y)) => self.project(ray_x, ray_y, depth_raw, rgb),
            _ => CloudPoint::INVALID,
        }
    }

    /// Projects a whole image into `out` (len = width*height), colour optional.
    ///
    /// `depth` (and `color`, when given) hold `width * height` row-major
    /// pixels; `color` is packed into [`CloudPoint::rgb`]. Should a length be
    /// wrong, nothing panics: a warning is logged, pixels without depth (and
    /// `out` beyond `width * height`) become [`CloudPoint::INVALID`], and
    /// pixels without colour get `rgb = 0`.
    ///
    /// Every element of `out` is set, whatever the lengths: `out` may be a
    /// loaned sample's uninitialised slice, which is then initialised.
    pub fn project_into<S: PointSlot>(
        &self,
        depth: &[u16],
        color: Option<&[[u8; 3]]>,
        out: &mut [S],
    ) {
        let n = self.len();
        let sizes_match = depth.len() == n && out.len() == n && color.is_none_or(|c| c.len() == n);
        if !sizes_match || n == 0 {
            if !sizes_match {
                tracing::warn!(
                    expected = n,
                    depth = depth.len(),
                    color = color.map(<[_]>::len),
                    out = out.len(),
                    "projecting buffers of the wrong length"
                );
            }
            for (index, point) in out.iter_mut().enumerate() {
                let rgb = color
                    .and_then(|c| c.get(index))
                    .map_or(0, |&[r, g, b]| CloudPoint::pack_rgb(r, g, b));
                point.set(match depth.get(index) {
                    Some(&raw) if index < n => self.point(index, raw, rgb),
                    _ => CloudPoint::INVALID,
                });
            }
            return;
        }

        let width = self.ray_x.len();
        match color {
            Some(color) => {
                for ((out_row, (depth_row, color_row)), &ray_y) in out
                    .chunks_exact_mut(width)
                    .zip(depth.chunks_exact(width).zip(color.chunks_exact(width)))
                    .zip(&self.ray_y)
                {
                    for (((point, &raw), &[r, g, b]), &ray_x) in out_row
                        .iter_mut()
                        .zip(depth_row)
                        .zip(color_row)
                        .zip(&self.ray_x)
                    {
                        point.set(self.project(ray_x, ray_y, raw, CloudPoint::pack_rgb(r, g, b)));
                    }
                }
            }
            None => {
                for ((out_row, depth_row), &ray_y) in out
                    .chunks_exact_mut(width)
                    .zip(depth.chunks_exact(width))
                    .zip(&self.ray_y)
                {
                    for ((point, &raw), &ray_x) in
                        out_row.iter_mut().zip(depth_row).zip(&self.ray_x)
                    {
                        point.set(self.project(ray_x, ray_y, raw, 0));
                    }
                }
            }
        }
    }

    /// Branch-free (a select for `rgb`), so whole rows vectorise; a pixel
    /// without depth gets NaN coordinates from the table and `rgb = 0`.
    #[inline]
    fn project(&self, ray_x: f32, ray_y: f32, depth_raw: u16, rgb: u32) -> CloudPoint {
        let z_m = self.depth_m[usize::from(depth_raw)];
        CloudPoint {
            x_m: ray_x * z_m,
            y_m: ray_y * z_m,
            z_m,
            rgb: if depth_raw == 0 { 0 } else { rgb },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The formula of the recording spec, in f64, pixel by pixel.
    fn oracle(intr: Intrinsics, unit_m: f64, u: u32, v: u32, raw: u16) -> Option<[f64; 3]> {
        (raw != 0).then(|| {
            let z = f64::from(raw) * unit_m;
            [
                (f64::from(u) - intr.cx) * z / intr.fx,
                (f64::from(v) - intr.cy) * z / intr.fy,
                z,
            ]
        })
    }

    /// f32 results may differ from the f64 formula by the rounding of the
    /// ray, of z and of their product: at most 1.5 f32 epsilons, relative.
    fn assert_close(found: f32, expected: f64, ulps: f64, what: &str) {
        let tolerance = ulps * f64::from(f32::EPSILON) * expected.abs() + 1e-30;
        assert!(
            (f64::from(found) - expected).abs() <= tolerance,
            "{what}: {found} vs {expected}"
        );
    }

    fn test_depth(width: u32, height: u32) -> Vec<u16> {
        (0..width * height)
            .map(|i| match i % 11 {
                0 => 0,
                1 => 1,
                2 => u16::MAX,
                _ => (i * 7919 % 9000) as u16 + 300,
            })
            .collect()
    }

    fn test_color(width: u32, height: u32) -> Vec<[u8; 3]> {
        (0..width * height)
            .map(|i| [(i * 3) as u8, (i * 5 + 1) as u8, (255 - i) as u8])
            .collect()
    }

    #[test]
    fn every_pixel_matches_the_formula() {
        let (width, height) = (13, 9);
        let cases = [
            (
                Intrinsics {
                    fx: 365.32,
                    fy: 363.1,
                    cx: 5.69,
                    cy: 3.55,
                },
                0.001,
            ),
            (
                Intrinsics {
                    fx: 525.0,
                    fy: 525.0,
                    cx: 6.0,
                    cy: 4.0,
                },
                0.0002,
            ),
        ];
        let depth = test_depth(width, height);
        let color = test_color(width, height);
        for (intr, unit_m) in cases {
            let projector = Projector::new(width, height, intr, unit_m);
            assert_eq!(projector.len(), (width * height) as usize);
            let mut with_color = vec![CloudPoint::default(); projector.len()];
            let mut without_color = with_color.clone();
            projector.project_into(&depth, Some(&color), &mut with_color);
            projector.project_into(&depth, None, &mut without_color);
            let mut valid = 0;
            for v in 0..height {
                for u in 0..width {
                    let i = (v * width + u) as usize;
                    let [r, g, b] = color[i];
                    let rgb = CloudPoint::pack_rgb(r, g, b);
                    let single = projector.point(i, depth[i], rgb);
                    let p = with_color[i];
                    let q = without_color[i];
                    match oracle(intr, unit_m, u, v, depth[i]) {
                        None => {
                            for point in [single, p, q] {
                                assert!(!point.is_valid());
                                assert!(point.x_m.is_nan() && point.y_m.is_nan());
                                assert_eq!(point.rgb, 0);
                            }
                        }
                        Some([x, y, z]) => {
                            valid += 1;
                            assert_close(p.z_m, z, 0.5, "z");
                            assert_close(p.x_m, x, 2.0, "x");
                            assert_close(p.y_m, y, 2.0, "y");
                            assert_eq!(p.rgb, rgb);
                            assert_eq!(single, p, "point() and project_into() at {u},{v}");
                            assert_eq!(q.xyz(), p.xyz());
                            assert_eq!(q.rgb, 0);
                        }
                    }
                }
            }
            assert!(valid > 80, "{valid}");
        }
    }

    /// `CloudPublisher::publish` relies on this: every slot of an
    /// uninitialised sample is set, with what a `Vec` would get.
    #[test]
    fn uninitialised_slots_are_all_set_like_a_vec() {
        let (width, height) = (13, 9);
        let intr = Intrinsics {
            fx: 365.32,
            fy: 363.1,
            cx: 5.69,
            cy: 3.55,
        };
        let p = Projector::new(width, height, intr, 0.001);
        let depth = test_depth(width, height);
        let color = test_color(width, height);
        let n = p.len();
        for (depth, color, out_len) in [
            (&depth[..], Some(&color[..]), n),
            (&depth[..], None, n),
            (&depth[..n - 5], Some(&color[..]), n + 3),
            (&depth[..], Some(&color[..n - 1]), n - 2),
        ] {
            let mut cloud = vec![CloudPoint::default(); out_len];
            p.project_into(depth, color, &mut cloud);
            let mut slots = vec![MaybeUninit::<CloudPoint>::uninit(); out_len];
            p.project_into(depth, color, &mut slots);
            for (i, (slot, expected)) in slots.iter().zip(&cloud).enumerate() {
                // SAFETY: project_into sets every slot (what this test checks;
                // Miri would flag an unset one).
                let point = unsafe { slot.assume_init() };
                assert_eq!(point.rgb, expected.rgb, "{i}");
                assert_eq!(
                    point.xyz().map(f32::to_bits),
                    expected.xyz().map(f32::to_bits),
                    "{i}"
                );
            }
        }
    }

    #[test]
    fn pixel_centres_sit_at_integer_coordinates() {
        let intr = Intrinsics {
            fx: 500.0,
            fy: 400.0,
            cx: 2.0,
            cy: 1.0,
        };
        let p = Projector::new(5, 3, intr, 0.001);
        // Pixel (2, 1) is the principal point: on the optical axis.
        let centre = p.point(5 + 2, 2000, 0);
        assert_eq!(centre.xyz(), [0.0, 0.0, 2.0]);
        // Pixel (0, 0): two columns left and one row up of it.
        let corner = p.point(0, 2000, 0);
        assert_eq!(corner.xyz(), [-2.0 * 2.0 / 500.0, -2.0 / 400.0, 2.0]);
        // Pixel (4, 2): last column and row.
        let last = p.point(14, 1000, 0);
        assert_eq!(last.xyz(), [2.0 / 500.0, 1.0 / 400.0, 1.0]);
    }

    #[test]
    fn kinect_half_pixel_shift_reproduces_libfreenect2() {
        // libfreenect2: x = (c + 0.5 - cx_f2) * z / fx; recordings store cx_f2 - 0.5.
        let (cx_f2, cy_f2, f) = (256.3, 207.9, 365.0);
        let intr = Intrinsics {
            fx: f,
            fy: f,
            cx: cx_f2 - 0.5,
            cy: cy_f2 - 0.5,
        };
        let p = Projector::new(512, 424, intr, 0.001);
        for (c, r) in [(0u32, 0u32), (100, 300), (511, 423)] {
            let point = p.point((r * 512 + c) as usize, 1500, 0);
            assert_close(point.x_m, (f64::from(c) + 0.5 - cx_f2) * 1.5 / f, 2.0, "x");
            assert_close(point.y_m, (f64::from(r) + 0.5 - cy_f2) * 1.5 / f, 2.0, "y");
        }
    }

    #[test]
    fn indices_outside_the_image_are_invalid() {
        let p = Projector::new(
            4,
            3,
            Intrinsics {
                fx: 1.0,
                fy: 1.0,
                cx: 0.0,
                cy: 0.0,
            },
            1.0,
        );
        assert!(p.point(11, 5, 0).is_valid());
        assert!(!p.point(12, 5, 0).is_valid());
        assert!(!p.point(usize::MAX, 5, 0).is_valid());
        let empty = Projector::new(0, 3, Intrinsics::default(), 1.0);
        assert!(empty.is_empty());
        assert!(!empty.point(0, 5, 0).is_valid());
    }

    #[test]
    fn wrong_lengths_degrade_without_panicking() {
        let intr = Intrinsics {
            fx: 2.0,
            fy: 2.0,
            cx: 1.0,
            cy: 1.0,
        };
        let p = Projector::new(3, 2, intr, 1.0);
        let depth = [1u16, 2, 3, 4];
        let color = [[1u8, 2, 3]; 2];
        let mut out = vec![
            CloudPoint {
                x_m: 9.0,
                y_m: 9.0,
                z_m: 9.0,
                rgb: 9
            };
            8
        ];
        p.project_into(&depth, Some(&color), &mut out);
        for (i, point) in out.iter().enumerate() {
            if i < depth.len() {
                let (u, v) = (i as u32 % 3, i as u32 / 3);
                let [x, y, z] = oracle(intr, 1.0, u, v, depth[i]).unwrap();
                assert_eq!(point.xyz(), [x as f32, y as f32, z as f32]);
                let rgb = if i < 2 {
                    CloudPoint::pack_rgb(1, 2, 3)
                } else {
                    0
                };
                assert_eq!(point.rgb, rgb);
            } else {
                assert!(!point.is_valid() && point.rgb == 0, "{i}: {point:?}");
            }
        }
        // A short `out` gets only its own pixels.
        let mut short = vec![CloudPoint::default(); 2];
        p.project_into(&[5; 6], None, &mut short);
        assert_eq!(short[1].xyz(), [0.0, -2.5, 5.0]);
    }
}
