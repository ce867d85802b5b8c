//! [`Estimator`]: runs the stages on one frame and times them.
//!
//! Paper method: statistical outlier removal -> RANSAC planes -> ground /
//! inclined selection -> per chosen plane: pass-through, normals, cosine
//! k-means -> cumulative averaging of the angle. The baselines share
//! everything up to the selection and then fit each chosen plane's RANSAC
//! inliers by ordinary least squares or TLS (`baseline.rs`).
//! Either method's fit becomes the estimate (sign, distance, confidence)
//! in `finish.rs`.
//!
//! What it returns ([`Estimate`], `estimate.rs`) and what it saw
//! ([`Inspection`], `inspection.rs`) are data in files of their own,
//! re-exported here.

use std::sync::Arc;
use std::time::Instant;

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use slope_ipc_types::{EstimateStatus, SlopeMethod};

use crate::baseline::baseline_fit;
use crate::cloud::{is_measured, CloudView};
use crate::confidence::{is_small_surface, with_road_choice, Confidence, RoadChoice};
use crate::config::{EstimatorConfig, NormalsConfig, PassThroughConfig};
use crate::cosine_kmeans::CosineKmeans;
use crate::cumulative_angle::{cumulative_angle, rotation_axis};
use crate::finish::{finish, flat_ground_estimate, Fit};
use crate::ground_reach::ground_seen_to_m;
use crate::literal::{
    DepthPassThrough, EveryPointRansac, KnnNormalEstimator, KnnOutlierFilter, NormalsNeighbourhood,
    OutlierNeighbourhood, PassThroughMode, RansacScoring,
};
use crate::normals::{NormalEstimator, PlaneSupport};
use crate::pass_through::PassThrough;
use crate::plane_fit::Plane;
use crate::ransac_planes::{SegmentedPlane, Threshold};
use crate::segmentation::Segmentation;
use crate::selection::{
    chosen_segments, mount_disagrees, road_pieces, select_ground, survey_surfaces, Ground,
    PlaneSegment, PlaneSummary, RoadScene, Selection, SurveyInput,
};
use crate::statistical_outlier::StatisticalOutlierFilter;
use crate::tracking::{FrameSlope, SlopeTracker, StreamPosition};
use slope_ipc_types::SurfaceSupport;

pub use crate::estimate::{Estimate, PlaneEstimate, StageTimings};
pub use crate::inspection::{InspectedNormal, Inspection};

/// Where a frame sits in its stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FrameInfo {
    /// Frame index (the cloud header's `frame_index`).
    pub index: u64,
    /// Capture time, nanoseconds (any epoch, one clock per stream): a pause
    /// longer than `tracking.max_gap_s` restarts the tracked slope.
    pub stamp_ns: u64,
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

/// The selection's roles, kept for [`Inspection`].
#[derive(Debug, Clone, Default)]
struct Roles {
    ground: Vec<usize>,
    inclined: Option<usize>,
}

/// The slope estimator. Owns every buffer the stages reuse from frame to
/// frame.
#[derive(Debug, Clone)]
pub struct Estimator {
    config: EstimatorConfig,
    outlier: StatisticalOutlierFilter,
    keep: Vec<bool>,
    segmenter: Segmentation,
    /// The paper's stages 1 and 2 as written (`literal/`), when configured.
    knn_outlier: KnnOutlierFilter,
    every_point: EveryPointRansac,
    summaries: Vec<PlaneSummary>,
    /// Inlier pixels of every segment of the ground, in pixel order.
    ground_pixels: Vec<u32>,
    /// Inlier pixels of every piece of the road's surface, in pixel order.
    inclined_pixels: Vec<u32>,
    paper: PaperStages,
    tracker: SlopeTracker,
    roles: Roles,
    /// The last frame's surfaces and road (moved into its estimate).
    scene: Option<RoadScene>,
    /// The last frame's floor disagreed with the mount
    /// ([`mount_disagrees`]).
    mount_mismatch: bool,
    /// With `threads` > 1: the worker threads, made once with the
    /// estimator (clones share them).
    pool: Option<Arc<rayon::ThreadPool>>,
}

impl Estimator {
    pub fn new(config: EstimatorConfig) -> Self {
        Self {
            config,
            outlier: StatisticalOutlierFilter::new(),
            keep: Vec::new(),
            segmenter: Segmentation::new(),
            knn_outlier: KnnOutlierFilter::new(),
            every_point: EveryPointRansac::new(),
            summaries: Vec::new(),
            mount_mismatch: false,
            ground_pixels: Vec::new(),
            inclined_pixels: Vec::new(),
            paper: PaperStages::default(),
            tracker: SlopeTracker::new(),
            roles: Roles::default(),
            scene: None,
            pool: None,
        }
        .with_threads()
    }

    /// The worker pool for `config.threads` (none for 1); without one (the
    /// system refused the threads) the stages run on the caller's thread.
    fn with_threads(mut self) -> Self {
        self.pool = crate::workers::worker_pool(self.config.threads, self.config.pin_threads);
        self.segmenter.set_workers(self.pool.clone());
        for plane in [&mut self.paper.inclined, &mut self.paper.ground] {
            plane.normals.window.set_workers(self.pool.clone());
        }
        self
    }

    /// Keeps the paper method's sampled normals of each frame for
    /// [`Self::inspection`] (off by default: the daemon needs none).
    pub fn set_inspect(&mut self, on: bool) {
        self.paper.inspected = on.then(Vec::new);
    }

    /// What the last frame's stages saw. Planes and roles are always
    /// there; the normals only with [`Self::set_inspect`]. After a frame
    /// that failed before segmentation (bad frame, too few points) the
    /// roles and normals are empty and the planes may be those of an
    /// earlier frame.
    pub fn inspection(&self) -> Inspection<'_> {
        Inspection {
            planes: segmented(&self.segmenter, &self.every_point, &self.config),
            ground: &self.roles.ground,
            inclined: self.roles.inclined,
            normals: self.paper.inspected.as_deref().unwrap_or(&[]),
        }
    }

    pub fn config(&self) -> &EstimatorConfig {
        &self.config
    }

    /// Estimates the slope in one frame. Never panics: a malformed view
    /// (`points.len() != width * height`, zero size) gives `BadFrame`.
    /// The frame is taken as frame 0 and not tracked; see
    /// [`Estimator::estimate_frame`].
    pub fn estimate(&mut self, cloud: &CloudView<'_>) -> Estimate {
        let mut clock = Stopwatch::new();
        let mut estimate = self.run(cloud, 0, &mut clock);
        estimate.timings = clock.finish();
        estimate
    }

    /// True when the last frame's floor disagreed with its mount
    /// ([`mount_disagrees`]: the nearest floor seen tilted against the
    /// ground the mount chose, or off the mount's height). Its `ok`
    /// estimate says so too (`mount_mismatch`); a daemon warns in health.
    pub fn mount_mismatch(&self) -> bool {
        self.mount_mismatch
    }

    /// Estimates the slope in frame `frame` of a stream. The random draws
    /// depend on the seed and the frame index (a bad draw on a static scene
    /// does not repeat on every frame; the same seed and frame give the same
    /// answer).
    /// The estimate carries the tracked slope after this frame
    /// (`tracking.rs`); a frame that does not continue the last one's
    /// stream (its index not larger, a pause over `tracking.max_gap_s`,
    /// another image size or intrinsics) starts a new track.
    pub fn estimate_frame(&mut self, cloud: &CloudView<'_>, frame: FrameInfo) -> Estimate {
        let mut clock = Stopwatch::new();
        let mut estimate = self.run(cloud, frame.index, &mut clock);
        let samples = f64::from(estimate.samples.max(1));
        let slope = FrameSlope {
            status: estimate.status,
            slope_deg: estimate.slope_deg,
            error_deg: estimate.slope_std_deg / samples.sqrt(),
            confidence: estimate.confidence,
            road: estimate.road_place(),
        };
        let position = StreamPosition::of(cloud, frame.index, frame.stamp_ns);
        let tracked = self
            .tracker
            .update_at(position, &slope, &self.config.tracking);
        estimate.tracked = Some(tracked);
        clock.lap("tracking");
        estimate.timings = clock.finish();
        estimate
    }

    fn run(&mut self, cloud: &CloudView<'_>, frame_index: u64, clock: &mut Stopwatch) -> Estimate {
        let method = self.config.method;
        match self.try_run(cloud, frame_index, clock) {
            Ok(estimate) => estimate,
            Err(status) => Estimate::failed(status, method),
        }
    }

    /// The stages in the paper's order; the error is the status to report.
    fn try_run(
        &mut self,
        cloud: &CloudView<'_>,
        frame_index: u64,
        clock: &mut Stopwatch,
    ) -> Result<Estimate, EstimateStatus> {
        self.forget_last_frame();
        if !cloud.is_well_formed() {
            return Err(EstimateStatus::BadFrame);
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.config.seed);
        rng.set_stream(frame_index);
        self.remove_outliers(cloud)?;
        clock.lap("outlier");
        self.segment_planes(cloud, &mut rng);
        clock.lap("ransac");
        let ground = self.select_ground(cloud);
        clock.lap("selection");
        let selection = ground.map(|ground| self.survey(cloud, ground));
        clock.lap("surfaces");
        let selection = match selection {
            None => return Err(EstimateStatus::NoGround),
            Some(Ok(selection)) => selection,
            Some(Err(ground)) => {
                let mut estimate = self.ground_only(cloud, ground);
                estimate.scene = self.scene.take();
                return Ok(estimate);
            }
        };
        self.keep_roles(&selection);
        let (inclined, ground) = chosen_segments(
            segmented(&self.segmenter, &self.every_point, &self.config),
            &self.summaries,
            &selection,
            &mut self.inclined_pixels,
            &mut self.ground_pixels,
        );
        let fit = match self.config.method {
            SlopeMethod::Paper => self.paper.fit(
                cloud,
                &inclined,
                ground.as_ref(),
                &selection,
                &self.config,
                &mut rng,
                clock,
                self.pool.as_deref(),
            )?,
            method => {
                let fit = baseline_fit(&inclined, ground.as_ref(), &selection, method);
                clock.lap("fit");
                fit
            }
        };
        let mut estimate = finish(
            self.config.method,
            &fit,
            &inclined,
            ground.as_ref(),
            &selection,
        )?;
        if let Some(ground) = &ground {
            estimate.ground_seen_to_m =
                ground_seen_to_m(cloud.points, ground.inliers, &selection.forward);
        }
        self.lower_for_road_choice(&mut estimate);
        estimate.scene = self.scene.take();
        clock.lap("confidence");
        Ok(estimate)
    }

    /// The estimate's confidence lowered for how its road was chosen (a
    /// close call, a hidden foot: `selection/road.rs`).
    fn lower_for_road_choice(&self, estimate: &mut Estimate) {
        let Some(scene) = &self.scene else {
            return;
        };
        let (Some(road), Some(surface)) = (scene.road, scene.road_surface()) else {
            return;
        };
        let choice = RoadChoice {
            mount_mismatch: self.mount_mismatch,
            close_choice: road.close_choice,
            foot_hidden: scene.heights_known && surface.support == SurfaceSupport::Hidden,
            small_surface: is_small_surface(
                surface.right_m - surface.left_m,
                surface.inliers,
                surface.area_m2,
            ),
        };
        let c = with_road_choice(
            Confidence {
                value: estimate.confidence,
                reasons: estimate.confidence_reasons,
            },
            choice,
        );
        (estimate.confidence, estimate.confidence_reasons) = (c.value, c.reasons);
    }

    /// Empties the roles, normals and surfaces of the last frame
    /// ([`Self::inspection`]).
    fn forget_last_frame(&mut self) {
        self.scene = None;
        self.mount_mismatch = false;
        self.roles.ground.clear();
        self.roles.inclined = None;
        if let Some(seen) = &mut self.paper.inspected {
            seen.clear();
        }
    }

    /// Stage 2 with the configured design (its planes: [`segmented`]).
    fn segment_planes(&mut self, cloud: &CloudView<'_>, rng: &mut ChaCha8Rng) {
        match self.config.ransac.scoring {
            RansacScoring::SampleGrid => {
                self.segmenter.segment(
                    cloud,
                    &self.keep,
                    &self.config.ransac,
                    &self.config.segmentation,
                    rng,
                );
            }
            RansacScoring::EveryPoint => {
                self.every_point
                    .segment(cloud, &self.keep, &self.config.ransac, rng);
            }
        }
    }

    /// The segmented planes' summaries and the ground among them (`None`:
    /// no ground).
    fn select_ground(&mut self, cloud: &CloudView<'_>) -> Option<Ground> {
        self.summarize_planes(cloud);
        let mount_up = cloud.mount.up_vector().map(Vector3::from);
        let height = Some(cloud.mount.height_m);
        let ground = select_ground(&self.summaries, mount_up, height, &self.config.selection);
        self.mount_mismatch = ground.as_ref().is_some_and(|g| {
            mount_disagrees(&self.summaries, g, mount_up, height, &self.config.selection)
        });
        ground
    }

    /// Every surface over `ground` (into `self.scene`) and the road among
    /// them: the ground alone (the error) without a road.
    fn survey(&mut self, cloud: &CloudView<'_>, ground: Ground) -> Result<Selection, Ground> {
        let input = SurveyInput {
            cloud,
            planes: segmented(&self.segmenter, &self.every_point, &self.config),
            summaries: &self.summaries,
            mount_up: cloud.mount.up_vector().map(Vector3::from),
            mount_height_m: Some(cloud.mount.height_m),
        };
        self.scene = survey_surfaces(&input, &ground, &self.config.selection, &self.config.road);
        let selection = &self.config.selection;
        let road = self.scene.as_ref().and_then(|scene| {
            let road = scene.road?;
            let surface = scene.road_surface()?;
            let pieces = road_pieces(
                &scene.surfaces,
                &self.summaries,
                &scene.frame,
                selection,
                &road,
            )
            .into_iter()
            .map(|k| scene.surfaces[k].plane_index)
            .collect();
            Some((surface.plane_index, pieces, scene.frame))
        });
        match road {
            Some((inclined, inclined_pieces, frame)) => Ok(Selection {
                ground,
                inclined,
                inclined_pieces,
                up: frame.up,
                forward: frame.forward,
            }),
            None => Err(ground),
        }
    }

    /// Keeps the selection's roles for [`Self::inspection`].
    fn keep_roles(&mut self, selection: &Selection) {
        if let Ground::Planes(members) = &selection.ground {
            self.roles.ground.extend_from_slice(members);
        }
        self.roles.inclined = Some(selection.inclined);
    }

    /// Stage 1 into `self.keep`; too few points left is an error.
    fn remove_outliers(&mut self, cloud: &CloudView<'_>) -> Result<(), EstimateStatus> {
        let kept = if self.config.outlier.enabled {
            match self.config.outlier.neighbourhood {
                OutlierNeighbourhood::Grid => self.outlier.filter_on(
                    cloud,
                    &self.config.outlier,
                    &mut self.keep,
                    self.pool.as_deref(),
                ),
                OutlierNeighbourhood::KdTree => {
                    self.knn_outlier
                        .filter(cloud, &self.config.outlier, &mut self.keep)
                }
            }
            .kept
        } else {
            self.keep.clear();
            self.keep.extend(cloud.points.iter().map(is_measured));
            self.keep.iter().filter(|&&k| k).count()
        };
        let kept = kept.min(keep_within_depth_range(
            cloud,
            self.depth_range_m(),
            &mut self.keep,
        ));
        if kept < self.config.ransac.min_plane_points.max(3) {
            return Err(EstimateStatus::TooFewPoints);
        }
        Ok(())
    }

    /// The depths read at all: `outlier.depth_range_m`, else the noise
    /// model's.
    fn depth_range_m(&self) -> (f64, f64) {
        match self.config.outlier.depth_range_m {
            Some([near, far]) => (near, far),
            None => self
                .config
                .selection
                .noise_model
                .unwrap_or_default()
                .depth_range_m(),
        }
    }

    /// No inclined plane: the estimate says so, with the ground plane (its
    /// TLS fit) when one was seen, so that a planner knows the floor ahead
    /// is flat and where it is.
    fn ground_only(&mut self, cloud: &CloudView<'_>, ground: Ground) -> Estimate {
        let mut estimate = Estimate::failed(EstimateStatus::NoInclinedPlane, self.config.method);
        if let Ground::Planes(members) = ground {
            self.roles.ground.extend_from_slice(&members);
            let segment = PlaneSegment::joined(
                segmented(&self.segmenter, &self.every_point, &self.config),
                &self.summaries,
                &members,
                &mut self.ground_pixels,
            );
            estimate.ground = flat_ground_estimate(&segment);
            // The ground frame's forward, as for the selection.
            if let Some(scene) = &self.scene {
                estimate.ground_seen_to_m =
                    ground_seen_to_m(cloud.points, segment.inliers, &scene.frame.forward);
            }
        }
        estimate
    }

    /// What the selection needs of every segmented plane: with a pool,
    /// the planes' summaries on its threads (each plane's alone, collected
    /// in plane order: the same summaries).
    fn summarize_planes(&mut self, cloud: &CloudView<'_>) {
        use rayon::prelude::*;
        let threshold = Threshold::of(&self.config.ransac);
        let noise = self.config.selection.noise_model.unwrap_or_default();
        let planes = segmented(&self.segmenter, &self.every_point, &self.config);
        let summary = |p: &SegmentedPlane| PlaneSummary::of(cloud, p, &threshold, noise);
        self.summaries.clear();
        match self.pool.as_deref() {
            Some(pool) if planes.len() > 1 => pool.install(|| {
                planes
                    .par_iter()
                    .map(summary)
                    .collect_into_vec(&mut self.summaries)
            }),
            _ => self.summaries.extend(planes.iter().map(summary)),
        }
    }
}

/// The planes of the last segmentation, from the configured RANSAC.
fn segmented<'a>(
    segmenter: &'a Segmentation,
    every_point: &'a EveryPointRansac,
    config: &EstimatorConfig,
) -> &'a [SegmentedPlane] {
    match config.ransac.scoring {
        RansacScoring::SampleGrid => segmenter.planes(),
        RansacScoring::EveryPoint => every_point.planes(),
    }
}

/// The buffers of the paper method's stages 3-6.
#[derive(Debug, Clone, Default)]
struct PaperStages {
    /// Stages 3-5 of the inclined plane and of the ground, each with its
    /// own buffers (with `threads` > 1 the two run at once).
    inclined: PlaneStages,
    ground: PlaneStages,
    ground_normals: Vec<Vector3<f64>>,
    inclined_normals: Vec<Vector3<f64>>,
    /// The sampled normals of the frame, when inspecting.
    inspected: Option<Vec<InspectedNormal>>,
}

impl PaperStages {
    /// Pass-through, normals and k-means on both planes, then the
    /// cumulative angle (`ground` `None`: the selection's up vector).
    /// With a pool (and not inspecting) the two planes' stages 3-5 run at
    /// once, each on its own buffers: the same computations as one after
    /// the other, so the same bits; their time is one lap, `normals`.
    #[allow(clippy::too_many_arguments)]
    fn fit(
        &mut self,
        cloud: &CloudView<'_>,
        inclined: &PlaneSegment<'_>,
        ground: Option<&PlaneSegment<'_>>,
        selection: &Selection,
        config: &EstimatorConfig,
        rng: &mut ChaCha8Rng,
        clock: &mut Stopwatch,
        pool: Option<&rayon::ThreadPool>,
    ) -> Result<Fit, EstimateStatus> {
        let (incl, ground_normal) = match (ground, pool) {
            (Some(g), Some(pool)) if self.inspected.is_none() => {
                let (a, b) = (&mut self.inclined, &mut self.ground);
                let (ia, ib) = (&mut self.inclined_normals, &mut self.ground_normals);
                let (incl, ground_normal) = pool.join(
                    || a.dominant_normal(cloud, inclined, config, ia, None),
                    || b.dominant_normal(cloud, g, config, ib, None),
                );
                clock.lap("normals");
                let incl = incl.ok_or(EstimateStatus::NoInclinedPlane)?;
                (incl, Some(ground_normal.ok_or(EstimateStatus::NoGround)?))
            }
            _ => {
                let seen = self.inspected.as_mut().map(|v| (v, true));
                let incl = self
                    .inclined
                    .dominant_normal(
                        cloud,
                        inclined,
                        config,
                        &mut self.inclined_normals,
                        Some((clock, seen)),
                    )
                    .ok_or(EstimateStatus::NoInclinedPlane)?;
                let ground_normal = match ground {
                    Some(g) => {
                        let seen = self.inspected.as_mut().map(|v| (v, false));
                        Some(
                            self.ground
                                .dominant_normal(
                                    cloud,
                                    g,
                                    config,
                                    &mut self.ground_normals,
                                    Some((clock, seen)),
                                )
                                .ok_or(EstimateStatus::NoGround)?,
                        )
                    }
                    None => {
                        self.ground_normals.clear();
                        self.ground_normals.push(selection.up);
                        None
                    }
                };
                (incl, ground_normal)
            }
        };
        let axis = config
            .cumulative
            .about_axis
            .then(|| rotation_axis(&ground_normal.unwrap_or(selection.up), &incl))
            .flatten();
        let summary = cumulative_angle(
            &self.inclined_normals,
            &self.ground_normals,
            config.cumulative.draws,
            axis.as_ref(),
            rng,
        )
        .ok_or(EstimateStatus::NoInclinedPlane)?;
        clock.lap("cumulative");
        Ok(Fit {
            inclined: Plane::from_point_normal(&inclined.centroid, &incl),
            ground: ground_normal
                .zip(ground)
                .and_then(|(n, g)| Plane::from_point_normal(&g.centroid, &n)),
            angle_deg: summary.mean_deg,
            std_deg: summary.std_deg,
            samples: summary.samples,
        })
    }
}

/// Where one plane's stages report: the clock (a lap per stage) and, when
/// inspecting, the frame's sampled normals with whether this is the
/// inclined plane.
type PlaneReport<'a> = (
    &'a mut Stopwatch,
    Option<(&'a mut Vec<InspectedNormal>, bool)>,
);

/// Stages 3-5 of one plane, with their buffers.
#[derive(Debug, Clone, Default)]
struct PlaneStages {
    pass_through: PassThroughStage,
    normals: NormalsStage,
    kmeans: CosineKmeans,
}

impl PlaneStages {
    /// Pass-through, normals and cosine k-means for one plane: fills `out`
    /// with the dominant cluster's normals and returns their (unit) mean.
    fn dominant_normal(
        &mut self,
        cloud: &CloudView<'_>,
        segment: &PlaneSegment<'_>,
        config: &EstimatorConfig,
        out: &mut Vec<Vector3<f64>>,
        mut report: Option<PlaneReport<'_>>,
    ) -> Option<Vector3<f64>> {
        let mut lap = |name| {
            if let Some((clock, _)) = &mut report {
                clock.lap(name);
            }
        };
        out.clear();
        let (members, support, walked) =
            self.pass_through
                .filter(cloud, segment, &config.pass_through);
        lap("pass_through");
        let found = self.normals.estimate(
            cloud,
            members,
            (support, walked),
            segment.rms_m,
            &config.normals,
        );
        lap("normals");
        let clustering = self.kmeans.cluster(
            found,
            config.kmeans.clusters,
            config.kmeans.max_iterations,
            config.kmeans.merge_spread_ratio,
        );
        if let (Some((_, Some((seen, inclined)))), Some(c)) = (&mut report, &clustering) {
            let flags = self.kmeans.kept_flags(found, c);
            inspect_normals(seen, members, found, flags, *inclined);
        }
        let result = clustering.and_then(|c| {
            out.extend(self.kmeans.kept_members(&c).copied());
            out.iter().sum::<Vector3<f64>>().try_normalize(1e-12)
        });
        if let Some((clock, _)) = &mut report {
            clock.lap("kmeans");
        }
        result
    }
}

/// Stage 3, ours (surface-uniform) or the paper's as written (depth).
#[derive(Debug, Clone, Default)]
struct PassThroughStage {
    surface_uniform: PassThrough,
    depth: DepthPassThrough,
}

impl PassThroughStage {
    /// The points of `inliers` kept, and the points their normals take
    /// their neighbourhoods from. The depth cut is the plane from here on
    /// (the paper); the surface-uniform sample's normals see all its
    /// points, which the pass-through's walk also summarises for them
    /// (when it can: `PassThrough::filter_plane`).
    fn filter<'a>(
        &'a mut self,
        cloud: &CloudView<'_>,
        segment: &PlaneSegment<'a>,
        config: &PassThroughConfig,
    ) -> (&'a [u32], &'a [u32], Option<PlaneSupport<'a>>) {
        let (max_points, inliers) = (config.max_points, segment.inliers);
        match (config.mode, segment.pixel_box) {
            // The labelling's inliers: their box and centre are known.
            (PassThroughMode::SurfaceUniform, Some(pixel_box)) => {
                let (kept, support) = self.surface_uniform.filter_segment(
                    cloud.points,
                    inliers,
                    (pixel_box, segment.centroid),
                    max_points,
                );
                (kept, inliers, support)
            }
            (PassThroughMode::SurfaceUniform, None) => {
                let (kept, walked) = self
                    .surface_uniform
                    .filter_plane(cloud, inliers, max_points);
                (kept, inliers, walked)
            }
            (PassThroughMode::Depth, _) => {
                let kept = self.depth.filter(cloud.points, inliers, max_points);
                (kept, kept, None)
            }
        }
    }
}

/// Stage 4, ours (summed-area windows) or the paper's as written (k-d
/// tree).
#[derive(Debug, Clone, Default)]
struct NormalsStage {
    window: NormalEstimator,
    kd_tree: KnnNormalEstimator,
}

impl NormalsStage {
    /// The normals at `members` from the neighbourhoods among `support`,
    /// oriented towards the camera, on a patch that grows with the plane's
    /// own noise (`rms_m`). The windows take `support` from its summary
    /// when the pass-through made one (`walked`, the same points).
    fn estimate(
        &mut self,
        cloud: &CloudView<'_>,
        members: &[u32],
        (support, walked): (&[u32], Option<PlaneSupport<'_>>),
        rms_m: f64,
        config: &NormalsConfig,
    ) -> &[Vector3<f64>] {
        let normals_config = config.for_plane_noise(rms_m);
        let origin = Vector3::zeros();
        match (config.neighbourhood, walked) {
            (NormalsNeighbourhood::Window, Some(walked)) => {
                self.window
                    .estimate_on_plane(cloud, members, &walked, &normals_config, &origin)
                    .0
            }
            (NormalsNeighbourhood::Window, None) => {
                self.window
                    .estimate_with_support(cloud, members, support, &normals_config, &origin)
                    .0
            }
            (NormalsNeighbourhood::KdTree, _) => {
                self.kd_tree
                    .estimate(cloud, members, support, &normals_config, &Vector3::zeros())
            }
        }
    }
}

/// Keeps a plane's finite normals for [`Inspection`], each with the
/// k-means verdict (`kept`, one flag per normal in `found`).
fn inspect_normals(
    seen: &mut Vec<InspectedNormal>,
    members: &[u32],
    found: &[Vector3<f64>],
    kept: impl Iterator<Item = bool>,
    inclined: bool,
) {
    for ((&pixel, n), kept) in members.iter().zip(found).zip(kept) {
        if n.iter().all(|x| x.is_finite()) {
            seen.push(InspectedNormal {
                pixel,
                normal: [n.x as f32, n.y as f32, n.z as f32],
                kept,
                inclined,
            });
        }
    }
}

// The estimator daemon moves the estimator into its worker thread.
const _: fn() = || {
    fn assert_send<T: Send>() {}
    assert_send::<Estimator>();
};

/// Drops from `keep` the points whose depth lies outside `(near, far)`
/// metres (a saturated frame of 65.5 m read as a plane at 70 degrees);
/// the points kept.
fn keep_within_depth_range(
    cloud: &CloudView<'_>,
    (near, far): (f64, f64),
    keep: &mut [bool],
) -> usize {
    let mut kept = 0;
    for (keep, p) in keep.iter_mut().zip(cloud.points) {
        *keep &= (near..=far).contains(&f64::from(p.z_m));
        kept += usize::from(*keep);
    }
    kept
}
