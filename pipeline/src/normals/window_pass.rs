//! The window pass: each member's smallest window in the summed-area
//! table (`window_table.rs`) and the normal of that window's moments
//! (`window_cache.rs`: once per distinct window), member by member.
//!
//! With worker threads the members are cut into chunks of [`CHUNK`], each
//! passed on a worker with a cache of its own. A member's window and
//! normal depend on nothing but the table and the member, and a cached
//! normal is the one its window's sums give, so the normals, radii,
//! fallbacks (in member order) and counts are the same, bit for bit,
//! whatever the chunks. Called from inside a pool's job (the estimator's
//! two planes run at once), a worker that has finished its own plane
//! takes chunks of the other: the larger plane (a floor beside a riser)
//! no longer sets the pace alone.

use nalgebra::Vector3;

use super::eigen::smallest_eigenvector_sym3;
use super::window_cache::WindowNormals;
use super::window_table::{smallest_window, start_radius};
use super::TABLE_CELL_PX;
use super::{normal_from_sums_by, orient, Bounds, NormalStats, NormalsConfig, CHANNELS};
use crate::cloud::{is_measured, CloudView};

/// Members to a chunk on the workers: a few chunks for the 10,000 points
/// the pass-through keeps, each long enough that the chunk's cache (2,048
/// slots cleared) and its spawn are small against its windows.
pub(super) const CHUNK: usize = 2048;

/// What every chunk reads: the cloud, the table over `bounds` and the
/// configuration.
#[derive(Clone, Copy)]
pub(super) struct WindowPass<'a> {
    pub cloud: &'a CloudView<'a>,
    pub table: &'a [[f64; CHANNELS]],
    pub bounds: Bounds,
    pub config: &'a NormalsConfig,
    /// The table's moments are about `centre`.
    pub centre: Vector3<f64>,
    pub noise_scale: f64,
    pub viewpoint: Vector3<f64>,
}

/// One chunk's own buffers: its members that need the k-d tree (slots of
/// the whole call), its cache and its counts.
#[derive(Debug, Clone, Default)]
pub(super) struct WindowChunk {
    pub fallback: Vec<usize>,
    cache: WindowNormals,
    pub stats: NormalStats,
}

impl WindowPass<'_> {
    /// The window and normal of each of `members` (slots `first_slot..`
    /// of the call): `radius` how far each window grew beyond its start
    /// (`u16::MAX`: none), `normals` its normal towards the viewpoint (left
    /// as they are where there is none). A member outside the bounds or
    /// without a window holding K points goes to the chunk's fallback.
    pub fn run(
        &self,
        (members, first_slot): (&[u32], usize),
        radius: &mut [u16],
        normals: &mut [Vector3<f64>],
        chunk: &mut WindowChunk,
    ) {
        chunk.fallback.clear();
        chunk.cache.clear();
        chunk.stats = NormalStats::default();
        let (cloud, b) = (self.cloud, &self.bounds);
        let w = cloud.width;
        let k = self.config.neighbours.max(3);
        let focal = cloud.focal_px();
        let r0 = start_radius(k);
        let r_max = self.config.max_window_radius_px.max(r0);
        let g = TABLE_CELL_PX;
        let cells = (b.width.div_ceil(g), b.height.div_ceil(g));
        let slots = members.iter().zip(radius).zip(normals).enumerate();
        for (j, ((&pixel, radius), normal)) in slots {
            let pixel = pixel as usize;
            let Some(p) = cloud.points.get(pixel).filter(|p| is_measured(p)) else {
                chunk.stats.undefined += 1;
                continue;
            };
            let (Some(u), Some(v)) = (
                (pixel % w).checked_sub(b.u0).filter(|&u| u < b.width),
                (pixel / w).checked_sub(b.v0).filter(|&v| v < b.height),
            ) else {
                chunk.fallback.push(first_slot + j);
                continue;
            };
            // The patch spans at least `min_patch_radius_m` on the surface.
            let metric =
                (self.config.min_patch_radius_m * focal / f64::from(p.z_m).max(1e-3)).ceil();
            let r_start = if metric.is_finite() {
                (metric as usize).clamp(r0, r_max.max(r0))
            } else {
                r0
            };
            let Some((m, r, window)) =
                smallest_window(self.table, cells, (u, v), r_start..=r_max, k)
            else {
                chunk.fallback.push(first_slot + j);
                continue;
            };
            chunk.stats.from_window += 1;
            // 0: the first window sufficed (an interior point).
            *radius = (r - r_start) as u16;
            let Some(p) = cloud.point(pixel).filter(|_| m[0] >= 0.5) else {
                continue;
            };
            let (centre, noise) = (&self.centre, self.noise_scale);
            let found = chunk.cache.get_or_solve(window, || {
                normal_from_sums_by(&m, centre, noise, focal, smallest_eigenvector_sym3)
            });
            match found {
                Some(n) => *normal = orient(n, &p, &self.viewpoint),
                None => chunk.stats.undefined += 1,
            }
        }
    }
}
