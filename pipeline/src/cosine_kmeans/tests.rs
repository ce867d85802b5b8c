//! Clusters of known directions, the merge of one population cut in
//! pieces, and degenerate inputs.

use super::lloyd::CONVERGED_COSINE_DISTANCE;
use super::*;
use crate::cloud::angle_between_deg;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn jitter(rng: &mut ChaCha8Rng, n: Vector3<f64>, deg: f64) -> Vector3<f64> {
    let s = deg.to_radians();
    (n + Vector3::new(
        rng.random_range(-s..s),
        rng.random_range(-s..s),
        rng.random_range(-s..s),
    ))
    .normalize()
}

#[test]
fn two_well_separated_clusters_are_found() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let a = Vector3::new(0.0, -1.0, -0.3).normalize();
    let b = Vector3::new(0.0, -0.2, -1.0).normalize();
    let mut normals: Vec<Vector3<f64>> = (0..700).map(|_| jitter(&mut rng, a, 2.0)).collect();
    normals.extend((0..300).map(|_| jitter(&mut rng, b, 2.0)));
    normals.push(Vector3::repeat(f64::NAN));
    let mut km = CosineKmeans::new();
    let c = km.cluster(&normals, 2, 50, 0.0).unwrap();
    assert_eq!(c.centres.len(), 2);
    let mut counts = c.counts.clone();
    counts.sort_unstable();
    assert_eq!(counts, vec![300, 700]);
    assert!(angle_between_deg(&c.centres[c.dominant], &a) < 0.5);
    // Every dominant member is one of the 700 around a.
    assert!(km
        .members(c.dominant)
        .all(|m| angle_between_deg(m, &a) < 5.0));
    assert_eq!(km.members(c.dominant).count(), 700);
}

#[test]
fn farthest_first_puts_an_outlier_in_its_own_cluster() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let a = Vector3::new(0.3, -0.9, -0.2).normalize();
    let mut normals: Vec<Vector3<f64>> = (0..500).map(|_| jitter(&mut rng, a, 1.0)).collect();
    let outliers = [
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.9, 0.1, 0.1).normalize(),
    ];
    normals.extend(outliers);
    let mut km = CosineKmeans::new();
    let c = km.cluster(&normals, 2, 50, 0.0).unwrap();
    assert_eq!(c.counts[c.dominant], 500);
    assert!(km
        .members(c.dominant)
        .all(|m| angle_between_deg(m, &a) < 3.0));
}

#[test]
fn one_noisy_population_is_not_cut_in_half() {
    // A single isotropic population around `a` plus a far cluster: with
    // k = 3 k-means splits the population; merging restores it and the
    // kept mean is unbiased, while the far cluster is still dropped.
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let a = Vector3::new(0.0, -0.9, -0.4).normalize();
    let far = Vector3::new(0.0, 0.0, -1.0);
    let mut normals: Vec<Vector3<f64>> = (0..3000).map(|_| jitter(&mut rng, a, 3.0)).collect();
    normals.extend((0..200).map(|_| jitter(&mut rng, far, 1.0)));
    let mut km = CosineKmeans::new();
    let split = km.cluster(&normals, 3, 50, 0.0).unwrap();
    let biased: Vector3<f64> = km.members(split.dominant).sum();
    assert!(split.counts[split.dominant] < 2900, "{:?}", split.counts);
    assert!(angle_between_deg(&biased, &a) > 0.3);
    let merged = km.cluster(&normals, 3, 50, 2.5).unwrap();
    let kept: Vec<Vector3<f64>> = km.kept_members(&merged).copied().collect();
    assert_eq!(kept.len(), 3000, "{:?} {:?}", merged.counts, merged.kept);
    let mean: Vector3<f64> = kept.iter().sum();
    assert!(
        angle_between_deg(&mean, &a) < 0.1,
        "{}",
        angle_between_deg(&mean, &a)
    );
}

#[test]
fn convergence_tolerance_is_a_hundredth_of_a_degree() {
    let expected = 1.0 - CONVERGED_DEG.to_radians().cos();
    assert!((CONVERGED_COSINE_DISTANCE - expected).abs() < 1e-3 * expected);
}

#[test]
fn degenerate_inputs() {
    let mut km = CosineKmeans::new();
    assert!(km.cluster(&[], 2, 10, 2.5).is_none());
    assert!(km.cluster(&[Vector3::zeros()], 2, 10, 2.5).is_none());
    let same = vec![Vector3::z(); 10];
    let c = km.cluster(&same, 3, 10, 2.5).unwrap();
    assert_eq!(c.centres.len(), 1);
    assert_eq!(c.counts, vec![10]);
    assert!((cosine_distance(&Vector3::x(), &Vector3::y()) - 1.0).abs() < 1e-15);
}

#[test]
fn each_centre_is_the_mean_direction_of_its_members_summed_afresh() {
    // The sums are moved normal by normal as labels change; summed afresh
    // from the final labels they give the same centres. Three populations
    // that k-means cuts and reassigns over many iterations, k from 1 to 5.
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let dirs = [
        Vector3::new(0.0, -1.0, -0.2).normalize(),
        Vector3::new(0.1, -0.3, -1.0).normalize(),
        Vector3::new(0.8, -0.5, -0.3).normalize(),
    ];
    let mut normals: Vec<Vector3<f64>> = Vec::new();
    for (d, (n, spread)) in dirs.iter().zip([(2500, 4.0), (900, 6.0), (150, 10.0)]) {
        normals.extend((0..n).map(|_| jitter(&mut rng, *d, spread)));
    }
    let mut km = CosineKmeans::new();
    for k in 1..=5 {
        let c = km.cluster(&normals, k, 100, 0.0).unwrap();
        assert!(
            c.iterations > 1 || k == 1,
            "k {k}: {} iterations",
            c.iterations
        );
        for (j, centre) in c.centres.iter().enumerate() {
            let members: Vec<Vector3<f64>> = km.members(j).copied().collect();
            assert_eq!(members.len(), c.counts[j], "k {k} cluster {j}");
            let Some(mean) = members.iter().sum::<Vector3<f64>>().try_normalize(1e-12) else {
                continue; // an empty cluster keeps its last centre
            };
            let off = angle_between_deg(centre, &mean);
            assert!(
                off < 1e-7,
                "k {k} cluster {j}: centre {off} degrees off its members' mean"
            );
        }
    }
}

/// The assignment of 2-4 centres at once gives every normal the centre the
/// assignment centre by centre gives it (ties included: a normal
/// equidistant from two centres goes to the lower index either way).
#[test]
fn the_assignment_at_once_is_the_assignment_centre_by_centre() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let axis = Vector3::new(0.1, -0.9, -0.4).normalize();
    let mut normals: Vec<Vector3<f64>> = (0..3000).map(|_| jitter(&mut rng, axis, 30.0)).collect();
    // Exact ties: the normals halfway between the first two centres.
    let (a, b) = (Vector3::new(0.0, -1.0, 0.0), Vector3::new(0.0, 0.0, -1.0));
    normals.extend(std::iter::repeat_n((a + b).normalize(), 10));
    let mut km = CosineKmeans::new();
    km.load_units(&normals);
    km.load_copies();
    let mut moved = 0;
    for k in 2..=4 {
        let mut centres: Vec<Vector3<f64>> = (0..k).map(|_| jitter(&mut rng, axis, 20.0)).collect();
        (centres[0], centres[1]) = (a, b);
        km.assign_centre_by_centre(&centres);
        let expected = km.best.clone();
        km.best.iter_mut().for_each(|b| *b = u32::MAX);
        match k {
            2 => km.assign_at_once::<2>(&centres),
            3 => km.assign_at_once::<3>(&centres),
            _ => km.assign_at_once::<4>(&centres),
        }
        assert_eq!(km.best, expected, "{k} centres");
        moved += expected.iter().filter(|&&j| j as usize == k - 1).count();
        // A tie of the first two centres never goes to the second.
        let ties = &expected[expected.len() - 10..];
        assert!(ties.iter().all(|&j| j != 1), "{ties:?}");
    }
    // Every centre wins some normals.
    assert!(moved > 100, "{moved}");
}
