//! The floor of a real frame: RANSAC over the up-facing points of the lower
//! image, then least-squares refits on its inliers. Deterministic: the
//! samples come from a ChaCha8 stream of the given seed.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::hinge::FloorPlane;
use super::organised::OrganisedCloud;

/// RANSAC hypotheses drawn.
const ITERATIONS: usize = 400;
/// At most this many candidates score each hypothesis (an even subsample).
const SCORED: usize = 20_000;
/// Least-squares refits on the inliers after RANSAC.
const REFITS: usize = 3;
/// Fewer up-facing candidates than this: no floor.
pub const MIN_CANDIDATES: usize = 500;
/// A hypothesis closer to the camera than this is not a floor under it.
const MIN_HEIGHT_M: f64 = 0.05;

/// How far a floor point may lie from the plane: 1.5 cm plus 1 % of its
/// depth. Wide enough for a Kinect v1's noise at 4 m (about 3 cm) and a
/// Kinect v2's at any range, narrow enough to leave a 5 cm kerb out.
pub fn inlier_band_m(depth_m: f64) -> f64 {
    0.015 + 0.01 * depth_m
}

/// Where to look for the floor and how far its normal may lean.
#[derive(Debug, Clone, Copy)]
pub struct FloorSearch {
    /// Rough upward direction in camera coordinates (the mount's, else -y).
    pub hint_up: Vector3<f64>,
    /// Largest angle between a candidate's normal (and the plane's) and
    /// `hint_up`, degrees.
    pub cone_deg: f64,
    pub seed: u64,
}

/// Why no floor was found (the caller adds which frame).
#[derive(Debug, Clone, PartialEq)]
pub enum FitFailure {
    TooFewCandidates { found: usize },
    NoPlane,
}

impl std::fmt::Display for FitFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::TooFewCandidates { found } => write!(
                f,
                "{found} up-facing points in the lower half of the image (at least \
                 {MIN_CANDIDATES} needed)"
            ),
            Self::NoPlane => write!(
                f,
                "no plane below the camera facing up among the lower image's up-facing points"
            ),
        }
    }
}

/// Fits the floor of `cloud`: candidates are the points of the lower half
/// of the image whose local normal lies within `search.cone_deg` of
/// `search.hint_up`.
pub fn fit_floor(cloud: &OrganisedCloud, search: &FloorSearch) -> Result<FloorPlane, FitFailure> {
    let cos_cone = search.cone_deg.to_radians().cos();
    let first_row = cloud.height / 2;
    let candidates: Vec<Vector3<f64>> = (first_row * cloud.width..cloud.len())
        .filter_map(|i| {
            let p = cloud.points[i]?;
            let n = cloud.normals[i]?;
            (n.dot(&search.hint_up) >= cos_cone).then_some(p)
        })
        .collect();
    if candidates.len() < MIN_CANDIDATES {
        return Err(FitFailure::TooFewCandidates {
            found: candidates.len(),
        });
    }
    let stride = candidates.len().div_ceil(SCORED);
    let scored: Vec<Vector3<f64>> = candidates.iter().step_by(stride).copied().collect();

    let mut rng = ChaCha8Rng::seed_from_u64(search.seed);
    let mut best: Option<(usize, Vector3<f64>, f64)> = None;
    for _ in 0..ITERATIONS {
        let a = candidates[rng.random_range(0..candidates.len())];
        let b = candidates[rng.random_range(0..candidates.len())];
        let c = candidates[rng.random_range(0..candidates.len())];
        let Some((up, height)) = plane_through(a, b, c, search.hint_up) else {
            continue;
        };
        if up.dot(&search.hint_up) < cos_cone || height < MIN_HEIGHT_M {
            continue;
        }
        let score = count_inliers(&scored, up, height);
        if best.is_none_or(|(s, _, _)| score > s) {
            best = Some((score, up, height));
        }
    }
    let (_, mut up, mut height) = best.ok_or(FitFailure::NoPlane)?;
    let mut fit_points = 0;
    let mut rms_m = 0.0;
    for _ in 0..REFITS {
        let inliers: Vec<Vector3<f64>> = candidates
            .iter()
            .copied()
            .filter(|p| (up.dot(p) + height).abs() <= inlier_band_m(p.z))
            .collect();
        let Some((u, h)) = least_squares_plane(&inliers, search.hint_up) else {
            break;
        };
        (up, height) = (u, h);
        fit_points = inliers.len();
        rms_m = (inliers
            .iter()
            .map(|p| (up.dot(p) + height).powi(2))
            .sum::<f64>()
            / inliers.len().max(1) as f64)
            .sqrt();
    }
    if height < MIN_HEIGHT_M {
        return Err(FitFailure::NoPlane);
    }
    Ok(FloorPlane {
        up: up.into(),
        height_m: height,
        fit_points,
        rms_m,
    })
}

/// The plane through three points, its normal turned towards `hint_up`:
/// `(up, height)` with `up · p + height = 0`. `None` when they are
/// (nearly) collinear.
fn plane_through(
    a: Vector3<f64>,
    b: Vector3<f64>,
    c: Vector3<f64>,
    hint_up: Vector3<f64>,
) -> Option<(Vector3<f64>, f64)> {
    let n = (b - a).cross(&(c - a));
    let norm = n.norm();
    if norm < 1e-9 {
        return None;
    }
    let mut up = n / norm;
    if up.dot(&hint_up) < 0.0 {
        up = -up;
    }
    Some((up, -up.dot(&a)))
}

fn count_inliers(points: &[Vector3<f64>], up: Vector3<f64>, height: f64) -> usize {
    points
        .iter()
        .filter(|p| (up.dot(p) + height).abs() <= inlier_band_m(p.z))
        .count()
}

/// The total least-squares plane of `points` (the centroid and the
/// scatter's smallest eigenvector), its normal turned towards `hint_up`.
pub fn least_squares_plane(
    points: &[Vector3<f64>],
    hint_up: Vector3<f64>,
) -> Option<(Vector3<f64>, f64)> {
    if points.len() < 3 {
        return None;
    }
    let centroid = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let scatter = points
        .iter()
        .map(|p| {
            let d = p - centroid;
            d * d.transpose()
        })
        .sum::<Matrix3<f64>>();
    let eigen = SymmetricEigen::new(scatter);
    let smallest = eigen.eigenvalues.imin();
    let mut up: Vector3<f64> = eigen.eigenvectors.column(smallest).into_owned();
    if up.dot(&hint_up) < 0.0 {
        up = -up;
    }
    Some((up, -up.dot(&centroid)))
}
