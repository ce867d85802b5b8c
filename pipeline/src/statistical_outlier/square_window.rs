//! The general path, for m other than 20: the m nearest of the smallest
//! square window with at least m other pixels.

use super::fallback::fallback_window;
use super::StatisticalOutlierFilter;

impl StatisticalOutlierFilter {
    /// The general path: the m nearest of the smallest square window with
    /// at least m other pixels.
    pub(super) fn square_window_statistic(
        &mut self,
        w: usize,
        h: usize,
        r: usize,
        r_fb: usize,
        m: usize,
    ) {
        let pw = w + 2 * r_fb;
        let drop = (2 * r + 1) * (2 * r + 1) - 1 - m;
        self.row_sum.resize(w, 0.0);
        self.row_count.resize(w, 0.0);
        self.row_value.resize(w, 0.0);
        self.row_top.resize(drop * w, 0.0);
        let ri = r as isize;
        for v in 0..h {
            let centre_row = (v + r_fb) * pw + r_fb;
            self.row_sum.fill(0.0);
            self.row_count.fill(0.0);
            self.row_top.fill(f32::NEG_INFINITY);
            for dv in -ri..=ri {
                for du in -ri..=ri {
                    if du == 0 && dv == 0 {
                        continue;
                    }
                    let other = (centre_row as isize + dv * pw as isize + du) as usize;
                    self.accumulate_offset(centre_row, other, w, drop);
                }
            }
            for u in 0..w {
                if !self.zs[centre_row + u].is_finite() {
                    continue;
                }
                let count = self.row_count[u] as usize;
                let d = if count >= m {
                    let mut dropped = 0.0f32;
                    for s in 0..drop {
                        let t = self.row_top[s * w + u];
                        if t.is_finite() {
                            dropped += t;
                        }
                    }
                    (self.row_sum[u] - dropped) / m as f32
                } else {
                    let planes = [&self.xs[..], &self.ys[..], &self.zs[..]];
                    let c = centre_row + u;
                    match r_fb {
                        3 => fallback_window::<7>(planes, c, pw, m),
                        4 => fallback_window::<9>(planes, c, pw, m),
                        _ => fallback_window::<11>(planes, c, pw, m),
                    }
                };
                self.mean_distance[v * w + u] = d;
            }
        }
    }

    /// Folds the distances between row `centre..centre+w` and the same row
    /// shifted to `other` into the running sums and top lists.
    #[inline(never)]
    fn accumulate_offset(&mut self, centre: usize, other: usize, w: usize, drop: usize) {
        let (cx, cy, cz) = (
            &self.xs[centre..centre + w],
            &self.ys[centre..centre + w],
            &self.zs[centre..centre + w],
        );
        let (ox, oy, oz) = (
            &self.xs[other..other + w],
            &self.ys[other..other + w],
            &self.zs[other..other + w],
        );
        let sum = &mut self.row_sum[..w];
        let count = &mut self.row_count[..w];
        let value = &mut self.row_value[..w];
        for u in 0..w {
            let dx = cx[u] - ox[u];
            let dy = cy[u] - oy[u];
            let dz = cz[u] - oz[u];
            let d = (dx * dx + dy * dy + dz * dz).sqrt();
            let valid = !d.is_nan();
            sum[u] += if valid { d } else { 0.0 };
            count[u] += if valid { 1.0 } else { 0.0 };
            value[u] = if valid { d } else { f32::INFINITY };
        }
        for s in 0..drop {
            let top = &mut self.row_top[s * w..(s + 1) * w];
            for u in 0..w {
                let x = value[u];
                let t = top[u];
                top[u] = if x > t { x } else { t };
                value[u] = if x > t { t } else { x };
            }
        }
    }
}
