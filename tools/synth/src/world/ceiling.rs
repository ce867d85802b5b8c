//! `[ceiling]`: everything above `height_m`, optionally only between
//! `from_m` and `to_m` ahead (an overhang with vertical ends).

use super::World;
use crate::geometry::{BoxFace, ConvexSolid, HalfSpace, Pos3, Surface, SurfaceKind, Vec3};
use crate::scene::Ceiling;

impl World {
    /// Adds the scene's ceiling (validated).
    pub(super) fn add_ceiling(&mut self, ceiling: &Ceiling) {
        let face = |f: BoxFace| Surface::new(SurfaceKind::Ceiling, 0, f as u8);
        let mut faces = vec![HalfSpace::through(
            &Pos3::new(0.0, 0.0, ceiling.height_m),
            -Vec3::z(),
            face(BoxFace::Bottom),
        )];
        if ceiling.from_m.is_finite() {
            faces.push(HalfSpace::through(
                &Pos3::new(0.0, ceiling.from_m, 0.0),
                -Vec3::y(),
                face(BoxFace::Near),
            ));
        }
        if ceiling.to_m.is_finite() {
            faces.push(HalfSpace::through(
                &Pos3::new(0.0, ceiling.to_m, 0.0),
                Vec3::y(),
                face(BoxFace::Far),
            ));
        }
        self.solids.push(ConvexSolid { faces });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Ray;
    use crate::scene::Scene;

    fn up_from(y: f64) -> Ray {
        Ray {
            origin: Pos3::new(0.4, y, 1.0),
            direction: Vec3::z(),
        }
    }

    #[test]
    fn unbounded_ceiling_is_at_its_height_everywhere() {
        let w = World::build(&Scene {
            ceiling: Some(Ceiling {
                height_m: 2.2,
                ..Ceiling::default()
            }),
            ..Scene::default()
        });
        for y in [-50.0, 0.0, 3.0, 400.0] {
            let hit = w.cast(&up_from(y)).expect("hits the ceiling");
            assert!((hit.t - 1.2).abs() < 1e-12);
            assert_eq!(hit.normal, -Vec3::z());
            assert_eq!(hit.surface.kind, SurfaceKind::Ceiling);
        }
    }

    #[test]
    fn overhang_covers_only_its_range() {
        let w = World::build(&Scene {
            ceiling: Some(Ceiling {
                height_m: 1.8,
                from_m: 2.0,
                to_m: 3.5,
            }),
            ..Scene::default()
        });
        assert!(w.cast(&up_from(1.9)).is_none());
        assert!(w.cast(&up_from(3.6)).is_none());
        let hit = w.cast(&up_from(2.1)).expect("under the overhang");
        assert!((hit.t - 0.8).abs() < 1e-12);
        // Looking forward above its underside: the near end face.
        let ahead = Ray {
            origin: Pos3::new(0.0, 0.0, 2.5),
            direction: Vec3::y(),
        };
        let hit = w.cast(&ahead).expect("hits the near end");
        assert!((hit.t - 2.0).abs() < 1e-12);
        assert_eq!(hit.surface.face, BoxFace::Near as u8);
    }
}
