//! The scene description: what `slope-synth` renders, as read from a TOML
//! scene file (see the crate README for the format and an example).
//!
//! World frame: x right, y forward, z up, metres; the origin is on the
//! ground directly below the camera's optical centre in the first frame.
//! Parsing is pure (text in, [`Scene`] and [`SensorModel`] out); only
//! [`load_scene_file`] touches the disk.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::SceneError;
use crate::sensor_model::SensorModel;

mod clutter;
mod panel;
pub use clutter::{Ceiling, SoftBlock, Table};
pub use panel::Panel;

/// Everything that is in front of the camera, and the camera itself.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct Scene {
    /// `[camera]`: the depth camera's image size and intrinsics.
    pub camera: CameraModel,
    /// `[mount]`: the camera's nominal pose above the ground.
    pub mount: MountPose,
    /// `[motion]`: how the camera moves between frames.
    pub motion: Motion,
    /// `[ramp]`: the inclined plane; absent = flat ground only.
    pub ramp: Option<Ramp>,
    /// `[[walls]]`: walls parallel to the forward axis.
    pub walls: Vec<SideWall>,
    /// `[[boxes]]`: boxes standing on the ground.
    pub boxes: Vec<GroundBox>,
    /// `[[tables]]`: tables (a slab on four legs) standing on the ground.
    pub tables: Vec<Table>,
    /// `[ceiling]`: a horizontal ceiling or overhang; absent = open sky.
    pub ceiling: Option<Ceiling>,
    /// `[[soft_blocks]]`: blocks with bumpy top and sides (beds, sofas).
    pub soft_blocks: Vec<SoftBlock>,
    /// `[[panels]]`: flat boards at any tilt and heading (free-standing
    /// walls, leaning or propped-up boards).
    pub panels: Vec<Panel>,
}

/// Pinhole depth camera, pixel centres at integer coordinates (the ray
/// through pixel (u, v) is `((u - cx) / fx, (v - cy) / fy, 1)`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CameraModel {
    pub width: u32,
    pub height: u32,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

impl CameraModel {
    /// The Kinect v2 depth camera (512 x 424, about 70° x 60° field of view).
    pub const KINECT2: CameraModel = CameraModel {
        width: 512,
        height: 424,
        fx: 365.0,
        fy: 365.0,
        cx: 255.5,
        cy: 211.5,
    };
}

impl Default for CameraModel {
    fn default() -> Self {
        Self::KINECT2
    }
}

/// The camera's nominal pose, as in the recording format's `[mount]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MountPose {
    /// Optical centre above the ground, metres.
    pub height_m: f64,
    /// Rotation about the camera x axis; negative looks down.
    pub pitch_deg: f64,
    /// Rotation about the optical axis; positive dips the image's right side.
    pub roll_deg: f64,
    /// Write `[mount]` into the recording (the default). `false`: the
    /// camera still stands as above, but the recording has no `[mount]`,
    /// so an estimator reading it runs without a mount.
    pub recorded: bool,
}

impl Default for MountPose {
    fn default() -> Self {
        Self {
            height_m: 0.5,
            pitch_deg: -20.0,
            roll_deg: 0.0,
            recorded: true,
        }
    }
}

/// Straight-line motion of the camera at constant height.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct Motion {
    /// Forward speed along +y, metres per second (frames are 1/30 s apart).
    pub speed_mps: f64,
}

/// Which way the inclined plane goes, seen from the camera.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum SlopeDirection {
    /// The surface rises away from the camera (a ramp up, or a wall at 90°).
    #[default]
    Ascending,
    /// The ground drops away from the camera (a ramp down).
    Descending,
}

/// The inclined plane. Its foot line (where it meets the ground it starts
/// from) is perpendicular to its uphill/downhill direction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Ramp {
    pub direction: SlopeDirection,
    /// Angle to the ground, degrees, in (0, 90]; 90 is a wall (ascending only).
    pub slope_deg: f64,
    /// Forward distance from the camera's ground point to the foot line's
    /// centre, metres.
    pub distance_m: f64,
    /// Width across the slope, metres; `inf` for unbounded.
    pub width_m: f64,
    /// Length along the slope, metres; `inf` for unbounded. The ramp rises
    /// (or drops) `length_m * sin(slope)`.
    pub length_m: f64,
    /// Length of the flat landing after the slope, metres (0 = none). An
    /// ascending ramp ends in a vertical back face after its landing; a wall
    /// (90°) without landing gets a 0.1 m thick top.
    pub landing_m: f64,
    /// Rotation of the ramp about the vertical through the foot line's
    /// centre, degrees; positive turns the uphill direction to the left.
    pub yaw_deg: f64,
    /// Sideways offset of the foot line's centre, metres, positive right.
    pub offset_m: f64,
    /// Height of the foot line above the ground, metres (ascending only;
    /// 0 = the ramp starts on the ground). A raised ramp stands on a
    /// vertical riser of this height under its foot line (its front face),
    /// and its sides and back reach down to the ground.
    pub base_m: f64,
}

impl Default for Ramp {
    fn default() -> Self {
        Self {
            direction: SlopeDirection::Ascending,
            slope_deg: 16.0,
            distance_m: 1.5,
            width_m: 3.0,
            length_m: 3.0,
            landing_m: 1.0,
            yaw_deg: 0.0,
            offset_m: 0.0,
            base_m: 0.0,
        }
    }
}

/// A wall parallel to the forward axis, standing on the ground.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SideWall {
    /// Sideways position of the face that looks at the centre line,
    /// metres (negative = left). The wall extends away from the centre line.
    pub x_m: f64,
    /// Forward extent, metres.
    pub from_m: f64,
    pub to_m: f64,
    pub height_m: f64,
    pub thickness_m: f64,
}

impl Default for SideWall {
    fn default() -> Self {
        Self {
            x_m: -1.5,
            from_m: 0.0,
            to_m: 6.0,
            height_m: 1.0,
            thickness_m: 0.1,
        }
    }
}

/// A box standing on the ground (z = 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GroundBox {
    /// Centre of the footprint, metres (x right, y forward).
    pub x_m: f64,
    pub y_m: f64,
    /// Size along its own x (across), y (along) and z (up), metres.
    pub size_m: [f64; 3],
    /// Rotation about the vertical, degrees, positive counter-clockwise
    /// seen from above.
    pub yaw_deg: f64,
}

impl Default for GroundBox {
    fn default() -> Self {
        Self {
            x_m: 0.5,
            y_m: 1.2,
            size_m: [0.3, 0.3, 0.3],
            yaw_deg: 0.0,
        }
    }
}

/// A parsed scene file: the scene and its optional `[sensor]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneFile {
    pub scene: Scene,
    /// `None` when the file has no `[sensor]` table.
    pub sensor: Option<SensorModel>,
}

impl Scene {
    /// The default scene of the command line: a 16° ascending ramp 1.5 m
    /// ahead, camera 0.5 m high looking 20° down.
    pub fn default_ramp() -> Self {
        Self {
            ramp: Some(Ramp::default()),
            ..Self::default()
        }
    }

    /// The ground truth slope: the unsigned angle between the ramp's and
    /// the ground's normals, degrees; `None` for flat ground. Clutter
    /// (walls, boxes, tables, ceilings, soft blocks) never changes it.
    pub fn truth_slope_deg(&self) -> Option<f64> {
        self.ramp.map(|r| r.slope_deg)
    }

    /// Checks every value; the error names the key.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.camera.validate()?;
        self.mount.validate()?;
        MOTION_SPEED.check(self.motion.speed_mps)?;
        if let Some(ramp) = &self.ramp {
            ramp.validate()?;
        }
        for (i, wall) in self.walls.iter().enumerate() {
            wall.validate(i)?;
        }
        for (i, ground_box) in self.boxes.iter().enumerate() {
            ground_box.validate(i)?;
        }
        for (i, table) in self.tables.iter().enumerate() {
            table.validate(i)?;
        }
        if let Some(ceiling) = &self.ceiling {
            ceiling.validate()?;
        }
        for (i, block) in self.soft_blocks.iter().enumerate() {
            block.validate(i)?;
        }
        for (i, panel) in self.panels.iter().enumerate() {
            panel.validate(i)?;
        }
        self.check_object_count()
    }

    /// The surfaces index their object in a `u16`: fewer than 65535
    /// objects in all.
    fn check_object_count(&self) -> Result<(), SceneError> {
        let objects = self.walls.len()
            + self.boxes.len()
            + self.tables.len()
            + self.soft_blocks.len()
            + self.panels.len();
        check(
            objects < usize::from(u16::MAX),
            "boxes",
            "too many objects (walls + boxes + tables + soft_blocks + panels must be < 65535)",
        )
    }
}

impl CameraModel {
    /// `[camera]`: an image size in (0, 4096], positive focal lengths, a
    /// finite principal point.
    fn validate(&self) -> Result<(), SceneError> {
        check(
            self.width > 0 && self.height > 0,
            "camera.width",
            "image size must be > 0",
        )?;
        check(
            self.width <= 4096 && self.height <= 4096,
            "camera.width",
            "image size must be <= 4096",
        )?;
        for (key, v) in [("camera.fx", self.fx), ("camera.fy", self.fy)] {
            check(v.is_finite() && v > 0.0, key, "must be a positive number")?;
        }
        for (key, v) in [("camera.cx", self.cx), ("camera.cy", self.cy)] {
            check(v.is_finite(), key, "must be a finite number")?;
        }
        Ok(())
    }
}

impl MountPose {
    /// `[mount]`: height, pitch and roll within their rules.
    fn validate(&self) -> Result<(), SceneError> {
        MOUNT_HEIGHT.check(self.height_m)?;
        MOUNT_PITCH.check(self.pitch_deg)?;
        MOUNT_ROLL.check(self.roll_deg)
    }
}

impl Ramp {
    /// `[ramp]`: a slope in (0, 90] (below 90° descending), its distances,
    /// sizes and yaw within their rules, a finite offset.
    fn validate(&self) -> Result<(), SceneError> {
        check(
            self.slope_deg.is_finite() && self.slope_deg > 0.0 && self.slope_deg <= 90.0,
            "ramp.slope_deg",
            "must lie in (0, 90]",
        )?;
        check(
            !(self.direction == SlopeDirection::Descending && self.slope_deg >= 90.0),
            "ramp.slope_deg",
            "a descending slope must be below 90°",
        )?;
        RAMP_DISTANCE.check(self.distance_m)?;
        RAMP_WIDTH.check(self.width_m)?;
        RAMP_LENGTH.check(self.length_m)?;
        RAMP_LANDING.check(self.landing_m)?;
        RAMP_YAW.check(self.yaw_deg)?;
        check(
            self.offset_m.is_finite(),
            "ramp.offset_m",
            "must be a finite number",
        )?;
        check(
            self.base_m.is_finite() && self.base_m >= 0.0,
            "ramp.base_m",
            "must be finite and >= 0",
        )?;
        check(
            !(self.direction == SlopeDirection::Descending && self.base_m > 0.0),
            "ramp.base_m",
            "must be 0 for a descending slope (it starts on the ground the robot stands on)",
        )
    }
}

impl SideWall {
    /// `[[walls]]` number `i`: an accepted x, a finite span with `to_m`
    /// past `from_m`, a positive height and thickness.
    fn validate(&self, i: usize) -> Result<(), SceneError> {
        let key = |k: &str| format!("walls[{i}].{k}");
        check((WALL_X.accepts)(self.x_m), &key("x_m"), WALL_X.reason)?;
        check(
            self.from_m.is_finite() && self.to_m.is_finite(),
            &key("from_m"),
            "must be finite",
        )?;
        check(
            self.to_m > self.from_m,
            &key("to_m"),
            "must be greater than from_m",
        )?;
        check(
            self.height_m.is_finite() && self.height_m > 0.0,
            &key("height_m"),
            "must be > 0",
        )?;
        check(
            self.thickness_m.is_finite() && self.thickness_m > 0.0,
            &key("thickness_m"),
            "must be > 0",
        )
    }
}

impl GroundBox {
    /// `[[boxes]]` number `i`: a finite position and yaw, positive sizes.
    fn validate(&self, i: usize) -> Result<(), SceneError> {
        let key = |k: &str| format!("boxes[{i}].{k}");
        check(
            self.x_m.is_finite() && self.y_m.is_finite(),
            &key("x_m"),
            "must be finite",
        )?;
        check(
            self.size_m.iter().all(|s| s.is_finite() && *s > 0.0),
            &key("size_m"),
            "every size must be > 0",
        )?;
        check(self.yaw_deg.is_finite(), &key("yaw_deg"), "must be finite")
    }
}

/// The range of a scene value that a `slope-synth` flag can also set: one
/// rule for both, so that [`Scene::validate`] names the key (`key`) and
/// the flag's parser names the flag, with the same `reason`.
#[derive(Debug, Clone, Copy)]
pub struct ValueRule {
    /// The key in a scene file (`[walls]`: of every wall).
    pub key: &'static str,
    pub accepts: fn(f64) -> bool,
    /// What the value must be ("must lie in (-90, 90)").
    pub reason: &'static str,
}

impl ValueRule {
    /// [`SceneError::InvalidKey`] naming [`Self::key`] unless `value` is accepted.
    pub fn check(&self, value: f64) -> Result<(), SceneError> {
        check((self.accepts)(value), self.key, self.reason)
    }
}

pub const MOUNT_HEIGHT: ValueRule = ValueRule {
    key: "mount.height_m",
    accepts: |v| v.is_finite() && v > 0.0,
    reason: "must be > 0",
};
pub const MOUNT_PITCH: ValueRule = ValueRule {
    key: "mount.pitch_deg",
    accepts: |v| v.is_finite() && v.abs() < 90.0,
    reason: "must lie in (-90, 90)",
};
pub const MOUNT_ROLL: ValueRule = ValueRule {
    key: "mount.roll_deg",
    ..MOUNT_PITCH
};
pub const MOTION_SPEED: ValueRule = ValueRule {
    key: "motion.speed_mps",
    accepts: |v| v.is_finite() && v.abs() <= 10.0,
    reason: "must lie in [-10, 10]",
};
pub const RAMP_DISTANCE: ValueRule = ValueRule {
    key: "ramp.distance_m",
    accepts: |v| v.is_finite() && v > 0.0,
    reason: "must be > 0 (the foot line lies ahead of the camera)",
};
pub const RAMP_WIDTH: ValueRule = ValueRule {
    key: "ramp.width_m",
    accepts: |v| !v.is_nan() && v > 0.0,
    reason: "must be > 0 or inf",
};
pub const RAMP_LENGTH: ValueRule = ValueRule {
    key: "ramp.length_m",
    ..RAMP_WIDTH
};
pub const RAMP_LANDING: ValueRule = ValueRule {
    key: "ramp.landing_m",
    accepts: |v| v.is_finite() && v >= 0.0,
    reason: "must be >= 0",
};
pub const RAMP_YAW: ValueRule = ValueRule {
    key: "ramp.yaw_deg",
    ..MOUNT_PITCH
};
pub const WALL_X: ValueRule = ValueRule {
    key: "walls.x_m",
    accepts: |v| v.is_finite() && v != 0.0,
    reason: "must be finite and non-zero",
};

fn check(ok: bool, key: &str, reason: &str) -> Result<(), SceneError> {
    if ok {
        Ok(())
    } else {
        Err(SceneError::InvalidKey {
            key: key.to_string(),
            reason: reason.to_string(),
        })
    }
}

/// Parses the text of a scene file: the scene tables and an optional
/// `[sensor]` table. `path` is only used in errors. Unknown keys are errors
/// (a typo must not silently fall back to a default).
pub fn parse_scene(text: &str, path: &Path) -> Result<SceneFile, SceneError> {
    let mut table: toml::Table = toml::from_str(text).map_err(|source| SceneError::Toml {
        path: path.to_path_buf(),
        source,
    })?;
    let sensor = table
        .remove("sensor")
        .map(|value| {
            SensorModel::deserialize(value).map_err(|source| SceneError::Toml {
                path: path.to_path_buf(),
                source,
            })
        })
        .transpose()?;
    let scene =
        Scene::deserialize(toml::Value::Table(table)).map_err(|source| SceneError::Toml {
            path: path.to_path_buf(),
            source,
        })?;
    scene.validate().map_err(|e| e.in_file(path))?;
    if let Some(model) = &sensor {
        model.validate().map_err(|e| e.in_file(path))?;
    }
    Ok(SceneFile { scene, sensor })
}

/// Reads and parses a scene file.
pub fn load_scene_file(path: &Path) -> Result<SceneFile, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_scene(&text, path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use slope_sensor::error_chain::ErrorChain;

    #[test]
    fn full_scene_file_parses() {
        let text = r#"
            [camera]
            fx = 366.0
            [mount]
            height_m = 0.6
            pitch_deg = -25.0
            [motion]
            speed_mps = 0.3
            [ramp]
            direction = "descending"
            slope_deg = 10.0
            distance_m = 2.0
            width_m = inf
            [[walls]]
            x_m = 1.2
            [[boxes]]
            x_m = -0.4
            y_m = 1.0
            size_m = [0.2, 0.3, 0.4]
            [sensor]
            axial_noise = false
        "#;
        let file = parse_scene(text, Path::new("s.toml")).expect("valid scene");
        let s = &file.scene;
        assert_eq!(s.camera.fx, 366.0);
        assert_eq!(s.camera.fy, 365.0);
        assert_eq!(s.mount.height_m, 0.6);
        assert_eq!(s.mount.roll_deg, 0.0);
        assert_eq!(s.motion.speed_mps, 0.3);
        let ramp = s.ramp.expect("has a ramp");
        assert_eq!(ramp.direction, SlopeDirection::Descending);
        assert!(ramp.width_m.is_infinite());
        assert_eq!(ramp.length_m, Ramp::default().length_m);
        assert_eq!(s.walls[0].x_m, 1.2);
        assert_eq!(s.boxes[0].size_m, [0.2, 0.3, 0.4]);
        let sensor = file.sensor.expect("has a sensor table");
        assert!(!sensor.axial_noise);
        assert_eq!(
            sensor.lateral_noise_px,
            SensorModel::default().lateral_noise_px
        );
    }

    #[test]
    fn clutter_tables_parse_with_defaults() {
        let text = r#"
            [[tables]]
            x_m = 0.1
            y_m = 1.4
            size_m = [2.0, 1.5]
            top_m = 0.5
            [ceiling]
            height_m = 2.2
            to_m = 4.0
            [[soft_blocks]]
            size_m = [1.0, 1.8, 0.6]
            seed = 9
        "#;
        let file = parse_scene(text, Path::new("c.toml")).expect("valid scene");
        let s = &file.scene;
        assert!(s.ramp.is_none());
        assert_eq!(s.truth_slope_deg(), None);
        let t = s.tables[0];
        assert_eq!((t.x_m, t.size_m, t.top_m), (0.1, [2.0, 1.5], 0.5));
        assert_eq!(t.thickness_m, Table::default().thickness_m);
        assert_eq!(t.leg_m, Table::default().leg_m);
        let c = s.ceiling.expect("has a ceiling");
        assert_eq!((c.height_m, c.to_m), (2.2, 4.0));
        assert_eq!(c.from_m, f64::NEG_INFINITY);
        let b = s.soft_blocks[0];
        assert_eq!((b.size_m, b.seed), ([1.0, 1.8, 0.6], 9));
        assert_eq!(b.roughness_m, SoftBlock::default().roughness_m);
        // Clutter never changes the truth.
        let with_ramp = Scene {
            ramp: Some(Ramp::default()),
            ..s.clone()
        };
        assert_eq!(with_ramp.truth_slope_deg(), Some(16.0));
        let back = toml::to_string(&with_ramp).expect("serialisable");
        let back = parse_scene(&back, Path::new("rt.toml")).expect("parses back");
        assert_eq!(back.scene, with_ramp);
    }

    #[test]
    fn clutter_errors_name_file_and_key() {
        for (text, key) in [
            ("[[tables]]\ntop_m = 0.01\n", "tables[0].top_m"),
            ("[[tables]]\n[[tables]]\nleg_m = -1.0\n", "tables[1].leg_m"),
            ("[ceiling]\nheight_m = -2.0\n", "ceiling.height_m"),
            ("[ceiling]\nfrom_m = 2.0\nto_m = 1.0\n", "ceiling.to_m"),
            (
                "[[soft_blocks]]\nroughness_m = 0.2\n",
                "soft_blocks[0].roughness_m",
            ),
            (
                "[[soft_blocks]]\nwavelength_m = 0.0\n",
                "soft_blocks[0].wavelength_m",
            ),
        ] {
            let err = parse_scene(text, Path::new("k.toml")).expect_err(text);
            let message = ErrorChain(&err).to_string();
            assert!(
                message.contains(key) && message.contains("k.toml") && message.contains("must"),
                "{message}"
            );
        }
        let err = parse_scene("[[tables]]\nheight_m = 1.0\n", Path::new("k.toml"))
            .expect_err("unknown key");
        let message = ErrorChain(&err).to_string();
        assert!(message.contains("height_m"), "{message}");
    }

    #[test]
    fn empty_file_is_flat_ground() {
        let file = parse_scene("", Path::new("s.toml")).expect("valid");
        assert_eq!(file.scene, Scene::default());
        assert!(file.scene.ramp.is_none());
        assert!(file.sensor.is_none());
    }

    #[test]
    fn typo_is_an_error_naming_the_key() {
        let err =
            parse_scene("[ramp]\nslope_dg = 3.0\n", Path::new("s.toml")).expect_err("unknown key");
        let text = ErrorChain(&err).to_string();
        assert!(
            text.contains("slope_dg") && text.contains("s.toml"),
            "{text}"
        );
    }

    #[test]
    fn bad_value_names_file_and_key() {
        let err = parse_scene("[ramp]\nslope_deg = 95.0\n", Path::new("x.toml"))
            .expect_err("out of range");
        let text = err.to_string();
        assert!(
            text.contains("ramp.slope_deg") && text.contains("x.toml"),
            "{text}"
        );
        let err = parse_scene("[[walls]]\nfrom_m = 3.0\nto_m = 1.0\n", Path::new("x.toml"))
            .expect_err("empty wall");
        assert!(err.to_string().contains("walls[0].to_m"), "{err}");
        let err = parse_scene(
            "[ramp]\ndirection = \"descending\"\nslope_deg = 90.0\n",
            Path::new("x.toml"),
        )
        .expect_err("descending wall");
        assert!(err.to_string().contains("ramp.slope_deg"), "{err}");
    }

    #[test]
    fn default_scene_round_trips_through_toml() {
        let scene = Scene::default_ramp();
        let text = toml::to_string(&scene).expect("serialisable");
        let back = parse_scene(&text, Path::new("rt.toml")).expect("parses back");
        assert_eq!(back.scene, scene);
    }
}
