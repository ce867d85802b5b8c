//! Analytic test scenes shared by the unit tests, the integration tests and
//! the benches: planes ray-cast through a pinhole camera (Kinect v2
//! intrinsics by default) with Gaussian depth noise. Not part of the API.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slope_ipc_types::{CloudPoint, Intrinsics, Mount};

use crate::cloud::CloudView;

/// A bounded plane in world coordinates (X right, Y forward, Z up; the robot
/// stands at the origin on Z = 0).
#[derive(Debug, Clone, Copy)]
pub struct Surface {
    pub normal: Vector3<f64>,
    pub point: Vector3<f64>,
    pub min: Vector3<f64>,
    pub max: Vector3<f64>,
}

/// A camera pose and the surfaces it sees.
#[derive(Debug, Clone)]
pub struct Scene {
    pub camera_height_m: f64,
    pub pitch_deg: f64,
    pub roll_deg: f64,
    pub surfaces: Vec<Surface>,
    /// Signed slope of the inclined surface, degrees (+ uphill).
    pub truth_slope_deg: f64,
    /// Distance from the camera to the inclined surface along the optical
    /// axis, metres (NaN when the axis misses it).
    pub truth_distance_m: f64,
}

const BIG: f64 = 1e6;

/// Pass as `sigma_1m` for the Kinect v2 axial noise of Fankhauser et al.
/// (2015): `1.5 - 0.5 z + 0.3 z^2 + 0.1 z^1.5 t^2 / (pi/2 - t)^2` mm at depth
/// z and incidence t.
pub const KINECT2_NOISE: f64 = -1.0;

/// The Kinect v2 axial noise, metres.
pub fn kinect2_sigma_m(z: f64, incidence_rad: f64) -> f64 {
    let t = incidence_rad.clamp(0.0, 89f64.to_radians());
    let g = t * t / (std::f64::consts::FRAC_PI_2 - t).powi(2);
    (1.5 - 0.5 * z + 0.3 * z * z + 0.1 * z.powf(1.5) * g) * 1e-3
}

impl Scene {
    /// Flat ground up to 2 m ahead, then a ramp of `slope_deg` (negative:
    /// downhill; 90: a wall) seen from 0.5 m up, pitched 20 degrees down.
    pub fn ramp(slope_deg: f64) -> Self {
        Self::ramp_at(slope_deg, 2.0, 0.5, -20.0, 0.0)
    }

    /// As [`Scene::ramp`] with the ramp's foot at `foot_m` and the camera at
    /// `height_m`, `pitch_deg`, `roll_deg`.
    pub fn ramp_at(
        slope_deg: f64,
        foot_m: f64,
        height_m: f64,
        pitch_deg: f64,
        roll_deg: f64,
    ) -> Self {
        let t = slope_deg.to_radians();
        let ground = Surface {
            normal: Vector3::z(),
            point: Vector3::zeros(),
            min: Vector3::new(-BIG, -BIG, -BIG),
            max: Vector3::new(BIG, foot_m, BIG),
        };
        let ramp = Surface {
            normal: Vector3::new(0.0, -t.sin(), t.cos()),
            point: Vector3::new(0.0, foot_m, 0.0),
            min: Vector3::new(-BIG, foot_m, -BIG),
            max: Vector3::new(BIG, BIG, 4.0),
        };
        let mut scene = Self {
            camera_height_m: height_m,
            pitch_deg,
            roll_deg,
            surfaces: vec![ground, ramp],
            truth_slope_deg: slope_deg,
            truth_distance_m: f64::NAN,
        };
        scene.truth_distance_m = scene.axis_distance(&ramp);
        scene
    }

    /// [`Scene::ramp`] between two vertical side walls 0.8 m either side.
    pub fn ramp_between_walls(slope_deg: f64) -> Self {
        let mut scene = Self::ramp(slope_deg);
        for side in [-1.0, 1.0] {
            scene.surfaces.push(Surface {
                normal: Vector3::new(-side, 0.0, 0.0),
                point: Vector3::new(0.8 * side, 0.0, 0.0),
                min: Vector3::new(-BIG, 0.8, -BIG),
                max: Vector3::new(BIG, 6.0, 1.5),
            });
        }
        scene
    }

    /// A level camera facing a wall `distance_m` ahead, nothing else.
    pub fn wall_facing(distance_m: f64) -> Self {
        let wall = Surface {
            normal: -Vector3::y(),
            point: Vector3::new(0.0, distance_m, 0.0),
            min: Vector3::new(-BIG, -BIG, -BIG),
            max: Vector3::new(BIG, BIG, BIG),
        };
        Self {
            camera_height_m: 1.0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            surfaces: vec![wall],
            truth_slope_deg: 90.0,
            truth_distance_m: distance_m,
        }
    }

    /// Camera axes (x right, y down, z forward) in world coordinates.
    pub fn camera_axes(&self) -> [Vector3<f64>; 3] {
        let (sp, cp) = self.pitch_deg.to_radians().sin_cos();
        let (sr, cr) = self.roll_deg.to_radians().sin_cos();
        let x0 = Vector3::x();
        let y0 = Vector3::new(0.0, sp, -cp);
        let z = Vector3::new(0.0, cp, sp);
        [x0 * cr + y0 * sr, -x0 * sr + y0 * cr, z]
    }

    pub fn camera_centre(&self) -> Vector3<f64> {
        Vector3::new(0.0, 0.0, self.camera_height_m)
    }

    /// A world direction in camera coordinates.
    pub fn to_camera(&self, v: &Vector3<f64>) -> Vector3<f64> {
        let [x, y, z] = self.camera_axes();
        Vector3::new(v.dot(&x), v.dot(&y), v.dot(&z))
    }

    pub fn mount(&self) -> Mount {
        Mount {
            height_m: self.camera_height_m,
            pitch_deg: self.pitch_deg,
            roll_deg: self.roll_deg,
        }
    }

    /// Distance along the optical axis to the (unbounded) plane of `s`.
    fn axis_distance(&self, s: &Surface) -> f64 {
        let [_, _, z] = self.camera_axes();
        let denom = s.normal.dot(&z);
        if denom.abs() < 1e-12 {
            return f64::NAN;
        }
        let t = s.normal.dot(&(s.point - self.camera_centre())) / denom;
        if t > 0.0 {
            t
        } else {
            f64::NAN
        }
    }

    /// Ray parameter of the hit of `dir` (camera z component 1) on `s`.
    fn hit(&self, s: &Surface, dir: &Vector3<f64>) -> Option<f64> {
        let c = self.camera_centre();
        let denom = s.normal.dot(dir);
        if denom.abs() < 1e-12 {
            return None;
        }
        let t = s.normal.dot(&(s.point - c)) / denom;
        if t <= 0.0 {
            return None;
        }
        let p = c + dir * t;
        let inside = (0..3).all(|k| p[k] >= s.min[k] - 1e-9 && p[k] <= s.max[k] + 1e-9);
        inside.then_some(t)
    }
}

/// A rendered organised cloud and what it was rendered from.
#[derive(Debug, Clone)]
pub struct SceneCloud {
    pub points: Vec<CloudPoint>,
    pub width: usize,
    pub height: usize,
    pub intrinsics: Intrinsics,
    pub mount: Mount,
    pub truth_slope_deg: f64,
    pub truth_distance_m: f64,
}

impl SceneCloud {
    /// Renders `scene` at `width x height` with the Kinect v2 field of view
    /// (fx = fy = 365 at 512 px wide), depth noise `sigma_1m * z^2` (or the
    /// Kinect v2 model for [`KINECT2_NOISE`]) and depth rounded to
    /// millimetres like a recording.
    pub fn render(scene: &Scene, width: usize, height: usize, sigma_1m: f64, seed: u64) -> Self {
        let f = 365.0 * width as f64 / 512.0;
        let mut cloud = Self::render_with_intrinsics(scene, width, height, f, sigma_1m, seed);
        for p in &mut cloud.points {
            if p.is_valid() {
                let z = (f64::from(p.z_m) * 1000.0).round() / 1000.0;
                let scale = z / f64::from(p.z_m);
                p.x_m = (f64::from(p.x_m) * scale) as f32;
                p.y_m = (f64::from(p.y_m) * scale) as f32;
                p.z_m = z as f32;
            }
        }
        cloud
    }

    /// Full-size Kinect v2 frame (512 x 424, fx = fy = 365, cx = 255.5,
    /// cy = 211.5) with the Kinect v2 axial noise model (a negative
    /// `sigma_1m` selects it) and millimetre depth.
    pub fn kinect2(scene: &Scene, seed: u64) -> Self {
        Self::render(scene, 512, 424, KINECT2_NOISE, seed)
    }

    /// Renders with focal length `f` and the principal point at the centre,
    /// without depth rounding.
    pub fn render_with_intrinsics(
        scene: &Scene,
        width: usize,
        height: usize,
        f: f64,
        sigma_1m: f64,
        seed: u64,
    ) -> Self {
        let intrinsics = Intrinsics {
            fx: f,
            fy: f,
            cx: (width as f64 - 1.0) / 2.0,
            cy: (height as f64 - 1.0) / 2.0,
        };
        let [xa, ya, za] = scene.camera_axes();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut points = Vec::with_capacity(width * height);
        for v in 0..height {
            for u in 0..width {
                let a = (u as f64 - intrinsics.cx) / f;
                let b = (v as f64 - intrinsics.cy) / f;
                let dir = xa * a + ya * b + za;
                let hit = scene
                    .surfaces
                    .iter()
                    .filter_map(|s| scene.hit(s, &dir).map(|t| (t, s)))
                    .min_by(|a, b| a.0.total_cmp(&b.0));
                let point = match hit {
                    Some((z, surface)) if z < 8.0 => {
                        let noise = if sigma_1m > 0.0 {
                            gaussian(&mut rng) * sigma_1m * z * z
                        } else if sigma_1m < 0.0 {
                            let cos_t = surface.normal.dot(&dir).abs() / dir.norm();
                            gaussian(&mut rng) * kinect2_sigma_m(z, cos_t.clamp(0.0, 1.0).acos())
                        } else {
                            0.0
                        };
                        let z = z + noise;
                        CloudPoint {
                            x_m: (a * z) as f32,
                            y_m: (b * z) as f32,
                            z_m: z as f32,
                            rgb: 0,
                        }
                    }
                    _ => CloudPoint::INVALID,
                };
                points.push(point);
            }
        }
        Self {
            points,
            width,
            height,
            intrinsics,
            mount: scene.mount(),
            truth_slope_deg: scene.truth_slope_deg,
            truth_distance_m: scene.truth_distance_m,
        }
    }

    pub fn view(&self) -> CloudView<'_> {
        CloudView {
            points: &self.points,
            width: self.width,
            height: self.height,
            intrinsics: self.intrinsics,
            mount: self.mount,
        }
    }

    /// The measured points in pixel order.
    pub fn measured_points(&self) -> Vec<[f64; 3]> {
        self.points
            .iter()
            .filter(|p| p.is_valid())
            .map(|p| [f64::from(p.x_m), f64::from(p.y_m), f64::from(p.z_m)])
            .collect()
    }

    /// Moves `count` random measured pixels 40-60 % of the way towards the
    /// camera (flying pixels floating in mid-air), each at least 5 pixels
    /// from the others in a row or a column; returns their indices,
    /// sorted. Fewer when the frame has no room for `count` of them: the
    /// draws stop after [`FLYING_DRAWS_IN_A_ROW`] in a row that found no
    /// free spot.
    pub fn inject_flying_pixels(&mut self, count: usize, seed: u64) -> Vec<usize> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let measured: Vec<usize> = (0..self.points.len())
            .filter(|&i| self.points[i].is_valid())
            .collect();
        let mut chosen = Vec::new();
        if measured.is_empty() {
            return chosen;
        }
        let wanted = count.min(measured.len());
        let mut misses = 0;
        while chosen.len() < wanted && misses < FLYING_DRAWS_IN_A_ROW {
            let i = measured[rng.random_range(0..measured.len())];
            let (u, v) = (i % self.width, i / self.width);
            // Keep injected pixels apart so each one is isolated.
            if chosen.iter().any(|&j: &usize| {
                let (uj, vj) = (j % self.width, j / self.width);
                uj.abs_diff(u) <= 4 && vj.abs_diff(v) <= 4
            }) {
                misses += 1;
                continue;
            }
            misses = 0;
            let s = 1.0 - rng.random_range(0.4..0.6);
            let p = &mut self.points[i];
            p.x_m *= s;
            p.y_m *= s;
            p.z_m *= s;
            chosen.push(i);
        }
        chosen.sort_unstable();
        chosen
    }
}

/// Draws in a row that may miss (land next to an injected pixel) before
/// [`SceneCloud::inject_flying_pixels`] gives up.
pub const FLYING_DRAWS_IN_A_ROW: usize = 10_000;

/// A standard normal sample (Box-Muller), to keep `rand_distr` a
/// dev-dependency.
fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.random_range(f64::MIN_POSITIVE..1.0);
    let u2: f64 = rng.random_range(0.0..1.0);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mount_up_vector_matches_the_rendered_world_up() {
        let scene = Scene::ramp_at(10.0, 2.0, 0.5, -25.0, 7.0);
        let up = scene.to_camera(&Vector3::z());
        let m = scene.mount().up_vector().unwrap();
        for k in 0..3 {
            assert!((up[k] - m[k]).abs() < 1e-12, "{up:?} vs {m:?}");
        }
    }

    /// A 10 x 10 frame has room for 4 flying pixels 5 apart, not 40: the
    /// injection ends with at most 4, each isolated, instead of drawing
    /// for ever.
    #[test]
    fn flying_pixels_stop_when_the_frame_has_no_room() {
        let scene = Scene::wall_facing(2.0);
        let mut cloud = SceneCloud::render_with_intrinsics(&scene, 10, 10, 8.0, 0.0, 1);
        assert!(cloud.points.iter().all(|p| p.is_valid()));
        let chosen = cloud.inject_flying_pixels(40, 3);
        assert!((1..=4).contains(&chosen.len()), "{chosen:?}");
        for (k, &a) in chosen.iter().enumerate() {
            for &b in &chosen[k + 1..] {
                let (du, dv) = ((a % 10).abs_diff(b % 10), (a / 10).abs_diff(b / 10));
                assert!(du > 4 || dv > 4, "{a} and {b}");
            }
        }
    }

    #[test]
    fn rendered_ground_points_lie_on_the_ground() {
        let scene = Scene::ramp(12.5);
        let cloud = SceneCloud::render_with_intrinsics(&scene, 64, 53, 45.0, 0.0, 1);
        let up = scene.to_camera(&Vector3::z());
        // Bottom row sees the ground: its height below the camera is h.
        let p = cloud.points[52 * 64 + 32];
        let q = Vector3::new(f64::from(p.x_m), f64::from(p.y_m), f64::from(p.z_m));
        assert!((q.dot(&up) + 0.5).abs() < 1e-5, "{}", q.dot(&up));
    }
}
