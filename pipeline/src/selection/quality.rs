//! How good a segmented plane is as a measurement surface: its flatness at
//! the sensor's noise level, its area on the surface, and how much of it
//! lies along the image border.

use nalgebra::Vector3;

use crate::cloud::CloudView;
use crate::plane_fit::Plane;
use crate::ransac_planes::Threshold;
use crate::sensor_noise::NoiseModel;

/// Pixels this close to the image's edge are "at the border".
pub const BORDER_PX: usize = 8;

/// The smallest `|cos|` of the incidence angle in a pixel's footprint
/// (a plane seen edge-on would otherwise count infinite area).
const MIN_COS_INCIDENCE: f64 = 0.05;

/// Quality figures of one plane, from its inlier pixels.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlaneQuality {
    /// RMS distance of the inliers from the plane, metres.
    pub rms_m: f64,
    /// RMS of each inlier's distance divided by its inlier threshold
    /// (`ransac_planes::Threshold`): about `sigma / threshold` for a flat
    /// surface with depth noise sigma, and 0.58 for a surface that fills the
    /// threshold band evenly (a rough surface cut by the threshold).
    pub relative_rms: f64,
    /// Area the inlier pixels cover on the plane, square metres.
    pub area_m2: f64,
    /// Share of the inlier pixels within [`BORDER_PX`] of the image's edge.
    pub border_fraction: f64,
    /// RMS of each inlier's distance divided by the sensor's noise (one
    /// standard deviation of the [`NoiseModel`] at the point's depth and
    /// incidence): about 1 for a flat surface seen by that sensor, more for
    /// a surface that is not flat at the sensor's noise level.
    pub noise_ratio: f64,
    /// Share of the inlier pixels that are veil points: mixed readings
    /// between a near and a far surface (see [`is_veil_point`]).
    pub veil_fraction: f64,
}

/// The quality of `plane` over its `inliers` (pixel indices of `cloud`).
/// Without a measured inlier (or for a view of width 0): NaN RMS figures,
/// no area, no border share.
pub fn plane_quality(
    cloud: &CloudView<'_>,
    plane: &Plane,
    inliers: &[u32],
    threshold: &Threshold,
    noise: NoiseModel,
) -> PlaneQuality {
    let (w, h) = (cloud.width, cloud.height);
    let focal_area = cloud.intrinsics.fx * cloud.intrinsics.fy;
    let focal_area = if focal_area.is_finite() && focal_area > 0.0 {
        focal_area
    } else {
        cloud.focal_px().powi(2)
    };
    let mut sums = Sums::default();
    if w == 0 {
        // No pixel grid (a malformed view): no inlier has a place in it.
        return sums.quality();
    }
    let stride = inliers.len().div_ceil(QUALITY_SAMPLES).max(1);
    for &pixel in inliers.iter().step_by(stride) {
        let pixel = pixel as usize;
        let Some(p) = cloud.point(pixel) else {
            continue;
        };
        let (u, v) = (pixel % w, pixel / w);
        let at_border = u < BORDER_PX || v < BORDER_PX || u + BORDER_PX >= w || v + BORDER_PX >= h;
        sums.add(plane, &p, threshold.at(&p), at_border, focal_area, noise);
        sums.veil += usize::from(is_veil_point(cloud, pixel, p.z));
    }
    let mut quality = sums.quality();
    // The sampled footprints stand for all inliers.
    quality.area_m2 *= inliers.len() as f64 / sums.count.max(1) as f64;
    quality
}

/// A veil point's local surface is seen at more than this incidence
/// (degrees): the depth jumps to both of its neighbours along a row or a
/// column by more than `tan(VEIL_INCIDENCE_DEG)` pixel footprints. A real
/// floor is seen at 81 degrees 8 m ahead of a camera 1.3 m up, a ramp
/// falling away from a camera 0.5 m up at up to 86; the jumps between a
/// person's legs and the floor behind are tens of centimetres a pixel.
pub const VEIL_INCIDENCE_DEG: f64 = 88.0;

/// True when the reading at `pixel` (depth `z`) is a veil point: a mixed
/// reading between a near and a far surface, whose depth jumps to both
/// neighbours along its row or its column (each jump steeper than
/// [`VEIL_INCIDENCE_DEG`]). A surface's edge pixel jumps on one side only;
/// a neighbour without a reading (or out of the image) is no jump.
pub fn is_veil_point(cloud: &CloudView<'_>, pixel: usize, z: f64) -> bool {
    let w = cloud.width;
    let focal = cloud.focal_px();
    if w == 0 || !(focal > 0.0) {
        return false;
    }
    let jump = VEIL_INCIDENCE_DEG.to_radians().tan() * z / focal;
    let steep = |q: Option<usize>| {
        q.and_then(|q| cloud.points.get(q))
            .is_some_and(|n| n.z_m.is_finite() && (f64::from(n.z_m) - z).abs() > jump)
    };
    let (u, v) = (pixel % w, pixel / w);
    let left = u.checked_sub(1).map(|_| pixel - 1);
    let right = (u + 1 < w).then_some(pixel + 1);
    let up = v.checked_sub(1).map(|_| pixel - w);
    let down = (v + 1 < cloud.height).then_some(pixel + w);
    (steep(left) && steep(right)) || (steep(up) && steep(down))
}

/// The figures are taken over at most about this many inliers, evenly
/// spaced in pixel order (a plane's inliers are in raster order, so the
/// sample covers its whole extent): an RMS over 1000 samples is within
/// about 2.2 % (one standard error) of the RMS over all of them, and area
/// and border share are sums over a smooth footprint and a border band
/// that a regular sample estimates to within a few per cent (the tests).
/// It keeps the noise model's cost off the per-pixel path.
pub const QUALITY_SAMPLES: usize = 1000;

/// The quality of planes taken together (the ground's segments), pooled
/// over their pixels: each RMS figure the root of the pixel-weighted mean
/// square, the areas summed, the border share pixel-weighted.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct PooledQuality {
    squared_m2: f64,
    squared_relative: f64,
    squared_noise: f64,
    area_m2: f64,
    border_pixels: f64,
    veil_pixels: f64,
}

impl PooledQuality {
    /// Adds a plane of `pixels` pixels whose RMS distance from its own
    /// plane is `rms_m`, of quality `quality`.
    pub(crate) fn add(&mut self, pixels: usize, rms_m: f64, quality: &PlaneQuality) {
        let n = pixels as f64;
        self.squared_m2 += rms_m.powi(2) * n;
        self.squared_relative += quality.relative_rms.powi(2) * n;
        self.squared_noise += quality.noise_ratio.powi(2) * n;
        self.area_m2 += quality.area_m2;
        self.border_pixels += quality.border_fraction * n;
        self.veil_pixels += quality.veil_fraction * n;
    }

    /// The quality of the planes added, `pixels` pixels in all (counted as
    /// at least 1).
    pub(crate) fn quality(&self, pixels: usize) -> PlaneQuality {
        let n = pixels.max(1) as f64;
        PlaneQuality {
            rms_m: (self.squared_m2 / n).sqrt(),
            relative_rms: (self.squared_relative / n).sqrt(),
            area_m2: self.area_m2,
            border_fraction: self.border_pixels / n,
            noise_ratio: (self.squared_noise / n).sqrt(),
            veil_fraction: self.veil_pixels / n,
        }
    }
}

#[derive(Debug, Default)]
struct Sums {
    count: usize,
    squared_m2: f64,
    squared_relative: f64,
    area_m2: f64,
    at_border: usize,
    squared_noise: f64,
    veil: usize,
}

impl Sums {
    fn add(
        &mut self,
        plane: &Plane,
        p: &Vector3<f64>,
        threshold_m: f64,
        at_border: bool,
        focal_area: f64,
        noise: NoiseModel,
    ) {
        let d = plane.signed_distance(p);
        self.count += 1;
        self.at_border += usize::from(at_border);
        self.squared_m2 += d * d;
        if threshold_m > 0.0 {
            self.squared_relative += (d / threshold_m).powi(2);
        }
        // A pixel's footprint on the plane: z^3 / (fx fy |n . p|), with the
        // incidence's cosine |n . p| / |p| at least MIN_COS_INCIDENCE.
        let cos = (plane.normal.dot(p).abs() / p.norm()).min(1.0);
        let clamped = cos.max(MIN_COS_INCIDENCE);
        self.area_m2 += p.z.powi(3) / (focal_area * clamped * p.norm());
        let sigma = noise.sigma_m(p.z, cos.acos());
        self.squared_noise += (d / sigma).powi(2);
    }

    fn quality(&self) -> PlaneQuality {
        if self.count == 0 {
            return PlaneQuality {
                rms_m: f64::NAN,
                relative_rms: f64::NAN,
                area_m2: 0.0,
                border_fraction: 0.0,
                noise_ratio: f64::NAN,
                veil_fraction: 0.0,
            };
        }
        let n = self.count as f64;
        PlaneQuality {
            rms_m: (self.squared_m2 / n).sqrt(),
            relative_rms: (self.squared_relative / n).sqrt(),
            area_m2: self.area_m2,
            border_fraction: self.at_border as f64 / n,
            noise_ratio: (self.squared_noise / n).sqrt(),
            veil_fraction: self.veil as f64 / n,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::{Scene, SceneCloud};
    use crate::ransac_planes::RansacConfig;
    use slope_ipc_types::{CloudPoint, Intrinsics};

    /// A fronto-parallel wall 2 m ahead filling the image: its area is the
    /// image's footprint at 2 m, `(W z / fx) (H z / fy)`.
    /// The quality of the wall plane `z = 2` over every pixel of `view`.
    fn wall_quality(view: &CloudView<'_>) -> PlaneQuality {
        let all: Vec<u32> = (0..view.points.len() as u32).collect();
        let plane = Plane::from_point_normal(&Vector3::new(0.0, 0.0, 2.0), &-Vector3::z()).unwrap();
        plane_quality(
            view,
            &plane,
            &all,
            &Threshold::of(&RansacConfig::default()),
            NoiseModel::Kinect2,
        )
    }

    #[test]
    fn area_of_a_wall_is_the_image_footprint() {
        let scene = Scene::wall_facing(2.0);
        let cloud = SceneCloud::render(&scene, 64, 48, 0.0, 0);
        let view = cloud.view();
        let q = wall_quality(&view);
        let f = view.intrinsics.fx;
        let expected = (64.0 * 2.0 / f) * (48.0 * 2.0 / f);
        assert!(
            (q.area_m2 - expected).abs() < 1e-3 * expected,
            "{} vs {expected}",
            q.area_m2
        );
        assert!(q.rms_m < 1e-6 && q.relative_rms < 1e-4, "{q:?}");
        // An 8-pixel frame around 64 x 48: 1 - 48 * 32 / (64 * 48).
        assert!(
            (q.border_fraction - 0.5).abs() < 1e-12,
            "{}",
            q.border_fraction
        );
    }

    /// Veil points against their definition, on a row of readings: a wall
    /// 2 m away, three mixed readings stepping to a wall 3 m away, and that
    /// wall. The mixed readings jump to both neighbours (veil); the walls'
    /// edge pixels jump to one side only, and a steep but real surface (a
    /// floor seen 8 m ahead of a camera 1.3 m up: 0.14 m a row at 525 px)
    /// is no veil either; a neighbour without a reading is no jump.
    #[test]
    fn veil_points_jump_to_both_neighbours_steeper_than_88_degrees() {
        let depths = [2.0, 2.0, 2.0, 2.25, 2.5, 2.75, 3.0, 3.0, 3.0];
        let w = depths.len();
        let row = |depths: &[f64]| -> Vec<CloudPoint> {
            depths
                .iter()
                .map(|&z| CloudPoint {
                    x_m: 0.0,
                    y_m: 0.0,
                    z_m: if z > 0.0 { z as f32 } else { f32::NAN },
                    rgb: 0,
                })
                .collect()
        };
        let intrinsics = Intrinsics {
            fx: 525.0,
            fy: 525.0,
            cx: 4.0,
            cy: 0.0,
        };
        let points = row(&depths);
        let view = CloudView {
            points: &points,
            width: w,
            height: 1,
            intrinsics,
            mount: Default::default(),
        };
        let veil: Vec<bool> = (0..w).map(|k| is_veil_point(&view, k, depths[k])).collect();
        assert_eq!(
            veil,
            [false, false, false, true, true, true, false, false, false]
        );
        // 0.14 m a pixel at 8 m: steeper than a wall, shallower than 88 deg.
        let floor: Vec<f64> = (0..w).map(|k| 8.0 + 0.14 * k as f64).collect();
        let points = row(&floor);
        let view = CloudView {
            points: &points,
            ..view
        };
        assert!((0..w).all(|k| !is_veil_point(&view, k, floor[k])));
        // A hole beside a mixed reading: one jump only.
        let holed = [2.0, 2.0, 2.0, 0.0, 2.5, 2.75, 3.0, 3.0, 3.0];
        let points = row(&holed);
        let view = CloudView {
            points: &points,
            ..view
        };
        assert!(!is_veil_point(&view, 4, 2.5));
        assert!(is_veil_point(&view, 5, 2.75));
    }

    /// A view of width 0 (malformed: its points have no pixel grid) has no
    /// inlier to measure: the empty quality, instead of a panic.
    #[test]
    fn a_view_of_width_0_has_the_empty_quality() {
        let scene = Scene::wall_facing(2.0);
        let cloud = SceneCloud::render(&scene, 64, 48, 0.0, 0);
        let view = CloudView {
            width: 0,
            ..cloud.view()
        };
        let q = wall_quality(&view);
        assert!(q.rms_m.is_nan() && q.relative_rms.is_nan() && q.noise_ratio.is_nan());
        assert_eq!((q.area_m2, q.border_fraction), (0.0, 0.0));
    }

    /// Points spread evenly over the threshold band give 1/sqrt(3).
    #[test]
    fn a_surface_filling_the_band_has_relative_rms_0_58() {
        let plane = Plane::from_point_normal(&Vector3::zeros(), &Vector3::z()).unwrap();
        let t = Threshold::of(&RansacConfig::default());
        let mut sums = Sums::default();
        let n = 10_000;
        for k in 0..n {
            let p = Vector3::new(0.0, 0.0, 0.01);
            let d = -t.at(&p) + 2.0 * t.at(&p) * (k as f64 + 0.5) / n as f64;
            sums.add(
                &plane,
                &Vector3::new(0.0, 0.0, d),
                t.at(&p),
                false,
                1.0,
                NoiseModel::Kinect2,
            );
        }
        let q = sums.quality();
        assert!((q.relative_rms - 1.0 / 3f64.sqrt()).abs() < 1e-3, "{q:?}");
    }

    /// Readings off a wall by one standard deviation of the sensor model
    /// (at their own depth and incidence) score 1; by three, 3. The same
    /// metres of roughness score less with the noisier Kinect v1 far away.
    #[test]
    fn noise_ratio_counts_standard_deviations_of_the_sensor_model() {
        let plane = Plane::from_point_normal(&Vector3::new(0.0, 0.0, 2.0), &-Vector3::z()).unwrap();
        let t = Threshold::of(&RansacConfig::default());
        for model in [NoiseModel::Kinect2, NoiseModel::Kinect1] {
            for k_sigma in [1.0, 3.0] {
                let mut sums = Sums::default();
                for k in 0..1000 {
                    let (x, y) = ((k % 40) as f64 * 0.02 - 0.4, (k / 40) as f64 * 0.02 - 0.25);
                    let on_plane = Vector3::new(x, y, 2.0);
                    let theta = (2.0 / on_plane.norm()).acos();
                    let d =
                        k_sigma * model.sigma_m(2.0, theta) * if k % 2 == 0 { 1.0 } else { -1.0 };
                    // The reading moves along z, off the plane by |d|.
                    let p = Vector3::new(x, y, 2.0 + d);
                    sums.add(&plane, &p, t.at(&p), false, 1.0, model);
                }
                let q = sums.quality();
                assert!(
                    (q.noise_ratio - k_sigma).abs() < 0.01 * k_sigma,
                    "{model:?} {q:?}"
                );
            }
        }
        let (v2, v1) = (NoiseModel::Kinect2, NoiseModel::Kinect1);
        assert!(v1.sigma_m(3.5, 0.0) > 5.0 * v2.sigma_m(3.5, 0.0));
    }

    /// The sampled figures against every inlier (brute force) on a noisy
    /// Kinect v2 frame of a 16 degree ramp: the ground's inliers (~80,000
    /// pixels, sampled 1 in 80).
    #[test]
    fn sampled_figures_match_all_inliers() {
        let scene = Scene::ramp(16.0);
        let cloud = SceneCloud::kinect2(&scene, 3);
        let view = cloud.view();
        let up = scene.to_camera(&Vector3::z());
        let foot = scene.to_camera(&(scene.surfaces[0].point - scene.camera_centre()));
        let plane = Plane::from_point_normal(&foot, &up).unwrap();
        let t = Threshold::of(&RansacConfig::default());
        let inliers: Vec<u32> = (0..view.points.len())
            .filter(|&i| {
                view.point(i)
                    .is_some_and(|p| plane.signed_distance(&p).abs() <= t.at(&p))
            })
            .map(|i| i as u32)
            .collect();
        assert!(inliers.len() > 20 * QUALITY_SAMPLES, "{}", inliers.len());
        let sampled = plane_quality(&view, &plane, &inliers, &t, NoiseModel::Kinect2);
        let mut all = Sums::default();
        for &i in &inliers {
            let i = i as usize;
            let p = view.point(i).unwrap();
            let (u, v) = (i % view.width, i / view.width);
            let border = u < BORDER_PX
                || v < BORDER_PX
                || u + BORDER_PX >= view.width
                || v + BORDER_PX >= view.height;
            let f = view.intrinsics.fx * view.intrinsics.fy;
            all.add(&plane, &p, t.at(&p), border, f, NoiseModel::Kinect2);
        }
        let exact = all.quality();
        // Relative tolerances: RMS figures 5 %, area 2 %.
        for (name, s, e, tol) in [
            ("rms", sampled.rms_m, exact.rms_m, 0.05),
            (
                "relative rms",
                sampled.relative_rms,
                exact.relative_rms,
                0.05,
            ),
            ("noise ratio", sampled.noise_ratio, exact.noise_ratio, 0.05),
            ("area", sampled.area_m2, exact.area_m2, 0.02),
        ] {
            assert!((s - e).abs() <= tol * e.abs(), "{name}: {s} vs {e}");
        }
        assert!(
            (sampled.border_fraction - exact.border_fraction).abs() < 0.01,
            "{sampled:?} {exact:?}"
        );
    }
}
