//! Hypotheses: drawing planes from the free sample points, scoring them on
//! a stratified subset, local optimisation of each new best, and the
//! adaptive number of draws.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::points::Points;
use super::PlaneSegmenter;
use super::RansacConfig;
use crate::plane_fit::{fit_tls, Plane};

/// Hypotheses are scored on at most this many sample points (a stratified
/// subset, copied contiguously in its visiting order).
const SCORE_POINTS: usize = 2000;

/// Points of the score subset a hypothesis is first tested on.
const PRETEST: usize = 100;

/// Stride of the scrambled visiting order of the score subset; coprime with
/// `SCORE_POINTS`, near its golden section.
const SCRAMBLE: usize = 1237;

/// Local-optimisation refits of a new best hypothesis, at most.
const LO_STEPS: usize = 4;

/// Hypotheses drawn per plane at least, whatever the adaptive count says.
const MIN_HYPOTHESES: usize = 64;

impl PlaneSegmenter {
    /// The hypothesis with the most inliers on a subset of the free sample.
    pub(super) fn best_hypothesis(
        &mut self,
        config: &RansacConfig,
        gated: bool,
        rng: &mut ChaCha8Rng,
    ) -> Option<Plane> {
        self.fill_pool(gated);
        if self.pool.len() < 3 {
            return None;
        }
        let sample = &self.sample.points;
        let score = score_subset(sample, &mut self.score, &mut self.indices);
        let mut best: Option<(usize, Plane)> = None;
        let mut needed = config.max_iterations;
        let mut it = 0;
        let log_fail = (1.0 - config.confidence).ln();
        let pool = &self.pool;
        let pre = PRETEST.min(score.len());
        while it < needed.max(MIN_HYPOTHESES).min(config.max_iterations) {
            it += 1;
            let Some(plane) = draw(sample, pool, gated && it % 2 == 1, rng) else {
                continue;
            };
            // Preemptive test: a hypothesis that scores under half the best
            // rate on the first PRETEST points is not scored further.
            let pre_score = score.count_inliers(0..pre, &plane);
            if let Some((best_score, _)) = &best {
                let expected = *best_score as f64 * pre as f64 / score.len() as f64;
                if (pre_score as f64) < 0.5 * expected {
                    continue;
                }
            }
            let count = pre_score + score.count_inliers(pre..score.len(), &plane);
            if best.as_ref().is_none_or(|(s, _)| count > *s) {
                // Local optimisation (LO-RANSAC): refit the new best by TLS
                // on its inliers until the score stops growing, so that
                // whichever triple found the plane, the plane kept is the
                // same fixed point of "fit the inliers, collect the inliers".
                let (count, plane) = local_optimisation(count, plane, score);
                best = Some((count, plane));
                let w = count as f64 / score.len() as f64;
                if let Some(required) = hypotheses_required(w, gated, log_fail) {
                    needed = required;
                }
            }
        }
        best.filter(|(s, _)| *s >= 3).map(|(_, p)| p)
    }

    /// `pool`: the free sample points a hypothesis may be drawn from; with
    /// the gate on, only those with a known normal (a point without one
    /// sits on an edge or in clutter).
    fn fill_pool(&mut self, gated: bool) {
        let sample = &self.sample.points;
        self.pool.clear();
        if gated {
            sample.indices_with_normal(&mut self.pool);
        } else {
            self.pool.extend(0..sample.len() as u32);
        }
    }
}

/// The adaptive number of hypotheses after a new best with inlier ratio
/// `w`: enough that one draw of good points happens with the confidence
/// whose `ln(1 - confidence)` is `log_fail`. Gated, half the hypotheses
/// need one good point (point and normal), half three. `None`: the count
/// stays as it was (a ratio of 0, or a count that is not finite).
fn hypotheses_required(w: f64, gated: bool, log_fail: f64) -> Option<usize> {
    let p_good = if gated {
        0.5 * (w + w * w * w)
    } else {
        w * w * w
    };
    if p_good > 0.0 && p_good < 1.0 {
        let n_req = log_fail / (1.0 - p_good).ln();
        n_req.is_finite().then(|| n_req.ceil() as usize)
    } else if p_good >= 1.0 {
        Some(0)
    } else {
        None
    }
}

/// One hypothesis from `pool` (indices into `sample`): with `from_normal`,
/// one point and its coarse normal (a small plane, a stair riser among
/// several parallel ones, is hit with the probability of its share w of the
/// points, not w^3; local optimisation corrects the coarse normal), else
/// three points whose normals agree with their plane. `None`: a degenerate
/// draw.
fn draw(sample: &Points, pool: &[u32], from_normal: bool, rng: &mut ChaCha8Rng) -> Option<Plane> {
    let a = pool[rng.random_range(0..pool.len())] as usize;
    if from_normal {
        return Plane::from_point_normal(&sample.point(a), &sample.normal(a)?);
    }
    let b = pool[rng.random_range(0..pool.len())] as usize;
    let c = pool[rng.random_range(0..pool.len())] as usize;
    if a == b || b == c || a == c {
        return None;
    }
    let plane = Plane::from_three_points(&sample.point(a), &sample.point(b), &sample.point(c))?;
    [a, b, c]
        .iter()
        .all(|&k| sample.normal_agrees(k, &plane))
        .then_some(plane)
}

/// The score subset: all of `sample` when small (then `sample` itself, in
/// its order), else every (n / SCORE_POINTS)-th point in raster order, so
/// each image region is scored in proportion, copied into `score` in a
/// scrambled order (a stride coprime with SCORE_POINTS) so that the
/// pretest prefix is spread over the whole image.
fn score_subset<'a>(
    sample: &'a Points,
    score: &'a mut Points,
    indices: &mut Vec<u32>,
) -> &'a Points {
    let n = sample.len();
    if n <= SCORE_POINTS {
        return sample;
    }
    indices.clear();
    indices.extend(
        (0..SCORE_POINTS).map(|k| ((k * SCRAMBLE) % SCORE_POINTS * n / SCORE_POINTS) as u32),
    );
    score.gather(sample, indices);
    score
}

/// Refits `plane` by TLS on its inliers among `score` and rescores it,
/// while the inlier count grows (at most `LO_STEPS` times).
fn local_optimisation(count: usize, plane: Plane, score: &Points) -> (usize, Plane) {
    let mut best = (count, plane);
    for _ in 0..LO_STEPS {
        let Some(refit) = fit_tls(&score.inlier_moments(&best.1)) else {
            break;
        };
        let count = score.count_inliers(0..score.len(), &refit);
        if count <= best.0 {
            break;
        }
        best = (count, refit);
    }
    best
}
