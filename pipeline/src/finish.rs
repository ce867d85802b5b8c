//! The estimate from a method's fit: the planes oriented towards the
//! camera, the slope's sign, the distance to the inclined plane along the
//! optical axis, and the confidence (the paper method checked against a
//! TLS fit of the same pixels); without an inclined plane, the ground's
//! TLS fit.

use nalgebra::Vector3;
use slope_ipc_types::{EstimateStatus, SlopeMethod};

use crate::baseline::fit_plane;
use crate::cloud::angle_between_deg;
use crate::confidence::{confidence, ChosenPlane};
use crate::estimate::{Estimate, PlaneEstimate, StageTimings};
use crate::plane_fit::Plane;
use crate::selection::{axis_distance, slope_sign, PlaneSegment, Selection};

/// The planes a method fitted and the angle between them.
pub(crate) struct Fit {
    pub(crate) inclined: Option<Plane>,
    pub(crate) ground: Option<Plane>,
    pub(crate) angle_deg: f64,
    pub(crate) std_deg: f64,
    pub(crate) samples: u32,
}

/// The estimate from a method's fit: sign, distance, planes and confidence
/// (the paper method checked against a TLS fit of the same pixels).
pub(crate) fn finish(
    method: SlopeMethod,
    fit: &Fit,
    inclined: &PlaneSegment<'_>,
    ground: Option<&PlaneSegment<'_>>,
    selection: &Selection,
) -> Result<Estimate, EstimateStatus> {
    let incl_plane = fit
        .inclined
        .map(|p| p.oriented_towards(&Vector3::zeros()))
        .ok_or(EstimateStatus::NoInclinedPlane)?;
    if ground.is_some() && fit.ground.is_none() {
        return Err(EstimateStatus::NoGround);
    }
    let ground_plane = fit.ground.map(|p| p.oriented_towards(&Vector3::zeros()));
    let method_difference_deg = (method == SlopeMethod::Paper).then(|| {
        let up = ground.map_or(Some(selection.up), |g| {
            fit_plane(g, SlopeMethod::Tls).map(|p| p.normal)
        });
        let check = fit_plane(inclined, SlopeMethod::Tls)
            .zip(up)
            .map_or(f64::NAN, |(p, up)| angle_between_deg(&p.normal, &up));
        fit.angle_deg - check
    });
    let confidence = confidence(
        &chosen_plane(inclined),
        ground.map(chosen_plane).as_ref(),
        method_difference_deg,
    );
    Ok(Estimate {
        status: EstimateStatus::Ok,
        method,
        slope_deg: slope_sign(&incl_plane.normal, &selection.forward) * fit.angle_deg,
        slope_std_deg: fit.std_deg,
        samples: fit.samples,
        distance_m: axis_distance(&incl_plane),
        ground: ground_plane.zip(ground).map(|(p, g)| plane_estimate(g, &p)),
        inclined: Some(plane_estimate(inclined, &incl_plane)),
        ground_from_mount: ground.is_none(),
        ground_seen_to_m: f64::NAN,
        confidence: confidence.value,
        confidence_reasons: confidence.reasons,
        tracked: None,
        scene: None,
        timings: StageTimings::default(),
    })
}

/// The ground in an estimate without an inclined plane (a flat floor
/// ahead): its TLS fit, whatever the method.
pub(crate) fn flat_ground_estimate(ground: &PlaneSegment<'_>) -> Option<PlaneEstimate> {
    fit_plane(ground, SlopeMethod::Tls).map(|plane| plane_estimate(ground, &plane))
}

/// A chosen plane in the estimate: `plane` (a fit of the segment's
/// pixels), with the segment's inliers, RMS and area.
fn plane_estimate(segment: &PlaneSegment<'_>, plane: &Plane) -> PlaneEstimate {
    PlaneEstimate {
        coefficients: plane.coefficients(),
        inliers: u32::try_from(segment.inliers.len()).unwrap_or(u32::MAX),
        rms_m: segment.rms_m,
        area_m2: segment.quality.area_m2,
    }
}

/// A chosen plane as the confidence sees it.
fn chosen_plane(segment: &PlaneSegment<'_>) -> ChosenPlane {
    ChosenPlane {
        pixels: segment.inliers.len(),
        quality: segment.quality,
    }
}
