//! Stage 4, normal estimation (paper 2.3): each point's normal is the
//! smallest-eigenvalue eigenvector of the covariance of its K = 100 nearest
//! neighbours, oriented so that `n . (V - p) > 0` for the viewpoint V.
//!
//! **Shortcut.** The paper (PCL/Open3D) queries a k-d tree for the K nearest
//! neighbours of each of up to 10,000 points of a plane and builds each
//! covariance from them: 50-100 ms per plane. The plane's points come from
//! an organised cloud, so its neighbourhoods are pixel windows: we mark the
//! plane's pixels on the grid, build summed-area tables of the ten moments
//! (count, x, y, z, xx, xy, xz, yy, yz, zz; coordinates centred on the plane
//! so nothing cancels) over the plane's bounding box, and read the
//! covariance of any window in O(1). Each point takes the smallest square
//! window that holds at least K of the plane's points *and* spans the patch
//! radius on the surface (below), growing it near holes and edges up to
//! `max_window_radius_px`; only a point that still has fewer than K falls
//! back to the exact K nearest from a kiddo k-d tree over the plane's points
//! (and not even that when only interior normals are kept, as by default:
//! such a point is no interior point). On a plane, a window of >= K samples
//! around the point and the K nearest samples are two patches of the same
//! surface, so the fitted normal is the same plane normal with (at least)
//! the same noise averaging. The 3x3 eigenvector comes from the closed-form
//! solver in `plane_fit.rs` (checked against nalgebra's symmetric
//! eigen-decomposition in the tests), for the windows with the smallest
//! eigenvalue by Newton's method instead of `acos`/`cos` (`eigen.rs`; the
//! same vector to rounding, tested). The table is built in one pass, each
//! cell written once.
//!
//! **Table cells of 2 x 2 pixels.** A table of ten `f64` per pixel is 80
//! bytes a pixel, 12-17 MB for a floor: building and reading it is bound by
//! memory bandwidth, not arithmetic. Its cells are blocks of
//! [`TABLE_CELL_PX`] x [`TABLE_CELL_PX`] pixels (a quarter of the memory),
//! so a window's edges fall on even pixel offsets from the plane's
//! bounding box: the window of radius r around a pixel holds the blocks
//! that its `2r + 1` pixels touch, up to one pixel more on a side, off
//! centre by at most one pixel. On a plane that moves nothing (a window is
//! a patch of the same surface either way); the patch radius (below) is
//! 5-30 pixels. The brute-force k-d tree comparison below holds as before.
//!
//! **Patch radius.** K = 100 is a minimum. The smallest eigenvector is the
//! least-squares plane for *isotropic* noise; a depth camera's noise runs
//! along the viewing ray, and on a patch of radius r it tilts the
//! eigenvector by about `2 (sigma / r)^2` radians (sigma the noise normal to
//! the surface): on the K = 100 patch of a Kinect v2 (2-3 cm across) that is
//! 2-5 degrees on the grazing ground of `slope-synth` recordings, and
//! averaging angles does not remove a bias. So the patch spans at least
//! `min_patch_radius_m` (10 cm) and at least `patch_per_rms` (20) times the
//! plane's own RMS residual about its TLS fit (`NormalsConfig::
//! for_plane_noise`; the residual holds depth noise, quantisation and real
//! roughness together, measured on the frame, for any sensor): the bias
//! stays near 0.3 degrees. A Kinect v1 wall at 5 m (7 cm disparity
//! terraces, RMS ~3 cm) gets ~60 cm patches, a Kinect v2 floor at 2 m the
//! 10 cm minimum. Summed-area tables make the patch size free.
//!
//! **Noise model (`ray_noise_correction`, off by default).** The alternative
//! to a large patch: with points `p = q + e r` (q on the plane, e the depth
//! error along the unit ray r, variance s^2) the covariance is
//! `C = C_q + s^2 r r^T`, so subtracting the expected `s^2 r r^T` before
//! taking the smallest eigenvector gives the plane's own covariance `C_q`.
//! The noise is the Kinect v2 axial model of Fankhauser et al. (2015),
//! `sigma_z = 1.5 - 0.5 z + 0.3 z^2 + 0.1 z^1.5 t^2 / (pi/2 - t)^2` mm at depth
//! z m and incidence t (from the uncorrected normal), plus millimetre depth
//! quantisation, plus 0.5 px of lateral jitter, along the ray
//! `s = sigma_z / r_z`; never subtracted beyond the point where
//! `C - s^2 r r^T` turns singular. It is exact on the simulator's noise
//! (tested) but tied to one sensor model: on real frames (libfreenect2's
//! filtered Kinect v2 depth, a Kinect v1) it over-corrected by 1-3 degrees,
//! which is why the measured patch radius replaced it.
//!
//! One concern per file: `window_table.rs` (the summed-area tables and the
//! window search), `window_pass.rs` (each member's window and normal, in
//! chunks on the worker threads when there are workers), `window_cache.rs`
//! (one eigenvector per distinct window), `support.rs` (the support's
//! bounds and centre, walked once, by the pass-through when it runs first),
//! `tree.rs` (the k-d tree fallback), `eigen.rs` (the windows' eigenvector
//! solver), `ray_noise.rs` (the optional noise correction), `grid.rs` (the
//! coarse normals that gate RANSAC), `config.rs` ([`NormalsConfig`]).

use nalgebra::Vector3;

use crate::cloud::{is_measured, CloudView};
use crate::plane_fit::smallest_eigenvector_3x3;
use window_pass::{WindowChunk, WindowPass, CHUNK};

mod config;
mod eigen;
mod grid;
mod ray_noise;
mod support;
mod tree;
mod window_cache;
mod window_pass;
mod window_table;

pub use config::NormalsConfig;
pub(crate) use grid::grid_normal;
pub use ray_noise::{ray_noise_model, ray_noise_variance};
pub use support::{PlaneSupport, SupportWalk};

/// How the normals of one call were found.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NormalStats {
    /// Points whose neighbourhood was a pixel window.
    pub from_window: usize,
    /// Points that needed the k-d tree.
    pub from_tree: usize,
    /// Points without a defined normal (degenerate neighbourhood).
    pub undefined: usize,
    /// Border points whose normal was dropped (`interior_only`).
    pub border: usize,
}

const CHANNELS: usize = 10;

/// Pixels per side of a summed-area table cell (module doc).
pub const TABLE_CELL_PX: usize = 2;

/// The moments one point adds to a neighbourhood's sums, relative to a
/// reference point: count, first and second moments
/// (1, x, y, z, xx, xy, xz, yy, yz, zz).
#[inline]
fn moments(q: &Vector3<f64>) -> [f64; CHANNELS] {
    [
        1.0,
        q.x,
        q.y,
        q.z,
        q.x * q.x,
        q.x * q.y,
        q.x * q.z,
        q.y * q.y,
        q.y * q.z,
        q.z * q.z,
    ]
}

/// Reusable buffers of the normal estimation.
#[derive(Debug, Default, Clone)]
pub struct NormalEstimator {
    table: Vec<[f64; CHANNELS]>,
    /// The support's measured pixels in pixel order, and one row of block
    /// sums.
    order: Vec<u32>,
    block_row: Vec<[f64; CHANNELS]>,
    normals: Vec<Vector3<f64>>,
    radius: Vec<u16>,
    fallback: Vec<usize>,
    /// The window pass's chunks (one without workers), each with its own
    /// cache of one normal per distinct window (`window_pass.rs`).
    chunks: Vec<WindowChunk>,
    /// With `threads` > 1: the estimator's worker threads, which pass the
    /// chunks at once.
    workers: Option<std::sync::Arc<rayon::ThreadPool>>,
}

/// Pixel bounding box `[u0, u1) x [v0, v1)`.
#[derive(Debug, Clone, Copy)]
struct Bounds {
    u0: usize,
    v0: usize,
    width: usize,
    height: usize,
}

impl NormalEstimator {
    pub fn new() -> Self {
        Self::default()
    }

    /// Threads the window pass may use (`None`: the caller's alone); the
    /// normals are the same, bit for bit, either way.
    pub fn set_workers(&mut self, workers: Option<std::sync::Arc<rayon::ThreadPool>>) {
        self.workers = workers;
    }

    /// Normals of the points `members` (pixel indices into `cloud`, one
    /// plane's points), each from its neighbours among `members`. The result
    /// is aligned with `members`; an entry is NaN when the point has no
    /// reading or its neighbourhood is degenerate (every entry for a view of
    /// width 0).
    pub fn estimate(
        &mut self,
        cloud: &CloudView<'_>,
        members: &[u32],
        config: &NormalsConfig,
        viewpoint: &Vector3<f64>,
    ) -> (&[Vector3<f64>], NormalStats) {
        self.estimate_with_support(cloud, members, members, config, viewpoint)
    }

    /// As [`Self::estimate`], but the neighbourhoods are drawn from
    /// `support` (all of the plane's points) while normals are computed for
    /// `members` only (a subsample of the plane): each evaluated point keeps
    /// its full, dense neighbourhood however sparsely the points to
    /// evaluate were picked. A member outside `support`'s bounding box gets
    /// its neighbours from the k-d tree over `support`.
    pub fn estimate_with_support(
        &mut self,
        cloud: &CloudView<'_>,
        members: &[u32],
        support: &[u32],
        config: &NormalsConfig,
        viewpoint: &Vector3<f64>,
    ) -> (&[Vector3<f64>], NormalStats) {
        // The measured support pixels in pixel order, with their bounds
        // and centre; the k-d tree takes `support` as given.
        let mut order = std::mem::take(&mut self.order);
        order.clear();
        let walked = SupportWalk::new(cloud.width).and_then(|mut walk| {
            for &pixel in support {
                if let Some(p) = cloud.points.get(pixel as usize).filter(|p| is_measured(p)) {
                    walk.add(pixel as usize, p);
                    order.push(pixel);
                }
            }
            if !order.is_sorted() {
                order.sort_unstable();
            }
            walk.finish(&order)
        });
        let stats = self.estimate_walked(cloud, members, walked, support, config, viewpoint);
        self.order = order;
        (&self.normals, stats)
    }

    /// As [`Self::estimate_with_support`] with the support already walked
    /// (by the pass-through, `pass_through.rs`): the same normals, bit for
    /// bit, without a second walk over the plane's points.
    pub fn estimate_on_plane(
        &mut self,
        cloud: &CloudView<'_>,
        members: &[u32],
        support: &PlaneSupport<'_>,
        config: &NormalsConfig,
        viewpoint: &Vector3<f64>,
    ) -> (&[Vector3<f64>], NormalStats) {
        let stats = self.estimate_walked(
            cloud,
            members,
            Some(*support),
            support.pixels,
            config,
            viewpoint,
        );
        (&self.normals, stats)
    }

    /// The normals of `members` from the tables over `walked` (none: every
    /// normal undefined), the k-d tree fallback over `tree_support`.
    fn estimate_walked(
        &mut self,
        cloud: &CloudView<'_>,
        members: &[u32],
        walked: Option<PlaneSupport<'_>>,
        tree_support: &[u32],
        config: &NormalsConfig,
        viewpoint: &Vector3<f64>,
    ) -> NormalStats {
        self.reset(members.len());
        let mut stats = NormalStats::default();
        let Some(support) = walked else {
            stats.undefined = members.len();
            return stats;
        };
        let (bounds, centre) = (support.bounds, support.centre);
        self.build_table(cloud, support.pixels, &bounds, &centre);
        let noise_scale = if config.ray_noise_correction {
            1.0
        } else {
            0.0
        };
        // The table is read by the chunks while the estimator's other
        // buffers take their results.
        let table = std::mem::take(&mut self.table);
        let pass = WindowPass {
            cloud,
            table: &table,
            bounds,
            config,
            centre,
            noise_scale,
            viewpoint: *viewpoint,
        };
        self.pass_windows(pass, members, &mut stats);
        self.table = table;
        // Interior points only: a point the windows could not serve is no
        // interior point, so when the interior normals will be kept alone
        // the k-d tree is not built for the others.
        let k = config.neighbours.max(3);
        let interior = self.radius.iter().filter(|&&r| r == 0).count();
        let interior_only = config.interior_only && interior >= k.max(members.len() / 10);
        if interior_only {
            stats.border += self.fallback.len();
            self.fallback.clear();
        }
        if !self.fallback.is_empty() {
            stats.from_tree = self.fallback.len();
            stats.undefined +=
                self.tree_normals(cloud, members, tree_support, k, viewpoint, noise_scale);
        }
        if interior_only {
            stats.border += self.drop_border_normals();
        }
        stats
    }

    /// Empties the per-call buffers and sizes them for `members` members:
    /// every normal NaN, every radius unknown, every window empty.
    fn reset(&mut self, members: usize) {
        self.normals.clear();
        self.normals.resize(members, Vector3::repeat(f64::NAN));
        self.fallback.clear();
        self.radius.clear();
        self.radius.resize(members, u16::MAX);
    }

    /// Runs the window pass over `members`: in chunks on the workers when
    /// there are workers and more than one chunk, else as one chunk; then
    /// gathers the chunks' fallbacks (in member order) and counts.
    fn pass_windows(&mut self, pass: WindowPass<'_>, members: &[u32], stats: &mut NormalStats) {
        let pool = self.workers.as_deref();
        let size = match pool {
            Some(_) => CHUNK,
            None => members.len().max(1),
        };
        let count = members.len().div_ceil(size);
        if self.chunks.len() < count {
            self.chunks.resize_with(count, WindowChunk::default);
        }
        let jobs = members
            .chunks(size)
            .zip(self.radius.chunks_mut(size))
            .zip(self.normals.chunks_mut(size))
            .zip(&mut self.chunks)
            .enumerate();
        let run =
            move |(j, (((members, radius), normals), chunk)): (usize, (_, &mut WindowChunk))| {
                pass.run((members, j * size), radius, normals, chunk);
            };
        match pool {
            Some(pool) if count > 1 => pool.scope(|scope| {
                for job in jobs {
                    scope.spawn(move |_| run(job));
                }
            }),
            _ => jobs.for_each(run),
        }
        self.fallback.clear();
        for chunk in &self.chunks[..count] {
            self.fallback.extend_from_slice(&chunk.fallback);
            stats.from_window += chunk.stats.from_window;
            stats.undefined += chunk.stats.undefined;
        }
    }

    /// Sets the normals of the points that are not interior (whose first
    /// window did not suffice) to NaN; returns how many defined ones it
    /// dropped.
    fn drop_border_normals(&mut self) -> usize {
        let nan = Vector3::repeat(f64::NAN);
        let mut dropped = 0;
        for (n, &r) in self.normals.iter_mut().zip(&self.radius) {
            if r != 0 && n.x.is_finite() {
                *n = nan;
                dropped += 1;
            }
        }
        dropped
    }
}

/// The normal of a neighbourhood from its raw moment sums
/// `[n, x, y, z, xx, xy, xz, yy, yz, zz]` of coordinates relative to
/// `origin` (camera frame, viewpoint at the camera centre): the smallest
/// eigenvector, or with `ray_noise` the direction `C^-1 r` (module doc).
#[inline]
pub(crate) fn normal_from_sums(
    m: &[f64; CHANNELS],
    origin: &Vector3<f64>,
    noise_scale: f64,
    focal_px: f64,
) -> Option<Vector3<f64>> {
    normal_from_sums_by(m, origin, noise_scale, focal_px, smallest_eigenvector_3x3)
}

/// As [`normal_from_sums`], the smallest eigenvector from `solve`.
#[inline]
fn normal_from_sums_by(
    m: &[f64; CHANNELS],
    origin: &Vector3<f64>,
    noise_scale: f64,
    focal_px: f64,
    solve: impl Fn(&[f64; 6]) -> Option<Vector3<f64>>,
) -> Option<Vector3<f64>> {
    let n = m[0];
    if n < 3.0 {
        return None;
    }
    let (mx, my, mz) = (m[1] / n, m[2] / n, m[3] / n);
    let cov = [
        m[4] / n - mx * mx,
        m[5] / n - mx * my,
        m[6] / n - mx * mz,
        m[7] / n - my * my,
        m[8] / n - my * mz,
        m[9] / n - mz * mz,
    ];
    let pca = solve(&cov)?;
    if !(noise_scale > 0.0) {
        return Some(pca);
    }
    let mean = origin + Vector3::new(mx, my, mz);
    let Some(ray) = mean.try_normalize(1e-12) else {
        return Some(pca);
    };
    let s2 = ray_noise_variance(&cov, &ray, mean.z, &pca, focal_px, noise_scale);
    if !(s2 > 0.0) {
        return Some(pca);
    }
    let corrected = [
        cov[0] - s2 * ray.x * ray.x,
        cov[1] - s2 * ray.x * ray.y,
        cov[2] - s2 * ray.x * ray.z,
        cov[3] - s2 * ray.y * ray.y,
        cov[4] - s2 * ray.y * ray.z,
        cov[5] - s2 * ray.z * ray.z,
    ];
    Some(solve(&corrected).unwrap_or(pca))
}

/// Flips `n` so that `n . (viewpoint - p) > 0`.
#[inline]
pub fn orient(n: Vector3<f64>, p: &Vector3<f64>, viewpoint: &Vector3<f64>) -> Vector3<f64> {
    if n.dot(&(viewpoint - p)) < 0.0 {
        -n
    } else {
        n
    }
}

#[cfg(test)]
mod tests;
