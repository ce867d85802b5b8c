//! Labelling: the taken sample cells relaxed to the nearer plane along
//! junctions, then every kept pixel given to the nearest plane (within the
//! threshold) among those that took the sample cells around it, in fixed
//! bands of rows (on the estimator's worker threads when it has them),
//! joined in band order.

use nalgebra::Vector3;
use slope_ipc_types::CloudPoint;

use super::sample::{cell_neighbourhood, neighbourhood_span};
use super::sample_axis::SampleAxis;
use super::{PlaneSegmenter, SegmentedPlane, Threshold, NO_PLANE};
use crate::cloud::{is_measured, to_vec3, CloudView, PixelBox};
use crate::plane_fit::{MomentSums, Moments, Plane};

impl PlaneSegmenter {
    /// Moves each taken cell to a plane of a neighbouring cell (8-connected)
    /// while its sample point is strictly nearer to that plane and within
    /// the threshold. Each move brings a point strictly nearer to its
    /// plane, so it ends; a coplanar piece elsewhere is never adjacent.
    /// Leaves every cell's candidate planes (those of its 3x3 cells) as the
    /// labelling reads them.
    pub(super) fn relax_cells(&mut self, found: &[Plane], t: Threshold) {
        let (cw, ch) = (self.sample.coarse_w, self.sample.coarse_h);
        let neighbours = |c: usize| cell_neighbourhood(c, cw, ch);
        // Work list: the cells on a border between two planes, then the
        // neighbours of every cell that moved.
        self.fill_cell_candidates();
        self.push_border_cells();
        let mut moved = std::mem::take(&mut self.moved);
        moved.clear();
        while let Some(c) = self.stack.pop() {
            let c = c as usize;
            self.in_work[c] = false;
            let a = self.cell_plane[c];
            let p = self.sample.cell_point[c];
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
                moved.push(c as u32);
                for q in neighbours(c) {
                    if self.cell_plane[q] != NO_PLANE && !self.in_work[q] {
                        self.in_work[q] = true;
                        self.stack.push(q as u32);
                    }
                }
            }
        }
        self.refresh_candidates_around(&moved);
        self.moved = moved;
    }

    /// The relaxation's first work list (`stack`, each marked `in_work`):
    /// the cells on a border between two planes, a taken cell with two
    /// candidate planes (its own and another).
    #[inline]
    fn push_border_cells(&mut self) {
        let cells = self.cell_plane.len();
        self.stack.clear();
        self.in_work.clear();
        self.in_work.resize(cells, false);
        let candidates = self.cell_plane.iter().zip(&self.cell_candidates);
        for (c, (&a, (_, n))) in candidates.enumerate() {
            if a != NO_PLANE && *n >= 2 {
                self.stack.push(c as u32);
                self.in_work[c] = true;
            }
        }
    }

    /// The candidates of the cells around those that `moved`, afresh, each
    /// once (after the relaxation: `in_work` all false, `stack` empty; the
    /// cells refreshed stay marked, `push_border_cells` clears the marks).
    #[inline]
    fn refresh_candidates_around(&mut self, moved: &[u32]) {
        let (cw, ch) = (self.sample.coarse_w, self.sample.coarse_h);
        for &c in moved {
            for q in cell_neighbourhood(c as usize, cw, ch) {
                if !self.in_work[q] {
                    self.in_work[q] = true;
                    self.stack.push(q as u32);
                }
            }
        }
        while let Some(q) = self.stack.pop() {
            let q = q as usize;
            self.cell_candidates[q] = self.candidates_of(q % cw, q / cw);
        }
    }

    /// Gives every kept, measured pixel to the plane nearest to it among
    /// those that took one of the (up to 3x3) sample points around it, if
    /// within the threshold; fills `planes[k].inliers` (pixel order) and
    /// `moments[k]`. Reads the cells' candidate planes as
    /// [`Self::relax_cells`] leaves them.
    pub(super) fn label_pixels(
        &mut self,
        cloud: &CloudView<'_>,
        keep: &[bool],
        found: &[Plane],
        t: Threshold,
    ) {
        let (cw, ch) = (self.sample.coarse_w, self.sample.coarse_h);
        if found.is_empty() || cw == 0 || ch == 0 {
            self.planes.clear();
            self.moments.clear();
            return;
        }
        self.reset_planes(found);
        self.label_rows(cloud, keep, found, t);
        self.moments.clear();
        self.moments
            .extend(self.sums.iter().map(MomentSums::moments));
    }

    /// One empty plane per found plane, reusing the last frame's inlier
    /// lists (no reallocation), and one moment sum about each plane.
    fn reset_planes(&mut self, found: &[Plane]) {
        self.planes.truncate(found.len());
        self.planes.iter_mut().for_each(|p| p.inliers.clear());
        self.planes.resize_with(found.len(), || SegmentedPlane {
            plane: found[0],
            inliers: Vec::new(),
            pixel_box: None,
            centroid: Vector3::zeros(),
            rms_m: 0.0,
            moments: Moments::new(),
        });
        self.sums.clear();
        self.sums
            .extend(found.iter().map(|p| MomentSums::about(-p.d * p.normal)));
    }

    /// Per coarse cell, the distinct planes of the 3x3 cells around it, in
    /// the order of [`cell_neighbourhood`] (row by row); with workers, in
    /// bands of cell rows on their threads (each cell's own: the same sets).
    fn fill_cell_candidates(&mut self) {
        let (cw, ch) = (self.sample.coarse_w, self.sample.coarse_h);
        self.cell_candidates.clear();
        self.cell_candidates.resize(cw * ch, ([NO_PLANE; 9], 0));
        if cw == 0 || ch == 0 {
            return;
        }
        let pool = self.workers.as_deref();
        let bands = pool.map_or(1, |p| (2 * p.current_num_threads()).min(ch));
        let rows = ch.div_ceil(bands);
        let labels = &self.cell_plane[..];
        let fill = move |(b, sets): (usize, &mut [([u16; 9], u8)])| {
            for (r, row) in sets.chunks_mut(cw).enumerate() {
                for (cu, set) in row.iter_mut().enumerate() {
                    *set = candidates_in(labels, (cw, ch), cu, b * rows + r);
                }
            }
        };
        let jobs = self.cell_candidates.chunks_mut(rows * cw).enumerate();
        match pool {
            Some(pool) if bands > 1 => pool.scope(|scope| {
                for job in jobs {
                    scope.spawn(move |_| fill(job));
                }
            }),
            _ => jobs.for_each(fill),
        }
    }

    /// The distinct planes of the 3x3 cells around cell `(cu, cv)`, row by
    /// row.
    #[inline]
    fn candidates_of(&self, cu: usize, cv: usize) -> ([u16; 9], u8) {
        let dims = (self.sample.coarse_w, self.sample.coarse_h);
        candidates_in(&self.cell_plane, dims, cu, cv)
    }

    /// The labelling pass proper: each kept, measured pixel to the nearest
    /// of its cell's candidate planes within the threshold, pushed onto
    /// that plane's inliers and added to its sums. The rows are labelled in
    /// bands of [`LABEL_BAND_ROWS`] (on the workers' threads, when there
    /// are workers), each with its own inlier lists and sums, then joined
    /// in band order: the same inliers, in pixel order, and the same sums,
    /// bit for bit, whatever the thread count.
    fn label_rows(&mut self, cloud: &CloudView<'_>, keep: &[bool], found: &[Plane], t: Threshold) {
        let bands = cloud.height.div_ceil(LABEL_BAND_ROWS);
        if self.bands.len() < bands {
            self.bands.resize_with(bands, LabelBand::default);
        }
        for band in &mut self.bands[..bands] {
            band.reset(&self.sums);
        }
        let grid = RunGrid {
            cloud,
            keep,
            found,
            t,
            candidates: &self.cell_candidates,
            columns: &self.sample.columns,
            rows: &self.sample.rows,
        };
        let jobs = self.bands[..bands].iter_mut().enumerate();
        match self.workers.as_deref() {
            Some(pool) if bands > 1 => pool.scope(|scope| {
                for (b, band) in jobs {
                    scope.spawn(move |_| grid.label_band(b, band));
                }
            }),
            _ => jobs.for_each(|(b, band)| grid.label_band(b, band)),
        }
        for (k, (plane, sums)) in self.planes.iter_mut().zip(&mut self.sums).enumerate() {
            let mut pixel_box = PixelBox::EMPTY;
            for band in &self.bands[..bands] {
                plane.inliers.extend_from_slice(&band.inliers[k]);
                sums.merge(&band.sums[k]);
                pixel_box = pixel_box.union(&band.boxes[k]);
            }
            plane.pixel_box = (!pixel_box.is_empty()).then_some(pixel_box);
        }
    }
}

/// The distinct planes of `labels` (a `cw x ch` grid of sample cells) in
/// the 3x3 cells around cell `(cu, cv)`, row by row.
#[inline]
fn candidates_in(labels: &[u16], (cw, ch): (usize, usize), cu: usize, cv: usize) -> ([u16; 9], u8) {
    let (rows, columns) = neighbourhood_span(cu, cv, cw, ch);
    let mut set = ([NO_PLANE; 9], 0u8);
    for r in rows {
        for &k in &labels[r * cw..][columns.clone()] {
            if k != NO_PLANE && !set.0[..set.1 as usize].contains(&k) {
                set.0[set.1 as usize] = k;
                set.1 += 1;
            }
        }
    }
    set
}

/// Image rows per band of the labelling pass: fixed, so that the sums are
/// added in the same order whatever the thread count (14 bands on a
/// Kinect v2 frame).
pub(super) const LABEL_BAND_ROWS: usize = 32;

/// One band's inliers and sums, per plane.
#[derive(Debug, Default, Clone)]
pub(super) struct LabelBand {
    inliers: Vec<Vec<u32>>,
    sums: Vec<MomentSums>,
    /// The inliers' pixel bounding boxes.
    boxes: Vec<PixelBox>,
    /// A run's inlier flags (an image row long).
    flags: Vec<bool>,
}

impl LabelBand {
    /// Empty, one list and one sum per plane of `empty` (the planes' empty
    /// sums about their origins), reusing the last frame's lists.
    fn reset(&mut self, empty: &[MomentSums]) {
        self.inliers.truncate(empty.len());
        self.inliers.iter_mut().for_each(Vec::clear);
        self.inliers.resize_with(empty.len(), Vec::new);
        self.sums.clear();
        self.sums.extend_from_slice(empty);
        self.boxes.clear();
        self.boxes.resize(empty.len(), PixelBox::EMPTY);
    }
}

/// What the labelling of a band reads: the pixels, the planes, and the
/// sample cells' candidate planes.
#[derive(Clone, Copy)]
struct RunGrid<'a> {
    cloud: &'a CloudView<'a>,
    keep: &'a [bool],
    found: &'a [Plane],
    t: Threshold,
    candidates: &'a [([u16; 9], u8)],
    /// The sample columns and rows, and the pixels each stands for.
    columns: &'a SampleAxis,
    rows: &'a SampleAxis,
}

impl RunGrid<'_> {
    /// Labels the rows of band `b` into `band`.
    fn label_band(&self, b: usize, band: &mut LabelBand) {
        let (w, h) = (self.cloud.width, self.cloud.height);
        let cw = self.columns.len();
        let runs = &self.columns.run_start;
        // Each row is walked a sample cell's columns at a time: pixels
        // of one run share their candidate planes (none: skipped whole).
        band.flags.resize(w, false);
        let mut labeller = RunLabeller {
            inliers: &mut band.inliers,
            sums: &mut band.sums,
            boxes: &mut band.boxes,
            width: w,
            flags: &mut band.flags,
            found: self.found,
            t: self.t,
        };
        for v in b * LABEL_BAND_ROWS..((b + 1) * LABEL_BAND_ROWS).min(h) {
            let cells = &self.candidates[self.rows.of_pixel[v] as usize * cw..][..cw];
            let mut column = 0;
            while column < cw {
                let (candidates, n) = &cells[column];
                let candidates = &candidates[..*n as usize];
                // Sample cells in a row with the same one candidate are
                // one run (the same additions in the same order).
                let mut end = column + 1;
                if let &[k] = candidates {
                    while end < cw && cells[end].1 == 1 && cells[end].0[0] == k {
                        end += 1;
                    }
                }
                let at = (v, runs[column] as usize);
                let run = v * w + at.1..v * w + runs[end] as usize;
                column = end;
                let (keep, points) = (&self.keep[run.clone()], &self.cloud.points[run]);
                match candidates {
                    [] => {}
                    &[k] => labeller.one(k as usize, at, keep, points),
                    several => labeller.nearest(several, at, keep, points),
                }
            }
        }
    }
}

/// The labelling of one run of pixels (a row's pixels within one sample
/// cell's columns) given the run's candidate planes. A pixel is an inlier
/// only with a reading (three finite coordinates) at a depth other than 0:
/// what the pass-through and the normals count as one
/// ([`SegmentedPlane::pixel_box`]).
struct RunLabeller<'a> {
    inliers: &'a mut [Vec<u32>],
    sums: &'a mut [MomentSums],
    boxes: &'a mut [PixelBox],
    /// The image's width.
    width: usize,
    /// Per pixel of a run: an inlier of its one candidate plane.
    flags: &'a mut [bool],
    found: &'a [Plane],
    t: Threshold,
}

impl RunLabeller<'_> {
    /// One candidate (most runs): the run's inliers flagged first, in a
    /// loop without branches (which the compiler vectorises), then pushed
    /// and summed; the same inliers and the same additions in the same
    /// order as [`Self::nearest`]. A pixel without a reading is no inlier:
    /// a coordinate that is not finite makes the distance NaN or infinite
    /// (and the threshold too when it is z, hence its own test). The run
    /// starts at column `at.1` of row `at.0`.
    #[inline]
    fn one(&mut self, k: usize, at: (usize, usize), keep: &[bool], points: &[CloudPoint]) {
        let (plane, inliers) = (&self.found[k], &mut self.inliers[k]);
        let flags = &mut self.flags[..points.len()];
        let t = self.t;
        for (flag, (&kept, point)) in flags.iter_mut().zip(keep.iter().zip(points)) {
            let p = to_vec3(point);
            let near = plane.signed_distance(&p).abs() <= t.at(&p);
            *flag = kept & (p.z.abs() < f64::INFINITY) & (p.z != 0.0) & near;
        }
        let mut sums = self.sums[k];
        let (row_start, before) = (at.0 * self.width, inliers.len());
        for (i, (&flag, point)) in (row_start + at.1..).zip(flags.iter().zip(points)) {
            if flag {
                inliers.push(i as u32);
                sums.add(
                    f64::from(point.x_m),
                    f64::from(point.y_m),
                    f64::from(point.z_m),
                );
            }
        }
        self.sums[k] = sums;
        if let (Some(&a), Some(&b)) = (inliers[before..].first(), inliers.last()) {
            self.boxes[k].add_run(at.0, a as usize - row_start, b as usize - row_start);
        }
    }

    /// Each pixel to the nearest of `candidates` within the threshold (the
    /// run at `at`, as for [`Self::one`]).
    fn nearest(
        &mut self,
        candidates: &[u16],
        at: (usize, usize),
        keep: &[bool],
        points: &[CloudPoint],
    ) {
        let row_start = at.0 * self.width;
        for (i, (&kept, point)) in (row_start + at.1..).zip(keep.iter().zip(points)) {
            if !kept || !is_measured(point) || point.z_m == 0.0 {
                continue;
            }
            let p = to_vec3(point);
            let limit = self.t.at(&p);
            let mut best: Option<(f64, u16)> = None;
            for &k in candidates {
                let d = self.found[k as usize].signed_distance(&p).abs();
                if d <= limit && best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, k));
                }
            }
            if let Some((_, k)) = best {
                let k = k as usize;
                self.inliers[k].push(i as u32);
                self.sums[k].add(p.x, p.y, p.z);
                self.boxes[k].add_run(at.0, i - row_start, i - row_start);
            }
        }
    }
}
