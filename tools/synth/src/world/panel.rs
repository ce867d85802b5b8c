//! `[[panels]]`: a tilted, yawed slab. In the panel's frame (origin at the
//! middle of its lower edge; `across` along that edge, to the right seen
//! looking up the slope; `up_slope` from the lower to the upper edge;
//! `normal` out of the top surface), the slab is
//! `|across| <= width / 2`, `0 <= up_slope <= length`,
//! `-thickness <= normal <= 0`. A panel whose lower edge stands on the
//! floor meets it along that edge (a concave junction for multipath).

use super::{ConcaveJunction, World, GROUND};
use crate::geometry::{BoxFace, ConvexSolid, HalfSpace, Pos3, Surface, SurfaceKind, Vec3};
use crate::scene::Panel;

/// A panel's frame in the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PanelFrame {
    /// Middle of the lower edge of the top surface.
    pub origin: Pos3,
    /// Along the lower edge (horizontal), to the right looking uphill.
    pub across: Vec3,
    /// From the lower to the upper edge, along the top surface.
    pub up_slope: Vec3,
    /// Out of the top surface (up, and towards the camera for yaw 0).
    pub normal: Vec3,
}

impl PanelFrame {
    /// The frame of `panel`.
    pub fn new(panel: &Panel) -> Self {
        let (sy, cy) = panel.yaw_deg.to_radians().sin_cos();
        let (st, ct) = panel.tilt_deg.to_radians().sin_cos();
        let across = Vec3::new(cy, sy, 0.0);
        let uphill = Vec3::new(-sy, cy, 0.0);
        Self {
            origin: Pos3::new(panel.x_m, panel.y_m, panel.bottom_m),
            across,
            up_slope: uphill * ct + Vec3::z() * st,
            normal: Vec3::z() * ct - uphill * st,
        }
    }

    /// The point `a` across, `s` up the slope and `n` along the normal.
    pub fn point(&self, a: f64, s: f64, n: f64) -> Pos3 {
        self.origin + self.across * a + self.up_slope * s + self.normal * n
    }
}

impl World {
    /// Adds panel `index` of the scene (validated).
    pub(super) fn add_panel(&mut self, panel: &Panel, index: u16) {
        let face = |f: BoxFace| Surface::new(SurfaceKind::Panel, index, f as u8);
        let frame = PanelFrame::new(panel);
        let half = panel.width_m / 2.0;
        let faces = vec![
            HalfSpace::through(
                &frame.point(-half, 0.0, 0.0),
                -frame.across,
                face(BoxFace::Inner),
            ),
            HalfSpace::through(
                &frame.point(half, 0.0, 0.0),
                frame.across,
                face(BoxFace::Outer),
            ),
            HalfSpace::through(&frame.origin, -frame.up_slope, face(BoxFace::Near)),
            HalfSpace::through(
                &frame.point(0.0, panel.length_m, 0.0),
                frame.up_slope,
                face(BoxFace::Far),
            ),
            HalfSpace::through(
                &frame.point(0.0, 0.0, -panel.thickness_m),
                -frame.normal,
                face(BoxFace::Bottom),
            ),
            HalfSpace::through(&frame.origin, frame.normal, face(BoxFace::Top)),
        ];
        self.solids.push(ConvexSolid { faces });
        if panel.bottom_m == 0.0 && panel.tilt_deg > 0.0 {
            self.junctions.push(ConcaveJunction {
                a: frame.point(-half, 0.0, 0.0),
                b: frame.point(half, 0.0, 0.0),
                surfaces: [GROUND, face(BoxFace::Top)],
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Ray;
    use crate::scene::Scene;

    fn world(panel: Panel) -> World {
        World::build(&Scene {
            panels: vec![panel],
            ..Scene::default()
        })
    }

    fn top() -> Surface {
        Surface::new(SurfaceKind::Panel, 0, BoxFace::Top as u8)
    }

    #[test]
    fn vertical_panel_is_a_wall_facing_the_camera() {
        let w = world(Panel {
            y_m: 3.0,
            width_m: 2.0,
            length_m: 1.5,
            ..Panel::default()
        });
        let ahead = Ray {
            origin: Pos3::new(0.5, 0.0, 1.0),
            direction: Vec3::y(),
        };
        let hit = w.cast(&ahead).expect("hits the wall");
        assert!((hit.t - 3.0).abs() < 1e-12, "{}", hit.t);
        assert_eq!(hit.surface, top());
        assert!((hit.normal - (-Vec3::y())).norm() < 1e-12);
        // Above its top edge (1.5 m) and beyond its right end: nothing.
        for origin in [Pos3::new(0.0, 0.0, 1.6), Pos3::new(1.1, 0.0, 1.0)] {
            let ray = Ray {
                origin,
                direction: Vec3::y(),
            };
            assert!(w
                .cast(&ray)
                .is_none_or(|h| h.surface.kind != SurfaceKind::Panel));
        }
    }

    #[test]
    fn leaning_panel_starts_at_the_floor_without_a_lip() {
        let tilt = 20f64.to_radians();
        let w = world(Panel {
            y_m: 2.0,
            tilt_deg: 20.0,
            length_m: 2.0,
            thickness_m: 0.05,
            ..Panel::default()
        });
        // Vertical rays: the floor up to the lower edge, then the top surface
        // at (y - 2) tan(tilt), however close to the edge.
        for y in [1.9, 1.999, 2.001, 2.5, 3.8] {
            let ray = Ray {
                origin: Pos3::new(0.1, y, 5.0),
                direction: -Vec3::z(),
            };
            let hit = w.cast(&ray).expect("terrain everywhere");
            let z = 5.0 - hit.t;
            if y < 2.0 {
                assert!(hit.surface == GROUND && z.abs() < 1e-12, "y = {y}");
            } else {
                assert_eq!(hit.surface, top(), "y = {y}");
                assert!((z - (y - 2.0) * tilt.tan()).abs() < 1e-12, "y = {y}: {z}");
            }
        }
    }

    #[test]
    fn yawed_floating_panel_turns_its_uphill_direction_left() {
        let frame = PanelFrame::new(&Panel {
            yaw_deg: 90.0,
            tilt_deg: 35.0,
            bottom_m: 0.7,
            ..Panel::default()
        });
        // Uphill towards -x (left), normal tilted towards +x, up.
        let (s, c) = 35f64.to_radians().sin_cos();
        assert!((frame.up_slope - Vec3::new(-c, 0.0, s)).norm() < 1e-12);
        assert!((frame.normal - Vec3::new(s, 0.0, c)).norm() < 1e-12);
        assert!((frame.across - Vec3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
        assert_eq!(frame.origin.z, 0.7);
        let w = world(Panel {
            bottom_m: 0.7,
            tilt_deg: 35.0,
            ..Panel::default()
        });
        assert!(w.junctions.is_empty(), "a floating panel meets nothing");
        let under = Ray {
            origin: Pos3::new(0.0, 2.3, 0.3),
            direction: Vec3::z(),
        };
        let hit = w.cast(&under).expect("sees its back from below");
        assert_eq!(hit.surface.face, BoxFace::Bottom as u8);
    }
}
