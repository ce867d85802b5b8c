//! The cell grid: blocks of `k x k` sample cells, each with the moments of
//! its kept pixels (every `step`-th pixel in both directions), its TLS
//! plane, and whether it is planar.
//!
//! A pixel belongs to the cell of its sample cell (the labelling's own
//! mapping, `ransac_planes/labelling.rs`): pixel column `u` is in sample
//! column `(u - stride / 2) / stride` (clamped), so a cell's pixels are the
//! pixels its sample cells label.

use nalgebra::Vector3;

use crate::cloud::{is_measured, CloudView};
use crate::plane_fit::smallest_eigenvector_3x3;
use crate::ransac_planes::Threshold;

/// Sums of a cell's points about the camera: count, x, y, z, xx, xy, xz,
/// yy, yz, zz. About the origin, not the centroid: a cell spans
/// centimetres at most metres away, and `f64` keeps its spread (1e-5 m^2
/// against 1e-15 of rounding at 5 m).
pub(super) type RawSums = [f64; 10];

/// Adds sums `b` into `a`.
#[inline]
pub(super) fn add_sums(a: &mut RawSums, b: &RawSums) {
    for (x, y) in a.iter_mut().zip(b) {
        *x += y;
    }
}

/// A plane from raw sums: unit normal towards the camera, offset
/// (`n . p + d = 0`), centroid, and mean squared distance of the points
/// from the plane; `None` with fewer than 3 points or no defined normal.
#[derive(Debug, Clone, Copy)]
pub(super) struct SumsPlane {
    pub normal: Vector3<f64>,
    pub d: f64,
    pub centroid: Vector3<f64>,
    pub mse: f64,
}

impl SumsPlane {
    pub fn of(s: &RawSums) -> Option<Self> {
        let n = s[0];
        if n < 3.0 {
            return None;
        }
        let m = Vector3::new(s[1], s[2], s[3]) / n;
        let cov = [
            s[4] / n - m.x * m.x,
            s[5] / n - m.x * m.y,
            s[6] / n - m.x * m.z,
            s[7] / n - m.y * m.y,
            s[8] / n - m.y * m.z,
            s[9] / n - m.z * m.z,
        ];
        let mut normal = smallest_eigenvector_3x3(&cov)?;
        if normal.dot(&m) > 0.0 {
            normal = -normal;
        }
        let [xx, xy, xz, yy, yz, zz] = cov;
        let (a, b, c) = (normal.x, normal.y, normal.z);
        let mse =
            a * a * xx + b * b * yy + c * c * zz + 2.0 * (a * b * xy + a * c * xz + b * c * yz);
        Some(Self {
            normal,
            d: -normal.dot(&m),
            centroid: m,
            mse: mse.max(0.0),
        })
    }

    /// Signed distance of `p` from the plane.
    #[inline]
    pub fn distance(&self, p: &Vector3<f64>) -> f64 {
        self.normal.dot(p) + self.d
    }
}

/// The cells of one frame.
#[derive(Debug, Default, Clone)]
pub(super) struct CellGrid {
    /// Cells per row and per column.
    pub width: usize,
    pub height: usize,
    /// Sample cells per cell side.
    pub k: usize,
    pub sums: Vec<RawSums>,
    /// Per cell: its plane when planar.
    pub planar: Vec<Option<SumsPlane>>,
    /// Per cell: how far from planar (`mse / t^2`), the seed order.
    pub badness: Vec<f64>,
    /// The pixel columns summed, and the cell column of each.
    columns: Vec<u32>,
    column_cell: Vec<u32>,
}

/// What [`CellGrid::load`] needs of the sample grid and the config.
#[derive(Debug, Clone, Copy)]
pub(super) struct CellLayout {
    /// Sample cells per row and per column, pixels between sample points.
    pub sample_w: usize,
    pub sample_h: usize,
    pub stride: usize,
    /// Sample cells per cell side.
    pub k: usize,
    /// Every `step`-th pixel in both directions is summed.
    pub step: usize,
    /// Planar: RMS at most `rms_ratio` times the inlier distance.
    pub rms_ratio: f64,
}

impl CellGrid {
    /// Sums the kept, measured pixels of `cloud` into their cells and
    /// decides which cells are planar.
    pub fn load(&mut self, cloud: &CloudView<'_>, keep: &[bool], layout: CellLayout, t: Threshold) {
        let CellLayout {
            k, step, stride, ..
        } = layout;
        self.k = k;
        self.width = layout.sample_w.div_ceil(k);
        self.height = layout.sample_h.div_ceil(k);
        self.sums.clear();
        self.sums.resize(self.width * self.height, [0.0; 10]);
        let (w, h) = (cloud.width, cloud.height);
        if self.width == 0 || self.height == 0 {
            self.planar.clear();
            self.badness.clear();
            return;
        }
        let half = stride / 2;
        let cell_of =
            |px: usize, samples: usize| (px.saturating_sub(half) / stride).min(samples - 1) / k;
        // Every step-th column counted from the nearer image edge: the
        // columns summed are symmetric about the image's centre, so the
        // mirror image of a frame sums the mirror image of its pixels.
        self.columns.clear();
        self.columns.extend(
            (0..w)
                .filter(|&u| u.min(w - 1 - u) % step == 0)
                .map(|u| u as u32),
        );
        self.column_cell.clear();
        self.column_cell.extend(
            self.columns
                .iter()
                .map(|&u| cell_of(u as usize, layout.sample_w) as u32),
        );
        for v in (0..h).step_by(step) {
            let base = cell_of(v, layout.sample_h) * self.width;
            let row = v * w;
            for (&cu, &u) in self.column_cell.iter().zip(&self.columns) {
                let u = u as usize;
                let i = row + u;
                let p = &cloud.points[i];
                if !keep[i] || !is_measured(p) {
                    continue;
                }
                let (x, y, z) = (f64::from(p.x_m), f64::from(p.y_m), f64::from(p.z_m));
                let s = &mut self.sums[base + cu as usize];
                s[0] += 1.0;
                s[1] += x;
                s[2] += y;
                s[3] += z;
                s[4] += x * x;
                s[5] += x * y;
                s[6] += x * z;
                s[7] += y * y;
                s[8] += y * z;
                s[9] += z * z;
            }
        }
        self.classify(layout, t);
    }

    /// A cell is planar with at least half its summed pixels measured and
    /// an RMS within `rms_ratio` of the inlier distance at its centroid.
    fn classify(&mut self, layout: CellLayout, t: Threshold) {
        let side = (layout.k * layout.stride).div_ceil(layout.step);
        let min_points = ((side * side) as f64 / 2.0).max(3.0);
        self.planar.clear();
        self.badness.clear();
        for s in &self.sums {
            let plane = (s[0] >= min_points).then(|| SumsPlane::of(s)).flatten();
            let verdict = plane.and_then(|p| {
                let limit = layout.rms_ratio * t.at(&p.centroid);
                let bad = p.mse / (limit * limit);
                (bad <= 1.0).then_some((p, bad))
            });
            self.planar.push(verdict.map(|(p, _)| p));
            self.badness.push(verdict.map_or(f64::INFINITY, |(_, b)| b));
        }
    }
}
