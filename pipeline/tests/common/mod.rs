//! Recordings for the pipeline's tests and examples, read and projected by
//! the programs' own reader (`slope_sensor::recording`, a dev-dependency:
//! the pipeline library itself does not depend on the sensor crate).

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use slope_ipc_types::{CloudPoint, Intrinsics, Mount};
use slope_pipeline::CloudView;
use slope_sensor::projection::Projector;
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
    /// The recording's `sensor` ("synthetic" for a simulated cloud).
    pub sensor: String,
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

    /// The recording's `sensor`.
    pub fn sensor(&self) -> &str {
        &self.reader.meta().sensor
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.reader.frames().len()
    }

    /// Decodes and projects frame `k`.
    pub fn frame(&self, k: usize) -> Result<Frame, String> {
        self.frame_as(k, View::AsRecorded)
    }

    /// Decodes frame `k`, mirrors it left-right when asked, and projects it.
    pub fn frame_as(&self, k: usize, view: View) -> Result<Frame, String> {
        let entry = self.reader.frames().get(k).ok_or("no such frame")?;
        let mut depth = self
            .reader
            .read_depth(entry)
            .map_err(|e| e.to_string())?
            .data;
        let projector = self.reader.projector();
        let mut mount = self.reader.mount();
        let projector = match view {
            View::AsRecorded => projector,
            View::Mirrored => {
                let (w, h) = (projector.width(), projector.height());
                mount = mirror_mount(mount);
                mirror_rows(&mut depth, w as usize);
                let mut intrinsics = projector.intrinsics();
                intrinsics.cx = f64::from(w) - 1.0 - intrinsics.cx;
                Projector::new(w, h, intrinsics, projector.unit_m())
            }
        };
        let mut points = vec![CloudPoint::INVALID; projector.len()];
        projector.project_into(&depth, None, &mut points);
        Ok(Frame {
            points,
            width: projector.width() as usize,
            height: projector.height() as usize,
            intrinsics: projector.intrinsics(),
            mount,
            sensor: self.sensor().to_owned(),
        })
    }
}

/// A frame as recorded or as its left-right mirror image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    AsRecorded,
    /// Rows reversed, `cx -> W - 1 - cx`, roll negated (the recording
    /// format's rule for data kept in libfreenect2's pixel order).
    Mirrored,
}

impl View {
    pub const BOTH: [View; 2] = [View::AsRecorded, View::Mirrored];

    pub fn name(self) -> &'static str {
        match self {
            View::AsRecorded => "as recorded",
            View::Mirrored => "mirrored",
        }
    }
}

/// Reverses every row of a row-major image `width` wide.
pub fn mirror_rows<T>(image: &mut [T], width: usize) {
    for row in image.chunks_exact_mut(width) {
        row.reverse();
    }
}

/// The mount of the mirror image: the roll changes sign.
pub fn mirror_mount(mount: Mount) -> Mount {
    Mount {
        roll_deg: -mount.roll_deg,
        ..mount
    }
}

/// `../shared/data/<name>`, or `None` (with a note) when absent; a failure
/// instead in CI ([`slope_test_support::shared_data`]).
pub fn shared_data(name: &str) -> Option<PathBuf> {
    slope_test_support::shared_data(name)
}

/// The left-right mirror image of an organised cloud: rows reversed, x
/// negated, `cx -> W - 1 - cx`, roll negated. The same as mirroring the depth
/// image and projecting it ([`Recording::frame_as`]).
pub fn mirror_cloud(
    points: &[CloudPoint],
    width: usize,
    intrinsics: Intrinsics,
    mount: Mount,
) -> (Vec<CloudPoint>, Intrinsics, Mount) {
    let mut mirrored: Vec<CloudPoint> = points
        .iter()
        .map(|p| CloudPoint { x_m: -p.x_m, ..*p })
        .collect();
    mirror_rows(&mut mirrored, width);
    let intrinsics = Intrinsics {
        cx: width as f64 - 1.0 - intrinsics.cx,
        ..intrinsics
    };
    (mirrored, intrinsics, mirror_mount(mount))
}
