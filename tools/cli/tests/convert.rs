//! `slope-convert` on a recording with bad frames: the frames are skipped
//! and each warning names the cause (what the decoder or the file system
//! said), not only the file.

use std::path::Path;
use std::process::Command;

const CONVERT: &str = env!("CARGO_BIN_EXE_slope-convert");

/// Copies the first `frames` frames of tests/recordings/ramp16 (depth
/// only) into `dir`.
fn copy_ramp16(dir: &Path, frames: usize) {
    let ramp16 = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/recordings/ramp16");
    std::fs::create_dir_all(dir.join("depth")).expect("mkdir");
    std::fs::copy(ramp16.join("recording.toml"), dir.join("recording.toml")).expect("copy");
    let mut csv = String::from("index,timestamp_ns,depth,color\n");
    for k in 0..frames {
        let png = format!("depth/{k:06}.png");
        std::fs::copy(ramp16.join(&png), dir.join(&png)).expect("copy");
        csv.push_str(&format!("{k},{},{png},\n", k as u64 * 33_333_333));
    }
    std::fs::write(dir.join("frames.csv"), csv).expect("write");
}

/// A truncated and a missing depth image: both frames skipped, the others
/// converted, and the warnings give "unexpected end of file" and "No such
/// file or directory" (they stopped at "cannot decode X" / "cannot read X").
#[test]
fn a_bad_frame_warning_names_its_cause() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rec = dir.path().join("rec");
    copy_ramp16(&rec, 4);
    let truncated = rec.join("depth/000001.png");
    let bytes = std::fs::read(&truncated).expect("read");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).expect("write");
    let missing = rec.join("depth/000002.png");
    std::fs::remove_file(&missing).expect("remove");
    let mcap = dir.path().join("rec.mcap");
    let out = Command::new(CONVERT)
        .args([
            rec.to_str().expect("utf-8"),
            "-o",
            mcap.to_str().expect("utf-8"),
            "--no-estimates",
        ])
        .env_remove("RUST_LOG")
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let decode = format!(
        "skipping a bad frame: frames.csv line 3: cannot decode {}: unexpected end of file",
        truncated.display()
    );
    let read = format!(
        "skipping a bad frame: frames.csv line 4: cannot read {}: No such file or directory",
        missing.display()
    );
    assert!(stderr.contains(&decode), "{decode}\n{stderr}");
    assert!(stderr.contains(&read), "{read}\n{stderr}");
    assert!(
        stderr.contains("frames=2") && stderr.contains("bad_frames=2"),
        "{stderr}"
    );
}
