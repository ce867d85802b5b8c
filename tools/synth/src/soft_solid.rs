//! A box standing on the ground whose top and four sides are displaced
//! along their normals by [`BumpField`]s (a soft block: a bed under a
//! fabric cover), and the ray march that finds where a ray meets it.
//!
//! In the block's own coordinates q (x across, y along, z up, origin at the
//! footprint's centre on the ground) face j is the zero set of
//! `g_j(q) = sign_j q[axis_j] - offset_j - bumps_j(q[s_j], q[t_j])`, and the
//! block is `max_j g_j(q) < 0` (the bottom, `-q.z`, has no bumps). Each g_j
//! changes by at most `L = sqrt(1 + slope²)` per metre (slope = the
//! field's gradient bound), and so does their maximum; so from a point
//! where it is `g > 0`, the surface is at least `g / L` away. The march
//! steps exactly that far (sphere tracing: it can never step through the
//! surface), stops within [`SURFACE_TOLERANCE_M`] of it, and polishes the
//! hit with one Newton step on the face it found. Deterministic, no
//! randomness: the fields are fixed when the solid is built.

use crate::bump_field::BumpField;
use crate::geometry::{BoxFace, Hit, Pos3, Ray, Surface, Vec3};

/// The march stops when the implicit function is below this, metres.
pub const SURFACE_TOLERANCE_M: f64 = 1e-7;
/// Most steps of one march; a ray that has not arrived by then (it would
/// have to creep along the surface for metres) counts as a miss.
const MAX_STEPS: usize = 4_000;
/// Largest distance the final Newton step may move the hit, metres.
const MAX_POLISH_M: f64 = 1e-4;
/// Extra room around the bounding box of the bumps, metres.
const BOUNDS_PAD_M: f64 = 1e-3;

/// One face of a soft block, in the block's coordinates.
#[derive(Debug, Clone, PartialEq)]
struct SoftFace {
    /// Coordinate the face's normal is along (0 across, 1 along, 2 up).
    axis: usize,
    /// +1 when the outward normal points along +axis, -1 otherwise.
    sign: f64,
    /// The undisplaced face is `sign * q[axis] = offset`.
    offset: f64,
    /// The face's in-plane coordinates (s, t) of the bump field.
    tangents: [usize; 2],
    bumps: BumpField,
    surface: Surface,
}

impl SoftFace {
    fn plain(&self, q: &[f64; 3]) -> f64 {
        self.sign * q[self.axis] - self.offset
    }

    fn value(&self, q: &[f64; 3], plain: f64) -> f64 {
        plain
            - self
                .bumps
                .height_m(q[self.tangents[0]], q[self.tangents[1]])
    }

    /// Gradient of the face's function, block coordinates.
    fn gradient(&self, q: &[f64; 3]) -> [f64; 3] {
        let [s, t] = self.tangents;
        let [ds, dt] = self.bumps.gradient(q[s], q[t]);
        let mut g = [0.0; 3];
        g[self.axis] = self.sign;
        g[s] -= ds;
        g[t] -= dt;
        g
    }
}

/// A soft block: see the module documentation.
#[derive(Debug, Clone, PartialEq)]
pub struct SoftSolid {
    /// Centre of the footprint, on the ground.
    centre: Pos3,
    across: Vec3,
    along: Vec3,
    faces: Vec<SoftFace>,
    /// Largest bump of any face, metres.
    margin_m: f64,
    /// Bound of the implicit function's change per metre.
    lipschitz: f64,
    /// Box around every bump, block coordinates: (low, high) per axis.
    bounds: [(f64, f64); 3],
}

impl SoftSolid {
    /// A block with footprint centre `centre` (on the ground), turned by
    /// `yaw_deg` about the vertical, of size `size_m` (across, along, up),
    /// with the bumps of its Inner, Outer, Near, Far and Top faces (see
    /// [`BoxFace`]); `label` names each face.
    pub fn new(
        centre: Pos3,
        yaw_deg: f64,
        size_m: [f64; 3],
        bumps: [BumpField; 5],
        label: impl Fn(BoxFace) -> Surface,
    ) -> Self {
        let (s, c) = yaw_deg.to_radians().sin_cos();
        let [sx, sy, sz] = size_m;
        let [inner, outer, near, far, top] = bumps;
        let layout = [
            (BoxFace::Inner, 0, -1.0, sx / 2.0, [1, 2], inner),
            (BoxFace::Outer, 0, 1.0, sx / 2.0, [1, 2], outer),
            (BoxFace::Near, 1, -1.0, sy / 2.0, [0, 2], near),
            (BoxFace::Far, 1, 1.0, sy / 2.0, [0, 2], far),
            (BoxFace::Top, 2, 1.0, sz, [0, 1], top),
            (BoxFace::Bottom, 2, -1.0, 0.0, [0, 1], BumpField::flat()),
        ];
        let faces: Vec<SoftFace> = layout
            .into_iter()
            .map(|(face, axis, sign, offset, tangents, bumps)| SoftFace {
                axis,
                sign,
                offset,
                tangents,
                bumps,
                surface: label(face),
            })
            .collect();
        let margin_m = faces
            .iter()
            .map(|f| f.bumps.max_height_m())
            .fold(0.0, f64::max);
        let slope = faces
            .iter()
            .map(|f| f.bumps.max_slope())
            .fold(0.0, f64::max);
        let pad = margin_m + BOUNDS_PAD_M;
        Self {
            centre: Pos3::new(centre.x, centre.y, 0.0),
            across: Vec3::new(c, s, 0.0),
            along: Vec3::new(-s, c, 0.0),
            faces,
            margin_m,
            lipschitz: slope.hypot(1.0),
            bounds: [
                (-sx / 2.0 - pad, sx / 2.0 + pad),
                (-sy / 2.0 - pad, sy / 2.0 + pad),
                (-pad, sz + pad),
            ],
        }
    }

    /// True when `p` is strictly inside the block.
    pub fn contains(&self, p: &Pos3) -> bool {
        self.implicit(&self.local_point(p)).0 < 0.0
    }

    /// Where `ray` first enters the block at some t > 0; `None` when it
    /// misses or starts inside.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let origin = self.local_point(&ray.origin);
        let dir = self.local_direction(&ray.direction);
        let (t_enter, t_exit) = self.clip(&origin, &dir)?;
        let speed = self.lipschitz * dir.iter().map(|d| d * d).sum::<f64>().sqrt();
        let mut t = t_enter;
        for _ in 0..MAX_STEPS {
            let (g, _) = self.implicit(&along_ray(&origin, &dir, t));
            if g <= SURFACE_TOLERANCE_M {
                if g < 0.0 && t <= 0.0 {
                    return None;
                }
                return Some(self.hit(&origin, &dir, self.polish(&origin, &dir, t)));
            }
            t += g / speed;
            if t > t_exit {
                return None;
            }
        }
        None
    }

    /// The block's implicit function at `q` (negative inside) and the face
    /// it comes from. Faces whose undisplaced plane is too far below the
    /// largest cannot win and are skipped (their bumps are bounded).
    fn implicit(&self, q: &[f64; 3]) -> (f64, usize) {
        let mut plain = [0.0; 6];
        for (p, f) in plain.iter_mut().zip(&self.faces) {
            *p = f.plain(q);
        }
        let highest = plain.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mut best = (f64::NEG_INFINITY, 0);
        for (j, (f, &p)) in self.faces.iter().zip(&plain).enumerate() {
            if p < highest - 2.0 * self.margin_m {
                continue;
            }
            let g = f.value(q, p);
            if g > best.0 {
                best = (g, j);
            }
        }
        best
    }

    /// One Newton step on the face found, if it stays tiny.
    fn polish(&self, origin: &[f64; 3], dir: &[f64; 3], t: f64) -> f64 {
        let q = along_ray(origin, dir, t);
        let (g, j) = self.implicit(&q);
        let Some(face) = self.faces.get(j) else {
            return t;
        };
        let grad = face.gradient(&q);
        let rate: f64 = grad.iter().zip(dir).map(|(a, b)| a * b).sum();
        if rate >= 0.0 {
            return t;
        }
        let step = -g / rate;
        let length = step.abs() * dir.iter().map(|d| d * d).sum::<f64>().sqrt();
        if length <= MAX_POLISH_M {
            t + step
        } else {
            t
        }
    }

    fn hit(&self, origin: &[f64; 3], dir: &[f64; 3], t: f64) -> Hit {
        let q = along_ray(origin, dir, t);
        let (_, j) = self.implicit(&q);
        // `implicit` returns the index of one of the six faces.
        let face = &self.faces[j];
        let [gx, gy, gz] = face.gradient(&q);
        let normal = (self.across * gx + self.along * gy + Vec3::z() * gz).normalize();
        Hit {
            t,
            normal,
            surface: face.surface,
        }
    }

    /// The part of the ray (t >= 0) inside the bounding box of the bumps.
    fn clip(&self, origin: &[f64; 3], dir: &[f64; 3]) -> Option<(f64, f64)> {
        let mut t_enter: f64 = 0.0;
        let mut t_exit = f64::INFINITY;
        for ((&o, &d), &(low, high)) in origin.iter().zip(dir).zip(&self.bounds) {
            if d == 0.0 {
                if o < low || o > high {
                    return None;
                }
                continue;
            }
            let (a, b) = ((low - o) / d, (high - o) / d);
            t_enter = t_enter.max(a.min(b));
            t_exit = t_exit.min(a.max(b));
        }
        (t_enter <= t_exit).then_some((t_enter, t_exit))
    }

    fn local_point(&self, p: &Pos3) -> [f64; 3] {
        let d = p - self.centre;
        [self.across.dot(&d), self.along.dot(&d), d.z]
    }

    fn local_direction(&self, d: &Vec3) -> [f64; 3] {
        [self.across.dot(d), self.along.dot(d), d.z]
    }
}

fn along_ray(origin: &[f64; 3], dir: &[f64; 3], t: f64) -> [f64; 3] {
    [
        origin[0] + t * dir[0],
        origin[1] + t * dir[1],
        origin[2] + t * dir[2],
    ]
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::geometry::{ConvexSolid, HalfSpace, SurfaceKind};

    const SIZE: [f64; 3] = [0.8, 1.2, 0.5];
    const YAW: f64 = 25.0;

    fn label(face: BoxFace) -> Surface {
        Surface::new(SurfaceKind::SoftBlock, 0, face as u8)
    }

    fn centre() -> Pos3 {
        Pos3::new(0.3, 2.0, 0.0)
    }

    fn block(roughness_m: f64) -> SoftSolid {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let bumps = [0; 5].map(|_| BumpField::random(roughness_m, 0.2, &mut rng));
        SoftSolid::new(centre(), YAW, SIZE, bumps, label)
    }

    /// The same box as six exact half-spaces.
    fn convex_box() -> ConvexSolid {
        let (s, c) = YAW.to_radians().sin_cos();
        let (across, along) = (Vec3::new(c, s, 0.0), Vec3::new(-s, c, 0.0));
        let [sx, sy, sz] = SIZE;
        let o = centre();
        let faces = [
            (-across, o + across * (-sx / 2.0), BoxFace::Inner),
            (across, o + across * (sx / 2.0), BoxFace::Outer),
            (-along, o + along * (-sy / 2.0), BoxFace::Near),
            (along, o + along * (sy / 2.0), BoxFace::Far),
            (Vec3::z(), o + Vec3::z() * sz, BoxFace::Top),
            (-Vec3::z(), o, BoxFace::Bottom),
        ]
        .map(|(n, p, f)| HalfSpace::through(&p, n, label(f)));
        ConvexSolid {
            faces: faces.to_vec(),
        }
    }

    /// Camera-like rays from above and in front, aimed around the block.
    fn rays(count: usize) -> Vec<Ray> {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        (0..count)
            .map(|_| {
                let origin =
                    Pos3::new(rng.random_range(-1.0..1.0), 0.0, rng.random_range(0.3..1.5));
                let target = centre()
                    + Vec3::new(
                        rng.random_range(-0.8..0.8),
                        rng.random_range(-0.9..0.9),
                        rng.random_range(-0.1..0.7),
                    );
                Ray {
                    origin,
                    // Not unit length, like camera rays.
                    direction: (target - origin) * 0.7,
                }
            })
            .collect()
    }

    #[test]
    fn without_bumps_it_is_the_exact_box() {
        let soft = block(0.0);
        let exact = convex_box();
        let mut hits = 0;
        for ray in rays(2_000) {
            match (soft.intersect(&ray), exact.intersect(&ray)) {
                (Some(a), Some(b)) => {
                    assert!((a.t - b.t).abs() < 1e-9, "{} vs {}", a.t, b.t);
                    assert!((a.normal - b.normal).norm() < 1e-9);
                    assert_eq!(a.surface, b.surface);
                    hits += 1;
                }
                (None, None) => {}
                other => panic!("disagree for {ray:?}: {other:?}"),
            }
        }
        assert!(hits > 1_000, "{hits} hits");
    }

    #[test]
    fn bumpy_hits_match_brute_force_marching() {
        let soft = block(0.03);
        let step = 2e-4;
        let mut hits = 0;
        for ray in rays(300) {
            let len = ray.direction.norm();
            let marched = (1..40_000)
                .map(|i| f64::from(i) * step / len)
                .find(|&t| soft.contains(&ray.at(t)));
            match (soft.intersect(&ray), marched) {
                (Some(hit), Some(m)) => {
                    assert!((hit.t - m).abs() * len <= 1.01 * step, "{} vs {m}", hit.t);
                    // The hit lies on the surface: just outside before it,
                    // inside after it.
                    assert!(soft.implicit(&soft.local_point(&ray.at(hit.t))).0.abs() < 1e-9);
                    hits += 1;
                }
                (None, None) => {}
                other => panic!("disagree for {ray:?}: {other:?}"),
            }
        }
        assert!(hits > 150, "{hits} hits");
    }

    #[test]
    fn bumpy_normal_is_the_implicit_gradient() {
        let soft = block(0.03);
        let value = |p: &Pos3| soft.implicit(&soft.local_point(p)).0;
        let h = 1e-7;
        let (mut checked, mut tilted) = (0, 0);
        for ray in rays(400) {
            let Some(hit) = soft.intersect(&ray) else {
                continue;
            };
            let p = ray.at(hit.t);
            let q = soft.local_point(&p);
            // Near an edge two faces compete (a crease): skip those.
            let competing = soft
                .faces
                .iter()
                .filter(|f| f.plain(&q) > -2.0 * soft.margin_m - 0.01)
                .count();
            if competing > 1 {
                continue;
            }
            let numeric = Vec3::new(
                value(&(p + Vec3::x() * h)) - value(&(p - Vec3::x() * h)),
                value(&(p + Vec3::y() * h)) - value(&(p - Vec3::y() * h)),
                value(&(p + Vec3::z() * h)) - value(&(p - Vec3::z() * h)),
            )
            .normalize();
            assert!(
                (numeric - hit.normal).norm() < 1e-5,
                "{numeric:?} vs {:?}",
                hit.normal
            );
            checked += 1;
            let face = soft
                .faces
                .iter()
                .find(|f| f.surface == hit.surface)
                .expect("own face");
            let mut g = [0.0; 3];
            g[face.axis] = face.sign;
            let flat = soft.across * g[0] + soft.along * g[1] + Vec3::z() * g[2];
            if flat.dot(&hit.normal) < 0.99 {
                tilted += 1;
            }
        }
        assert!(checked > 100, "{checked} checked");
        // The bumps tilt the normal by more than 8° for many hits.
        assert!(tilted > checked / 5, "{tilted} of {checked} tilted");
    }

    #[test]
    fn ray_from_inside_has_no_entry() {
        let soft = block(0.03);
        let ray = Ray {
            origin: centre() + Vec3::z() * 0.2,
            direction: Vec3::y(),
        };
        assert!(soft.contains(&ray.origin));
        assert!(soft.intersect(&ray).is_none());
    }
}
