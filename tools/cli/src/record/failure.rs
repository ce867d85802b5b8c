//! What a failed recording says it left in its output directory.

use std::path::Path;

use slope_sensor::recording::Recording;

/// A failed recording's error, saying what is left in `out`: the frames
/// recorded before (a valid recording), or nothing (a directory this run
/// `created` and whose first frame failed, a full disk, is removed).
pub(super) fn explain_failure(err: anyhow::Error, out: &Path, created: bool) -> anyhow::Error {
    match frames_recorded(out) {
        Some(0) if created => match std::fs::remove_dir_all(out) {
            Ok(()) => err.context(format!(
                "no frame was recorded; {} was removed",
                out.display()
            )),
            Err(_) => err.context(format!(
                "no frame was recorded; remove {} by hand",
                out.display()
            )),
        },
        Some(frames) if frames > 0 => err.context(format!(
            "{} holds the {frames} frame(s) recorded before, a valid recording",
            out.display()
        )),
        _ => err,
    }
}

/// The frames a recording directory lists (`None` when it holds no
/// readable recording).
fn frames_recorded(dir: &Path) -> Option<usize> {
    match Recording::open(dir) {
        Ok(recording) => Some(recording.frames().len()),
        Err(_) => dir.join("recording.toml").is_file().then_some(0),
    }
}
