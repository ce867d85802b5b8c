//! The fit of a proposed region: the paper's RANSAC over the region's own
//! free sample points (three-point hypotheses scored by their consensus,
//! each new best refitted by TLS on its inliers while its consensus grows,
//! the adaptive count for `ransac.confidence`), then the TLS plane of the
//! winner's inliers. The region's free sample cells whose point is an
//! inlier seed the plane's surface on the sample grid (`boundary.rs`: the
//! connected free cells within the inlier distance), which is refitted by
//! TLS and flooded once more from the refitted plane; the plane is the TLS
//! fit of that surface. A region whose cells earlier planes took (but
//! fewer than `min_cells`) is no plane.

use nalgebra::Vector3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::boundary::flood_band;
use super::grid::CellGrid;
use crate::plane_fit::{fit_tls, Moments, Plane};
use crate::ransac_planes::{RansacConfig, SampleCells, Threshold, NO_PLANE};

/// Hypotheses are scored on at most this many of the region's points (a
/// regular subset).
const SCORE_POINTS: usize = 500;
/// Hypotheses drawn per region at least.
const MIN_HYPOTHESES: usize = 32;
/// Local-optimisation refits of a new best, at most.
const LO_STEPS: usize = 4;
/// Refits of the winner on all the region's points, at most.
const SETTLE_STEPS: usize = 8;

/// The fit's buffers.
#[derive(Debug, Default, Clone)]
pub(super) struct RegionFit {
    /// The region's sample points, their sample cells and inlier
    /// distances.
    points: Vec<Vector3<f64>>,
    sample_cells: Vec<u32>,
    limits: Vec<f64>,
    /// The score subset: indices into `points`, and its points' coordinates
    /// and inlier distances in a structure of arrays (the consensus of a
    /// hypothesis, in lanes).
    score: Vec<u32>,
    score_xyz: [Vec<f64>; 3],
    score_limits: Vec<f64>,
    /// The flood's seeds and the plane's sample cells.
    seeds: Vec<u32>,
    taken: Vec<u32>,
}

/// What a region's fit needs besides the region and the RANSAC config.
#[derive(Debug, Clone, Copy)]
pub(super) struct FitTarget {
    /// The label of the plane.
    pub label: u16,
    pub t: Threshold,
    /// Sample cells a plane must hold.
    pub min_cells: usize,
}

impl RegionFit {
    /// Fits the free sample points of `region` (cells of `grid`) and labels
    /// the plane's sample cells `target.label`; `None` (and no label) when
    /// no plane has 3 inliers or its surface holds fewer than
    /// `target.min_cells` cells.
    pub fn fit(
        &mut self,
        cells: &mut SampleCells<'_>,
        (region, grid): (&[u32], &CellGrid),
        target: FitTarget,
        config: &RansacConfig,
        rng: &mut ChaCha8Rng,
    ) -> Option<Plane> {
        let FitTarget {
            label,
            t,
            min_cells,
        } = target;
        self.gather(cells, region, grid, t);
        if self.points.len() < min_cells.max(3) {
            return None;
        }
        let mut plane = self.settle(self.ransac(config, rng)?)?;
        self.flood(cells, &plane, label, t);
        if let Some(refit) = self.surface_fit(cells) {
            // Flood again from the surface's own plane.
            self.release(cells);
            plane = refit;
            self.flood(cells, &plane, label, t);
        }
        if self.taken.len() < min_cells {
            self.release(cells);
            return None;
        }
        Some(self.surface_fit(cells).unwrap_or(plane))
    }

    /// The sample cells of the last plane fitted.
    pub fn taken(&self) -> &[u32] {
        &self.taken
    }

    /// The TLS plane of the last flood's cells.
    fn surface_fit(&self, cells: &SampleCells<'_>) -> Option<Plane> {
        let mut moments = Moments::new();
        for &c in &self.taken {
            moments.add(&cells.points[c as usize]);
        }
        fit_tls(&moments)
    }

    /// Labels the region's free points within the inlier distance of
    /// `plane` and floods the band from them (`taken`: the cells labelled).
    fn flood(&mut self, cells: &mut SampleCells<'_>, plane: &Plane, label: u16, t: Threshold) {
        self.seeds.clear();
        for ((p, &limit), &c) in self.points.iter().zip(&self.limits).zip(&self.sample_cells) {
            if plane.signed_distance(p).abs() <= limit && cells.labels[c as usize] == NO_PLANE {
                cells.labels[c as usize] = label;
                self.seeds.push(c);
            }
        }
        self.taken.clear();
        flood_band(cells, plane, label, t, (&self.seeds, &mut self.taken));
    }

    /// Frees the cells of the last flood.
    fn release(&mut self, cells: &mut SampleCells<'_>) {
        for &c in &self.taken {
            cells.labels[c as usize] = NO_PLANE;
        }
        self.taken.clear();
    }

    /// The TLS plane of `plane`'s inliers among all the region's points,
    /// refitted on its own inliers until their count stops growing (a
    /// fixed point that does not depend on which hypothesis won).
    fn settle(&self, mut plane: Plane) -> Option<Plane> {
        let mut count = 0;
        for _ in 0..SETTLE_STEPS {
            let mut moments = Moments::new();
            for (p, &limit) in self.points.iter().zip(&self.limits) {
                if plane.signed_distance(p).abs() <= limit {
                    moments.add(p);
                }
            }
            if moments.count() <= count {
                break;
            }
            count = moments.count();
            plane = fit_tls(&moments)?;
        }
        Some(plane)
    }

    /// The region's free sample points (raster order within each cell).
    fn gather(&mut self, cells: &SampleCells<'_>, region: &[u32], grid: &CellGrid, t: Threshold) {
        self.points.clear();
        self.sample_cells.clear();
        self.limits.clear();
        for &c in region {
            let (cu, cv) = (c as usize % grid.width, c as usize / grid.width);
            for row in grid.rows_of.samples(cv) {
                for column in grid.columns_of.samples(cu) {
                    let j = row * cells.width + column;
                    let p = cells.points[j];
                    if p.x.is_finite() && cells.labels[j] == NO_PLANE {
                        self.points.push(p);
                        self.sample_cells.push(j as u32);
                        self.limits.push(t.at(&p));
                    }
                }
            }
        }
        let n = self.points.len();
        let m = n.min(SCORE_POINTS);
        self.score.clear();
        self.score.extend((0..m).map(|i| (i * n / m.max(1)) as u32));
        let [xs, ys, zs] = &mut self.score_xyz;
        for (k, coordinate) in [xs, ys, zs].into_iter().enumerate() {
            coordinate.clear();
            coordinate.extend(self.score.iter().map(|&j| self.points[j as usize][k]));
        }
        self.score_limits.clear();
        self.score_limits
            .extend(self.score.iter().map(|&j| self.limits[j as usize]));
    }

    /// The consensus of `plane` on the score subset.
    fn consensus(&self, plane: &Plane) -> usize {
        let [xs, ys, zs] = &self.score_xyz;
        let points = xs.iter().zip(ys).zip(zs).zip(&self.score_limits);
        points
            .map(|(((&x, &y), &z), &limit)| {
                let p = Vector3::new(x, y, z);
                usize::from(plane.signed_distance(&p).abs() <= limit)
            })
            .sum()
    }

    /// The TLS plane of `plane`'s inliers in the score subset.
    fn refit(&self, plane: &Plane) -> Option<Plane> {
        let mut m = Moments::new();
        for &j in &self.score {
            let p = &self.points[j as usize];
            if plane.signed_distance(p).abs() <= self.limits[j as usize] {
                m.add(p);
            }
        }
        fit_tls(&m)
    }

    /// RANSAC over the region's points: the best (locally optimised)
    /// three-point hypothesis.
    fn ransac(&self, config: &RansacConfig, rng: &mut ChaCha8Rng) -> Option<Plane> {
        let n = self.points.len();
        if n < 3 || self.score.is_empty() {
            return None;
        }
        let log_fail = (1.0 - config.confidence).ln();
        let mut needed = config.max_iterations;
        let mut best: Option<(usize, Plane)> = None;
        let mut it = 0;
        while it < needed.max(MIN_HYPOTHESES).min(config.max_iterations) {
            it += 1;
            let (a, b, c) = (
                rng.random_range(0..n),
                rng.random_range(0..n),
                rng.random_range(0..n),
            );
            if a == b || b == c || a == c {
                continue;
            }
            let Some(plane) =
                Plane::from_three_points(&self.points[a], &self.points[b], &self.points[c])
            else {
                continue;
            };
            let count = self.consensus(&plane);
            if best.as_ref().is_some_and(|(s, _)| count <= *s) {
                continue;
            }
            let (mut count, mut plane) = (count, plane);
            for _ in 0..LO_STEPS {
                let Some(refit) = self.refit(&plane) else {
                    break;
                };
                let c = self.consensus(&refit);
                if c <= count {
                    break;
                }
                (count, plane) = (c, refit);
            }
            best = Some((count, plane));
            let w = count as f64 / self.score.len() as f64;
            let fail = (1.0 - w * w * w).ln();
            if fail < 0.0 {
                needed = (log_fail / fail).ceil().min(config.max_iterations as f64) as usize;
            }
        }
        best.filter(|(s, _)| *s >= 3).map(|(_, p)| p)
    }
}
