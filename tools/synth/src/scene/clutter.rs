//! Clutter: objects that hide or imitate the ground but are not the truth
//! (`[[tables]]`, `[ceiling]`, `[[soft_blocks]]`), and the checks of their
//! keys. The truth slope of a scene stays its ramp's angle.

use serde::{Deserialize, Serialize};

use super::check;
use crate::error::SceneError;

/// Largest bump amplitude of a soft block, metres.
pub const MAX_ROUGHNESS_M: f64 = 0.1;
/// Range of a soft block's typical bump wavelength, metres.
pub const WAVELENGTH_RANGE_M: (f64, f64) = (0.05, 2.0);

/// A table standing on the ground: a horizontal slab on four square legs
/// at its corners (the legs' outer faces flush with the slab's edges).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Table {
    /// Centre of the top, metres (x right, y forward).
    pub x_m: f64,
    pub y_m: f64,
    /// Size of the top along its own x (across) and y (along), metres.
    pub size_m: [f64; 2],
    /// Height of the top surface above the ground, metres.
    pub top_m: f64,
    /// Thickness of the top slab, metres.
    pub thickness_m: f64,
    /// Side of the square legs, metres.
    pub leg_m: f64,
    /// Rotation about the vertical, degrees, positive counter-clockwise
    /// seen from above.
    pub yaw_deg: f64,
    /// Slope of the top, degrees, in (-45, 45): the slab turned about its
    /// own across axis through the centre of its top surface, far edge up
    /// (negative: near edge up). `top_m` is then the height of the top
    /// surface's centre; the legs stay vertical and reach the underside.
    pub tilt_deg: f64,
}

impl Default for Table {
    fn default() -> Self {
        Self {
            x_m: 0.0,
            y_m: 1.5,
            size_m: [1.2, 0.8],
            top_m: 0.75,
            thickness_m: 0.04,
            leg_m: 0.05,
            yaw_deg: 0.0,
            tilt_deg: 0.0,
        }
    }
}

impl Table {
    /// Checks the keys of `[[tables]]` entry `i`; the error names the key
    /// and the allowed range.
    pub fn validate(&self, i: usize) -> Result<(), SceneError> {
        let key = |k: &str| format!("tables[{i}].{k}");
        check(
            self.x_m.is_finite() && self.y_m.is_finite(),
            &key("x_m"),
            "x_m and y_m must be finite",
        )?;
        check(
            self.size_m.iter().all(|s| s.is_finite() && *s > 0.0),
            &key("size_m"),
            "both sizes must be finite and > 0",
        )?;
        check(
            self.thickness_m.is_finite() && self.thickness_m > 0.0,
            &key("thickness_m"),
            "must be finite and > 0",
        )?;
        check(
            self.tilt_deg.is_finite() && self.tilt_deg.abs() < 45.0,
            &key("tilt_deg"),
            "must lie in (-45, 45)",
        )?;
        if self.tilt_deg == 0.0 {
            check(
                self.top_m.is_finite() && self.top_m > self.thickness_m,
                &key("top_m"),
                "must be finite and > thickness_m (the legs need a length)",
            )?;
        } else {
            check(
                self.top_m.is_finite() && self.lowest_underside_m() > 0.0,
                &key("top_m"),
                "must be finite and > thickness_m * cos(tilt) + size_m[1] / 2 * sin|tilt| \
                 (the lowest corner of the underside above the ground)",
            )?;
        }
        let narrowest = self.size_m[0].min(self.size_m[1] * self.tilt_deg.to_radians().cos());
        check(
            self.leg_m.is_finite() && self.leg_m > 0.0 && self.leg_m <= narrowest / 2.0,
            &key("leg_m"),
            "must lie in (0, min(size_m[0], size_m[1] * cos(tilt)) / 2]",
        )?;
        check(self.yaw_deg.is_finite(), &key("yaw_deg"), "must be finite")
    }

    /// Height of the lowest corner of the slab (its underside at the
    /// lower edge), metres.
    pub fn lowest_underside_m(&self) -> f64 {
        let (s, c) = self.tilt_deg.to_radians().sin_cos();
        self.top_m - self.size_m[1] / 2.0 * s.abs() - self.thickness_m * c
    }
}

/// A horizontal ceiling facing down, unbounded across; along the forward
/// axis it spans `from_m..to_m` (unbounded by default; finite ends make it
/// an overhang with vertical end faces). It is solid all the way up.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Ceiling {
    /// Height of the underside above the ground, metres.
    pub height_m: f64,
    /// Forward extent, metres; `-inf` / `inf` for unbounded.
    pub from_m: f64,
    pub to_m: f64,
}

impl Default for Ceiling {
    fn default() -> Self {
        Self {
            height_m: 2.5,
            from_m: f64::NEG_INFINITY,
            to_m: f64::INFINITY,
        }
    }
}

impl Ceiling {
    /// Checks the keys of `[ceiling]`; the error names the key and the
    /// allowed range.
    pub fn validate(&self) -> Result<(), SceneError> {
        check(
            self.height_m.is_finite() && self.height_m > 0.0,
            "ceiling.height_m",
            "must be finite and > 0",
        )?;
        check(
            !self.from_m.is_nan() && self.from_m < f64::INFINITY,
            "ceiling.from_m",
            "must be a number or -inf",
        )?;
        check(
            !self.to_m.is_nan() && self.to_m > self.from_m,
            "ceiling.to_m",
            "must be greater than from_m (inf = unbounded)",
        )
    }
}

/// A block standing on the ground whose top and sides carry smooth bumps,
/// like a bed under a fabric cover: each of those five faces is displaced
/// along its normal by a sum of three sinusoids in the face's own
/// coordinates. The bottom is flat on the ground.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SoftBlock {
    /// Centre of the footprint, metres (x right, y forward).
    pub x_m: f64,
    pub y_m: f64,
    /// Size of the undisplaced box along its own x (across), y (along)
    /// and z (up), metres.
    pub size_m: [f64; 3],
    /// Rotation about the vertical, degrees, positive counter-clockwise
    /// seen from above.
    pub yaw_deg: f64,
    /// Largest displacement of a face from the box's plane, metres (the
    /// three sinusoids' amplitudes add up to it; their RMS is about 0.43 x).
    pub roughness_m: f64,
    /// Typical bump wavelength, metres; each sinusoid's wavelength is drawn
    /// from 0.75 to 1.5 times it.
    pub wavelength_m: f64,
    /// Seeds the bump pattern (with the block's index in the list): the
    /// same scene always has the same bumps, whatever the noise seed.
    pub seed: u64,
}

impl Default for SoftBlock {
    fn default() -> Self {
        Self {
            x_m: 0.0,
            y_m: 2.0,
            size_m: [1.4, 2.0, 0.6],
            yaw_deg: 0.0,
            roughness_m: 0.03,
            wavelength_m: 0.2,
            seed: 0,
        }
    }
}

impl SoftBlock {
    /// Checks the keys of `[[soft_blocks]]` entry `i`; the error names the
    /// key and the allowed range.
    pub fn validate(&self, i: usize) -> Result<(), SceneError> {
        let key = |k: &str| format!("soft_blocks[{i}].{k}");
        check(
            self.x_m.is_finite() && self.y_m.is_finite(),
            &key("x_m"),
            "x_m and y_m must be finite",
        )?;
        check(
            self.size_m.iter().all(|s| s.is_finite() && *s > 0.0),
            &key("size_m"),
            "every size must be finite and > 0",
        )?;
        check(self.yaw_deg.is_finite(), &key("yaw_deg"), "must be finite")?;
        let (shortest, longest) = WAVELENGTH_RANGE_M;
        check(
            (shortest..=longest).contains(&self.wavelength_m),
            &key("wavelength_m"),
            "must lie in [0.05, 2]",
        )?;
        let smallest = self.size_m.iter().copied().fold(f64::INFINITY, f64::min);
        let limit = MAX_ROUGHNESS_M
            .min(self.wavelength_m / 4.0)
            .min(smallest / 4.0);
        check(
            (0.0..=limit).contains(&self.roughness_m),
            &key("roughness_m"),
            &format!("must lie in [0, min(0.1, wavelength_m / 4, min(size_m) / 4)] = [0, {limit}]"),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reason(result: Result<(), SceneError>) -> String {
        result.expect_err("invalid").to_string()
    }

    #[test]
    fn defaults_are_valid() {
        Table::default().validate(0).expect("valid table");
        Ceiling::default().validate().expect("valid ceiling");
        SoftBlock::default().validate(0).expect("valid soft block");
    }

    #[test]
    fn table_errors_name_key_and_range() {
        let text = reason(
            Table {
                top_m: 0.03,
                ..Table::default()
            }
            .validate(2),
        );
        assert!(text.contains("tables[2].top_m") && text.contains("thickness_m"));
        let text = reason(
            Table {
                leg_m: 0.5,
                ..Table::default()
            }
            .validate(0),
        );
        assert!(text.contains("tables[0].leg_m") && text.contains("(0, min(size_m[0]"));
        let text = reason(
            Table {
                size_m: [1.0, 0.0],
                ..Table::default()
            }
            .validate(0),
        );
        assert!(text.contains("tables[0].size_m"), "{text}");
    }

    #[test]
    fn tilted_table_errors_name_key_and_range() {
        let tilted = Table {
            tilt_deg: 12.0,
            ..Table::default()
        };
        tilted.validate(0).expect("a 12° top 0.75 m high is valid");
        let text = reason(
            Table {
                tilt_deg: 45.0,
                ..Table::default()
            }
            .validate(1),
        );
        assert!(text.contains("tables[1].tilt_deg") && text.contains("(-45, 45)"));
        // 0.8 m deep at 30°: the near edge drops 0.2 m, the underside 0.035 m more.
        let low = Table {
            tilt_deg: -30.0,
            top_m: 0.2,
            ..Table::default()
        };
        assert!(low.lowest_underside_m() < 0.0);
        let text = reason(low.validate(0));
        assert!(text.contains("tables[0].top_m") && text.contains("lowest corner"));
        // Legs as wide as the tilted top's horizontal depth allows.
        let text = reason(
            Table {
                tilt_deg: 40.0,
                size_m: [1.2, 0.2],
                leg_m: 0.09,
                ..Table::default()
            }
            .validate(0),
        );
        assert!(text.contains("tables[0].leg_m"), "{text}");
    }

    #[test]
    fn ceiling_errors_name_key_and_range() {
        let text = reason(
            Ceiling {
                height_m: 0.0,
                ..Ceiling::default()
            }
            .validate(),
        );
        assert!(text.contains("ceiling.height_m") && text.contains("> 0"));
        let text = reason(
            Ceiling {
                from_m: 3.0,
                to_m: 2.0,
                ..Ceiling::default()
            }
            .validate(),
        );
        assert!(text.contains("ceiling.to_m") && text.contains("from_m"));
    }

    #[test]
    fn soft_block_roughness_is_bounded_by_wavelength_and_size() {
        let ok = SoftBlock {
            roughness_m: 0.05,
            ..SoftBlock::default()
        };
        ok.validate(0).expect("0.05 <= 0.2 / 4");
        let text = reason(
            SoftBlock {
                roughness_m: 0.06,
                ..SoftBlock::default()
            }
            .validate(1),
        );
        assert!(
            text.contains("soft_blocks[1].roughness_m") && text.contains("[0, 0.05]"),
            "{text}"
        );
        let text = reason(
            SoftBlock {
                size_m: [1.0, 1.0, 0.1],
                ..SoftBlock::default()
            }
            .validate(0),
        );
        assert!(text.contains("[0, 0.025]"), "{text}");
        let text = reason(
            SoftBlock {
                wavelength_m: 3.0,
                ..SoftBlock::default()
            }
            .validate(0),
        );
        assert!(text.contains("soft_blocks[0].wavelength_m") && text.contains("[0.05, 2]"));
    }
}
