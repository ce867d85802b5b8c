//! How far to trust an estimate: a confidence in [0, 1] and the reasons it
//! is below 1 (bits of `slope_ipc_types::confidence`).
//!
//! The confidence is the product of one factor per reason, each 1 when the
//! reason does not apply:
//!
//! | reason | applies when | factor |
//! |---|---|---|
//! | `few_points` | a chosen plane has fewer than 3000 pixels | `max(n / 3000, 0.2)` |
//! | `rough_plane` | a chosen plane's relative RMS is above 0.3, or the inclined plane's noise ratio above 2.5 | down to 0.5 at 0.45 (3.5) |
//! | `small_area` | the inclined plane covers under 0.05 m^2 | `max(area / 0.05, 0.3)` |
//! | `ground_from_mount` | no ground plane was seen | 0.7 |
//! | `near_border` | over 30 % of a plane's pixels are within 8 px of the border | `1 - (share - 0.3)`, at least 0.5 |
//! | `methods_disagree` | paper method and TLS differ by more than 1 degree | `max(1 / difference, 0.2)` |
//! | `close_choice` | another ramp or wall at a different slope lies in the corridor within `road.close_choice_m` behind the road | 0.7 |
//! | `foot_hidden` | the road's foot is hidden behind something nearer | 0.7 |
//! | `mount_mismatch` | the floor seen (the nearest, `selection::mount_disagrees`) is not parallel to the ground the mount chose, or not at the mount's height | 0.7 |
//! | `small_surface` | the road's surface is narrower than 0.2 m, under 1,500 pixels or under 0.03 m^2 ([`is_small_surface`]) | at most 0.3 in all |
//!
//! A planner may gate on the value (e.g. `>= 0.5`) and log the reasons.

use slope_ipc_types::confidence as reason;

use crate::selection::PlaneQuality;

/// Fewer pixels than this on a chosen plane lower the confidence.
pub const FEW_PIXELS: usize = 3000;
/// Relative RMS above this lowers the confidence...
pub const ROUGH_RELATIVE_RMS: f64 = 0.3;
/// ...to half at this (the selection's default flatness limit).
pub const ROUGH_HALF_AT: f64 = 0.45;
/// An inclined plane's noise ratio (RMS in standard deviations of the
/// sensor's noise) above this lowers the confidence...
pub const ROUGH_NOISE_RATIO: f64 = 2.5;
/// ...to half at this (the selection's default limit).
pub const ROUGH_NOISE_HALF_AT: f64 = 3.5;
/// An inclined plane smaller than this lowers the confidence, m^2.
pub const SMALL_AREA_M2: f64 = 0.05;
/// The factor for a ground taken from the mount.
pub const GROUND_FROM_MOUNT_FACTOR: f64 = 0.7;
/// A share of border pixels above this lowers the confidence.
pub const BORDER_SHARE: f64 = 0.3;
/// Paper method and TLS differing by more than this lower it, degrees.
pub const DISAGREEMENT_DEG: f64 = 1.0;

/// A chosen plane as the confidence sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChosenPlane {
    pub pixels: usize,
    pub quality: PlaneQuality,
}

/// The confidence and its reasons.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Confidence {
    pub value: f64,
    pub reasons: u32,
}

impl Confidence {
    fn full() -> Self {
        Self {
            value: 1.0,
            reasons: 0,
        }
    }

    fn lower(&mut self, bit: u32, factor: f64) {
        if factor < 1.0 {
            self.value *= factor.clamp(0.0, 1.0);
            self.reasons |= bit;
        }
    }
}

/// The confidence of an estimate from its inclined plane, its ground
/// (`None`: from the mount) and, when known, the difference between the
/// paper method's and a TLS fit's angle, degrees.
pub fn confidence(
    inclined: &ChosenPlane,
    ground: Option<&ChosenPlane>,
    method_difference_deg: Option<f64>,
) -> Confidence {
    let mut c = Confidence::full();
    let is_inclined = std::iter::once(true).chain(ground.map(|_| false));
    for (plane, is_inclined) in std::iter::once(inclined).chain(ground).zip(is_inclined) {
        let few = (plane.pixels as f64 / FEW_PIXELS as f64).max(0.2);
        c.lower(reason::FEW_POINTS, few);
        let q = &plane.quality;
        let mut rough = falling(q.relative_rms, ROUGH_RELATIVE_RMS, ROUGH_HALF_AT);
        if is_inclined {
            rough = rough.min(falling(
                q.noise_ratio,
                ROUGH_NOISE_RATIO,
                ROUGH_NOISE_HALF_AT,
            ));
        }
        c.lower(reason::ROUGH_PLANE, rough);
        let border = 1.0 - (plane.quality.border_fraction - BORDER_SHARE).max(0.0);
        c.lower(reason::NEAR_BORDER, border.max(0.5));
    }
    c.lower(
        reason::SMALL_AREA,
        (inclined.quality.area_m2 / SMALL_AREA_M2).max(0.3),
    );
    if ground.is_none() {
        c.lower(reason::GROUND_FROM_MOUNT, GROUND_FROM_MOUNT_FACTOR);
    }
    if let Some(diff) = method_difference_deg.filter(|d| d.is_finite()) {
        let diff = diff.abs();
        if diff > DISAGREEMENT_DEG {
            c.lower(reason::METHODS_DISAGREE, (1.0 / diff).max(0.2));
        }
    }
    c
}

/// 1 up to `from`, falling linearly to 0.5 at `half_at`, 0.5 beyond.
/// The factor of a road chosen in a close call (`close_choice`).
pub const CLOSE_CHOICE_FACTOR: f64 = 0.7;
/// The factor of a road whose foot is hidden (`foot_hidden`).
pub const FOOT_HIDDEN_FACTOR: f64 = 0.7;

/// A road narrower than this across the corridor is a small surface,
/// metres (a post, a table leg: too narrow to measure a slope on).
pub const SMALL_SURFACE_WIDTH_M: f64 = 0.2;
/// A road with fewer pixels than this is a small surface.
pub const SMALL_SURFACE_PIXELS: usize = 1500;
/// A road covering less than this is a small surface, square metres.
pub const SMALL_SURFACE_AREA_M2: f64 = 0.03;
/// The most a small surface's confidence can be.
pub const SMALL_SURFACE_CAP: f64 = 0.3;

/// True when a road surface `width_m` wide across the corridor (its lateral
/// extent), of `pixels` inliers covering `area_m2`, is too small to measure
/// its slope well. Its role and distance hold (a post in the path is an
/// obstacle); its confidence says so.
pub fn is_small_surface(width_m: f64, pixels: usize, area_m2: f64) -> bool {
    !(width_m >= SMALL_SURFACE_WIDTH_M)
        || pixels < SMALL_SURFACE_PIXELS
        || !(area_m2 >= SMALL_SURFACE_AREA_M2)
}

/// The factor of an estimate whose floor disagrees with the mount
/// (`mount_mismatch`).
pub const MOUNT_MISMATCH_FACTOR: f64 = 0.7;

/// How the road was chosen and what it is (`selection/road.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RoadChoice {
    /// The floor seen disagrees with the mount (`selection::mount_disagrees`).
    pub mount_mismatch: bool,
    /// Another candidate at a different slope lies close behind it.
    pub close_choice: bool,
    /// Its foot is hidden behind something nearer.
    pub foot_hidden: bool,
    /// Its surface is too small to measure well ([`is_small_surface`]).
    pub small_surface: bool,
}

/// `c` lowered for how the road was chosen and what it is.
pub fn with_road_choice(mut c: Confidence, road: RoadChoice) -> Confidence {
    if road.close_choice {
        c.lower(reason::CLOSE_CHOICE, CLOSE_CHOICE_FACTOR);
    }
    if road.foot_hidden {
        c.lower(reason::FOOT_HIDDEN, FOOT_HIDDEN_FACTOR);
    }
    if road.mount_mismatch {
        c.lower(reason::MOUNT_MISMATCH, MOUNT_MISMATCH_FACTOR);
    }
    if road.small_surface {
        c.value = c.value.min(SMALL_SURFACE_CAP);
        c.reasons |= reason::SMALL_SURFACE;
    }
    c
}

fn falling(value: f64, from: f64, half_at: f64) -> f64 {
    let excess = (value - from).max(0.0);
    1.0 - 0.5 * (excess / (half_at - from)).min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(pixels: usize, relative_rms: f64, area_m2: f64, border: f64) -> ChosenPlane {
        ChosenPlane {
            pixels,
            quality: PlaneQuality {
                rms_m: 0.003,
                relative_rms,
                area_m2,
                border_fraction: border,
                noise_ratio: 1.2,
                veil_fraction: 0.0,
            },
        }
    }

    /// A plane flat within its band but `noise_ratio` sensor deviations rough.
    fn rough_at_noise_level(noise_ratio: f64) -> ChosenPlane {
        let mut p = plane(20_000, 0.15, 1.0, 0.0);
        p.quality.noise_ratio = noise_ratio;
        p
    }

    /// A ground rough at the noise level (a bent floor) is no reason; the
    /// plane the slope is measured on is.
    #[test]
    fn only_the_inclined_plane_is_judged_at_the_noise_level() {
        let good = plane(20_000, 0.15, 1.0, 0.05);
        let c = confidence(&good, Some(&rough_at_noise_level(3.3)), None);
        assert_eq!(c, Confidence::full());
        let c = confidence(&rough_at_noise_level(3.5), Some(&good), None);
        assert_eq!(c.reasons, reason::ROUGH_PLANE);
        assert!((c.value - 0.5).abs() < 1e-12, "{}", c.value);
    }

    #[test]
    fn a_good_pair_is_fully_trusted() {
        let good = plane(20_000, 0.15, 1.0, 0.05);
        let c = confidence(&good, Some(&good), Some(0.3));
        assert_eq!(c, Confidence::full());
    }

    #[test]
    fn each_reason_lowers_the_confidence_and_is_named() {
        let good = plane(20_000, 0.15, 1.0, 0.05);
        let cases = [
            (
                plane(1500, 0.15, 1.0, 0.0),
                Some(good),
                None,
                reason::FEW_POINTS,
                0.5,
            ),
            (
                plane(20_000, 0.45, 1.0, 0.0),
                Some(good),
                None,
                reason::ROUGH_PLANE,
                0.5,
            ),
            (
                plane(20_000, 0.15, 0.025, 0.0),
                Some(good),
                None,
                reason::SMALL_AREA,
                0.5,
            ),
            (
                rough_at_noise_level(3.0),
                Some(good),
                None,
                reason::ROUGH_PLANE,
                0.75,
            ),
            (good, None, None, reason::GROUND_FROM_MOUNT, 0.7),
            (
                plane(20_000, 0.15, 1.0, 0.6),
                Some(good),
                None,
                reason::NEAR_BORDER,
                0.7,
            ),
            (good, Some(good), Some(4.0), reason::METHODS_DISAGREE, 0.25),
        ];
        for (inclined, ground, diff, bit, value) in cases {
            let c = confidence(&inclined, ground.as_ref(), diff);
            assert_eq!(c.reasons, bit, "{bit}");
            assert!((c.value - value).abs() < 1e-12, "{bit}: {}", c.value);
        }
        // Reasons combine: the product of the factors.
        let c = confidence(&plane(1500, 0.15, 0.025, 0.0), None, Some(4.0));
        assert_eq!(
            c.reasons,
            reason::FEW_POINTS
                | reason::SMALL_AREA
                | reason::GROUND_FROM_MOUNT
                | reason::METHODS_DISAGREE
        );
        assert!((c.value - 0.5 * 0.5 * 0.7 * 0.25).abs() < 1e-12);
    }
}
