//! `[[tables]]`: a slab whose top is `top_m` above the ground, on four
//! square legs at its corners. The slab and each leg are box solids; each
//! leg's sides meet the ground and the slab's underside in concave
//! junctions (multipath).

use super::blocks::OrientedBox;
use super::{ConcaveJunction, World, GROUND};
use crate::geometry::{BoxFace, Pos3, Surface, SurfaceKind, Vec3};
use crate::scene::Table;

/// Leg corners in the table's frame (across, along): near-left,
/// near-right, far-left, far-right; the leg number is the position here.
const LEG_CORNERS: [(f64, f64); 4] = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)];

impl World {
    /// Adds table `index` of the scene (validated: its legs have a length).
    pub(super) fn add_table(&mut self, table: &Table, index: u16) {
        let [sx, sy] = table.size_m;
        let leg_height = table.top_m - table.thickness_m;
        let slab = OrientedBox {
            base: Pos3::new(table.x_m, table.y_m, leg_height),
            yaw_deg: table.yaw_deg,
            size_m: [sx, sy, table.thickness_m],
        };
        let slab_face = |f: BoxFace| Surface::new(SurfaceKind::Table, index, f as u8);
        self.solids.push(slab.solid(slab_face));

        let (s, c) = table.yaw_deg.to_radians().sin_cos();
        let (across, along) = (Vec3::new(c, s, 0.0), Vec3::new(-s, c, 0.0));
        let inset = table.leg_m / 2.0;
        for (leg, (fx, fy)) in (0u8..).zip(LEG_CORNERS) {
            let offset = across * fx * (sx / 2.0 - inset) + along * fy * (sy / 2.0 - inset);
            let shape = OrientedBox {
                base: Pos3::new(table.x_m, table.y_m, 0.0) + offset,
                yaw_deg: table.yaw_deg,
                size_m: [table.leg_m, table.leg_m, leg_height],
            };
            let leg_face =
                |f: BoxFace| Surface::new(SurfaceKind::TableLeg, index, 6 * leg + f as u8);
            self.solids.push(shape.solid(leg_face));
            for (edges, other) in [
                (shape.bottom_edges(), GROUND),
                (shape.top_edges(), slab_face(BoxFace::Bottom)),
            ] {
                for e in edges {
                    self.junctions.push(ConcaveJunction {
                        a: e.a,
                        b: e.b,
                        surfaces: [other, leg_face(e.face)],
                    });
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Ray;
    use crate::scene::Scene;

    fn world(table: Table) -> World {
        World::build(&Scene {
            tables: vec![table],
            ..Scene::default()
        })
    }

    fn down(x: f64, y: f64, z: f64) -> Ray {
        Ray {
            origin: Pos3::new(x, y, z),
            direction: -Vec3::z(),
        }
    }

    #[test]
    fn top_is_at_top_m_and_legs_stand_at_the_corners() {
        let table = Table {
            x_m: 0.2,
            y_m: 1.5,
            size_m: [1.0, 0.6],
            top_m: 0.7,
            thickness_m: 0.05,
            leg_m: 0.06,
            yaw_deg: 0.0,
        };
        let w = world(table);
        let top = w.cast(&down(0.4, 1.6, 2.0)).expect("hits the top");
        assert!((2.0 - top.t - 0.7).abs() < 1e-12);
        assert_eq!(
            top.surface,
            Surface::new(SurfaceKind::Table, 0, BoxFace::Top as u8)
        );
        // Under the slab, between the legs: the ground.
        let under = w.cast(&down(0.2, 1.5, 0.6)).expect("hits the ground");
        assert!((under.t - 0.6).abs() < 1e-12 && under.surface == GROUND);
        // Looking up from under the table: the underside at top - thickness.
        let up = Ray {
            origin: Pos3::new(0.2, 1.5, 0.1),
            direction: Vec3::z(),
        };
        let hit = w.cast(&up).expect("hits the underside");
        assert!((hit.t - (0.65 - 0.1)).abs() < 1e-12);
        assert_eq!(hit.surface.face, BoxFace::Bottom as u8);
        // Inside the far-right leg (leg 3), beside it not.
        assert!(w.contains(&Pos3::new(0.2 + 0.5 - 0.03, 1.5 + 0.3 - 0.03, 0.3)));
        assert!(!w.contains(&Pos3::new(0.2 + 0.5 - 0.07, 1.5 + 0.3 - 0.03, 0.3)));
        let side = Ray {
            origin: Pos3::new(0.2 + 0.5 - 0.03, 0.0, 0.3),
            direction: Vec3::y(),
        };
        let leg = w.cast(&side).expect("hits a near leg");
        assert!((leg.t - (1.5 - 0.3)).abs() < 1e-12);
        assert_eq!(
            leg.surface,
            Surface::new(SurfaceKind::TableLeg, 0, 6 + BoxFace::Near as u8)
        );
    }

    #[test]
    fn yawed_table_turns_its_legs_with_it() {
        let w = world(Table {
            x_m: 0.0,
            y_m: 2.0,
            size_m: [1.0, 0.6],
            yaw_deg: 90.0,
            ..Table::default()
        });
        // Turned 90°: the 1 m side runs along y, so x = ±0.3 are its edges.
        assert!(w.contains(&Pos3::new(0.27, 2.47, 0.3)));
        assert!(!w.contains(&Pos3::new(0.47, 2.27, 0.3)));
        assert!(w
            .cast(&down(0.0, 2.45, 2.0))
            .is_some_and(|h| h.surface.kind == SurfaceKind::Table));
        assert!(w
            .cast(&down(0.35, 2.0, 2.0))
            .is_some_and(|h| h.surface == GROUND));
    }
}
