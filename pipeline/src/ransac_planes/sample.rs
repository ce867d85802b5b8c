//! The sample grid: every `sample_stride_px`-th pixel in both directions
//! (counted from the nearer edge, `sample_axis.rs`), with its coarse
//! normal; the free points (not yet taken by a plane) as [`Points`], and
//! per coarse cell its free point and its original point.

use nalgebra::Vector3;

use super::points::Points;
use super::sample_axis::SampleAxis;
use super::RansacConfig;
use super::Threshold;
use crate::cloud::{is_measured, to_vec3, CloudView};
use crate::normals::grid_normal;

/// Removing fewer than 1/`RUNS_BELOW` of the free points from the first
/// removed one on uses [`Points::remove_sorted`] (the runs between removed
/// points are long and move whole), otherwise [`Points::retain_tail`] (the
/// runs are short and the kept points are copied one by one).
const RUNS_BELOW: usize = 2;

/// A cell without a free sample point.
pub(super) const NO_SAMPLE: u32 = u32::MAX;

#[derive(Debug, Default, Clone)]
pub(super) struct SampleGrid {
    /// The free sample points; `tag` is the coarse cell.
    pub points: Points,
    /// Per coarse cell: the index of its free point in `points`, or
    /// `NO_SAMPLE`.
    pub coarse: Vec<u32>,
    /// Per coarse cell: its sample point (NaN if none), kept after the
    /// point leaves the free points.
    pub cell_point: Vec<Vector3<f64>>,
    pub coarse_w: usize,
    pub coarse_h: usize,
    pub stride: usize,
    /// The sample columns and rows, and the pixels each stands for.
    pub columns: SampleAxis,
    pub rows: SampleAxis,
    /// Scratch for [`Self::compact`]: the free points removed, and kept.
    removed: Vec<u32>,
    keep: Vec<u32>,
    /// Scratch for a banded [`Self::load`]: each band's points.
    band_points: Vec<Points>,
}

/// What [`SampleGrid::load`] reads: the pixels, the sample columns and
/// rows, the inlier distance and the normal gate.
#[derive(Clone, Copy)]
struct RowLoader<'a> {
    cloud: &'a CloudView<'a>,
    keep: &'a [bool],
    columns: &'a [u32],
    rows: &'a [u32],
    t: Threshold,
    cos_gate: Option<f64>,
}

impl RowLoader<'_> {
    /// Adds the kept, measured sample points of the sample rows `rows` to
    /// `points`, in raster order, each with its coarse normal when the
    /// gate is on.
    fn load_rows(&self, rows: std::ops::Range<usize>, points: &mut Points) {
        let (cloud, keep) = (self.cloud, self.keep);
        let (w, coarse_w) = (cloud.width, self.columns.len());
        let radius = 2;
        for row in rows {
            let v = self.rows[row] as usize;
            for (column, &u) in self.columns.iter().enumerate() {
                let u = u as usize;
                let i = v * w + u;
                if !keep[i] || !is_measured(&cloud.points[i]) {
                    continue;
                }
                let n = if self.cos_gate.is_some() {
                    central_difference_normal(cloud, keep, u, v, radius)
                        .or_else(|| grid_normal(cloud, keep, u, v, radius, 2))
                } else {
                    None
                };
                let p = to_vec3(&cloud.points[i]);
                let cell = row * coarse_w + column;
                points.push(&p, n.as_ref(), &self.t, self.cos_gate, cell as u32);
            }
        }
    }
}

impl SampleGrid {
    /// Fills the grid from the kept, measured pixels of `cloud`. With a
    /// pool the sample rows are cut into bands, two per thread, each
    /// loaded on a worker and appended in order: the same points, bit for
    /// bit, whatever the thread count.
    pub fn load(
        &mut self,
        cloud: &CloudView<'_>,
        keep: &[bool],
        config: &RansacConfig,
        cos_gate: Option<f64>,
        pool: Option<&rayon::ThreadPool>,
    ) {
        self.points.clear();
        let s = config.sample_stride_px.max(1);
        self.stride = s;
        self.columns.build(cloud.width, s);
        self.rows.build(cloud.height, s);
        self.coarse_w = self.columns.len();
        self.coarse_h = self.rows.len();
        self.points.reserve(self.coarse_w * self.coarse_h);
        let loader = RowLoader {
            cloud,
            keep,
            columns: &self.columns.at,
            rows: &self.rows.at,
            t: Threshold::of(config),
            cos_gate,
        };
        let bands = pool.map_or(1, |p| (2 * p.current_num_threads()).min(self.coarse_h));
        match pool {
            Some(pool) if bands > 1 => {
                let per_band = self.coarse_h.div_ceil(bands);
                if self.band_points.len() < bands {
                    self.band_points.resize_with(bands, Points::default);
                }
                let jobs = self.band_points[..bands].iter_mut().enumerate();
                pool.scope(|scope| {
                    for (b, points) in jobs {
                        let rows = b * per_band..((b + 1) * per_band).min(loader.rows.len());
                        scope.spawn(move |_| {
                            points.clear();
                            loader.load_rows(rows, points);
                        });
                    }
                });
                for band in &self.band_points[..bands] {
                    self.points.append(band);
                }
            }
            _ => loader.load_rows(0..self.coarse_h, &mut self.points),
        }
        self.rebuild_cells();
        self.cell_point.clear();
        self.cell_point
            .resize(self.coarse_w * self.coarse_h, Vector3::repeat(f64::NAN));
        for (&c, p) in self.coarse.iter().zip(&mut self.cell_point) {
            if c != NO_SAMPLE {
                *p = self.points.point(c as usize);
            }
        }
    }

    /// Removes the free points whose flag is set and renumbers the cells.
    pub fn remove(&mut self, remove: &[bool]) {
        debug_assert_eq!(remove.len(), self.points.len());
        self.removed.clear();
        self.removed
            .extend((0..remove.len() as u32).filter(|&j| remove[j as usize]));
        self.compact();
    }

    /// Removes the free points of the given cells (increasing, each with a
    /// free point).
    pub fn remove_cells(&mut self, cells: &[u32]) {
        debug_assert!(cells.iter().all(|&c| self.coarse[c as usize] != NO_SAMPLE));
        self.removed.clear();
        self.removed
            .extend(cells.iter().map(|&c| self.coarse[c as usize]));
        self.compact();
    }

    /// Removes the free points `removed` (increasing, as the cells of free
    /// points are in raster order) and renumbers the cells of the points
    /// after the first one removed. Few removed points (a small region):
    /// the runs between them move down; many (short runs): the points
    /// kept are copied one by one.
    fn compact(&mut self) {
        debug_assert!(
            self.removed.windows(2).all(|w| w[0] < w[1])
                && self
                    .removed
                    .last()
                    .is_none_or(|&j| (j as usize) < self.points.len())
        );
        let Some(&first) = self.removed.first() else {
            return;
        };
        for &j in &self.removed {
            self.coarse[self.points.tag[j as usize] as usize] = NO_SAMPLE;
        }
        let n = self.points.len();
        if self.removed.len() * RUNS_BELOW < n - first as usize {
            self.points.remove_sorted(&self.removed);
        } else {
            let (coarse, tag) = (&self.coarse, &self.points.tag);
            self.keep.clear();
            self.keep.extend(
                (first..n as u32).filter(|&j| coarse[tag[j as usize] as usize] != NO_SAMPLE),
            );
            self.points.retain_tail(first as usize, &self.keep);
        }
        let tag = &self.points.tag;
        for (j, &c) in (first..).zip(&tag[first as usize..]) {
            self.coarse[c as usize] = j;
        }
    }

    /// The coarse cell of free point `j`.
    #[inline]
    pub fn cell_of(&self, j: usize) -> usize {
        self.points.tag[j] as usize
    }

    fn rebuild_cells(&mut self) {
        self.coarse.clear();
        self.coarse.resize(self.coarse_w * self.coarse_h, NO_SAMPLE);
        for (j, &c) in self.points.tag.iter().enumerate() {
            self.coarse[c as usize] = j as u32;
        }
    }
}

/// The normal at pixel `(u, v)` from the cross product of the central
/// differences `r` pixels left/right and up/down, towards the camera; `None`
/// when one of the four is missing or more than a few pixel spacings away in
/// 3D (a depth edge: then the PCA window decides).
pub(super) fn central_difference_normal(
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
pub(super) fn cell_neighbourhood(c: usize, cw: usize, ch: usize) -> impl Iterator<Item = usize> {
    let (rows, columns) = neighbourhood_span(c % cw, c / cw, cw, ch);
    rows.flat_map(move |r| columns.clone().map(move |q| r * cw + q))
}

/// The rows and the columns of the (up to) 3x3 sample cells around cell
/// `(cu, cv)` of a `cw` x `ch` grid: [`cell_neighbourhood`] is their
/// cells, row by row.
pub(super) fn neighbourhood_span(
    cu: usize,
    cv: usize,
    cw: usize,
    ch: usize,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    (
        cv.saturating_sub(1)..(cv + 2).min(ch),
        cu.saturating_sub(1)..(cu + 2).min(cw),
    )
}
