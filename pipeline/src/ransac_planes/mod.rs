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
//!
//! One concern per file: `sample.rs` (the sample grid and its coarse
//! normals), `sample_axis.rs` (which pixels are sample points, and which
//! pixels each stands for: symmetric under a mirror), `points.rs` (the `f32` structure of arrays and the inlier
//! test the inner loops run), `hypotheses.rs` (drawing, scoring, local
//! optimisation), `regions.rs` (the largest connected region),
//! `labelling.rs` (cell relaxation and the full-resolution labelling).

use std::sync::Arc;

use nalgebra::Vector3;
use rand_chacha::ChaCha8Rng;

use crate::cloud::{CloudView, PixelBox};
use crate::plane_fit::{fit_tls, MomentSums, Moments, Plane};
use crate::segmentation::Proposal;

mod config;
mod hypotheses;
mod labelling;
mod points;
mod regions;
mod sample;
mod sample_axis;

pub use config::RansacConfig;
use points::{Gate, Points};
use sample::SampleGrid;
pub use sample_axis::SampleAxis;

/// One segmented plane.
#[derive(Debug, Clone)]
pub struct SegmentedPlane {
    /// TLS fit of all inliers, normal towards the camera (origin).
    pub plane: Plane,
    /// Pixel indices of the inliers, in pixel order.
    pub inliers: Vec<u32>,
    /// The inliers' pixel bounding box, when the segmentation knows it
    /// (the labelling pass): then every inlier has a reading (three finite
    /// coordinates) at a depth other than 0, and the pass-through and the
    /// normals take the box instead of walking the inliers for it.
    pub pixel_box: Option<PixelBox>,
    /// Mean of the inliers.
    pub centroid: Vector3<f64>,
    /// RMS distance of the inliers from `plane`, metres.
    pub rms_m: f64,
    /// Moments of the inliers (`plane` is their TLS fit).
    pub moments: Moments,
}

/// What a plane proposal sees of the sample grid (every
/// `sample_stride_px`-th pixel in both directions, counted from the nearer
/// edge: [`SampleAxis`]), and where it says which plane takes each sample
/// cell.
#[derive(Debug)]
pub struct SampleCells<'a> {
    /// Sample cells per row and per column.
    pub width: usize,
    pub height: usize,
    /// Pixels between sample points.
    pub stride: usize,
    /// The sample columns and rows, and the pixels each stands for.
    pub columns: &'a SampleAxis,
    pub rows: &'a SampleAxis,
    /// Per sample cell (raster order): its kept sample point, NaN if none.
    pub points: &'a [Vector3<f64>],
    /// Per sample cell: the index of the proposed plane that takes it,
    /// [`NO_PLANE`] for none (all [`NO_PLANE`] on entry). Every kept pixel
    /// then goes to the nearest of the planes of the 3x3 sample cells
    /// around it, within the threshold.
    pub labels: &'a mut [u16],
    /// The estimator's worker threads, if any, for the proposal's own
    /// banded passes (which must give the same bits with or without them).
    pub workers: Option<&'a rayon::ThreadPool>,
}

/// A way of proposing the planes of a frame on the sample grid, in place
/// of the sequential extraction ([`PlaneSegmenter::segment_proposed`]).
pub trait PlaneProposal {
    /// The planes of the kept pixels (largest first), each owning the
    /// sample cells labelled with its index in `cells.labels`.
    fn propose(
        &mut self,
        cloud: &CloudView<'_>,
        keep: &[bool],
        cells: SampleCells<'_>,
        config: &RansacConfig,
        rng: &mut ChaCha8Rng,
    ) -> Vec<Plane>;
}

/// Reusable buffers of the segmentation.
#[derive(Debug, Default, Clone)]
pub struct PlaneSegmenter {
    /// The sample grid and its free points.
    sample: SampleGrid,
    /// The score subset of the current extraction, contiguous; filled only
    /// when there are more than `SCORE_POINTS` (2000) free points, else
    /// hypotheses are scored on the free points themselves.
    score: Points,
    /// Free points a hypothesis may be drawn from.
    pool: Vec<u32>,
    /// The score subset's indices into the free points; filled, like
    /// `score`, only when there are more than `SCORE_POINTS` free points.
    indices: Vec<u32>,
    /// Per free point: inlier of the plane at hand.
    flags: Vec<bool>,
    /// Per coarse cell: a component label during region search, and the
    /// plane that took the cell's sample point (`NO_PLANE` if none).
    coarse_label: Vec<u32>,
    cell_plane: Vec<u16>,
    /// Per coarse cell: the distinct planes of the 3x3 cells around it.
    cell_candidates: Vec<([u16; 9], u8)>,
    in_work: Vec<bool>,
    stack: Vec<u32>,
    /// The cells the relaxation moved.
    moved: Vec<u32>,
    /// Region search: the inliers' cells, and (after the search) the
    /// largest region's cells, sorted.
    seeds: Vec<u32>,
    region: Vec<u32>,
    planes: Vec<SegmentedPlane>,
    sums: Vec<MomentSums>,
    moments: Vec<Moments>,
    /// The labelling pass's bands of rows.
    bands: Vec<labelling::LabelBand>,
    /// With `threads` > 1: the estimator's worker threads, which label the
    /// bands at once.
    workers: Option<Arc<rayon::ThreadPool>>,
}

/// The label of a sample cell no plane took.
pub const NO_PLANE: u16 = u16::MAX;
/// Hypotheses whose largest region is too small before segmentation stops.
const MAX_FAILURES: usize = 8;
/// Plane labels are `u16` (`NO_PLANE` excluded).
pub const MAX_PLANES: usize = NO_PLANE as usize;

impl PlaneSegmenter {
    pub fn new() -> Self {
        Self::default()
    }

    /// Threads the labelling pass may use (`None`: the caller's alone);
    /// the planes are the same, bit for bit, either way.
    pub fn set_workers(&mut self, workers: Option<Arc<rayon::ThreadPool>>) {
        self.workers = workers;
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
        if !self.fits(cloud, keep) {
            self.planes.clear();
            return &self.planes;
        }
        let cos_gate = normal_gate(config);
        self.load_sample(cloud, keep, config, cos_gate);
        let total = self.sample.points.len();
        let cap = config.plane_cap(Proposal::Sequential.max_planes());
        let found = self.extract_planes(config, (cos_gate.is_some(), total, cap), rng, Vec::new());
        self.finish(cloud, keep, config, found)
    }

    /// Segments the points marked in `keep` into the planes `proposal`
    /// proposes on the sample grid (instead of the sequential extraction),
    /// then labels the pixels and refits as [`Self::segment`] does.
    pub fn segment_proposed<P: PlaneProposal>(
        &mut self,
        cloud: &CloudView<'_>,
        keep: &[bool],
        config: &RansacConfig,
        proposal: &mut P,
        rng: &mut ChaCha8Rng,
    ) -> &[SegmentedPlane] {
        if !self.fits(cloud, keep) {
            self.planes.clear();
            return &self.planes;
        }
        let cos_gate = normal_gate(config);
        self.load_sample(cloud, keep, config, cos_gate);
        let total = self.sample.points.len();
        let cells = SampleCells {
            width: self.sample.coarse_w,
            height: self.sample.coarse_h,
            stride: self.sample.stride,
            columns: &self.sample.columns,
            rows: &self.sample.rows,
            points: &self.sample.cell_point,
            labels: &mut self.cell_plane,
            workers: self.workers.as_deref(),
        };
        let mut found = proposal.propose(cloud, keep, cells, config, rng);
        found.truncate(config.plane_cap(Proposal::Cells.max_planes()));
        for label in &mut self.cell_plane {
            if *label as usize >= found.len() {
                *label = NO_PLANE;
            }
        }
        // What the proposal left (thin structures no cell is planar on: a
        // table's legs and edge) goes to the sequential extraction.
        self.region.clear();
        self.region.extend(
            (0..self.cell_plane.len() as u32).filter(|&c| self.cell_plane[c as usize] != NO_PLANE),
        );
        self.sample.remove_cells(&self.region);
        self.drop_points_on(&found);
        let cap = config.plane_cap(Proposal::Cells.max_planes());
        let found = self.extract_planes(config, (cos_gate.is_some(), total, cap), rng, found);
        self.finish(cloud, keep, config, found)
    }

    /// Whether `cloud` and `keep` describe one frame the sample grid can
    /// index (`u32` cells).
    fn fits(&self, cloud: &CloudView<'_>, keep: &[bool]) -> bool {
        cloud.width.checked_mul(cloud.height).is_some_and(|n| {
            cloud.points.len() == n && keep.len() == n && n < sample::NO_SAMPLE as usize
        })
    }

    /// Fills the sample grid (coarse normals when `cos_gate` is set) and
    /// frees every cell.
    fn load_sample(
        &mut self,
        cloud: &CloudView<'_>,
        keep: &[bool],
        config: &RansacConfig,
        cos_gate: Option<f64>,
    ) {
        self.sample
            .load(cloud, keep, config, cos_gate, self.workers.as_deref());
        self.cell_plane.clear();
        self.cell_plane
            .resize(self.sample.coarse_w * self.sample.coarse_h, NO_PLANE);
    }

    /// The extraction loop on the free sample points: planes one after
    /// another (after those `found` already), each the largest connected
    /// region of the best hypothesis's inliers, until fewer than
    /// `min_remaining_fraction` of the `total` sample points are free or
    /// `cap` planes are found.
    fn extract_planes(
        &mut self,
        config: &RansacConfig,
        (gated, total, cap): (bool, usize, usize),
        rng: &mut ChaCha8Rng,
        mut found: Vec<Plane>,
    ) -> Vec<Plane> {
        // A plane's sample region must stand for `min_plane_points` pixels.
        let s2 = (self.sample.stride as f64).powi(2);
        let min_cells = ((config.min_plane_points as f64 / s2).ceil() as usize).max(3);
        let mut failures = 0;
        while found.len() < cap
            && self.sample.points.len() >= 3
            && (self.sample.points.len() as f64) >= config.min_remaining_fraction * total as f64
        {
            let Some(plane) = self.best_hypothesis(config, gated, rng) else {
                break;
            };
            let plane = self.refine_on_sample(plane);
            // The largest 8-connected region of its sample inliers on the
            // sample grid, refitted alone (without the pull of other pieces
            // in the same plane), collects its region once more.
            let region = self
                .largest_sample_region(&plane, Gate::Normals)
                .and_then(|refit| self.largest_sample_region(&refit, Gate::DistanceOnly));
            let Some(plane_fit) = region.filter(|_| self.region.len() >= min_cells) else {
                // Too small (or only scattered pieces): these sample points
                // cannot seed a plane; drop them and try again a few times.
                failures += 1;
                if failures > MAX_FAILURES {
                    break;
                }
                self.drop_sample_inliers(&plane);
                continue;
            };
            self.take_region(found.len() as u16);
            tracing::trace!(
                plane = found.len(),
                cells = self.region.len(),
                normal = ?plane_fit.normal,
                "ransac plane"
            );
            found.push(plane_fit);
        }
        found
    }

    /// `plane` refined on the sample: the TLS fit of its sample inliers,
    /// twice (or fewer times, while a fit exists).
    fn refine_on_sample(&self, mut plane: Plane) -> Plane {
        for _ in 0..2 {
            match fit_tls(&self.sample.points.inlier_moments(&plane)) {
                Some(refined) => plane = refined,
                None => break,
            }
        }
        plane
    }

    /// Drops the (normal-gated) sample inliers of `plane` from the sample:
    /// they could not seed a plane.
    fn drop_sample_inliers(&mut self, plane: &Plane) {
        self.sample
            .points
            .inlier_flags(plane, Gate::Normals, &mut self.flags);
        self.sample.remove(&self.flags);
    }

    /// Drops the free sample points within the inlier distance of any of
    /// `planes` (pieces of those planes that no region reached: a floor
    /// beyond a cabinet), so that the extraction after a proposal finds
    /// only what no proposed plane explains.
    fn drop_points_on(&mut self, planes: &[Plane]) {
        let mut drop = std::mem::take(&mut self.in_work);
        drop.clear();
        drop.resize(self.sample.points.len(), false);
        for plane in planes {
            self.sample
                .points
                .inlier_flags(plane, Gate::DistanceOnly, &mut self.flags);
            for (d, &f) in drop.iter_mut().zip(&self.flags) {
                *d |= f;
            }
        }
        self.sample.remove(&drop);
        self.in_work = drop;
    }

    /// Gives the cells of `region` to plane `label` and takes them out of
    /// the sample.
    fn take_region(&mut self, label: u16) {
        for &c in &self.region {
            self.cell_plane[c as usize] = label;
        }
        self.sample.remove_cells(&self.region);
    }

    /// A plane found first took the sample cells of its neighbour along
    /// their junction where the normal gate could not tell them apart (a
    /// shallow ramp): give each cell to the nearer of the planes around it,
    /// then every kept pixel to the nearest (within the threshold) of the
    /// planes that took the sample cells around it, and refit.
    fn finish(
        &mut self,
        cloud: &CloudView<'_>,
        keep: &[bool],
        config: &RansacConfig,
        mut found: Vec<Plane>,
    ) -> &[SegmentedPlane] {
        let t = Threshold::of(config);
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
            plane.moments = *m;
        }
        self.planes
            .retain(|p| p.inliers.len() >= config.min_plane_points.max(3));
        &self.planes
    }
}

/// The cosine of the coarse-normal gate, `None` when off.
fn normal_gate(config: &RansacConfig) -> Option<f64> {
    (config.normal_threshold_deg > 0.0 && config.normal_threshold_deg < 90.0)
        .then(|| config.normal_threshold_deg.to_radians().cos())
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

    /// The inlier distance at point `p`, metres. (`base_m.max(z_term)`,
    /// written as the comparison that is one instruction, also two lanes
    /// at a time: the same value, as the base is a number; a NaN z gives
    /// the base.)
    #[inline]
    pub fn at(&self, p: &Vector3<f64>) -> f64 {
        let z_term = self.per_m2 * p.z * p.z;
        if z_term > self.base_m {
            z_term
        } else {
            self.base_m
        }
    }
}

#[cfg(test)]
mod tests;
