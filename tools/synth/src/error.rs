//! Errors: one enum per operation (loading a scene, writing a recording).

use std::io;
use std::path::{Path, PathBuf};

use slope_sensor::recording::RecordingError;

/// Why a scene (or sensor model) could not be loaded or is invalid.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("cannot read scene file {}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: io::Error,
    },

    /// The scene file is not valid TOML or does not match the scene format.
    #[error("{} is not a valid scene file", path.display())]
    Toml {
        path: PathBuf,
        #[source]
        source: toml::de::Error,
    },

    /// A key has an impossible value.
    #[error("scene key `{key}`: {reason}")]
    InvalidKey { key: String, reason: String },

    /// A key of a scene file has an impossible value.
    #[error("{}: key `{key}`: {reason}", path.display())]
    InvalidKeyInFile {
        path: PathBuf,
        key: String,
        reason: String,
    },
}

impl SceneError {
    /// Attaches the file an [`SceneError::InvalidKey`] came from.
    pub fn in_file(self, path: &Path) -> Self {
        match self {
            Self::InvalidKey { key, reason } => Self::InvalidKeyInFile {
                path: path.to_path_buf(),
                key,
                reason,
            },
            other => other,
        }
    }
}

/// Why a recording could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The scene or the sensor model is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),

    /// At least one frame is asked for.
    #[error("the number of frames must be at least 1")]
    NoFrames,

    /// The camera's path runs into a solid (forward motion into the ramp).
    #[error(
        "frame {frame}: the camera at y = {y_m:.3} m is inside the scene's geometry \
         (lower motion.speed_mps or the number of frames)"
    )]
    CameraInsideGeometry { frame: u64, y_m: f64 },

    /// The recording writer failed (directory not empty, disk full, ...).
    #[error("writing recording {}", dir.display())]
    Recording {
        dir: PathBuf,
        #[source]
        source: RecordingError,
    },
}

/// Why a real frame's floor could not be bent into a ramp
/// ([`crate::bend::bend_floor`], `slope-bend`).
#[derive(Debug, thiserror::Error)]
pub enum BendError {
    /// A bend parameter is out of range.
    #[error("{name} = {value}: {reason}")]
    InvalidParameter {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },

    /// The source recording could not be read.
    #[error("reading recording {}", dir.display())]
    Read {
        dir: PathBuf,
        #[source]
        source: RecordingError,
    },

    /// The recording has no frame of that number.
    #[error("{}: no frame {frame} (the recording has {frames})", dir.display())]
    NoSuchFrame {
        dir: PathBuf,
        frame: usize,
        frames: usize,
    },

    /// The frame's images disagree with its `[depth]` size.
    #[error("{origin}: {reason}")]
    BadFrame { origin: String, reason: String },

    /// No floor plane was found (too few up-facing points in the lower image,
    /// or none that RANSAC could gather into a plane below the camera).
    #[error("{origin}: no floor found: {reason}")]
    NoFloor { origin: String, reason: String },

    /// A floor was found, but it does not reach past the hinge line.
    #[error(
        "{origin}: the floor does not reach past the hinge at {hinge_m} m: {beyond} floor points \
         beyond it (at least {needed} needed), the floor reaches {reach_m:.2} m ahead; \
         give a smaller --hinge-m"
    )]
    FloorShort {
        origin: String,
        hinge_m: f64,
        reach_m: f64,
        beyond: usize,
        needed: usize,
    },

    /// The floor is first seen beyond the hinge line: none of it would stay
    /// as the ground in front of the ramp.
    #[error(
        "{origin}: no floor before the hinge at {hinge_m} m: {before} floor points before it \
         (at least {needed} needed), the floor is first seen {from_m:.2} m ahead; \
         give a larger --hinge-m"
    )]
    NoGroundBeforeHinge {
        origin: String,
        hinge_m: f64,
        from_m: f64,
        before: usize,
        needed: usize,
    },

    /// The camera looks straight down the floor's normal: no forward direction.
    #[error("{origin}: the camera looks along the floor's normal; no forward direction to put a hinge across")]
    NoForward { origin: String },

    /// The bent recording could not be written.
    #[error("writing recording {}", dir.display())]
    Write {
        dir: PathBuf,
        #[source]
        source: RecordingError,
    },
}
