//! Frame sources: anything that yields depth (and colour) frames with the
//! intrinsics to project them. The Kinect v2 and a recording on disk both
//! implement [`FrameSource`], so both feed the same publishing code
//! ([`crate::publish::publish_stream`]).

use std::path::PathBuf;

use slope_ipc_types::{CloudSource, Intrinsics, Mount};

use crate::frame_reads::{read_frame_images, Colour};
use crate::interruptible::InterruptibleError;
use crate::publish::StopFlag;
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
    /// The sensor that takes the frames, as a recording's `sensor`
    /// (`kinect2`, or a replayed recording's own name; empty when unknown):
    /// every cloud header carries it.
    pub sensor: String,
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
    #[error("bad frame {index} (row {row} of {file})")]
    BadFrame {
        index: u64,
        row: usize,
        file: PathBuf,
        #[source]
        source: RecordingError,
    },
    /// The thread that reads a frame's images could not run.
    #[error(transparent)]
    Reader(#[from] InterruptibleError),
    /// The Kinect v2 failed in a way the source cannot recover from.
    #[error(transparent)]
    Kinect2(Box<crate::kinect2::Kinect2Error>),
}

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
/// passes (pass `k` adds `k * (last index - first index + 1)` and
/// `k * (duration + one frame period)`), so subscribers see one monotonic
/// stream with the recording's own gaps. A pass that would overflow the
/// 64-bit index or stamp ends the stream instead.
pub struct RecordingSource {
    recording: Recording,
    /// With a stop request, each frame's images are read on a thread of
    /// their own ([`RecordingSource::stop_reads_on`]).
    stop: Option<StopFlag>,
    info: SourceInfo,
    next: usize,
    pass: u64,
    looping: bool,
    /// Duration of one pass plus one frame period, ns.
    pass_ns: u64,
    /// Index span of one pass: last index - first index + 1.
    pass_frames: u64,
    /// Whether the current pass has yielded a good frame yet.
    good_in_pass: bool,
    /// Frames published without colour because their colour image could
    /// not be read (the first is logged as a warning, the others at debug).
    bad_colors: u64,
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
            sensor: meta.sensor.clone(),
        };
        let pass_ns = match (frames.first(), frames.last()) {
            (Some(first), Some(last)) => {
                let span = last.timestamp_ns.saturating_sub(first.timestamp_ns);
                let period = if frames.len() > 1 {
                    span / (frames.len() as u64 - 1)
                } else {
                    33_333_333
                };
                span.saturating_add(period.max(1))
            }
            _ => 0,
        };
        let pass_frames = match (frames.first(), frames.last()) {
            (Some(first), Some(last)) => (last.index - first.index).saturating_add(1),
            _ => 0,
        };
        Self {
            recording,
            stop: None,
            info,
            next: 0,
            pass: 0,
            looping,
            pass_ns,
            pass_frames,
            good_in_pass: false,
            bad_colors: 0,
        }
    }

    /// Reads each frame's images on a thread of its own, so that `stop`
    /// ends the wait for a read that blocks (a recording on a stalled
    /// network mount) within [`crate::frame_reads::READ_SLICE`]: [`FrameSource::next_frame`]
    /// then answers the end of the stream. Without it the reads block the
    /// caller.
    pub fn stop_reads_on(mut self, stop: StopFlag) -> Self {
        self.stop = Some(stop);
        self
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
            if !self.good_in_pass {
                tracing::warn!(
                    recording = %self.recording.dir().display(),
                    "no frame of the recording could be read in a whole pass; stopping the loop"
                );
                return Ok(false);
            }
            self.next = 0;
            self.pass += 1;
            self.good_in_pass = false;
        }
        // Offsets of this pass; a stream that would overflow them ends.
        let (Some(index_offset), Some(stamp_offset)) = (
            self.pass.checked_mul(self.pass_frames),
            self.pass.checked_mul(self.pass_ns),
        ) else {
            return Ok(false);
        };
        let entry = &self.recording.frames()[self.next];
        let (Some(index), Some(stamp)) = (
            entry.index.checked_add(index_offset),
            entry.timestamp_ns.checked_add(stamp_offset),
        ) else {
            return Ok(false);
        };
        self.next += 1;
        let bad = |source: RecordingError| SourceError::BadFrame {
            index: entry.index,
            row: entry.row,
            file: self.recording.dir().join("frames.csv"),
            source,
        };
        let stop = self.stop.as_ref();
        let Some(images) =
            read_frame_images(&self.recording, entry, &mut frame.depth, Colour::Read, stop)?
        else {
            return Ok(false);
        };
        images.depth.map_err(bad)?;
        // The colour is optional: a frame whose colour image cannot be read
        // is published without it (rgb 0), as slope-eval and slope-convert
        // read it.
        frame.color = match images.color {
            Ok(color) => color,
            Err(err) => {
                self.bad_colors += 1;
                if self.bad_colors == 1 {
                    tracing::warn!(
                        frame = entry.index,
                        "published without colour: {err} (further frames like it are logged at debug)"
                    );
                } else {
                    tracing::debug!(frame = entry.index, "published without colour: {err}");
                }
                None
            }
        };
        frame.index = index;
        frame.source_stamp_ns = stamp;
        frame.capture_stamp_ns = 0;
        self.good_in_pass = true;
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::{test_meta, RecordingWriter};

    /// A two-frame recording whose frames.csv is then rewritten with `rows`.
    fn recording_with_rows(dir: &std::path::Path, rows: &str) -> Recording {
        let meta = test_meta(2, 2);
        let mut writer = RecordingWriter::create(dir, &meta, false).expect("create");
        let depth = DepthImage {
            width: 2,
            height: 2,
            data: vec![1000, 0, 2000, 3000],
        };
        writer.write_frame(0, &depth, None, None).expect("frame 0");
        writer.write_frame(1, &depth, None, None).expect("frame 1");
        writer.finish().expect("finish");
        std::fs::write(dir.join("frames.csv"), rows).expect("rewrite frames.csv");
        Recording::open(dir).expect("reopen")
    }

    fn indices(source: &mut RecordingSource, max: usize) -> Vec<(u64, u64)> {
        let mut frame = SourceFrame::default();
        let mut out = Vec::new();
        while out.len() < max && source.next_frame(&mut frame).expect("frame") {
            out.push((frame.index, frame.source_stamp_ns));
        }
        out
    }

    /// Read on their own thread (`stop_reads_on`), the frames are those read
    /// on the caller's; once the stop request is there, the stream ends
    /// without another read.
    #[test]
    fn frames_read_on_their_own_thread_are_the_same_and_a_stop_ends_the_stream() {
        let dir = tempfile::tempdir().expect("temp dir");
        let rows =
            "index,timestamp_ns,depth,color\n0,0,depth/000000.png,\n1,100,depth/000001.png,\n";
        let frames = |source: &mut RecordingSource| {
            let mut frame = SourceFrame::default();
            let mut out = Vec::new();
            while out.len() < 3 && source.next_frame(&mut frame).expect("frame") {
                out.push((frame.index, frame.source_stamp_ns, frame.depth.clone()));
            }
            out
        };
        let mut inline =
            RecordingSource::new(recording_with_rows(&dir.path().join("a"), rows), true);
        let stop = StopFlag::new();
        let mut threaded =
            RecordingSource::new(recording_with_rows(&dir.path().join("b"), rows), true)
                .stop_reads_on(stop.clone());
        let expected = frames(&mut inline);
        assert_eq!(expected.len(), 3);
        assert_eq!(expected[0].2.data, vec![1000, 0, 2000, 3000]);
        assert_eq!(frames(&mut threaded), expected);
        stop.stop();
        let mut frame = SourceFrame::default();
        assert!(
            !threaded.next_frame(&mut frame).expect("no error"),
            "stopped: the end"
        );
    }

    #[test]
    fn looping_keeps_indices_and_stamps_increasing_with_the_recordings_gaps() {
        let dir = tempfile::tempdir().expect("temp dir");
        let rec = recording_with_rows(
            &dir.path().join("r"),
            "index,timestamp_ns,depth,color\n0,0,depth/000000.png,\n3,100,depth/000001.png,\n",
        );
        let mut source = RecordingSource::new(rec, true);
        // Pass span: indices 0..=3 (4), stamps 100 + one period of 100.
        assert_eq!(
            indices(&mut source, 6),
            vec![(0, 0), (3, 100), (4, 200), (7, 300), (8, 400), (11, 500)]
        );
    }

    #[test]
    fn huge_stamps_end_a_loop_instead_of_overflowing() {
        let dir = tempfile::tempdir().expect("temp dir");
        let rows = format!(
            "index,timestamp_ns,depth,color\n0,0,depth/000000.png,\n{},{},depth/000001.png,\n",
            u64::MAX - 1,
            u64::MAX
        );
        let rec = recording_with_rows(&dir.path().join("r"), &rows);
        let mut source = RecordingSource::new(rec, true);
        // The second pass fits exactly once more (index and stamp u64::MAX),
        // then the next offset would overflow and the stream ends.
        assert_eq!(
            indices(&mut source, 10),
            vec![(0, 0), (u64::MAX - 1, u64::MAX), (u64::MAX, u64::MAX)]
        );
    }

    /// A colour image that cannot be read costs the frame its colour, not
    /// the frame (replay stopped on it, good depth and all).
    #[test]
    fn an_unreadable_colour_image_leaves_the_frame_without_colour() {
        let dir = tempfile::tempdir().expect("temp dir");
        let rec = recording_with_rows(
            &dir.path().join("r"),
            "index,timestamp_ns,depth,color\n0,0,depth/000000.png,depth/000000.png\n\
             1,100,depth/000001.png,color/missing.png\n",
        );
        let mut source = RecordingSource::new(rec, false);
        assert!(source.info().has_color);
        let mut frame = SourceFrame::default();
        for index in [0, 1] {
            assert!(source.next_frame(&mut frame).expect("a frame"), "{index}");
            assert_eq!(frame.index, index);
            assert_eq!(frame.depth.data, [1000, 0, 2000, 3000]);
            assert!(frame.color.is_none());
        }
        assert_eq!(source.bad_colors, 2);
        assert!(!source.next_frame(&mut frame).expect("the end"));
    }

    #[test]
    fn a_loop_over_only_bad_frames_ends() {
        let dir = tempfile::tempdir().expect("temp dir");
        let rec = recording_with_rows(
            &dir.path().join("r"),
            "index,timestamp_ns,depth,color\n0,0,depth/missing.png,\n",
        );
        let mut source = RecordingSource::new(rec, true);
        let mut frame = SourceFrame::default();
        assert!(matches!(
            source.next_frame(&mut frame),
            Err(SourceError::BadFrame { index: 0, .. })
        ));
        assert!(!source.next_frame(&mut frame).expect("ends cleanly"));
    }
}
