//! A minimal reader of slope recordings (recording.toml, frames.csv, 16-bit
//! depth PNGs) for the pipeline's tests and examples. The real reader is
//! `slope_sensor::recording`, which the pipeline may not depend on.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use slope_ipc_types::{CloudPoint, Intrinsics, Mount};
use slope_pipeline::CloudView;

/// One recording's metadata.
#[derive(Debug, Clone)]
pub struct Recording {
    pub dir: PathBuf,
    pub width: usize,
    pub height: usize,
    pub unit_m: f64,
    pub intrinsics: Intrinsics,
    pub mount: Mount,
    pub truth_slope_deg: Option<f64>,
    pub depth_files: Vec<PathBuf>,
}

/// A projected frame.
#[derive(Debug, Clone)]
pub struct Frame {
    pub points: Vec<CloudPoint>,
    pub width: usize,
    pub height: usize,
    pub intrinsics: Intrinsics,
    pub mount: Mount,
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

fn key(table: &toml::Table, section: &str, name: &str) -> Option<f64> {
    let v = table.get(section)?.get(name)?;
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
}

impl Recording {
    pub fn open(dir: &Path) -> Result<Self, String> {
        let meta = std::fs::read_to_string(dir.join("recording.toml"))
            .map_err(|e| format!("{}: {e}", dir.join("recording.toml").display()))?;
        let table: toml::Table = meta
            .parse()
            .map_err(|e| format!("{}: {e}", dir.display()))?;
        let need = |s: &str, k: &str| {
            key(&table, s, k).ok_or_else(|| format!("{}: missing [{s}] {k}", dir.display()))
        };
        let width = need("depth", "width")? as usize;
        let height = need("depth", "height")? as usize;
        let unit_m = key(&table, "depth", "unit_m").unwrap_or(0.001);
        let intrinsics = Intrinsics {
            fx: need("depth", "fx")?,
            fy: need("depth", "fy")?,
            cx: need("depth", "cx")?,
            cy: need("depth", "cy")?,
        };
        let mount = Mount {
            height_m: key(&table, "mount", "height_m").unwrap_or(f64::NAN),
            pitch_deg: key(&table, "mount", "pitch_deg").unwrap_or(f64::NAN),
            roll_deg: key(&table, "mount", "roll_deg").unwrap_or(f64::NAN),
        };
        let truth_slope_deg = key(&table, "truth", "slope_deg");
        let mut reader = csv::Reader::from_path(dir.join("frames.csv"))
            .map_err(|e| format!("{}: {e}", dir.display()))?;
        let headers = reader.headers().map_err(|e| e.to_string())?.clone();
        let depth_col = headers
            .iter()
            .position(|h| h == "depth")
            .ok_or("frames.csv has no depth column")?;
        let mut depth_files = Vec::new();
        for row in reader.records() {
            let row = row.map_err(|e| e.to_string())?;
            depth_files.push(dir.join(row.get(depth_col).ok_or("short row")?));
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            width,
            height,
            unit_m,
            intrinsics,
            mount,
            truth_slope_deg,
            depth_files,
        })
    }

    /// Decodes and projects frame `k`.
    pub fn frame(&self, k: usize) -> Result<Frame, String> {
        let path = self.depth_files.get(k).ok_or("no such frame")?;
        let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
        decoder.set_transformations(png::Transformations::IDENTITY);
        let mut reader = decoder
            .read_info()
            .map_err(|e| format!("{}: {e}", path.display()))?;
        let size = reader.output_buffer_size().ok_or("png too large")?;
        let mut buf = vec![0u8; size];
        let info = reader
            .next_frame(&mut buf)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        if info.width as usize != self.width
            || info.height as usize != self.height
            || info.bit_depth != png::BitDepth::Sixteen
        {
            return Err(format!(
                "{}: not a {}x{} 16-bit image",
                path.display(),
                self.width,
                self.height
            ));
        }
        let Intrinsics { fx, fy, cx, cy } = self.intrinsics;
        let mut points = Vec::with_capacity(self.width * self.height);
        for v in 0..self.height {
            for u in 0..self.width {
                let i = 2 * (v * self.width + u);
                let raw = u16::from_be_bytes([buf[i], buf[i + 1]]);
                points.push(if raw == 0 {
                    CloudPoint::INVALID
                } else {
                    let z = f64::from(raw) * self.unit_m;
                    CloudPoint {
                        x_m: ((u as f64 - cx) * z / fx) as f32,
                        y_m: ((v as f64 - cy) * z / fy) as f32,
                        z_m: z as f32,
                        rgb: 0,
                    }
                });
            }
        }
        Ok(Frame {
            points,
            width: self.width,
            height: self.height,
            intrinsics: self.intrinsics,
            mount: self.mount,
        })
    }
}

/// `pipeline/../../shared/data/<name>`, or `None` (with a note) when absent.
pub fn shared_data(name: &str) -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data")
        .join(name);
    if dir.join("recording.toml").is_file() {
        Some(dir)
    } else {
        println!("note: {} is absent, skipping", dir.display());
        None
    }
}
