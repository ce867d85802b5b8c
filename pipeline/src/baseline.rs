//! The least-squares and TLS baselines: each chosen plane's pixels fitted
//! by one plane (from their moments: no pass over the pixels), and the
//! angle between the inclined plane's fit and the ground's (or the
//! selection's up vector without a ground plane).

use nalgebra::Vector3;
use slope_ipc_types::SlopeMethod;

use crate::cloud::angle_between_deg;
use crate::finish::Fit;
use crate::plane_fit::{fit_least_squares, fit_tls, Plane};
use crate::selection::{PlaneSegment, Selection};

/// The least-squares or TLS baseline: each plane's inliers fitted.
pub(crate) fn baseline_fit(
    inclined: &PlaneSegment<'_>,
    ground: Option<&PlaneSegment<'_>>,
    selection: &Selection,
    method: SlopeMethod,
) -> Fit {
    let incl_plane = fit_plane(inclined, method);
    let ground_plane = ground.and_then(|g| fit_plane(g, method));
    let up = ground_plane.map_or(selection.up, |g| g.normal);
    Fit {
        inclined: incl_plane,
        ground: ground_plane,
        angle_deg: incl_plane.map_or(f64::NAN, |p| angle_between_deg(&p.normal, &up)),
        // One fit is one sample: it has no spread (not a spread of 0).
        std_deg: f64::NAN,
        samples: 1,
    }
}

/// A least-squares or TLS plane through the segment's pixels, oriented
/// towards the camera (from their moments: no pass over the pixels).
pub(crate) fn fit_plane(segment: &PlaneSegment<'_>, method: SlopeMethod) -> Option<Plane> {
    let plane = if method == SlopeMethod::LeastSquares {
        fit_least_squares(&segment.moments)
    } else {
        fit_tls(&segment.moments)
    };
    plane.map(|p| p.oriented_towards(&Vector3::zeros()))
}
