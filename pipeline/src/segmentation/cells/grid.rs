//! The cell grid: blocks of `k x k` sample cells, each with the moments of
//! its kept pixels (every `step`-th pixel in both directions), its TLS
//! plane, and whether it is planar.
//!
//! A pixel belongs to the cell of its sample cell (the labelling's own
//! mapping, `ransac_planes/sample_axis.rs`: the nearest sample point), so
//! a cell's pixels are the pixels its sample cells label. The sample
//! cells are grouped `k` to a cell from both ends of each axis towards the
//! middle ([`CellAxis`]), as the sample points are counted from both
//! edges: the mirror image of a frame has the mirrored cells.

use nalgebra::Vector3;

use crate::cloud::{is_measured, CloudView};
use crate::plane_fit::smallest_eigenvector_3x3;
use crate::ransac_planes::{SampleAxis, Threshold};

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

/// One axis of the cell grid: its sample cells grouped `k` to a cell from
/// both ends towards the middle, `ceil(floor(n / 2) / k)` cells on each
/// side and, for an odd number `n` of sample cells, the middle one a cell
/// of its own. With `n` a multiple of `2 k` (128 sample columns of a
/// Kinect v2 frame in cells of 2): cell `j / k`, as from one end. Else the
/// cells next to the middle are smaller (the 106 sample rows of a Kinect
/// v2 frame: 53 a side, so the two middle cell rows hold one sample row
/// each), and [`CellGrid::load`] asks them for as many measured points as
/// a whole cell, so they are planar less readily.
#[derive(Debug, Default, Clone)]
pub(super) struct CellAxis {
    /// Per sample cell: its cell.
    pub of_sample: Vec<u32>,
    /// Per cell: its first sample cell; then the number of sample cells
    /// (cell `c` holds sample cells `start[c]..start[c + 1]`).
    pub start: Vec<u32>,
}

impl CellAxis {
    /// The cells of an axis of `n` sample cells, `k` (at least 1) to a cell.
    pub fn build(&mut self, n: usize, k: usize) {
        let k = k.max(1);
        let half = n / 2;
        let side = half.div_ceil(k);
        let count = 2 * side + n % 2;
        self.of_sample.clear();
        self.of_sample.extend((0..n).map(|j| {
            (if j < half {
                j / k
            } else if j >= n - half {
                count - 1 - (n - 1 - j) / k
            } else {
                side
            }) as u32
        }));
        self.start.clear();
        for (j, &c) in self.of_sample.iter().enumerate() {
            if j == 0 || c != self.of_sample[j - 1] {
                self.start.push(j as u32);
            }
        }
        self.start.push(n as u32);
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// The sample cells of cell `c`.
    pub fn samples(&self, c: usize) -> std::ops::Range<usize> {
        self.start[c] as usize..self.start[c + 1] as usize
    }
}

/// The cells of one frame.
#[derive(Debug, Default, Clone)]
pub(super) struct CellGrid {
    /// Cells per row and per column.
    pub width: usize,
    pub height: usize,
    /// The cells' columns and rows of sample cells.
    pub columns_of: CellAxis,
    pub rows_of: CellAxis,
    pub sums: Vec<RawSums>,
    /// Per cell: its plane when planar.
    pub planar: Vec<Option<SumsPlane>>,
    /// Per cell: how far from planar (`mse / t^2`), the seed order.
    pub badness: Vec<f64>,
    /// The pixel columns summed, and the cell column of each.
    columns: Vec<u32>,
    column_cell: Vec<u32>,
}

/// What a band of [`CellGrid::load`] reads: the pixels, the columns
/// summed and their cells, each sample row's cell row.
#[derive(Clone, Copy)]
struct RowSummer<'a> {
    cloud: &'a CloudView<'a>,
    keep: &'a [bool],
    columns: &'a [u32],
    column_cell: &'a [u32],
    cell_row: &'a [u32],
    rows: &'a SampleAxis,
    /// Cells per row.
    width: usize,
    step: usize,
}

impl RowSummer<'_> {
    /// Adds every `step`-th pixel row whose cell row is one of the rows
    /// `sums` holds (whole cell rows from `first_row` on) into its cells,
    /// rows top to bottom.
    fn sum_band(&self, first_row: usize, sums: &mut [RawSums]) {
        let (w, h) = (self.cloud.width, self.cloud.height);
        let band = first_row..first_row + sums.len() / self.width;
        for v in (0..h).step_by(self.step) {
            let cell_row = self.cell_row[self.rows.of_pixel[v] as usize] as usize;
            if !band.contains(&cell_row) {
                continue;
            }
            let base = (cell_row - first_row) * self.width;
            let row = v * w;
            for (&cu, &u) in self.column_cell.iter().zip(self.columns) {
                let i = row + u as usize;
                let p = &self.cloud.points[i];
                if !self.keep[i] || !is_measured(p) {
                    continue;
                }
                let (x, y, z) = (f64::from(p.x_m), f64::from(p.y_m), f64::from(p.z_m));
                let s = &mut sums[base + cu as usize];
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
    }
}

/// What [`CellGrid::load`] needs of the sample grid and the config.
#[derive(Debug, Clone, Copy)]
pub(super) struct CellLayout<'a> {
    /// The sample columns and rows, pixels between sample points.
    pub columns: &'a SampleAxis,
    pub rows: &'a SampleAxis,
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
    /// decides which cells are planar. With a pool the cell rows are cut
    /// into bands, two per thread, each summed and classified on a worker:
    /// a cell's sums add its pixels in the same order either way, so they
    /// are the same bits whatever the thread count.
    pub fn load(
        &mut self,
        cloud: &CloudView<'_>,
        keep: &[bool],
        layout: CellLayout<'_>,
        t: Threshold,
        pool: Option<&rayon::ThreadPool>,
    ) {
        let CellLayout {
            k, columns, rows, ..
        } = layout;
        self.columns_of.build(columns.len(), k);
        self.rows_of.build(rows.len(), k);
        self.width = self.columns_of.len();
        self.height = self.rows_of.len();
        let cells = self.width * self.height;
        self.sums.clear();
        self.sums.resize(cells, [0.0; 10]);
        self.planar.clear();
        self.planar.resize(cells, None);
        self.badness.clear();
        self.badness.resize(cells, f64::INFINITY);
        if cells == 0 {
            return;
        }
        self.load_columns(cloud.width, layout);
        let bands = pool.map_or(1, |p| (2 * p.current_num_threads()).min(self.height));
        let per_band = self.height.div_ceil(bands);
        let summer = RowSummer {
            cloud,
            keep,
            columns: &self.columns,
            column_cell: &self.column_cell,
            cell_row: &self.rows_of.of_sample,
            rows,
            width: self.width,
            step: layout.step,
        };
        let chunk = per_band * self.width;
        let jobs = self
            .sums
            .chunks_mut(chunk)
            .zip(
                self.planar
                    .chunks_mut(chunk)
                    .zip(self.badness.chunks_mut(chunk)),
            )
            .enumerate();
        let band = move |(b, (sums, verdicts)): (usize, (&mut [RawSums], _))| {
            summer.sum_band(b * per_band, sums);
            classify(sums, verdicts, layout, t);
        };
        match pool {
            Some(pool) if bands > 1 => pool.scope(|scope| {
                for job in jobs {
                    scope.spawn(move |_| band(job));
                }
            }),
            _ => jobs.for_each(band),
        }
    }

    /// The pixel columns summed and the cell column of each: every
    /// `step`-th column counted from the nearer image edge, so that the
    /// columns summed are symmetric about the image's centre and the
    /// mirror image of a frame sums the mirror image of its pixels.
    fn load_columns(&mut self, w: usize, layout: CellLayout<'_>) {
        let step = layout.step;
        self.columns.clear();
        self.columns.extend(
            (0..w)
                .filter(|&u| u.min(w - 1 - u) % step == 0)
                .map(|u| u as u32),
        );
        self.column_cell.clear();
        let columns_of = &self.columns_of.of_sample;
        self.column_cell.extend(
            self.columns
                .iter()
                .map(|&u| columns_of[layout.columns.of_pixel[u as usize] as usize]),
        );
    }
}

/// Whether each cell of `sums` is planar (`planar`, `badness`: one each
/// per cell): at least half its summed pixels measured and an RMS within
/// `rms_ratio` of the inlier distance at its centroid.
fn classify(
    sums: &[RawSums],
    (planar, badness): (&mut [Option<SumsPlane>], &mut [f64]),
    layout: CellLayout<'_>,
    t: Threshold,
) {
    let side = (layout.k * layout.stride).div_ceil(layout.step);
    let min_points = ((side * side) as f64 / 2.0).max(3.0);
    for ((s, planar), badness) in sums.iter().zip(planar).zip(badness) {
        let plane = (s[0] >= min_points).then(|| SumsPlane::of(s)).flatten();
        let verdict = plane.and_then(|p| {
            let limit = layout.rms_ratio * t.at(&p.centroid);
            let bad = p.mse / (limit * limit);
            (bad <= 1.0).then_some((p, bad))
        });
        *planar = verdict.map(|(p, _)| p);
        *badness = verdict.map_or(f64::INFINITY, |(_, b)| b);
    }
}
