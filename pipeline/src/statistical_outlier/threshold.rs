//! The cloud's mean and spread of the statistic, and each point's verdict.

use super::{OutlierConfig, OutlierStats, StatisticalOutlierFilter};

impl StatisticalOutlierFilter {
    /// Mean and standard deviation of the statistic, and the verdicts.
    pub(super) fn threshold(&mut self, config: &OutlierConfig, keep: &mut [bool]) -> OutlierStats {
        // Statistics over the points with a finite statistic (isolated
        // points are outliers whatever the threshold).
        let FiniteSums {
            measured,
            count,
            sum,
            sum_sq,
        } = finite_sums(&self.mean_distance);
        if count == 0 {
            keep.fill(false);
            return OutlierStats {
                removed: measured,
                ..OutlierStats::default()
            };
        }
        let mean = sum / count as f64;
        let std = (sum_sq / count as f64 - mean * mean).max(0.0).sqrt();
        let threshold = mean + config.std_ratio * std;
        // `f64::from(d) <= threshold` as an f32 comparison: against the
        // largest f32 not above the threshold (NaN stays NaN, and NaN
        // statistics compare false either way).
        let mut limit = threshold as f32;
        if f64::from(limit) > threshold {
            limit = limit.next_down();
        }
        let mut kept = 0;
        for (k, &d) in keep.iter_mut().zip(&self.mean_distance) {
            *k = d <= limit;
            kept += usize::from(*k);
        }
        OutlierStats {
            mean_distance_m: mean,
            std_distance_m: std,
            threshold_m: threshold,
            kept,
            removed: measured - kept,
        }
    }
}

/// What [`finite_sums`] counts and sums.
struct FiniteSums {
    /// Values that are not NaN.
    measured: usize,
    /// Finite values.
    count: usize,
    /// Sum and sum of squares of the finite values, in f64.
    sum: f64,
    sum_sq: f64,
}

/// Counts the measured and the finite values of `values` and sums the
/// finite ones in f64, four interleaved running sums so that the additions
/// vectorise. Blocks are first copied with the other values zeroed and
/// counted (a loop of its own, so that it vectorises too).
#[inline]
fn finite_sums(values: &[f32]) -> FiniteSums {
    let (mut sum, mut sum_sq) = ([0.0f64; 4], [0.0f64; 4]);
    let (mut measured, mut count) = (0, 0);
    let mut block = [0.0f32; 64];
    for chunk in values.chunks(block.len()) {
        // At most 64 per block: u32 lanes do not overflow.
        let (mut block_measured, mut block_count) = (0u32, 0u32);
        for (b, &d) in block.iter_mut().zip(chunk) {
            *b = if d.is_finite() { d } else { 0.0 };
            block_measured += u32::from(!d.is_nan());
            block_count += u32::from(d.is_finite());
        }
        measured += block_measured as usize;
        count += block_count as usize;
        block[chunk.len()..].fill(0.0);
        for quad in block.chunks_exact(4) {
            for l in 0..4 {
                let x = f64::from(quad[l]);
                sum[l] += x;
                sum_sq[l] += x * x;
            }
        }
    }
    FiniteSums {
        measured,
        count,
        sum: (sum[0] + sum[1]) + (sum[2] + sum[3]),
        sum_sq: (sum_sq[0] + sum_sq[1]) + (sum_sq[2] + sum_sq[3]),
    }
}
