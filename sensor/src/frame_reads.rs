//! [`read_frame_images`]: a frame's depth and colour images, read so that a
//! stop request need not wait for them.
//!
//! A recording on a network mount that stalls blocks the `open` or `read`
//! of an image for as long as the mount does. Read on a thread of its own
//! (a [`Recording`] clones cheaply), the caller looks at the [`StopFlag`]
//! every [`READ_SLICE`] and goes on as soon as it is set; the abandoned read
//! ends on its thread, or with the process. (A read in uninterruptible sleep,
//! as on a hard NFS mount, still holds the process until the mount answers.)

use std::time::Duration;

use crate::interruptible::{run_interruptible, InterruptibleError};
use crate::publish::StopFlag;
use crate::recording::{ColorImage, DepthImage, FrameEntry, Recording, RecordingError};

/// How often a caller waiting for a frame's images looks at the stop request.
pub const READ_SLICE: Duration = Duration::from_millis(50);

/// What reading a frame's images gave.
#[derive(Debug)]
pub struct FrameImages {
    /// The depth image, read into the caller's buffer.
    pub depth: Result<(), RecordingError>,
    /// The colour image (`Ok(None)`: the frame has none, it was not asked
    /// for, or the depth image could not be read).
    pub color: Result<Option<ColorImage>, RecordingError>,
}

/// Whether [`read_frame_images`] reads the colour image too.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Colour {
    Read,
    Skip,
}

/// The images of `entry` of `recording`, the depth image into `depth`
/// (reusing its buffer). With `stop`, on a thread of its own: `Ok(None)`
/// when the stop request came first (then `depth` is left empty). Without
/// it, on the caller's thread.
pub fn read_frame_images(
    recording: &Recording,
    entry: &FrameEntry,
    depth: &mut DepthImage,
    colour: Colour,
    stop: Option<&StopFlag>,
) -> Result<Option<FrameImages>, InterruptibleError> {
    let Some(stop) = stop else {
        return Ok(Some(read_images(recording, entry, depth, colour)));
    };
    let recording = recording.clone();
    let entry = entry.clone();
    let mut buffer = std::mem::take(depth);
    let read = run_interruptible("read-frame", stop, READ_SLICE, &mut || {}, move || {
        let images = read_images(&recording, &entry, &mut buffer, colour);
        (buffer, images)
    })?;
    Ok(read.map(|(buffer, images)| {
        *depth = buffer;
        images
    }))
}

/// The depth image of `entry` into `depth`, then (if asked for and the
/// depth image was read) its colour image.
fn read_images(
    recording: &Recording,
    entry: &FrameEntry,
    depth: &mut DepthImage,
    colour: Colour,
) -> FrameImages {
    let depth = recording.read_depth_into(entry, depth);
    let color = match colour {
        Colour::Read if depth.is_ok() => recording.read_color(entry),
        _ => Ok(None),
    };
    FrameImages { depth, color }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::{test_meta, RecordingWriter};

    fn recording(dir: &std::path::Path) -> (Recording, DepthImage) {
        let meta = test_meta(2, 1);
        let depth = DepthImage {
            width: 2,
            height: 1,
            data: vec![1234, 0],
        };
        let color = ColorImage {
            width: 2,
            height: 1,
            data: vec![[1, 2, 3], [4, 5, 6]],
        };
        let mut writer = RecordingWriter::create(dir, &meta, false).expect("create");
        writer
            .write_frame(0, &depth, Some(&color), None)
            .expect("frame");
        writer.finish().expect("finish");
        (Recording::open(dir).expect("open"), depth)
    }

    /// On a thread of its own the images are those read inline; a stop
    /// request ends the wait without a read; a missing image is its error.
    #[test]
    fn images_read_on_their_own_thread_are_those_read_inline() {
        let dir = tempfile::tempdir().expect("temp dir");
        let (recording, expected) = recording(&dir.path().join("r"));
        let entry = &recording.frames()[0];
        let stop = StopFlag::new();
        let mut depth = DepthImage::default();
        let images = read_frame_images(&recording, entry, &mut depth, Colour::Read, Some(&stop))
            .expect("thread")
            .expect("not stopped");
        assert!(images.depth.is_ok(), "{:?}", images.depth);
        assert_eq!(depth, expected);
        let color = images.color.expect("colour").expect("a colour image");
        assert_eq!(color.data, vec![[1, 2, 3], [4, 5, 6]]);
        let skipped = read_frame_images(&recording, entry, &mut depth, Colour::Skip, None)
            .expect("inline")
            .expect("not stopped");
        assert!(matches!(skipped.color, Ok(None)), "{:?}", skipped.color);
        assert_eq!(depth, expected);

        std::fs::remove_file(recording.dir().join(&entry.depth)).expect("remove the image");
        let missing = read_frame_images(&recording, entry, &mut depth, Colour::Read, Some(&stop))
            .expect("thread")
            .expect("not stopped");
        assert!(missing.depth.is_err() && matches!(missing.color, Ok(None)));

        stop.stop();
        let stopped = read_frame_images(&recording, entry, &mut depth, Colour::Read, Some(&stop))
            .expect("no thread error");
        assert!(stopped.is_none(), "{stopped:?}");
    }
}
