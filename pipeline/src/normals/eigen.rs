//! The smallest eigenvector of a window's covariance, as
//! `plane_fit::smallest_eigenvector_3x3` finds it but with the smallest
//! eigenvalue from Newton's method on the characteristic cubic instead of
//! its trigonometric solution (`acos`, `cos` and a square root, half the
//! solver's instructions). The two agree to rounding (tested); the
//! per-point normals call it once a point. The coarse grid normals that
//! gate RANSAC and the k-d tree fallback keep the shared solver.

use nalgebra::Vector3;

use crate::plane_fit::{eigen_spread, eigenvector_for, smallest_eigenvector_3x3};

/// The unit eigenvector of the smallest eigenvalue of the symmetric
/// positive semi-definite matrix `[[xx, xy, xz], [xy, yy, yz], [xz, yz,
/// zz]]` (a covariance); `None` when it is not finite or the smallest
/// eigenvalue is not separated from the others.
///
/// The characteristic cubic `g(l) = l^3 - c2 l^2 + c1 l - c0` is negative,
/// increasing and concave from 0 (`g(0) = -det <= 0`) up to the smallest
/// eigenvalue (which is below the mean, where `g''` turns positive), so
/// Newton's method from 0 climbs to it monotonically, quadratically once
/// near; on a plane's patch (one small eigenvalue) the first step,
/// `det / c1`, is already close. When the two smaller eigenvalues nearly
/// coincide (the normal barely defined) the root turns double and Newton
/// slows: after [`MAX_NEWTON_STEPS`] without settling the shared
/// trigonometric solver answers.
#[inline]
pub(super) fn smallest_eigenvector_sym3(cov: &[f64; 6]) -> Option<Vector3<f64>> {
    let (_, p2) = eigen_spread(cov)?;
    let Some(lambda) = smallest_eigenvalue(cov) else {
        return smallest_eigenvector_3x3(cov);
    };
    eigenvector_for(cov, lambda, p2)
}

/// The smallest eigenvalue by Newton's method from 0
/// ([`smallest_eigenvector_sym3`]); `None` when it has not settled within
/// [`MAX_NEWTON_STEPS`].
#[inline]
fn smallest_eigenvalue(cov: &[f64; 6]) -> Option<f64> {
    let [xx, xy, xz, yy, yz, zz] = *cov;
    let c2 = xx + yy + zz;
    let c1 = (xx * yy - xy * xy) + (xx * zz - xz * xz) + (yy * zz - yz * yz);
    let c0 = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
    // Settled: convergence is quadratic, so after a step this small the
    // error is far below the rounding of the eigenvalues' scale (which
    // itself can be several times 1e-16 c2: a tolerance there may never
    // be met).
    let tolerance = 1e-11 * c2.abs();
    let mut lambda = 0.0;
    for _ in 0..MAX_NEWTON_STEPS {
        let g = ((lambda - c2) * lambda + c1) * lambda - c0;
        let slope = (3.0 * lambda - 2.0 * c2) * lambda + c1;
        let step = g / slope;
        lambda -= step;
        if step.abs() <= tolerance {
            return lambda.is_finite().then_some(lambda);
        }
    }
    None
}

/// Newton steps at most before the trigonometric solver takes over: a
/// patch whose smallest eigenvalue is half the next settles in about 7, a
/// plane's (noise-small normal eigenvalue) in 2-4.
const MAX_NEWTON_STEPS: usize = 12;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plane_fit::upper_triangle;
    use nalgebra::{Matrix3, SymmetricEigen};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Covariances of planar patches (one eigenvalue at most half the next,
    /// the others in ratios up to 1:10 as on grazing ground), any ones and nearly
    /// degenerate ones, random orientations, scales from millimetres to
    /// metres: Newton settles on every patch-like one, and the vector is
    /// the shared solver's to rounding (to within the gap's conditioning).
    #[test]
    fn newton_eigenvector_is_the_trigonometric_one() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let (mut planar, mut settled) = (0, 0);
        for k in 0..6000 {
            let scale = 10f64.powf(rng.random_range(-5.0..1.0));
            let m = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let basis = m.qr().q();
            let (l1, l2, l3) = match k % 3 {
                // A plane's patch: the normal's eigenvalue noise-small.
                0 => (
                    rng.random_range(0.0..0.05),
                    rng.random_range(0.05..1.0),
                    1.0,
                ),
                // Any spectrum.
                1 => (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0), 1.0),
                // The two smaller nearly equal.
                _ => {
                    let l = rng.random_range(0.0..0.5);
                    (l, l * (1.0 + rng.random_range(0.0..1e-6)), 1.0)
                }
            };
            let d = Matrix3::from_diagonal(&Vector3::new(l1, l2, l3));
            let a = basis * d * basis.transpose() * scale;
            let a = (a + a.transpose()) * 0.5;
            let cov = upper_triangle(&a);
            if k % 3 == 0 {
                planar += 1;
                settled += usize::from(smallest_eigenvalue(&cov).is_some());
            }
            let (ours, shared) = (
                smallest_eigenvector_sym3(&cov),
                smallest_eigenvector_3x3(&cov),
            );
            let (Some(ours), Some(shared)) = (ours, shared) else {
                assert_eq!(ours.is_some(), shared.is_some(), "{a:?}");
                continue;
            };
            let mut ev: Vec<f64> = SymmetricEigen::new(a).eigenvalues.iter().copied().collect();
            ev.sort_by(f64::total_cmp);
            let tol = 1e-12 * ev[2] / (ev[1] - ev[0]);
            assert!(
                1.0 - ours.dot(&shared).abs() < tol.max(1e-14),
                "{ours:?} vs {shared:?} for {a:?}"
            );
            assert!((ours.norm() - 1.0).abs() < 1e-15);
        }
        assert_eq!(settled, planar);
        assert!(smallest_eigenvector_sym3(&[0.0; 6]).is_none());
        assert!(smallest_eigenvector_sym3(&[f64::NAN, 0.0, 0.0, 1.0, 0.0, 1.0]).is_none());
    }
}
