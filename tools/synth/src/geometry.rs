//! Exact ray casting against convex solids.
//!
//! Every object of a scene is a union of convex solids, and every convex
//! solid is an intersection of half-spaces `normal · p <= offset` (unbounded
//! ones are allowed: the ground is the single half-space `z <= 0`). A ray
//! enters a convex solid where it crosses the last of the planes it enters
//! through (the Cyrus–Beck / slab clip), so the first surface a ray meets in
//! a scene is the smallest entry parameter over all solids. No tessellation,
//! no tolerance: the hit lies on the analytic plane up to f64 rounding.
//! The one exception, the bumpy soft block, is ray-marched in
//! `soft_solid.rs` and returns the same [`Hit`].

use nalgebra::{Point3, Vector3};

/// A direction or displacement in world or camera coordinates, metres.
pub type Vec3 = Vector3<f64>;
/// A position in world or camera coordinates, metres.
pub type Pos3 = Point3<f64>;

/// What a face is, in the robot's terms. Faces of one kind and index form
/// one planar surface of the scene (the ground may be split over several
/// solids; its faces are coplanar).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SurfaceKind {
    /// The ground the robot stands on (z = 0).
    Ground,
    /// The inclined plane (ramp, or wall at 90°).
    Ramp,
    /// The flat after the ramp: on top of an ascending ramp, at the bottom of
    /// a descending one.
    Landing,
    /// The vertical sides of an ascending ramp, or the banks beside a
    /// descending one.
    RampSide,
    /// The vertical back (face 1), the underside (face 0) and, under a
    /// raised foot line (`[ramp] base_m`), the vertical riser (face 2) of
    /// the ramp solid.
    RampBack,
    /// A side wall (`[[walls]]`), indexed.
    Wall,
    /// A box on the ground (`[[boxes]]`), indexed.
    Box,
    /// The top slab of a table (`[[tables]]`), indexed; faces are [`BoxFace`]s.
    Table,
    /// A leg of a table, indexed by its table; face `6 * leg + BoxFace`, legs
    /// numbered near-left, near-right, far-left, far-right (table frame).
    TableLeg,
    /// The ceiling (`[ceiling]`): its underside is [`BoxFace::Bottom`], the
    /// vertical ends of an overhang [`BoxFace::Near`] and [`BoxFace::Far`].
    Ceiling,
    /// A block with bumpy top and sides (`[[soft_blocks]]`), indexed; faces
    /// are [`BoxFace`]s. Its top and sides are not planar.
    SoftBlock,
    /// A flat board (`[[panels]]`), indexed; faces are [`BoxFace`]s in the
    /// board's own frame: `Top` the surface facing up its normal, `Bottom`
    /// the back, `Near` the lower edge, `Far` the upper edge, `Inner` /
    /// `Outer` the left / right ends seen looking up the slope.
    Panel,
}

/// One surface of the scene: a kind, which object of that kind (walls,
/// boxes, tables and soft blocks are numbered in scene order), and which
/// face of it. Every surface is planar except the top and sides of a soft
/// block.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Surface {
    pub kind: SurfaceKind,
    pub index: u16,
    /// Which face of the object: for walls, boxes, tables, ceilings and
    /// soft blocks see [`BoxFace`] (table legs: `6 * leg + BoxFace`); the
    /// two sides of a ramp are 0 (left) and 1 (right); a ramp's back is 1
    /// and its underside 0. Ground, ramp and landing have face 0.
    pub face: u8,
}

impl Surface {
    /// The surface of a kind that exists once per scene (ground, ramp, landing).
    pub const fn single(kind: SurfaceKind) -> Self {
        Self {
            kind,
            index: 0,
            face: 0,
        }
    }

    /// Face `face` of object `index` of a kind.
    pub const fn new(kind: SurfaceKind, index: u16, face: u8) -> Self {
        Self { kind, index, face }
    }
}

/// The faces of a box-shaped solid (walls, boxes, tables, table legs,
/// soft blocks; the ceiling's underside and ends), for [`Surface::face`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum BoxFace {
    /// A wall's face towards the centre line; a box's face towards -x (own frame).
    Inner = 0,
    /// A wall's face away from the centre line; a box's face towards +x.
    Outer = 1,
    /// Facing the camera (-y, own frame).
    Near = 2,
    /// Facing away (+y).
    Far = 3,
    Bottom = 4,
    Top = 5,
}

/// A bounding plane of a convex solid: points inside satisfy
/// `normal · p <= offset`. `normal` is a unit vector pointing out of the solid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfSpace {
    pub normal: Vec3,
    pub offset: f64,
    pub surface: Surface,
}

impl HalfSpace {
    /// The half-space with outward `normal` (normalised here) whose boundary
    /// passes through `point`. `normal` must be non-zero (scene code only
    /// passes constant or trigonometric unit vectors).
    pub fn through(point: &Pos3, normal: Vec3, surface: Surface) -> Self {
        let normal = normal.normalize();
        Self {
            normal,
            offset: normal.dot(&point.coords),
            surface,
        }
    }

    /// Signed distance of `p` from the plane, positive outside.
    pub fn signed_distance(&self, p: &Pos3) -> f64 {
        self.normal.dot(&p.coords) - self.offset
    }
}

/// An intersection of half-spaces.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ConvexSolid {
    pub faces: Vec<HalfSpace>,
}

/// A ray `origin + t * direction`, t >= 0. `direction` need not be unit
/// length: the camera uses `(x/z, y/z, 1)` in camera coordinates so that t is
/// the depth along the optical axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub origin: Pos3,
    pub direction: Vec3,
}

impl Ray {
    /// The point at parameter `t`.
    pub fn at(&self, t: f64) -> Pos3 {
        self.origin + self.direction * t
    }
}

/// Where a ray first meets a solid or a scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit (depth along the optical axis for camera rays).
    pub t: f64,
    /// Outward unit normal of the face that was hit.
    pub normal: Vec3,
    pub surface: Surface,
}

impl ConvexSolid {
    /// True when `p` lies strictly inside every face.
    pub fn contains(&self, p: &Pos3) -> bool {
        self.faces.iter().all(|f| f.signed_distance(p) < 0.0)
    }

    /// The point where `ray` enters this solid, if it does at some t > 0.
    /// A ray starting inside the solid (or on its boundary, leaving) has no
    /// entry and gives `None`.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut t_enter = f64::NEG_INFINITY;
        let mut t_exit = f64::INFINITY;
        let mut entry: Option<&HalfSpace> = None;
        for face in &self.faces {
            let rate = face.normal.dot(&ray.direction);
            let outside_by = face.signed_distance(&ray.origin);
            if rate == 0.0 {
                // Parallel to this plane: either always inside it or never.
                if outside_by >= 0.0 {
                    return None;
                }
                continue;
            }
            let t = -outside_by / rate;
            if rate < 0.0 {
                if t > t_enter {
                    t_enter = t;
                    entry = Some(face);
                }
            } else if t < t_exit {
                t_exit = t;
            }
            if t_enter > t_exit {
                return None;
            }
        }
        let face = entry?;
        (t_enter > 0.0 && t_enter <= t_exit).then_some(Hit {
            t: t_enter,
            normal: face.normal,
            surface: face.surface,
        })
    }
}

/// Nearest entry of `ray` over `solids`.
pub fn cast(solids: &[ConvexSolid], ray: &Ray) -> Option<Hit> {
    solids
        .iter()
        .filter_map(|s| s.intersect(ray))
        .min_by(|a, b| a.t.total_cmp(&b.t))
}

/// Distance from `p` to the segment `a`–`b`.
pub fn distance_to_segment(p: &Pos3, a: &Pos3, b: &Pos3) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let s = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * s)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    const FACE: Surface = Surface::single(SurfaceKind::Box);

    fn unit_cube() -> ConvexSolid {
        let mut faces = Vec::new();
        for axis in 0..3 {
            let mut n = Vec3::zeros();
            n[axis] = 1.0;
            faces.push(HalfSpace {
                normal: n,
                offset: 1.0,
                surface: FACE,
            });
            faces.push(HalfSpace {
                normal: -n,
                offset: 0.0,
                surface: FACE,
            });
        }
        ConvexSolid { faces }
    }

    #[test]
    fn ray_enters_cube_through_the_near_face() {
        let ray = Ray {
            origin: Pos3::new(0.5, 0.5, -2.0),
            direction: Vec3::new(0.0, 0.0, 1.0),
        };
        let hit = unit_cube().intersect(&ray).expect("hits the cube");
        assert_eq!(hit.t, 2.0);
        assert_eq!(hit.normal, Vec3::new(0.0, 0.0, -1.0));
    }

    #[test]
    fn oblique_ray_matches_brute_force_marching() {
        let cube = unit_cube();
        // Oracle: march along the ray in tiny steps and find the first
        // point inside the cube.
        let dirs = [
            Vec3::new(0.3, 0.2, 1.0),
            Vec3::new(-0.3, 0.1, 1.0),
            Vec3::new(-0.5, 0.1, 1.0),
            Vec3::new(0.9, 0.8, 0.7),
        ];
        for dir in dirs {
            let ray = Ray {
                origin: Pos3::new(0.2, 0.3, -0.5),
                direction: dir,
            };
            let analytic = cube.intersect(&ray).map(|h| h.t);
            let step = 1e-5;
            let marched = (1..400_000)
                .map(|i| f64::from(i) * step)
                .find(|&t| cube.contains(&ray.at(t)));
            match (analytic, marched) {
                (Some(a), Some(m)) => assert!((a - m).abs() <= 1.5 * step, "{a} vs {m}"),
                (None, None) => {}
                other => panic!("disagree for {dir:?}: {other:?}"),
            }
        }
    }

    #[test]
    fn ray_missing_or_pointing_away_has_no_hit() {
        let cube = unit_cube();
        let miss = Ray {
            origin: Pos3::new(2.0, 2.0, -1.0),
            direction: Vec3::new(0.0, 0.0, 1.0),
        };
        assert!(cube.intersect(&miss).is_none());
        let away = Ray {
            origin: Pos3::new(0.5, 0.5, -1.0),
            direction: Vec3::new(0.0, 0.0, -1.0),
        };
        assert!(cube.intersect(&away).is_none());
        let from_inside = Ray {
            origin: Pos3::new(0.5, 0.5, 0.5),
            direction: Vec3::new(0.0, 0.0, 1.0),
        };
        assert!(cube.intersect(&from_inside).is_none());
    }

    #[test]
    fn half_space_ground_is_hit_at_height_over_sine() {
        let ground = ConvexSolid {
            faces: vec![HalfSpace {
                normal: Vec3::z(),
                offset: 0.0,
                surface: Surface::single(SurfaceKind::Ground),
            }],
        };
        let depression = 30f64.to_radians();
        let ray = Ray {
            origin: Pos3::new(0.0, 0.0, 0.5),
            direction: Vec3::new(0.0, depression.cos(), -depression.sin()),
        };
        let hit = ground.intersect(&ray).expect("looks down at the ground");
        assert!((hit.t - 0.5 / depression.sin()).abs() < 1e-12);
    }

    #[test]
    fn nearest_solid_wins() {
        let near = unit_cube();
        let mut far = unit_cube();
        for f in &mut far.faces {
            // Shift the cube by +3 along z.
            f.offset += f.normal.z * 3.0;
        }
        let ray = Ray {
            origin: Pos3::new(0.5, 0.5, -1.0),
            direction: Vec3::z(),
        };
        let hit = cast(&[far, near], &ray).expect("hits both");
        assert_eq!(hit.t, 1.0);
    }

    #[test]
    fn segment_distance() {
        let a = Pos3::new(0.0, 0.0, 0.0);
        let b = Pos3::new(2.0, 0.0, 0.0);
        assert_eq!(distance_to_segment(&Pos3::new(1.0, 3.0, 4.0), &a, &b), 5.0);
        assert_eq!(distance_to_segment(&Pos3::new(-3.0, 4.0, 0.0), &a, &b), 5.0);
    }
}
