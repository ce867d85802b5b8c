//! Stage 2, RANSAC plane segmentation (paper 2.2 and 3): find the plane with
//! the most inliers (points within the distance threshold), take its inliers
//! out, repeat until the rest is smaller than a threshold or the last plane
//! was too small.
//!
//! **Shortcut: planes are found on a grid subsample, pixels labelled once.**
//! The paper (like PCL's `SACSegmentation` on the filtered cloud) scores
//! every hypothesis against every point, once per extracted plane. Here the
//! whole extraction loop runs on a regular subsample of the pixel grid
//! (every `sample_stride_px`-th pixel in both directions, ~13,500 points of
//! a Kinect v2 frame at stride 4; the paper itself downsamples before
//! segmentation); after it, one pass over the full-resolution cloud gives
//! every pixel to the nearest of the planes that took the sample points
//! around it (its 3x3 neighbourhood on the sample grid), when within the
//! threshold, and refits each plane by TLS on all of its pixels. The inlier
//! count of a plane on a uniform grid subsample is proportional to its full
//! count, so the largest plane is the same plane, and the final planes are
//! fitted on every point. Cost: ~13,500 points per extraction instead of
//! ~200,000, and one full-resolution pass instead of one per plane.
//!
//! Within the loop, per plane:
//!
//! - *Hypotheses* are scored on a stratified 2,000-point subset of the
//!   sample, visited in a scrambled order so that the 100-point pretest
//!   (a hypothesis scoring under half the best rate there is dropped) covers
//!   the whole image. Every other hypothesis is one sample point and its
//!   coarse normal (a plane holding a share w of the points is hit with
//!   probability w, not w^3: five parallel stair risers); the others are
//!   three points. Each new best is locally optimised (LO-RANSAC: TLS refit
//!   on its inliers, rescored, while the score grows). At least 64
//!   hypotheses, more until the adaptive count for `confidence` is reached.
//! - *Normals gate the inliers* (as PCL's `SACSegmentationFromNormals`):
//!   each sample point carries a coarse normal: the cross product of the
//!   central differences two pixels left/right and up/down (the PCA of
//!   every other pixel of its 5x5 window where one of the four is missing
//!   or across a depth edge); a three-point
//!   hypothesis whose points disagree with it, or a sample point more than
//!   `normal_threshold_deg` off, is not an inlier. A plane that merely
//!   slices through the edges of a staircase does not win.
//! - *A plane is one connected surface*: its sample inliers' largest
//!   8-connected region on the sample grid is refitted alone, and that fit's
//!   largest region (distance only: the coarse normals of a Kinect v1 wall
//!   at 5 m are noise) is the plane. Coplanar pieces elsewhere (a floor on
//!   both sides of a cabinet that hides the link) stay free.
//! - Too small a region (fewer cells than `min_plane_points` pixels): its
//!   sample inliers are dropped and the loop tries again, up to 8 times.
//!
//! The inlier distance is
//! `max(distance_threshold_m, distance_threshold_per_m2 * z^2)`: depth
//! noise and quantisation grow with z^2 (a Kinect v1
//! quantises 5 m into 7 cm terraces, where a fixed 2 cm threshold picks
//! single terraces). A pixel within the threshold of two planes goes to the
//! nearer one: where the normal gate cannot tell two planes apart (a
//! shallow ramp) the plane found first takes sample cells of the other
//! along their junction, so before the pixels are labelled each cell moves
//! to a neighbouring cell's plane while that plane is strictly nearer to
//! its point (the first-found plane does not keep a strip of its
//! neighbour).

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
    /// Pixel indices of the inliers, in pixel order.
    pub inliers: Vec<u32>,
    /// Mean of the inliers.
    pub centroid: Vector3<f64>,
    /// RMS distance of the inliers from `plane`, metres.
    pub rms_m: f64,
}

/// Reusable buffers of the segmentation.
#[derive(Debug, Default, Clone)]
pub struct PlaneSegmenter {
    /// Free sample points: coordinates and coarse normal (NaN if unknown).
    sample_xyz: Vec<Vector3<f64>>,
    sample_normal: Vec<Vector3<f64>>,
    sample_pixel: Vec<u32>,
    sample_with_normal: Vec<u32>,
    /// The sample grid: per coarse cell, the index of its free sample point
    /// or `NO_SAMPLE`; a component label per cell during labelling; and the
    /// plane that took the cell's sample point (`NO_PLANE` if none).
    coarse: Vec<u32>,
    coarse_label: Vec<u32>,
    cell_plane: Vec<u16>,
    /// Per coarse cell: the distinct planes of the 3x3 cells around it.
    cell_candidates: Vec<([u16; 9], u8)>,
    /// Per coarse cell: its sample point (NaN if none).
    cell_point: Vec<Vector3<f64>>,
    in_work: Vec<bool>,
    column_cell: Vec<usize>,
    coarse_w: usize,
    coarse_h: usize,
    stride: usize,
    stack: Vec<u32>,
    region_sizes: Vec<usize>,
    /// Coarse cells of the last largest region.
    region: Vec<u32>,
    score_subset: Vec<u32>,
    planes: Vec<SegmentedPlane>,
    moments: Vec<Moments>,
}

const NO_PLANE: u16 = u16::MAX;
const NO_SAMPLE: u32 = u32::MAX;
/// Hypotheses whose largest region is too small before segmentation stops.
const MAX_FAILURES: usize = 8;
/// Plane labels are `u16` (`NO_PLANE` excluded).
pub const MAX_PLANES: usize = NO_PLANE as usize;

impl PlaneSegmenter {
    pub fn new() -> Self {
        Self::default()
    }

    /// The planes of the last [`Self::segment`] call, in the order they
    /// were found (largest first, up to the final relabelling).
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
        let Some(n) = w.checked_mul(h) else {
            return &self.planes;
        };
        if cloud.points.len() != n || keep.len() != n || n >= NO_SAMPLE as usize {
            return &self.planes;
        }
        self.load_sample(cloud, keep, config);
        self.cell_plane.clear();
        self.cell_plane
            .resize(self.coarse_w * self.coarse_h, NO_PLANE);
        let total = self.sample_xyz.len();
        // A plane's sample region must stand for `min_plane_points` pixels.
        let s2 = (self.stride as f64).powi(2);
        let min_cells = ((config.min_plane_points as f64 / s2).ceil() as usize).max(3);
        let mut failures = 0;
        let t = Threshold::of(config);
        let cos_gate = if config.normal_threshold_deg > 0.0 && config.normal_threshold_deg < 90.0 {
            Some(config.normal_threshold_deg.to_radians().cos())
        } else {
            None
        };
        let mut found: Vec<Plane> = Vec::new();
        while found.len() < config.max_planes.min(MAX_PLANES)
            && self.sample_xyz.len() >= 3
            && (self.sample_xyz.len() as f64) >= config.min_remaining_fraction * total as f64
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
            // The largest 8-connected region of its sample inliers on the
            // sample grid, refitted alone (without the pull of other pieces
            // in the same plane), collects its region once more.
            let region = self
                .largest_sample_region(&plane, t, cos_gate)
                .and_then(|refit| self.largest_sample_region(&refit, t, None));
            let Some(plane_fit) = region.filter(|_| self.region.len() >= min_cells) else {
                // Too small (or only scattered pieces): these sample points
                // cannot seed a plane; drop them and try again a few times.
                failures += 1;
                if failures > MAX_FAILURES {
                    break;
                }
                for j in 0..self.sample_xyz.len() {
                    if is_inlier(
                        &plane,
                        &self.sample_xyz[j],
                        &self.sample_normal[j],
                        t,
                        cos_gate,
                    ) {
                        self.sample_pixel[j] = NO_SAMPLE;
                    }
                }
                self.compact_sample(w);
                continue;
            };
            // Take the region's cells out of the sample.
            let label = found.len() as u16;
            for &c in &self.region {
                self.cell_plane[c as usize] = label;
                let j = self.coarse[c as usize] as usize;
                self.sample_pixel[j] = NO_SAMPLE;
            }
            self.compact_sample(w);
            tracing::trace!(
                plane = found.len(),
                cells = self.region.len(),
                normal = ?plane_fit.normal,
                "ransac plane"
            );
            found.push(plane_fit);
        }
        // A plane found first took the sample cells of its neighbour along
        // their junction where the normal gate could not tell them apart (a
        // shallow ramp): give each cell to the nearer of the planes around
        // it, then every kept pixel to the nearest (within the threshold) of
        // the planes that took the sample cells around it, and refit.
        self.relax_cells(&found, t);
        self.label_pixels(cloud, keep, &found, t);
        for (k, m) in self.moments.iter().enumerate() {
            if let Some(fitted) = fit_tls(m) {
                found[k] = fitted;
            }
        }
        for (k, plane) in self.planes.iter_mut().enumerate() {
            let m = &self.moments[k];
            plane.plane = found[k].oriented_towards(&Vector3::zeros());
            plane.centroid = m.mean().unwrap_or_else(Vector3::zeros);
            plane.rms_m = rms_distance(m, &plane.plane);
        }
        self.planes
            .retain(|p| p.inliers.len() >= config.min_plane_points.max(3));
        &self.planes
    }

    /// Moves each taken cell to a plane of a neighbouring cell (8-connected)
    /// while its sample point is strictly nearer to that plane and within
    /// the threshold. Each move brings a point strictly nearer to its
    /// plane, so it ends; a coplanar piece elsewhere is never adjacent.
    fn relax_cells(&mut self, found: &[Plane], t: Threshold) {
        let (cw, ch) = (self.coarse_w, self.coarse_h);
        let neighbours = |c: usize| cell_neighbourhood(c, cw, ch);
        // Work list: the cells on a border between two planes, then the
        // neighbours of every cell that moved.
        self.stack.clear();
        self.in_work.clear();
        self.in_work.resize(cw * ch, false);
        for c in 0..cw * ch {
            let a = self.cell_plane[c];
            if a != NO_PLANE
                && neighbours(c).any(|q| {
                    let b = self.cell_plane[q];
                    b != NO_PLANE && b != a
                })
            {
                self.stack.push(c as u32);
                self.in_work[c] = true;
            }
        }
        while let Some(c) = self.stack.pop() {
            let c = c as usize;
            self.in_work[c] = false;
            let a = self.cell_plane[c];
            let p = self.cell_point[c];
            let limit = t.at(&p);
            let mut best = (found[a as usize].signed_distance(&p).abs(), a);
            for q in neighbours(c) {
                let b = self.cell_plane[q];
                if b == NO_PLANE || b == best.1 {
                    continue;
                }
                let d = found[b as usize].signed_distance(&p).abs();
                if d < best.0 && d <= limit {
                    best = (d, b);
                }
            }
            if best.1 != a {
                self.cell_plane[c] = best.1;
                for q in neighbours(c) {
                    if self.cell_plane[q] != NO_PLANE && !self.in_work[q] {
                        self.in_work[q] = true;
                        self.stack.push(q as u32);
                    }
                }
            }
        }
    }

    /// Gives every kept, measured pixel to the plane nearest to it among
    /// those that took one of the (up to 3x3) sample points around it, if
    /// within the threshold; fills `planes[k].inliers` (pixel order) and
    /// `moments[k]`.
    fn label_pixels(
        &mut self,
        cloud: &CloudView<'_>,
        keep: &[bool],
        found: &[Plane],
        t: Threshold,
    ) {
        let (w, h) = (cloud.width, cloud.height);
        let (s, half) = (self.stride, self.stride / 2);
        let (cw, ch) = (self.coarse_w, self.coarse_h);
        if found.is_empty() || cw == 0 || ch == 0 {
            self.planes.clear();
            self.moments.clear();
            return;
        }
        self.planes.resize_with(found.len(), || SegmentedPlane {
            plane: found[0],
            inliers: Vec::new(),
            centroid: Vector3::zeros(),
            rms_m: 0.0,
        });
        self.moments.clear();
        self.moments.resize(found.len(), Moments::new());
        // Per coarse cell, the distinct planes of the 3x3 cells around it.
        self.cell_candidates.clear();
        for c in 0..cw * ch {
            let mut set = ([NO_PLANE; 9], 0u8);
            for q in cell_neighbourhood(c, cw, ch) {
                let k = self.cell_plane[q];
                if k != NO_PLANE && !set.0[..set.1 as usize].contains(&k) {
                    set.0[set.1 as usize] = k;
                    set.1 += 1;
                }
            }
            self.cell_candidates.push(set);
        }
        // The sample column of every pixel column (no division per pixel).
        self.column_cell.clear();
        self.column_cell
            .extend((0..w).map(|u| (u.saturating_sub(half) / s).min(cw - 1)));
        for v in 0..h {
            let row = (v.saturating_sub(half) / s).min(ch - 1) * cw;
            for (u, &column) in self.column_cell.iter().enumerate() {
                let i = v * w + u;
                let (candidates, n) = &self.cell_candidates[row + column];
                let n = *n as usize;
                if n == 0 || !keep[i] || !is_measured(&cloud.points[i]) {
                    continue;
                }
                let p = to_vec3(&cloud.points[i]);
                let limit = t.at(&p);
                let mut best: Option<(f64, u16)> = None;
                for &k in &candidates[..n] {
                    let d = found[k as usize].signed_distance(&p).abs();
                    if d <= limit && best.is_none_or(|(bd, _)| d < bd) {
                        best = Some((d, k));
                    }
                }
                if let Some((_, k)) = best {
                    self.planes[k as usize].inliers.push(i as u32);
                    self.moments[k as usize].add(&p);
                }
            }
        }
    }

    /// Drops the sample points whose pixel was set to `NO_SAMPLE` and
    /// rebuilds the sample grid.
    fn compact_sample(&mut self, w: usize) {
        let mut k = 0;
        for j in 0..self.sample_xyz.len() {
            if self.sample_pixel[j] != NO_SAMPLE {
                self.sample_xyz[k] = self.sample_xyz[j];
                self.sample_normal[k] = self.sample_normal[j];
                self.sample_pixel[k] = self.sample_pixel[j];
                k += 1;
            }
        }
        self.sample_xyz.truncate(k);
        self.sample_normal.truncate(k);
        self.sample_pixel.truncate(k);
        self.coarse.clear();
        self.coarse.resize(self.coarse_w * self.coarse_h, NO_SAMPLE);
        let (s, half) = (self.stride, self.stride / 2);
        for (j, &p) in self.sample_pixel.iter().enumerate() {
            let (u, v) = (p as usize % w, p as usize / w);
            self.coarse[(v - half) / s * self.coarse_w + (u - half) / s] = j as u32;
        }
    }

    /// Fills `region` with the coarse cells of the largest 8-connected
    /// region (on the sample grid) of the sample inliers of `plane`; returns
    /// the TLS plane of that region's sample points.
    fn largest_sample_region(
        &mut self,
        plane: &Plane,
        t: Threshold,
        cos_gate: Option<f64>,
    ) -> Option<Plane> {
        let (cw, ch) = (self.coarse_w, self.coarse_h);
        const UNLABELLED: u32 = u32::MAX;
        const OUTSIDE: u32 = u32::MAX - 1;
        self.coarse_label.clear();
        self.coarse_label.extend(self.coarse.iter().map(|&j| {
            if j != NO_SAMPLE
                && is_inlier(
                    plane,
                    &self.sample_xyz[j as usize],
                    &self.sample_normal[j as usize],
                    t,
                    cos_gate,
                )
            {
                UNLABELLED
            } else {
                OUTSIDE
            }
        }));
        self.region_sizes.clear();
        for seed in 0..cw * ch {
            if self.coarse_label[seed] != UNLABELLED {
                continue;
            }
            let label = self.region_sizes.len() as u32;
            let mut size = 0;
            self.coarse_label[seed] = label;
            self.stack.clear();
            self.stack.push(seed as u32);
            while let Some(c) = self.stack.pop() {
                size += 1;
                for q in cell_neighbourhood(c as usize, cw, ch) {
                    if self.coarse_label[q] == UNLABELLED {
                        self.coarse_label[q] = label;
                        self.stack.push(q as u32);
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
        self.region.clear();
        let mut moments = Moments::new();
        for (c, &label) in self.coarse_label.iter().enumerate() {
            if Some(label) == largest {
                self.region.push(c as u32);
                moments.add(&self.sample_xyz[self.coarse[c] as usize]);
            }
        }
        fit_tls(&moments)
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
                    central_difference_normal(cloud, keep, u, v, radius)
                        .or_else(|| grid_normal(cloud, keep, u, v, radius, 2))
                        .unwrap_or_else(|| Vector3::repeat(f64::NAN))
                } else {
                    Vector3::repeat(f64::NAN)
                };
                self.sample_xyz.push(to_vec3(&cloud.points[i]));
                self.sample_normal.push(n);
                self.sample_pixel.push(i as u32);
            }
        }
        self.stride = s;
        self.coarse_w = w.saturating_sub(s / 2).div_ceil(s);
        self.coarse_h = h.saturating_sub(s / 2).div_ceil(s);
        self.compact_sample(w);
        // Every cell's sample point, kept after the point leaves the sample.
        self.cell_point.clear();
        self.cell_point
            .resize(self.coarse_w * self.coarse_h, Vector3::repeat(f64::NAN));
        for (&c, p) in self.coarse.iter().zip(&mut self.cell_point) {
            if c != NO_SAMPLE {
                *p = self.sample_xyz[c as usize];
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
        let t = Threshold::of(config);
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
}

/// The normal at pixel `(u, v)` from the cross product of the central
/// differences `r` pixels left/right and up/down, towards the camera; `None`
/// when one of the four is missing or more than a few pixel spacings away in
/// 3D (a depth edge: then the PCA window decides).
fn central_difference_normal(
    cloud: &CloudView<'_>,
    keep: &[bool],
    u: usize,
    v: usize,
    r: usize,
) -> Option<Vector3<f64>> {
    let (w, h) = (cloud.width, cloud.height);
    if u < r || v < r || u + r >= w || v + r >= h {
        return None;
    }
    let centre = to_vec3(&cloud.points[v * w + u]);
    let reach = 8.0 * r as f64 * centre.z.abs() / cloud.focal_px();
    let at = |i: usize| {
        let p = cloud.points.get(i).filter(|p| keep[i] && is_measured(p))?;
        let p = to_vec3(p);
        ((p - centre).norm_squared() <= reach * reach).then_some(p)
    };
    let dx = at(v * w + u + r)? - at(v * w + u - r)?;
    let dy = at((v + r) * w + u)? - at((v - r) * w + u)?;
    let n = dx.cross(&dy).try_normalize(1e-12)?;
    Some(if n.dot(&centre) > 0.0 { -n } else { n })
}

/// Cell `c` and its 8-connected neighbours on a `cw x ch` grid.
fn cell_neighbourhood(c: usize, cw: usize, ch: usize) -> impl Iterator<Item = usize> {
    let (cu, cv) = (c % cw, c / cw);
    (cv.saturating_sub(1)..(cv + 2).min(ch))
        .flat_map(move |r| (cu.saturating_sub(1)..(cu + 2).min(cw)).map(move |q| r * cw + q))
}

/// RMS distance from `plane` of the points summed in `moments` (0 if none).
fn rms_distance(moments: &Moments, plane: &Plane) -> f64 {
    moments.covariance().map_or(0.0, |c| {
        let n = plane.normal;
        (n.dot(&(c * n))).max(0.0).sqrt()
    })
}

/// The inlier distance at a point: `max(base, per_m2 * z^2)`.
#[derive(Debug, Clone, Copy)]
pub struct Threshold {
    base_m: f64,
    per_m2: f64,
}

impl Threshold {
    /// The threshold of `config`.
    pub fn of(config: &RansacConfig) -> Self {
        Self {
            base_m: config.distance_threshold_m,
            per_m2: config.distance_threshold_per_m2,
        }
    }

    /// The inlier distance at point `p`, metres.
    #[inline]
    pub fn at(&self, p: &Vector3<f64>) -> f64 {
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

    /// The planes of `cloud`'s valid points.
    fn segment_cloud(cloud: &SceneCloud, cfg: &RansacConfig, seed: u64) -> Vec<SegmentedPlane> {
        let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
        PlaneSegmenter::new()
            .segment(
                &cloud.view(),
                &keep,
                cfg,
                &mut ChaCha8Rng::seed_from_u64(seed),
            )
            .to_vec()
    }

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
    fn a_plane_is_one_connected_region() {
        // A wall 2 m ahead split by a 12-pixel gap without readings into a
        // wide left piece and a narrow right piece: the same plane equation,
        // but two regions; the first plane is the wide piece alone, the
        // second the narrow one, and no pixel is in both.
        let scene = Scene::wall_facing(2.0);
        let mut cloud = SceneCloud::render(&scene, 256, 212, 0.001, 3);
        let (w, gap) = (cloud.width, 160..172);
        for (i, p) in cloud.points.iter_mut().enumerate() {
            if gap.contains(&(i % w)) {
                *p = slope_ipc_types::CloudPoint::INVALID;
            }
        }
        let cfg = RansacConfig {
            min_plane_points: 200,
            ..RansacConfig::default()
        };
        let planes = segment_cloud(&cloud, &cfg, 1);
        assert_eq!(planes.len(), 2, "{planes:?}");
        let left = |p: &SegmentedPlane| p.inliers.iter().all(|&i| (i as usize % w) < gap.start);
        let right = |p: &SegmentedPlane| p.inliers.iter().all(|&i| (i as usize % w) >= gap.end);
        assert!(left(&planes[0]) && right(&planes[1]));
        let measured = cloud.points.iter().filter(|p| p.is_valid()).count();
        assert_eq!(planes[0].inliers.len() + planes[1].inliers.len(), measured);
        for p in &planes {
            assert!(angle_between_deg(&p.plane.normal, &Vector3::new(0.0, 0.0, -1.0)) < 0.5);
            assert!(p.rms_m < 0.01, "{}", p.rms_m);
        }
    }

    #[test]
    fn tiny_images_and_oversized_strides_give_no_plane_and_no_panic() {
        let scene = Scene::ramp(16.0);
        for (w, h) in [(1, 1), (2, 2), (3, 1), (1, 7)] {
            let cloud = SceneCloud::render(&scene, w, h, 0.0, 1);
            let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
            for stride in [1, 2, 4, 5, 1000, usize::MAX] {
                let cfg = RansacConfig {
                    sample_stride_px: stride,
                    min_plane_points: 3,
                    ..RansacConfig::default()
                };
                let mut seg = PlaneSegmenter::new();
                let planes = seg.segment(
                    &cloud.view(),
                    &keep,
                    &cfg,
                    &mut ChaCha8Rng::seed_from_u64(0),
                );
                assert!(
                    planes.iter().all(|p| p.inliers.len() >= 3),
                    "{w}x{h} stride {stride}"
                );
            }
        }
        // A full frame with a stride larger than the image.
        let cloud = SceneCloud::render(&scene, 128, 106, 0.0, 1);
        let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
        let cfg = RansacConfig {
            sample_stride_px: 848,
            ..RansacConfig::default()
        };
        assert!(PlaneSegmenter::new()
            .segment(
                &cloud.view(),
                &keep,
                &cfg,
                &mut ChaCha8Rng::seed_from_u64(0)
            )
            .is_empty());
    }

    #[test]
    fn junction_pixels_go_to_the_nearer_plane_on_a_shallow_ramp() {
        // A 5 degree ramp: the 30 degree normal gate cannot tell the ground
        // from the ramp, so the plane found first reaches into the other
        // along their junction; after segmentation no pixel may be nearer
        // (and within the threshold) to another plane than to its own,
        // beyond what the final refit moves.
        let scene = Scene::ramp(5.0);
        let cloud = SceneCloud::kinect2(&scene, 2);
        let cfg = RansacConfig::default();
        let planes = segment_cloud(&cloud, &cfg, 1);
        assert!(planes.len() >= 2, "{}", planes.len());
        let t = Threshold::of(&cfg);
        // Per plane: pixels nearer (and within the threshold of) another
        // plane than their own.
        let misplaced: Vec<usize> = planes
            .iter()
            .enumerate()
            .map(|(k, plane)| {
                plane
                    .inliers
                    .iter()
                    .filter(|&&i| {
                        let p = to_vec3(&cloud.points[i as usize]);
                        let own = plane.plane.signed_distance(&p).abs();
                        planes.iter().enumerate().any(|(j, o)| {
                            let d = o.plane.signed_distance(&p).abs();
                            j != k && d < own && d <= t.at(&p)
                        })
                    })
                    .count()
            })
            .collect();
        // What is left comes from the refit after labelling and falls on
        // both sides alike; the first plane keeping its neighbour's strip
        // is one-sided (before the cell relaxation: [3494, 0] here).
        let (a, b) = (misplaced[0], misplaced[1]);
        assert!(
            a.max(b) <= 4 * a.min(b) + 100,
            "one-sided: {misplaced:?} of {:?}",
            planes.iter().map(|p| p.inliers.len()).collect::<Vec<_>>()
        );
        let total: usize = planes.iter().map(|p| p.inliers.len()).sum();
        assert!(a + b < total / 50, "{misplaced:?} of {total}");
    }

    #[test]
    fn central_difference_normals_are_exact_on_planes_and_refuse_edges() {
        // A 16 degree ramp without noise: every sample point with its four
        // neighbours on one plane gets that plane's normal, facing the
        // camera; at the image border and across the ground/ramp crease
        // the difference is refused or still on a plane.
        let scene = Scene::ramp(16.0);
        let cloud = SceneCloud::render_with_intrinsics(&scene, 128, 106, 90.0, 0.0, 1);
        let view = cloud.view();
        let keep: Vec<bool> = cloud.points.iter().map(|p| p.is_valid()).collect();
        let normals = [
            scene.to_camera(&Vector3::z()),
            scene.to_camera(&scene.surfaces[1].normal),
        ];
        let mut exact = 0;
        for v in 0..cloud.height {
            for u in 0..cloud.width {
                let Some(n) = central_difference_normal(&view, &keep, u, v, 2) else {
                    continue;
                };
                assert!(u >= 2 && v >= 2 && u + 2 < cloud.width && v + 2 < cloud.height);
                let p = to_vec3(&cloud.points[v * cloud.width + u]);
                assert!(n.dot(&p) < 0.0, "faces the camera");
                if normals.iter().any(|m| angle_between_deg(&n, m) < 0.05) {
                    exact += 1;
                }
            }
        }
        // All but the 2-pixel image border and the rows along the crease
        // (f32 coordinates: exact to a few thousandths of a degree).
        let measured = keep.iter().filter(|&&k| k).count();
        assert!(exact * 100 > measured * 85, "{exact} of {measured}");
        // A point whose neighbour is a metre behind it (a depth edge).
        let mut edged = cloud.points.clone();
        let (u, v) = (64, 80);
        edged[v * cloud.width + u + 2].z_m += 1.0;
        let edged_view = CloudView {
            points: &edged,
            ..cloud.view()
        };
        assert!(central_difference_normal(&edged_view, &keep, u, v, 2).is_none());
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
