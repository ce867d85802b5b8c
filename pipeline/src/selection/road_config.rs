//! [`RoadConfig`]: what makes a surface a step, a ramp or a wall, and which
//! of them is the road ahead (`[road]` in the estimator's config).

use serde::{Deserialize, Serialize};

use crate::validate::{angle, check, non_negative, positive, InvalidValue};

/// The roles of the surfaces in view and the robot's corridor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RoadConfig {
    /// The steepest surface a robot could drive onto, degrees: an inclined
    /// surface up to this is a `ramp`, a steeper one a `wall` (wheelchair
    /// ramps are at most 5-10 degrees, rough-terrain robots climb 30-35).
    pub max_ramp_deg: f64,
    /// A level surface at most this above the ground (or above another
    /// step) is a `step`: a curb, a threshold, a stair's tread, metres (a
    /// stair's rise is at most about 0.2 m).
    pub max_step_rise_m: f64,
    /// A surface joins the one below it when its inliers come within this
    /// of that surface's plane, metres.
    pub join_tolerance_m: f64,
    /// Half the width of the robot's corridor, metres either side of the
    /// forward axis: the road is a surface that reaches into it.
    pub corridor_half_width_m: f64,
    /// How far ahead the corridor reaches, metres.
    pub look_ahead_m: f64,
    /// A second ramp or wall in the corridor at a different slope within
    /// this distance behind the road makes the choice a close call (lower
    /// confidence: `close_choice`), metres.
    pub close_choice_m: f64,
}

impl Default for RoadConfig {
    fn default() -> Self {
        Self {
            max_ramp_deg: 35.0,
            max_step_rise_m: 0.2,
            join_tolerance_m: 0.05,
            corridor_half_width_m: 0.4,
            look_ahead_m: 8.0,
            close_choice_m: 0.5,
        }
    }
}

impl RoadConfig {
    /// Checks every value's range; the error names the first bad key.
    pub fn validate(&self) -> Result<(), InvalidValue> {
        angle("max_ramp_deg", self.max_ramp_deg)?;
        check(
            self.max_ramp_deg < 90.0,
            "max_ramp_deg",
            self.max_ramp_deg,
            "must be below 90 degrees (a vertical surface is a wall)",
        )?;
        non_negative("max_step_rise_m", self.max_step_rise_m)?;
        positive("join_tolerance_m", self.join_tolerance_m)?;
        positive("corridor_half_width_m", self.corridor_half_width_m)?;
        positive("look_ahead_m", self.look_ahead_m)?;
        non_negative("close_choice_m", self.close_choice_m)
    }
}
