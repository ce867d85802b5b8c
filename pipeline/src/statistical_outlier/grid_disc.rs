//! The m = 20 fast path: each pixel's 20 grid-nearest neighbours (the 5x5
//! window without its corners), every pair's distance computed once for
//! both pixels, a row at a time.

use super::fallback::fallback_disc;
use super::StatisticalOutlierFilter;

/// Half of the 20 offsets with du^2 + dv^2 <= 5 (the 5x5 window without its
/// corners); the other half is the same pairs seen from the other pixel.
const HALF_DISC: [(isize, isize); 10] = [
    (1, 0),
    (2, 0),
    (-2, 1),
    (-1, 1),
    (0, 1),
    (1, 1),
    (2, 1),
    (-1, 2),
    (0, 2),
    (1, 2),
];

/// A pixel's 20 pair distances in the pair rows, in the order they are
/// summed: `(k, dv, shift)`, the pair of offset `HALF_DISC[k]` stored
/// with the row `dv` rows up, at column `u + 2 - shift` of that pair row.
const DISC_TERMS: [(usize, usize, isize); 20] = [
    (7, 2, -1),
    (8, 2, 0),
    (9, 2, 1),
    (2, 1, -2),
    (3, 1, -1),
    (4, 1, 0),
    (5, 1, 1),
    (6, 1, 2),
    (0, 0, 0),
    (0, 0, 1),
    (1, 0, 0),
    (1, 0, 2),
    (2, 0, 0),
    (3, 0, 0),
    (4, 0, 0),
    (5, 0, 0),
    (6, 0, 0),
    (7, 0, 0),
    (8, 0, 0),
    (9, 0, 0),
];

/// Grid neighbours a pixel must have to take the mean distance to those it
/// has: half of m.
pub(super) const MIN_PRESENT: usize = 10;

/// True when `HALF_DISC[start..start + len]` are `(du, dv)`, `(du + 1, dv)`,
/// ...: offsets that reach one image row, from column `du` on.
const fn disc_row_run(start: usize, len: usize, du: isize, dv: isize) -> bool {
    let mut k = 0;
    while k < len {
        let (a, b) = HALF_DISC[start + k];
        if a != du + k as isize || b != dv {
            return false;
        }
        k += 1;
    }
    true
}

/// The scratch of one band of rows: the pair distances of its last three
/// rows, one row per half-disc offset and row slot, and a row's sums.
#[derive(Debug, Default, Clone)]
pub(super) struct DiscScratch {
    pairs: Vec<f32>,
    row_sum: Vec<f32>,
}

/// The NaN-padded coordinate planes and their layout, shared by the bands.
#[derive(Clone, Copy)]
struct Padded<'a> {
    planes: [&'a [f32]; 3],
    w: usize,
    pad: usize,
}

impl StatisticalOutlierFilter {
    /// The m = 20 fast path: each pixel's 20 grid-nearest neighbours, every
    /// pair's distance computed once. With a pool the image is cut into
    /// bands of rows, two per thread, each computed as the whole image is
    /// (a band's first two pair rows are its upper neighbour's last, done
    /// again): every statistic is the same bits whatever the thread count.
    ///
    /// With `present` a pixel that has at least [`MIN_PRESENT`] of its 20
    /// grid neighbours takes the mean distance to those it has instead (the
    /// finite pair distances, summed in the same order); only the others
    /// search the 9x9 window.
    pub(super) fn grid_disc_statistic(
        &mut self,
        (w, h, pad): (usize, usize, usize),
        present: bool,
        pool: Option<&rayon::ThreadPool>,
    ) {
        // The pair rows span the columns -2..w+2 of the rows -2..h; `pad`
        // (4 for m = 20) keeps every access inside the padded planes.
        debug_assert!(pad >= 4);
        let padded = Padded {
            planes: [&self.xs[..], &self.ys[..], &self.zs[..]],
            w,
            pad,
        };
        let stats = &mut self.mean_distance[..w * h];
        let bands = pool.map_or(1, |p| (2 * p.current_num_threads()).min(h));
        if self.disc_scratch.len() < bands {
            self.disc_scratch.resize_with(bands, DiscScratch::default);
        }
        let rows = h.div_ceil(bands);
        let jobs = stats
            .chunks_mut(rows * w)
            .zip(&mut self.disc_scratch)
            .enumerate();
        match pool {
            Some(pool) if bands > 1 => pool.scope(|scope| {
                for (b, (stats, scratch)) in jobs {
                    scope.spawn(move |_| disc_band(padded, b * rows, stats, present, scratch));
                }
            }),
            _ => {
                for (b, (stats, scratch)) in jobs {
                    disc_band(padded, b * rows, stats, present, scratch);
                }
            }
        }
    }
}

/// The statistics of the image rows `v0..` that `stats` holds (whole
/// rows). Rows are processed top to bottom; the distances from row `R` to
/// rows `R`, `R+1` and `R+2` are kept for three rows, so row `R`'s sums
/// gather its 20 distances from the rows `R-2..=R` without scattering into
/// other rows. A NaN in the sum means a missing neighbour (NaN coordinates
/// propagate), and such pixels take the fallback.
fn disc_band(padded: Padded<'_>, v0: usize, stats: &mut [f32], present: bool, s: &mut DiscScratch) {
    const M: usize = 20;
    let Padded { planes, w, pad } = padded;
    let [xs, ys, zs] = planes;
    let pw = w + 2 * pad;
    let ew = w + 4;
    s.pairs.clear();
    s.pairs.resize(HALF_DISC.len() * 3 * ew, f32::NAN);
    s.row_sum.clear();
    s.row_sum.resize(w, 0.0);
    let first_row = v0 + pad;
    for row in first_row - 2..first_row + stats.len() / w {
        let slot = row % 3;
        let first = row * pw + pad - 2;
        let out = &mut s.pairs[slot * HALF_DISC.len() * ew..][..HALF_DISC.len() * ew];
        // The offsets one image row apart at a time (HALF_DISC is in
        // that order): the centre row is loaded once per group, and the
        // other row once per plane. The group sizes (2, 5, 3) and the
        // other rows' bases (`dv * pw + du` of a group's first offset:
        // 1, pw - 2, 2 * pw - 1) are HALF_DISC's, checked here:
        const {
            assert!(
                disc_row_run(0, 2, 1, 0)
                    && disc_row_run(2, 5, -2, 1)
                    && disc_row_run(7, 3, -1, 2)
                    && HALF_DISC.len() == 2 + 5 + 3
            )
        };
        let (same_row, out) = out.split_at_mut(2 * ew);
        let (next_row, two_rows) = out.split_at_mut(5 * ew);
        pair_distances::<2>(planes, first, first + 1, same_row);
        pair_distances::<5>(planes, first, first + pw - 2, next_row);
        pair_distances::<3>(planes, first, first + 2 * pw - 1, two_rows);
        if row < first_row {
            continue;
        }
        disc_row_sums(&s.pairs, row, ew, &mut s.row_sum);
        let v = row - first_row;
        let centre = row * pw + pad;
        // The sum is NaN where the centre or a neighbour has no reading;
        // blocks with a measured centre among those take the mean of the
        // neighbours present (with `present`, at least MIN_PRESENT) or
        // the exact window search.
        const BLOCK: usize = 32;
        let stats = &mut stats[v * w..(v + 1) * w];
        let measured = &zs[centre..centre + w];
        let blocks = stats
            .chunks_mut(BLOCK)
            .zip(s.row_sum[..w].chunks(BLOCK).zip(measured.chunks(BLOCK)));
        let mut starts = None;
        for (b, (stats, (sums, block_z))) in blocks.enumerate() {
            let mut missing = false;
            for ((stat, &sum), &z) in stats.iter_mut().zip(sums).zip(block_z) {
                *stat = sum / M as f32;
                missing |= sum.is_nan() & z.is_finite();
            }
            if !missing {
                continue;
            }
            let starts = starts.get_or_insert_with(|| disc_starts(row, ew));
            const { assert!(BLOCK <= 32) };
            let (needing, n) = needing_pixels(stats, block_z);
            // Many such pixels in a block: their present sums for the
            // whole block at once (the same sums, bit for bit).
            let u0 = b * BLOCK;
            let block = (present && n >= PRESENT_BLOCK_MIN)
                .then(|| PresentBlock::of(&s.pairs, starts, u0, stats.len()));
            for &j in &needing[..n] {
                let j = usize::from(j);
                let near = match &block {
                    Some(block) => block.mean(j),
                    None => present
                        .then(|| present_mean(&s.pairs, starts, u0 + j))
                        .flatten(),
                };
                stats[j] = near.unwrap_or_else(|| fallback_disc([xs, ys, zs], centre + u0 + j, pw));
            }
        }
    }
}

/// Sums the 20 pair distances of every pixel of padded row `row` into
/// `row_sum`, in a fixed order that sets the f32 rounding of the
/// statistic (pinned bit for bit by the test
/// `a_complete_disc_sums_its_distances_in_f32_in_a_fixed_order`): the
/// pairs from two rows up, from one row up, then the row's own.
fn disc_row_sums(pairs: &[f32], row: usize, ew: usize, row_sum: &mut [f32]) {
    let w = ew - 4;
    // Pixel u sits at column e = u + 2 of a pair row; the pair (k) seen
    // from its other end is at column e - du_k of row row - dv_k.
    let term = |k: usize, dv: usize, shift: isize| -> &[f32] {
        let base = ((row - dv) % 3 * HALF_DISC.len() + k) * ew;
        let start = (2 - shift) as usize;
        &pairs[base + start..base + start + w]
    };
    let terms: [&[f32]; 20] = DISC_TERMS.map(|(k, dv, shift)| term(k, dv, shift));
    // Two passes of ten terms: twenty streams at once do not fit the
    // registers.
    let out = &mut row_sum[..w];
    for (u, o) in out.iter_mut().enumerate() {
        let mut s = terms[0][u];
        for t in &terms[1..10] {
            s += t[u];
        }
        *o = s;
    }
    for (u, o) in out.iter_mut().enumerate() {
        let mut s = *o;
        for t in &terms[10..] {
            s += t[u];
        }
        *o = s;
    }
}

/// Where pixel 0's 20 pair distances sit in the pair rows for padded row
/// `row` (pixel `u`'s are `u` further), in `DISC_TERMS` order.
fn disc_starts(row: usize, ew: usize) -> [usize; 20] {
    DISC_TERMS
        .map(|(k, dv, shift)| ((row - dv) % 3 * HALF_DISC.len() + k) * ew + (2 - shift) as usize)
}

/// The mean distance from pixel `u` to those of its 20 grid neighbours
/// that have a reading (the finite pair distances at `starts`, summed in
/// the order of a complete disc); `None` with fewer than [`MIN_PRESENT`].
#[inline]
pub(super) fn present_mean(pairs: &[f32], starts: &[usize; 20], u: usize) -> Option<f32> {
    let (mut sum, mut count) = (0.0f32, 0u32);
    for &s in starts {
        let d = pairs[s + u];
        let finite = !d.is_nan();
        sum += if finite { d } else { 0.0 };
        count += u32::from(finite);
    }
    (count as usize >= MIN_PRESENT).then(|| sum / count as f32)
}

/// The pixels of a block (at most 32) with a reading but no complete disc
/// (a NaN statistic so far), and how many there are.
#[inline]
fn needing_pixels(stats: &[f32], block_z: &[f32]) -> ([u8; 32], usize) {
    let (mut needing, mut n) = ([0u8; 32], 0);
    for (j, (stat, z)) in stats.iter().zip(block_z).enumerate() {
        if stat.is_nan() && z.is_finite() {
            needing[n] = j as u8;
            n += 1;
        }
    }
    (needing, n)
}

/// Pixels of a block of 32 without a complete disc from which their present
/// neighbours' sums are taken for the whole block at once: one pixel's
/// alone costs about an eighth of the block's (the block's 64 sums do not
/// fit the registers). Set by callgrind: 8 saves the most on stairs-front
/// and the office (1.4 M of `Estimator::run` on stairs-front against every
/// pixel alone; 6 and 12 about 0.1-0.3 M less).
const PRESENT_BLOCK_MIN: usize = 8;

/// The finite pair distances' sums and counts of the pixels `u0..u0 + len`
/// of a row (at most 32), each summed as [`present_mean`] sums it: from
/// 0.0, the terms in `DISC_TERMS` order, a missing one adding 0.0. (The
/// counts are `f32`, exact to 2^24, so that a term is one lane's work.)
#[derive(Debug, Clone, Copy)]
pub(super) struct PresentBlock {
    sum: [f32; 32],
    count: [f32; 32],
}

impl PresentBlock {
    /// The sums of the pixels `u0..u0 + len` (`len <= 32`) from the pair
    /// rows at `starts` (those of pixel 0).
    #[inline]
    pub(super) fn of(pairs: &[f32], starts: &[usize; 20], u0: usize, len: usize) -> Self {
        let mut block = Self {
            sum: [0.0; 32],
            count: [0.0; 32],
        };
        for &start in starts {
            let terms = &pairs[start + u0..][..len];
            match <&[f32; 32]>::try_from(terms) {
                // A whole block: lengths the compiler knows, in lanes.
                Ok(terms) => block.add(terms),
                Err(_) => block.add(terms),
            }
        }
        block
    }

    /// Adds one term of each pixel (`terms[j]`, pixel `j`'s).
    #[inline(always)]
    fn add(&mut self, terms: &[f32]) {
        let n = terms.len();
        let (sum, count) = (&mut self.sum[..n], &mut self.count[..n]);
        for j in 0..n {
            let d = terms[j];
            let finite = !d.is_nan();
            sum[j] += if finite { d } else { 0.0 };
            count[j] += if finite { 1.0 } else { 0.0 };
        }
    }

    /// [`present_mean`] of the block's pixel `j`.
    #[inline]
    pub(super) fn mean(&self, j: usize) -> Option<f32> {
        let count = self.count[j];
        (count >= MIN_PRESENT as f32).then(|| self.sum[j] / count)
    }
}

/// Distances from the `n` points at `first..` of the coordinate planes to
/// the points at `other + k..`, for k in `0..K`, into the `K` rows of `n`
/// values of `out` (`out.len() == K * n`); NaN where either point has no
/// reading. The `K` offsets share one other row, so the centre row is
/// loaded once for all of them.
#[inline(always)]
fn pair_distances<'a, const K: usize>(
    planes: [&'a [f32]; 3],
    first: usize,
    other: usize,
    out: &mut [f32],
) {
    let n = out.len() / K;
    debug_assert_eq!(out.len(), K * n);
    let [xs, ys, zs] = planes;
    let (cx, cy, cz) = (
        &xs[first..first + n],
        &ys[first..first + n],
        &zs[first..first + n],
    );
    // The other row at each offset, re-sliced to `[..n]` like the output
    // rows: `o[k][u]` then needs no index arithmetic in the loop (a checked
    // `u + k` in builds with overflow checks stops the loop vectorising).
    let shifted =
        |plane: &'a [f32]| -> [&'a [f32]; K] { std::array::from_fn(|k| &plane[other + k..][..n]) };
    let (ox, oy, oz) = (shifted(xs), shifted(ys), shifted(zs));
    let mut rows = out.chunks_exact_mut(n);
    // `out` holds exactly K rows of n, so the default (empty) row is never
    // taken. Each row is re-sliced to `[..n]`: its length is then known to
    // be n and the compiler drops the bounds checks of `row[u]` below.
    let mut outs: [&mut [f32]; K] = std::array::from_fn(|_| rows.next().unwrap_or_default());
    for row in &mut outs {
        *row = &mut std::mem::take(row)[..n];
    }
    for u in 0..n {
        let (x, y, z) = (cx[u], cy[u], cz[u]);
        for (k, row) in outs.iter_mut().enumerate() {
            let dx = x - ox[k][u];
            let dy = y - oy[k][u];
            let dz = z - oz[k][u];
            row[u] = (dx * dx + dy * dy + dz * dz).sqrt();
        }
    }
}
