//! Reading a recording: `frames.csv` parsing (bytes in, [`FrameEntry`]s out)
//! and [`Recording`], which decodes the images on demand.

use std::io::{self, BufReader};
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

use png::{BitDepth, ColorType};
use slope_ipc_types::{Intrinsics, Mount};

use super::meta::{check_truth_deg, parse_meta};
use super::{ColorImage, DepthImage, RecordingError, RecordingMeta, FRAMES_FILE, META_FILE};
use crate::input_file::{
    open_regular, read_bytes, read_text, MAX_FRAME_TABLE_BYTES, MAX_SETTINGS_BYTES,
};
use crate::projection::Projector;

/// One row of `frames.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameEntry {
    pub index: u64,
    /// Capture time from the start of the recording, ns.
    pub timestamp_ns: u64,
    /// Depth image path relative to the recording directory (normalised:
    /// no `.` components).
    pub depth: PathBuf,
    /// Colour image path relative to the recording directory, if any.
    pub color: Option<PathBuf>,
    /// Per-frame ground truth (the optional `slope_deg` column), degrees.
    pub slope_deg: Option<f64>,
    /// 1-based line number of this row in `frames.csv` (the header is line 1).
    pub row: usize,
}

/// A recording opened from disk: metadata and frame table validated, images
/// decoded when asked for.
///
/// Cloning is cheap (the frame table is shared): a frame's images can be
/// read on another thread ([`crate::frame_reads`]).
#[derive(Debug, Clone)]
pub struct Recording {
    dir: PathBuf,
    meta: RecordingMeta,
    frames: Arc<[FrameEntry]>,
}

impl Recording {
    /// Opens the recording in `dir`, reading and validating `recording.toml`
    /// and `frames.csv` (not the images).
    pub fn open(dir: &Path) -> Result<Recording, RecordingError> {
        let meta_path = dir.join(META_FILE);
        if !meta_path.exists() {
            return Err(RecordingError::NotARecording {
                dir: dir.to_path_buf(),
            });
        }
        let read_error = |path: &Path| {
            let path = path.to_path_buf();
            move |source| RecordingError::Read { path, source }
        };
        let text = read_text(&meta_path, MAX_SETTINGS_BYTES).map_err(read_error(&meta_path))?;
        let meta = parse_meta(&text, &meta_path)?;

        let frames_path = dir.join(FRAMES_FILE);
        let bytes =
            read_bytes(&frames_path, MAX_FRAME_TABLE_BYTES).map_err(read_error(&frames_path))?;
        let frames = parse_frames(&bytes, &frames_path)?;
        tracing::debug!(
            dir = %dir.display(),
            frames = frames.len(),
            width = meta.depth.width,
            height = meta.depth.height,
            "opened recording"
        );
        Ok(Recording {
            dir: dir.to_path_buf(),
            meta,
            frames: frames.into(),
        })
    }

    /// The recording directory, as given to [`Recording::open`].
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    pub fn meta(&self) -> &RecordingMeta {
        &self.meta
    }

    /// The rows of `frames.csv`, in order.
    pub fn frames(&self) -> &[FrameEntry] {
        &self.frames
    }

    /// Decodes the depth image of `frame`.
    pub fn read_depth(&self, frame: &FrameEntry) -> Result<DepthImage, RecordingError> {
        let mut image = DepthImage::default();
        self.read_depth_into(frame, &mut image)?;
        Ok(image)
    }

    /// Decodes the depth image of `frame` into `out`, reusing `out.data`'s
    /// allocation. On error the content of `out` is unspecified.
    pub fn read_depth_into(
        &self,
        frame: &FrameEntry,
        out: &mut DepthImage,
    ) -> Result<(), RecordingError> {
        let image = self.dir.join(&frame.depth);
        let ctx = ImageContext {
            row: frame.row,
            image: &image,
        };
        out.data.clear();
        decode_png(&ctx, &self.meta, PixelFormat::Depth, |bytes| {
            out.data.extend(
                bytes
                    .chunks_exact(2)
                    .map(|pair| u16::from_be_bytes([pair[0], pair[1]])),
            );
        })?;
        out.width = self.meta.depth.width;
        out.height = self.meta.depth.height;
        Ok(())
    }

    /// Decodes the colour image of `frame`; `None` when the row has none.
    pub fn read_color(&self, frame: &FrameEntry) -> Result<Option<ColorImage>, RecordingError> {
        let Some(relative) = &frame.color else {
            return Ok(None);
        };
        let image = self.dir.join(relative);
        let ctx = ImageContext {
            row: frame.row,
            image: &image,
        };
        let mut data = Vec::new();
        decode_png(&ctx, &self.meta, PixelFormat::Color, |bytes| {
            data.extend(bytes.chunks_exact(3).map(|rgb| [rgb[0], rgb[1], rgb[2]]));
        })?;
        Ok(Some(ColorImage {
            width: self.meta.depth.width,
            height: self.meta.depth.height,
            data,
        }))
    }

    /// Ground truth for `frame`: its `slope_deg` cell if set, else `[truth]`.
    pub fn truth_deg(&self, frame: &FrameEntry) -> Option<f64> {
        frame.slope_deg.or(self.meta.truth.slope_deg)
    }

    pub fn intrinsics(&self) -> Intrinsics {
        self.meta.depth.intrinsics()
    }

    /// The mount, NaN for each key `[mount]` does not give.
    pub fn mount(&self) -> Mount {
        self.meta.mount.to_mount()
    }

    /// The points of one frame (`[depth]` width x height), or
    /// [`RecordingError::TooManyPoints`] naming `recording.toml` when that
    /// is more than `max_points` (or none at all). Readers call this before
    /// allocating a frame's cloud: `[depth]` is only checked to be positive,
    /// and a typing error such as 100000 x 100000 would ask for a buffer of
    /// 10^10 points. [`slope_ipc_types::DEFAULT_MAX_CLOUD_POINTS`] is the
    /// limit the publishers use.
    pub fn check_points(&self, max_points: usize) -> Result<usize, RecordingError> {
        let (width, height) = (self.meta.depth.width, self.meta.depth.height);
        let points = u64::from(width) * u64::from(height);
        match usize::try_from(points) {
            Ok(n) if n > 0 && n <= max_points => Ok(n),
            _ => Err(RecordingError::TooManyPoints {
                path: self.dir.join(META_FILE),
                width,
                height,
                points,
                max_points,
            }),
        }
    }

    /// A projector for this recording's depth images.
    pub fn projector(&self) -> Projector {
        let d = &self.meta.depth;
        Projector::new(d.width, d.height, d.intrinsics(), d.unit_m)
    }
}

/// Parses the bytes of `frames.csv`; `path` is only used in errors.
pub(crate) fn parse_frames(input: &[u8], path: &Path) -> Result<Vec<FrameEntry>, RecordingError> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(input);
    let mut lines = LineCounter::new(input);
    let csv_error = |error: csv::Error, lines: &mut LineCounter| {
        let row = error.position().map_or(0, |p| lines.line_at(p.byte()));
        csv_to_recording_error(error, row, path)
    };
    let header = reader
        .headers()
        .map_err(|e| csv_error(e, &mut lines))?
        .clone();
    let columns = Columns::find(&header, path)?;
    let mut frames: Vec<FrameEntry> = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| csv_error(e, &mut lines))?;
        let row = record.position().map_or(0, |p| lines.line_at(p.byte()));
        let frame = columns.frame(&record, row, path)?;
        if let Some(previous) = frames.last() {
            check_order(previous, &frame, path)?;
        }
        frames.push(frame);
    }
    Ok(frames)
}

/// Where `frames.csv`'s columns are: the three required ones and the two
/// optional ones.
struct Columns {
    count: usize,
    index: usize,
    timestamp_ns: usize,
    depth: usize,
    color: Option<usize>,
    slope_deg: Option<usize>,
}

impl Columns {
    /// The columns of `header`; a required one missing is an error.
    fn find(header: &csv::StringRecord, path: &Path) -> Result<Self, RecordingError> {
        for name in ["index", "timestamp_ns", "depth", "color", "slope_deg"] {
            if header.iter().filter(|h| *h == name).count() > 1 {
                return Err(RecordingError::BadRow {
                    path: path.to_path_buf(),
                    row: 1,
                    reason: format!(
                        "the header names the column `{name}` twice (which one holds the frames?)"
                    ),
                });
            }
        }
        let column = |name: &str| header.iter().position(|h| h == name);
        let required = |name: &'static str| {
            column(name).ok_or(RecordingError::MissingColumn {
                path: path.to_path_buf(),
                column: name,
            })
        };
        Ok(Self {
            count: header.len(),
            index: required("index")?,
            timestamp_ns: required("timestamp_ns")?,
            depth: required("depth")?,
            color: column("color"),
            slope_deg: column("slope_deg"),
        })
    }

    /// The frame of one data row (`row`: its line in the file).
    fn frame(
        &self,
        record: &csv::StringRecord,
        row: usize,
        path: &Path,
    ) -> Result<FrameEntry, RecordingError> {
        let bad_row = |reason: String| RecordingError::BadRow {
            path: path.to_path_buf(),
            row,
            reason,
        };
        if record.len() != self.count {
            return Err(bad_row(format!(
                "{} fields, the header has {}",
                record.len(),
                self.count
            )));
        }
        let field = |col: usize| record.get(col).unwrap_or("");
        // An optional column's value, `None` when absent or empty.
        let given = |col: Option<usize>| col.map(field).filter(|text| !text.is_empty());
        let integer = |name: &str, col: usize| {
            let text = field(col);
            text.parse::<u64>().map_err(|_| {
                bad_row(format!(
                    "column `{name}`: {text:?} is not a non-negative integer"
                ))
            })
        };
        let image_path = |name: &str, text: &str| {
            relative_path(text)
                .map_err(|reason| bad_row(format!("column `{name}`: path {text:?} {reason}")))
        };
        let slope_deg = |text: &str| {
            let value = text
                .parse::<f64>()
                .map_err(|_| bad_row(format!("column `slope_deg`: {text:?} is not a number")))?;
            check_truth_deg(value)
                .map_err(|reason| bad_row(format!("column `slope_deg`: {reason}")))?;
            Ok(value)
        };
        Ok(FrameEntry {
            index: integer("index", self.index)?,
            timestamp_ns: integer("timestamp_ns", self.timestamp_ns)?,
            depth: image_path("depth", field(self.depth))?,
            color: given(self.color)
                .map(|text| image_path("color", text))
                .transpose()?,
            slope_deg: given(self.slope_deg).map(slope_deg).transpose()?,
            row,
        })
    }
}

/// Indices must grow and timestamps must not go back from `previous` to
/// `frame`.
fn check_order(
    previous: &FrameEntry,
    frame: &FrameEntry,
    path: &Path,
) -> Result<(), RecordingError> {
    if frame.index <= previous.index {
        return Err(RecordingError::NonIncreasingIndex {
            path: path.to_path_buf(),
            row: frame.row,
            index: frame.index,
            previous: previous.index,
        });
    }
    if frame.timestamp_ns < previous.timestamp_ns {
        return Err(RecordingError::DecreasingTimestamp {
            path: path.to_path_buf(),
            row: frame.row,
            timestamp_ns: frame.timestamp_ns,
            previous: previous.timestamp_ns,
        });
    }
    Ok(())
}

fn csv_to_recording_error(error: csv::Error, row: usize, path: &Path) -> RecordingError {
    let reason = error.to_string();
    match error.into_kind() {
        csv::ErrorKind::Io(source) => RecordingError::Read {
            path: path.to_path_buf(),
            source,
        },
        _ => RecordingError::BadRow {
            path: path.to_path_buf(),
            row,
            reason,
        },
    }
}

/// 1-based line numbers of csv records. The csv crate positions a record
/// where its reader started, before any blank lines it skipped; this counts
/// from the record's first byte instead. Offsets must be asked for in
/// increasing order (they are: records come in file order).
struct LineCounter<'a> {
    input: &'a [u8],
    offset: usize,
    line: usize,
}

impl<'a> LineCounter<'a> {
    fn new(input: &'a [u8]) -> Self {
        Self {
            input,
            offset: 0,
            line: 1,
        }
    }

    fn line_at(&mut self, byte: u64) -> usize {
        let mut target = usize::try_from(byte)
            .unwrap_or(usize::MAX)
            .min(self.input.len());
        // Skip the blank lines the csv reader skipped.
        while matches!(self.input.get(target), Some(b'\n' | b'\r')) {
            target += 1;
        }
        if target >= self.offset {
            let skipped = &self.input[self.offset..target];
            self.line += skipped.iter().filter(|&&b| b == b'\n').count();
            self.offset = target;
        }
        self.line
    }
}

/// A path from `frames.csv`, checked to stay inside the recording directory
/// and normalised (`.` dropped, `a/../b` folded).
fn relative_path(value: &str) -> Result<PathBuf, &'static str> {
    if value.is_empty() {
        return Err("is empty");
    }
    let mut normal: Vec<&std::ffi::OsStr> = Vec::new();
    for component in Path::new(value).components() {
        match component {
            Component::Prefix(_) | Component::RootDir => {
                return Err("is absolute; paths must be relative to the recording directory")
            }
            Component::CurDir => {}
            Component::ParentDir => {
                if normal.pop().is_none() {
                    return Err("leaves the recording directory");
                }
            }
            Component::Normal(part) => normal.push(part),
        }
    }
    if normal.is_empty() {
        return Err("names the recording directory itself, not a file");
    }
    Ok(normal.iter().collect())
}

/// What an image in a recording must be.
#[derive(Debug, Clone, Copy)]
enum PixelFormat {
    /// 16-bit single-channel.
    Depth,
    /// 8-bit RGB.
    Color,
}

impl PixelFormat {
    fn png(self) -> (ColorType, BitDepth) {
        match self {
            Self::Depth => (ColorType::Grayscale, BitDepth::Sixteen),
            Self::Color => (ColorType::Rgb, BitDepth::Eight),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::Depth => "16-bit Grayscale",
            Self::Color => "8-bit Rgb",
        }
    }

    fn describe(color: ColorType, depth: BitDepth) -> String {
        format!("{}-bit {color:?}", depth as u8)
    }
}

struct ImageContext<'a> {
    row: usize,
    image: &'a Path,
}

impl ImageContext<'_> {
    /// Failures after the file opened (truncation included) are decoding
    /// failures.
    fn decode_error(&self, source: png::DecodingError) -> RecordingError {
        RecordingError::ImageDecode {
            row: self.row,
            image: self.image.to_path_buf(),
            source,
        }
    }

    fn read_error(&self, source: io::Error) -> RecordingError {
        RecordingError::ImageRead {
            row: self.row,
            image: self.image.to_path_buf(),
            source,
        }
    }
}

/// Decodes the PNG at `ctx.image`, checks its format and size against
/// `meta`, and hands the pixel bytes (big-endian samples, row-major) to
/// `sink` in order.
fn decode_png(
    ctx: &ImageContext<'_>,
    meta: &RecordingMeta,
    format: PixelFormat,
    mut sink: impl FnMut(&[u8]),
) -> Result<(), RecordingError> {
    let file = open_regular(ctx.image).map_err(|e| ctx.read_error(e))?;
    let decoder = png::Decoder::new(BufReader::new(file));
    let mut reader = decoder.read_info().map_err(|e| ctx.decode_error(e))?;

    let info = reader.info();
    let found = (info.color_type, info.bit_depth);
    let expected = format.png();
    if found != expected {
        return Err(RecordingError::ImageFormat {
            row: ctx.row,
            image: ctx.image.to_path_buf(),
            expected: format.name(),
            found: PixelFormat::describe(found.0, found.1),
        });
    }
    let (width, height) = (meta.depth.width, meta.depth.height);
    if (info.width, info.height) != (width, height) {
        return Err(RecordingError::ImageSize {
            row: ctx.row,
            image: ctx.image.to_path_buf(),
            width,
            height,
            found_width: info.width,
            found_height: info.height,
        });
    }

    if info.interlaced {
        // Adam7 rows arrive in passes; decode the whole frame, then hand it on.
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| ctx.decode_error(png::DecodingError::LimitsExceeded))?;
        let mut buffer = vec![0; size];
        reader
            .next_frame(&mut buffer)
            .map_err(|e| ctx.decode_error(e))?;
        sink(&buffer);
    } else {
        while let Some(row) = reader.next_row().map_err(|e| ctx.decode_error(e))? {
            sink(row.data());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_stay_inside_the_recording() {
        assert_eq!(
            relative_path("depth/000000.png"),
            Ok(PathBuf::from("depth/000000.png"))
        );
        assert_eq!(
            relative_path("./depth/../depth/1.png"),
            Ok(PathBuf::from("depth/1.png"))
        );
        assert!(relative_path("").is_err());
        assert!(relative_path("/etc/passwd").is_err());
        assert!(relative_path("../other/depth/0.png").is_err());
        assert!(relative_path("depth/../../x.png").is_err());
        assert!(relative_path("depth/..").is_err());
    }

    #[test]
    fn rows_carry_their_line_numbers_and_optional_cells() {
        let text = "index,timestamp_ns,depth,color,slope_deg\n\
                    0,0,depth/000000.png,color/000000.png,12.5\n\
                    \n\
                    3,33333333,depth/000003.png,,\n";
        let frames = parse_frames(text.as_bytes(), Path::new("frames.csv")).unwrap();
        assert_eq!(
            frames,
            vec![
                FrameEntry {
                    index: 0,
                    timestamp_ns: 0,
                    depth: "depth/000000.png".into(),
                    color: Some("color/000000.png".into()),
                    slope_deg: Some(12.5),
                    row: 2,
                },
                FrameEntry {
                    index: 3,
                    timestamp_ns: 33_333_333,
                    depth: "depth/000003.png".into(),
                    color: None,
                    slope_deg: None,
                    row: 4,
                },
            ]
        );
    }

    #[test]
    fn line_numbers_count_blank_lines_and_crlf() {
        let text = "index,timestamp_ns,depth,color\r\n\r\n0,0,d/0.png,\r\n\r\n\r\n1,5,d/1.png,\r\n\n2,1,d/2.png,\r\n";
        let err = parse_frames(text.as_bytes(), Path::new("frames.csv")).unwrap_err();
        // Rows sit on lines 3, 6 and 8; the third goes back in time.
        assert!(
            matches!(
                err,
                RecordingError::DecreasingTimestamp {
                    row: 8,
                    timestamp_ns: 1,
                    previous: 5,
                    ..
                }
            ),
            "{err}"
        );
        let ok = text.replace("2,1,", "2,9,");
        let frames = parse_frames(ok.as_bytes(), Path::new("frames.csv")).unwrap();
        let rows: Vec<usize> = frames.iter().map(|f| f.row).collect();
        assert_eq!(rows, [3, 6, 8]);
    }

    #[test]
    fn columns_are_found_by_name_and_extra_columns_ignored() {
        let text = "depth,exposure_us,timestamp_ns,index\ndepth/a.png,100,5,7\n";
        let frames = parse_frames(text.as_bytes(), Path::new("frames.csv")).unwrap();
        assert_eq!(frames.len(), 1);
        assert_eq!((frames[0].index, frames[0].timestamp_ns), (7, 5));
        assert_eq!(frames[0].color, None);
    }

    /// A duplicate `depth` column was read as its first one without a word.
    #[test]
    fn a_column_named_twice_is_refused() {
        let text = "index,timestamp_ns,depth,depth\n0,0,depth/0.png,depth/1.png\n";
        let err = parse_frames(text.as_bytes(), Path::new("frames.csv")).unwrap_err();
        assert!(
            matches!(&err, RecordingError::BadRow { row: 1, reason, .. }
                if reason.contains("`depth` twice")),
            "{err}"
        );
    }

    #[test]
    fn an_empty_file_lacks_the_index_column() {
        let err = parse_frames(b"", Path::new("frames.csv")).unwrap_err();
        assert!(
            matches!(
                &err,
                RecordingError::MissingColumn {
                    column: "index",
                    ..
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn invalid_utf8_names_the_row() {
        let text = b"index,timestamp_ns,depth,color\n0,0,depth/0.png,\n1,1,depth/\xff.png,\n";
        let err = parse_frames(text, Path::new("frames.csv")).unwrap_err();
        assert!(
            matches!(err, RecordingError::BadRow { row: 3, .. }),
            "{err}"
        );
    }
}
