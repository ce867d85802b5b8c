//! A depth image as an organised cloud (the recording format's projection:
//! `x = (u - cx) z / fx`, `y = (v - cy) z / fy`) with a local normal per
//! point, for the floor fit.

use nalgebra::Vector3;
use slope_sensor::recording::{DepthImage, DepthInfo};

/// Neighbours farther apart in depth than this share of the centre's
/// depth give the centre no normal (a depth edge, not a surface).
const NORMAL_CONTINUITY: f64 = 0.1;

/// The points of a depth image, row-major; `None` where it has no reading.
#[derive(Debug, Clone)]
pub struct OrganisedCloud {
    pub width: usize,
    pub height: usize,
    pub points: Vec<Option<Vector3<f64>>>,
    /// Unit normal facing the camera, from the neighbours `step` pixels
    /// left, right, above and below; `None` at edges and holes.
    pub normals: Vec<Option<Vector3<f64>>>,
}

impl OrganisedCloud {
    /// Projects `depth` with the intrinsics and unit of `info` (the image's
    /// size is checked by the caller).
    pub fn new(depth: &DepthImage, info: &DepthInfo) -> Self {
        let (width, height) = (depth.width as usize, depth.height as usize);
        let points: Vec<Option<Vector3<f64>>> = depth
            .data
            .iter()
            .enumerate()
            .map(|(i, &count)| {
                (count != 0).then(|| {
                    let (u, v) = ((i % width) as f64, (i / width) as f64);
                    let z = f64::from(count) * info.unit_m;
                    Vector3::new((u - info.cx) * z / info.fx, (v - info.cy) * z / info.fy, z)
                })
            })
            .collect();
        // About 1/200 of the width: 2 px at 512, 3 at 640, 4 at 960.
        let step = (width / 200).max(2);
        let normals = (0..points.len())
            .map(|i| normal_at(&points, width, height, i, step))
            .collect();
        Self {
            width,
            height,
            points,
            normals,
        }
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True for an image of no pixels.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

fn normal_at(
    points: &[Option<Vector3<f64>>],
    width: usize,
    height: usize,
    i: usize,
    step: usize,
) -> Option<Vector3<f64>> {
    let (u, v) = (i % width, i / width);
    if u < step || v < step || u + step >= width || v + step >= height {
        return None;
    }
    let centre = points[i]?;
    let near = |j: usize| -> Option<Vector3<f64>> {
        let p = points[j]?;
        ((p.z - centre.z).abs() <= NORMAL_CONTINUITY * centre.z).then_some(p)
    };
    let right = near(i + step)?;
    let left = near(i - step)?;
    let below = near(i + step * width)?;
    let above = near(i - step * width)?;
    let n = (below - above).cross(&(right - left));
    let norm = n.norm();
    if norm < 1e-12 {
        return None;
    }
    let n = n / norm;
    // Facing the camera (at the origin).
    Some(if n.dot(&centre) > 0.0 { -n } else { n })
}
