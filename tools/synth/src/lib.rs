//! `slope-synth`: a Kinect v2 scene simulator. It ray-casts scenes (ground,
//! an ascending or descending inclined plane with an optional landing, side
//! walls, boxes, tables, a ceiling, soft blocks with bumpy faces, panels) through a
//! pinhole depth camera, applies a sensor model (axial and lateral noise,
//! flying pixels, multipath, dropouts, range limits, quantisation, pose
//! jitter) and writes recordings in the format of
//! `shared/spec/recording-format.md` with exact ground truth.
//!
//! Files, lowest first:
//! - `geometry.rs`: half-spaces, convex solids, exact ray/solid intersection.
//! - `bump_field.rs`: smooth random bumps (a sum of plane waves) on a face.
//! - `soft_solid.rs`: a box with bumpy top and sides, and its ray march.
//! - `scene.rs`: the scene description (TOML scene files); the clutter
//!   objects (tables, ceiling, soft blocks) in `scene/clutter.rs`, panels
//!   in `scene/panel.rs`.
//! - `world.rs`: a scene turned into solids and concave junctions; one file
//!   per kind of clutter under `world/`.
//! - `camera.rs`: camera pose (mount convention) and pixel rays.
//! - `raycast.rs`: the exact geometry of one view.
//! - `sensor_model.rs`: the error model's parameters and formulas.
//! - `render.rs`: the sensor model applied to a view: a depth image.
//! - `shading.rs`: a colour image registered to the depth image.
//! - `recording.rs`: frames, poses, seeds and the recording on disk.
//! - `cli.rs`: the command line and [`run`].
//! - `bend/`: real frames' floors bent into ramps of known angle
//!   ([`bend::bend_floor`], the program `slope-bend`).
//!
//! ```no_run
//! use slope_synth::{write_recording, Scene, SensorModel};
//! let scene = Scene::default_ramp();
//! write_recording(&scene, &SensorModel::default(), 30, 7, "/tmp/ramp16".as_ref())?;
//! # Ok::<(), slope_synth::WriteError>(())
//! ```

pub mod bend;
pub mod bump_field;
pub mod camera;
pub mod cli;
pub mod error;
pub mod geometry;
pub mod raycast;
pub mod recording;
pub mod render;
pub mod scene;
pub mod sensor_model;
pub mod shading;
pub mod soft_solid;
pub mod world;

pub use camera::{Camera, CameraPose};
pub use cli::{run, Args};
pub use error::{BendError, SceneError, WriteError};
pub use geometry::{BoxFace, Surface, SurfaceKind};
pub use raycast::{raycast, GeometryImage, PixelHit};
pub use recording::{
    frame_camera, frame_rng, recording_meta, write_recording, write_recording_with,
    RecordingSummary, WriteOptions, FRAME_INTERVAL_NS,
};
pub use render::{quantise, render_depth, render_frame, DEPTH_UNIT_M};
pub use scene::{
    load_scene_file, parse_scene, CameraModel, Ceiling, GroundBox, Motion, MountPose, Panel, Ramp,
    Scene, SceneFile, SideWall, SlopeDirection, SoftBlock, Table,
};
pub use sensor_model::{axial_sigma_m, RangeBias, SensorModel};
pub use world::World;
