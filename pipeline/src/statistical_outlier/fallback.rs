//! The exact fallback for pixels missing a grid neighbour: the m nearest
//! measured pixels of a square window, selected without branches for
//! m = 20.

/// The widest fallback window: radius `window_radius(MAX_NEIGHBOURS) + 2`.
const MAX_FALLBACK_SIDE: usize = 11;

/// Floats after the last padded row, so that a window row can be read four
/// lanes at a time past its end.
pub(super) const TAIL: usize = 3;

/// The squared distances from the point at padded index `centre` to the
/// other points of the `S x S` window around it, row-major with the centre
/// left out (its slot holds the window's last pixel) in the first
/// `S * S - 1` values, infinity where a distance is not finite (no reading).
/// Each window row is computed a whole number of 4-lane vectors wide: the
/// extra values are overwritten by the next row or lie past the candidates.
#[inline(always)]
fn window_sq_distances<const S: usize>(
    planes: [&[f32]; 3],
    centre: usize,
    pw: usize,
    sq: &mut [f32],
) {
    const { assert!(S % 2 == 1 && S <= MAX_FALLBACK_SIDE && S.next_multiple_of(4) - S <= TAIL) };
    let wide = S.next_multiple_of(4);
    let [xs, ys, zs] = planes;
    let (x, y, z) = (xs[centre], ys[centre], zs[centre]);
    let r = S / 2;
    for dv in 0..S {
        let start = centre + dv * pw - r * pw - r;
        let (rx, ry, rz) = (
            &xs[start..start + wide],
            &ys[start..start + wide],
            &zs[start..start + wide],
        );
        let out = &mut sq[dv * S..dv * S + wide];
        for k in 0..wide {
            let (dx, dy, dz) = (x - rx[k], y - ry[k], z - rz[k]);
            // NaN (no reading) becomes infinity: `min` returns the non-NaN
            // operand.
            out[k] = (dx * dx + dy * dy + dz * dz).min(f32::INFINITY);
        }
    }
    let last = S * S - 1;
    sq[last / 2] = sq[last];
}

/// The statistic from the `S x S` window around padded index `centre`: the
/// mean of the `m` smallest finite distances, or infinity when fewer than
/// `m` are finite (an isolated point). Used by the general path.
pub(super) fn fallback_window<const S: usize>(
    planes: [&[f32]; 3],
    centre: usize,
    pw: usize,
    m: usize,
) -> f32 {
    let mut sq = [f32::INFINITY; MAX_FALLBACK_SIDE * MAX_FALLBACK_SIDE + TAIL];
    window_sq_distances::<S>(planes, centre, pw, &mut sq);
    let candidates = &mut sq[..S * S - 1];
    let finite = candidates.iter().filter(|s| s.is_finite()).count();
    if finite < m {
        return f32::INFINITY;
    }
    candidates.select_nth_unstable_by(m - 1, f32::total_cmp);
    candidates[..m].iter().map(|s| s.sqrt()).sum::<f32>() / m as f32
}

/// The m = 20 fallback: the mean distance to the 20 nearest of the 80 other
/// pixels of the 9x9 window, or infinity when fewer than 20 have a reading
/// (then an infinite squared distance is among the 20 smallest).
pub(super) fn fallback_disc(planes: [&[f32]; 3], centre: usize, pw: usize) -> f32 {
    let mut rows = [[f32::INFINITY; 4]; 21];
    window_sq_distances::<9>(planes, centre, pw, rows.as_flattened_mut());
    sum_sqrt_smallest20(&mut rows) / 20.0
}

/// The sum of the square roots of the 20 smallest of the 80 values in
/// `rows[..20]` (non-negative or infinity); `rows` is scratch.
///
/// Branch-free selection in two rounds. The 80 values are four groups of
/// 20, the four lanes, sorted side by side by a sorting network. For sorted
/// `a` and `b`, `min(a[i], b[19 - i])` over i is exactly the 20 smallest of
/// both (as a multiset), and rises then falls (bitonic); that gives the 20
/// smallest of groups 0 and 1 and of groups 2 and 3. A bitonic merging
/// network sorts those, and the same reduction gives the 20 smallest of all
/// 80.
///
/// Not inlined: behind the reference the rows stay `[f32; 4]` in memory and
/// each step is one vector instruction; inlined, they are split into
/// scalars.
#[inline(never)]
pub(super) fn sum_sqrt_smallest20(rows: &mut [[f32; 4]; 21]) -> f32 {
    let rows = &mut rows[..20];
    sort20(rows);
    // Row i against row 19 - i with neighbouring lanes swapped: lanes
    // [ab_i, ab_(19-i), cd_i, cd_(19-i)] where ab and cd are the 20 smallest
    // of lanes 0 and 1 and of lanes 2 and 3. Each lane is bitonic.
    for i in 0..10 {
        let (p, q) = (rows[i], rows[19 - i]);
        rows[i] = lanes_min(p, [q[1], q[0], q[3], q[2]]);
        rows[19 - i] = lanes_min(q, [p[1], p[0], p[3], p[2]]);
    }
    merge_bitonic20(rows);
    // Lanes 0 and 1 now both hold ab sorted, lanes 2 and 3 cd sorted. Row i
    // of that order against row 19 - i with the lane halves swapped: lanes
    // 0 and 2 hold the i-th and (19 - i)-th of the 20 smallest.
    let mut smallest = [0.0f32; 20];
    for i in 0..10 {
        let (p, q) = (rows[BITONIC20_ORDER[i]], rows[BITONIC20_ORDER[19 - i]]);
        let z = lanes_min(p, [q[2], q[3], q[0], q[1]]);
        smallest[2 * i] = z[0];
        smallest[2 * i + 1] = z[2];
    }
    let mut sums = [0.0f32; 4];
    for chunk in smallest.chunks_exact(4) {
        for l in 0..4 {
            sums[l] += chunk[l].sqrt();
        }
    }
    (sums[0] + sums[1]) + (sums[2] + sums[3])
}

/// Lane-wise `min`, one `minps` (no NaN here: missing distances are
/// infinity).
#[inline(always)]
fn lanes_min(a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
    let mut out = [0.0f32; 4];
    for l in 0..4 {
        out[l] = if a[l] < b[l] { a[l] } else { b[l] };
    }
    out
}

/// Compare-exchange of rows `a` and `b`, lane by lane: the smaller value to
/// `a`.
#[inline(always)]
fn compare_exchange(v: &mut [[f32; 4]], a: usize, b: usize) {
    let (x, y) = (v[a], v[b]);
    let mut lo = [0.0f32; 4];
    let mut hi = [0.0f32; 4];
    for l in 0..4 {
        lo[l] = if x[l] < y[l] { x[l] } else { y[l] };
        hi[l] = if x[l] < y[l] { y[l] } else { x[l] };
    }
    v[a] = lo;
    v[b] = hi;
}

/// Defines a comparator list `$list` and a function `$name` applying it
/// to each lane of the rows (unrolled, so every index is a constant).
macro_rules! network {
    ($list:ident, $name:ident, $n:literal: $($a:literal $b:literal),* $(,)?) => {
        #[cfg(test)]
        pub(super) const $list: [(usize, usize); $n] = [$(($a, $b)),*];
        #[inline(always)]
        fn $name(v: &mut [[f32; 4]]) {
            $(compare_exchange(v, $a, $b);)*
        }
    };
}

// The 97 comparators of Batcher's merge-exchange network for 20 inputs
// (Knuth, TAOCP vol. 3, 5.2.2 Algorithm M): sorts each lane of 20 rows
// ascending. The tests check that it sorts every 0/1 input, hence every
// input (the 0-1 principle).
network!(SORT20, sort20, 97:
    0 16, 1 17, 2 18, 3 19, 0 8, 1 9, 2 10, 3 11, 4 12, 5 13, 6 14, 7 15, 8 16, 9 17, 10 18,
    11 19, 0 4, 1 5, 2 6, 3 7, 8 12, 9 13, 10 14, 11 15, 4 16, 5 17, 6 18, 7 19, 4 8, 5 9,
    6 10, 7 11, 12 16, 13 17, 14 18, 15 19, 0 2, 1 3, 4 6, 5 7, 8 10, 9 11, 12 14, 13 15,
    16 18, 17 19, 2 16, 3 17, 2 8, 3 9, 6 12, 7 13, 10 16, 11 17, 2 4, 3 5, 6 8, 7 9, 10 12,
    11 13, 14 16, 15 17, 0 1, 2 3, 4 5, 6 7, 8 9, 10 11, 12 13, 14 15, 16 17, 18 19, 1 16,
    3 18, 1 8, 3 10, 5 12, 7 14, 9 16, 11 18, 1 4, 3 6, 5 8, 7 10, 9 12, 11 14, 13 16, 15 18,
    1 2, 3 4, 5 6, 7 8, 9 10, 11 12, 13 14, 15 16, 17 18,
);

// Batcher's bitonic merger for 32 rows, of which rows 20..32 hold -infinity
// (a rising-then-falling sequence stays bitonic with them appended), with
// the comparators that only move a -infinity pruned and the rows renamed:
// 40 comparators that sort each lane of 20 bitonic rows into the row order
// `BITONIC20_ORDER`. The tests check it on every 0/1 bitonic input.
network!(MERGE_BITONIC20, merge_bitonic20, 40:
    0 16, 1 17, 2 18, 3 19, 16 8, 17 9, 18 10, 19 11, 4 12, 5 13, 6 14, 7 15, 16 4, 17 5,
    18 6, 19 7, 8 12, 9 13, 10 14, 11 15, 0 2, 1 3, 16 18, 17 19, 4 6, 5 7, 8 10, 9 11,
    12 14, 13 15, 0 1, 2 3, 16 17, 18 19, 4 5, 6 7, 8 9, 10 11, 12 13, 14 15,
);

/// The rows holding the ascending output of [`merge_bitonic20`].
pub(super) const BITONIC20_ORDER: [usize; 20] = [
    0, 1, 2, 3, 16, 17, 18, 19, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15,
];
