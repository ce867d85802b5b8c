//! A simple colour image registered to the depth image, so that clouds made
//! from synthetic recordings have colour: a flat colour per kind of surface,
//! Lambert-shaded by a light at the camera, with a faint 0.5 m checker on
//! horizontal surfaces (to see motion). Deterministic: no randomness.

use slope_sensor::recording::ColorImage;

use crate::geometry::SurfaceKind;
use crate::raycast::{GeometryImage, PixelHit};

/// Colour of pixels that see nothing.
pub const SKY_RGB: [u8; 3] = [168, 196, 228];

/// Base colour of a surface kind.
pub fn base_rgb(kind: SurfaceKind) -> [u8; 3] {
    match kind {
        SurfaceKind::Ground => [128, 126, 120],
        SurfaceKind::Ramp => [214, 128, 54],
        SurfaceKind::Landing => [150, 150, 140],
        SurfaceKind::RampSide | SurfaceKind::RampBack => [170, 100, 44],
        SurfaceKind::Wall => [196, 190, 200],
        SurfaceKind::Box => [64, 112, 176],
        SurfaceKind::Table => [150, 104, 62],
        SurfaceKind::TableLeg => [96, 72, 50],
        SurfaceKind::Ceiling => [224, 222, 212],
        SurfaceKind::SoftBlock => [118, 150, 108],
        SurfaceKind::Panel => [186, 160, 96],
    }
}

/// Shades every pixel of a view.
pub fn shade(geometry: &GeometryImage) -> ColorImage {
    let mut image = ColorImage::new(geometry.width, geometry.height);
    for (out, pixel) in image.data.iter_mut().zip(&geometry.pixels) {
        *out = pixel.as_ref().map_or(SKY_RGB, shade_pixel);
    }
    image
}

fn shade_pixel(hit: &PixelHit) -> [u8; 3] {
    let base = base_rgb(hit.surface.kind);
    let mut light = 0.35 + 0.65 * hit.cos_incidence;
    if hit.normal.z.abs() > 0.99 {
        let cell = (hit.point.x / 0.5).floor() + (hit.point.y / 0.5).floor();
        if cell.rem_euclid(2.0) >= 1.0 {
            light *= 0.9;
        }
    }
    // Clamped to [0, 255] first, so the cast cannot truncate.
    base.map(|c| (f64::from(c) * light).round().clamp(0.0, 255.0) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, CameraPose};
    use crate::raycast::raycast;
    use crate::scene::Scene;
    use crate::world::World;

    #[test]
    fn ramp_pixels_are_orange_and_sky_is_blue() {
        let scene = Scene::default_ramp();
        let camera = Camera {
            model: scene.camera,
            pose: CameraPose::new(0.5, -20.0, 0.0, 0.0, 0.0),
        };
        let geometry = raycast(&World::build(&scene), &camera);
        let image = shade(&geometry);
        for (rgb, pixel) in image.data.iter().zip(&geometry.pixels) {
            match pixel {
                None => assert_eq!(*rgb, SKY_RGB),
                Some(p) if p.surface.kind == SurfaceKind::Ramp => {
                    assert!(rgb[0] > rgb[1] && rgb[1] > rgb[2], "{rgb:?}")
                }
                Some(_) => {}
            }
        }
    }
}
