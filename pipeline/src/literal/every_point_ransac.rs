//! Stage 2 as the paper (and PCL's `SACSegmentation` in a loop) runs it:
//! three random non-collinear points give a plane; its inliers are the
//! points within the distance threshold, counted over *every* kept point;
//! the plane with the most inliers wins, is refitted by TLS on its inliers
//! (PCL's `optimizeModelCoefficients`), and its inliers leave the cloud;
//! repeat until fewer than `min_remaining_fraction` of the points are left,
//! the best plane has fewer than `min_plane_points` inliers, or
//! `max_planes` were found. Hypotheses per plane: the adaptive RANSAC count
//! for `confidence` (`log(1 - confidence) / log(1 - w^3)`, w the best
//! inlier ratio so far), at most `max_iterations`. No normal gating, no
//! connectivity, no sample grid: those are our changes
//! (`ransac_planes/`). The threshold is `Threshold::at` (a constant unless
//! `distance_threshold_per_m2` is set, which is one of our changes too).

use nalgebra::Vector3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::cloud::CloudView;
use crate::plane_fit::{fit_tls, Moments, Plane};
use crate::ransac_planes::{RansacConfig, SegmentedPlane, Threshold};
use crate::segmentation::Proposal;

/// What RANSAC scores its hypotheses on (`ransac.scoring`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RansacScoring {
    /// A grid subsample, normal-gated, connected regions, every pixel
    /// labelled once at the end (`ransac_planes/`, ours).
    #[default]
    SampleGrid,
    /// Every kept point, once per extracted plane (the paper).
    EveryPoint,
}

/// Reusable buffers of the every-point segmentation.
#[derive(Debug, Default, Clone)]
pub struct EveryPointRansac {
    /// The free points: pixel index, coordinates, inlier distance.
    pixels: Vec<u32>,
    xs: Vec<f64>,
    ys: Vec<f64>,
    zs: Vec<f64>,
    limits: Vec<f64>,
    inlier: Vec<bool>,
    planes: Vec<SegmentedPlane>,
}

impl EveryPointRansac {
    pub fn new() -> Self {
        Self::default()
    }

    /// The planes of the last [`Self::segment`] call, largest first.
    pub fn planes(&self) -> &[SegmentedPlane] {
        &self.planes
    }

    /// Segments the points marked in `keep` (one flag per pixel).
    pub fn segment(
        &mut self,
        cloud: &CloudView<'_>,
        keep: &[bool],
        config: &RansacConfig,
        rng: &mut ChaCha8Rng,
    ) -> &[SegmentedPlane] {
        self.planes.clear();
        self.load_free_points(cloud, keep, Threshold::of(config));
        let total = self.pixels.len();
        let min_points = config.min_plane_points.max(3);
        while self.planes.len() < config.plane_cap(Proposal::Sequential.max_planes())
            && self.pixels.len() >= min_points
            && (self.pixels.len() as f64) >= config.min_remaining_fraction * total as f64
        {
            let Some((plane, count)) = self.best_hypothesis(config, rng) else {
                break;
            };
            if count < min_points {
                break;
            }
            self.flag_inliers(&plane);
            let segmented = self.fit_inliers(&plane, count);
            self.planes.push(segmented);
            self.remove_inliers();
        }
        &self.planes
    }

    /// The free points: every kept, measured pixel, with its coordinates
    /// and inlier distance under `threshold`, in pixel order.
    fn load_free_points(&mut self, cloud: &CloudView<'_>, keep: &[bool], threshold: Threshold) {
        self.pixels.clear();
        self.xs.clear();
        self.ys.clear();
        self.zs.clear();
        self.limits.clear();
        for (i, &k) in keep.iter().enumerate() {
            if let Some(p) = cloud.point(i).filter(|_| k) {
                self.pixels.push(i as u32);
                self.xs.push(p.x);
                self.ys.push(p.y);
                self.zs.push(p.z);
                self.limits.push(threshold.at(&p));
            }
        }
    }

    /// The plane of the flagged inliers (`count` of them; found as
    /// `plane`): their TLS fit (`plane` if none) towards the camera, with
    /// their pixels, centroid, RMS distance and moments.
    fn fit_inliers(&self, plane: &Plane, count: usize) -> SegmentedPlane {
        let mut moments = Moments::new();
        let mut inliers = Vec::with_capacity(count);
        for (k, &is_inlier) in self.inlier.iter().enumerate() {
            if is_inlier {
                moments.add(&self.point(k));
                inliers.push(self.pixels[k]);
            }
        }
        let fitted = fit_tls(&moments)
            .unwrap_or(*plane)
            .oriented_towards(&Vector3::zeros());
        let rms_m = moments.covariance().map_or(0.0, |c| {
            let n = fitted.normal;
            n.dot(&(c * n)).max(0.0).sqrt()
        });
        SegmentedPlane {
            plane: fitted,
            inliers,
            pixel_box: None,
            centroid: moments.mean().unwrap_or_else(Vector3::zeros),
            rms_m,
            moments,
        }
    }

    fn point(&self, k: usize) -> Vector3<f64> {
        Vector3::new(self.xs[k], self.ys[k], self.zs[k])
    }

    /// Inliers of `plane` among the free points.
    fn count_inliers(&self, plane: &Plane) -> usize {
        let (n, d) = (plane.normal, plane.d);
        let mut count = 0;
        for k in 0..self.xs.len() {
            let dist = (n.x * self.xs[k] + n.y * self.ys[k] + n.z * self.zs[k] + d).abs();
            count += usize::from(dist <= self.limits[k]);
        }
        count
    }

    fn flag_inliers(&mut self, plane: &Plane) {
        let (n, d) = (plane.normal, plane.d);
        self.inlier.clear();
        self.inlier.extend((0..self.xs.len()).map(|k| {
            (n.x * self.xs[k] + n.y * self.ys[k] + n.z * self.zs[k] + d).abs() <= self.limits[k]
        }));
    }

    /// The three-point hypothesis with the most inliers and its count.
    fn best_hypothesis(
        &self,
        config: &RansacConfig,
        rng: &mut ChaCha8Rng,
    ) -> Option<(Plane, usize)> {
        let n = self.pixels.len();
        let mut best: Option<(Plane, usize)> = None;
        let mut needed = config.max_iterations;
        let mut drawn = 0;
        while drawn < needed {
            drawn += 1;
            let (a, b, c) = (
                rng.random_range(0..n),
                rng.random_range(0..n),
                rng.random_range(0..n),
            );
            if a == b || b == c || a == c {
                continue;
            }
            let Some(plane) =
                Plane::from_three_points(&self.point(a), &self.point(b), &self.point(c))
            else {
                continue;
            };
            let count = self.count_inliers(&plane);
            if best.is_none_or(|(_, best_count)| count > best_count) {
                best = Some((plane, count));
                let w = count as f64 / n as f64;
                let miss = 1.0 - w * w * w;
                if miss <= 0.0 {
                    break;
                }
                let adaptive = (1.0 - config.confidence).ln() / miss.ln();
                if adaptive.is_finite() && adaptive >= 0.0 {
                    needed = (adaptive.ceil() as usize).min(config.max_iterations);
                }
            }
        }
        best
    }

    /// Drops the flagged inliers from the free points (order kept).
    fn remove_inliers(&mut self) {
        let mut out = 0;
        for k in 0..self.pixels.len() {
            if !self.inlier[k] {
                self.pixels[out] = self.pixels[k];
                self.xs[out] = self.xs[k];
                self.ys[out] = self.ys[k];
                self.zs[out] = self.zs[k];
                self.limits[out] = self.limits[k];
                out += 1;
            }
        }
        self.pixels.truncate(out);
        self.xs.truncate(out);
        self.ys.truncate(out);
        self.zs.truncate(out);
        self.limits.truncate(out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::{Scene, SceneCloud};
    use rand::SeedableRng;

    fn angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
        crate::cloud::angle_between_deg(a, b)
    }

    /// A noise-free ramp scene (f32 coordinates, no depth rounding) and a
    /// 0.1 mm threshold (so that hardly a point of one surface is within
    /// it of the other): the two largest planes are the analytic ground
    /// and ramp (normals within 0.01 degrees, RMS under 10 micrometres:
    /// f32 rounding only), the planes cover the measured pixels, each
    /// pixel once, in pixel order.
    #[test]
    fn recovers_the_analytic_planes() {
        let scene = Scene::ramp(30.0);
        let cloud = SceneCloud::render_with_intrinsics(&scene, 80, 60, 57.0, 0.0, 1);
        let view = cloud.view();
        let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
        let config = RansacConfig {
            distance_threshold_m: 1e-4,
            distance_threshold_per_m2: 0.0,
            min_plane_points: 50,
            ..RansacConfig::default()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut ransac = EveryPointRansac::new();
        let planes = ransac.segment(&view, &keep, &config, &mut rng).to_vec();
        assert!(planes.len() >= 2, "{}", planes.len());
        let truth: Vec<Vector3<f64>> = scene
            .surfaces
            .iter()
            .map(|s| scene.to_camera(&s.normal))
            .collect();
        for plane in &planes[..2] {
            let best = truth
                .iter()
                .map(|t| angle_deg(&plane.plane.normal, t).min(angle_deg(&plane.plane.normal, &-t)))
                .fold(f64::INFINITY, f64::min);
            assert!(best < 0.01, "normal off by {best} degrees");
            assert!(plane.rms_m < 1e-5, "{}", plane.rms_m);
            assert!(plane.inliers.windows(2).all(|w| w[0] < w[1]));
        }
        // No pixel in two planes; together they cover the measured pixels
        // but the few near the junction and the horizon.
        let mut seen = vec![false; cloud.points.len()];
        for p in &planes {
            for &i in &p.inliers {
                assert!(!seen[i as usize]);
                seen[i as usize] = true;
            }
        }
        let measured = keep.iter().filter(|&&k| k).count();
        let covered = seen.iter().filter(|&&s| s).count();
        assert!(
            covered as f64 >= 0.99 * measured as f64,
            "{covered} of {measured}"
        );
    }

    /// The score is the brute-force inlier count over every free point.
    #[test]
    fn score_counts_every_point() {
        let cloud = SceneCloud::render(&Scene::ramp(12.5), 40, 30, 0.005, 2);
        let view = cloud.view();
        let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
        let config = RansacConfig {
            max_planes: Some(1),
            min_plane_points: 10,
            ..RansacConfig::default()
        };
        let mut ransac = EveryPointRansac::new();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        ransac.segment(&view, &keep, &config, &mut rng);
        // Before the segmentation's removal the free set was all points.
        let mut fresh = EveryPointRansac::new();
        fresh.segment(
            &view,
            &keep,
            &RansacConfig {
                max_planes: Some(0),
                ..config.clone()
            },
            &mut rng,
        );
        let t = Threshold::of(&config);
        let planes = [
            Plane::from_point_normal(&Vector3::new(0.0, 0.5, 2.0), &Vector3::new(0.1, -1.0, 0.3))
                .expect("a non-zero normal"),
            ransac
                .planes()
                .first()
                .expect("the ramp scene has a plane of 10 points")
                .plane,
        ];
        for plane in planes {
            let brute = (0..cloud.points.len())
                .filter_map(|i| view.point(i))
                .filter(|p| plane.signed_distance(p).abs() <= t.at(p))
                .count();
            assert_eq!(fresh.count_inliers(&plane), brute);
        }
    }
}
