//! Writing a recording: [`RecordingWriter`] and PNG encoding.
//!
//! Output is deterministic: the same metadata and frames give the same bytes
//! in every file.

use std::fs::{self, File};
use std::path::{Path, PathBuf};

use png::{BitDepth, ColorType};

use super::meta::{check_truth_deg, format_meta, validate_meta};
use super::{
    ColorImage, DepthImage, RecordingError, RecordingMeta, COLOR_DIR, DEPTH_DIR, FRAMES_FILE,
    META_FILE,
};

/// How hard the writer compresses its PNGs. All levels are lossless and
/// deterministic; they trade encoding time against file size. Measured on
/// the 512x424 Kinect v2 frames in `shared/data` (one busy core): `Fast`
/// about 8 ms and 115-150 kB per depth frame, `Balanced` 55-110 ms and
/// 10-20 % smaller, `High` 130-370 ms and barely smaller still.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PngCompression {
    /// The default: keeps up with a 30 Hz camera.
    #[default]
    Fast,
    /// Smaller files, several times slower than `Fast`.
    Balanced,
    /// Smallest files, slowest (recordings bundled with the repository).
    High,
}

impl PngCompression {
    fn png(self) -> png::Compression {
        match self {
            Self::Fast => png::Compression::Fast,
            Self::Balanced => png::Compression::Balanced,
            Self::High => png::Compression::High,
        }
    }
}

/// Writes a recording frame by frame. Every frame's row is flushed to
/// `frames.csv` as soon as its images are on disk, so a recording cut short
/// (power loss, SIGKILL) is still readable up to its last complete frame.
#[derive(Debug)]
pub struct RecordingWriter {
    dir: PathBuf,
    frames_path: PathBuf,
    csv: csv::Writer<File>,
    width: u32,
    height: u32,
    per_frame_truth: bool,
    next_index: u64,
    last_timestamp_ns: Option<u64>,
    color_dir_created: bool,
    compression: PngCompression,
    /// Reused buffers: raw samples and the encoded PNG.
    samples: Vec<u8>,
    encoded: Vec<u8>,
}

/// A `map_err` for a failed write of `path`.
fn write_error(path: &Path) -> impl FnOnce(std::io::Error) -> RecordingError {
    let path = path.to_path_buf();
    move |source| RecordingError::Write { path, source }
}

/// Creates `dir`, or checks that it is an empty directory.
fn prepare_empty_dir(dir: &Path) -> Result<(), RecordingError> {
    match fs::read_dir(dir) {
        Ok(mut entries) => {
            if entries.next().is_some() {
                return Err(RecordingError::NotEmpty {
                    path: dir.to_path_buf(),
                });
            }
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            fs::create_dir_all(dir).map_err(write_error(dir))
        }
        // Exists but is a file, or is unreadable.
        Err(_) if dir.exists() && !dir.is_dir() => Err(RecordingError::NotEmpty {
            path: dir.to_path_buf(),
        }),
        Err(source) => Err(RecordingError::Read {
            path: dir.to_path_buf(),
            source,
        }),
    }
}

/// Creates frames.csv at `path` with its header (a `slope_deg` column iff
/// `per_frame_truth`), flushed.
fn create_frames_csv(
    path: &Path,
    per_frame_truth: bool,
) -> Result<csv::Writer<File>, RecordingError> {
    let file = File::create(path).map_err(write_error(path))?;
    let mut csv = csv::WriterBuilder::new().from_writer(file);
    let mut header = vec!["index", "timestamp_ns", "depth", "color"];
    if per_frame_truth {
        header.push("slope_deg");
    }
    csv.write_record(&header)
        .map_err(|e| csv_write_error(e, path))?;
    csv.flush().map_err(write_error(path))?;
    Ok(csv)
}

impl RecordingWriter {
    /// Creates `dir` (it must not exist, or be an empty directory), depth/ and color/ as needed,
    /// writes recording.toml and the frames.csv header (with a `slope_deg` column iff per_frame_truth).
    pub fn create(
        dir: &Path,
        meta: &RecordingMeta,
        per_frame_truth: bool,
    ) -> Result<Self, RecordingError> {
        let meta_path = dir.join(META_FILE);
        validate_meta(meta, &meta_path)?;
        prepare_empty_dir(dir)?;
        let depth_dir = dir.join(DEPTH_DIR);
        fs::create_dir(&depth_dir).map_err(write_error(&depth_dir))?;

        let text = format_meta(meta).map_err(|e| RecordingError::InvalidKey {
            path: meta_path.clone(),
            key: "(whole file)".into(),
            reason: e.to_string(),
        })?;
        fs::write(&meta_path, text).map_err(write_error(&meta_path))?;

        let frames_path = dir.join(FRAMES_FILE);
        let csv = create_frames_csv(&frames_path, per_frame_truth)?;

        tracing::debug!(dir = %dir.display(), per_frame_truth, "created recording");
        Ok(Self {
            dir: dir.to_path_buf(),
            frames_path,
            csv,
            width: meta.depth.width,
            height: meta.depth.height,
            per_frame_truth,
            next_index: 0,
            last_timestamp_ns: None,
            color_dir_created: false,
            compression: PngCompression::default(),
            samples: Vec::new(),
            encoded: Vec::new(),
        })
    }

    /// Sets the PNG compression for the frames written from now on.
    pub fn set_compression(&mut self, compression: PngCompression) {
        self.compression = compression;
    }

    /// The recording directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Frames written so far (also the index the next frame gets).
    pub fn frames_written(&self) -> u64 {
        self.next_index
    }

    /// Writes depth/NNNNNN.png (+ color/NNNNNN.png) and appends + flushes the csv row; returns the index.
    ///
    /// Rejects (before writing anything) a timestamp earlier than the
    /// previous frame's, images whose size differs from `[depth]`, a
    /// `slope_deg` outside [0, 90] or given without per-frame truth.
    pub fn write_frame(
        &mut self,
        timestamp_ns: u64,
        depth: &DepthImage,
        color: Option<&ColorImage>,
        slope_deg: Option<f64>,
    ) -> Result<u64, RecordingError> {
        let index = self.next_index;
        // The header is line 1, frame k is line k + 2.
        let row = usize::try_from(index).map_or(usize::MAX, |i| i.saturating_add(2));
        let name = format!("{index:06}.png");
        let depth_rel = format!("{DEPTH_DIR}/{name}");
        let color_rel = format!("{COLOR_DIR}/{name}");

        self.check_frame(row, timestamp_ns, slope_deg)?;
        self.check_size(row, &depth_rel, depth.width, depth.height, depth.data.len())?;
        if let Some(color) = color {
            self.check_size(row, &color_rel, color.width, color.height, color.data.len())?;
        }

        self.samples.clear();
        self.samples
            .extend(depth.data.iter().flat_map(|count| count.to_be_bytes()));
        self.encode(&depth_rel, ColorType::Grayscale, BitDepth::Sixteen)?;
        if let Some(color) = color {
            self.create_color_dir()?;
            self.samples.clear();
            self.samples.extend(color.data.iter().flatten());
            self.encode(&color_rel, ColorType::Rgb, BitDepth::Eight)?;
        }
        let color_rel = color.map(|_| color_rel.as_str());
        self.append_row(index, timestamp_ns, &depth_rel, color_rel, slope_deg)?;
        self.next_index += 1;
        self.last_timestamp_ns = Some(timestamp_ns);
        Ok(index)
    }

    /// Refuses a frame whose timestamp is earlier than the last one's, or
    /// whose `slope_deg` is given without a truth column or out of range.
    fn check_frame(
        &self,
        row: usize,
        timestamp_ns: u64,
        slope_deg: Option<f64>,
    ) -> Result<(), RecordingError> {
        if let Some(previous) = self.last_timestamp_ns.filter(|&p| timestamp_ns < p) {
            return Err(RecordingError::DecreasingTimestamp {
                path: self.frames_path.clone(),
                row,
                timestamp_ns,
                previous,
            });
        }
        if let Some(slope) = slope_deg {
            if !self.per_frame_truth {
                return Err(RecordingError::NoTruthColumn {
                    path: self.frames_path.clone(),
                    row,
                });
            }
            check_truth_deg(slope).map_err(|reason| RecordingError::BadRow {
                path: self.frames_path.clone(),
                row,
                reason: format!("column `slope_deg`: {reason}"),
            })?;
        }
        Ok(())
    }

    /// Creates `color/` before the first colour image.
    fn create_color_dir(&mut self) -> Result<(), RecordingError> {
        if !self.color_dir_created {
            let color_dir = self.dir.join(COLOR_DIR);
            fs::create_dir_all(&color_dir).map_err(|source| RecordingError::Write {
                path: color_dir,
                source,
            })?;
            self.color_dir_created = true;
        }
        Ok(())
    }

    /// Appends the frame's row to `frames.csv` and flushes it.
    fn append_row(
        &mut self,
        index: u64,
        timestamp_ns: u64,
        depth_rel: &str,
        color_rel: Option<&str>,
        slope_deg: Option<f64>,
    ) -> Result<(), RecordingError> {
        let index_text = index.to_string();
        let timestamp_text = timestamp_ns.to_string();
        let slope_text = slope_deg.map(|s| s.to_string()).unwrap_or_default();
        let mut record = vec![
            index_text.as_str(),
            timestamp_text.as_str(),
            depth_rel,
            color_rel.unwrap_or(""),
        ];
        if self.per_frame_truth {
            record.push(slope_text.as_str());
        }
        self.csv
            .write_record(&record)
            .map_err(|e| csv_write_error(e, &self.frames_path))?;
        self.csv.flush().map_err(|source| RecordingError::Write {
            path: self.frames_path.clone(),
            source,
        })
    }

    /// Flushes `frames.csv` and returns the recording directory.
    pub fn finish(mut self) -> Result<PathBuf, RecordingError> {
        self.csv.flush().map_err(|source| RecordingError::Write {
            path: self.frames_path.clone(),
            source,
        })?;
        tracing::debug!(dir = %self.dir.display(), frames = self.next_index, "finished recording");
        Ok(self.dir)
    }

    fn check_size(
        &self,
        row: usize,
        relative: &str,
        width: u32,
        height: u32,
        len: usize,
    ) -> Result<(), RecordingError> {
        let image = self.dir.join(relative);
        if (width, height) != (self.width, self.height) {
            return Err(RecordingError::ImageSize {
                row,
                image,
                width: self.width,
                height: self.height,
                found_width: width,
                found_height: height,
            });
        }
        let expected = width as usize * height as usize;
        if len != expected {
            return Err(RecordingError::ImageData {
                row,
                image,
                width,
                height,
                expected,
                found: len,
            });
        }
        Ok(())
    }

    /// Encodes `self.samples` (big-endian samples, row-major) as a PNG of
    /// the recording's size and writes it to `relative`.
    fn encode(
        &mut self,
        relative: &str,
        color: ColorType,
        depth: BitDepth,
    ) -> Result<(), RecordingError> {
        let image = self.dir.join(relative);
        let encode_error = |source| RecordingError::ImageEncode {
            image: image.clone(),
            source,
        };
        self.encoded.clear();
        let mut encoder = png::Encoder::new(&mut self.encoded, self.width, self.height);
        encoder.set_color(color);
        encoder.set_depth(depth);
        encoder.set_compression(self.compression.png());
        let mut writer = encoder.write_header().map_err(encode_error)?;
        writer
            .write_image_data(&self.samples)
            .map_err(encode_error)?;
        writer.finish().map_err(encode_error)?;
        fs::write(&image, &self.encoded).map_err(|source| RecordingError::Write {
            path: image.clone(),
            source,
        })
    }
}

fn csv_write_error(error: csv::Error, path: &Path) -> RecordingError {
    let message = error.to_string();
    let source = match error.into_kind() {
        csv::ErrorKind::Io(source) => source,
        _ => std::io::Error::other(message),
    };
    RecordingError::Write {
        path: path.to_path_buf(),
        source,
    }
}
