//! Why an estimate's confidence is low: bits of `SlopeEstimate`'s
//! `confidence_reasons`, one per reason (several may be set).

use std::borrow::Cow;

/// A chosen plane has few pixels (under 3000 for the inclined plane).
pub const FEW_POINTS: u32 = 1 << 0;
/// A chosen plane is rough: its inliers fill much of the RANSAC threshold
/// band (relative RMS above 0.3), or the inclined plane is rougher than the
/// sensor's noise explains (more than 2.5 standard deviations RMS).
pub const ROUGH_PLANE: u32 = 1 << 1;
/// The inclined plane covers little surface (under 0.05 square metres).
pub const SMALL_AREA: u32 = 1 << 2;
/// No ground plane was seen; the mount's plane stands in for it.
pub const GROUND_FROM_MOUNT: u32 = 1 << 3;
/// A chosen plane lies largely along the image border (partly out of view).
pub const NEAR_BORDER: u32 = 1 << 4;
/// The paper method and a TLS fit of the same planes disagree.
pub const METHODS_DISAGREE: u32 = 1 << 5;

/// The road was a close call: another ramp or wall in the robot's corridor
/// lies within a short distance of the one measured.
pub const CLOSE_CHOICE: u32 = 1 << 6;

/// The road's foot is hidden behind something nearer (a box before a
/// ramp): it may stand on the ground out of sight, or not.
pub const FOOT_HIDDEN: u32 = 1 << 7;

/// The road's surface is too small to measure its slope well (narrower than
/// 0.2 m across the corridor, under 1,500 pixels or under 0.03 square
/// metres: a post, a table leg): its role and distance hold, its slope is a
/// guess (confidence at most 0.3).
pub const SMALL_SURFACE: u32 = 1 << 8;

/// The floor the camera sees disagrees with the configured mount (tilted
/// beyond the parallel tolerance, or off the mount's height): the robot may
/// stand tilted, or the mount's figures are wrong.
pub const MOUNT_MISMATCH: u32 = 1 << 9;

/// Every reason with its name, in bit order.
pub const ALL: [(u32, &str); 10] = [
    (FEW_POINTS, "few_points"),
    (ROUGH_PLANE, "rough_plane"),
    (SMALL_AREA, "small_area"),
    (GROUND_FROM_MOUNT, "ground_from_mount"),
    (NEAR_BORDER, "near_border"),
    (METHODS_DISAGREE, "methods_disagree"),
    (CLOSE_CHOICE, "close_choice"),
    (FOOT_HIDDEN, "foot_hidden"),
    (SMALL_SURFACE, "small_surface"),
    (MOUNT_MISMATCH, "mount_mismatch"),
];

/// The names of the reasons set in `bits`, in bit order; a bit this build
/// does not know (set by a newer estimator) is named `bit_N`, never dropped.
pub fn names(bits: u32) -> impl Iterator<Item = Cow<'static, str>> {
    let known = ALL.iter().fold(0, |acc, (bit, _)| acc | bit);
    let named = ALL
        .into_iter()
        .filter(move |(bit, _)| bits & bit != 0)
        .map(|(_, name)| Cow::Borrowed(name));
    let unknown = (0..u32::BITS)
        .filter(move |n| (bits & !known) & (1 << n) != 0)
        .map(|n| Cow::Owned(format!("bit_{n}")));
    named.chain(unknown)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_are_distinct_and_named() {
        let all = ALL.iter().fold(0, |acc, (bit, _)| {
            assert_eq!(acc & bit, 0);
            acc | bit
        });
        assert_eq!(all, 0b11_1111_1111);
        let names: Vec<_> = names(FEW_POINTS | GROUND_FROM_MOUNT).collect();
        assert_eq!(names, ["few_points", "ground_from_mount"]);
        assert_eq!(super::names(0).count(), 0);
        let names: Vec<_> = super::names(ROUGH_PLANE | 1 << 10 | 1 << 31).collect();
        assert_eq!(names, ["rough_plane", "bit_10", "bit_31"]);
    }
}
