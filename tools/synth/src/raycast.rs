//! The exact geometry a posed camera sees: for every pixel centre, the first
//! surface its ray meets, the depth along the optical axis and the angle of
//! incidence. No sensor effects here; `render` adds them.

use crate::camera::Camera;
use crate::geometry::{Hit, Pos3, Ray, Surface, Vec3};
use crate::world::World;

/// What the ray through one pixel meets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelHit {
    /// Depth along the optical axis, metres.
    pub z_m: f64,
    /// The surface hit.
    pub surface: Surface,
    /// Outward unit normal of that surface, world coordinates.
    pub normal: Vec3,
    /// The hit point, world coordinates.
    pub point: Pos3,
    /// Cosine of the angle between the ray and the surface normal (1 =
    /// head-on, 0 = grazing).
    pub cos_incidence: f64,
}

impl PixelHit {
    /// Builds the pixel's view of a ray hit.
    pub fn from_hit(ray: &Ray, hit: &Hit) -> Self {
        let cos_incidence = (hit.normal.dot(&ray.direction).abs() / ray.direction.norm()).min(1.0);
        Self {
            z_m: hit.t,
            surface: hit.surface,
            normal: hit.normal,
            point: ray.at(hit.t),
            cos_incidence,
        }
    }

    /// Angle between the ray and the surface normal, radians.
    pub fn incidence_rad(&self) -> f64 {
        self.cos_incidence.acos()
    }
}

/// The exact geometry of one view: one entry per pixel, row-major; `None`
/// where the ray meets nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct GeometryImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Option<PixelHit>>,
}

impl GeometryImage {
    /// The pixel at column `u`, row `v` (`None` outside the image or
    /// where nothing was hit).
    pub fn get(&self, u: u32, v: u32) -> Option<&PixelHit> {
        if u >= self.width || v >= self.height {
            return None;
        }
        self.pixels
            .get(v as usize * self.width as usize + u as usize)
            .and_then(Option::as_ref)
    }
}

/// The first hit of one camera ray through image position (u, v).
pub fn cast_pixel(world: &World, camera: &Camera, u: f64, v: f64) -> Option<PixelHit> {
    let ray = camera.ray(u, v);
    world.cast(&ray).map(|hit| PixelHit::from_hit(&ray, &hit))
}

/// Casts the ray through every pixel centre.
pub fn raycast(world: &World, camera: &Camera) -> GeometryImage {
    let (width, height) = (camera.model.width, camera.model.height);
    let mut pixels = Vec::with_capacity(width as usize * height as usize);
    for v in 0..height {
        for u in 0..width {
            pixels.push(cast_pixel(world, camera, f64::from(u), f64::from(v)));
        }
    }
    GeometryImage {
        width,
        height,
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraPose;
    use crate::geometry::SurfaceKind;
    use crate::scene::{CameraModel, Scene};

    #[test]
    fn flat_ground_depth_matches_closed_form() {
        // Camera h above the ground with pitch p: the ray through row v hits
        // the ground at depth z = h / (-up . d) with d = ((u-cx)/fx, (v-cy)/fy, 1).
        let scene = Scene::default();
        let world = World::build(&scene);
        let pose = CameraPose::new(0.7, -25.0, 3.0, 0.0, 0.0);
        let camera = Camera {
            model: CameraModel::KINECT2,
            pose,
        };
        let geometry = raycast(&world, &camera);
        let up = pose.up_in_camera();
        let m = CameraModel::KINECT2;
        let mut checked = 0;
        for v in (0..m.height).step_by(7) {
            for u in (0..m.width).step_by(11) {
                let d = Vec3::new(
                    (f64::from(u) - m.cx) / m.fx,
                    (f64::from(v) - m.cy) / m.fy,
                    1.0,
                );
                let down = -up.dot(&d);
                match geometry.get(u, v) {
                    Some(hit) => {
                        assert!(down > 0.0);
                        assert!((hit.z_m - 0.7 / down).abs() < 1e-9 * hit.z_m);
                        assert_eq!(hit.surface.kind, SurfaceKind::Ground);
                        checked += 1;
                    }
                    None => assert!(down <= 0.0, "missed the ground at ({u}, {v})"),
                }
            }
        }
        assert!(checked > 1000);
    }

    #[test]
    fn default_scene_shows_large_ground_and_ramp_areas() {
        let scene = Scene::default_ramp();
        let world = World::build(&scene);
        let m = &scene.mount;
        let camera = Camera {
            model: scene.camera,
            pose: CameraPose::new(m.height_m, m.pitch_deg, m.roll_deg, 0.0, 0.0),
        };
        let geometry = raycast(&world, &camera);
        let count = |kind| {
            geometry
                .pixels
                .iter()
                .flatten()
                .filter(|p| p.surface.kind == kind && p.z_m < 4.5)
                .count()
        };
        let total = geometry.pixels.len();
        let ground = count(SurfaceKind::Ground);
        let ramp = count(SurfaceKind::Ramp);
        assert!(ground > total / 4, "ground {ground} of {total}");
        assert!(ramp > total / 5, "ramp {ramp} of {total}");
    }
}
