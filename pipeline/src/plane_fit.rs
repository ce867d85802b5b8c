//! Plane fits from point moments: total least squares (PCA), the paper's
//! "traditional" ordinary least squares, and the 3x3 eigen-solver the normal
//! estimation shares.
//!
//! Both fits work from [`Moments`] (count, mean and centred second moments),
//! so a plane with 200,000 inliers is fitted in one pass without copying.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// A plane `normal . p + d = 0` with a unit normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    pub normal: Vector3<f64>,
    pub d: f64,
}

impl Plane {
    /// The plane through `point` with the given (not necessarily unit) normal;
    /// `None` for a zero or non-finite normal.
    pub fn from_point_normal(point: &Vector3<f64>, normal: &Vector3<f64>) -> Option<Self> {
        let n = normal.try_normalize(1e-300)?;
        let d = -n.dot(point);
        (n.iter().all(|c| c.is_finite()) && d.is_finite()).then_some(Self { normal: n, d })
    }

    /// The plane through three points; `None` when they are (nearly) collinear.
    pub fn from_three_points(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> Option<Self> {
        let n = (b - a).cross(&(c - a));
        let scale = (b - a).norm() * (c - a).norm();
        if !(scale > 0.0) || n.norm() < 1e-6 * scale {
            return None;
        }
        Self::from_point_normal(a, &n)
    }

    /// Signed distance of `p` from the plane (positive on the normal's side).
    #[inline]
    pub fn signed_distance(&self, p: &Vector3<f64>) -> f64 {
        self.normal.dot(p) + self.d
    }

    /// The same plane with its normal flipped, if needed, so that
    /// `normal . (viewpoint - p) >= 0` for points `p` on it: the normal points
    /// to the viewpoint's side.
    pub fn oriented_towards(self, viewpoint: &Vector3<f64>) -> Self {
        if self.signed_distance(viewpoint) < 0.0 {
            Self {
                normal: -self.normal,
                d: -self.d,
            }
        } else {
            self
        }
    }

    /// `[a, b, c, d]` as in `SlopeEstimate`.
    pub fn coefficients(&self) -> [f64; 4] {
        [self.normal.x, self.normal.y, self.normal.z, self.d]
    }
}

/// Count, mean and centred scatter matrix of a point set, accumulated around
/// a reference point so that large coordinates lose no precision.
#[derive(Debug, Clone, Copy, Default)]
pub struct Moments {
    count: usize,
    origin: Vector3<f64>,
    sum: Vector3<f64>,
    sum_outer: Matrix3<f64>,
}

impl Moments {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a point (ignored when not finite).
    #[inline]
    pub fn add(&mut self, p: &Vector3<f64>) {
        if !p.iter().all(|c| c.is_finite()) {
            return;
        }
        if self.count == 0 {
            self.origin = *p;
        }
        let q = p - self.origin;
        self.count += 1;
        self.sum += q;
        self.sum_outer += q * q.transpose();
    }

    pub fn count(&self) -> usize {
        self.count
    }

    /// Adds every point of `other` (the moments of the union).
    pub fn merge(&mut self, other: &Moments) {
        if other.count == 0 {
            return;
        }
        if self.count == 0 {
            *self = *other;
            return;
        }
        // other's points relative to self's origin: q + delta.
        let delta = other.origin - self.origin;
        let n = other.count as f64;
        self.sum_outer += other.sum_outer
            + delta * other.sum.transpose()
            + other.sum * delta.transpose()
            + delta * delta.transpose() * n;
        self.sum += other.sum + delta * n;
        self.count += other.count;
    }

    /// The centroid, `None` when empty.
    pub fn mean(&self) -> Option<Vector3<f64>> {
        (self.count > 0).then(|| self.origin + self.sum / self.count as f64)
    }

    /// The covariance `1/n sum (p - mean)(p - mean)^T`, `None` when empty.
    pub fn covariance(&self) -> Option<Matrix3<f64>> {
        if self.count == 0 {
            return None;
        }
        let n = self.count as f64;
        let m = self.sum / n;
        Some(self.sum_outer / n - m * m.transpose())
    }
}

/// [`Moments`] for hot loops: sums about a fixed origin given up front, no
/// checks per point (the caller adds finite points only); symmetric
/// second moments kept once.
#[derive(Debug, Clone, Copy, Default)]
pub struct MomentSums {
    origin: Vector3<f64>,
    count: usize,
    /// x, y, z, xx, xy, xz, yy, yz, zz about `origin`.
    sums: [f64; 9],
}

impl MomentSums {
    /// Empty sums about `origin` (any point near the set: a plane's foot).
    pub fn about(origin: Vector3<f64>) -> Self {
        Self {
            origin,
            count: 0,
            sums: [0.0; 9],
        }
    }

    /// Adds a finite point.
    #[inline(always)]
    pub fn add(&mut self, x: f64, y: f64, z: f64) {
        let (x, y, z) = (x - self.origin.x, y - self.origin.y, z - self.origin.z);
        let s = &mut self.sums;
        self.count += 1;
        s[0] += x;
        s[1] += y;
        s[2] += z;
        s[3] += x * x;
        s[4] += x * y;
        s[5] += x * z;
        s[6] += y * y;
        s[7] += y * z;
        s[8] += z * z;
    }

    /// Adds the points of `other`, summed about the same origin.
    pub fn merge(&mut self, other: &MomentSums) {
        debug_assert_eq!(self.origin, other.origin);
        self.count += other.count;
        for (s, o) in self.sums.iter_mut().zip(&other.sums) {
            *s += o;
        }
    }

    /// The same moments as [`Moments`] (which fits take).
    pub fn moments(&self) -> Moments {
        let s = &self.sums;
        if self.count == 0 {
            return Moments::new();
        }
        Moments {
            count: self.count,
            origin: self.origin,
            sum: Vector3::new(s[0], s[1], s[2]),
            sum_outer: Matrix3::new(s[3], s[4], s[5], s[4], s[6], s[7], s[5], s[7], s[8]),
        }
    }
}

/// The unit eigenvector of the smallest eigenvalue of a symmetric 3x3 matrix
/// (nalgebra's symmetric eigen-decomposition) and that eigenvalue; `None`
/// for a non-finite matrix.
pub fn smallest_eigenvector(m: &Matrix3<f64>) -> Option<(Vector3<f64>, f64)> {
    if !m.iter().all(|c| c.is_finite()) {
        return None;
    }
    let eig = SymmetricEigen::new(*m);
    let (i, &lambda) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))?;
    let v = eig.eigenvectors.column(i).into_owned();
    let v = v.try_normalize(1e-300)?;
    Some((v, lambda))
}

/// Total least squares: the plane through the centroid whose normal is the
/// covariance's smallest eigenvector. `None` with fewer than 3 points or a
/// degenerate (collinear) set.
pub fn fit_tls(moments: &Moments) -> Option<Plane> {
    if moments.count() < 3 {
        return None;
    }
    let cov = moments.covariance()?;
    if !cov.iter().all(|c| c.is_finite()) {
        return None;
    }
    let eig = SymmetricEigen::new(cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let ev = order.map(|k| eig.eigenvalues[k]);
    // Two vanishing eigenvalues: the points lie on a line (or a point).
    if !(ev[1] > 1e-12 * ev[2].max(f64::MIN_POSITIVE)) {
        return None;
    }
    let n = eig.eigenvectors.column(order[0]).into_owned();
    Plane::from_point_normal(&moments.mean()?, &n)
}

/// The unit eigenvector of the smallest eigenvalue of the symmetric matrix
/// `[[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]` in closed form: eigenvalues
/// from the trigonometric solution of the characteristic cubic, the
/// eigenvector as the longest cross product of two rows of `A - lambda I`.
/// About 10x faster than the iterative [`SymmetricEigen`] (which the tests
/// use as its oracle); the per-point normals call it tens of thousands of
/// times per frame. `None` when the matrix is not finite or the smallest
/// eigenvalue is not separated from the others (no defined normal).
#[inline]
pub fn smallest_eigenvector_3x3(cov: &[f64; 6]) -> Option<Vector3<f64>> {
    let [xx, xy, xz, yy, yz, zz] = *cov;
    let (q, p2) = eigen_spread(cov)?;
    let (a, b, c) = (xx - q, yy - q, zz - q);
    let p = (p2 / 6.0).sqrt();
    // det(A - q I) / p^3 / 2
    let det = a * (b * c - yz * yz) - xy * (xy * c - yz * xz) + xz * (xy * yz - b * xz);
    let r = (det / (2.0 * p * p * p)).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let lambda = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    eigenvector_for(cov, lambda, p2)
}

/// The mean `q` of the eigenvalues of the symmetric matrix `cov` (as in
/// [`smallest_eigenvector_3x3`]) and `p2`, the sum of their squared
/// deviations from it (`tr((A - q I)^2)`); `None` unless `p2` is finite and
/// positive (a matrix with a non-finite entry, or a multiple of I).
#[inline]
pub(crate) fn eigen_spread(cov: &[f64; 6]) -> Option<(f64, f64)> {
    let [xx, xy, xz, yy, yz, zz] = *cov;
    let q = (xx + yy + zz) / 3.0;
    let p1 = xy * xy + xz * xz + yz * yz;
    let (a, b, c) = (xx - q, yy - q, zz - q);
    let p2 = a * a + b * b + c * c + 2.0 * p1;
    (p2 > 0.0 && p2.is_finite()).then_some((q, p2))
}

/// The unit eigenvector of eigenvalue `lambda` of the symmetric matrix
/// `cov` (as in [`smallest_eigenvector_3x3`]): the longest cross product of
/// two rows of `A - lambda I`; `None` when that product vanishes against
/// `p2` ([`eigen_spread`]), i.e. when `lambda` is not separated from
/// another eigenvalue.
#[inline]
pub(crate) fn eigenvector_for(cov: &[f64; 6], lambda: f64, p2: f64) -> Option<Vector3<f64>> {
    let [xx, xy, xz, yy, yz, zz] = *cov;
    let r0 = Vector3::new(xx - lambda, xy, xz);
    let r1 = Vector3::new(xy, yy - lambda, yz);
    let r2 = Vector3::new(xz, yz, zz - lambda);
    let c01 = r0.cross(&r1);
    let c02 = r0.cross(&r2);
    let c12 = r1.cross(&r2);
    let (n01, n02, n12) = (c01.norm_squared(), c02.norm_squared(), c12.norm_squared());
    let (best, norm_sq) = if n01 >= n02 && n01 >= n12 {
        (c01, n01)
    } else if n02 >= n12 {
        (c02, n02)
    } else {
        (c12, n12)
    };
    // The cross product vanishes when the two smaller eigenvalues coincide.
    if !(norm_sq > 1e-20 * p2 * p2) {
        return None;
    }
    Some(best / norm_sq.sqrt())
}

/// Ordinary least squares, the paper's "traditional method": the coordinate
/// along which the plane is best conditioned (the largest component of the
/// TLS normal, z for a floor seen from a level camera) is regressed on the
/// other two, `k = a i + b j + c`. Residuals are measured along that axis,
/// not perpendicular to the plane, which is what makes it differ from TLS.
pub fn fit_least_squares(moments: &Moments) -> Option<Plane> {
    let tls = fit_tls(moments)?;
    let cov = moments.covariance()?;
    let k = tls.normal.iamax();
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    let (sii, sij, sjj) = (cov[(i, i)], cov[(i, j)], cov[(j, j)]);
    let (sik, sjk) = (cov[(i, k)], cov[(j, k)]);
    let det = sii * sjj - sij * sij;
    if !(det.abs() > 1e-18 * (sii * sjj).max(f64::MIN_POSITIVE)) {
        return None;
    }
    let a = (sik * sjj - sjk * sij) / det;
    let b = (sjk * sii - sik * sij) / det;
    let mut n = Vector3::zeros();
    n[k] = 1.0;
    n[i] = -a;
    n[j] = -b;
    Plane::from_point_normal(&moments.mean()?, &n)
}

/// The six entries `[xx, xy, xz, yy, yz, zz]` of a symmetric matrix, as
/// the eigenvector solvers take a covariance (tests only).
#[cfg(test)]
pub(crate) fn upper_triangle(m: &Matrix3<f64>) -> [f64; 6] {
    [
        m[(0, 0)],
        m[(0, 1)],
        m[(0, 2)],
        m[(1, 1)],
        m[(1, 2)],
        m[(2, 2)],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::angle_between_deg;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The moments of two sets merged are the moments of their union.
    #[test]
    fn merged_moments_are_the_union_s() {
        let a = plane_points(500, Vector3::new(0.1, -0.9, -0.4), 1.2, 0.01);
        let b = plane_points(300, Vector3::new(0.6, 0.2, -0.7), 2.5, 0.02);
        let (mut ma, mut mb, mut all) = (Moments::new(), Moments::new(), Moments::new());
        a.iter().for_each(|p| ma.add(p));
        b.iter().for_each(|p| mb.add(p));
        a.iter().chain(&b).for_each(|p| all.add(p));
        let mut merged = ma;
        merged.merge(&mb);
        assert_eq!(merged.count(), all.count());
        assert!((merged.mean().unwrap() - all.mean().unwrap()).norm() < 1e-12);
        let diff = merged.covariance().unwrap() - all.covariance().unwrap();
        assert!(diff.abs().max() < 1e-12, "{diff}");
        let mut empty = Moments::new();
        empty.merge(&ma);
        assert_eq!(empty.mean(), ma.mean());
        ma.merge(&Moments::new());
        assert_eq!(empty.covariance(), ma.covariance());
    }

    /// The lean sums give the moments of the checked accumulator.
    #[test]
    fn moment_sums_match_moments() {
        let points = plane_points(400, Vector3::new(0.2, -0.8, -0.5), 1.7, 0.01);
        let mut checked = Moments::new();
        let mut lean = MomentSums::about(Vector3::new(0.0, 1.4, 0.9));
        for p in &points {
            checked.add(p);
            lean.add(p.x, p.y, p.z);
        }
        let lean = lean.moments();
        assert_eq!(lean.count(), checked.count());
        assert!((lean.mean().unwrap() - checked.mean().unwrap()).norm() < 1e-12);
        let diff = lean.covariance().unwrap() - checked.covariance().unwrap();
        assert!(diff.abs().max() < 1e-12, "{diff}");
        assert_eq!(MomentSums::default().moments().count(), 0);
    }

    fn plane_points(n: usize, normal: Vector3<f64>, d: f64, noise: f64) -> Vec<Vector3<f64>> {
        let n0 = normal.normalize();
        let u = n0.cross(&Vector3::new(0.3, 0.5, 0.8)).normalize();
        let v = n0.cross(&u);
        let origin = -d * n0;
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        (0..n)
            .map(|_| {
                origin
                    + u * rng.random_range(-1.0..1.0)
                    + v * rng.random_range(-1.0..1.0)
                    + n0 * rng.random_range(-noise..=noise)
            })
            .collect()
    }

    #[test]
    fn tls_recovers_an_exact_plane() {
        let normal = Vector3::new(0.2, -0.9, -0.4).normalize();
        let pts = plane_points(500, normal, 3.0, 0.0);
        let mut m = Moments::new();
        pts.iter().for_each(|p| m.add(p));
        let plane = fit_tls(&m).unwrap();
        assert!(plane.normal.dot(&normal).abs() > 1.0 - 1e-12);
        for p in &pts {
            assert!(plane.signed_distance(p).abs() < 1e-9);
        }
        let lsq = fit_least_squares(&m).unwrap();
        assert!(lsq.normal.dot(&normal).abs() > 1.0 - 1e-12);
    }

    /// Noise along the normal (uniform +-10 cm, sigma 5.8 cm) on a plane at
    /// 45 degrees to the regressed axis: least squares, with noise in its
    /// regressors, tilts its normal by about `sigma^2 / (2 var(y))` = 0.57
    /// degrees (the regressor's spread `var(y)` is 1/6 m^2 here); TLS is
    /// unbiased and off by its sampling error only (about 0.13 degrees for
    /// 2000 points).
    #[test]
    fn least_squares_differs_from_tls_under_noise_but_both_are_close() {
        let normal = Vector3::new(0.0, -0.7, -0.7).normalize();
        let pts = plane_points(2000, normal, 2.0, 0.1);
        let mut m = Moments::new();
        pts.iter().for_each(|p| m.add(p));
        let tls = fit_tls(&m).unwrap();
        let lsq = fit_least_squares(&m).unwrap();
        // Angles between unoriented normals, degrees.
        let apart = |a: &Vector3<f64>, b: &Vector3<f64>| {
            angle_between_deg(a, b).min(angle_between_deg(a, &-b))
        };
        let (tls_off, lsq_off) = (apart(&tls.normal, &normal), apart(&lsq.normal, &normal));
        assert!(tls_off < 0.5, "tls {tls_off}");
        assert!(lsq_off < 1.0, "lsq {lsq_off}");
        // They differ by the bias, more than twice TLS's sampling error.
        let between = apart(&tls.normal, &lsq.normal);
        assert!(between > 0.3, "{between}");
        assert!(lsq_off > tls_off + 0.3, "{lsq_off} vs {tls_off}");
    }

    #[test]
    fn degenerate_sets_give_none() {
        let mut m = Moments::new();
        assert!(fit_tls(&m).is_none());
        for i in 0..10 {
            m.add(&Vector3::new(i as f64, 2.0 * i as f64, 1.0));
        }
        assert!(fit_tls(&m).is_none());
        assert!(fit_least_squares(&m).is_none());
        m.add(&Vector3::new(f64::NAN, 0.0, 0.0));
        assert_eq!(m.count(), 10);
        assert!(Plane::from_three_points(
            &Vector3::zeros(),
            &Vector3::new(1.0, 1.0, 1.0),
            &Vector3::new(2.0, 2.0, 2.0)
        )
        .is_none());
    }

    #[test]
    fn orientation_faces_the_viewpoint() {
        let plane = Plane::from_point_normal(&Vector3::new(0.0, 0.0, 2.0), &Vector3::z()).unwrap();
        let o = plane.oriented_towards(&Vector3::zeros());
        assert!((o.normal.z + 1.0).abs() < 1e-12);
        assert!((o.d - 2.0).abs() < 1e-12);
    }

    #[test]
    fn closed_form_eigenvector_matches_nalgebra() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for _ in 0..2000 {
            // Random planar-ish covariances: two large, one small eigenvalue,
            // random orientation, at scales from millimetres to metres.
            let scale = 10f64.powf(rng.random_range(-4.0..1.0));
            let axis = |rng: &mut ChaCha8Rng| {
                Vector3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
            };
            let (a, b, c) = (axis(&mut rng), axis(&mut rng), axis(&mut rng));
            let m: Matrix3<f64> = (a * a.transpose()
                + b * b.transpose()
                + c * c.transpose() * rng.random_range(0.0..0.05))
                * scale;
            let (oracle, _) = smallest_eigenvector(&m).unwrap();
            let fast = smallest_eigenvector_3x3(&upper_triangle(&m)).unwrap();
            let eig = SymmetricEigen::new(m);
            let mut ev: Vec<f64> = eig.eigenvalues.iter().copied().collect();
            ev.sort_by(f64::total_cmp);
            // The eigenvector is defined to within the gap's conditioning.
            let tol = 1e-9 * ev[2] / (ev[1] - ev[0]);
            assert!(
                1.0 - oracle.dot(&fast).abs() < tol.max(1e-12),
                "{oracle:?} vs {fast:?} for {m:?}"
            );
        }
        assert!(smallest_eigenvector_3x3(&[0.0; 6]).is_none());
        assert!(smallest_eigenvector_3x3(&[f64::NAN, 0.0, 0.0, 1.0, 0.0, 1.0]).is_none());
    }

    #[test]
    fn moments_match_a_direct_covariance() {
        let pts = plane_points(100, Vector3::new(1.0, 2.0, 3.0), 1000.0, 0.5);
        let mut m = Moments::new();
        pts.iter().for_each(|p| m.add(p));
        let mean = pts.iter().sum::<Vector3<f64>>() / pts.len() as f64;
        let cov = pts
            .iter()
            .map(|p| (p - mean) * (p - mean).transpose())
            .sum::<Matrix3<f64>>()
            / pts.len() as f64;
        assert!((m.mean().unwrap() - mean).norm() < 1e-9);
        assert!((m.covariance().unwrap() - cov).norm() < 1e-9);
    }
}
