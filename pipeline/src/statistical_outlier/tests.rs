use super::fallback::{sum_sqrt_smallest20, BITONIC20_ORDER, MERGE_BITONIC20, SORT20};
use super::*;
use crate::fixtures::{Scene, SceneCloud};
use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// Brute-force statistic: mean distance to the m nearest of all points,
/// with a k-d tree (checked against a linear scan below).
fn brute_force_statistic(points: &[[f64; 3]], m: usize) -> Vec<f64> {
    let tree = ImmutableKdTree::<f64, 3>::new_from_slice(points).unwrap();
    points
        .iter()
        .map(|p| {
            let nn = tree
                .query(p)
                .nearest_n::<SquaredEuclidean<f64>>(std::num::NonZero::new(m + 1).unwrap())
                .execute();
            nn.iter().skip(1).map(|n| n.distance.sqrt()).sum::<f64>() / m as f64
        })
        .collect()
}

#[test]
fn kd_tree_oracle_matches_a_linear_scan() {
    let cloud = SceneCloud::render(&Scene::ramp(12.5), 64, 53, 0.002, 3);
    let pts = cloud.measured_points();
    let stat = brute_force_statistic(&pts, 20);
    for (i, p) in pts.iter().enumerate().step_by(97) {
        let mut d: Vec<f64> = pts
            .iter()
            .map(|q| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt())
            .collect();
        d.sort_by(f64::total_cmp);
        let linear = d[1..21].iter().sum::<f64>() / 20.0;
        assert!((linear - stat[i]).abs() < 1e-9, "{linear} vs {}", stat[i]);
    }
}

#[test]
fn window_statistic_is_exact_on_a_fronto_parallel_grid() {
    // A wall facing the camera: the 20 nearest neighbours of an interior
    // pixel are its 20 nearest grid pixels, so the window answer must
    // equal the brute-force one.
    let scene = Scene::wall_facing(2.0);
    let cloud = SceneCloud::render_with_intrinsics(&scene, 40, 30, 365.0, 0.0, 1);
    let view = cloud.view();
    let pts: Vec<[f64; 3]> = cloud.measured_points();
    assert_eq!(pts.len(), 40 * 30);
    // m = 20: the grid disc; m = 8 and 24: the general square-window path.
    for m in [20, 8, 24] {
        let mut filter = StatisticalOutlierFilter::new();
        let mut keep = Vec::new();
        let config = OutlierConfig {
            neighbours: m,
            ..OutlierConfig::default()
        };
        filter.filter(&view, &config, &mut keep);
        let oracle = brute_force_statistic(&pts, m);
        for v in 2..28 {
            for u in 2..38 {
                let i = v * 40 + u;
                let ours = f64::from(filter.mean_distances()[i]);
                assert!(
                    (ours - oracle[i]).abs() < 1e-4 * oracle[i],
                    "m {m} pixel ({u},{v}): {ours} vs {}",
                    oracle[i]
                );
            }
        }
    }
}

/// Runs ours and the brute-force filter; returns (ours keep, oracle keep)
/// over the measured pixels.
fn both_filters(cloud: &SceneCloud) -> (Vec<usize>, Vec<bool>, Vec<bool>) {
    let view = cloud.view();
    let mut filter = StatisticalOutlierFilter::new();
    let mut keep = Vec::new();
    let stats = filter.filter(&view, &OutlierConfig::default(), &mut keep);
    let idx: Vec<usize> = (0..view.points.len())
        .filter(|&i| view.points[i].is_valid())
        .collect();
    assert_eq!(stats.kept + stats.removed, idx.len());
    let stat = brute_force_statistic(&cloud.measured_points(), 20);
    let n = stat.len() as f64;
    let mean = stat.iter().sum::<f64>() / n;
    let std = (stat.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n).sqrt();
    let oracle: Vec<bool> = stat.iter().map(|&d| d <= mean + 2.0 * std).collect();
    let ours: Vec<bool> = idx.iter().map(|&i| keep[i]).collect();
    (idx, ours, oracle)
}

#[test]
fn injected_outliers_are_removed_like_the_brute_force_filter() {
    let mut cloud = SceneCloud::render(&Scene::wall_facing(2.5), 128, 106, 0.0015, 5);
    let injected = cloud.inject_flying_pixels(60, 11);
    let (idx, ours, oracle) = both_filters(&cloud);
    for &i in &injected {
        let k = idx.binary_search(&i).unwrap();
        assert!(!ours[k], "injected outlier {i} kept");
        assert!(!oracle[k], "the oracle keeps injected outlier {i}");
    }
    let disagree = ours.iter().zip(&oracle).filter(|(a, b)| a != b).count();
    assert!(disagree * 100 < idx.len(), "{disagree} of {}", idx.len());
}

#[test]
fn grid_filter_agrees_with_the_brute_force_filter_on_a_ramp() {
    // Ground, ramp and range up to 8 m: neighbourhoods stretched by
    // grazing incidence, where the grid is an approximation.
    let cloud = SceneCloud::render(&Scene::ramp_between_walls(16.0), 128, 106, 0.0015, 5);
    let (idx, ours, oracle) = both_filters(&cloud);
    let disagree = ours.iter().zip(&oracle).filter(|(a, b)| a != b).count();
    assert!(disagree * 50 < idx.len(), "{disagree} of {}", idx.len());
}

/// The filter's rule written plainly, per pixel, in f64: the measured
/// pixels of the first window (m = 20: the 5x5 window without its
/// corners; otherwise the smallest square with m others) if there are at
/// least m, their m nearest; else the m nearest measured pixels of the
/// window two pixels wider, or infinity with fewer than m there. Returns
/// the statistic per pixel (NaN without a reading), the threshold and
/// the number of pixels that took the wider window.
fn reference_statistic(
    cloud: &SceneCloud,
    config: &OutlierConfig,
) -> (Vec<f64>, f64, usize, usize) {
    let (m, alpha) = (config.neighbours, config.std_ratio);
    let present = m == 20 && config.fallback == Fallback::PresentNeighbours;
    let mut present_used = 0;
    let (w, h) = (cloud.width as isize, cloud.height as isize);
    let point = |u: isize, v: isize| -> Option<[f64; 3]> {
        if u < 0 || v < 0 || u >= w || v >= h {
            return None;
        }
        let p = cloud.points[(v * w + u) as usize];
        p.is_valid()
            .then(|| [f64::from(p.x_m), f64::from(p.y_m), f64::from(p.z_m)])
    };
    let r = window_radius(m) as isize;
    let mut fallbacks = 0;
    let mut stat = vec![f64::NAN; cloud.points.len()];
    for v in 0..h {
        for u in 0..w {
            let Some(c) = point(u, v) else { continue };
            let distances = |radius: isize, disc: bool| -> Vec<f64> {
                let mut d = Vec::new();
                for dv in -radius..=radius {
                    for du in -radius..=radius {
                        if (du, dv) == (0, 0) || (disc && du * du + dv * dv > 5) {
                            continue;
                        }
                        if let Some(q) = point(u + du, v + dv) {
                            let d2: f64 = (0..3).map(|k| (c[k] - q[k]).powi(2)).sum();
                            d.push(d2.sqrt());
                        }
                    }
                }
                d.sort_by(f64::total_cmp);
                d
            };
            let mut d = distances(r, m == 20);
            if d.len() < m && present && d.len() >= 10 {
                // The mean distance to the grid neighbours it has.
                present_used += 1;
                stat[(v * w + u) as usize] = d.iter().sum::<f64>() / d.len() as f64;
                continue;
            }
            if d.len() < m {
                fallbacks += 1;
                d = distances(r + 2, false);
            }
            stat[(v * w + u) as usize] = if d.len() < m {
                f64::INFINITY
            } else {
                d[..m].iter().sum::<f64>() / m as f64
            };
        }
    }
    let finite: Vec<f64> = stat.iter().copied().filter(|d| d.is_finite()).collect();
    let n = finite.len() as f64;
    let mean = finite.iter().sum::<f64>() / n;
    let std = (finite.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n).sqrt();
    (stat, mean + alpha * std, fallbacks, present_used)
}

/// A ramp between walls with holes of every kind: scattered missing
/// pixels, missing blocks and lines, a nearly empty patch (isolated
/// points) and flying pixels.
fn holed_fixture(width: usize, height: usize, seed: u64) -> SceneCloud {
    use rand::{Rng, SeedableRng};
    let mut cloud = SceneCloud::render(
        &Scene::ramp_between_walls(16.0),
        width,
        height,
        0.0015,
        seed,
    );
    cloud.inject_flying_pixels(40, seed + 1);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed + 2);
    let invalid = slope_ipc_types::CloudPoint::INVALID;
    for v in 0..height {
        for u in 0..width {
            let i = v * width + u;
            let hole = rng.random_bool(0.12)
                || (u % 23 == 7 && v % 3 != 0)
                || (v % 31 == 11 && u % 5 != 0)
                || ((40..52).contains(&u) && (30..37).contains(&v))
                || ((90..120).contains(&u) && (60..80).contains(&v) && rng.random_bool(0.85));
            if hole {
                cloud.points[i] = invalid;
            }
        }
    }
    cloud
}

#[test]
fn statistic_and_verdicts_match_a_per_pixel_reference_on_a_frame_with_holes() {
    let cloud = holed_fixture(160, 120, 21);
    let view = cloud.view();
    let measured = cloud.points.iter().filter(|p| p.is_valid()).count();
    let cases = [
        (20, Fallback::ExactWindow),
        (20, Fallback::PresentNeighbours),
        (8, Fallback::PresentNeighbours),
        (24, Fallback::PresentNeighbours),
    ];
    for (m, fallback) in cases {
        let config = OutlierConfig {
            neighbours: m,
            fallback,
            ..OutlierConfig::default()
        };
        let mut filter = StatisticalOutlierFilter::new();
        let mut keep = Vec::new();
        // Twice: the second run reuses the buffers.
        filter.filter(&view, &config, &mut keep);
        let stats = filter.filter(&view, &config, &mut keep);
        let (oracle, threshold, fallbacks, present) = reference_statistic(&cloud, &config);
        // The fixture exercises the fallback, the present neighbours' mean
        // and the isolated case.
        if m == 20 && fallback == Fallback::PresentNeighbours {
            assert!(present * 4 > measured, "{present} of {measured}");
            assert!(fallbacks >= 20, "{fallbacks} of {measured}");
        } else {
            assert!(fallbacks * 4 > measured, "m {m}: {fallbacks} of {measured}");
        }
        let isolated = oracle.iter().filter(|d| d.is_infinite()).count();
        assert!(isolated >= 10, "m {m}: {isolated} isolated");
        assert_eq!(stats.kept + stats.removed, measured);
        assert!(
            (stats.threshold_m - threshold).abs() < 1e-6 * threshold,
            "m {m}: {} vs {threshold}",
            stats.threshold_m
        );
        let mut ties = 0;
        for (i, (&ours, &theirs)) in filter.mean_distances().iter().zip(&oracle).enumerate() {
            let ours = f64::from(ours);
            if theirs.is_nan() || theirs.is_infinite() {
                assert_eq!(ours.to_bits(), theirs.to_bits(), "m {m} pixel {i}");
            } else {
                assert!(
                    (ours - theirs).abs() <= 1e-5 * theirs,
                    "m {m} pixel {i}: {ours} vs {theirs}"
                );
            }
            let verdict = theirs <= threshold;
            if keep[i] != verdict {
                assert!(
                    (theirs - threshold).abs() <= 1e-5 * threshold,
                    "m {m} pixel {i}: {theirs} vs threshold {threshold}"
                );
                ties += 1;
            }
        }
        assert!(ties <= 2, "m {m}: {ties} verdicts differ");
    }
}

/// The offsets of a pixel's 20 grid neighbours in the order
/// `disc_row_sums` adds their distances: rows two and one above, then
/// the pixel's own row and the rows below.
const ORDER: [(isize, isize); 20] = [
    (1, -2),
    (0, -2),
    (-1, -2),
    (2, -1),
    (1, -1),
    (0, -1),
    (-1, -1),
    (-2, -1),
    (1, 0),
    (-1, 0),
    (2, 0),
    (-2, 0),
    (-2, 1),
    (-1, 1),
    (0, 1),
    (1, 1),
    (2, 1),
    (-1, 2),
    (0, 2),
    (1, 2),
];

/// Checks the fast path's statistic of every pixel of `cloud` with a
/// complete disc (it and its 20 grid neighbours measured) bit for bit:
/// the 20 f32 distances summed one after the other in `ORDER`, divided
/// by 20. Returns the number of such pixels.
fn check_complete_discs(cloud: &SceneCloud) -> usize {
    use crate::cloud::is_measured;
    let (w, h) = (cloud.width as isize, cloud.height as isize);
    let mut filter = StatisticalOutlierFilter::new();
    let mut keep = Vec::new();
    filter.filter(&cloud.view(), &OutlierConfig::default(), &mut keep);
    let point = |u: isize, v: isize| {
        let inside = (0..w).contains(&u) && (0..h).contains(&v);
        inside
            .then(|| cloud.points[(v * w + u) as usize])
            .filter(is_measured)
    };
    let mut complete = 0;
    for v in 0..h {
        for u in 0..w {
            let Some(c) = point(u, v) else { continue };
            let disc: Option<Vec<_>> = ORDER
                .iter()
                .map(|&(du, dv)| point(u + du, v + dv))
                .collect();
            let Some(disc) = disc else { continue };
            let mut sum = 0.0f32;
            for q in disc {
                let (dx, dy, dz) = (c.x_m - q.x_m, c.y_m - q.y_m, c.z_m - q.z_m);
                sum += (dx * dx + dy * dy + dz * dz).sqrt();
            }
            complete += 1;
            let ours = filter.mean_distances()[(v * w + u) as usize];
            assert_eq!(ours.to_bits(), (sum / 20.0).to_bits(), "pixel ({u},{v})");
        }
    }
    complete
}

#[test]
fn a_complete_disc_sums_its_distances_in_f32_in_a_fixed_order() {
    let mut cloud = SceneCloud::render(&Scene::ramp_between_walls(16.0), 160, 120, 0.0015, 33);
    cloud.inject_flying_pixels(40, 34);
    let complete = check_complete_discs(&cloud);
    assert!(complete > 15_000, "{complete} pixels with a complete disc");
    // Complete discs next to holes, blocks and lines of missing pixels.
    let holed = check_complete_discs(&holed_fixture(160, 120, 21));
    assert!(holed > 500, "{holed} pixels with a complete disc, holed");
}

/// A block's present sums are each pixel's alone, bit for bit, with every
/// number of missing terms, at every place and length of a block.
#[test]
fn a_blocks_present_means_are_each_pixels_own() {
    use super::grid_disc::{present_mean, PresentBlock};
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let mut means = 0;
    for trial in 0..300 {
        let missing = rng.random_range(0.0..1.0);
        let pairs: Vec<f32> = (0..2000)
            .map(|_| {
                if rng.random_bool(missing) {
                    f32::NAN
                } else {
                    rng.random_range(0.001f32..0.3)
                }
            })
            .collect();
        let starts: [usize; 20] = std::array::from_fn(|_| rng.random_range(0..1900));
        let (u0, len) = (rng.random_range(0..60), rng.random_range(1..=32));
        let block = PresentBlock::of(&pairs, &starts, u0, len);
        for j in 0..len {
            let (ours, own) = (block.mean(j), present_mean(&pairs, &starts, u0 + j));
            assert_eq!(
                ours.map(f32::to_bits),
                own.map(f32::to_bits),
                "trial {trial} pixel {j}"
            );
            means += usize::from(own.is_some());
        }
    }
    // Both outcomes occur: a mean, and too few present.
    assert!((500..4000).contains(&means), "{means} means");
}

#[test]
fn smallest20_selection_matches_a_sort() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    for trial in 0..20_000 {
        // Few distinct values (ties), some infinite, every count of
        // finite values around 20.
        let infinite = rng.random_range(0.0..0.9);
        let distinct = rng.random_range(1..40);
        let values: Vec<f32> = (0..80)
            .map(|_| {
                if rng.random_bool(infinite) {
                    f32::INFINITY
                } else {
                    rng.random_range(0..distinct) as f32 * 0.37 + 0.01
                }
            })
            .collect();
        let mut rows = [[0.0f32; 4]; 21];
        rows.as_flattened_mut()[..80].copy_from_slice(&values);
        let ours = sum_sqrt_smallest20(&mut rows);
        let mut sorted = values.clone();
        sorted.sort_by(f32::total_cmp);
        let oracle: f64 = sorted[..20].iter().map(|&s| f64::from(s).sqrt()).sum();
        if oracle.is_infinite() {
            assert_eq!(ours, f32::INFINITY, "trial {trial}");
        } else {
            assert!(
                (f64::from(ours) - oracle).abs() <= 1e-6 * oracle,
                "trial {trial}: {ours} vs {oracle}"
            );
        }
    }
}

/// Applies a comparator list to 64 0/1 inputs at once (bit b of word i
/// is element i of input b).
fn run_network(network: &[(usize, usize)], words: &mut [u64]) {
    for &(a, b) in network {
        let (lo, hi) = (words[a] & words[b], words[a] | words[b]);
        words[a] = lo;
        words[b] = hi;
    }
}

#[test]
fn sort20_sorts_every_zero_one_input() {
    // The 0-1 principle: sorting all 2^20 0/1 inputs proves it sorts
    // every input.
    for batch in 0..(1u64 << 20) / 64 {
        let mut words = [0u64; 20];
        for b in 0..64 {
            let input = batch * 64 + b;
            for (i, word) in words.iter_mut().enumerate() {
                *word |= ((input >> i) & 1) << b;
            }
        }
        run_network(&SORT20, &mut words);
        for i in 0..19 {
            assert_eq!(
                words[i] & !words[i + 1],
                0,
                "batch {batch} rows {i}, {}",
                i + 1
            );
        }
    }
}

#[test]
fn bitonic_merger_sorts_every_rising_then_falling_zero_one_input() {
    // A rising-then-falling 0/1 sequence is 0^a 1^b 0^c; thresholding
    // any rising-then-falling sequence gives one, so by the 0-1 principle
    // these prove the merger for all of them.
    for a in 0..=20 {
        for b in 0..=20 - a {
            let mut words = [0u64; 20];
            for word in &mut words[a..a + b] {
                *word = 1;
            }
            run_network(&MERGE_BITONIC20, &mut words);
            let out: Vec<u64> = BITONIC20_ORDER.iter().map(|&r| words[r]).collect();
            let expected: Vec<u64> = (0..20).map(|i| u64::from(i >= 20 - b)).collect();
            assert_eq!(out, expected, "0^{a} 1^{b} 0^{}", 20 - a - b);
        }
    }
}

#[test]
fn empty_and_invalid_clouds_keep_nothing() {
    let scene = Scene::ramp(5.0);
    let mut cloud = SceneCloud::render(&scene, 16, 12, 0.0, 1);
    cloud
        .points
        .iter_mut()
        .for_each(|p| *p = slope_ipc_types::CloudPoint::INVALID);
    let mut filter = StatisticalOutlierFilter::new();
    let mut keep = Vec::new();
    let stats = filter.filter(&cloud.view(), &OutlierConfig::default(), &mut keep);
    assert_eq!(stats.kept, 0);
    assert!(keep.iter().all(|k| !k));
}

#[test]
fn bands_of_rows_on_threads_give_every_statistic_and_verdict_bit_for_bit() {
    // Heights that split into bands of unequal size and bands of one or two
    // rows (fewer rows than bands are asked for too).
    for (width, height) in [(160, 121), (37, 5), (40, 3)] {
        let cloud = if height > 100 {
            holed_fixture(width, height, 5)
        } else {
            // Too small for the fixture's forty flying pixels kept apart.
            let mut cloud = SceneCloud::render(&Scene::ramp(16.0), width, height, 0.0015, 5);
            for i in (0..cloud.points.len()).step_by(7) {
                cloud.points[i] = slope_ipc_types::CloudPoint::INVALID;
            }
            cloud
        };
        let view = cloud.view();
        for fallback in [Fallback::ExactWindow, Fallback::PresentNeighbours] {
            let config = OutlierConfig {
                fallback,
                ..OutlierConfig::default()
            };
            let mut one = StatisticalOutlierFilter::new();
            let mut keep_one = Vec::new();
            let stats_one = one.filter(&view, &config, &mut keep_one);
            for threads in [2, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let mut many = StatisticalOutlierFilter::new();
                let mut keep_many = Vec::new();
                // Twice: the second run reuses the bands' buffers.
                many.filter_on(&view, &config, &mut keep_many, Some(&pool));
                let stats_many = many.filter_on(&view, &config, &mut keep_many, Some(&pool));
                let bits = |f: &StatisticalOutlierFilter| -> Vec<u32> {
                    f.mean_distances().iter().map(|d| d.to_bits()).collect()
                };
                let case = format!("{width}x{height} {fallback:?} {threads} threads");
                assert_eq!(bits(&one), bits(&many), "{case}");
                assert_eq!(keep_one, keep_many, "{case}");
                assert_eq!(stats_one, stats_many, "{case}");
            }
        }
    }
    // The fixture reaches the fallback and every verdict.
    let cloud = holed_fixture(160, 121, 5);
    let mut filter = StatisticalOutlierFilter::new();
    let mut keep = Vec::new();
    let stats = filter.filter(&cloud.view(), &OutlierConfig::default(), &mut keep);
    assert!(stats.kept > 0 && stats.removed > 0, "{stats:?}");
}
