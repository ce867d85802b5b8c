//! Frame sources: anything that yields depth (and colour) frames with the
//! intrinsics to project them. The Kinect v2 and a recording on disk both
//! implement [`FrameSource`], so both feed the same publishing code
//! ([`crate::publish::publish_stream`]).

use std::path::PathBuf;

use slope_ipc_types::{CloudSource, Intrinsics, Mount};

use crate::recording::{ColorImage, DepthImage, Recording, RecordingError};

/// What a source produces, fixed for the whole stream.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceInfo {
    pub width: u32,
    pub height: u32,
    pub intrinsics: Intrinsics,
    /// Metres per depth count.
    pub unit_m: f64,
    pub mount: Mount,
    pub source: CloudSource,
    pub has_color: bool,
}

/// One frame, with buffers that a source reuses from call to call.
#[derive(Debug, Clone)]
pub struct SourceFrame {
    pub index: u64,
    /// The frame's time in the source's own clock, ns.
    pub source_stamp_ns: u64,
    /// When the frame was captured, ns since the Unix epoch. Sources that
    /// replay set it when the frame is emitted.
    pub capture_stamp_ns: u64,
    pub depth: DepthImage,
    pub color: Option<ColorImage>,
}

impl Default for SourceFrame {
    fn default() -> Self {
        Self {
            index: 0,
            source_stamp_ns: 0,
            capture_stamp_ns: 0,
            depth: DepthImage {
                width: 0,
                height: 0,
                data: Vec::new(),
            },
            color: None,
        }
    }
}

/// Why a source could not produce a frame.
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    /// The stream cannot go on (unreadable recording, device gone for good).
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// One frame is bad; the stream can go on without it.
    #[error("bad frame {index} (row {row} of {file}): {source}")]
    BadFrame {
        index: u64,
        row: usize,
        file: PathBuf,
        #[source]
        source: RecordingError,
    },
    /// The Kinect v2 failed in a way the source cannot recover from.
    #[cfg(feature = "kinect2")]
    #[error(transparent)]
    Kinect2(Box<crate::kinect2::Kinect2Error>),
}

#[cfg(feature = "kinect2")]
impl From<crate::kinect2::Kinect2Error> for SourceError {
    fn from(err: crate::kinect2::Kinect2Error) -> Self {
        Self::Kinect2(Box::new(err))
    }
}

/// A stream of depth frames.
pub trait FrameSource {
    fn info(&self) -> &SourceInfo;

    /// Fills `frame` with the next frame, reusing its buffers. `Ok(false)` at
    /// the end of the stream.
    fn next_frame(&mut self, frame: &mut SourceFrame) -> Result<bool, SourceError>;
}

/// Plays a recording from disk, optionally over and over.
///
/// With `looping`, frame indices and source stamps keep increasing across
/// passes (pass `k` adds `k * frames` and `k * (duration + one frame
/// period)`), so subscribers see one monotonic stream.
pub struct RecordingSource {
    recording: Recording,
    info: SourceInfo,
    next: usize,
    pass: u64,
    looping: bool,
    /// Duration of one pass plus one frame period, ns.
    pass_ns: u64,
}

impl RecordingSource {
    pub fn new(recording: Recording, looping: bool) -> Self {
        let meta = recording.meta();
        let frames = recording.frames();
        let has_color = frames.iter().any(|f| f.color.is_some());
        let info = SourceInfo {
            width: meta.depth.width,
            height: meta.depth.height,
            intrinsics: recording.intrinsics(),
            unit_m: meta.depth.unit_m,
            mount: recording.mount(),
            source: CloudSource::Replay,
            has_color,
        };
        let pass_ns = match (frames.first(), frames.last()) {
            (Some(first), Some(last)) => {
                let span = last.timestamp_ns.saturating_sub(first.timestamp_ns);
                let period = if frames.len() > 1 {
                    span / (frames.len() as u64 - 1)
                } else {
                    33_333_333
                };
                span + period.max(1)
            }
            _ => 0,
        };
        Self {
            recording,
            info,
            next: 0,
            pass: 0,
            looping,
            pass_ns,
        }
    }

    pub fn recording(&self) -> &Recording {
        &self.recording
    }

    /// Number of frames in one pass.
    pub fn frames_per_pass(&self) -> usize {
        self.recording.frames().len()
    }
}

impl FrameSource for RecordingSource {
    fn info(&self) -> &SourceInfo {
        &self.info
    }

    fn next_frame(&mut self, frame: &mut SourceFrame) -> Result<bool, SourceError> {
        let count = self.recording.frames().len();
        if count == 0 {
            return Ok(false);
        }
        if self.next >= count {
            if !self.looping {
                return Ok(false);
            }
            self.next = 0;
            self.pass += 1;
        }
        let entry = &self.recording.frames()[self.next];
        self.next += 1;
        let bad = |source: RecordingError| SourceError::BadFrame {
            index: entry.index,
            row: entry.row,
            file: self.recording.dir().join("frames.csv"),
            source,
        };
        self.recording
            .read_depth_into(entry, &mut frame.depth)
            .map_err(bad)?;
        frame.color = self.recording.read_color(entry).map_err(bad)?;
        frame.index = entry.index + self.pass * count as u64;
        frame.source_stamp_ns = entry.timestamp_ns + self.pass * self.pass_ns;
        Ok(true)
    }
}
