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
