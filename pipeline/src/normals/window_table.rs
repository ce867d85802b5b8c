//! The summed-area tables of a plane's moments and the smallest window
//! around a point that holds K of its points (module doc of `normals`).

use nalgebra::Vector3;

use super::window_cache::WindowKey;
use super::{moments, Bounds, NormalEstimator, CHANNELS, TABLE_CELL_PX};
use crate::cloud::{to_vec3, CloudView};

impl NormalEstimator {
    /// Summed-area tables of the ten moments over the bounding box, one
    /// cell per `TABLE_CELL_PX` x `TABLE_CELL_PX` block of pixels, from
    /// `pixels`: measured, in pixel order, inside `b` (a [`PlaneSupport`]'s).
    ///
    /// [`PlaneSupport`]: super::PlaneSupport
    pub(super) fn build_table(
        &mut self,
        cloud: &CloudView<'_>,
        pixels: &[u32],
        b: &Bounds,
        c: &Vector3<f64>,
    ) {
        let g = TABLE_CELL_PX;
        let (bw, bh) = (b.width.div_ceil(g), b.height.div_ceil(g));
        let tw = bw + 1;
        self.block_row.clear();
        self.block_row.resize(bw, [0.0; CHANNELS]);
        // One pass, row by row: each cell is written once.
        self.table.clear();
        self.table.reserve(tw * (bh + 1));
        self.table
            .extend(std::iter::repeat_n([0.0; CHANNELS], tw + 1));
        let mut rest = pixels;
        for bv in 0..bh {
            rest = self.sum_block_row(cloud, rest, b, c, bv);
            let mut run = [0.0; CHANNELS];
            for bu in 0..bw {
                let above = &self.table[bv * tw + bu + 1];
                // Each block is zeroed as it is read, for the next block
                // row: no separate clear (which the compiler makes a libc
                // memset, counted per byte by callgrind).
                let block = std::mem::replace(&mut self.block_row[bu], [0.0; CHANNELS]);
                let mut cell = [0.0; CHANNELS];
                for ch in 0..CHANNELS {
                    run[ch] += block[ch];
                    cell[ch] = run[ch] + above[ch];
                }
                self.table.push(cell);
            }
            if bv + 1 < bh {
                self.table.push([0.0; CHANNELS]);
            }
        }
    }

    /// The moments (relative to `c`) of the pixels of `pixels` (measured,
    /// in pixel order, inside `b`) that lie in the pixel rows of block row
    /// `bv`, the first ones of `pixels`, summed per block into
    /// `block_row` (all zeros on entry: `build_table` zeroes each block as
    /// it reads it); returns the pixels after these rows.
    fn sum_block_row<'p>(
        &mut self,
        cloud: &CloudView<'_>,
        mut pixels: &'p [u32],
        b: &Bounds,
        c: &Vector3<f64>,
        bv: usize,
    ) -> &'p [u32] {
        let g = TABLE_CELL_PX;
        let w = cloud.width;
        // The pixel rows of this row of blocks, walked without a
        // division per pixel; a block's sum is kept in registers while
        // consecutive pixels fall into it.
        for v in b.v0 + bv * g..(b.v0 + (bv + 1) * g).min(b.v0 + b.height) {
            let row_start = v * w;
            let (first, end) = (row_start + b.u0, row_start + w);
            let in_row = pixels.partition_point(|&p| (p as usize) < end);
            let (row, after) = pixels.split_at(in_row);
            pixels = after;
            // (block, moments) of each of the row's pixels.
            let mut members = row.iter().map(|&pixel| {
                let pixel = pixel as usize;
                (
                    (pixel - first) / g,
                    moments(&(to_vec3(&cloud.points[pixel]) - c)),
                )
            });
            let Some((mut at, mut sums)) = members.next() else {
                continue;
            };
            for (block, m) in members {
                if block == at {
                    add_into(&mut sums, &m);
                } else {
                    add_into(&mut self.block_row[at], &sums);
                    (at, sums) = (block, m);
                }
            }
            add_into(&mut self.block_row[at], &sums);
        }
        pixels
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
pub(super) fn start_radius(k: usize) -> usize {
    let mut r = 1;
    while (2 * r + 1) * (2 * r + 1) < k {
        r += 1;
    }
    r
}

/// The moment sums of the smallest window around table pixel `(u, v)`,
/// its radius tried from `radii` in turn, that holds at least `k` points,
/// that radius and the window's [`WindowKey`]; `None` when none does (or
/// the window covers the whole table of `cells` = (columns, rows) before).
/// A window holds the table cells its pixels touch.
#[inline]
pub(super) fn smallest_window(
    table: &[[f64; CHANNELS]],
    (bw, bh): (usize, usize),
    (u, v): (usize, usize),
    radii: std::ops::RangeInclusive<usize>,
    k: usize,
) -> Option<([f64; CHANNELS], usize, WindowKey)> {
    let g = TABLE_CELL_PX;
    let tw = bw + 1;
    for r in radii {
        // The table cells the window's pixels touch.
        let (a0, a1) = (u.saturating_sub(r) / g, ((u + r) / g + 1).min(bw));
        let (b0, b1) = (v.saturating_sub(r) / g, ((v + r) / g + 1).min(bh));
        // The four corners once (not their index arithmetic per channel).
        let (p11, p01) = (&table[b1 * tw + a1], &table[b0 * tw + a1]);
        let (p10, p00) = (&table[b1 * tw + a0], &table[b0 * tw + a0]);
        let s = |c: usize| p11[c] - p01[c] - p10[c] + p00[c];
        let count = s(0);
        if count + 0.5 >= k as f64 {
            let mut m = [0.0; CHANNELS];
            for (c, mc) in m.iter_mut().enumerate() {
                *mc = s(c);
            }
            return Some((m, r, WindowKey::new(a0, a1, b0, b1)));
        }
        if a0 == 0 && b0 == 0 && a1 == bw && b1 == bh {
            break;
        }
    }
    None
}
