//! What `slope-eval` writes besides its report, frame by frame: the overlay
//! picture (`--render`, `--render-every`) and the labelled cloud
//! (`--export-ply`) of the frames asked for, each method separately.
//!
//! [`Snapshot`] is what one estimator saw of one frame; [`overlay_of`] and
//! [`caption_lines`] are pure, [`Artifacts::write`] does the I/O.

use std::path::{Path, PathBuf};

use anyhow::Context;
use slope_ipc_types::{CloudPoint, EstimateStatus, Intrinsics, SurfaceRole};
use slope_pipeline::selection::{RoadScene, Surface};
use slope_pipeline::{Estimate, Inspection};
use slope_sensor::recording::ColorImage;

use crate::overlay::{render_overlay, NormalDot, Overlay, Role, SurfacePixels};
use crate::overlay_marks::{boundary_pixels, corridor_segments};
use crate::ply::{write_labelled_cloud, LabelledCloud};
use crate::render::write_png;

/// One estimator's view of one frame.
#[derive(Debug, Clone, Copy)]
pub struct Snapshot<'a> {
    /// The recording as given on the command line.
    pub recording: &'a str,
    /// File-name stem for this recording.
    pub name: &'a str,
    /// The frame's index in frames.csv.
    pub index: u64,
    pub points: &'a [CloudPoint],
    pub width: u32,
    pub height: u32,
    /// The depth camera's, to project the corridor.
    pub intrinsics: Intrinsics,
    pub estimate: &'a Estimate,
    pub inspection: Inspection<'a>,
    pub truth_deg: Option<f64>,
}

impl Snapshot<'_> {
    /// The role of segmented plane `k`.
    pub fn role(&self, k: usize) -> Role {
        if self.inspection.inclined == Some(k) {
            Role::Inclined
        } else if self.inspection.ground.contains(&k) || self.ground_planes().contains(&k) {
            Role::Ground
        } else {
            Role::Other
        }
    }

    /// The planes of the ground's surface: its segments and the floor
    /// pieces joined to it (none without a scene).
    fn ground_planes(&self) -> &[usize] {
        self.estimate
            .scene
            .as_ref()
            .map_or(&[], |scene| scene.ground_planes.as_slice())
    }

    /// The file name of an artifact with `extension`.
    fn file_name(&self, extension: &str) -> String {
        format!(
            "{}-{}-frame{:06}.{extension}",
            self.name,
            self.estimate.method.name(),
            self.index
        )
    }
}

/// The caption of a snapshot's overlay: what, then the result.
pub fn caption_lines(s: &Snapshot<'_>) -> Vec<String> {
    let e = s.estimate;
    let mut lines = vec![format!(
        "{} · frame {} · {} · {}",
        s.recording,
        s.index,
        e.method.name(),
        e.status.name()
    )];
    let truth = s
        .truth_deg
        .map(|t| format!(" · truth {t:.1}°"))
        .unwrap_or_default();
    if e.status == EstimateStatus::Ok {
        let spread = if e.slope_std_deg.is_finite() {
            format!(" ± {:.2}°", e.slope_std_deg)
        } else {
            String::new()
        };
        let reasons: Vec<_> = slope_ipc_types::confidence::names(e.confidence_reasons).collect();
        let reasons = if reasons.is_empty() {
            String::new()
        } else {
            format!(" ({})", reasons.join(", "))
        };
        let tracked = e
            .tracked
            .as_ref()
            .filter(|t| t.slope_deg.is_finite())
            .map(|t| format!(" · tracked {:+.2}°", t.slope_deg))
            .unwrap_or_default();
        lines.push(format!(
            "slope {:+.2}°{spread} · confidence {:.2}{reasons}{tracked}{truth}",
            e.slope_deg, e.confidence
        ));
    } else {
        let ground = e
            .ground
            .as_ref()
            .map(|g| format!(" · ground {:.2} m below", g.coefficients[3]))
            .unwrap_or_default();
        lines.push(format!("no slope: {}{ground}{truth}", e.status.name()));
    }
    lines
}

/// The overlay picture of a snapshot: its surfaces by role, the road's
/// outline and the corridor when the estimator saw the scene, else its
/// planes unclassified.
pub fn overlay_of(s: &Snapshot<'_>) -> ColorImage {
    let dots: Vec<NormalDot> = s
        .inspection
        .normals
        .iter()
        .map(|n| NormalDot {
            pixel: n.pixel,
            kept: n.kept,
        })
        .collect();
    let (w, h) = (s.width as usize, s.height as usize);
    let (surfaces, road_outline, corridor) = match &s.estimate.scene {
        Some(scene) => {
            let surfaces: Vec<SurfacePixels<'_>> = scene
                .surfaces
                .iter()
                .map(|surface| surface_pixels(s, surface))
                .collect();
            let outline = scene
                .road
                .and_then(|r| surfaces.get(r.surface))
                .map(|road| boundary_pixels(&road.pixels, w, h))
                .unwrap_or_default();
            (surfaces, outline, corridor_of(s, scene))
        }
        None => {
            let planes = s.inspection.planes.iter().map(|p| SurfacePixels {
                pixels: vec![p.inliers.as_slice()],
                role: None,
                label: String::new(),
            });
            (planes.collect(), Vec::new(), Vec::new())
        }
    };
    render_overlay(&Overlay {
        points: s.points,
        width: s.width,
        height: s.height,
        surfaces,
        road_outline,
        corridor,
        normals: &dots,
        caption: caption_lines(s),
    })
}

/// A surface's pixels (the ground's: every segment's and floor piece's)
/// and its label: role and slope (the ground's slope, 0 by definition, is
/// left out).
fn surface_pixels<'a>(s: &Snapshot<'a>, surface: &Surface) -> SurfacePixels<'a> {
    let planes = s.inspection.planes;
    let indices: Vec<usize> = if surface.role == SurfaceRole::Ground && surface.segments > 1 {
        s.ground_planes().to_vec()
    } else {
        vec![surface.plane_index]
    };
    let label = if surface.role == SurfaceRole::Ground {
        surface.role.name().to_string()
    } else {
        format!("{} {:.1}°", surface.role.name(), surface.slope_deg)
    };
    SurfacePixels {
        pixels: indices
            .iter()
            .filter_map(|&k| planes.get(k))
            .map(|p| p.inliers.as_slice())
            .collect(),
        role: Some(surface.role),
        label,
    }
}

/// The corridor's edges from the nearest ground in view (the camera's
/// foot when no ground plane was seen) to the look-ahead.
fn corridor_of(s: &Snapshot<'_>, scene: &RoadScene) -> Vec<crate::overlay_marks::Segment> {
    let near = scene
        .surfaces
        .iter()
        .find(|x| x.role == SurfaceRole::Ground)
        .map(|g| g.distance_m)
        .filter(|d| d.is_finite())
        .unwrap_or(0.0);
    corridor_segments(
        &scene.frame,
        &s.intrinsics,
        (s.width, s.height),
        scene.corridor_half_width_m,
        (near, scene.look_ahead_m),
    )
}

/// Which frames get pictures and clouds, and where they go.
#[derive(Debug, Clone, Default)]
pub struct Artifacts {
    /// `--render DIR`.
    pub render_dir: Option<PathBuf>,
    /// `--export-ply DIR`.
    pub ply_dir: Option<PathBuf>,
    /// `--render-frame`: this frame only.
    pub frame: Option<u64>,
    /// `--render-every N`: every Nth evaluated frame (from the first).
    pub every: Option<u64>,
}

impl Artifacts {
    /// True when anything is written at all (the estimators then keep
    /// their sampled normals).
    pub fn enabled(&self) -> bool {
        self.render_dir.is_some() || self.ply_dir.is_some()
    }

    /// Whether the frame at `position` among the evaluated frames (index
    /// `index` in frames.csv, `count` frames evaluated) is written. Without
    /// `--render-frame` or `--render-every`: the middle one.
    pub fn wants(&self, position: usize, index: u64, count: usize) -> bool {
        if !self.enabled() {
            return false;
        }
        match (self.frame, self.every) {
            (Some(frame), _) => index == frame,
            (None, Some(every)) => (position as u64).is_multiple_of(every.max(1)),
            (None, None) => position == count / 2,
        }
    }

    /// Creates the output directories.
    pub fn prepare(&self) -> anyhow::Result<()> {
        for dir in [&self.render_dir, &self.ply_dir].into_iter().flatten() {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create the directory {}", dir.display()))?;
        }
        Ok(())
    }

    /// Writes the snapshot's overlay and cloud; returns the files written.
    pub fn write(&self, s: &Snapshot<'_>) -> anyhow::Result<Vec<PathBuf>> {
        let mut written = Vec::new();
        if let Some(dir) = &self.render_dir {
            let path = dir.join(s.file_name("png"));
            write_png(&path, &overlay_of(s))
                .with_context(|| format!("cannot render frame {} of {}", s.index, s.recording))?;
            written.push(path);
        }
        if let Some(dir) = &self.ply_dir {
            let path = dir.join(s.file_name("ply"));
            write_ply(&path, s)?;
            written.push(path);
        }
        Ok(written)
    }
}

/// The cloud of a snapshot with each point's plane, role and normal.
fn write_ply(path: &Path, s: &Snapshot<'_>) -> anyhow::Result<()> {
    let roles: Vec<Role> = (0..s.inspection.planes.len()).map(|k| s.role(k)).collect();
    let cloud = LabelledCloud {
        points: s.points,
        planes: s.inspection.planes,
        roles: &roles,
        normals: s.inspection.normals,
    };
    write_labelled_cloud(path, &cloud)
        .with_context(|| format!("cannot export frame {} of {}", s.index, s.recording))
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use nalgebra::Vector3;
    use slope_ipc_types::SlopeMethod;
    use slope_pipeline::{CloudView, Estimator, EstimatorConfig, FrameInfo};
    use slope_sensor::recording::{DepthImage, PngCompression, Recording};
    use slope_synth::{load_scene_file, write_recording_with, SensorModel, WriteOptions};

    use super::*;
    use crate::overlay::{tint_role, to_output, SCALE};
    use crate::render::{CORRIDOR_LINE, ROAD_OUTLINE};

    /// The bundled clean 16° ramp (foot 1.5 m ahead, 3 m wide; camera
    /// 0.5 m high, 20° down), frame 0, rendered as `slope-eval` does.
    fn ramp16_clean() -> (ColorImage, Estimate) {
        render_first_frame(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/recordings/ramp16-clean"),
        )
    }

    /// Frame 0 of the recording in `dir`, rendered as `slope-eval` does.
    fn render_first_frame(dir: &Path) -> (ColorImage, Estimate) {
        let recording = Recording::open(dir).expect("recording");
        let frame = recording.frames()[0].clone();
        let mut depth = DepthImage::default();
        recording
            .read_depth_into(&frame, &mut depth)
            .expect("depth");
        let projector = recording.projector();
        let mut points = vec![CloudPoint::INVALID; projector.len()];
        projector.project_into(&depth.data, None, &mut points);
        let (w, h) = (depth.width, depth.height);
        let view = CloudView {
            points: &points,
            width: w as usize,
            height: h as usize,
            intrinsics: recording.intrinsics(),
            mount: recording.mount(),
        };
        // Least squares: no sampled normals' dots over the surfaces.
        let mut estimator = Estimator::new(EstimatorConfig {
            method: SlopeMethod::LeastSquares,
            ..EstimatorConfig::default()
        });
        let estimate = estimator.estimate_frame(
            &view,
            FrameInfo {
                index: 0,
                stamp_ns: frame.timestamp_ns,
            },
        );
        let snapshot = Snapshot {
            recording: "ramp16-clean",
            name: "ramp16-clean",
            index: 0,
            points: &points,
            width: w,
            height: h,
            intrinsics: recording.intrinsics(),
            estimate: &estimate,
            inspection: estimator.inspection(),
            truth_deg: Some(16.0),
        };
        (overlay_of(&snapshot), estimate)
    }

    /// Share of the output pixels in depth rows `rows`, columns `cols`
    /// whose tint is `role`'s.
    fn share(image: &ColorImage, rows: (u32, u32), cols: (u32, u32), role: SurfaceRole) -> f64 {
        let (mut hit, mut all) = (0, 0);
        for v in rows.0 * SCALE..rows.1 * SCALE {
            for u in cols.0 * SCALE..cols.1 * SCALE {
                all += 1;
                hit += usize::from(image.get(u, v).and_then(tint_role) == Some(role));
            }
        }
        hit as f64 / all as f64
    }

    /// The ramp's pixels (rows above its foot line, v < 201.5 at the
    /// centre: the ray 18.4° down) are blue, the ground's red; the corridor
    /// lies on the lines the true camera projects (`up` = (0, -cos 20°,
    /// -sin 20°), 0.5 m above the ground) to 2 px; the road's outline runs
    /// along the ramp's foot.
    #[test]
    fn a_rendered_ramp_has_its_colours_corridor_and_outline_where_the_geometry_puts_them() {
        let (image, estimate) = ramp16_clean();
        let scene = estimate.scene.as_ref().expect("a scene");
        let road = scene.road_surface().expect("a road");
        assert_eq!(road.role, SurfaceRole::Ramp);
        // Rows 150..195 at the centre see the ramp (its top edge is off the
        // image's top at 16°: 4.5 m ahead, 1.4 m up), 230..420 the ground;
        // labels cover a few per cent.
        let ramp = share(&image, (150, 195), (180, 330), SurfaceRole::Ramp);
        let ground = share(&image, (230, 420), (20, 490), SurfaceRole::Ground);
        assert!(ramp > 0.9, "ramp share {ramp}");
        assert!(ground > 0.9, "ground share {ground}");
        // The corridor: ground points at lateral ±half width, projected
        // with the recording's intrinsics and the true pose.
        let t = 20f64.to_radians();
        let up = Vector3::new(0.0, -t.cos(), -t.sin());
        let forward = Vector3::new(0.0, -t.sin(), t.cos());
        let right = Vector3::new(1.0, 0.0, 0.0);
        let near = |x: f64, y: f64, colour: [u8; 3], r: i64| {
            (-r..=r).any(|dy| {
                (-r..=r).any(|dx| {
                    let (u, v) = (x.round() as i64 + dx, y.round() as i64 + dy);
                    u >= 0 && v >= 0 && image.get(u as u32, v as u32) == Some(colour)
                })
            })
        };
        let l = scene.corridor_half_width_m;
        for lateral in [-l, l] {
            for ahead in [0.7, 1.0, 1.3, 2.0, 3.0] {
                let p = forward * ahead + right * lateral - up * 0.5;
                let u = 365.0 * p.x / p.z + 255.5;
                let v = 365.0 * p.y / p.z + 211.5;
                let (x, y) = (to_output(u), to_output(v));
                assert!(
                    near(x, y, CORRIDOR_LINE, 2),
                    "no corridor within 2 px of ({x:.1}, {y:.1}) ({lateral} m, {ahead} m)"
                );
            }
        }
        // Away from the lines: none.
        assert!(!near(to_output(255.5), to_output(300.0), CORRIDOR_LINE, 6));
        // The outline along the foot (depth row 201.5 at every column the
        // ramp spans): within 3 depth rows of it at the centre, and long.
        assert!(near(to_output(255.5), to_output(201.5), ROAD_OUTLINE, 6));
        let outline = image.data.iter().filter(|&&p| p == ROAD_OUTLINE).count();
        assert!(outline > 2 * 512, "{outline} outline pixels");
    }

    /// The camera-frame point of world point `(x right, y ahead, z up)`
    /// for the synthetic camera 0.5 m high looking 20° down, projected
    /// into output pixels with the Kinect v2 intrinsics of the scenes.
    fn world_to_output(x: f64, y: f64, z: f64) -> (u32, u32) {
        let t = 20f64.to_radians();
        let up = Vector3::new(0.0, -t.cos(), -t.sin());
        let forward = Vector3::new(0.0, -t.sin(), t.cos());
        let p = Vector3::new(x, 0.0, 0.0) + forward * y + up * (z - 0.5);
        let u = 365.0 * p.x / p.z + 255.5;
        let v = 365.0 * p.y / p.z + 211.5;
        (to_output(u).round() as u32, to_output(v).round() as u32)
    }

    /// `slope-synth`'s ramp with a wall beside the path, one clean frame:
    /// the wall's pixels (near its upper left corner, away from its
    /// label) are brown, the ramp's (left of its centre line) blue, and
    /// the ramp is the road.
    #[test]
    fn a_synthetic_wall_beside_a_ramp_is_drawn_in_the_wall_colour() {
        let scene = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../synth/tests/scenes/ramp_wall_beside_path.toml");
        let scene = load_scene_file(&scene).expect("scene").scene;
        let dir = tempfile::tempdir().expect("temp dir");
        let options = WriteOptions {
            color: false,
            compression: PngCompression::Fast,
        };
        write_recording_with(
            &scene,
            &SensorModel::clean(),
            1,
            5,
            dir.path(),
            options,
            |_| std::ops::ControlFlow::Continue(()),
        )
        .expect("recording written");
        let (image, estimate) = render_first_frame(dir.path());
        let scene = estimate.scene.as_ref().expect("a scene");
        assert_eq!(
            scene.road_surface().map(|r| r.role),
            Some(SurfaceRole::Ramp)
        );
        let around = |(x, y): (u32, u32)| {
            let mut roles = Vec::new();
            for v in y - 4..=y + 4 {
                for u in x - 4..=x + 4 {
                    roles.push(image.get(u, v).and_then(tint_role));
                }
            }
            roles
        };
        // The wall's face: lower edge (0.60, 2.00) -> (1.37, 2.64), 0.7 m
        // high; a tenth along it, 0.6 m up.
        let wall = around(world_to_output(0.677, 2.064, 0.6));
        let walls = wall
            .iter()
            .filter(|r| **r == Some(SurfaceRole::Wall))
            .count();
        assert!(walls * 10 >= wall.len() * 9, "{wall:?}");
        // The ramp: foot at 2.2 m, rising 16°; 0.4 m left, 2.7 m ahead.
        let ramp = around(world_to_output(-0.4, 2.7, 0.5 * 16f64.to_radians().tan()));
        let ramps = ramp
            .iter()
            .filter(|r| **r == Some(SurfaceRole::Ramp))
            .count();
        assert!(ramps * 10 >= ramp.len() * 9, "{ramp:?}");
    }
}
