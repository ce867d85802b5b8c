//! Criterion benches, one group per stage, on a full 512 x 424 Kinect v2
//! frame of a 16 degree ramp (the fixtures the unit tests use).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use slope_pipeline::cosine_kmeans::CosineKmeans;
use slope_pipeline::cumulative_angle::cumulative_angle;
use slope_pipeline::fixtures::{Scene, SceneCloud};
use slope_pipeline::normals::{NormalEstimator, NormalsConfig, PlaneSupport};
use slope_pipeline::pass_through::PassThrough;
use slope_pipeline::ransac_planes::PlaneSegmenter;
use slope_pipeline::statistical_outlier::StatisticalOutlierFilter;
use slope_pipeline::{CloudView, Estimator, EstimatorConfig, SlopeMethod};

fn frame() -> SceneCloud {
    SceneCloud::kinect2(&Scene::ramp_between_walls(16.0), 1)
}

/// Every stage in pipeline order, each on the previous stage's output,
/// then the whole estimator per method.
fn stages(c: &mut Criterion) {
    let cloud = frame();
    let view = cloud.view();
    let config = EstimatorConfig::default();
    let keep = bench_statistical_outlier(c, &view, &config);
    let (largest, rms_m) = bench_ransac_planes(c, &view, &config, &keep);
    let mut pt = PassThrough::new();
    let (members, support) = bench_pass_through(c, &mut pt, &view, &config, &largest);
    // The normals as the estimator computes them: 10k surface-uniform
    // members, neighbourhoods from the whole plane, the noise-scaled patch.
    let normals_config = config.normals.for_plane_noise(rms_m);
    let normals = bench_normals(c, &view, &members, &support, &normals_config);
    bench_cosine_kmeans(c, &config, &normals);
    bench_cumulative_angle(c, &normals);
    bench_estimator(c, &view);
}

/// `statistical_outlier/full_frame`; returns which points it keeps.
fn bench_statistical_outlier(
    c: &mut Criterion,
    view: &CloudView<'_>,
    config: &EstimatorConfig,
) -> Vec<bool> {
    let mut sor = StatisticalOutlierFilter::new();
    let mut keep = Vec::new();
    c.bench_function("statistical_outlier/full_frame", |b| {
        b.iter(|| black_box(sor.filter(view, &config.outlier, &mut keep)))
    });
    // The statistic in bands of rows on two threads (`threads = 2`).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("two threads");
    c.bench_function("statistical_outlier/full_frame_2_threads", |b| {
        b.iter(|| black_box(sor.filter_on(view, &config.outlier, &mut keep, Some(&pool))))
    });
    sor.filter(view, &config.outlier, &mut keep);
    keep
}

/// `ransac_planes/full_frame`; returns the largest plane's inliers and its
/// RMS distance.
fn bench_ransac_planes(
    c: &mut Criterion,
    view: &CloudView<'_>,
    config: &EstimatorConfig,
    keep: &[bool],
) -> (Vec<u32>, f64) {
    let mut seg = PlaneSegmenter::new();
    c.bench_function("ransac_planes/full_frame", |b| {
        b.iter(|| {
            let mut rng = ChaCha8Rng::seed_from_u64(0);
            black_box(seg.segment(view, keep, &config.ransac, &mut rng).len())
        })
    });
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let planes = seg.segment(view, keep, &config.ransac, &mut rng).to_vec();
    planes
        .iter()
        .max_by_key(|p| p.inliers.len())
        .map(|p| (p.inliers.clone(), p.rms_m))
        .unwrap_or_default()
}

/// `pass_through/largest_plane`, as the estimator runs it: its walk over
/// the plane also takes the support the normals' tables need. Returns the
/// members kept and that support.
fn bench_pass_through<'a>(
    c: &mut Criterion,
    pt: &'a mut PassThrough,
    view: &CloudView<'_>,
    config: &EstimatorConfig,
    largest: &[u32],
) -> (Vec<u32>, PlaneSupport<'a>) {
    c.bench_function("pass_through/largest_plane", |b| {
        b.iter(|| {
            black_box(
                pt.filter_plane(view, largest, config.pass_through.max_points)
                    .0
                    .len(),
            )
        })
    });
    let (kept, support) = pt.filter_plane(view, largest, config.pass_through.max_points);
    let members = kept.to_vec();
    let support = support.expect("the largest plane's pixels are in order and measured");
    (members, support)
}

/// `normals/10k_points_k100`; returns the normals.
fn bench_normals(
    c: &mut Criterion,
    view: &CloudView<'_>,
    members: &[u32],
    support: &PlaneSupport<'_>,
    normals_config: &NormalsConfig,
) -> Vec<Vector3<f64>> {
    let mut ne = NormalEstimator::new();
    c.bench_function("normals/10k_points_k100", |b| {
        b.iter(|| {
            black_box(
                ne.estimate_on_plane(view, members, support, normals_config, &Vector3::zeros())
                    .1,
            )
        })
    });
    ne.estimate_on_plane(view, members, support, normals_config, &Vector3::zeros())
        .0
        .to_vec()
}

/// `cosine_kmeans/10k_normals`.
fn bench_cosine_kmeans(c: &mut Criterion, config: &EstimatorConfig, normals: &[Vector3<f64>]) {
    let mut km = CosineKmeans::new();
    c.bench_function("cosine_kmeans/10k_normals", |b| {
        b.iter(|| {
            black_box(km.cluster(
                normals,
                config.kmeans.clusters,
                config.kmeans.max_iterations,
                config.kmeans.merge_spread_ratio,
            ))
        })
    });
}

/// `cumulative_angle/100_draws`, against 1000 copies of one ground normal.
fn bench_cumulative_angle(c: &mut Criterion, normals: &[Vector3<f64>]) {
    let ground = vec![Vector3::new(0.0, -0.94, -0.34); 1000];
    c.bench_function("cumulative_angle/100_draws", |b| {
        b.iter(|| {
            let mut rng = ChaCha8Rng::seed_from_u64(0);
            black_box(cumulative_angle(normals, &ground, 100, None, &mut rng))
        })
    });
}

/// `estimator/<method>`: the whole estimator, per method.
fn bench_estimator(c: &mut Criterion, view: &CloudView<'_>) {
    for method in SlopeMethod::ALL {
        let mut est = Estimator::new(EstimatorConfig {
            method,
            ..EstimatorConfig::default()
        });
        c.bench_function(&format!("estimator/{}", method.name()), |b| {
            b.iter(|| black_box(est.estimate(view).slope_deg))
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = stages
}
criterion_main!(benches);
