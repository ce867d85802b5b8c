//! The geometry the overlay draws over the surfaces, in depth-pixel
//! coordinates: the road's boundary pixels ([`boundary_pixels`]) and the
//! robot's corridor on the ground projected into the image
//! ([`corridor_segments`]). Pure functions.

use nalgebra::Vector3;
use slope_ipc_types::Intrinsics;
use slope_pipeline::selection::GroundFrame;

/// Points nearer the camera plane than this (metres along the optical
/// axis) are not projected: the corridor is clipped there.
pub const MIN_DEPTH_M: f64 = 0.05;

/// Holes up to this many pixels across are closed in a surface's mask
/// before its boundary is taken (noise leaves single missing inliers).
pub const CLOSE_RADIUS: usize = 2;

/// A line segment in depth-pixel coordinates `(u, v)` (pixel centres at
/// integers).
pub type Segment = [(f64, f64); 2];

/// The pixels on the boundary of the region `pixels` (on a `w` x `h`
/// grid), after closing its holes of up to [`CLOSE_RADIUS`] pixels: the
/// region's pixels with a 4-neighbour outside it. The image's edge is no
/// boundary (the view cuts the surface there, it does not end).
pub fn boundary_pixels(pixels: &[&[u32]], w: usize, h: usize) -> Vec<u32> {
    let mut mask = vec![false; w * h];
    for &p in pixels.iter().flat_map(|list| list.iter()) {
        if let Some(m) = mask.get_mut(p as usize) {
            *m = true;
        }
    }
    let closed = erode(&dilate(&mask, w, h, CLOSE_RADIUS), w, h, CLOSE_RADIUS);
    let inside = |u: usize, v: usize| closed[v * w + u];
    let mut out = Vec::new();
    for v in 0..h {
        for u in 0..w {
            if !inside(u, v) {
                continue;
            }
            let edge = (u > 0 && !inside(u - 1, v))
                || (u + 1 < w && !inside(u + 1, v))
                || (v > 0 && !inside(u, v - 1))
                || (v + 1 < h && !inside(u, v + 1));
            if edge {
                out.push((v * w + u) as u32);
            }
        }
    }
    out
}

/// True where any pixel within `r` (square neighbourhood) is set.
fn dilate(mask: &[bool], w: usize, h: usize, r: usize) -> Vec<bool> {
    morph(mask, w, h, r, true)
}

/// True where every pixel within `r` inside the image is set.
fn erode(mask: &[bool], w: usize, h: usize, r: usize) -> Vec<bool> {
    morph(mask, w, h, r, false)
}

/// One pass per direction (rows, then columns) of a square max (`any`) or
/// min filter of radius `r`.
fn morph(mask: &[bool], w: usize, h: usize, r: usize, any: bool) -> Vec<bool> {
    let pass = |src: &[bool], horizontal: bool| -> Vec<bool> {
        let mut out = vec![false; w * h];
        for v in 0..h {
            for u in 0..w {
                let (pos, len) = if horizontal { (u, w) } else { (v, h) };
                let lo = pos.saturating_sub(r);
                let hi = (pos + r).min(len - 1);
                let at = |k: usize| {
                    if horizontal {
                        src[v * w + k]
                    } else {
                        src[k * w + u]
                    }
                };
                out[v * w + u] = if any {
                    (lo..=hi).any(at)
                } else {
                    (lo..=hi).all(at)
                };
            }
        }
        out
    };
    pass(&pass(mask, true), false)
}

/// The corridor's two edges, the lines `lateral = ±half_width_m` on the
/// ground plane from `near_m` to `far_m` ahead, projected with
/// `intrinsics` into a `w` x `h` image: the ground points
/// `forward * ahead + right * lateral - up * d` (`d` the ground plane's, the
/// camera's height), cut where they come nearer the camera plane than
/// [`MIN_DEPTH_M`] and at the image's border. Left edge first; a part out
/// of view gives no segment. Nothing without a finite ground height.
pub fn corridor_segments(
    frame: &GroundFrame,
    intrinsics: &Intrinsics,
    (w, h): (u32, u32),
    half_width_m: f64,
    (near_m, far_m): (f64, f64),
) -> Vec<Segment> {
    let d = frame.ground.d;
    if !(d.is_finite() && half_width_m.is_finite() && near_m < far_m) {
        return Vec::new();
    }
    let mut out = Vec::new();
    for lateral in [-half_width_m, half_width_m] {
        let at = |ahead: f64| -> Vector3<f64> {
            frame.forward * ahead + frame.right * lateral - frame.up * d
        };
        let Some((a0, a1)) = in_front(at(near_m), at(far_m)) else {
            continue;
        };
        let p0 = at(near_m + (far_m - near_m) * a0);
        let p1 = at(near_m + (far_m - near_m) * a1);
        let project = |p: Vector3<f64>| {
            (
                intrinsics.fx * p.x / p.z + intrinsics.cx,
                intrinsics.fy * p.y / p.z + intrinsics.cy,
            )
        };
        // The image's pixels span centres 0..w-1, half a pixel either side.
        let bounds = (-0.5, -0.5, f64::from(w) - 0.5, f64::from(h) - 0.5);
        if let Some(segment) = clip_to_rect([project(p0), project(p1)], bounds) {
            out.push(segment);
        }
    }
    out
}

/// The part `[t0, t1]` of the segment `p0 -> p1` (parameter 0..1) at least
/// [`MIN_DEPTH_M`] in front of the camera; `None` when none is.
fn in_front(p0: Vector3<f64>, p1: Vector3<f64>) -> Option<(f64, f64)> {
    let (z0, z1) = (p0.z - MIN_DEPTH_M, p1.z - MIN_DEPTH_M);
    match (z0 >= 0.0, z1 >= 0.0) {
        (true, true) => Some((0.0, 1.0)),
        (false, false) => None,
        // z is linear along the segment: it crosses MIN_DEPTH_M at t.
        (true, false) => Some((0.0, z0 / (z0 - z1))),
        (false, true) => Some((z0 / (z0 - z1), 1.0)),
    }
}

/// The segment clipped to the rectangle `(x0, y0, x1, y1)`
/// (Liang-Barsky); `None` when it misses it.
fn clip_to_rect(s: Segment, (x0, y0, x1, y1): (f64, f64, f64, f64)) -> Option<Segment> {
    let [(ax, ay), (bx, by)] = s;
    let (dx, dy) = (bx - ax, by - ay);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [(-dx, ax - x0), (dx, x1 - ax), (-dy, ay - y0), (dy, y1 - ay)] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 <= t1 && t0.is_finite() && t1.is_finite())
        .then_some([(ax + t0 * dx, ay + t0 * dy), (ax + t1 * dx, ay + t1 * dy)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use slope_pipeline::plane_fit::Plane;

    /// A camera 0.5 m above the ground looking `pitch` degrees down.
    fn pitched(pitch_deg: f64) -> GroundFrame {
        let t = pitch_deg.to_radians();
        GroundFrame::over(Plane {
            normal: Vector3::new(0.0, -t.cos(), -t.sin()),
            d: 0.5,
        })
    }

    const KINECT: Intrinsics = Intrinsics {
        fx: 365.0,
        fy: 365.0,
        cx: 255.5,
        cy: 211.5,
    };

    /// A level camera: the corridor's edges are the lines from
    /// `(cx ± fx * l / a, cy + fy * d / a)`; each point on the drawn
    /// segment is on that line, the far end at the look-ahead.
    #[test]
    fn the_corridor_projects_onto_the_analytic_lines() {
        let frame = pitched(0.0);
        let segments = corridor_segments(&frame, &KINECT, (512, 424), 0.4, (1.0, 3.0));
        assert_eq!(segments.len(), 2, "{segments:?}");
        for (segment, l) in segments.iter().zip([-0.4, 0.4]) {
            // Near end 1 m ahead: v = 211.5 + 365 * 0.5 = 394 (in view).
            let [(u0, v0), (u1, v1)] = *segment;
            assert!((u0 - (255.5 + 365.0 * l)).abs() < 1e-9, "{segment:?}");
            assert!((v0 - 394.0).abs() < 1e-9, "{segment:?}");
            assert!((u1 - (255.5 + 365.0 * l / 3.0)).abs() < 1e-9, "{segment:?}");
            assert!((v1 - (211.5 + 365.0 * 0.5 / 3.0)).abs() < 1e-9);
        }
        // Nearer than the bottom row sees: cut at the border, where the
        // line still runs through the analytic points (v = 423.5 at
        // a = 182.5 / 212 m).
        let segments = corridor_segments(&frame, &KINECT, (512, 424), 0.4, (0.5, 3.0));
        let [(u0, v0), _] = segments[1];
        let a = 365.0 * 0.5 / (423.5 - 211.5);
        assert!((v0 - 423.5).abs() < 1e-9 && (u0 - (255.5 + 365.0 * 0.4 / a)).abs() < 1e-9);
    }

    /// Looking 20° down, ground points behind the camera plane are cut;
    /// a corridor wholly behind or out of view gives nothing; an unknown
    /// ground height gives nothing.
    #[test]
    fn parts_behind_the_camera_or_out_of_view_are_cut() {
        let frame = pitched(-40.0);
        // Looking 40° up: the ground ahead lies under the image (its
        // nearest point, 0.5 m ahead, 45° down: 85° below the axis).
        assert!(corridor_segments(&frame, &KINECT, (512, 424), 0.4, (0.5, 3.0)).is_empty());
        let frame = pitched(20.0);
        let segments = corridor_segments(&frame, &KINECT, (512, 424), 0.4, (-5.0, 3.0));
        assert_eq!(segments.len(), 2);
        for [(u0, v0), (u1, v1)] in segments {
            for (u, v) in [(u0, v0), (u1, v1)] {
                assert!((-0.5..=511.5).contains(&u) && (-0.5..=423.5).contains(&v));
            }
        }
        assert!(corridor_segments(&frame, &KINECT, (512, 424), 0.4, (-5.0, -1.0)).is_empty());
        let mut unknown = frame;
        unknown.ground.d = f64::NAN;
        assert!(corridor_segments(&unknown, &KINECT, (512, 424), 0.4, (1.0, 3.0)).is_empty());
    }

    /// A filled rectangle with one-pixel holes: its boundary is its outer
    /// ring only (the holes are closed), not the image's edge.
    #[test]
    fn the_boundary_is_the_outer_ring_of_the_closed_region() {
        let (w, h) = (40usize, 30usize);
        let region: Vec<u32> = (5..20)
            .flat_map(|v| (0..30).map(move |u| (v * w + u) as u32))
            .filter(|&p| p != (12 * w + 15) as u32 && p != (8 * w + 8) as u32)
            .collect();
        let boundary = boundary_pixels(&[&region], w, h);
        let expected: Vec<u32> = (5..20)
            .flat_map(|v| (0..30).map(move |u| (u, v)))
            .filter(|&(u, v)| v == 5 || v == 19 || u == 29)
            .map(|(u, v)| (v * w + u) as u32)
            .collect();
        assert_eq!(boundary, expected);
        assert!(boundary_pixels(&[&[], &[5_000_000]], w, h).is_empty());
    }
}
