//! `[[tables]]`: a slab whose top is `top_m` above the ground, on four
//! square legs at its corners. The slab and each leg are box solids; each
//! leg's sides meet the ground and the slab's underside in concave
//! junctions (multipath).

use super::blocks::OrientedBox;
use super::{ConcaveJunction, World, GROUND};
use crate::geometry::{BoxFace, ConvexSolid, HalfSpace, Pos3, Surface, SurfaceKind, Vec3};
use crate::scene::Table;

/// Leg corners in the table's frame (across, along): near-left,
/// near-right, far-left, far-right; the leg number is the position here.
const LEG_CORNERS: [(f64, f64); 4] = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)];

impl World {
    /// Adds table `index` of the scene (validated: its legs have a length).
    pub(super) fn add_table(&mut self, table: &Table, index: u16) {
        if table.tilt_deg != 0.0 {
            self.add_tilted_table(table, index);
            return;
        }
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

    /// A table whose top is turned by `tilt_deg` about its across axis
    /// through the centre of the top surface. The slab's faces are planes of
    /// the tilted frame; each leg is a vertical square prism under an
    /// underside corner, cut by the underside's plane, so it meets the slab
    /// exactly.
    fn add_tilted_table(&mut self, table: &Table, index: u16) {
        let [sx, sy] = table.size_m;
        let frame = TiltedTop::new(table);
        let slab_face = |f: BoxFace| Surface::new(SurfaceKind::Table, index, f as u8);
        let (half_x, half_y) = (sx / 2.0, sy / 2.0);
        let t = table.thickness_m;
        let slab = ConvexSolid {
            faces: vec![
                frame.face(
                    &frame.point(-half_x, 0.0, 0.0),
                    -frame.across,
                    slab_face(BoxFace::Inner),
                ),
                frame.face(
                    &frame.point(half_x, 0.0, 0.0),
                    frame.across,
                    slab_face(BoxFace::Outer),
                ),
                frame.face(
                    &frame.point(0.0, -half_y, 0.0),
                    -frame.along,
                    slab_face(BoxFace::Near),
                ),
                frame.face(
                    &frame.point(0.0, half_y, 0.0),
                    frame.along,
                    slab_face(BoxFace::Far),
                ),
                frame.face(
                    &frame.point(0.0, 0.0, -t),
                    -frame.up,
                    slab_face(BoxFace::Bottom),
                ),
                frame.face(&frame.centre, frame.up, slab_face(BoxFace::Top)),
            ],
        };
        self.solids.push(slab);

        // The underside's corners seen from above: legs go under them.
        let leg = table.leg_m;
        let underside = |a: f64, b: f64| frame.point(a, b, -t);
        for (number, (fx, fy)) in (0u8..).zip(LEG_CORNERS) {
            let corner = underside(fx * half_x, fy * half_y);
            // Leg centre: inset by half a leg from the corner, horizontally.
            let centre = corner - frame.across * (fx * leg / 2.0) - frame.level * (fy * leg / 2.0);
            let shape = OrientedBox {
                base: Pos3::new(centre.x, centre.y, 0.0),
                yaw_deg: table.yaw_deg,
                size_m: [leg, leg, 1.0],
            };
            let leg_face =
                |f: BoxFace| Surface::new(SurfaceKind::TableLeg, index, 6 * number + f as u8);
            let mut solid = shape.solid(leg_face);
            // Replace the box's top with the underside's plane.
            if let Some(top) = solid.faces.last_mut() {
                *top = frame.face(&frame.point(0.0, 0.0, -t), frame.up, leg_face(BoxFace::Top));
            }
            self.solids.push(solid);
            for e in shape.bottom_edges() {
                self.junctions.push(ConcaveJunction {
                    a: e.a,
                    b: e.b,
                    surfaces: [GROUND, leg_face(e.face)],
                });
            }
            for e in shape.bottom_edges() {
                self.junctions.push(ConcaveJunction {
                    a: frame.onto_underside(&e.a, t),
                    b: frame.onto_underside(&e.b, t),
                    surfaces: [slab_face(BoxFace::Bottom), leg_face(e.face)],
                });
            }
        }
    }
}

/// The frame of a tilted table top: origin at the centre of the top
/// surface; `across` the table's own x; `along` its own y tilted up by
/// `tilt_deg`; `up` the top's normal; `level` the horizontal `along`.
struct TiltedTop {
    centre: Pos3,
    across: Vec3,
    along: Vec3,
    up: Vec3,
    level: Vec3,
}

impl TiltedTop {
    fn new(table: &Table) -> Self {
        let (sy, cy) = table.yaw_deg.to_radians().sin_cos();
        let (st, ct) = table.tilt_deg.to_radians().sin_cos();
        let level = Vec3::new(-sy, cy, 0.0);
        Self {
            centre: Pos3::new(table.x_m, table.y_m, table.top_m),
            across: Vec3::new(cy, sy, 0.0),
            along: level * ct + Vec3::z() * st,
            up: Vec3::z() * ct - level * st,
            level,
        }
    }

    fn point(&self, a: f64, b: f64, n: f64) -> Pos3 {
        self.centre + self.across * a + self.along * b + self.up * n
    }

    fn face(&self, point: &Pos3, normal: Vec3, surface: Surface) -> HalfSpace {
        HalfSpace::through(point, normal, surface)
    }

    /// `p` moved vertically onto the plane of the underside.
    fn onto_underside(&self, p: &Pos3, thickness_m: f64) -> Pos3 {
        let on_plane = self.point(0.0, 0.0, -thickness_m);
        // up · (p + k z - on_plane) = 0; up.z = cos(tilt) > 0 (|tilt| < 45°).
        let k = -self.up.dot(&(p - on_plane)) / self.up.z;
        p + Vec3::z() * k
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
            tilt_deg: 0.0,
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

    #[test]
    fn tilted_top_rises_to_the_far_edge_and_the_legs_reach_it() {
        let tilt = 12f64.to_radians();
        let table = Table {
            x_m: 0.0,
            y_m: 2.0,
            size_m: [1.0, 0.8],
            top_m: 0.7,
            tilt_deg: 12.0,
            ..Table::default()
        };
        let w = world(table);
        // The top surface: z = 0.7 + (y - 2) tan(tilt), cut 0.4 cos(tilt) either side.
        for y in [1.65, 2.0, 2.3] {
            let hit = w.cast(&down(0.1, y, 2.0)).expect("hits the top");
            assert_eq!(hit.surface.kind, SurfaceKind::Table);
            assert_eq!(hit.surface.face, BoxFace::Top as u8);
            assert!((2.0 - hit.t - (0.7 + (y - 2.0) * tilt.tan())).abs() < 1e-12);
            assert!((hit.normal - Vec3::new(0.0, -tilt.sin(), tilt.cos())).norm() < 1e-12);
        }
        // Each leg fills the height from the ground to the underside at its
        // centre: a point just below the underside is inside, just above
        // the ground too, and the leg touches the slab without a gap.
        let frame = TiltedTop::new(&table);
        for (fx, fy) in LEG_CORNERS {
            let corner = frame.point(fx * 0.5, fy * 0.4, -table.thickness_m);
            let centre = corner - frame.across * (fx * 0.025) - frame.level * (fy * 0.025);
            let underside = frame.onto_underside(&Pos3::new(centre.x, centre.y, 0.0), 0.04);
            assert!(w.contains(&Pos3::new(centre.x, centre.y, 0.001)));
            assert!(w.contains(&Pos3::new(centre.x, centre.y, underside.z - 0.001)));
            assert!(w.contains(&Pos3::new(centre.x, centre.y, underside.z + 0.001)));
            let up = Ray {
                origin: Pos3::new(centre.x - fx * 0.03, centre.y, 0.1),
                direction: Vec3::z(),
            };
            let hit = w.cast(&up).expect("beside the leg: the underside");
            assert_eq!(hit.surface.face, BoxFace::Bottom as u8);
        }
    }
}
