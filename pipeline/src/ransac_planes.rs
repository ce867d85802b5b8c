//! Stage 2, RANSAC plane segmentation (paper 2.2 and 3): find the plane with
//! the most inliers (points within `distance_threshold_m`), take its inliers
//! out, repeat until the rest is smaller than a threshold or the last plane
//! was too small.
//!
//! **Shortcut.** The paper (like PCL's `SACSegmentation` on the filtered
//! cloud) scores every hypothesis against every point. Here hypotheses are
//! drawn and scored on a regular subsample of the grid (every
//! `sample_stride_px`-th pixel in both directions, ~13,500 points of a
//! Kinect v2 frame at stride 4; the paper itself downsamples during
//! segmentation), then the winner is refined by total least squares on its
//! sample inliers and takes its inliers from *every* remaining point. The
//! inlier count of a plane on a uniform grid subsample is proportional to
//! its full count, so the largest plane is the same plane. Each sample point
//! also carries a coarse local normal; a hypothesis is rejected before
//! scoring when its three points' normals disagree with it, and a sample
//! point whose normal is more than `normal_threshold_deg` off the hypothesis
//! is not its inlier (as PCL's `SACSegmentationFromNormals`), so a plane
//! that merely slices through the edges of a staircase never wins. Finally a
//! point within the threshold of two planes (near their intersection line)
//! goes to the nearer one, so the first-found plane does not steal a strip
//! of its neighbour.

use nalgebra::Vector3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::cloud::{is_measured, to_vec3, CloudView};
use crate::config::RansacConfig;
use crate::normals::grid_normal;
use crate::plane_fit::{fit_tls, Moments, Plane};

/// Hypotheses are scored on at most this many sample points (a random
/// subset); the winner is rescored on all of them.
const SCORE_POINTS: usize = 2000;

/// Points of the score subset a hypothesis is first tested on.
const PRETEST: usize = 100;

/// Stride of the scrambled visiting order of the score subset; coprime with
/// `SCORE_POINTS`, near its golden section.
const SCRAMBLE: usize = 1237;

/// Local-optimisation refits of a new best hypothesis, at most.
const LO_STEPS: usize = 4;

/// Hypotheses drawn per plane at least, whatever the adaptive count says.
const MIN_HYPOTHESES: usize = 64;

/// One segmented plane.
#[derive(Debug, Clone)]
pub struct SegmentedPlane {
    /// TLS fit of all inliers, normal towards the camera (origin).
    pub plane: Plane,
    /// Pixel indices of the inliers.
    pub inliers: Vec<u32>,
    /// Mean of the inliers.
    pub centroid: Vector3<f64>,
}

/// Reusable buffers of the segmentation.
#[derive(Debug, Default, Clone)]
pub struct PlaneSegmenter {
    /// Free full-resolution points: pixel index and coordinates.
    free_index: Vec<u32>,
    free_xyz: Vec<[f32; 3]>,
    /// Free sample points: coordinates and coarse normal (NaN if unknown).
    sample_xyz: Vec<Vector3<f64>>,
    sample_normal: Vec<Vector3<f64>>,
    sample_pixel: Vec<u32>,
    sample_with_normal: Vec<u32>,
    /// Per pixel: FREE, TAKEN (in an extracted plane), or a candidate
    /// region's label during [`Self::keep_largest_region`].
    region: Vec<u32>,
    stack: Vec<u32>,
    region_sizes: Vec<usize>,
    score_subset: Vec<u32>,
    inlier_flags: Vec<bool>,
    planes: Vec<SegmentedPlane>,
    owner: Vec<u16>,
}

const NO_PLANE: u16 = u16::MAX;
const FREE: u32 = u32::MAX;
const TAKEN: u32 = u32::MAX - 1;
const CANDIDATE: u32 = u32::MAX - 2;
/// Hypotheses whose largest region is too small before segmentation stops.
const MAX_FAILURES: usize = 8;

impl PlaneSegmenter {
    pub fn new() -> Self {
        Self::default()
    }

    /// The planes of the last [`Self::segment`] call, largest first.
    pub fn planes(&self) -> &[SegmentedPlane] {
        &self.planes
    }

    /// Segments the points marked in `keep` (one flag per pixel) into planes.
    pub fn segment(
        &mut self,
        cloud: &CloudView<'_>,
        keep: &[bool],
        config: &RansacConfig,
        rng: &mut ChaCha8Rng,
    ) -> &[SegmentedPlane] {
        self.planes.clear();
        let (w, h) = (cloud.width, cloud.height);
        if cloud.points.len() != w * h || keep.len() != w * h || w * h >= CANDIDATE as usize {
            return &self.planes;
        }
        self.free_index.clear();
        self.free_xyz.clear();
        for (i, (p, &k)) in cloud.points.iter().zip(keep).enumerate() {
            if k && is_measured(p) {
                self.free_index.push(i as u32);
                self.free_xyz.push([p.x_m, p.y_m, p.z_m]);
            }
        }
        let total = self.free_index.len();
        self.load_sample(cloud, keep, config);
        self.region.clear();
        self.region.resize(w * h, FREE);
        let mut failures = 0;
        let t = Threshold {
            base_m: config.distance_threshold_m,
            per_m2: config.distance_threshold_per_m2,
        };
        let cos_gate = if config.normal_threshold_deg > 0.0 && config.normal_threshold_deg < 90.0 {
            Some(config.normal_threshold_deg.to_radians().cos())
        } else {
            None
        };
        while self.planes.len() < config.max_planes
            && self.free_index.len() >= 3
            && (self.free_index.len() as f64) >= config.min_remaining_fraction * total as f64
            && self.sample_xyz.len() >= 3
        {
            let Some(plane) = self.best_hypothesis(config, cos_gate, rng) else {
                break;
            };
            // Refine on the sample: TLS of the inliers, twice.
            let mut plane = plane;
            for _ in 0..2 {
                let mut m = Moments::new();
                for (p, n) in self.sample_xyz.iter().zip(&self.sample_normal) {
                    if is_inlier(&plane, p, n, t, cos_gate) {
                        m.add(p);
                    }
                }
                match fit_tls(&m) {
                    Some(refined) => plane = refined,
                    None => break,
                }
            }
            // Inliers from every free point, then only the largest
            // 8-connected region of them on the pixel grid; the region's TLS
            // plane collects the inliers once more (it is the better plane:
            // fitted on every point, without the other regions' pull).
            let mut inliers = Vec::new();
            let mut moments = Moments::new();
            for round in 0..2 {
                self.inlier_flags.clear();
                for q in &self.free_xyz {
                    let p = Vector3::new(f64::from(q[0]), f64::from(q[1]), f64::from(q[2]));
                    self.inlier_flags
                        .push(plane.signed_distance(&p).abs() <= t.at(&p));
                }
                self.keep_largest_region(w, h);
                inliers.clear();
                moments = Moments::new();
                for ((&i, q), &inside) in self
                    .free_index
                    .iter()
                    .zip(&self.free_xyz)
                    .zip(&self.inlier_flags)
                {
                    if inside {
                        inliers.push(i);
                        moments.add(&Vector3::new(
                            f64::from(q[0]),
                            f64::from(q[1]),
                            f64::from(q[2]),
                        ));
                    }
                }
                if round == 0 && inliers.len() >= config.min_plane_points {
                    match fit_tls(&moments) {
                        Some(refit) => plane = refit,
                        None => break,
                    }
                } else {
                    break;
                }
            }
            if inliers.len() < config.min_plane_points {
                // Too small (or only scattered pieces): these sample points
                // cannot seed a plane; drop them and try again a few times.
                failures += 1;
                if failures > MAX_FAILURES {
                    break;
                }
                let mut k = 0;
                for j in 0..self.sample_xyz.len() {
                    if !is_inlier(
                        &plane,
                        &self.sample_xyz[j],
                        &self.sample_normal[j],
                        t,
                        cos_gate,
                    ) {
                        self.sample_xyz[k] = self.sample_xyz[j];
                        self.sample_normal[k] = self.sample_normal[j];
                        self.sample_pixel[k] = self.sample_pixel[j];
                        k += 1;
                    }
                }
                self.sample_xyz.truncate(k);
                self.sample_normal.truncate(k);
                self.sample_pixel.truncate(k);
                continue;
            }
            let Some(fitted) = fit_tls(&moments) else {
                break;
            };
            let plane = fitted.oriented_towards(&Vector3::zeros());
            let centroid = moments.mean().unwrap_or_else(Vector3::zeros);
            // Take the inliers out of the free points and the sample.
            let mut k = 0;
            for j in 0..self.free_index.len() {
                if !self.inlier_flags[j] {
                    self.free_index[k] = self.free_index[j];
                    self.free_xyz[k] = self.free_xyz[j];
                    k += 1;
                }
            }
            self.free_index.truncate(k);
            self.free_xyz.truncate(k);
            for &i in &inliers {
                self.region[i as usize] = TAKEN;
            }
            let mut k = 0;
            for j in 0..self.sample_xyz.len() {
                if self.region[self.sample_pixel[j] as usize] != TAKEN {
                    self.sample_xyz[k] = self.sample_xyz[j];
                    self.sample_normal[k] = self.sample_normal[j];
                    self.sample_pixel[k] = self.sample_pixel[j];
                    k += 1;
                }
            }
            self.sample_xyz.truncate(k);
            self.sample_normal.truncate(k);
            self.sample_pixel.truncate(k);
            tracing::trace!(
                plane = self.planes.len(),
                inliers = inliers.len(),
                normal = ?plane.normal,
                "ransac plane"
            );
            self.planes.push(SegmentedPlane {
                plane,
                inliers,
                centroid,
            });
        }
        self.assign_to_nearest(cloud, t);
        &self.planes
    }

    /// Keeps in `inlier_flags` only the largest 8-connected pixel region of
    /// the flagged free points.
    fn keep_largest_region(&mut self, w: usize, h: usize) {
        for (&i, &inside) in self.free_index.iter().zip(&self.inlier_flags) {
            if inside {
                self.region[i as usize] = CANDIDATE;
            }
        }
        self.region_sizes.clear();
        for (&seed, &inside) in self.free_index.iter().zip(&self.inlier_flags) {
            if !inside || self.region[seed as usize] != CANDIDATE {
                continue;
            }
            let label = self.region_sizes.len() as u32;
            let mut size = 0;
            self.region[seed as usize] = label;
            self.stack.clear();
            self.stack.push(seed);
            while let Some(p) = self.stack.pop() {
                size += 1;
                let (u, v) = ((p as usize) % w, (p as usize) / w);
                for dv in -1isize..=1 {
                    for du in -1isize..=1 {
                        let (uu, vv) = (u as isize + du, v as isize + dv);
                        if uu < 0 || vv < 0 || uu >= w as isize || vv >= h as isize {
                            continue;
                        }
                        let q = vv as usize * w + uu as usize;
                        if self.region[q] == CANDIDATE {
                            self.region[q] = label;
                            self.stack.push(q as u32);
                        }
                    }
                }
            }
            self.region_sizes.push(size);
        }
        let largest = self
            .region_sizes
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(&a.0)))
            .map(|(l, _)| l as u32);
        for (&i, inside) in self.free_index.iter().zip(self.inlier_flags.iter_mut()) {
            if *inside {
                *inside = Some(self.region[i as usize]) == largest;
                self.region[i as usize] = FREE;
            }
        }
    }

    /// The sample grid and its coarse normals.
    fn load_sample(&mut self, cloud: &CloudView<'_>, keep: &[bool], config: &RansacConfig) {
        self.sample_xyz.clear();
        self.sample_normal.clear();
        self.sample_pixel.clear();
        let s = config.sample_stride_px.max(1);
        let (w, h) = (cloud.width, cloud.height);
        let radius = 2;
        let need_normals = config.normal_threshold_deg > 0.0 && config.normal_threshold_deg < 90.0;
        for v in (s / 2..h).step_by(s) {
            for u in (s / 2..w).step_by(s) {
                let i = v * w + u;
                if !keep[i] || !is_measured(&cloud.points[i]) {
                    continue;
                }
                let n = if need_normals {
                    grid_normal(cloud, keep, u, v, radius)
                        .unwrap_or_else(|| Vector3::repeat(f64::NAN))
                } else {
                    Vector3::repeat(f64::NAN)
                };
                self.sample_xyz.push(to_vec3(&cloud.points[i]));
                self.sample_normal.push(n);
                self.sample_pixel.push(i as u32);
            }
        }
    }

    /// The hypothesis with the most inliers on a random subset of the sample.
    fn best_hypothesis(
        &mut self,
        config: &RansacConfig,
        cos_gate: Option<f64>,
        rng: &mut ChaCha8Rng,
    ) -> Option<Plane> {
        let n = self.sample_xyz.len();
        // Hypotheses are drawn from points with a known normal when the gate
        // is on (a point without one sits on an edge or in clutter).
        self.sample_with_normal.clear();
        for (j, nrm) in self.sample_normal.iter().enumerate() {
            if cos_gate.is_none() || nrm.x.is_finite() {
                self.sample_with_normal.push(j as u32);
            }
        }
        if self.sample_with_normal.len() < 3 {
            return None;
        }
        self.score_subset.clear();
        if n <= SCORE_POINTS {
            self.score_subset.extend(0..n as u32);
        } else {
            // A stratified subset: every (n / SCORE_POINTS)-th sample point
            // in raster order, so each image region is scored in proportion,
            // visited in a scrambled order (a stride coprime with
            // SCORE_POINTS) so that the pretest prefix is spread over the
            // whole image too.
            self.score_subset.extend(
                (0..SCORE_POINTS)
                    .map(|k| ((k * SCRAMBLE) % SCORE_POINTS * n / SCORE_POINTS) as u32),
            );
        }
        let t = Threshold {
            base_m: config.distance_threshold_m,
            per_m2: config.distance_threshold_per_m2,
        };
        let mut best: Option<(usize, Plane)> = None;
        let mut needed = config.max_iterations;
        let mut it = 0;
        let log_fail = (1.0 - config.confidence).ln();
        let pool = &self.sample_with_normal;
        while it < needed.max(MIN_HYPOTHESES).min(config.max_iterations) {
            it += 1;
            let a = pool[rng.random_range(0..pool.len())] as usize;
            let plane = if cos_gate.is_some() && it % 2 == 1 {
                // Every other hypothesis is one point and its coarse normal:
                // a small plane (a stair riser among several parallel ones)
                // is hit with the probability of its share w of the points,
                // not w^3; local optimisation corrects the coarse normal.
                let Some(plane) =
                    Plane::from_point_normal(&self.sample_xyz[a], &self.sample_normal[a])
                else {
                    continue;
                };
                plane
            } else {
                let b = pool[rng.random_range(0..pool.len())] as usize;
                let c = pool[rng.random_range(0..pool.len())] as usize;
                if a == b || b == c || a == c {
                    continue;
                }
                let Some(plane) = Plane::from_three_points(
                    &self.sample_xyz[a],
                    &self.sample_xyz[b],
                    &self.sample_xyz[c],
                ) else {
                    continue;
                };
                if let Some(cg) = cos_gate {
                    if [a, b, c]
                        .iter()
                        .any(|&k| self.sample_normal[k].dot(&plane.normal).abs() < cg)
                    {
                        continue;
                    }
                }
                plane
            };
            // Preemptive test: a hypothesis that scores under half the best
            // rate on the first PRETEST points is not scored further.
            let inlier = |k: &u32| {
                let k = *k as usize;
                is_inlier(
                    &plane,
                    &self.sample_xyz[k],
                    &self.sample_normal[k],
                    t,
                    cos_gate,
                )
            };
            let pre = PRETEST.min(self.score_subset.len());
            let pre_score = self.score_subset[..pre]
                .iter()
                .filter(|k| inlier(k))
                .count();
            if let Some((best_score, _)) = &best {
                let expected = *best_score as f64 * pre as f64 / self.score_subset.len() as f64;
                if (pre_score as f64) < 0.5 * expected {
                    continue;
                }
            }
            let score = pre_score
                + self.score_subset[pre..]
                    .iter()
                    .filter(|k| inlier(k))
                    .count();
            if best.as_ref().is_none_or(|(s, _)| score > *s) {
                // Local optimisation (LO-RANSAC): refit the new best by TLS
                // on its inliers until the score stops growing, so that
                // whichever triple found the plane, the plane kept is the
                // same fixed point of "fit the inliers, collect the inliers".
                let (score, plane) = local_optimisation(
                    score,
                    plane,
                    &self.sample_xyz,
                    &self.sample_normal,
                    &self.score_subset,
                    t,
                    cos_gate,
                );
                best = Some((score, plane));
                let w = score as f64 / self.score_subset.len() as f64;
                // Half the hypotheses need one good point, half three.
                let p_good = if cos_gate.is_some() {
                    0.5 * (w + w * w * w)
                } else {
                    w * w * w
                };
                if p_good > 0.0 && p_good < 1.0 {
                    let n_req = log_fail / (1.0 - p_good).ln();
                    needed = if n_req.is_finite() {
                        n_req.ceil() as usize
                    } else {
                        needed
                    };
                } else if p_good >= 1.0 {
                    needed = 0;
                }
            }
        }
        best.filter(|(s, _)| *s >= 3).map(|(_, p)| p)
    }

    /// Gives a point within the threshold of several planes to the nearest.
    fn assign_to_nearest(&mut self, cloud: &CloudView<'_>, t: Threshold) {
        if self.planes.len() < 2 {
            return;
        }
        let n = cloud.points.len();
        self.owner.clear();
        self.owner.resize(n, NO_PLANE);
        let mut changed = false;
        for (k, plane) in self.planes.iter().enumerate() {
            for &i in &plane.inliers {
                self.owner[i as usize] = k as u16;
            }
        }
        for (k, plane) in self.planes.iter().enumerate() {
            for &i in &plane.inliers {
                let p = to_vec3(&cloud.points[i as usize]);
                let mut best = (plane.plane.signed_distance(&p).abs(), k);
                for (j, other) in self.planes.iter().enumerate() {
                    if j == k {
                        continue;
                    }
                    let d = other.plane.signed_distance(&p).abs();
                    if d < best.0 && d <= t.at(&p) {
                        best = (d, j);
                    }
                }
                if best.1 != k {
                    self.owner[i as usize] = best.1 as u16;
                    changed = true;
                }
            }
        }
        if !changed {
            return;
        }
        for plane in &mut self.planes {
            plane.inliers.clear();
        }
        for (i, &o) in self.owner.iter().enumerate() {
            if o != NO_PLANE {
                self.planes[o as usize].inliers.push(i as u32);
            }
        }
        for plane in &mut self.planes {
            let mut m = Moments::new();
            for &i in &plane.inliers {
                m.add(&to_vec3(&cloud.points[i as usize]));
            }
            if let (Some(fitted), Some(c)) = (fit_tls(&m), m.mean()) {
                plane.plane = fitted.oriented_towards(&Vector3::zeros());
                plane.centroid = c;
            }
        }
        self.planes.retain(|p| p.inliers.len() >= 3);
    }
}

/// The inlier distance at a point: `max(base, per_m2 * z^2)`.
#[derive(Debug, Clone, Copy)]
struct Threshold {
    base_m: f64,
    per_m2: f64,
}

impl Threshold {
    #[inline]
    fn at(&self, p: &Vector3<f64>) -> f64 {
        self.base_m.max(self.per_m2 * p.z * p.z)
    }
}

/// Refits `plane` by TLS on its inliers among `subset` and rescores it,
/// while the inlier count grows (at most `LO_STEPS` times).
fn local_optimisation(
    score: usize,
    plane: Plane,
    xyz: &[Vector3<f64>],
    normals: &[Vector3<f64>],
    subset: &[u32],
    t: Threshold,
    cos_gate: Option<f64>,
) -> (usize, Plane) {
    let mut best = (score, plane);
    for _ in 0..LO_STEPS {
        let mut m = Moments::new();
        for &k in subset {
            let k = k as usize;
            if is_inlier(&best.1, &xyz[k], &normals[k], t, cos_gate) {
                m.add(&xyz[k]);
            }
        }
        let Some(refit) = fit_tls(&m) else {
            break;
        };
        let count = subset
            .iter()
            .filter(|&&k| is_inlier(&refit, &xyz[k as usize], &normals[k as usize], t, cos_gate))
            .count();
        if count <= best.0 {
            break;
        }
        best = (count, refit);
    }
    best
}

#[inline]
fn is_inlier(
    plane: &Plane,
    p: &Vector3<f64>,
    n: &Vector3<f64>,
    t: Threshold,
    cos_gate: Option<f64>,
) -> bool {
    if plane.signed_distance(p).abs() > t.at(p) {
        return false;
    }
    match cos_gate {
        // A point without a normal counts on distance alone.
        Some(cg) if n.x.is_finite() => n.dot(&plane.normal).abs() >= cg,
        _ => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::angle_between_deg;
    use crate::fixtures::{Scene, SceneCloud};
    use rand::SeedableRng;

    fn segment(scene: &Scene, sigma: f64) -> (SceneCloud, Vec<SegmentedPlane>) {
        let cloud = SceneCloud::render(scene, 256, 212, sigma, 2);
        let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
        let mut seg = PlaneSegmenter::new();
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let cfg = RansacConfig {
            min_plane_points: 200,
            ..RansacConfig::default()
        };
        let planes = seg.segment(&cloud.view(), &keep, &cfg, &mut rng).to_vec();
        (cloud, planes)
    }

    #[test]
    fn finds_ground_and_ramp_of_exact_geometry() {
        let scene = Scene::ramp(16.0);
        let (cloud, planes) = segment(&scene, 0.0);
        assert!(planes.len() >= 2, "{}", planes.len());
        let up = scene.to_camera(&Vector3::z());
        let ramp = scene.to_camera(&scene.surfaces[1].normal);
        let ground = planes
            .iter()
            .find(|p| angle_between_deg(&p.plane.normal, &up) < 0.01);
        let incl = planes
            .iter()
            .find(|p| angle_between_deg(&p.plane.normal, &ramp) < 0.01);
        let (ground, incl) = (ground.expect("ground"), incl.expect("ramp"));
        // Ground: n.p + d = 0 with d = camera height.
        assert!((ground.plane.d - 0.5).abs() < 1e-4, "{}", ground.plane.d);
        // Every measured point belongs to exactly one of the two.
        let measured = cloud.points.iter().filter(|p| p.is_valid()).count();
        assert_eq!(ground.inliers.len() + incl.inliers.len(), measured);
        for &i in &ground.inliers {
            let p = to_vec3(&cloud.points[i as usize]);
            assert!(
                ground.plane.signed_distance(&p).abs()
                    <= incl.plane.signed_distance(&p).abs() + 1e-9
            );
        }
    }

    #[test]
    fn noisy_planes_keep_their_orientation() {
        let scene = Scene::ramp_between_walls(12.5);
        let (_, planes) = segment(&scene, 0.0015);
        let ramp = scene.to_camera(&scene.surfaces[1].normal);
        let up = scene.to_camera(&Vector3::z());
        assert!(planes
            .iter()
            .any(|p| angle_between_deg(&p.plane.normal, &ramp) < 0.3));
        assert!(planes
            .iter()
            .any(|p| angle_between_deg(&p.plane.normal, &up) < 0.3));
        for wall in [&scene.surfaces[2], &scene.surfaces[3]] {
            let n = scene.to_camera(&wall.normal);
            assert!(
                planes
                    .iter()
                    .any(|p| angle_between_deg(&p.plane.normal, &n) < 1.0),
                "wall {n:?} not found"
            );
        }
        for p in &planes {
            assert!(p.plane.d >= 0.0, "normal must face the camera");
        }
    }

    #[test]
    fn empty_input_gives_no_plane() {
        let scene = Scene::ramp(5.0);
        let cloud = SceneCloud::render(&scene, 32, 24, 0.0, 1);
        let keep = vec![false; cloud.points.len()];
        let mut seg = PlaneSegmenter::new();
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        assert!(seg
            .segment(&cloud.view(), &keep, &RansacConfig::default(), &mut rng)
            .is_empty());
        assert!(seg
            .segment(&cloud.view(), &[], &RansacConfig::default(), &mut rng)
            .is_empty());
    }
}
