//! Box-shaped solids turned about the vertical (boxes, table tops, table
//! legs, and the undisplaced shape of soft blocks), and the edges where
//! their sides meet what they stand on or carry.

use crate::geometry::{BoxFace, ConvexSolid, HalfSpace, Pos3, Surface, Vec3};

/// A box whose bottom face's centre is `base`, turned by `yaw_deg` about
/// the vertical (positive counter-clockwise seen from above), of size
/// `size_m` along its own x (across), y (along) and z (up).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct OrientedBox {
    pub base: Pos3,
    pub yaw_deg: f64,
    pub size_m: [f64; 3],
}

/// A horizontal edge of a box's side face: its ends and which side.
pub(super) struct SideEdge {
    pub a: Pos3,
    pub b: Pos3,
    pub face: BoxFace,
}

impl OrientedBox {
    /// The box's own x (across) and y (along) axes in the world.
    fn axes(&self) -> (Vec3, Vec3) {
        let (s, c) = self.yaw_deg.to_radians().sin_cos();
        (Vec3::new(c, s, 0.0), Vec3::new(-s, c, 0.0))
    }

    /// The four sides: outward normal, distance from the centre line,
    /// half-length along the side, face.
    fn sides(&self) -> [(Vec3, f64, f64, BoxFace); 4] {
        let (across, along) = self.axes();
        let [sx, sy, _] = self.size_m;
        [
            (-across, sx / 2.0, sy / 2.0, BoxFace::Inner),
            (across, sx / 2.0, sy / 2.0, BoxFace::Outer),
            (-along, sy / 2.0, sx / 2.0, BoxFace::Near),
            (along, sy / 2.0, sx / 2.0, BoxFace::Far),
        ]
    }

    /// The box as six half-spaces (sides, then bottom, then top), each
    /// face named by `label`.
    pub fn solid(&self, label: impl Fn(BoxFace) -> Surface) -> ConvexSolid {
        let mut faces = Vec::with_capacity(6);
        for (normal, half, _, face) in self.sides() {
            faces.push(HalfSpace::through(
                &(self.base + normal * half),
                normal,
                label(face),
            ));
        }
        faces.push(HalfSpace::through(
            &self.base,
            -Vec3::z(),
            label(BoxFace::Bottom),
        ));
        faces.push(HalfSpace::through(
            &(self.base + Vec3::z() * self.size_m[2]),
            Vec3::z(),
            label(BoxFace::Top),
        ));
        ConvexSolid { faces }
    }

    /// The bottom edges of the four sides (where they meet the ground).
    pub fn bottom_edges(&self) -> [SideEdge; 4] {
        self.side_edges(0.0)
    }

    /// The top edges of the four sides (where they meet what they carry).
    pub fn top_edges(&self) -> [SideEdge; 4] {
        self.side_edges(self.size_m[2])
    }

    fn side_edges(&self, height_m: f64) -> [SideEdge; 4] {
        self.sides().map(|(normal, half, tangent_half, face)| {
            let tangent = Vec3::z().cross(&normal);
            let mid = self.base + normal * half + Vec3::z() * height_m;
            SideEdge {
                a: mid - tangent * tangent_half,
                b: mid + tangent * tangent_half,
                face,
            }
        })
    }
}
