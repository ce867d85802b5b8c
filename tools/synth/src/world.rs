//! A [`Scene`] turned into geometry: convex solids to ray-cast, and the
//! concave junctions where multipath interference biases the depth.
//!
//! - Ascending ramp: the ground half-space `z <= 0`, plus one convex solid
//!   under the ramp surface, its landing and its back/sides (the region
//!   under `min(slope, landing)` is convex).
//! - Descending ramp: the lower ground `z <= -drop`, a wedge between the
//!   upper ground and the slope, and (for a finite width) two banks beside
//!   the trench.
//! - Walls and boxes: one box-shaped solid each (boxes, table slabs and
//!   legs share `world/blocks.rs`).
//! - Tables: a slab and four legs, box solids (`world/table.rs`).
//! - Ceiling: one convex solid above its height (`world/ceiling.rs`).
//! - Soft blocks: one ray-marched [`SoftSolid`] each (`world/soft_block.rs`).
//! - Panels: one tilted, yawed slab each (`world/panel.rs`).
//! - A ramp whose foot is raised (`base_m`) stands on a vertical riser: its
//!   solid reaches the ground under the foot line.

mod blocks;
mod ceiling;
mod panel;
mod soft_block;
mod table;

use blocks::OrientedBox;

use crate::geometry::{
    cast, distance_to_segment, BoxFace, ConvexSolid, HalfSpace, Hit, Pos3, Ray, Surface,
    SurfaceKind, Vec3,
};
use crate::scene::{GroundBox, Ramp, Scene, SideWall, SlopeDirection};
use crate::sensor_model::SensorModel;
use crate::soft_solid::SoftSolid;

/// Half-length used for edges of unbounded surfaces, metres: far beyond
/// any depth the camera reports, small enough for exact f64 distances.
const UNBOUNDED_EDGE_M: f64 = 1.0e3;
/// Thickness given to the top of a 90° wall that has no landing, metres.
const WALL_TOP_M: f64 = 0.1;

/// A line segment where two surfaces meet in a concave corner (seen from
/// the free space): light bounces between them (multipath).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConcaveJunction {
    pub a: Pos3,
    pub b: Pos3,
    pub surfaces: [Surface; 2],
}

/// The geometry of a scene.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct World {
    pub solids: Vec<ConvexSolid>,
    /// Solids with bumpy faces (soft blocks), ray-marched.
    pub soft_solids: Vec<SoftSolid>,
    pub junctions: Vec<ConcaveJunction>,
}

impl World {
    /// Builds the solids and junctions of a (validated) scene.
    pub fn build(scene: &Scene) -> Self {
        let mut world = World::default();
        match &scene.ramp {
            None => world.solids.push(ground_half_space()),
            Some(ramp) => match ramp.direction {
                SlopeDirection::Ascending => {
                    world.solids.push(ground_half_space());
                    world.add_ascending(ramp);
                }
                SlopeDirection::Descending => world.add_descending(ramp),
            },
        }
        for (i, wall) in scene.walls.iter().enumerate() {
            world.add_wall(wall, surface_index(i));
        }
        for (i, b) in scene.boxes.iter().enumerate() {
            world.add_box(b, surface_index(i));
        }
        for (i, table) in scene.tables.iter().enumerate() {
            world.add_table(table, surface_index(i));
        }
        if let Some(ceiling) = &scene.ceiling {
            world.add_ceiling(ceiling);
        }
        for (i, block) in scene.soft_blocks.iter().enumerate() {
            world.add_soft_block(block, surface_index(i));
        }
        for (i, panel) in scene.panels.iter().enumerate() {
            world.add_panel(panel, surface_index(i));
        }
        world
    }

    /// The first surface `ray` meets.
    pub fn cast(&self, ray: &Ray) -> Option<Hit> {
        let exact = cast(&self.solids, ray);
        self.soft_solids
            .iter()
            .filter_map(|s| s.intersect(ray))
            .chain(exact)
            .min_by(|a, b| a.t.total_cmp(&b.t))
    }

    /// True when `p` is strictly inside some solid.
    pub fn contains(&self, p: &Pos3) -> bool {
        self.solids.iter().any(|s| s.contains(p)) || self.soft_solids.iter().any(|s| s.contains(p))
    }

    /// Multipath bias (metres, positive = measured too far) of a reading of
    /// `surface` at `p`: the model's amplitude, decaying exponentially with
    /// the distance to the nearest concave junction that `surface` is part of.
    pub fn multipath_bias_m(&self, model: &SensorModel, p: &Pos3, surface: Surface) -> f64 {
        if model.multipath_bias_m == 0.0 {
            return 0.0;
        }
        let nearest = self
            .junctions
            .iter()
            .filter(|j| j.surfaces.contains(&surface))
            .map(|j| distance_to_segment(p, &j.a, &j.b))
            .fold(f64::INFINITY, f64::min);
        if nearest.is_finite() {
            model.multipath_bias_m * (-nearest / model.multipath_decay_m).exp()
        } else {
            0.0
        }
    }

    fn add_ascending(&mut self, ramp: &Ramp) {
        let frame = RampFrame::new(ramp);
        let (run, rise) = frame.run_rise(ramp);
        let (sa, ca) = ramp.slope_deg.to_radians().sin_cos();
        let half_width = ramp.width_m / 2.0;
        // A raised foot stands on a riser: the solid reaches down to the
        // ground (frame z = -base) and has a vertical front under the foot line.
        let base = ramp.base_m;
        let mut solid = ConvexSolid::default();
        solid
            .faces
            .push(frame.face([0.0, 0.0, -base], [0.0, 0.0, -1.0], RAMP_UNDERSIDE));
        solid
            .faces
            .push(frame.face([0.0, 0.0, 0.0], [0.0, -sa, ca], RAMP));
        if base > 0.0 {
            solid
                .faces
                .push(frame.face([0.0, 0.0, 0.0], [0.0, -1.0, 0.0], RAMP_FRONT));
        }
        let mut back_y = f64::INFINITY;
        if rise.is_finite() {
            back_y = if ramp.slope_deg >= 90.0 && ramp.landing_m == 0.0 {
                WALL_TOP_M
            } else {
                run + ramp.landing_m
            };
            solid
                .faces
                .push(frame.face([0.0, 0.0, rise], [0.0, 0.0, 1.0], LANDING));
            solid
                .faces
                .push(frame.face([0.0, back_y, 0.0], [0.0, 1.0, 0.0], RAMP_BACK));
        }
        if half_width.is_finite() {
            solid
                .faces
                .push(frame.face([-half_width, 0.0, 0.0], [-1.0, 0.0, 0.0], RAMP_LEFT));
            solid
                .faces
                .push(frame.face([half_width, 0.0, 0.0], [1.0, 0.0, 0.0], RAMP_RIGHT));
        }
        self.solids.push(solid);

        // The ground meets the ramp at its foot line, or the riser under it.
        let edge = half_width.min(UNBOUNDED_EDGE_M);
        let foot = if base > 0.0 { RAMP_FRONT } else { RAMP };
        self.junctions.push(ConcaveJunction {
            a: frame.point([-edge, 0.0, -base]),
            b: frame.point([edge, 0.0, -base]),
            surfaces: [GROUND, foot],
        });
        if half_width.is_finite() {
            let end = back_y.min(UNBOUNDED_EDGE_M);
            for (x, side) in [(-half_width, RAMP_LEFT), (half_width, RAMP_RIGHT)] {
                self.junctions.push(ConcaveJunction {
                    a: frame.point([x, 0.0, -base]),
                    b: frame.point([x, end, -base]),
                    surfaces: [GROUND, side],
                });
            }
        }
    }

    fn add_descending(&mut self, ramp: &Ramp) {
        let frame = RampFrame::new(ramp);
        let (run, drop) = frame.run_rise(ramp);
        let (sa, ca) = ramp.slope_deg.to_radians().sin_cos();
        let half_width = ramp.width_m / 2.0;

        let mut wedge = ConvexSolid::default();
        wedge
            .faces
            .push(frame.face([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], GROUND));
        wedge
            .faces
            .push(frame.face([0.0, 0.0, 0.0], [0.0, sa, ca], RAMP));
        if drop.is_finite() {
            wedge
                .faces
                .push(frame.face([0.0, 0.0, -drop], [0.0, 0.0, -1.0], LANDING));
            let mut lower = ConvexSolid::default();
            lower
                .faces
                .push(frame.face([0.0, 0.0, -drop], [0.0, 0.0, 1.0], LANDING));
            self.solids.push(lower);
            let edge = half_width.min(UNBOUNDED_EDGE_M);
            self.junctions.push(ConcaveJunction {
                a: frame.point([-edge, run, -drop]),
                b: frame.point([edge, run, -drop]),
                surfaces: [RAMP, LANDING],
            });
        }
        if half_width.is_finite() {
            // The wedge's own sides are buried in the banks; the banks'
            // inner faces are the visible sides of the trench.
            for (side, surface) in [(-1.0, RAMP_LEFT), (1.0, RAMP_RIGHT)] {
                let x = side * half_width;
                wedge
                    .faces
                    .push(frame.face([x, 0.0, 0.0], [side, 0.0, 0.0], surface));
                let mut bank = ConvexSolid::default();
                bank.faces
                    .push(frame.face([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], GROUND));
                bank.faces
                    .push(frame.face([x, 0.0, 0.0], [-side, 0.0, 0.0], surface));
                self.solids.push(bank);
            }
        }
        self.solids.push(wedge);
    }

    fn add_wall(&mut self, wall: &SideWall, index: u16) {
        let face = |f: BoxFace| Surface::new(SurfaceKind::Wall, index, f as u8);
        let side = wall.x_m.signum();
        let outer = wall.x_m + side * wall.thickness_m;
        let faces = vec![
            HalfSpace::through(
                &Pos3::new(wall.x_m, 0.0, 0.0),
                Vec3::new(-side, 0.0, 0.0),
                face(BoxFace::Inner),
            ),
            HalfSpace::through(
                &Pos3::new(outer, 0.0, 0.0),
                Vec3::new(side, 0.0, 0.0),
                face(BoxFace::Outer),
            ),
            HalfSpace::through(
                &Pos3::new(0.0, wall.from_m, 0.0),
                -Vec3::y(),
                face(BoxFace::Near),
            ),
            HalfSpace::through(
                &Pos3::new(0.0, wall.to_m, 0.0),
                Vec3::y(),
                face(BoxFace::Far),
            ),
            HalfSpace::through(&Pos3::origin(), -Vec3::z(), face(BoxFace::Bottom)),
            HalfSpace::through(
                &Pos3::new(0.0, 0.0, wall.height_m),
                Vec3::z(),
                face(BoxFace::Top),
            ),
        ];
        self.solids.push(ConvexSolid { faces });
        let near_inner = Pos3::new(wall.x_m, wall.from_m, 0.0);
        let near_outer = Pos3::new(outer, wall.from_m, 0.0);
        self.junctions.push(ConcaveJunction {
            a: near_inner,
            b: Pos3::new(wall.x_m, wall.to_m, 0.0),
            surfaces: [GROUND, face(BoxFace::Inner)],
        });
        self.junctions.push(ConcaveJunction {
            a: near_inner,
            b: near_outer,
            surfaces: [GROUND, face(BoxFace::Near)],
        });
    }

    fn add_box(&mut self, b: &GroundBox, index: u16) {
        let face = |f: BoxFace| Surface::new(SurfaceKind::Box, index, f as u8);
        let shape = OrientedBox {
            base: Pos3::new(b.x_m, b.y_m, 0.0),
            yaw_deg: b.yaw_deg,
            size_m: b.size_m,
        };
        self.solids.push(shape.solid(face));
        // Each side meets the ground along its bottom edge.
        for e in shape.bottom_edges() {
            self.junctions.push(ConcaveJunction {
                a: e.a,
                b: e.b,
                surfaces: [GROUND, face(e.face)],
            });
        }
    }
}

const GROUND: Surface = Surface::single(SurfaceKind::Ground);
const RAMP: Surface = Surface::single(SurfaceKind::Ramp);
const LANDING: Surface = Surface::single(SurfaceKind::Landing);
const RAMP_LEFT: Surface = Surface::new(SurfaceKind::RampSide, 0, 0);
const RAMP_RIGHT: Surface = Surface::new(SurfaceKind::RampSide, 0, 1);
const RAMP_UNDERSIDE: Surface = Surface::new(SurfaceKind::RampBack, 0, 0);
const RAMP_BACK: Surface = Surface::new(SurfaceKind::RampBack, 0, 1);
const RAMP_FRONT: Surface = Surface::new(SurfaceKind::RampBack, 0, 2);

fn ground_half_space() -> ConvexSolid {
    ConvexSolid {
        faces: vec![HalfSpace::through(&Pos3::origin(), Vec3::z(), GROUND)],
    }
}

fn surface_index(i: usize) -> u16 {
    // Scene::validate caps the number of indexed objects below u16::MAX.
    u16::try_from(i).unwrap_or(u16::MAX)
}

/// The ramp's own frame: origin at the foot line's centre, x' across the
/// ramp, y' along its uphill (or downhill) direction, z up.
struct RampFrame {
    origin: Pos3,
    across: Vec3,
    along: Vec3,
}

impl RampFrame {
    fn new(ramp: &Ramp) -> Self {
        let (s, c) = ramp.yaw_deg.to_radians().sin_cos();
        Self {
            origin: Pos3::new(ramp.offset_m, ramp.distance_m, ramp.base_m),
            across: Vec3::new(c, s, 0.0),
            along: Vec3::new(-s, c, 0.0),
        }
    }

    fn point(&self, [x, y, z]: [f64; 3]) -> Pos3 {
        self.origin + self.direction([x, y, z])
    }

    fn direction(&self, [x, y, z]: [f64; 3]) -> Vec3 {
        self.across * x + self.along * y + Vec3::z() * z
    }

    fn face(&self, point: [f64; 3], normal: [f64; 3], surface: Surface) -> HalfSpace {
        HalfSpace::through(&self.point(point), self.direction(normal), surface)
    }

    /// Horizontal run and vertical rise (or drop) of the slope; a 90° wall
    /// has no run.
    fn run_rise(&self, ramp: &Ramp) -> (f64, f64) {
        if ramp.slope_deg >= 90.0 {
            return (0.0, ramp.length_m);
        }
        let (s, c) = ramp.slope_deg.to_radians().sin_cos();
        (ramp.length_m * c, ramp.length_m * s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Ray;

    fn down_ray(y: f64, x: f64) -> Ray {
        Ray {
            origin: Pos3::new(x, y, 10.0),
            direction: -Vec3::z(),
        }
    }

    /// Height of the terrain under (x, y), by casting a vertical ray.
    fn terrain(world: &World, x: f64, y: f64) -> Option<(f64, SurfaceKind)> {
        world
            .cast(&down_ray(y, x))
            .map(|h| (10.0 - h.t, h.surface.kind))
    }

    #[test]
    fn ascending_ramp_profile_is_exact() {
        let ramp = Ramp {
            slope_deg: 30.0,
            distance_m: 2.0,
            width_m: 2.0,
            length_m: 2.0,
            landing_m: 0.5,
            ..Ramp::default()
        };
        let scene = Scene {
            ramp: Some(ramp),
            ..Scene::default()
        };
        let world = World::build(&scene);
        let tan = 30f64.to_radians().tan();
        let run = 2.0 * 30f64.to_radians().cos();
        for y in [0.5, 1.99, 2.01, 2.5, 3.0, 3.7] {
            let (z, kind) = terrain(&world, 0.0, y).expect("terrain everywhere");
            let expected = if y < 2.0 {
                (0.0, SurfaceKind::Ground)
            } else if y < 2.0 + run {
                ((y - 2.0) * tan, SurfaceKind::Ramp)
            } else {
                (1.0, SurfaceKind::Landing)
            };
            assert!((z - expected.0).abs() < 1e-9, "y = {y}: {z}");
            assert_eq!(kind, expected.1, "y = {y}");
        }
        // Beyond the landing, and beside the ramp: ground.
        assert_eq!(
            terrain(&world, 0.0, 2.0 + run + 0.6),
            Some((0.0, SurfaceKind::Ground))
        );
        assert_eq!(terrain(&world, 1.2, 2.5), Some((0.0, SurfaceKind::Ground)));
    }

    #[test]
    fn raised_foot_stands_on_a_riser() {
        let ramp = Ramp {
            slope_deg: 16.0,
            distance_m: 2.0,
            width_m: 1.2,
            length_m: 2.0,
            landing_m: 0.5,
            base_m: 0.1,
            ..Ramp::default()
        };
        let world = World::build(&Scene {
            ramp: Some(ramp),
            ..Scene::default()
        });
        let tan = 16f64.to_radians().tan();
        for y in [1.99, 2.001, 2.5, 3.5] {
            let (z, kind) = terrain(&world, 0.2, y).expect("terrain everywhere");
            if y < 2.0 {
                assert_eq!((z, kind), (0.0, SurfaceKind::Ground));
            } else {
                assert_eq!(kind, SurfaceKind::Ramp, "y = {y}");
                assert!((z - (0.1 + (y - 2.0) * tan)).abs() < 1e-12, "y = {y}: {z}");
            }
        }
        // The riser under the foot line faces the camera, 0.1 m high.
        for (z, front) in [(0.05, true), (0.099, true), (0.101, false)] {
            let hit = world
                .cast(&Ray {
                    origin: Pos3::new(0.3, 0.0, z),
                    direction: Vec3::y(),
                })
                .expect("hits the ramp");
            assert_eq!(hit.surface == RAMP_FRONT, front, "z = {z}");
            if front {
                assert!((hit.t - 2.0).abs() < 1e-12);
            }
        }
        // Beside the ramp: ground; the raised ramp meets the ground at its riser.
        assert_eq!(terrain(&world, 0.7, 2.5), Some((0.0, SurfaceKind::Ground)));
        assert!(world.junctions.iter().all(|j| j.a.z == 0.0 && j.b.z == 0.0));
    }

    #[test]
    fn descending_ramp_profile_is_exact() {
        let ramp = Ramp {
            direction: SlopeDirection::Descending,
            slope_deg: 20.0,
            distance_m: 1.0,
            width_m: 2.0,
            length_m: 1.5,
            ..Ramp::default()
        };
        let scene = Scene {
            ramp: Some(ramp),
            ..Scene::default()
        };
        let world = World::build(&scene);
        let tan = 20f64.to_radians().tan();
        let run = 1.5 * 20f64.to_radians().cos();
        let drop = 1.5 * 20f64.to_radians().sin();
        for y in [0.2, 0.99, 1.01, 1.5, 2.0, 2.5, 4.0] {
            let (z, kind) = terrain(&world, 0.3, y).expect("terrain everywhere");
            let expected = if y < 1.0 {
                (0.0, SurfaceKind::Ground)
            } else if y < 1.0 + run {
                (-(y - 1.0) * tan, SurfaceKind::Ramp)
            } else {
                (-drop, SurfaceKind::Landing)
            };
            assert!((z - expected.0).abs() < 1e-9, "y = {y}: {z}");
            assert_eq!(kind, expected.1, "y = {y}");
        }
        // The banks beside the trench stay at ground level.
        assert_eq!(terrain(&world, 1.5, 2.0), Some((0.0, SurfaceKind::Ground)));
        assert_eq!(terrain(&world, -1.5, 0.5), Some((0.0, SurfaceKind::Ground)));
        // A ray looking along the trench at the bank's inner face.
        let side_ray = Ray {
            origin: Pos3::new(0.0, 3.0, -0.2),
            direction: Vec3::x(),
        };
        let hit = world.cast(&side_ray).expect("hits the bank");
        assert_eq!(hit.surface.kind, SurfaceKind::RampSide);
        assert!((hit.t - 1.0).abs() < 1e-12);
    }

    #[test]
    fn yawed_ramp_foot_line_turns_left() {
        let ramp = Ramp {
            slope_deg: 45.0,
            distance_m: 2.0,
            width_m: f64::INFINITY,
            length_m: f64::INFINITY,
            yaw_deg: 30.0,
            ..Ramp::default()
        };
        let scene = Scene {
            ramp: Some(ramp),
            ..Scene::default()
        };
        let world = World::build(&scene);
        // Uphill direction (-sin 30, cos 30): a point 1 m uphill from the
        // foot centre, measured along it, is 1 m high (45°).
        let along = Vec3::new(-0.5, 30f64.to_radians().cos(), 0.0);
        let p = Pos3::new(0.0, 2.0, 0.0) + along;
        let (z, kind) = terrain(&world, p.x, p.y).expect("terrain");
        assert_eq!(kind, SurfaceKind::Ramp);
        assert!((z - 1.0).abs() < 1e-9);
    }

    #[test]
    fn wall_and_box_are_solid_and_bias_decays() {
        let scene = Scene {
            walls: vec![SideWall {
                x_m: -1.0,
                ..SideWall::default()
            }],
            boxes: vec![GroundBox {
                x_m: 0.5,
                y_m: 1.0,
                size_m: [0.2, 0.4, 0.3],
                yaw_deg: 0.0,
            }],
            ..Scene::default()
        };
        let world = World::build(&scene);
        assert!(world.contains(&Pos3::new(-1.05, 1.0, 0.5)));
        assert!(!world.contains(&Pos3::new(-0.95, 1.0, 0.5)));
        let (top, kind) = terrain(&world, 0.5, 1.1).expect("box top");
        assert!((top - 0.3).abs() < 1e-12 && kind == SurfaceKind::Box);
        let model = SensorModel::default();
        let ground = Surface::single(SurfaceKind::Ground);
        let at = |d: f64| world.multipath_bias_m(&model, &Pos3::new(-1.0 + d, 3.0, 0.0), ground);
        // The wall's inner face is part of the junction too, the top is not.
        let inner = Surface::new(SurfaceKind::Wall, 0, BoxFace::Inner as u8);
        let top = Surface::new(SurfaceKind::Wall, 0, BoxFace::Top as u8);
        let on_wall = Pos3::new(-1.0, 3.0, 0.1);
        let expected = model.multipath_bias_m * (-0.1 / model.multipath_decay_m).exp();
        assert!((world.multipath_bias_m(&model, &on_wall, inner) - expected).abs() < 1e-15);
        assert_eq!(world.multipath_bias_m(&model, &on_wall, top), 0.0);
        assert!((at(0.0) - model.multipath_bias_m).abs() < 1e-15);
        let expected = model.multipath_bias_m * (-0.2 / model.multipath_decay_m).exp();
        assert!((at(0.2) - expected).abs() < 1e-15);
        // A surface that is not part of any junction gets no bias.
        let ramp = Surface::single(SurfaceKind::Ramp);
        assert_eq!(
            world.multipath_bias_m(&model, &Pos3::new(-1.0, 3.0, 0.0), ramp),
            0.0
        );
    }
}
