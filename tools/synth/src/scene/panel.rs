//! `[[panels]]`: a flat rectangular board (a thin slab) placed anywhere, at
//! any tilt and heading: a free-standing wall (90°), a board leaning on the
//! floor (a ramp that is clutter), a propped-up board or lectern whose lower
//! edge floats above the floor. Panels are never the truth.

use serde::{Deserialize, Serialize};

use super::check;
use crate::error::SceneError;

/// A board described by its lower edge: the middle of that edge is at
/// (`x_m`, `y_m`) and `bottom_m` above the ground; the board rises from it
/// `length_m` along its slope at `tilt_deg` from horizontal, towards the
/// heading `yaw_deg`. The top surface is the one facing up the normal
/// (towards the camera for yaw 0); the slab's thickness lies behind it,
/// so a panel with `bottom_m = 0` meets the floor without a lip (its top
/// surface starts exactly at the floor and the slab's lower edge is
/// below it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Panel {
    /// Middle of the lower edge, metres (x right, y forward).
    pub x_m: f64,
    pub y_m: f64,
    /// Height of the lower edge above the ground, metres (0 = on the floor).
    pub bottom_m: f64,
    /// Along the lower edge, metres.
    pub width_m: f64,
    /// Up the slope, from the lower to the upper edge, metres.
    pub length_m: f64,
    /// Angle from horizontal, degrees, in [0, 90] (0 lies flat, 90 stands
    /// vertical: a wall).
    pub tilt_deg: f64,
    /// Heading of the uphill direction, degrees, positive turns it to the
    /// left; 0 rises straight away from the camera (as `[ramp] yaw_deg`).
    pub yaw_deg: f64,
    /// Slab thickness, metres, behind the top surface.
    pub thickness_m: f64,
}

impl Default for Panel {
    fn default() -> Self {
        Self {
            x_m: 0.0,
            y_m: 2.0,
            bottom_m: 0.0,
            width_m: 1.0,
            length_m: 1.0,
            tilt_deg: 90.0,
            yaw_deg: 0.0,
            thickness_m: 0.02,
        }
    }
}

impl Panel {
    /// Checks the keys of `[[panels]]` entry `i`; the error names the key
    /// and the allowed range.
    pub fn validate(&self, i: usize) -> Result<(), SceneError> {
        let key = |k: &str| format!("panels[{i}].{k}");
        check(
            self.x_m.is_finite() && self.y_m.is_finite(),
            &key("x_m"),
            "x_m and y_m must be finite",
        )?;
        check(
            self.bottom_m.is_finite() && self.bottom_m >= 0.0,
            &key("bottom_m"),
            "must be finite and >= 0 (0 = the lower edge stands on the floor)",
        )?;
        for (name, v) in [
            ("width_m", self.width_m),
            ("length_m", self.length_m),
            ("thickness_m", self.thickness_m),
        ] {
            check(
                v.is_finite() && v > 0.0,
                &key(name),
                "must be finite and > 0",
            )?;
        }
        check(
            (0.0..=90.0).contains(&self.tilt_deg),
            &key("tilt_deg"),
            "must lie in [0, 90] (0 lies flat, 90 stands vertical)",
        )?;
        check(self.yaw_deg.is_finite(), &key("yaw_deg"), "must be finite")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_key_is_checked_by_name() {
        Panel::default().validate(0).expect("default is valid");
        let cases: [(Panel, &str); 8] = [
            (
                Panel {
                    x_m: f64::NAN,
                    ..Panel::default()
                },
                "panels[3].x_m",
            ),
            (
                Panel {
                    y_m: f64::INFINITY,
                    ..Panel::default()
                },
                "panels[3].x_m",
            ),
            (
                Panel {
                    bottom_m: -0.1,
                    ..Panel::default()
                },
                "panels[3].bottom_m",
            ),
            (
                Panel {
                    width_m: 0.0,
                    ..Panel::default()
                },
                "panels[3].width_m",
            ),
            (
                Panel {
                    length_m: f64::INFINITY,
                    ..Panel::default()
                },
                "panels[3].length_m",
            ),
            (
                Panel {
                    thickness_m: -1.0,
                    ..Panel::default()
                },
                "panels[3].thickness_m",
            ),
            (
                Panel {
                    tilt_deg: 90.5,
                    ..Panel::default()
                },
                "panels[3].tilt_deg",
            ),
            (
                Panel {
                    yaw_deg: f64::NAN,
                    ..Panel::default()
                },
                "panels[3].yaw_deg",
            ),
        ];
        for (panel, key) in cases {
            let text = panel.validate(3).expect_err(key).to_string();
            assert!(text.contains(key) && text.contains("must"), "{key}: {text}");
        }
        let flat = Panel {
            tilt_deg: 0.0,
            ..Panel::default()
        };
        flat.validate(0).expect("tilt 0 lies flat");
    }
}
