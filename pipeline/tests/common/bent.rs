//! Real floors bent into ramps of known angle (`slope_synth::bend`, issue
//! #44), run through the estimator and judged against the bend's exact
//! truth: is the road the bent part, and how far is its slope from the
//! angle. Shared by `tests/gentle_ramps.rs` and `examples/gentle_ramps.rs`
//! (each includes it by path beside `common`).

#![allow(dead_code)]

use nalgebra::Vector3;
use slope_ipc_types::{CloudPoint, EstimateStatus, SurfaceRole};
use slope_pipeline::selection::Surface;
use slope_pipeline::{Estimate, Estimator, EstimatorConfig};
use slope_sensor::projection::Projector;
use slope_synth::bend::{bend_recording, BendParams, BentFrame, FloorCoordinates};

use crate::common::Frame;

/// The frames of `shared/data` whose floor reaches past a hinge with ground
/// before it, and the hinge each is bent at, metres (measured by the bend
/// tool's author: `tools/synth/tests/bend_real_frames.rs`, `QUALIFYING`).
pub const QUALIFYING: [(&str, f64); 7] = [
    ("kv2-mine-tunnel-0", 1.5),
    ("kinect2-stairs-front", 1.5),
    ("cape-foot-tunnel", 2.0),
    ("tum-office-desk", 2.0),
    ("nyu-basement", 2.5),
    ("pcl-corridor-people", 3.0),
    ("kinect1-office", 3.8),
];

/// The road is the bent part when its plane is within this of the ramp's
/// plane (the rotated floor), degrees: a wider gate than the accuracy
/// asked (the error is reported on its own); another surface (a wall, a
/// riser, a person) is tens of degrees away.
pub const SAME_PLANE_DEG: f64 = 5.0;

/// ... and passes this close to the hinge line, metres: the ramp's plane
/// contains it (a wall or riser beyond it, however tilted, does not).
pub const AT_HINGE_M: f64 = 0.1;

/// A bent frame projected into an organised cloud, as a recording's frame
/// would be (the recording's intrinsics, unit and mount).
pub fn project(bent: &BentFrame) -> Frame {
    let d = &bent.meta.depth;
    let projector = Projector::new(d.width, d.height, d.intrinsics(), d.unit_m);
    let mut points = vec![CloudPoint::INVALID; projector.len()];
    projector.project_into(&bent.depth.data, None, &mut points);
    Frame {
        points,
        width: d.width as usize,
        height: d.height as usize,
        intrinsics: projector.intrinsics(),
        mount: bent.meta.mount.to_mount(),
        sensor: bent.meta.sensor.clone(),
    }
}

/// Frame 0 of the recording in `dir` bent by `angle_deg` at `hinge_m`.
pub fn bend(dir: &std::path::Path, angle_deg: f64, hinge_m: f64) -> BentFrame {
    bend_recording(dir, 0, &BendParams::new(angle_deg, hinge_m))
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
}

/// The estimate of `frame` with the default config for its sensor at `seed`.
pub fn estimate(frame: &Frame, seed: u64) -> Estimate {
    estimate_with(EstimatorConfig::default(), frame, seed)
}

/// The estimate of `frame` with `config` (made for its sensor) at `seed`.
pub fn estimate_with(config: EstimatorConfig, frame: &Frame, seed: u64) -> Estimate {
    let config = config.for_sensor(&frame.sensor);
    Estimator::new(EstimatorConfig { seed, ..config }).estimate(&frame.view())
}

/// What one estimate of a bent frame says, judged against the bend.
#[derive(Debug, Clone)]
pub struct Verdict {
    pub status: EstimateStatus,
    /// The road's role, when there is a road.
    pub road_role: Option<SurfaceRole>,
    /// The road is the bent part: rising (slope positive), its plane
    /// within [`SAME_PLANE_DEG`] of the ramp's and within [`AT_HINGE_M`]
    /// of the hinge line.
    pub road_is_bent: bool,
    /// Angle between the road's plane and the ramp's, degrees (NaN
    /// without a road).
    pub plane_off_deg: f64,
    /// The road's plane's distance from the hinge line's middle, metres.
    pub at_hinge_m: f64,
    /// The road's nearest point ahead less the hinge's distance, metres.
    pub start_from_hinge_m: f64,
    /// |slope| - truth, degrees (NaN unless ok).
    pub error_deg: f64,
    /// The angle between the estimate's ground plane and a least-squares
    /// plane of the bent output's ramp points (0.05-1.05 m up the ramp),
    /// degrees (NaN without a ground plane or ramp points): the truth as
    /// this ground sees the ramp, the sensor's own floor bend between the
    /// two included.
    pub ramp_to_ground_deg: f64,
}

impl Verdict {
    /// Status ok and the road is the bent part.
    pub fn found(&self) -> bool {
        self.status == EstimateStatus::Ok && self.road_is_bent
    }
}

/// Judges `e` (an estimate of `bent`) against the bend's truth;
/// `seen_ramp` is [`ramp_normal`] of `bent`.
pub fn judge(e: &Estimate, bent: &BentFrame, seen_ramp: Option<Vector3<f64>>) -> Verdict {
    let road = e.scene.as_ref().and_then(|s| s.road_surface());
    let hinge = &bent.hinge;
    let ramp_up = Vector3::from(hinge.ramp_up());
    let on_line = Vector3::from(hinge.from_coordinates(FloorCoordinates {
        ahead_m: hinge.hinge_m,
        height_m: 0.0,
        across_m: 0.0,
    }));
    let (plane_off_deg, at_hinge_m, start_from_hinge_m) = match road {
        Some(r) => (
            acute_deg(&r.plane.normal, &ramp_up),
            (r.plane.normal.dot(&on_line) + r.plane.d).abs(),
            r.distance_m - hinge.hinge_m,
        ),
        None => (f64::NAN, f64::NAN, f64::NAN),
    };
    let road_is_bent = road.is_some_and(|r| r.slope_deg > 0.0)
        && plane_off_deg <= SAME_PLANE_DEG
        && at_hinge_m <= AT_HINGE_M;
    Verdict {
        status: e.status,
        road_role: road.map(|r| r.role),
        road_is_bent,
        plane_off_deg,
        at_hinge_m,
        start_from_hinge_m,
        error_deg: if e.status == EstimateStatus::Ok {
            e.slope_deg.abs() - bent.truth_deg
        } else {
            f64::NAN
        },
        ramp_to_ground_deg: match (&e.ground, seen_ramp) {
            (Some(g), Some(n)) => {
                let [a, b, c, _] = g.coefficients;
                acute_deg(&Vector3::new(a, b, c), &n)
            }
            _ => f64::NAN,
        },
    }
}

/// The angle between two planes' unit normals, degrees, in [0, 90].
fn acute_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.dot(b).abs().min(1.0).acos().to_degrees()
}

/// The unit normal of a least-squares plane through the bent output's
/// ramp points: 0.05-1.05 m up the ramp from the hinge line, within 2 cm
/// plus 1 % of depth of the ramp's plane (the band of
/// `tools/synth/tests/bend_real_frames.rs`); `None` with fewer than 300.
pub fn ramp_normal(bent: &BentFrame) -> Option<Vector3<f64>> {
    let d = &bent.meta.depth;
    let w = d.width as usize;
    let points: Vec<Vector3<f64>> = bent
        .depth
        .data
        .iter()
        .enumerate()
        .filter(|(_, &count)| count != 0)
        .map(|(i, &count)| {
            let (u, v) = ((i % w) as f64, (i / w) as f64);
            let z = f64::from(count) * d.unit_m;
            Vector3::new((u - d.cx) * z / d.fx, (v - d.cy) * z / d.fy, z)
        })
        .filter(|p| {
            let c = bent.hinge.ramp_coordinates((*p).into());
            (0.05..1.05).contains(&c.ahead_m) && c.height_m.abs() < 0.02 + 0.01 * p.z
        })
        .collect();
    if points.len() < 300 {
        return None;
    }
    let mean = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let scatter = points
        .iter()
        .map(|p| (p - mean) * (p - mean).transpose())
        .sum::<nalgebra::Matrix3<f64>>();
    let eigen = scatter.symmetric_eigen();
    let k = eigen.eigenvalues.imin();
    Some(eigen.eigenvectors.column(k).into_owned())
}

/// Every surface of `e`'s scene, one a line, the road marked.
pub fn surfaces(e: &Estimate) -> String {
    let Some(scene) = &e.scene else {
        return "  (no scene: no ground)\n".into();
    };
    let road = scene.road.map(|r| r.surface);
    scene
        .surfaces
        .iter()
        .enumerate()
        .map(|(k, s): (usize, &Surface)| {
            let mark = if road == Some(k) { " <- road" } else { "" };
            format!(
                "  {k:2} {s} area {:5.2} noise {:4.1}{}{mark}\n",
                s.area_m2,
                s.noise_ratio,
                if s.measurable { " measurable" } else { "" }
            )
        })
        .collect()
}
