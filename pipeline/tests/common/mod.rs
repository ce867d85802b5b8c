//! Recordings for the pipeline's tests and examples, read and projected by
//! the programs' own reader (`slope_sensor::recording`, a dev-dependency:
//! the pipeline library itself does not depend on the sensor crate).

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use slope_ipc_types::{CloudPoint, Intrinsics, Mount};
use slope_pipeline::CloudView;
use slope_sensor::recording::Recording as Reader;

/// One opened recording.
pub struct Recording {
    reader: Reader,
    /// `[truth] slope_deg`, if given.
    pub truth_slope_deg: Option<f64>,
}

/// A projected frame.
#[derive(Debug, Clone)]
pub struct Frame {
    pub points: Vec<CloudPoint>,
    pub width: usize,
    pub height: usize,
    pub intrinsics: Intrinsics,
    pub mount: Mount,
}

impl Frame {
    pub fn view(&self) -> CloudView<'_> {
        CloudView {
            points: &self.points,
            width: self.width,
            height: self.height,
            intrinsics: self.intrinsics,
            mount: self.mount,
        }
    }
}

impl Recording {
    pub fn open(dir: &Path) -> Result<Self, String> {
        let reader = Reader::open(dir).map_err(|e| e.to_string())?;
        let truth_slope_deg = reader.meta().truth.slope_deg;
        Ok(Self {
            reader,
            truth_slope_deg,
        })
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.reader.frames().len()
    }

    /// Decodes and projects frame `k`.
    pub fn frame(&self, k: usize) -> Result<Frame, String> {
        let entry = self.reader.frames().get(k).ok_or("no such frame")?;
        let depth = self.reader.read_depth(entry).map_err(|e| e.to_string())?;
        let projector = self.reader.projector();
        let mut points = vec![CloudPoint::INVALID; projector.len()];
        projector.project_into(&depth.data, None, &mut points);
        Ok(Frame {
            points,
            width: projector.width() as usize,
            height: projector.height() as usize,
            intrinsics: projector.intrinsics(),
            mount: self.reader.mount(),
        })
    }
}

/// `pipeline/../../shared/data/<name>`, or `None` (with a note) when absent;
/// a failure instead when `SLOPE_REQUIRE_SHARED_DATA` is set (CI).
pub fn shared_data(name: &str) -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data")
        .join(name);
    if dir.join("recording.toml").is_file() {
        return Some(dir);
    }
    assert!(
        std::env::var_os("SLOPE_REQUIRE_SHARED_DATA").is_none(),
        "{} is missing and SLOPE_REQUIRE_SHARED_DATA is set",
        dir.display()
    );
    println!("note: {} is absent, skipping", dir.display());
    None
}
