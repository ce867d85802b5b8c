//! `[[soft_blocks]]`: a [`SoftSolid`] with random bumps fixed by the
//! block's `seed` and its index, and the junctions of its (undisplaced)
//! bottom edges with the ground.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::blocks::OrientedBox;
use super::{ConcaveJunction, World, GROUND};
use crate::bump_field::BumpField;
use crate::geometry::{BoxFace, Pos3, Surface, SurfaceKind};
use crate::scene::SoftBlock;
use crate::soft_solid::SoftSolid;

impl World {
    /// Adds soft block `index` of the scene (validated).
    pub(super) fn add_soft_block(&mut self, block: &SoftBlock, index: u16) {
        let face = |f: BoxFace| Surface::new(SurfaceKind::SoftBlock, index, f as u8);
        let bumps = bump_fields(block, index);
        let base = Pos3::new(block.x_m, block.y_m, 0.0);
        self.soft_solids.push(SoftSolid::new(
            base,
            block.yaw_deg,
            block.size_m,
            bumps,
            face,
        ));
        let shape = OrientedBox {
            base,
            yaw_deg: block.yaw_deg,
            size_m: block.size_m,
        };
        for e in shape.bottom_edges() {
            self.junctions.push(ConcaveJunction {
                a: e.a,
                b: e.b,
                surfaces: [GROUND, face(e.face)],
            });
        }
    }
}

/// The bumps of the Inner, Outer, Near, Far and Top faces, drawn in that
/// order from a ChaCha8 stream keyed by `(seed, index)`.
fn bump_fields(block: &SoftBlock, index: u16) -> [BumpField; 5] {
    let mut rng = ChaCha8Rng::seed_from_u64(block.seed);
    rng.set_stream(u64::from(index));
    [(); 5].map(|()| BumpField::random(block.roughness_m, block.wavelength_m, &mut rng))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Ray, Vec3};
    use crate::scene::Scene;

    fn top_heights(scene: &Scene) -> Vec<f64> {
        let w = World::build(scene);
        (0..40)
            .map(|i| {
                let ray = Ray {
                    origin: Pos3::new(-0.5 + 0.025 * f64::from(i), 2.0, 3.0),
                    direction: -Vec3::z(),
                };
                let hit = w.cast(&ray).expect("hits the block");
                assert_eq!(
                    hit.surface,
                    Surface::new(SurfaceKind::SoftBlock, 0, BoxFace::Top as u8)
                );
                3.0 - hit.t
            })
            .collect()
    }

    #[test]
    fn top_is_bumpy_within_roughness_and_fixed_by_the_seed() {
        let scene = Scene {
            soft_blocks: vec![SoftBlock::default()],
            ..Scene::default()
        };
        let heights = top_heights(&scene);
        let size_up = SoftBlock::default().size_m[2];
        assert!(heights.iter().all(|h| (h - size_up).abs() <= 0.03 + 1e-9));
        let spread = heights.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - heights.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(spread > 0.02, "top spread {spread}");
        assert_eq!(heights, top_heights(&scene));
        let reseeded = Scene {
            soft_blocks: vec![SoftBlock {
                seed: 1,
                ..SoftBlock::default()
            }],
            ..Scene::default()
        };
        assert_ne!(heights, top_heights(&reseeded));
    }
}
