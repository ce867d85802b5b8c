//! The input checks a frame must pass before it is estimated, shared by the
//! recording reader (`recording.toml`'s `[depth]` and `[mount]`) and the
//! estimator (a cloud's header from IPC, which any process may publish):
//! the image size and point count, the pinhole intrinsics and the mount.
//!
//! Pure: values in, the first value out of its range out. The ranges are
//! wide (every real camera and every test scene lies far inside them) and
//! exist to refuse what would make the estimate a lie: a focal length of 0,
//! NaN, 5e-324 or 1e300, a principal point far outside the image, a mount
//! pitch of 1e308.

use slope_ipc_types::{CloudHeader, Intrinsics, Mount};

use crate::recording::MountRange;

/// Focal lengths a pinhole camera may have, pixels: a fisheye of a few
/// pixels' image up to a telephoto lens on a large sensor.
pub const FOCAL_RANGE_PX: (f64, f64) = (1.0, 1e5);

/// Metres per depth count a recording may have: a micrometre (none is finer)
/// up to a metre.
pub const UNIT_RANGE_M: (f64, f64) = (1e-6, 1.0);

/// How far the principal point may lie outside the image, in image sizes:
/// `cx` in `[-width, 2 width]`, `cy` in `[-height, 2 height]`.
pub const PRINCIPAL_POINT_SPAN: f64 = 1.0;

/// A value out of its range: the key (`fx`, `mount.pitch_deg`, ...), the
/// value and the rule.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{key}` = {value}: {rule}")]
pub struct OutOfRange {
    pub key: &'static str,
    pub value: f64,
    pub rule: String,
}

/// Why a cloud from IPC is not estimated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CloudCheckError {
    /// Width or height 0.
    #[error("the header says {width} x {height}: an empty image")]
    Empty { width: u32, height: u32 },
    /// More points than the subscriber accepts (`--max-points`).
    #[error(
        "the header says {width} x {height} = {points} points; the limit is {max_points} \
         (--max-points)"
    )]
    TooManyPoints {
        width: u32,
        height: u32,
        points: u64,
        max_points: usize,
    },
    /// The payload does not hold `width * height` points.
    #[error("the header says {width} x {height} but the payload holds {found} points")]
    PayloadSize {
        width: u32,
        height: u32,
        found: usize,
    },
    /// Intrinsics out of range.
    #[error("intrinsics: {0}")]
    Intrinsics(OutOfRange),
    /// A mount value out of range.
    #[error("mount: {0}")]
    Mount(OutOfRange),
}

/// `value` when it lies in `[low, high]` (finite), else why not.
fn within(key: &'static str, value: f64, (low, high): (f64, f64)) -> Result<(), OutOfRange> {
    if value.is_finite() && (low..=high).contains(&value) {
        Ok(())
    } else {
        Err(OutOfRange {
            key,
            value,
            rule: format!("must be a number from {low} to {high}"),
        })
    }
}

/// The intrinsics of a `width` x `height` image: `fx`, `fy` in
/// [`FOCAL_RANGE_PX`], the principal point within [`PRINCIPAL_POINT_SPAN`]
/// image sizes of the image.
pub fn check_intrinsics(k: &Intrinsics, width: u32, height: u32) -> Result<(), OutOfRange> {
    within("fx", k.fx, FOCAL_RANGE_PX)?;
    within("fy", k.fy, FOCAL_RANGE_PX)?;
    let span = |size: u32| {
        let size = f64::from(size);
        (
            -PRINCIPAL_POINT_SPAN * size,
            (1.0 + PRINCIPAL_POINT_SPAN) * size,
        )
    };
    within("cx", k.cx, span(width))?;
    within("cy", k.cy, span(height))
}

/// Metres per depth count in [`UNIT_RANGE_M`].
pub fn check_unit_m(unit_m: f64) -> Result<(), OutOfRange> {
    within("unit_m", unit_m, UNIT_RANGE_M)
}

/// A mount in its IPC form: each value NaN (unknown) or within its
/// [`MountRange`] (infinities and 1e308 are not).
pub fn check_mount(mount: &Mount) -> Result<(), OutOfRange> {
    for (key, value, range) in [
        ("mount.height_m", mount.height_m, MountRange::HEIGHT_M),
        ("mount.pitch_deg", mount.pitch_deg, MountRange::PITCH_DEG),
        ("mount.roll_deg", mount.roll_deg, MountRange::ROLL_DEG),
    ] {
        if !value.is_nan() {
            range
                .check(value)
                .map_err(|rule| OutOfRange { key, value, rule })?;
        }
    }
    Ok(())
}

/// Every check of a cloud received over IPC with `points` points in its
/// payload, at most `max_points` accepted.
pub fn check_cloud(
    header: &CloudHeader,
    points: usize,
    max_points: usize,
) -> Result<(), CloudCheckError> {
    let (width, height) = (header.width, header.height);
    if width == 0 || height == 0 {
        return Err(CloudCheckError::Empty { width, height });
    }
    let count = u64::from(width) * u64::from(height);
    if !usize::try_from(count).is_ok_and(|n| n <= max_points) {
        return Err(CloudCheckError::TooManyPoints {
            width,
            height,
            points: count,
            max_points,
        });
    }
    if points as u64 != count {
        return Err(CloudCheckError::PayloadSize {
            width,
            height,
            found: points,
        });
    }
    check_intrinsics(&header.intrinsics, width, height).map_err(CloudCheckError::Intrinsics)?;
    check_mount(&header.mount).map_err(CloudCheckError::Mount)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinect2() -> CloudHeader {
        CloudHeader {
            width: 512,
            height: 424,
            intrinsics: Intrinsics {
                fx: 365.3,
                fy: 365.3,
                cx: 256.3,
                cy: 208.5,
            },
            mount: Mount {
                height_m: f64::NAN,
                pitch_deg: -20.0,
                roll_deg: f64::NAN,
            },
            ..CloudHeader::default()
        }
    }

    const POINTS: usize = 512 * 424;

    #[test]
    fn a_camera_header_passes() {
        assert_eq!(check_cloud(&kinect2(), POINTS, POINTS), Ok(()));
    }

    /// The headers the probe published (fx 0, NaN, inf, 5e-324: an `ok`
    /// estimate at 16.2 degrees; pitch 1e308: used as the prior) are each
    /// refused, naming the value.
    #[test]
    fn lying_intrinsics_and_mounts_are_refused() {
        for fx in [0.0, f64::NAN, f64::INFINITY, -f64::INFINITY, 5e-324, 1e300] {
            let mut header = kinect2();
            header.intrinsics.fx = fx;
            let err = check_cloud(&header, POINTS, POINTS).expect_err("refused");
            assert!(
                matches!(&err, CloudCheckError::Intrinsics(o) if o.key == "fx"),
                "{fx}: {err}"
            );
        }
        let mut header = kinect2();
        header.intrinsics.fy = 1e-300;
        assert!(check_cloud(&header, POINTS, POINTS).is_err());
        let mut header = kinect2();
        header.intrinsics.cx = 1e300;
        assert!(check_cloud(&header, POINTS, POINTS).is_err());
        for pitch in [1e308, f64::INFINITY, 90.5] {
            let mut header = kinect2();
            header.mount.pitch_deg = pitch;
            let err = check_cloud(&header, POINTS, POINTS).expect_err("refused");
            assert!(
                matches!(&err, CloudCheckError::Mount(o) if o.key == "mount.pitch_deg"),
                "{pitch}: {err}"
            );
        }
    }

    #[test]
    fn sizes_are_checked_before_anything_else() {
        let mut header = kinect2();
        header.width = 0;
        assert!(matches!(
            check_cloud(&header, 0, POINTS),
            Err(CloudCheckError::Empty { .. })
        ));
        let mut header = kinect2();
        (header.width, header.height) = (4096, 4096);
        let err = check_cloud(&header, 4096 * 4096, POINTS).expect_err("too large");
        assert!(err.to_string().contains("16777216 points"), "{err}");
        (header.width, header.height) = (u32::MAX, u32::MAX);
        assert!(matches!(
            check_cloud(&header, 0, usize::MAX),
            Err(CloudCheckError::TooManyPoints { .. } | CloudCheckError::PayloadSize { .. })
        ));
        assert!(matches!(
            check_cloud(&kinect2(), POINTS - 1, POINTS),
            Err(CloudCheckError::PayloadSize { found, .. }) if found == POINTS - 1
        ));
    }

    #[test]
    fn the_unit_of_a_recording_is_a_plausible_length() {
        assert_eq!(check_unit_m(0.001), Ok(()));
        assert_eq!(check_unit_m(0.0002), Ok(()));
        for unit in [0.0, -0.001, 1e300, 1e-300, f64::NAN] {
            assert!(check_unit_m(unit).is_err(), "{unit}");
        }
    }
}
