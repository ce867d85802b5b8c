//! The hinge: the floor's frame (forward along the floor, up its normal,
//! across the path) and the rigid rotation of everything beyond the hinge
//! line about that line.

use nalgebra::Vector3;

/// The floor plane in camera coordinates: `up · p + height_m = 0`, so that a
/// point's height above the floor is `up · p + height_m` and the camera
/// (the origin) stands `height_m` above it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloorPlane {
    /// Upward unit normal, camera coordinates (x right, y down, z forward).
    pub up: [f64; 3],
    /// The camera's height above the plane, metres (> 0).
    pub height_m: f64,
    /// Points of the final least-squares fit (the floor's inliers in the
    /// lower image).
    pub fit_points: usize,
    /// Their RMS distance from the plane, metres.
    pub rms_m: f64,
}

impl FloorPlane {
    /// Height of `p` above the plane, metres.
    pub fn height_of(&self, p: [f64; 3]) -> f64 {
        Vector3::from(self.up).dot(&Vector3::from(p)) + self.height_m
    }
}

/// A hinge line across the path on the floor, and the bend about it.
///
/// Floor coordinates of a camera point `p`: `ahead_m` = forward distance
/// from the camera's foot on the floor, along the optical axis projected
/// onto the floor; `height_m` = height above the floor; `across_m` = to the
/// right. The hinge line is `ahead_m = hinge_m`, `height_m = 0`; every point
/// with `ahead_m > hinge_m` is rotated upward by `angle_deg` about it, so
/// its height above the floor becomes its height above the ramp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hinge {
    pub floor: FloorPlane,
    /// Unit forward direction on the floor (camera coordinates).
    pub forward: [f64; 3],
    /// Unit direction of the hinge line, to the camera's right on the floor.
    pub across: [f64; 3],
    /// Distance of the hinge line ahead of the camera's foot, metres.
    pub hinge_m: f64,
    /// The bend, degrees (the ramp's slope).
    pub angle_deg: f64,
}

/// A point in the floor's frame (see [`Hinge`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloorCoordinates {
    pub ahead_m: f64,
    pub height_m: f64,
    pub across_m: f64,
}

impl Hinge {
    /// The hinge `hinge_m` ahead on `floor`; `None` when the optical axis
    /// is (within 1e-6) along the floor's normal, so that no forward
    /// direction exists.
    pub fn new(floor: FloorPlane, hinge_m: f64, angle_deg: f64) -> Option<Self> {
        let up = Vector3::from(floor.up);
        let axis = Vector3::z();
        let forward = axis - up * up.dot(&axis);
        let norm = forward.norm();
        if norm < 1e-6 {
            return None;
        }
        let forward = forward / norm;
        // x right, y down, z forward: forward x up points to the camera's right.
        let across = forward.cross(&up);
        Some(Self {
            floor,
            forward: forward.into(),
            across: across.into(),
            hinge_m,
            angle_deg,
        })
    }

    fn up(&self) -> Vector3<f64> {
        Vector3::from(self.floor.up)
    }

    fn forward(&self) -> Vector3<f64> {
        Vector3::from(self.forward)
    }

    /// `p` in the floor's frame.
    pub fn coordinates(&self, p: [f64; 3]) -> FloorCoordinates {
        let v = Vector3::from(p);
        FloorCoordinates {
            // The camera's foot is -height_m * up, which is orthogonal to forward.
            ahead_m: self.forward().dot(&v),
            height_m: self.up().dot(&v) + self.floor.height_m,
            across_m: Vector3::from(self.across).dot(&v),
        }
    }

    /// True for a point whose foot on the floor lies beyond the hinge line.
    pub fn is_beyond(&self, p: [f64; 3]) -> bool {
        self.coordinates(p).ahead_m > self.hinge_m
    }

    /// `p` rotated upward by the bend about the hinge line (whatever side
    /// of it `p` lies on).
    pub fn rotate(&self, p: [f64; 3]) -> [f64; 3] {
        let c = self.coordinates(p);
        let (sin, cos) = self.angle_deg.to_radians().sin_cos();
        let t = c.ahead_m - self.hinge_m;
        let ahead = self.hinge_m + t * cos - c.height_m * sin;
        let height = t * sin + c.height_m * cos;
        self.from_coordinates(FloorCoordinates {
            ahead_m: ahead,
            height_m: height,
            across_m: c.across_m,
        })
    }

    /// `p` bent: rotated when beyond the hinge line, unchanged otherwise.
    pub fn bend(&self, p: [f64; 3]) -> [f64; 3] {
        if self.is_beyond(p) {
            self.rotate(p)
        } else {
            p
        }
    }

    /// The camera point with floor coordinates `c`.
    pub fn from_coordinates(&self, c: FloorCoordinates) -> [f64; 3] {
        let v = self.forward() * c.ahead_m
            + self.up() * (c.height_m - self.floor.height_m)
            + Vector3::from(self.across) * c.across_m;
        v.into()
    }

    /// The ramp's upward unit normal (the floor's, rotated by the bend).
    pub fn ramp_up(&self) -> [f64; 3] {
        let (sin, cos) = self.angle_deg.to_radians().sin_cos();
        (self.up() * cos - self.forward() * sin).into()
    }

    /// Coordinates of `p` in the ramp's frame: distance up the ramp from
    /// the hinge line (`ahead_m`, counted from the hinge), height above the
    /// ramp, across. The inverse rotation of [`Hinge::rotate`].
    pub fn ramp_coordinates(&self, p: [f64; 3]) -> FloorCoordinates {
        let c = self.coordinates(p);
        let (sin, cos) = self.angle_deg.to_radians().sin_cos();
        let t = c.ahead_m - self.hinge_m;
        FloorCoordinates {
            ahead_m: t * cos + c.height_m * sin,
            height_m: -t * sin + c.height_m * cos,
            across_m: c.across_m,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hinge(angle_deg: f64) -> Hinge {
        // A camera 0.8 m up, pitched 20° down (p = -20°, r = 0): the spec's
        // up = (-sin r cos p, -cos r cos p, sin p).
        let p = (-20f64).to_radians();
        let floor = FloorPlane {
            up: [0.0, -p.cos(), p.sin()],
            height_m: 0.8,
            fit_points: 0,
            rms_m: 0.0,
        };
        Hinge::new(floor, 1.5, angle_deg).expect("a forward direction")
    }

    #[test]
    fn the_frame_is_orthonormal_and_right_handed_for_the_camera() {
        let h = hinge(10.0);
        let (f, u, a) = (
            Vector3::from(h.forward),
            Vector3::from(h.floor.up),
            Vector3::from(h.across),
        );
        assert!((f.norm() - 1.0).abs() < 1e-12 && (a.norm() - 1.0).abs() < 1e-12);
        assert!(f.dot(&u).abs() < 1e-12 && a.dot(&u).abs() < 1e-12 && a.dot(&f).abs() < 1e-12);
        // Across points to the camera's right (+x), forward away from it (+z).
        assert!(a.x > 0.99 && f.z > 0.9);
        // The camera's foot is 0 ahead, 0 high.
        let foot = h.from_coordinates(FloorCoordinates {
            ahead_m: 0.0,
            height_m: 0.0,
            across_m: 0.0,
        });
        let c = h.coordinates([0.0, 0.0, 0.0]);
        assert!(c.ahead_m.abs() < 1e-12 && (c.height_m - 0.8).abs() < 1e-12);
        assert!((h.floor.height_of(foot)).abs() < 1e-12);
    }

    #[test]
    fn rotation_keeps_the_hinge_and_offsets_and_turns_by_the_angle() {
        let h = hinge(25.0);
        let on_hinge = h.from_coordinates(FloorCoordinates {
            ahead_m: 1.5,
            height_m: 0.0,
            across_m: 0.7,
        });
        let moved = h.rotate(on_hinge);
        for k in 0..3 {
            assert!((moved[k] - on_hinge[k]).abs() < 1e-12);
        }
        // A floor point 2 m past the hinge, 0.1 m above the floor: its height
        // above the ramp stays 0.1, its distance up the ramp 2.
        let p = h.from_coordinates(FloorCoordinates {
            ahead_m: 3.5,
            height_m: 0.1,
            across_m: -0.3,
        });
        let r = h.ramp_coordinates(h.rotate(p));
        assert!((r.ahead_m - 2.0).abs() < 1e-12, "{r:?}");
        assert!((r.height_m - 0.1).abs() < 1e-12, "{r:?}");
        assert!((r.across_m + 0.3).abs() < 1e-12, "{r:?}");
        // Up the ramp means up: its height above the floor is 2 sin 25° + 0.1 cos 25°.
        let c = h.coordinates(h.rotate(p));
        let (s, co) = 25f64.to_radians().sin_cos();
        assert!((c.height_m - (2.0 * s + 0.1 * co)).abs() < 1e-12);
        let angle = Vector3::from(h.ramp_up())
            .angle(&Vector3::from(h.floor.up))
            .to_degrees();
        assert!((angle - 25.0).abs() < 1e-9);
        // Points before the hinge do not move.
        let near = h.from_coordinates(FloorCoordinates {
            ahead_m: 1.4,
            height_m: 0.5,
            across_m: 0.0,
        });
        assert_eq!(h.bend(near), near);
    }
}
