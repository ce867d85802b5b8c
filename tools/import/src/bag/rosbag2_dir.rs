//! A ROS 2 bag directory: `metadata.yaml` names its storage files
//! (`relative_file_paths`) and their compression; without it (a bag whose
//! recorder died), the directory's `.mcap` or `.db3` files in name order.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::BagError;

#[derive(Debug, Deserialize)]
struct Metadata {
    rosbag2_bagfile_information: BagInformation,
}

#[derive(Debug, Deserialize)]
struct BagInformation {
    #[serde(default)]
    relative_file_paths: Vec<String>,
    #[serde(default)]
    compression_format: String,
    #[serde(default)]
    compression_mode: String,
}

/// The storage files of the bag directory `dir`, in order.
pub fn storage_files(dir: &Path) -> Result<Vec<PathBuf>, BagError> {
    let meta_path = dir.join("metadata.yaml");
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| BagError::Io { path, source }
    };
    if meta_path.is_file() {
        let text = std::fs::read_to_string(&meta_path).map_err(io(&meta_path))?;
        let meta: Metadata = serde_yaml::from_str(&text).map_err(|e| BagError::NotABag {
            path: meta_path.clone(),
            reason: format!("not a rosbag2 metadata.yaml ({e})"),
        })?;
        let info = meta.rosbag2_bagfile_information;
        if !info.compression_mode.is_empty() && !info.compression_format.is_empty() {
            return Err(BagError::Unsupported {
                path: dir.to_path_buf(),
                reason: format!(
                    "the bag is compressed ({} per {}); decompress it first with `ros2 bag \
                     decompress` (or record without compression)",
                    info.compression_format,
                    info.compression_mode.to_lowercase()
                ),
            });
        }
        // Only the file name counts: older rosbag2 wrote paths with the
        // bag's directory in front.
        let files: Vec<PathBuf> = info
            .relative_file_paths
            .iter()
            .map(|p| dir.join(Path::new(p).file_name().unwrap_or_default()))
            .collect();
        if files.is_empty() {
            return Err(BagError::NotABag {
                path: meta_path,
                reason: "it lists no storage files".to_string(),
            });
        }
        return Ok(files);
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io(dir))?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("mcap") || e.eq_ignore_ascii_case("db3"))
        })
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(BagError::NotABag {
            path: dir.to_path_buf(),
            reason: "a directory without metadata.yaml or .mcap/.db3 files".to_string(),
        });
    }
    tracing::warn!(
        "{} has no metadata.yaml: reading its {} storage file(s) in name order",
        dir.display(),
        files.len()
    );
    Ok(files)
}
