//! [`Estimator`]: runs the stages on one frame and times them.
//!
//! Paper method: statistical outlier removal -> RANSAC planes -> ground /
//! inclined selection -> per chosen plane: pass-through, normals, cosine
//! k-means -> cumulative averaging of the angle. The baselines share
//! everything up to the selection and then fit each chosen plane's RANSAC
//! inliers by ordinary least squares or TLS.

use std::time::Instant;

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use slope_ipc_types::{EstimateStatus, SlopeEstimate, SlopeMethod};

use crate::cloud::{angle_between_deg, is_measured, to_vec3, CloudView};
use crate::config::EstimatorConfig;
use crate::cosine_kmeans::CosineKmeans;
use crate::cumulative_angle::{cumulative_angle, rotation_axis};
use crate::normals::NormalEstimator;
use crate::pass_through::PassThrough;
use crate::plane_fit::{fit_least_squares, fit_tls, Moments, Plane};
use crate::ransac_planes::{PlaneSegmenter, Threshold};
use crate::selection::{
    axis_distance, plane_quality, select_planes, slope_sign, Ground, PlaneSummary,
};
use crate::statistical_outlier::StatisticalOutlierFilter;

/// A fitted plane in the estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneEstimate {
    /// `[a, b, c, d]`: `a x + b y + c z + d = 0`, `(a, b, c)` a unit normal
    /// towards the camera side.
    pub coefficients: [f64; 4],
    /// RANSAC inliers of the plane.
    pub inliers: u32,
}

/// Milliseconds per stage.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageTimings {
    pub total_ms: f64,
    /// Stage name and milliseconds, in pipeline order.
    pub stages: Vec<(&'static str, f64)>,
}

impl StageTimings {
    /// The time of a stage, 0 when it did not run.
    pub fn stage_ms(&self, name: &str) -> f64 {
        self.stages
            .iter()
            .filter(|(n, _)| *n == name)
            .map(|(_, ms)| ms)
            .sum()
    }
}

/// The result for one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    pub status: EstimateStatus,
    pub method: SlopeMethod,
    /// Signed slope, degrees: + uphill, - downhill; NaN unless `Ok`.
    pub slope_deg: f64,
    /// Spread of the averaged angle samples (0 for a single fit), degrees.
    pub slope_std_deg: f64,
    /// Angle samples averaged (1 for the baselines).
    pub samples: u32,
    /// Distance to the inclined plane along the optical axis, metres.
    pub distance_m: f64,
    pub ground: Option<PlaneEstimate>,
    pub inclined: Option<PlaneEstimate>,
    /// True when the ground normal is the mount's up vector.
    pub ground_from_mount: bool,
    pub timings: StageTimings,
}

impl Estimate {
    fn failed(status: EstimateStatus, method: SlopeMethod) -> Self {
        Self {
            status,
            method,
            slope_deg: f64::NAN,
            slope_std_deg: f64::NAN,
            samples: 0,
            distance_m: f64::NAN,
            ground: None,
            inclined: None,
            ground_from_mount: false,
            timings: StageTimings::default(),
        }
    }

    /// Fills the estimate's fields of `msg` (not the stamps, frame index or
    /// drop counter, which belong to the caller).
    pub fn write_message(&self, msg: &mut SlopeEstimate) {
        msg.status = self.status as u32;
        msg.method = self.method as u32;
        msg.slope_deg = self.slope_deg;
        msg.slope_std_deg = self.slope_std_deg;
        msg.distance_m = self.distance_m;
        msg.ground_plane = self.ground.map_or([0.0; 4], |p| p.coefficients);
        msg.inclined_plane = self.inclined.map_or([0.0; 4], |p| p.coefficients);
        msg.ground_inliers = self.ground.map_or(0, |p| p.inliers);
        msg.inclined_inliers = self.inclined.map_or(0, |p| p.inliers);
        msg.samples = self.samples;
        msg.ground_from_mount = u32::from(self.ground_from_mount);
        msg.processing_us = (self.timings.total_ms * 1000.0).round().max(0.0) as u64;
    }
}

/// Times stages into a [`StageTimings`].
struct Stopwatch {
    start: Instant,
    last: Instant,
    timings: StageTimings,
}

impl Stopwatch {
    fn new() -> Self {
        let now = Instant::now();
        Self {
            start: now,
            last: now,
            timings: StageTimings::default(),
        }
    }

    fn lap(&mut self, name: &'static str) {
        let now = Instant::now();
        let ms = (now - self.last).as_secs_f64() * 1e3;
        self.last = now;
        match self.timings.stages.iter_mut().find(|(n, _)| *n == name) {
            Some((_, total)) => *total += ms,
            None => self.timings.stages.push((name, ms)),
        }
    }

    fn finish(mut self) -> StageTimings {
        self.timings.total_ms = self.start.elapsed().as_secs_f64() * 1e3;
        self.timings
    }
}

/// The slope estimator. Owns every buffer the stages reuse from frame to
/// frame.
#[derive(Debug, Clone)]
pub struct Estimator {
    config: EstimatorConfig,
    outlier: StatisticalOutlierFilter,
    keep: Vec<bool>,
    segmenter: PlaneSegmenter,
    summaries: Vec<PlaneSummary>,
    /// Inlier pixels of every segment of the ground, in pixel order.
    ground_pixels: Vec<u32>,
    pass_through: PassThrough,
    normals: NormalEstimator,
    kmeans: CosineKmeans,
    ground_normals: Vec<Vector3<f64>>,
    inclined_normals: Vec<Vector3<f64>>,
}

impl Estimator {
    pub fn new(config: EstimatorConfig) -> Self {
        Self {
            config,
            outlier: StatisticalOutlierFilter::new(),
            keep: Vec::new(),
            segmenter: PlaneSegmenter::new(),
            summaries: Vec::new(),
            ground_pixels: Vec::new(),
            pass_through: PassThrough::new(),
            normals: NormalEstimator::new(),
            kmeans: CosineKmeans::new(),
            ground_normals: Vec::new(),
            inclined_normals: Vec::new(),
        }
    }

    pub fn config(&self) -> &EstimatorConfig {
        &self.config
    }

    /// Estimates the slope in one frame. Never panics: a malformed view
    /// (`points.len() != width * height`, zero size) gives `BadFrame`.
    pub fn estimate(&mut self, cloud: &CloudView<'_>) -> Estimate {
        let mut clock = Stopwatch::new();
        let mut estimate = self.run(cloud, &mut clock);
        estimate.timings = clock.finish();
        estimate
    }

    fn run(&mut self, cloud: &CloudView<'_>, clock: &mut Stopwatch) -> Estimate {
        let method = self.config.method;
        if !cloud.is_well_formed() {
            return Estimate::failed(EstimateStatus::BadFrame, method);
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.config.seed);
        // 1. Statistical outlier removal.
        let kept = if self.config.outlier.enabled {
            self.outlier
                .filter(cloud, &self.config.outlier, &mut self.keep)
                .kept
        } else {
            self.keep.clear();
            self.keep.extend(cloud.points.iter().map(is_measured));
            self.keep.iter().filter(|&&k| k).count()
        };
        clock.lap("outlier");
        if kept < self.config.ransac.min_plane_points.max(3) {
            return Estimate::failed(EstimateStatus::TooFewPoints, method);
        }
        // 2. RANSAC planes.
        let planes = self
            .segmenter
            .segment(cloud, &self.keep, &self.config.ransac, &mut rng);
        clock.lap("ransac");
        // Plane quality and selection.
        let threshold = Threshold::of(&self.config.ransac);
        let bottom_start = (cloud.height - cloud.height / 3) * cloud.width;
        self.summaries.clear();
        self.summaries.extend(planes.iter().map(|p| {
            PlaneSummary {
                plane: p.plane,
                inliers: p.inliers.len(),
                bottom_pixels: p
                    .inliers
                    .iter()
                    .filter(|&&i| i as usize >= bottom_start)
                    .count(),
                centroid: p.centroid,
                quality: plane_quality(cloud, &p.plane, &p.inliers, &threshold),
            }
        }));
        let mount_up = cloud.mount.up_vector().map(Vector3::from);
        let selection = select_planes(
            &self.summaries,
            mount_up,
            Some(cloud.mount.height_m),
            &self.config.selection,
        );
        clock.lap("selection");
        let selection = match selection {
            Ok(s) => s,
            Err(status) => return Estimate::failed(status, method),
        };
        let planes = self.segmenter.planes();
        let inclined_seg = &planes[selection.inclined];
        // The ground's segments together: pixels, centroid and RMS.
        let ground_seg = match &selection.ground {
            Ground::Planes(members) => {
                self.ground_pixels.clear();
                let mut weighted = (Vector3::zeros(), 0.0);
                for &k in members {
                    let p = &planes[k];
                    self.ground_pixels.extend_from_slice(&p.inliers);
                    let n = p.inliers.len() as f64;
                    weighted.0 += p.centroid * n;
                    weighted.1 += p.rms_m.powi(2) * n;
                }
                self.ground_pixels.sort_unstable();
                let n = self.ground_pixels.len().max(1) as f64;
                Some(PlaneSegment {
                    inliers: &self.ground_pixels,
                    centroid: weighted.0 / n,
                    rms_m: (weighted.1 / n).sqrt(),
                })
            }
            Ground::Mount => None,
        };
        let inclined_seg = PlaneSegment {
            inliers: &inclined_seg.inliers,
            centroid: inclined_seg.centroid,
            rms_m: inclined_seg.rms_m,
        };
        let fits = match method {
            SlopeMethod::Paper => {
                let cfg = &self.config;
                let Some(incl) = paper_plane_normals(
                    cloud,
                    &inclined_seg,
                    cfg,
                    &mut self.pass_through,
                    &mut self.normals,
                    &mut self.kmeans,
                    &mut self.inclined_normals,
                    clock,
                ) else {
                    return Estimate::failed(EstimateStatus::NoInclinedPlane, method);
                };
                let ground = match &ground_seg {
                    Some(g) => {
                        let Some(n) = paper_plane_normals(
                            cloud,
                            g,
                            cfg,
                            &mut self.pass_through,
                            &mut self.normals,
                            &mut self.kmeans,
                            &mut self.ground_normals,
                            clock,
                        ) else {
                            return Estimate::failed(EstimateStatus::NoGround, method);
                        };
                        Some(n)
                    }
                    None => {
                        self.ground_normals.clear();
                        self.ground_normals.push(selection.up);
                        None
                    }
                };
                let axis = cfg
                    .cumulative
                    .about_axis
                    .then(|| rotation_axis(&ground.unwrap_or(selection.up), &incl))
                    .flatten();
                let Some(summary) = cumulative_angle(
                    &self.inclined_normals,
                    &self.ground_normals,
                    cfg.cumulative.draws,
                    axis.as_ref(),
                    &mut rng,
                ) else {
                    return Estimate::failed(EstimateStatus::NoInclinedPlane, method);
                };
                clock.lap("cumulative");
                let incl_plane = Plane::from_point_normal(&inclined_seg.centroid, &incl);
                let ground_plane = ground.and_then(|n| {
                    ground_seg
                        .as_ref()
                        .and_then(|g| Plane::from_point_normal(&g.centroid, &n))
                });
                (
                    incl_plane,
                    ground_plane,
                    summary.mean_deg,
                    summary.std_deg,
                    summary.samples,
                )
            }
            SlopeMethod::LeastSquares | SlopeMethod::Tls => {
                let fit = |inliers: &[u32]| {
                    let mut m = Moments::new();
                    for &i in inliers {
                        if let Some(p) = cloud.points.get(i as usize).filter(|p| is_measured(p)) {
                            m.add(&to_vec3(p));
                        }
                    }
                    let plane = if method == SlopeMethod::Tls {
                        fit_tls(&m)
                    } else {
                        fit_least_squares(&m)
                    };
                    plane.map(|p| p.oriented_towards(&Vector3::zeros()))
                };
                let incl_plane = fit(inclined_seg.inliers);
                let ground_plane = ground_seg.as_ref().and_then(|g| fit(g.inliers));
                clock.lap("fit");
                let up = ground_plane.map_or(selection.up, |g| g.normal);
                let angle = incl_plane.map_or(f64::NAN, |p| angle_between_deg(&p.normal, &up));
                (incl_plane, ground_plane, angle, 0.0, 1)
            }
        };
        let (incl_plane, ground_plane, angle, std, samples) = fits;
        let Some(incl_plane) = incl_plane.map(|p| p.oriented_towards(&Vector3::zeros())) else {
            return Estimate::failed(EstimateStatus::NoInclinedPlane, method);
        };
        if ground_seg.is_some() && ground_plane.is_none() {
            return Estimate::failed(EstimateStatus::NoGround, method);
        }
        let ground_plane = ground_plane.map(|p| p.oriented_towards(&Vector3::zeros()));
        let sign = slope_sign(&incl_plane.normal, &selection.forward);
        Estimate {
            status: EstimateStatus::Ok,
            method,
            slope_deg: sign * angle,
            slope_std_deg: std,
            samples,
            distance_m: axis_distance(&incl_plane),
            ground: ground_plane
                .zip(ground_seg.as_ref())
                .map(|(p, g)| PlaneEstimate {
                    coefficients: p.coefficients(),
                    inliers: u32::try_from(g.inliers.len()).unwrap_or(u32::MAX),
                }),
            inclined: Some(PlaneEstimate {
                coefficients: incl_plane.coefficients(),
                inliers: u32::try_from(inclined_seg.inliers.len()).unwrap_or(u32::MAX),
            }),
            ground_from_mount: ground_seg.is_none(),
            timings: StageTimings::default(),
        }
    }
}

/// The pixels of a chosen plane (one RANSAC plane, or the ground's
/// segments together), their centroid and RMS distance from their plane.
struct PlaneSegment<'a> {
    inliers: &'a [u32],
    centroid: Vector3<f64>,
    rms_m: f64,
}

/// Pass-through, normals and cosine k-means for one plane: fills `out` with
/// the dominant cluster's normals and returns its (unit) mean.
#[allow(clippy::too_many_arguments)]
fn paper_plane_normals(
    cloud: &CloudView<'_>,
    segment: &PlaneSegment<'_>,
    config: &EstimatorConfig,
    pass_through: &mut PassThrough,
    normals: &mut NormalEstimator,
    kmeans: &mut CosineKmeans,
    out: &mut Vec<Vector3<f64>>,
    clock: &mut Stopwatch,
) -> Option<Vector3<f64>> {
    out.clear();
    let inliers = segment.inliers;
    let (members, _) = pass_through.filter(cloud.points, inliers, config.pass_through.max_points);
    clock.lap("pass_through");
    // The patch grows with the plane's own noise.
    let normals_config = config.normals.for_plane_noise(segment.rms_m);
    let (found, _) =
        normals.estimate_with_support(cloud, members, inliers, &normals_config, &Vector3::zeros());
    clock.lap("normals");
    let clustering = kmeans.cluster(
        found,
        config.kmeans.clusters,
        config.kmeans.max_iterations,
        config.kmeans.merge_spread_ratio,
    );
    let result = clustering.and_then(|c| {
        out.extend(kmeans.kept_members(&c).copied());
        let mean = out.iter().sum::<Vector3<f64>>();
        mean.try_normalize(1e-12)
    });
    clock.lap("kmeans");
    result
}

// The estimator daemon moves the estimator into its worker thread.
const _: fn() = || {
    fn assert_send<T: Send>() {}
    assert_send::<Estimator>();
};
