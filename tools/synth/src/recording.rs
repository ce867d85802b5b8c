//! Writing a simulated recording: per-frame camera poses (forward motion
//! and vibration), rendering, and the recording directory through
//! `slope_sensor::recording::RecordingWriter`.
//!
//! Determinism: frame `k` draws all its randomness (pose jitter, then the
//! sensor effects pixel by pixel in row-major order) from a ChaCha8 stream
//! keyed by `(seed, k)`, so the same seed gives the same bytes, and any
//! frame can be rendered on its own.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use slope_sensor::recording::{
    ColorImage, DepthImage, DepthInfo, MountInfo, PngCompression, RecordingError, RecordingMeta,
    RecordingWriter, TruthInfo,
};

use crate::camera::{Camera, CameraPose};
use crate::error::WriteError;
use crate::raycast::raycast;
use crate::render::{render_depth, DEPTH_UNIT_M};
use crate::scene::Scene;
use crate::sensor_model::SensorModel;
use crate::shading::shade;
use crate::world::World;

/// Time between frames: 30 Hz, like the Kinect v2.
pub const FRAME_INTERVAL_NS: u64 = 33_333_333;

/// The `sensor` string of synthetic recordings.
pub const SENSOR_NAME: &str = "synthetic";

/// How to write a recording, beyond what is rendered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WriteOptions {
    /// Also write the shaded colour image of every frame.
    pub color: bool,
    pub compression: PngCompression,
}

impl Default for WriteOptions {
    fn default() -> Self {
        Self {
            color: true,
            compression: PngCompression::Balanced,
        }
    }
}

/// What [`write_recording`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingSummary {
    pub dir: PathBuf,
    /// Frames written (fewer than asked for when stopped early).
    pub frames: u64,
    /// Frames asked for.
    pub frames_asked: u64,
    /// Fraction of pixels with a depth reading, over the frames written.
    pub valid_fraction: f64,
}

impl RecordingSummary {
    /// True when the writing stopped before every frame asked for was written.
    pub fn is_partial(&self) -> bool {
        self.frames < self.frames_asked
    }
}

/// The random stream of frame `index` of a recording made with `seed`.
pub fn frame_rng(seed: u64, index: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index);
    rng
}

/// Time of frame `index` since the start of the recording.
pub fn frame_timestamp_ns(index: u64) -> u64 {
    index.saturating_mul(FRAME_INTERVAL_NS)
}

/// Forward position of the camera in frame `index`, metres.
pub fn frame_forward_m(scene: &Scene, index: u64) -> f64 {
    // Frame counts are far below 2^53, so the conversion is exact.
    scene.motion.speed_mps * (index as f64) * (FRAME_INTERVAL_NS as f64) * 1e-9
}

/// The camera of frame `index`: the nominal mount moved forward by the
/// scene's motion, plus the model's pose jitter drawn from `rng`.
pub fn frame_camera<R: Rng + ?Sized>(
    scene: &Scene,
    model: &SensorModel,
    index: u64,
    rng: &mut R,
) -> Camera {
    let m = &scene.mount;
    let mut jitter = |sigma: f64| -> f64 {
        if sigma > 0.0 {
            sigma * rng.sample::<f64, _>(StandardNormal)
        } else {
            0.0
        }
    };
    let pitch = m.pitch_deg + jitter(model.jitter_pitch_deg);
    let roll = m.roll_deg + jitter(model.jitter_roll_deg);
    let yaw = jitter(model.jitter_yaw_deg);
    let height = m.height_m + jitter(model.jitter_height_m);
    Camera {
        model: scene.camera,
        pose: CameraPose::new(height, pitch, roll, yaw, frame_forward_m(scene, index)),
    }
}

/// The metadata of a recording of `scene`: the nominal mount (without
/// jitter; none when `[mount] recorded = false`) and the exact slope.
pub fn recording_meta(scene: &Scene) -> RecordingMeta {
    let c = &scene.camera;
    RecordingMeta {
        sensor: SENSOR_NAME.to_string(),
        depth: DepthInfo {
            width: c.width,
            height: c.height,
            unit_m: DEPTH_UNIT_M,
            fx: c.fx,
            fy: c.fy,
            cx: c.cx,
            cy: c.cy,
        },
        mount: if scene.mount.recorded {
            MountInfo {
                height_m: Some(scene.mount.height_m),
                pitch_deg: Some(scene.mount.pitch_deg),
                roll_deg: Some(scene.mount.roll_deg),
            }
        } else {
            MountInfo::default()
        },
        truth: TruthInfo {
            slope_deg: scene.truth_slope_deg(),
        },
    }
}

/// Renders `frames` frames of `scene` through `model` and writes them as a
/// recording to `out_dir` (which must not exist or be empty), with colour
/// and the default PNG compression.
pub fn write_recording(
    scene: &Scene,
    model: &SensorModel,
    frames: u64,
    seed: u64,
    out_dir: &Path,
) -> Result<RecordingSummary, WriteError> {
    write_recording_with(
        scene,
        model,
        frames,
        seed,
        out_dir,
        WriteOptions::default(),
        |_| ControlFlow::Continue(()),
    )
}

/// [`write_recording`] with options, calling `on_frame(index)` after each
/// frame is on disk (for progress bars). When `on_frame` returns
/// `ControlFlow::Break`, no further frame is rendered: the recording holds
/// the frames written so far (recording.toml, and a frames.csv row for
/// every depth image) and is as valid as a complete one.
pub fn write_recording_with(
    scene: &Scene,
    model: &SensorModel,
    frames: u64,
    seed: u64,
    out_dir: &Path,
    options: WriteOptions,
    on_frame: impl FnMut(u64) -> ControlFlow<()>,
) -> Result<RecordingSummary, WriteError> {
    let world = prepare_world(scene, model, frames)?;
    let meta = recording_meta(scene);
    let mut writer =
        RecordingWriter::create(out_dir, &meta, false).map_err(recording_error(out_dir))?;
    writer.set_compression(options.compression);
    tracing::info!(
        dir = %out_dir.display(),
        frames,
        seed,
        clean = model.is_clean(),
        truth_slope_deg = ?meta.truth.slope_deg,
        "rendering recording"
    );

    let started = Instant::now();
    let renderer = FrameRenderer {
        scene,
        model,
        world: &world,
        seed,
        color: options.color,
    };
    let counts = write_frames(&renderer, frames, &mut writer, out_dir, on_frame)?;
    let dir = writer.finish().map_err(recording_error(out_dir))?;
    Ok(summarise(scene, dir, frames, counts, started))
}

/// Checks the scene, the sensor model and the frame count, and that the
/// camera's nominal path stays outside every object; returns the world to
/// render.
fn prepare_world(scene: &Scene, model: &SensorModel, frames: u64) -> Result<World, WriteError> {
    scene.validate()?;
    model.validate()?;
    if frames == 0 {
        return Err(WriteError::NoFrames);
    }
    let world = World::build(scene);
    for index in 0..frames {
        let nominal = Camera {
            model: scene.camera,
            pose: CameraPose::new(
                scene.mount.height_m,
                0.0,
                0.0,
                0.0,
                frame_forward_m(scene, index),
            ),
        };
        if world.contains(&nominal.pose.position) {
            return Err(WriteError::CameraInsideGeometry {
                frame: index,
                y_m: nominal.pose.position.y,
            });
        }
    }
    Ok(world)
}

/// [`WriteError::Recording`] for the recording in `dir`.
fn recording_error(dir: &Path) -> impl Fn(RecordingError) -> WriteError + '_ {
    move |source| WriteError::Recording {
        dir: dir.to_path_buf(),
        source,
    }
}

/// What renders the frames of one recording.
struct FrameRenderer<'a> {
    scene: &'a Scene,
    model: &'a SensorModel,
    world: &'a World,
    seed: u64,
    /// Also shade a colour image.
    color: bool,
}

impl FrameRenderer<'_> {
    /// Frame `index`: its depth image and, if asked for, its colour image;
    /// an error if the camera's jittered pose falls inside an object.
    fn render(&self, index: u64) -> Result<(DepthImage, Option<ColorImage>), WriteError> {
        let mut rng = frame_rng(self.seed, index);
        let camera = frame_camera(self.scene, self.model, index, &mut rng);
        if self.world.contains(&camera.pose.position) {
            return Err(WriteError::CameraInsideGeometry {
                frame: index,
                y_m: camera.pose.position.y,
            });
        }
        let geometry = raycast(self.world, &camera);
        let depth = render_depth(&geometry, self.world, self.model, &camera, &mut rng);
        let color = self.color.then(|| shade(&geometry));
        Ok((depth, color))
    }
}

/// Frames written and depth readings among them.
#[derive(Debug, Clone, Copy)]
struct FrameCounts {
    written: u64,
    valid_pixels: u64,
}

/// Renders and writes frames 0, 1, ... up to `frames`, calling
/// `on_frame(index)` after each and stopping early when it breaks.
fn write_frames(
    renderer: &FrameRenderer<'_>,
    frames: u64,
    writer: &mut RecordingWriter,
    out_dir: &Path,
    mut on_frame: impl FnMut(u64) -> ControlFlow<()>,
) -> Result<FrameCounts, WriteError> {
    let mut counts = FrameCounts {
        written: 0,
        valid_pixels: 0,
    };
    for index in 0..frames {
        let (depth, color) = renderer.render(index)?;
        let frame_valid = depth.data.iter().filter(|&&d| d != 0).count();
        counts.valid_pixels += frame_valid as u64;
        writer
            .write_frame(frame_timestamp_ns(index), &depth, color.as_ref(), None)
            .map_err(recording_error(out_dir))?;
        tracing::debug!(frame = index, valid_pixels = frame_valid, "frame written");
        counts.written += 1;
        if on_frame(index).is_break() {
            break;
        }
    }
    Ok(counts)
}

/// The summary of a written recording (logged): frames, the fraction of
/// pixels with a depth reading, the time per frame since `started`.
fn summarise(
    scene: &Scene,
    dir: PathBuf,
    frames_asked: u64,
    counts: FrameCounts,
    started: Instant,
) -> RecordingSummary {
    let written = counts.written;
    // `written` is at least 1: the loop runs for frame 0 and counts it
    // before it can stop.
    let pixels = written as f64 * f64::from(scene.camera.width) * f64::from(scene.camera.height);
    let valid_fraction = counts.valid_pixels as f64 / pixels;
    let elapsed = started.elapsed().as_secs_f64();
    tracing::info!(
        frames = written,
        valid_fraction = format!("{valid_fraction:.3}"),
        seconds_per_frame = format!("{:.3}", elapsed / written as f64),
        "recording written"
    );
    RecordingSummary {
        dir,
        frames: written,
        frames_asked,
        valid_fraction,
    }
}
