//! `recording.toml`: the metadata types, parsing (text in, [`RecordingMeta`]
//! out) and formatting. Pure: no file I/O here.

use std::path::Path;

use serde::{Deserialize, Serialize};
use slope_ipc_types::{Intrinsics, Mount};
use toml::{Table, Value};

use super::RecordingError;
use crate::cloud_checks::{check_intrinsics, check_unit_m};

/// The value of `format` every recording carries.
pub const FORMAT_NAME: &str = "slope-recording";
/// The one `version` this crate reads and writes.
pub const FORMAT_VERSION: i64 = 1;

/// Everything `recording.toml` says (besides `format` and `version`).
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingMeta {
    /// Free text: "kinect2", "synthetic", "tum", ...; empty when absent.
    pub sensor: String,
    pub depth: DepthInfo,
    pub mount: MountInfo,
    pub truth: TruthInfo,
}

/// `[depth]`: image size, depth unit and pinhole intrinsics (pixel centres
/// at integer coordinates).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DepthInfo {
    pub width: u32,
    pub height: u32,
    /// Metres per depth count.
    pub unit_m: f64,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

impl DepthInfo {
    pub fn intrinsics(&self) -> Intrinsics {
        Intrinsics {
            fx: self.fx,
            fy: self.fy,
            cx: self.cx,
            cy: self.cy,
        }
    }
}

/// `[mount]`: the camera's pose on the robot; each key optional (also the
/// `[mount]` of the daemons' configuration file, which serde reads).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MountInfo {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pitch_deg: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub roll_deg: Option<f64>,
}

/// The plausible range of a mount value (a recording's `[mount]`, the
/// daemons' `[mount]`, the `--mount-*` flags).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MountRange {
    /// What the value is, for messages: "the mount pitch (degrees)".
    pub what: &'static str,
    pub low: f64,
    pub high: f64,
    /// True when `low` itself is out of range.
    pub low_excluded: bool,
}

impl MountRange {
    /// The optical centre's height above the ground, metres: (0, 10].
    pub const HEIGHT_M: Self = Self {
        what: "the mount height (m)",
        low: 0.0,
        high: 10.0,
        low_excluded: true,
    };
    /// Pitch, degrees: [-90, 90] (a camera turned further is rolled by 180).
    pub const PITCH_DEG: Self = Self {
        what: "the mount pitch (degrees)",
        low: -90.0,
        high: 90.0,
        low_excluded: false,
    };
    /// Roll, degrees: [-180, 180].
    pub const ROLL_DEG: Self = Self {
        what: "the mount roll (degrees)",
        low: -180.0,
        high: 180.0,
        low_excluded: false,
    };

    /// `value` when finite and in range, else why not.
    pub fn check(&self, value: f64) -> Result<f64, String> {
        let above = if self.low_excluded {
            value > self.low
        } else {
            value >= self.low
        };
        if value.is_finite() && above && value <= self.high {
            Ok(value)
        } else {
            let lower = if self.low_excluded {
                "above"
            } else {
                "at least"
            };
            Err(format!(
                "{} must be {lower} {} and at most {}, not {value}",
                self.what, self.low, self.high
            ))
        }
    }
}

impl MountInfo {
    /// Checks every key given against its [`MountRange`] (a key left out
    /// is unknown; `nan` is not a way to say so). The error is the first bad
    /// key (`height_m`, `pitch_deg` or `roll_deg`), its value and the reason.
    pub fn check(&self) -> Result<(), (&'static str, f64, String)> {
        for (key, value, range) in [
            ("height_m", self.height_m, MountRange::HEIGHT_M),
            ("pitch_deg", self.pitch_deg, MountRange::PITCH_DEG),
            ("roll_deg", self.roll_deg, MountRange::ROLL_DEG),
        ] {
            if let Some(value) = value {
                range.check(value).map_err(|reason| (key, value, reason))?;
            }
        }
        Ok(())
    }

    /// The IPC form: NaN for every unknown key.
    pub fn to_mount(&self) -> Mount {
        Mount {
            height_m: self.height_m.unwrap_or(f64::NAN),
            pitch_deg: self.pitch_deg.unwrap_or(f64::NAN),
            roll_deg: self.roll_deg.unwrap_or(f64::NAN),
        }
    }

    fn is_empty(&self) -> bool {
        self.height_m.is_none() && self.pitch_deg.is_none() && self.roll_deg.is_none()
    }
}

/// `[truth]`: ground truth for evaluation.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct TruthInfo {
    /// Unsigned angle between the inclined plane and the ground plane,
    /// degrees, in [0, 90] (0 = no slope).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slope_deg: Option<f64>,
}

impl TruthInfo {
    fn is_empty(&self) -> bool {
        self.slope_deg.is_none()
    }
}

/// Parses the text of `recording.toml`; `path` is only used in errors.
/// Unknown keys are ignored.
pub(crate) fn parse_meta(text: &str, path: &Path) -> Result<RecordingMeta, RecordingError> {
    let root: Table = toml::from_str(text).map_err(|err| RecordingError::toml(path, text, &err))?;
    let keys = Keys { path };

    match root.get("format") {
        None => return Err(keys.missing("format")),
        Some(Value::String(found)) if found == FORMAT_NAME => {}
        Some(Value::String(found)) => {
            return Err(RecordingError::WrongFormat {
                path: path.to_path_buf(),
                found: found.clone(),
            })
        }
        Some(other) => return Err(keys.invalid("format", wrong_type("a string", other))),
    }
    match root.get("version") {
        None => return Err(keys.missing("version")),
        Some(Value::Integer(FORMAT_VERSION)) => {}
        Some(Value::Integer(found)) => {
            return Err(RecordingError::UnknownVersion {
                path: path.to_path_buf(),
                found: *found,
            })
        }
        Some(other) => return Err(keys.invalid("version", wrong_type("an integer", other))),
    }
    let sensor = match root.get("sensor") {
        None => String::new(),
        Some(Value::String(s)) => s.clone(),
        Some(other) => return Err(keys.invalid("sensor", wrong_type("a string", other))),
    };

    let depth = keys
        .table(&root, "depth")?
        .ok_or_else(|| keys.missing("depth"))?;
    let depth = DepthInfo {
        width: keys.required_size(depth, "depth", "width")?,
        height: keys.required_size(depth, "depth", "height")?,
        unit_m: keys.required_float(depth, "depth", "unit_m")?,
        fx: keys.required_float(depth, "depth", "fx")?,
        fy: keys.required_float(depth, "depth", "fy")?,
        cx: keys.required_float(depth, "depth", "cx")?,
        cy: keys.required_float(depth, "depth", "cy")?,
    };

    let mount = match keys.table(&root, "mount")? {
        None => MountInfo::default(),
        Some(mount) => MountInfo {
            height_m: keys.float(mount, "mount", "height_m")?,
            pitch_deg: keys.float(mount, "mount", "pitch_deg")?,
            roll_deg: keys.float(mount, "mount", "roll_deg")?,
        },
    };
    let truth = match keys.table(&root, "truth")? {
        None => TruthInfo::default(),
        Some(truth) => TruthInfo {
            slope_deg: keys.float(truth, "truth", "slope_deg")?,
        },
    };

    let meta = RecordingMeta {
        sensor,
        depth,
        mount,
        truth,
    };
    validate_meta(&meta, path)?;
    Ok(meta)
}

/// Checks the values a reader would reject: zero size, non-positive or
/// non-finite `unit_m`/`fx`/`fy`, non-finite `cx`/`cy` or mount values, a
/// truth outside [0, 90] degrees; then the ranges a cloud from IPC is held
/// to as well (`cloud_checks.rs`: a unit of 1e300 m, a focal length of
/// 1e-300 px, a principal point far outside the image).
pub(crate) fn validate_meta(meta: &RecordingMeta, path: &Path) -> Result<(), RecordingError> {
    let keys = Keys { path };
    let d = &meta.depth;
    for (key, value) in [("depth.width", d.width), ("depth.height", d.height)] {
        if value == 0 {
            return Err(keys.invalid(key, "must be a positive integer, found 0".into()));
        }
    }
    for (key, value) in [
        ("depth.unit_m", d.unit_m),
        ("depth.fx", d.fx),
        ("depth.fy", d.fy),
    ] {
        if !(value.is_finite() && value > 0.0) {
            return Err(keys.invalid(key, format!("must be a positive number, found {value}")));
        }
    }
    for (key, value) in [("depth.cx", d.cx), ("depth.cy", d.cy)] {
        if !value.is_finite() {
            return Err(keys.invalid(key, format!("must be a finite number, found {value}")));
        }
    }
    check_unit_m(d.unit_m)
        .and_then(|()| check_intrinsics(&d.intrinsics(), d.width, d.height))
        .map_err(|o| keys.invalid(&format!("depth.{}", o.key), o.rule))?;
    if let Err((key, _, reason)) = meta.mount.check() {
        return Err(keys.invalid(&format!("mount.{key}"), reason));
    }
    if let Some(slope) = meta.truth.slope_deg {
        check_truth_deg(slope).map_err(|reason| keys.invalid("truth.slope_deg", reason))?;
    }
    Ok(())
}

/// A ground-truth slope must lie in [0, 90] degrees (the spec's unsigned
/// angle between two planes' normals; 0 for flat ground).
pub(crate) fn check_truth_deg(slope_deg: f64) -> Result<(), String> {
    if (0.0..=90.0).contains(&slope_deg) {
        Ok(())
    } else {
        Err(format!(
            "a slope must lie in [0, 90] degrees, found {slope_deg}"
        ))
    }
}

/// The text of `recording.toml` for `meta`. Deterministic, and floats are
/// written so that they parse back to the same bits.
pub(crate) fn format_meta(meta: &RecordingMeta) -> Result<String, toml::ser::Error> {
    #[derive(Serialize)]
    struct File<'a> {
        format: &'static str,
        version: i64,
        sensor: &'a str,
        depth: &'a DepthInfo,
        #[serde(skip_serializing_if = "MountInfo::is_empty")]
        mount: &'a MountInfo,
        #[serde(skip_serializing_if = "TruthInfo::is_empty")]
        truth: &'a TruthInfo,
    }
    toml::to_string(&File {
        format: FORMAT_NAME,
        version: FORMAT_VERSION,
        sensor: &meta.sensor,
        depth: &meta.depth,
        mount: &meta.mount,
        truth: &meta.truth,
    })
}

/// Key look-ups that name the file and the dotted key in their errors.
struct Keys<'p> {
    path: &'p Path,
}

impl Keys<'_> {
    fn missing(&self, key: &str) -> RecordingError {
        RecordingError::MissingKey {
            path: self.path.to_path_buf(),
            key: key.to_string(),
        }
    }

    fn invalid(&self, key: &str, reason: String) -> RecordingError {
        RecordingError::InvalidKey {
            path: self.path.to_path_buf(),
            key: key.to_string(),
            reason,
        }
    }

    fn table<'t>(&self, root: &'t Table, key: &str) -> Result<Option<&'t Table>, RecordingError> {
        match root.get(key) {
            None => Ok(None),
            Some(Value::Table(table)) => Ok(Some(table)),
            Some(other) => Err(self.invalid(key, wrong_type("a table", other))),
        }
    }

    fn float(
        &self,
        table: &Table,
        section: &str,
        key: &str,
    ) -> Result<Option<f64>, RecordingError> {
        match table.get(key) {
            None => Ok(None),
            Some(Value::Float(v)) => Ok(Some(*v)),
            // Integers are exact in f64 up to 2^53; every plausible value is far below.
            Some(Value::Integer(v)) => Ok(Some(*v as f64)),
            Some(other) => {
                Err(self.invalid(&format!("{section}.{key}"), wrong_type("a number", other)))
            }
        }
    }

    fn required_float(
        &self,
        table: &Table,
        section: &str,
        key: &str,
    ) -> Result<f64, RecordingError> {
        self.float(table, section, key)?
            .ok_or_else(|| self.missing(&format!("{section}.{key}")))
    }

    fn required_size(
        &self,
        table: &Table,
        section: &str,
        key: &str,
    ) -> Result<u32, RecordingError> {
        let dotted = format!("{section}.{key}");
        match table.get(key) {
            None => Err(self.missing(&dotted)),
            Some(Value::Integer(v)) => u32::try_from(*v).map_err(|_| {
                self.invalid(&dotted, format!("must be a positive integer, found {v}"))
            }),
            Some(other) => Err(self.invalid(&dotted, wrong_type("an integer", other))),
        }
    }
}

fn wrong_type(expected: &str, found: &Value) -> String {
    format!("expected {expected}, found {} `{found}`", found.type_str())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> RecordingMeta {
        RecordingMeta {
            sensor: "synthetic".into(),
            depth: DepthInfo {
                width: 512,
                height: 424,
                unit_m: 0.001,
                fx: 365.32,
                fy: 365.1 + 0.2,
                cx: 254.69,
                cy: 0.1 + 0.2,
            },
            mount: MountInfo {
                height_m: Some(0.5),
                pitch_deg: Some(-20.0),
                roll_deg: None,
            },
            truth: TruthInfo {
                slope_deg: Some(16.0),
            },
        }
    }

    #[test]
    fn formatted_meta_parses_back_to_the_same_bits() {
        let path = Path::new("recording.toml");
        let mut meta = sample();
        for tricky in [1e-300, 5e-324, 1023.9999999999, 1.0 / 3.0] {
            meta.depth.cx = tricky;
            let text = format_meta(&meta).unwrap();
            let back = parse_meta(&text, path).unwrap();
            assert_eq!(back, meta, "{text}");
            assert_eq!(back.depth.cx.to_bits(), tricky.to_bits());
        }
    }

    #[test]
    fn formatting_is_the_spec_layout() {
        let text = format_meta(&sample()).unwrap();
        let expected = "format = \"slope-recording\"\nversion = 1\nsensor = \"synthetic\"\n\n\
                        [depth]\nwidth = 512\nheight = 424\nunit_m = 0.001\nfx = 365.32\n\
                        fy = 365.3\ncx = 254.69\ncy = 0.30000000000000004\n\n\
                        [mount]\nheight_m = 0.5\npitch_deg = -20.0\n\n\
                        [truth]\nslope_deg = 16.0\n";
        assert_eq!(text, expected);
    }

    #[test]
    fn empty_mount_and_truth_are_left_out() {
        let mut meta = sample();
        meta.mount = MountInfo::default();
        meta.truth = TruthInfo::default();
        let text = format_meta(&meta).unwrap();
        assert!(
            !text.contains("[mount]") && !text.contains("[truth]"),
            "{text}"
        );
        assert_eq!(parse_meta(&text, Path::new("r.toml")).unwrap(), meta);
    }

    #[test]
    fn integers_are_accepted_where_floats_are_expected() {
        let text = "format = \"slope-recording\"\nversion = 1\n[depth]\nwidth = 4\nheight = 3\n\
                    unit_m = 1\nfx = 365\nfy = 366\ncx = 2\ncy = 1\n[mount]\npitch_deg = -20\n";
        let meta = parse_meta(text, Path::new("r.toml")).unwrap();
        assert_eq!(meta.sensor, "");
        assert_eq!(meta.depth.fx, 365.0);
        assert_eq!(meta.depth.unit_m, 1.0);
        assert_eq!(meta.mount.pitch_deg, Some(-20.0));
        assert_eq!(meta.mount.height_m, None);
        let mount = meta.mount.to_mount();
        assert!(mount.height_m.is_nan() && mount.roll_deg.is_nan());
        assert_eq!(mount.pitch_deg, -20.0);
    }

    /// A broken file is one line (no cause, no snippet): the file, where,
    /// and the parser's message.
    #[test]
    fn invalid_toml_is_one_line_naming_file_line_and_column() {
        let text = "format = \"slope-recording\"\nversion = 1\n[depth\nfx = 1.0\n";
        let err = parse_meta(text, Path::new("rec/recording.toml")).unwrap_err();
        assert!(
            matches!(
                err,
                RecordingError::Toml {
                    at: Some((3, _)),
                    ..
                }
            ),
            "{err:?}"
        );
        let message = err.to_string();
        assert!(!message.contains('\n'), "{message:?}");
        assert!(
            message.starts_with("rec/recording.toml line 3, column "),
            "{message}"
        );
        assert!(message.contains("is not valid TOML: "), "{message}");
        assert!(std::error::Error::source(&err).is_none());
        let err = parse_meta("version = 1\n  bad key = 2\n", Path::new("r.toml")).unwrap_err();
        let message = err.to_string();
        assert!(message.starts_with("r.toml line 2, column 7"), "{message}");
        assert!(!message.contains('\n'), "{message:?}");
    }

    /// Finite but absurd values (every frame came out `too_few_points`,
    /// exit 0, no word why) are refused naming the key and the range.
    #[test]
    fn absurd_finite_depth_values_are_refused_by_key() {
        type Spoil = fn(&mut DepthInfo);
        let cases: [(Spoil, &str); 5] = [
            (|d| d.unit_m = 1e300, "depth.unit_m"),
            (|d| d.unit_m = 1e-300, "depth.unit_m"),
            (|d| d.cx = 1e300, "depth.cx"),
            (|d| d.fy = 1e-300, "depth.fy"),
            (|d| d.cy = -1e6, "depth.cy"),
        ];
        for (spoil, expected) in cases {
            let mut meta = sample();
            spoil(&mut meta.depth);
            let err = validate_meta(&meta, Path::new("r.toml")).unwrap_err();
            assert!(
                matches!(&err, RecordingError::InvalidKey { key, reason, .. }
                    if key == expected && reason.contains("must be a number from")),
                "{expected}: {err}"
            );
        }
        validate_meta(&sample(), Path::new("r.toml")).unwrap();
    }

    #[test]
    fn truth_outside_zero_to_ninety_is_rejected() {
        for bad in [-1.0, 90.5, f64::NAN] {
            let mut meta = sample();
            meta.truth.slope_deg = Some(bad);
            let err = validate_meta(&meta, Path::new("r.toml")).unwrap_err();
            assert!(
                matches!(&err, RecordingError::InvalidKey { key, .. } if key == "truth.slope_deg"),
                "{err}"
            );
        }
        for good in [0.0, 16.0, 90.0] {
            let mut meta = sample();
            meta.truth.slope_deg = Some(good);
            validate_meta(&meta, Path::new("r.toml")).unwrap();
        }
    }

    /// A recording's `[mount]` out of range (a typing error) is refused by
    /// key, as the daemons' `[mount]` and the flags are (it was read and
    /// spoiled every estimate).
    #[test]
    fn a_recording_mount_out_of_range_is_refused_by_key() {
        let text = "format = \"slope-recording\"\nversion = 1\n[depth]\nwidth = 4\nheight = 3\n\
                    unit_m = 1\nfx = 365\nfy = 366\ncx = 2\ncy = 1\n[mount]\npitch_deg = 500\n";
        let err = parse_meta(text, Path::new("r.toml")).unwrap_err();
        assert!(
            matches!(&err, RecordingError::InvalidKey { key, reason, .. }
                if key == "mount.pitch_deg" && reason.contains("at most 90, not 500")),
            "{err}"
        );
    }

    #[test]
    fn a_mount_out_of_range_or_nan_is_refused() {
        assert_eq!(MountInfo::default().check(), Ok(()));
        let good = MountInfo {
            height_m: Some(0.4),
            pitch_deg: Some(-90.0),
            roll_deg: Some(180.0),
        };
        assert_eq!(good.check(), Ok(()));
        for (mount, key) in [
            (
                MountInfo {
                    height_m: Some(-1.0),
                    ..MountInfo::default()
                },
                "height_m",
            ),
            (
                MountInfo {
                    height_m: Some(f64::NAN),
                    ..MountInfo::default()
                },
                "height_m",
            ),
            (
                MountInfo {
                    height_m: Some(0.4),
                    pitch_deg: Some(f64::NAN),
                    ..MountInfo::default()
                },
                "pitch_deg",
            ),
            (
                MountInfo {
                    roll_deg: Some(f64::INFINITY),
                    ..MountInfo::default()
                },
                "roll_deg",
            ),
        ] {
            let (bad, _, reason) = mount.check().expect_err("refused");
            assert_eq!(bad, key, "{mount:?}");
            assert!(reason.contains("must be"), "{reason}");
        }
    }
}
