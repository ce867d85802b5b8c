//! The bent frame rendered back into a depth image: the source image as a
//! triangle mesh (two triangles per 2 x 2 cell of pixel centres, where the
//! cell is a continuous surface), its vertices beyond the hinge rotated,
//! rasterised with a z-buffer (nearest wins) at the pixel centres and
//! quantised in the recording's unit.
//!
//! Why a mesh and not a point per pixel: a floor turned up towards the
//! camera covers more pixels than it did (its points spread apart), so one
//! pixel per point would leave a ramp full of holes a real ramp does not
//! have. The mesh covers exactly the surface between neighbouring readings;
//! a depth edge (a cell spanning more than [`CONTINUITY`] of its depth) is
//! not bridged, so what a bend uncovers stays a hole (0). Each rotated
//! point is also splatted on its nearest pixel, so readings without a
//! complete cell (isolated points) are not lost.
//!
//! Pixels whose source point stays (before the hinge line) keep their
//! count bit for bit unless a bent surface in front of them hides them.

use nalgebra::Vector3;
use slope_sensor::recording::{metres_to_count, ColorImage, DepthImage, DepthInfo};

use super::hinge::Hinge;
use super::organised::OrganisedCloud;

/// A cell whose deepest vertex is more than this share deeper than its
/// nearest is a depth edge: not rendered as surface. 5 % keeps a floor
/// seen from 0.8 m up connected to 20 m for a 520 px focal length (its
/// rows differ by about z / (f h) in depth) and cuts a person 0.3 m in
/// front of a wall at 6 m.
pub const CONTINUITY: f64 = 0.05;

/// A bent triangle whose edge grew by more than this factor (plus 1 cm)
/// tears: the rotation split an object standing across the hinge line. It
/// is left out rather than stretched into a skin.
const MAX_STRETCH: f64 = 1.5;

/// What the render did, for the log and the tests.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RenderStats {
    /// Points beyond the hinge line, rotated.
    pub moved_points: usize,
    /// Pixels whose source point stayed and whose count changed because a
    /// bent surface lies in front of it.
    pub kept_pixels_hidden: usize,
    /// Pixels with a reading in the output.
    pub readings: usize,
}

/// The rendered frame.
pub struct Rendered {
    pub depth: DepthImage,
    pub color: Option<ColorImage>,
    /// Per output pixel, the source pixel its reading comes from (see
    /// [`crate::bend::BentFrame::source_pixel`]).
    pub source_pixel: Vec<u32>,
    pub stats: RenderStats,
}

/// [`Rendered::source_pixel`] of a pixel without a reading.
pub const NO_SOURCE: u32 = u32::MAX;

/// Renders `cloud` bent about `hinge` into a depth image of `info`'s size,
/// intrinsics and unit (`source` is the image `cloud` was projected from,
/// `color` its registered colour).
pub fn render_bent(
    cloud: &OrganisedCloud,
    source: &DepthImage,
    color: Option<&ColorImage>,
    info: &DepthInfo,
    hinge: &Hinge,
) -> Rendered {
    let (w, h) = (cloud.width, cloud.height);
    let mut zbuf = vec![f64::INFINITY; w * h];
    let mut depth = DepthImage::new(source.width, source.height);
    let mut out_color = color.cloned();
    let mut moved = vec![false; w * h];
    let mut source_pixel = vec![NO_SOURCE; w * h];
    let mut bent: Vec<Option<Vector3<f64>>> = vec![None; w * h];
    let mut stats = RenderStats::default();

    for (i, p) in cloud.points.iter().enumerate() {
        let Some(p) = p else { continue };
        if hinge.is_beyond((*p).into()) {
            moved[i] = true;
            stats.moved_points += 1;
            bent[i] = Some(Vector3::from(hinge.rotate((*p).into())));
            if let Some(c) = out_color.as_mut() {
                // Uncovered by the bend unless a bent surface lands here.
                c.data[i] = [0, 0, 0];
            }
        } else {
            bent[i] = Some(*p);
            depth.data[i] = source.data[i];
            source_pixel[i] = u32::try_from(i).unwrap_or(NO_SOURCE);
            zbuf[i] = p.z;
        }
    }

    let mut raster = Raster {
        info,
        width: w,
        height: h,
        zbuf: &mut zbuf,
        depth: &mut depth,
        out_color: out_color.as_mut(),
        src_color: color,
        source_pixel: &mut source_pixel,
    };
    for v in 0..h.saturating_sub(1) {
        for u in 0..w.saturating_sub(1) {
            let i00 = v * w + u;
            let (i10, i01, i11) = (i00 + 1, i00 + w, i00 + w + 1);
            for tri in [[i00, i10, i01], [i10, i11, i01]] {
                if !tri.iter().any(|&i| moved[i]) {
                    continue; // Unchanged: its pixels were copied.
                }
                let (Some(a), Some(b), Some(c)) = (
                    cloud.points[tri[0]],
                    cloud.points[tri[1]],
                    cloud.points[tri[2]],
                ) else {
                    continue;
                };
                let (zmin, zmax) = (a.z.min(b.z).min(c.z), a.z.max(b.z).max(c.z));
                if zmax > zmin * (1.0 + CONTINUITY) {
                    continue;
                }
                let (Some(ba), Some(bb), Some(bc)) = (bent[tri[0]], bent[tri[1]], bent[tri[2]])
                else {
                    continue;
                };
                if stretched([a, b, c], [ba, bb, bc]) {
                    continue;
                }
                raster.triangle([ba, bb, bc], tri);
            }
        }
    }
    // Isolated readings (no complete cell) only where the mesh left a hole:
    // a point on its nearest pixel is up to half a pixel off, and would win
    // the z-buffer against the exact surface where it lies in front.
    let covered: Vec<bool> = raster.zbuf.iter().map(|z| z.is_finite()).collect();
    for (i, p) in bent.iter().enumerate() {
        if let (true, Some(p)) = (moved[i], p) {
            raster.point(*p, i, &covered);
        }
    }

    for (i, &count) in depth.data.iter().enumerate() {
        if count != 0 {
            stats.readings += 1;
        }
        if !moved[i] && source.data[i] != 0 && count != source.data[i] {
            stats.kept_pixels_hidden += 1;
        }
    }
    Rendered {
        depth,
        color: out_color,
        source_pixel,
        stats,
    }
}

fn stretched(before: [Vector3<f64>; 3], after: [Vector3<f64>; 3]) -> bool {
    (0..3).any(|k| {
        let j = (k + 1) % 3;
        let old = (before[j] - before[k]).norm();
        let new = (after[j] - after[k]).norm();
        new > MAX_STRETCH * old + 0.01
    })
}

struct Raster<'a> {
    info: &'a DepthInfo,
    width: usize,
    height: usize,
    zbuf: &'a mut [f64],
    depth: &'a mut DepthImage,
    out_color: Option<&'a mut ColorImage>,
    src_color: Option<&'a ColorImage>,
    source_pixel: &'a mut [u32],
}

impl Raster<'_> {
    fn project(&self, p: Vector3<f64>) -> Option<(f64, f64)> {
        (p.z > 1e-6).then(|| {
            (
                self.info.fx * p.x / p.z + self.info.cx,
                self.info.fy * p.y / p.z + self.info.cy,
            )
        })
    }

    /// Writes depth `z` (metres) at pixel `i` if nearer than what is there;
    /// `from` is the source pixel whose colour it carries.
    fn write(&mut self, i: usize, z: f64, from: usize) {
        if z < self.zbuf[i] {
            let count = metres_to_count(z, self.info.unit_m);
            if count == 0 {
                return;
            }
            self.zbuf[i] = z;
            self.depth.data[i] = count;
            self.source_pixel[i] = u32::try_from(from).unwrap_or(NO_SOURCE);
            if let (Some(out), Some(src)) = (self.out_color.as_deref_mut(), self.src_color) {
                out.data[i] = src.data[from];
            }
        }
    }

    /// The nearest pixel of point `p`, unless `covered` (by a surface).
    fn point(&mut self, p: Vector3<f64>, from: usize, covered: &[bool]) {
        let Some((u, v)) = self.project(p) else {
            return;
        };
        let (u, v) = (u.round(), v.round());
        if u >= 0.0 && v >= 0.0 && u < self.width as f64 && v < self.height as f64 {
            let i = v as usize * self.width + u as usize;
            if !covered[i] {
                self.write(i, p.z, from);
            }
        }
    }

    /// Every pixel centre inside the projected triangle, at the depth of
    /// the triangle's plane along its ray (1/z is affine on the screen).
    fn triangle(&mut self, p: [Vector3<f64>; 3], from: [usize; 3]) {
        let (Some(a), Some(b), Some(c)) =
            (self.project(p[0]), self.project(p[1]), self.project(p[2]))
        else {
            return;
        };
        let area = edge(a, b, c);
        if area.abs() < 1e-12 {
            return;
        }
        let u0 = a.0.min(b.0).min(c.0).ceil().max(0.0);
        let u1 = a.0.max(b.0).max(c.0).floor().min(self.width as f64 - 1.0);
        let v0 = a.1.min(b.1).min(c.1).ceil().max(0.0);
        let v1 = a.1.max(b.1).max(c.1).floor().min(self.height as f64 - 1.0);
        if u0 > u1 || v0 > v1 {
            return;
        }
        let inv_z = [1.0 / p[0].z, 1.0 / p[1].z, 1.0 / p[2].z];
        // Pixel centres exactly on an edge count (shared edges are written
        // twice with the same depth; the z-buffer keeps one).
        let eps = 1e-9;
        let mut v = v0;
        while v <= v1 {
            let mut u = u0;
            while u <= u1 {
                let q = (u, v);
                let w0 = edge(b, c, q) / area;
                let w1 = edge(c, a, q) / area;
                let w2 = edge(a, b, q) / area;
                if w0 >= -eps && w1 >= -eps && w2 >= -eps {
                    let z = 1.0 / (w0 * inv_z[0] + w1 * inv_z[1] + w2 * inv_z[2]);
                    let nearest = if w0 >= w1 && w0 >= w2 {
                        from[0]
                    } else if w1 >= w2 {
                        from[1]
                    } else {
                        from[2]
                    };
                    self.write(v as usize * self.width + u as usize, z, nearest);
                }
                u += 1.0;
            }
            v += 1.0;
        }
    }
}

/// Twice the signed area of (a, b, q).
fn edge(a: (f64, f64), b: (f64, f64), q: (f64, f64)) -> f64 {
    (b.0 - a.0) * (q.1 - a.1) - (b.1 - a.1) * (q.0 - a.0)
}
