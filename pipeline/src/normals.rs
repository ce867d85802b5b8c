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
//! eigen-decomposition in the tests). The table is built in one pass, each
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

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::Vector3;

use crate::cloud::{is_measured, to_vec3, CloudView};
use crate::plane_fit::smallest_eigenvector_3x3;
use crate::validate::{at_least, non_negative, InvalidValue};
use serde::{Deserialize, Serialize};

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
    /// The support's pixels in pixel order, and one row of block sums.
    order: Vec<u32>,
    block_row: Vec<[f64; CHANNELS]>,
    normals: Vec<Vector3<f64>>,
    radius: Vec<u16>,
    fallback: Vec<usize>,
    /// Window moment sums per member (count 0: no window).
    sums: Vec<[f64; CHANNELS]>,
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
        self.reset(members.len());
        let mut stats = NormalStats::default();
        let Some((bounds, centre)) = bounds_and_centre(cloud, support) else {
            stats.undefined = members.len();
            return (&self.normals, stats);
        };
        self.build_table(cloud, support, &bounds, &centre);
        self.find_windows(cloud, members, &bounds, config, &mut stats);
        let noise_scale = if config.ray_noise_correction {
            1.0
        } else {
            0.0
        };
        self.window_normals(cloud, members, &centre, noise_scale, viewpoint, &mut stats);
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
                self.tree_normals(cloud, members, support, k, viewpoint, noise_scale);
        }
        if interior_only {
            stats.border += self.drop_border_normals();
        }
        (&self.normals, stats)
    }

    /// Empties the per-call buffers and sizes them for `members` members:
    /// every normal NaN, every radius unknown, every window empty.
    fn reset(&mut self, members: usize) {
        self.normals.clear();
        self.normals.resize(members, Vector3::repeat(f64::NAN));
        self.fallback.clear();
        self.radius.clear();
        self.radius.resize(members, u16::MAX);
        self.sums.clear();
        self.sums.resize(members, [0.0; CHANNELS]);
    }

    /// For each member, the moment sums of its smallest window (from the
    /// table over `bounds`) that holds K points and spans the patch radius,
    /// into `sums`, and how far it had to grow, into `radius`; a member
    /// outside the bounds or without such a window goes to `fallback`.
    fn find_windows(
        &mut self,
        cloud: &CloudView<'_>,
        members: &[u32],
        bounds: &Bounds,
        config: &NormalsConfig,
        stats: &mut NormalStats,
    ) {
        let w = cloud.width;
        let k = config.neighbours.max(3);
        let focal = cloud.focal_px();
        let r0 = start_radius(k);
        let r_max = config.max_window_radius_px.max(r0);
        let g = TABLE_CELL_PX;
        let cells = (bounds.width.div_ceil(g), bounds.height.div_ceil(g));
        for (slot, &pixel) in members.iter().enumerate() {
            let pixel = pixel as usize;
            let Some(p) = cloud.points.get(pixel).filter(|p| is_measured(p)) else {
                stats.undefined += 1;
                continue;
            };
            let (Some(u), Some(v)) = (
                (pixel % w)
                    .checked_sub(bounds.u0)
                    .filter(|&u| u < bounds.width),
                (pixel / w)
                    .checked_sub(bounds.v0)
                    .filter(|&v| v < bounds.height),
            ) else {
                self.fallback.push(slot);
                continue;
            };
            self.radius[slot] = u16::MAX;
            // The patch spans at least `min_patch_radius_m` on the surface.
            let metric = (config.min_patch_radius_m * focal / f64::from(p.z_m).max(1e-3)).ceil();
            let r_start = if metric.is_finite() {
                (metric as usize).clamp(r0, r_max.max(r0))
            } else {
                r0
            };
            match smallest_window(&self.table, cells, (u, v), r_start..=r_max, k) {
                Some((m, r)) => {
                    stats.from_window += 1;
                    // 0: the first window sufficed (an interior point).
                    self.radius[slot] = (r - r_start) as u16;
                    self.sums[slot] = m;
                }
                None => self.fallback.push(slot),
            }
        }
    }

    /// The oriented normal of each member with a window, from its sums
    /// (coordinates relative to `centre`); a degenerate window counts as
    /// undefined.
    fn window_normals(
        &mut self,
        cloud: &CloudView<'_>,
        members: &[u32],
        centre: &Vector3<f64>,
        noise_scale: f64,
        viewpoint: &Vector3<f64>,
        stats: &mut NormalStats,
    ) {
        let focal = cloud.focal_px();
        for (slot, &pixel) in members.iter().enumerate() {
            let m = &self.sums[slot];
            if m[0] < 0.5 {
                continue;
            }
            let Some(p) = cloud.point(pixel as usize) else {
                continue;
            };
            if let Some(n) = normal_from_sums(m, centre, noise_scale, focal) {
                self.normals[slot] = orient(n, &p, viewpoint);
            } else {
                stats.undefined += 1;
            }
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

    /// Summed-area tables of the ten moments over the bounding box, one
    /// cell per `TABLE_CELL_PX` x `TABLE_CELL_PX` block of pixels.
    fn build_table(
        &mut self,
        cloud: &CloudView<'_>,
        members: &[u32],
        b: &Bounds,
        c: &Vector3<f64>,
    ) {
        let g = TABLE_CELL_PX;
        let (bw, bh) = (b.width.div_ceil(g), b.height.div_ceil(g));
        let tw = bw + 1;
        // The members' moments summed per block, a row of blocks at a
        // time; members in pixel order (as inliers are) need no sort.
        self.order.clear();
        self.order.extend_from_slice(members);
        if !self.order.is_sorted() {
            self.order.sort_unstable();
        }
        self.block_row.clear();
        self.block_row.resize(bw, [0.0; CHANNELS]);
        // One pass, row by row: each cell is written once.
        self.table.clear();
        self.table.reserve(tw * (bh + 1));
        self.table
            .extend(std::iter::repeat_n([0.0; CHANNELS], tw + 1));
        let mut next = 0;
        for bv in 0..bh {
            self.sum_block_row(cloud, b, c, bv, &mut next);
            let mut run = [0.0; CHANNELS];
            for bu in 0..bw {
                let above = &self.table[bv * tw + bu + 1];
                let mut cell = [0.0; CHANNELS];
                for ch in 0..CHANNELS {
                    run[ch] += self.block_row[bu][ch];
                    cell[ch] = run[ch] + above[ch];
                }
                self.table.push(cell);
            }
            if bv + 1 < bh {
                self.table.push([0.0; CHANNELS]);
            }
        }
    }

    /// The moments (relative to `c`) of the sorted members in the pixel
    /// rows of block row `bv`, summed per block into `block_row`; `next`
    /// is the first member not yet summed, and moves past these rows.
    fn sum_block_row(
        &mut self,
        cloud: &CloudView<'_>,
        b: &Bounds,
        c: &Vector3<f64>,
        bv: usize,
        next: &mut usize,
    ) {
        let g = TABLE_CELL_PX;
        let w = cloud.width;
        self.block_row.fill([0.0; CHANNELS]);
        // The pixel rows of this row of blocks, walked without a
        // division per pixel; a block's sum is kept in registers while
        // consecutive pixels fall into it.
        for v in b.v0 + bv * g..(b.v0 + (bv + 1) * g).min(b.v0 + b.height) {
            let row_start = v * w;
            let mut current: Option<(usize, [f64; CHANNELS])> = None;
            while let Some(&pixel) = self
                .order
                .get(*next)
                .filter(|&&p| (p as usize) < row_start + w)
            {
                *next += 1;
                let pixel = pixel as usize;
                let (Some(u), Some(p)) = (
                    pixel.checked_sub(row_start + b.u0).filter(|&u| u < b.width),
                    cloud.points.get(pixel).filter(|p| is_measured(p)),
                ) else {
                    continue;
                };
                let block = u / g;
                if let Some((at, sums)) = current.filter(|(at, _)| *at != block) {
                    add_into(&mut self.block_row[at], &sums);
                    current = None;
                }
                let sums = &mut current.get_or_insert((block, [0.0; CHANNELS])).1;
                for (s, x) in sums.iter_mut().zip(moments(&(to_vec3(p) - c))) {
                    *s += x;
                }
            }
            if let Some((at, sums)) = current {
                add_into(&mut self.block_row[at], &sums);
            }
        }
    }

    /// Exact K nearest neighbours from a k-d tree for the points the windows
    /// could not serve; returns how many stayed undefined.
    fn tree_normals(
        &mut self,
        cloud: &CloudView<'_>,
        members: &[u32],
        support: &[u32],
        k: usize,
        viewpoint: &Vector3<f64>,
        noise_scale: f64,
    ) -> usize {
        let mut entries: Vec<[f64; 3]> = Vec::with_capacity(support.len());
        let mut entry_point: Vec<Vector3<f64>> = Vec::with_capacity(support.len());
        for &pixel in support {
            if let Some(p) = cloud.point(pixel as usize) {
                entries.push([p.x, p.y, p.z]);
                entry_point.push(p);
            }
        }
        let (Some(k_nz), Ok(tree)) = (
            std::num::NonZero::new(k.min(entries.len())),
            ImmutableKdTree::<f64, 3>::new_from_slice(&entries),
        ) else {
            return self.fallback.len();
        };
        let mut undefined = 0;
        for &slot in &self.fallback {
            let Some(p) = cloud.point(members[slot] as usize) else {
                undefined += 1;
                continue;
            };
            let nn = tree
                .query(&[p.x, p.y, p.z])
                .nearest_n::<SquaredEuclidean<f64>>(k_nz)
                .execute();
            let mut m = [0.0; CHANNELS];
            for n in &nn {
                let Some(q) = entry_point.get(n.item as usize) else {
                    continue;
                };
                let q = q - p;
                let row = moments(&q);
                for (mc, r) in m.iter_mut().zip(row) {
                    *mc += r;
                }
            }
            match normal_from_sums(&m, &p, noise_scale, cloud.focal_px()) {
                Some(n) => self.normals[slot] = orient(n, &p, viewpoint),
                None => undefined += 1,
            }
        }
        undefined
    }
}

/// `into += from`, channel by channel.
#[inline]
fn add_into(into: &mut [f64; CHANNELS], from: &[f64; CHANNELS]) {
    for (a, b) in into.iter_mut().zip(from) {
        *a += b;
    }
}

/// Smallest radius whose square window holds K pixels.
fn start_radius(k: usize) -> usize {
    let mut r = 1;
    while (2 * r + 1) * (2 * r + 1) < k {
        r += 1;
    }
    r
}

/// The moment sums of the smallest window around table pixel `(u, v)`,
/// its radius tried from `radii` in turn, that holds at least `k` points,
/// and that radius; `None` when none does (or the window covers the whole
/// table of `cells` = (columns, rows) before). A window holds the table
/// cells its pixels touch.
#[inline]
fn smallest_window(
    table: &[[f64; CHANNELS]],
    (bw, bh): (usize, usize),
    (u, v): (usize, usize),
    radii: std::ops::RangeInclusive<usize>,
    k: usize,
) -> Option<([f64; CHANNELS], usize)> {
    let g = TABLE_CELL_PX;
    let tw = bw + 1;
    for r in radii {
        // The table cells the window's pixels touch.
        let (a0, a1) = (u.saturating_sub(r) / g, ((u + r) / g + 1).min(bw));
        let (b0, b1) = (v.saturating_sub(r) / g, ((v + r) / g + 1).min(bh));
        let s = |c: usize| {
            table[b1 * tw + a1][c] - table[b0 * tw + a1][c] - table[b1 * tw + a0][c]
                + table[b0 * tw + a0][c]
        };
        let count = s(0);
        if count + 0.5 >= k as f64 {
            let mut m = [0.0; CHANNELS];
            for (c, mc) in m.iter_mut().enumerate() {
                *mc = s(c);
            }
            return Some((m, r));
        }
        if a0 == 0 && b0 == 0 && a1 == bw && b1 == bh {
            break;
        }
    }
    None
}

/// Bounding box of the members' pixels and their centroid.
fn bounds_and_centre(cloud: &CloudView<'_>, members: &[u32]) -> Option<(Bounds, Vector3<f64>)> {
    let w = cloud.width;
    if w == 0 {
        // No pixel grid (a malformed view): no pixel has a place in it.
        return None;
    }
    let (mut u0, mut v0, mut u1, mut v1) = (usize::MAX, usize::MAX, 0, 0);
    let mut sum = Vector3::zeros();
    let mut count = 0usize;
    for &pixel in members {
        let pixel = pixel as usize;
        let Some(p) = cloud.point(pixel) else {
            continue;
        };
        let (u, v) = (pixel % w, pixel / w);
        u0 = u0.min(u);
        v0 = v0.min(v);
        u1 = u1.max(u);
        v1 = v1.max(v);
        sum += p;
        count += 1;
    }
    (count > 0).then(|| {
        (
            Bounds {
                u0,
                v0,
                width: u1 - u0 + 1,
                height: v1 - v0 + 1,
            },
            sum / count as f64,
        )
    })
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
    let pca = smallest_eigenvector_3x3(&cov)?;
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
    Some(smallest_eigenvector_3x3(&corrected).unwrap_or(pca))
}

/// Lateral jitter of the depth reading, pixels.
const LATERAL_JITTER_PX: f64 = 0.5;

/// Variance of the depth noise along the unit `ray` to subtract from the
/// covariance `cov` of a patch at depth `z_m` with (uncorrected) unit normal
/// `normal`, seen through a camera of focal length `focal_px`: the Kinect v2
/// model, capped below the variance that would make `cov - s^2 r r^T`
/// singular.
pub fn ray_noise_variance(
    cov: &[f64; 6],
    ray: &Vector3<f64>,
    z_m: f64,
    normal: &Vector3<f64>,
    focal_px: f64,
    scale: f64,
) -> f64 {
    let model = scale * ray_noise_model(ray, z_m, normal, focal_px);
    if !(model > 0.0) {
        return 0.0;
    }
    // 1 / r^T C^-1 r, through the adjugate: det / (r^T adj r).
    let [a, b, c, d, e, f] = *cov;
    let adj = [
        d * f - e * e,
        c * e - b * f,
        b * e - c * d,
        a * f - c * c,
        b * c - a * e,
        a * d - b * b,
    ];
    let det = a * adj[0] + b * adj[1] + c * adj[2];
    let quad = ray.x * (adj[0] * ray.x + adj[1] * ray.y + adj[2] * ray.z)
        + ray.y * (adj[1] * ray.x + adj[3] * ray.y + adj[4] * ray.z)
        + ray.z * (adj[2] * ray.x + adj[4] * ray.y + adj[5] * ray.z);
    if !(det > 0.0) || !(quad > 0.0) {
        return 0.0;
    }
    let cap = det / quad;
    model.min(0.95 * cap)
}

/// Variance of the modelled depth noise along the unit `ray` (before any
/// cap) of a patch at depth `z_m` with unit normal `normal`: the Kinect v2
/// axial model, mm quantisation and lateral jitter (module doc).
pub fn ray_noise_model(ray: &Vector3<f64>, z_m: f64, normal: &Vector3<f64>, focal_px: f64) -> f64 {
    if !(z_m > 0.0) || !(ray.z > 1e-3) || !(focal_px > 0.0) {
        return 0.0;
    }
    let cos_incidence = normal.dot(ray).abs();
    let theta = cos_incidence.clamp(0.0, 1.0).acos().min(89f64.to_radians());
    let grazing = theta * theta / (std::f64::consts::FRAC_PI_2 - theta).powi(2);
    let sigma_mm = (1.5 - 0.5 * z_m + 0.3 * z_m * z_m + 0.1 * z_m.powf(1.5) * grazing).max(0.0);
    // Millimetre depth quantisation: uniform, variance 1/12 mm^2.
    // Lateral jitter: the depth of a plane through pixel ray (a, b, 1) z
    // changes by -z n_xy / (n . r~) per unit of a or b.
    let slope =
        (normal.x * normal.x + normal.y * normal.y).sqrt() / (cos_incidence * (1.0 / ray.z));
    let lateral_m = LATERAL_JITTER_PX / focal_px * z_m * slope.min(50.0);
    let var_z = (sigma_mm * sigma_mm + 1.0 / 12.0) * 1e-6 + lateral_m * lateral_m;
    var_z / (ray.z * ray.z)
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

/// A coarse normal at pixel `(u, v)` from the measured, `keep`-marked
/// pixels of the `(2r+1)^2` window, every `step`-th in both directions,
/// that lie within a few pixel spacings of it in 3D (so a depth edge does
/// not bend it); at least 6 of them. Used to gate RANSAC inliers.
pub(crate) fn grid_normal(
    cloud: &CloudView<'_>,
    keep: &[bool],
    u: usize,
    v: usize,
    radius: usize,
    step: usize,
) -> Option<Vector3<f64>> {
    let w = cloud.width;
    let step = step.max(1);
    let centre = to_vec3(cloud.points.get(v * w + u)?);
    let focal = cloud.focal_px();
    // Up to 8 pixel spacings per pixel step: surfaces seen at down to ~7
    // degrees of grazing incidence still count.
    let reach = 8.0 * centre.z.abs() / focal;
    let mut m = [0.0; CHANNELS];
    let (u0, u1) = (u.saturating_sub(radius), (u + radius + 1).min(w));
    let (v0, v1) = (v.saturating_sub(radius), (v + radius + 1).min(cloud.height));
    // Offsets that are multiples of `step` from the centre.
    let (u0, v0) = (u - (u - u0) / step * step, v - (v - v0) / step * step);
    for vv in (v0..v1).step_by(step) {
        for uu in (u0..u1).step_by(step) {
            let i = vv * w + uu;
            if !keep.get(i).copied().unwrap_or(false) {
                continue;
            }
            let q = to_vec3(&cloud.points[i]) - centre;
            let steps = uu.abs_diff(u).max(vv.abs_diff(v)) as f64;
            let limit = reach * steps.max(1.0);
            if q.norm_squared() > limit * limit {
                continue;
            }
            let row = moments(&q);
            for (mc, r) in m.iter_mut().zip(row) {
                *mc += r;
            }
        }
    }
    if m[0] < 6.0 {
        return None;
    }
    normal_from_sums(&m, &centre, 0.0, focal).map(|n| orient(n, &centre, &Vector3::zeros()))
}

/// Normal estimation (`normals.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NormalsConfig {
    /// K: neighbours of the local plane fit (paper: 100).
    pub neighbours: usize,
    /// Largest pixel window radius tried before the k-d tree takes over.
    pub max_window_radius_px: usize,
    /// Fit each neighbourhood for depth noise along the viewing ray
    /// (`C^-1 r`) instead of isotropic noise (the smallest eigenvector, as
    /// the paper); see `normals.rs`.
    pub ray_noise_correction: bool,
    /// Keep only the normals of interior points, whose smallest window
    /// holds K of the plane's points (border points see one side of their
    /// neighbourhood, and on real surfaces the mixed pixels and multipath of
    /// the edge); all normals when fewer than K or a tenth are interior.
    /// Off by default: the ablation (pipeline README) shows no gain.
    pub interior_only: bool,
    /// The neighbourhood spans at least this radius on the surface, metres
    /// (more than K points near the camera); 0 = K points only.
    pub min_patch_radius_m: f64,
    /// ...and at least this many times the RMS distance of the plane's
    /// RANSAC inliers from their TLS plane (depth noise, quantisation and
    /// roughness together): the noise bias of a local PCA normal is about
    /// `2 (sigma / r)^2` radians, 0.3 degrees at 20; 0 = off.
    pub patch_per_rms: f64,
    /// Pixel windows (ours) or exactly the K nearest from a k-d tree (the
    /// paper, `literal/knn_normals.rs`).
    pub neighbourhood: crate::literal::NormalsNeighbourhood,
}

impl Default for NormalsConfig {
    fn default() -> Self {
        Self {
            neighbours: 100,
            max_window_radius_px: 80,
            ray_noise_correction: false,
            interior_only: false,
            min_patch_radius_m: 0.1,
            patch_per_rms: 20.0,
            neighbourhood: crate::literal::NormalsNeighbourhood::Window,
        }
    }
}

impl NormalsConfig {
    /// This configuration for a plane whose RANSAC inliers lie `rms_m` (RMS)
    /// from their TLS plane: the patch radius grows to `patch_per_rms *
    /// rms_m` when that is larger than `min_patch_radius_m`.
    pub fn for_plane_noise(&self, rms_m: f64) -> NormalsConfig {
        let scaled = self.patch_per_rms * rms_m;
        NormalsConfig {
            min_patch_radius_m: if scaled.is_finite() {
                self.min_patch_radius_m.max(scaled)
            } else {
                self.min_patch_radius_m
            },
            ..self.clone()
        }
    }
}

impl NormalsConfig {
    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), InvalidValue> {
        at_least("neighbours", self.neighbours, 3)?;
        at_least("max_window_radius_px", self.max_window_radius_px, 1)?;
        non_negative("min_patch_radius_m", self.min_patch_radius_m)?;
        non_negative("patch_per_rms", self.patch_per_rms)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::{Scene, SceneCloud};
    use crate::plane_fit::smallest_eigenvector;
    use nalgebra::Matrix3;

    fn all_measured(cloud: &SceneCloud) -> Vec<u32> {
        (0..cloud.points.len() as u32)
            .filter(|&i| cloud.points[i as usize].is_valid())
            .collect()
    }

    #[test]
    fn exact_plane_gives_its_normal_everywhere() {
        let scene = Scene::wall_facing(2.5);
        let cloud = SceneCloud::render_with_intrinsics(&scene, 80, 60, 70.0, 0.0, 1);
        let members = all_measured(&cloud);
        let mut est = NormalEstimator::new();
        let all = NormalsConfig {
            interior_only: false,
            ..NormalsConfig::default()
        };
        let (normals, stats) = est.estimate(&cloud.view(), &members, &all, &Vector3::zeros());
        assert_eq!(stats.undefined, 0);
        assert_eq!(stats.from_window, members.len());
        for n in normals {
            // The wall faces the camera: normal (0, 0, -1) in camera coordinates.
            assert!((n.z + 1.0).abs() < 1e-9, "{n:?}");
        }
        // Interior only: a pixel whose radius-5 window (the 2x2 table cells
        // its 11 x 11 pixels touch), cut by the image border, holds fewer
        // than K = 100 pixels is dropped.
        let (normals, stats) = est.estimate(
            &cloud.view(),
            &members,
            &NormalsConfig {
                interior_only: true,
                ..NormalsConfig::default()
            },
            &Vector3::zeros(),
        );
        let g = TABLE_CELL_PX;
        let span =
            |c: usize, len: usize| ((c + 5) / g * g + g).min(len) - c.saturating_sub(5) / g * g;
        let mut border = 0;
        for (slot, n) in normals.iter().enumerate() {
            let (u, v) = (slot % 80, slot / 80);
            let inside = span(u, 80) * span(v, 60) >= 100;
            border += usize::from(!inside);
            assert_eq!(n.x.is_finite(), inside, "({u},{v})");
        }
        assert!(border > 0);
        assert_eq!(stats.border, border);
    }

    #[test]
    fn window_normals_match_brute_force_knn_normals_on_a_noisy_ramp() {
        let scene = Scene::ramp(30.0);
        let cloud = SceneCloud::render(&scene, 128, 106, 0.0015, 4);
        let view = cloud.view();
        // The ramp's pixels: those whose world point is past the foot.
        let ramp_normal = scene.to_camera(&scene.surfaces[1].normal);
        let members: Vec<u32> = all_measured(&cloud)
            .into_iter()
            .filter(|&i| {
                let p = view.point(i as usize).unwrap();
                let plane_d = -ramp_normal
                    .dot(&scene.to_camera(&(scene.surfaces[1].point - scene.camera_centre())));
                (ramp_normal.dot(&p) + plane_d).abs() < 0.02
            })
            .collect();
        assert!(members.len() > 2000, "{}", members.len());
        let mut est = NormalEstimator::new();
        let cfg = NormalsConfig {
            interior_only: false,
            ..NormalsConfig::default()
        };
        let (normals, _) = est.estimate(&view, &members, &cfg, &Vector3::zeros());
        let normals = normals.to_vec();
        // Brute force: K nearest by linear scan, nalgebra eigen-decomposition.
        let pts: Vec<Vector3<f64>> = members
            .iter()
            .map(|&i| view.point(i as usize).unwrap())
            .collect();
        let mut ours_err = 0.0;
        let mut oracle_err = 0.0;
        let mut checked = 0;
        for s in (0..pts.len()).step_by(41) {
            let mut d: Vec<(f64, usize)> = pts
                .iter()
                .enumerate()
                .map(|(j, q)| ((q - pts[s]).norm_squared(), j))
                .collect();
            d.sort_by(|a, b| a.0.total_cmp(&b.0));
            let nn = &d[..100];
            let mean = nn.iter().map(|&(_, j)| pts[j]).sum::<Vector3<f64>>() / 100.0;
            let cov = nn
                .iter()
                .map(|&(_, j)| (pts[j] - mean) * (pts[j] - mean).transpose())
                .sum::<Matrix3<f64>>()
                / 100.0;
            let (n, _) = smallest_eigenvector(&cov).unwrap();
            let n = orient(n, &pts[s], &Vector3::zeros());
            oracle_err += crate::cloud::angle_between_deg(&n, &ramp_normal);
            ours_err += crate::cloud::angle_between_deg(&normals[s], &ramp_normal);
            checked += 1;
        }
        let (ours, oracle) = (ours_err / checked as f64, oracle_err / checked as f64);
        // Same estimator up to the neighbourhood's shape: mean angular error
        // within 25 % of the k-d tree's.
        assert!(
            ours < oracle * 1.25 + 0.05,
            "window {ours} deg vs knn {oracle} deg"
        );
        assert!(ours < 2.0, "{ours}");
    }

    #[test]
    fn sparse_members_fall_back_to_the_tree() {
        let scene = Scene::wall_facing(2.0);
        let cloud = SceneCloud::render_with_intrinsics(&scene, 100, 100, 80.0, 0.0, 1);
        // Every third pixel in each direction: windows of radius <= 12 hold
        // at most 81 members < 100, so all go to the tree.
        let members: Vec<u32> = (0..10_000u32)
            .filter(|i| (i % 100) % 3 == 0 && (i / 100) % 3 == 0)
            .collect();
        let mut est = NormalEstimator::new();
        let cfg = NormalsConfig {
            max_window_radius_px: 12,
            ..NormalsConfig::default()
        };
        let (normals, stats) = est.estimate(&cloud.view(), &members, &cfg, &Vector3::zeros());
        assert!(stats.from_tree > 0, "{stats:?}");
        for n in normals {
            assert!((n.z + 1.0).abs() < 1e-9, "{n:?}");
        }
    }

    /// The ground in front of a 30 degree ramp beyond 1 m, seen at grazing
    /// incidence where the depth noise is largest: the scene, its up vector
    /// in camera coordinates and the ground's pixels.
    fn grazing_ground() -> (Scene, Vector3<f64>, Vec<u32>) {
        let scene = Scene::ramp(30.0);
        let up = scene.to_camera(&Vector3::z());
        let exact = SceneCloud::render_with_intrinsics(&scene, 512, 424, 365.0, 0.0, 7);
        let members: Vec<u32> = all_measured(&exact)
            .into_iter()
            .filter(|&i| {
                let p = exact.view().point(i as usize).unwrap();
                (up.dot(&p) + 0.5).abs() < 1e-4 && p.z > 1.0
            })
            .collect();
        (scene, up, members)
    }

    /// Angle between the sum of the members' normals and `truth`, degrees.
    fn mean_normal_error(
        view: &CloudView<'_>,
        members: &[u32],
        cfg: &NormalsConfig,
        truth: &Vector3<f64>,
    ) -> f64 {
        let mut est = NormalEstimator::new();
        let (normals, _) = est.estimate(view, members, cfg, &Vector3::zeros());
        let sum: Vector3<f64> = normals.iter().filter(|n| n.x.is_finite()).sum();
        crate::cloud::angle_between_deg(&sum, truth)
    }

    #[test]
    fn ray_noise_correction_is_exact_without_noise_and_unbiased_with_it() {
        let (scene, up, members) = grazing_ground();
        assert!(members.len() > 10_000, "{}", members.len());
        for sigma in [0.0, crate::fixtures::KINECT2_NOISE] {
            let cloud = SceneCloud::render_with_intrinsics(&scene, 512, 424, 365.0, sigma, 7);
            let view = cloud.view();
            let mean_err = |ray_noise_correction: bool| {
                // K points only (the paper's neighbourhood), where the noise
                // bias is largest.
                let cfg = NormalsConfig {
                    ray_noise_correction,
                    min_patch_radius_m: 0.0,
                    max_window_radius_px: 12,
                    ..NormalsConfig::default()
                };
                mean_normal_error(&view, &members, &cfg, &up)
            };
            let (pca, corrected) = (mean_err(false), mean_err(true));
            if sigma == 0.0 {
                assert!(pca < 1e-4 && corrected < 1e-4, "{pca} {corrected}");
            } else {
                // Kinect v2 depth noise tilts the eigenvectors; the corrected
                // normals average to the plane's.
                assert!(pca > 0.15, "pca bias {pca}");
                assert!(
                    corrected < 0.1 && corrected < pca / 3.0,
                    "corrected bias {corrected} vs {pca}"
                );
                // The default 10 cm patch: plain PCA, the noise is small
                // against the patch and the bias is gone without a model.
                let wide = mean_normal_error(&view, &members, &NormalsConfig::default(), &up);
                assert!(
                    wide < 0.1 && wide < pca / 3.0,
                    "10 cm patch bias {wide} vs {pca}"
                );
            }
        }
    }

    #[test]
    fn patch_scaled_to_the_plane_noise_removes_the_bias_of_coarse_depth() {
        // Coarse depth (sigma = 2 cm * z^2 along the ray, the order of a
        // Kinect v1's disparity steps at 4-5 m) on the grazing ground: a
        // 10 cm patch is too small and its normals lean towards the rays;
        // the patch scaled to the plane's own RMS residual
        // (NormalsConfig::for_plane_noise) is not.
        let (scene, up, members) = grazing_ground();
        let cloud = SceneCloud::render_with_intrinsics(&scene, 512, 424, 365.0, 0.02, 7);
        let view = cloud.view();
        let mut m = crate::plane_fit::Moments::new();
        for &i in &members {
            m.add(&view.point(i as usize).unwrap());
        }
        let plane = crate::plane_fit::fit_tls(&m).unwrap();
        let c = m.covariance().unwrap();
        let rms = plane.normal.dot(&(c * plane.normal)).sqrt();
        let bias = |cfg: &NormalsConfig| mean_normal_error(&view, &members, cfg, &up);
        let fixed = bias(&NormalsConfig::default());
        let scaled = bias(&NormalsConfig::default().for_plane_noise(rms));
        assert!(rms > 0.005, "rms {rms}");
        assert!(fixed > 1.0, "10 cm patch bias {fixed}");
        assert!(
            scaled < 0.5 && scaled < fixed / 3.0,
            "scaled {scaled} vs {fixed}"
        );
    }

    #[test]
    fn support_gives_a_sparse_subsample_its_dense_neighbourhoods() {
        // Normals of every 7th point computed with the whole plane as
        // support equal those computed for all points (same windows).
        let scene = Scene::ramp(30.0);
        let cloud = SceneCloud::render_with_intrinsics(&scene, 256, 212, 180.0, 0.002, 3);
        let view = cloud.view();
        let all = all_measured(&cloud);
        let sparse: Vec<u32> = all.iter().copied().step_by(7).collect();
        let cfg = NormalsConfig {
            interior_only: false,
            ..NormalsConfig::default()
        };
        let mut est = NormalEstimator::new();
        let dense = est
            .estimate(&view, &all, &cfg, &Vector3::zeros())
            .0
            .to_vec();
        let (sub, _) = est.estimate_with_support(&view, &sparse, &all, &cfg, &Vector3::zeros());
        assert_eq!(sub.len(), sparse.len());
        for (k, n) in sub.iter().enumerate() {
            let d = dense[k * 7];
            assert!(
                (n.x.is_nan() && d.x.is_nan()) || (n - d).norm() < 1e-9,
                "{k}: {n:?} vs {d:?}"
            );
        }
    }

    /// A view of width 0 (malformed: its points have no pixel grid) gives
    /// every member a NaN normal, counted undefined, instead of a panic.
    #[test]
    fn a_view_of_width_0_gives_nan_normals() {
        let scene = Scene::wall_facing(2.5);
        let cloud = SceneCloud::render(&scene, 32, 24, 0.0, 1);
        let members = all_measured(&cloud);
        assert!(!members.is_empty());
        let view = CloudView {
            width: 0,
            ..cloud.view()
        };
        let mut est = NormalEstimator::new();
        let (normals, stats) = est.estimate(
            &view,
            &members,
            &NormalsConfig::default(),
            &Vector3::zeros(),
        );
        assert_eq!(normals.len(), members.len());
        assert!(normals.iter().all(|n| n.iter().all(|c| c.is_nan())));
        assert_eq!(stats.undefined, members.len());
        assert_eq!(stats.from_window + stats.from_tree, 0);
    }

    #[test]
    fn orientation_faces_the_viewpoint() {
        let p = Vector3::new(0.0, 0.0, 2.0);
        assert_eq!(orient(Vector3::z(), &p, &Vector3::zeros()), -Vector3::z());
        assert_eq!(orient(-Vector3::z(), &p, &Vector3::zeros()), -Vector3::z());
    }
}
