//! The sensor model applied to exact geometry: one simulated depth image.
//!
//! Per pixel, in this order (each step off when the model says so):
//! 1. lateral noise: the ray through a jittered image position decides
//!    which surface the pixel sees, so depth edges are ragged (a jittered
//!    ray on the same surface keeps the exact depth: on a plane the axial
//!    model already covers the error);
//! 2. flying pixels: at a depth discontinuity between two surfaces, the
//!    reading is a random mixture of the two depths;
//! 3. multipath: a bias near concave junctions, along the ray; then the
//!    range bias, `z + k z^2` along the ray ([`crate::sensor_model::RangeBias`]);
//! 4. axial noise: Gaussian in depth, `axial_sigma_m(z, incidence)`;
//! 5. dropouts: at grazing incidence and at random;
//! 6. range limits, then quantisation to [`DEPTH_UNIT_M`] (0 = no reading).

use rand::Rng;
use rand_distr::StandardNormal;
use slope_sensor::recording::DepthImage;

use crate::camera::Camera;
use crate::raycast::{cast_pixel, raycast, GeometryImage, PixelHit};
use crate::sensor_model::{axial_sigma_m, SensorModel};
use crate::world::World;

/// Metres per depth count in the recordings this crate writes.
pub const DEPTH_UNIT_M: f64 = 0.001;

/// Renders one depth image of `world` seen by `camera` through `model`.
pub fn render_frame<R: Rng + ?Sized>(
    world: &World,
    model: &SensorModel,
    camera: &Camera,
    rng: &mut R,
) -> DepthImage {
    let geometry = raycast(world, camera);
    render_depth(&geometry, world, model, camera, rng)
}

/// Like [`render_frame`], from an already cast [`GeometryImage`] of the same
/// camera (so the caller can also shade it or keep it as ground truth).
pub fn render_depth<R: Rng + ?Sized>(
    geometry: &GeometryImage,
    world: &World,
    model: &SensorModel,
    camera: &Camera,
    rng: &mut R,
) -> DepthImage {
    let (width, height) = (geometry.width, geometry.height);
    let edges = if model.flying_pixel_probability > 0.0 {
        discontinuity_partners(geometry, model.flying_pixel_jump_m)
    } else {
        Vec::new()
    };
    let mut depth = DepthImage::new(width, height);
    // The range bias's k for this frame's camera height (the world's
    // ground is z = 0): 0 without a bias.
    let bias_per_m = model
        .range_bias
        .depth_coefficient_per_m(camera.pose.position.z);
    for v in 0..height {
        for u in 0..width {
            let i = v as usize * width as usize + u as usize;
            let exact = geometry.pixels.get(i).copied().flatten();
            let seen = if model.lateral_noise_px > 0.0 {
                let du: f64 = rng.sample(StandardNormal);
                let dv: f64 = rng.sample(StandardNormal);
                let s = model.lateral_noise_px;
                let jittered =
                    cast_pixel(world, camera, f64::from(u) + s * du, f64::from(v) + s * dv);
                match (exact, jittered) {
                    (Some(e), Some(j)) if e.surface == j.surface => Some(e),
                    (_, j) => j,
                }
            } else {
                exact
            };
            let Some(hit) = seen else {
                continue;
            };
            let partner = edges.get(i).copied().flatten();
            // Length of the ray per metre of depth, to turn path-length
            // errors into depth errors.
            let ray_per_depth = camera.ray(f64::from(u), f64::from(v)).direction.norm();
            let z = measure(&hit, partner, ray_per_depth, world, model, rng, bias_per_m);
            depth.data[i] = match z {
                Some(z) => quantise(z),
                None => 0,
            };
        }
    }
    depth
}

/// The noisy depth of one reading, `None` when it is dropped. `partner` is
/// the depth across a discontinuity next to the pixel, if any;
/// `bias_per_m` the range bias's `k` (`z + k z^2`, 0 for none).
fn measure<R: Rng + ?Sized>(
    hit: &PixelHit,
    partner: Option<f64>,
    ray_per_depth: f64,
    world: &World,
    model: &SensorModel,
    rng: &mut R,
    bias_per_m: f64,
) -> Option<f64> {
    let mut z = hit.z_m;
    if let Some(other_z) = partner {
        if rng.random::<f64>() < model.flying_pixel_probability {
            let w: f64 = rng.random();
            z += w * (other_z - z);
        }
    }
    if model.multipath_bias_m > 0.0 {
        // The bias lengthens the light path along the ray.
        z += world.multipath_bias_m(model, &hit.point, hit.surface) / ray_per_depth;
    }
    if bias_per_m != 0.0 {
        // The range bias, along the ray: z' = z + k z^2.
        z += bias_per_m * z * z;
    }
    let theta = hit.incidence_rad();
    if model.axial_noise {
        let n: f64 = rng.sample(StandardNormal);
        z += n * axial_sigma_m(z, theta);
    }
    if model.grazing_dropout && rng.random::<f64>() < model.grazing_dropout_probability(theta) {
        return None;
    }
    if model.random_dropout_probability > 0.0
        && rng.random::<f64>() < model.random_dropout_probability
    {
        return None;
    }
    if model.range_limits && !(model.min_range_m..=model.max_range_m).contains(&z) {
        return None;
    }
    Some(z)
}

/// Depth in metres to recording counts: rounded to the nearest
/// [`DEPTH_UNIT_M`]; 0 (no reading) when not representable in 16 bits.
pub fn quantise(z_m: f64) -> u16 {
    slope_sensor::recording::metres_to_count(z_m, DEPTH_UNIT_M)
}

/// For each pixel at a depth discontinuity, the depth on the other side:
/// a 4-neighbour on a different surface whose exact depth differs by more
/// than `jump_m` (the largest such difference wins). Pixels next to empty
/// space get none: a time-of-flight pixel mixes returns, and empty space
/// returns nothing.
pub fn discontinuity_partners(geometry: &GeometryImage, jump_m: f64) -> Vec<Option<f64>> {
    let (w, h) = (geometry.width, geometry.height);
    let mut partners = vec![None; geometry.pixels.len()];
    for v in 0..h {
        for u in 0..w {
            let Some(me) = geometry.get(u, v) else {
                continue;
            };
            let neighbours = [
                (u.wrapping_sub(1), v),
                (u + 1, v),
                (u, v.wrapping_sub(1)),
                (u, v + 1),
            ];
            let mut best: Option<f64> = None;
            for (nu, nv) in neighbours {
                let Some(other) = geometry.get(nu, nv) else {
                    continue;
                };
                let jump = (other.z_m - me.z_m).abs();
                if other.surface != me.surface
                    && jump > jump_m
                    && best.is_none_or(|b| jump > (b - me.z_m).abs())
                {
                    best = Some(other.z_m);
                }
            }
            partners[v as usize * w as usize + u as usize] = best;
        }
    }
    partners
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::camera::CameraPose;
    use crate::scene::{CameraModel, Scene};

    #[test]
    fn quantisation_rounds_to_millimetres() {
        assert_eq!(quantise(1.2344), 1234);
        assert_eq!(quantise(1.2346), 1235);
        assert_eq!(quantise(0.0), 0);
        assert_eq!(quantise(-1.0), 0);
        assert_eq!(quantise(65.535), 65535);
        assert_eq!(quantise(70.0), 0);
        assert_eq!(quantise(f64::NAN), 0);
    }

    #[test]
    fn clean_render_is_the_quantised_geometry() {
        let scene = Scene::default_ramp();
        let world = World::build(&scene);
        let camera = Camera {
            model: CameraModel::KINECT2,
            pose: CameraPose::new(0.5, -20.0, 0.0, 0.0, 0.0),
        };
        let geometry = raycast(&world, &camera);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let depth = render_depth(&geometry, &world, &SensorModel::clean(), &camera, &mut rng);
        for (d, g) in depth.data.iter().zip(&geometry.pixels) {
            assert_eq!(*d, g.map_or(0, |g| quantise(g.z_m)));
        }
    }

    #[test]
    fn range_limits_drop_near_and_far() {
        let scene = Scene::default();
        let world = World::build(&scene);
        let camera = Camera {
            model: CameraModel::KINECT2,
            pose: CameraPose::new(0.5, -10.0, 0.0, 0.0, 0.0),
        };
        let model = SensorModel {
            range_limits: true,
            ..SensorModel::clean()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let depth = render_frame(&world, &model, &camera, &mut rng);
        let geometry = raycast(&world, &camera);
        let mut kept = 0;
        for (d, g) in depth.data.iter().zip(&geometry.pixels) {
            let inside = g.is_some_and(|g| (0.5..=4.5).contains(&g.z_m));
            assert_eq!(*d != 0, inside);
            kept += usize::from(inside);
        }
        assert!(kept > 10_000);
        assert!(depth
            .data
            .iter()
            .all(|&d| d == 0 || (500..=4500).contains(&d)));
    }
}
