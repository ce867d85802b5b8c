//! How good a segmented plane is as a measurement surface: its flatness at
//! the sensor's noise level, its area on the surface, and how much of it
//! lies along the image border.

use nalgebra::Vector3;

use crate::cloud::CloudView;
use crate::plane_fit::Plane;
use crate::ransac_planes::Threshold;

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
}

/// The quality of `plane` over its `inliers` (pixel indices of `cloud`).
pub fn plane_quality(
    cloud: &CloudView<'_>,
    plane: &Plane,
    inliers: &[u32],
    threshold: &Threshold,
) -> PlaneQuality {
    let (w, h) = (cloud.width, cloud.height);
    let focal_area = cloud.intrinsics.fx * cloud.intrinsics.fy;
    let focal_area = if focal_area.is_finite() && focal_area > 0.0 {
        focal_area
    } else {
        cloud.focal_px().powi(2)
    };
    let mut sums = Sums::default();
    for &pixel in inliers {
        let pixel = pixel as usize;
        let Some(p) = cloud.point(pixel) else {
            continue;
        };
        let (u, v) = (pixel % w, pixel / w);
        let at_border = u < BORDER_PX || v < BORDER_PX || u + BORDER_PX >= w || v + BORDER_PX >= h;
        sums.add(plane, &p, threshold.at(&p), at_border, focal_area);
    }
    sums.quality()
}

#[derive(Debug, Default)]
struct Sums {
    count: usize,
    squared_m2: f64,
    squared_relative: f64,
    area_m2: f64,
    at_border: usize,
}

impl Sums {
    fn add(
        &mut self,
        plane: &Plane,
        p: &Vector3<f64>,
        threshold_m: f64,
        at_border: bool,
        focal_area: f64,
    ) {
        let d = plane.signed_distance(p);
        self.count += 1;
        self.squared_m2 += d * d;
        if threshold_m > 0.0 {
            self.squared_relative += (d / threshold_m).powi(2);
        }
        // A pixel's footprint on the plane: z^3 / (fx fy |n . p|).
        let r = p.norm();
        let cos = (plane.normal.dot(p).abs() / r).max(MIN_COS_INCIDENCE);
        self.area_m2 += p.z.powi(2) * (p.z / r) / (focal_area * cos);
        self.at_border += usize::from(at_border);
    }

    fn quality(&self) -> PlaneQuality {
        if self.count == 0 {
            return PlaneQuality {
                rms_m: f64::NAN,
                relative_rms: f64::NAN,
                area_m2: 0.0,
                border_fraction: 0.0,
            };
        }
        let n = self.count as f64;
        PlaneQuality {
            rms_m: (self.squared_m2 / n).sqrt(),
            relative_rms: (self.squared_relative / n).sqrt(),
            area_m2: self.area_m2,
            border_fraction: self.at_border as f64 / n,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::RansacConfig;
    use crate::fixtures::{Scene, SceneCloud};

    /// A fronto-parallel wall 2 m ahead filling the image: its area is the
    /// image's footprint at 2 m, `(W z / fx) (H z / fy)`.
    #[test]
    fn area_of_a_wall_is_the_image_footprint() {
        let scene = Scene::wall_facing(2.0);
        let cloud = SceneCloud::render(&scene, 64, 48, 0.0, 0);
        let view = cloud.view();
        let all: Vec<u32> = (0..view.points.len() as u32).collect();
        let plane = Plane::from_point_normal(&Vector3::new(0.0, 0.0, 2.0), &-Vector3::z()).unwrap();
        let q = plane_quality(
            &view,
            &plane,
            &all,
            &Threshold::of(&RansacConfig::default()),
        );
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
            sums.add(&plane, &Vector3::new(0.0, 0.0, d), t.at(&p), false, 1.0);
        }
        let q = sums.quality();
        assert!((q.relative_rms - 1.0 / 3f64.sqrt()).abs() < 1e-3, "{q:?}");
    }
}
