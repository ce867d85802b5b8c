//! A bent recording on disk: every frame (or one) of a source recording
//! bent and written with the recording writer, the truth in
//! `recording.toml`, and `bend.toml` saying how it was made.

use std::fmt::Write as _;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

use slope_sensor::recording::{PngCompression, Recording, RecordingWriter};

use super::{bend_floor, BendParams, DepthFrame};
use crate::error::BendError;

/// The provenance file written beside `recording.toml`.
pub const PROVENANCE_FILE: &str = "bend.toml";

/// What [`write_bent_recording`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct BendSummary {
    pub dir: PathBuf,
    /// Frames written.
    pub frames: usize,
    /// Frames that were to be written (fewer written: stopped early).
    pub frames_asked: usize,
}

impl BendSummary {
    /// True when a stop request ended the writing early.
    pub fn is_partial(&self) -> bool {
        self.frames < self.frames_asked
    }
}

/// Bends frame `frame` of the recording `source` (every frame when
/// `None`, each with its own floor fit) and writes the result to `out`
/// (which must not exist, or be empty). `on_frame(k)` runs once the k-th
/// written frame is on disk; `ControlFlow::Break` stops there, leaving a
/// valid recording.
pub fn write_bent_recording(
    source: &Path,
    out: &Path,
    frame: Option<usize>,
    params: &BendParams,
    compression: PngCompression,
    mut on_frame: impl FnMut(usize) -> ControlFlow<()>,
) -> Result<BendSummary, BendError> {
    params.check()?;
    let recording = Recording::open(source).map_err(|source_error| BendError::Read {
        dir: source.to_path_buf(),
        source: source_error,
    })?;
    let chosen: Vec<usize> = match frame {
        Some(k) if k >= recording.frames().len() => {
            return Err(BendError::NoSuchFrame {
                dir: source.to_path_buf(),
                frame: k,
                frames: recording.frames().len(),
            })
        }
        Some(k) => vec![k],
        None => (0..recording.frames().len()).collect(),
    };
    let write_error = |source| BendError::Write {
        dir: out.to_path_buf(),
        source,
    };
    // Bend the first frame before creating anything: a frame that cannot
    // be bent leaves no directory behind.
    let mut writer = None;
    let mut provenance = provenance_header(source, frame, params);
    let mut written = 0;
    for (k, &index) in chosen.iter().enumerate() {
        let depth_frame = DepthFrame::from_recording(&recording, index)?;
        let bent = bend_floor(&depth_frame, params)?;
        let writer = match &mut writer {
            Some(w) => w,
            None => {
                let mut w = RecordingWriter::create(out, &bent.meta, false).map_err(write_error)?;
                w.set_compression(compression);
                writer.insert(w)
            }
        };
        writer
            .write_frame(
                depth_frame.timestamp_ns,
                &bent.depth,
                bent.color.as_ref(),
                None,
            )
            .map_err(write_error)?;
        let floor = bent.hinge.floor;
        // Writing to a String cannot fail.
        let _ = write!(
            provenance,
            "\n[[frames]]\nsource_frame = {index}\nfloor_up = [{:.9}, {:.9}, {:.9}]\n\
             floor_height_m = {:.6}\nfloor_rms_m = {:.6}\nfloor_fit_points = {}\n\
             floor_from_m = {:.3}\nfloor_reach_m = {:.3}\nfloor_before_hinge = {}\n\
             floor_beyond_hinge = {}\nforward = [{:.9}, {:.9}, {:.9}]\n",
            floor.up[0],
            floor.up[1],
            floor.up[2],
            floor.height_m,
            floor.rms_m,
            floor.fit_points,
            bent.floor.from_m,
            bent.floor.reach_m,
            bent.floor.before_hinge,
            bent.floor.beyond_hinge,
            bent.hinge.forward[0],
            bent.hinge.forward[1],
            bent.hinge.forward[2],
        );
        written += 1;
        if on_frame(k).is_break() {
            break;
        }
    }
    let Some(writer) = writer else {
        // No frame at all: the recording reader refuses an empty table
        // before this, so this is a recording of no rows.
        return Err(BendError::NoSuchFrame {
            dir: source.to_path_buf(),
            frame: 0,
            frames: 0,
        });
    };
    let dir = writer.finish().map_err(write_error)?;
    let path = dir.join(PROVENANCE_FILE);
    std::fs::write(&path, provenance).map_err(|e| BendError::Write {
        dir: dir.clone(),
        source: slope_sensor::recording::RecordingError::Write { path, source: e },
    })?;
    Ok(BendSummary {
        dir,
        frames: written,
        frames_asked: chosen.len(),
    })
}

fn provenance_header(source: &Path, frame: Option<usize>, params: &BendParams) -> String {
    let frame = frame.map_or_else(|| "\"all\"".to_string(), |k| k.to_string());
    format!(
        "# Made by slope-bend: a real frame's floor bent into a ramp (tools/synth/README.md).\n\
         source = {:?}\nframe = {frame}\nangle_deg = {}\nhinge_m = {}\nseed = {}\n",
        source.display().to_string(),
        params.angle_deg,
        params.hinge_m,
        params.seed
    )
}
