//! Prints what every stage did on one frame of a recording: planes, the
//! surfaces with their roles and the road (as the estimator chooses), the
//! pass-through range, normal and cluster statistics.
//!
//! `cargo run -p slope-pipeline --example debug_frame -- DIR [FRAME]`
//! (`CONFIG=toml` runs with that estimator config, e.g.
//! `CONFIG=$'[ransac]\ndistance_threshold_per_m2 = 0'`; unset: the default)

#[path = "../tests/common/mod.rs"]
mod common;

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use slope_pipeline::cloud::angle_between_deg;
use slope_pipeline::cosine_kmeans::CosineKmeans;
use slope_pipeline::normals::NormalEstimator;
use slope_pipeline::pass_through::PassThrough;
use slope_pipeline::ransac_planes::{SegmentedPlane, Threshold};
use slope_pipeline::segmentation::Segmentation;
use slope_pipeline::selection::{
    select_ground, survey_surfaces, Ground, PlaneSummary, SurveyInput,
};
use slope_pipeline::statistical_outlier::StatisticalOutlierFilter;
use slope_pipeline::{CloudView, EstimatorConfig};

/// The colours of the label image, plane k in colour k % 10.
const PALETTE: [[u8; 3]; 10] = [
    [230, 25, 75],
    [60, 180, 75],
    [255, 225, 25],
    [0, 130, 200],
    [245, 130, 48],
    [145, 30, 180],
    [70, 240, 240],
    [240, 50, 230],
    [210, 245, 60],
    [250, 190, 212],
];

fn main() {
    let mut args = std::env::args().skip(1);
    let dir = args.next().expect("recording directory");
    let k: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(0);
    let rec = common::Recording::open(std::path::Path::new(&dir)).expect("recording");
    let frame = rec.frame(k).expect("frame");
    let view = frame.view();
    let config = match std::env::var("CONFIG") {
        Ok(text) => EstimatorConfig::from_toml_str(&text).expect("CONFIG"),
        Err(_) => EstimatorConfig::default(),
    }
    .for_sensor(rec.sensor());
    let planes = segment_planes(&view, &config);
    let up = view.mount.up_vector().map(Vector3::from);
    let summaries = print_planes(&view, &planes, &config, up);
    write_label_image(&dir, &view, &planes);
    let config_sel = &config.selection;
    let Some(ground) = select_ground(&summaries, up, Some(view.mount.height_m), config_sel) else {
        println!("selection: no ground");
        return;
    };
    // The estimator's own choice: every surface with its role, the road.
    let input = SurveyInput {
        cloud: &view,
        planes: &planes,
        summaries: &summaries,
        mount_up: up,
        mount_height_m: Some(view.mount.height_m),
    };
    let scene = survey_surfaces(&input, &ground, config_sel, &config.road);
    println!("ground: {ground:?}");
    let road = scene.as_ref().and_then(|scene| {
        for (k, s) in scene.surfaces.iter().enumerate() {
            println!("  surface {k:2} plane {:2}: {s}", s.plane_index);
        }
        scene.road_surface().map(|s| s.plane_index)
    });
    println!("road: {road:?}");
    let mut chosen = Vec::new();
    if let Some(road) = road {
        chosen.push(("road", road));
    }
    if let Ground::Planes(g) = &ground {
        chosen.push(("ground", g[0]));
    }
    let means: Vec<_> = chosen
        .into_iter()
        .map(|(name, idx)| print_plane_normals(name, &view, &planes[idx], &config))
        .collect();
    if means.len() == 2 {
        println!(
            "angle of kept means {:.3}, of TLS planes {:.3}",
            angle_between_deg(&means[0].0, &means[1].0),
            angle_between_deg(&means[0].1, &means[1].1)
        );
    }
}

/// Runs the outlier filter (printing its statistics) and the segmentation
/// (`segmentation.proposal`); returns
/// the planes found.
fn segment_planes(view: &CloudView<'_>, config: &EstimatorConfig) -> Vec<SegmentedPlane> {
    let mut keep = Vec::new();
    let stats = StatisticalOutlierFilter::new().filter(view, &config.outlier, &mut keep);
    println!("outlier: {stats:?}");
    let mut seg = Segmentation::new();
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    seg.segment(view, &keep, &config.ransac, &config.segmentation, &mut rng)
        .to_vec()
}

/// Prints one line per plane (fit, quality, centroid, angle to `up`, pixel
/// bounding box); returns their summaries.
fn print_planes(
    view: &CloudView<'_>,
    planes: &[SegmentedPlane],
    config: &EstimatorConfig,
    up: Option<Vector3<f64>>,
) -> Vec<PlaneSummary> {
    let noise = config.selection.noise_model.unwrap_or_default();
    let threshold = Threshold::of(&config.ransac);
    let summaries: Vec<PlaneSummary> = planes
        .iter()
        .map(|p| PlaneSummary::of(view, p, &threshold, noise))
        .collect();
    for (i, s) in summaries.iter().enumerate() {
        let (u0, v0, u1, v1) = pixel_bbox(&planes[i], view.width);
        let q = &s.quality;
        println!(
            "plane {i}: n [{:+.4} {:+.4} {:+.4}] d {:.3} inliers {} rms {:.4} rel {:.2} noise {:.1} area {:.2} border {:.2} veil {:.2} centroid [{:.2} {:.2} {:.2}] up-angle {:.2} bbox u {u0}..{u1} v {v0}..{v1}",
            s.plane.normal.x, s.plane.normal.y, s.plane.normal.z, s.plane.d, s.inliers, q.rms_m, q.relative_rms, q.noise_ratio, q.area_m2, q.border_fraction, q.veil_fraction,
            s.centroid.x, s.centroid.y, s.centroid.z,
            up.map_or(f64::NAN, |u| angle_between_deg(&s.plane.normal, &u))
        );
    }
    summaries
}

/// The pixel bounding box of a plane's inliers: (u min, v min, u max, v max).
fn pixel_bbox(plane: &SegmentedPlane, w: usize) -> (usize, usize, usize, usize) {
    plane
        .inliers
        .iter()
        .fold((usize::MAX, usize::MAX, 0, 0), |b, &p| {
            let (u, v) = (p as usize % w, p as usize / w);
            (b.0.min(u), b.1.min(v), b.2.max(u), b.3.max(v))
        })
}

/// Writes the label image (depth in grey, planes in colour) to
/// `$TMPDIR/labels_<recording name>.png` and says where.
fn write_label_image(dir: &str, view: &CloudView<'_>, planes: &[SegmentedPlane]) {
    let w = view.width;
    let mut rgb = vec![0u8; w * view.height * 3];
    for (i, p) in view.points.iter().enumerate() {
        if p.z_m.is_finite() {
            let g = (255.0 - (p.z_m * 50.0).min(200.0)) as u8 / 2;
            rgb[3 * i..3 * i + 3].copy_from_slice(&[g, g, g]);
        }
    }
    for (k, p) in planes.iter().enumerate() {
        for &i in &p.inliers {
            let i = i as usize;
            rgb[3 * i..3 * i + 3].copy_from_slice(&PALETTE[k % 10]);
        }
    }
    let name = std::path::Path::new(dir)
        .file_name()
        .map_or_else(|| "frame".into(), |n| n.to_string_lossy().into_owned());
    let out = std::env::temp_dir().join(format!("labels_{name}.png"));
    let file = std::fs::File::create(&out).expect("png");
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w as u32, view.height as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header()
        .expect("png")
        .write_image_data(&rgb)
        .expect("png");
    println!("labels in {} (plane k = palette k: red, green, yellow, blue, orange, purple, cyan, magenta, lime, pink)", out.display());
}

/// Runs pass-through, normals and k-means on one chosen plane and prints
/// what they did and how the kept normals' mean compares with TLS fits;
/// returns the kept mean and the plane's normal.
fn print_plane_normals(
    name: &str,
    view: &CloudView<'_>,
    plane: &SegmentedPlane,
    config: &EstimatorConfig,
) -> (Vector3<f64>, Vector3<f64>) {
    let mut pt = PassThrough::new();
    let (members, range) = pt.filter(view.points, &plane.inliers, config.pass_through.max_points);
    let members = members.to_vec();
    let mut ne = NormalEstimator::new();
    let (normals, nstats) = ne.estimate_with_support(
        view,
        &members,
        &plane.inliers,
        &config.normals.for_plane_noise(plane.rms_m),
        &Vector3::zeros(),
    );
    let normals = normals.to_vec();
    let mut km = CosineKmeans::new();
    let c = km
        .cluster(
            &normals,
            config.kmeans.clusters,
            config.kmeans.max_iterations,
            config.kmeans.merge_spread_ratio,
        )
        .expect("clusters");
    let kept: Vector3<f64> = km.kept_members(&c).sum();
    let all: Vector3<f64> = normals.iter().filter(|n| n.x.is_finite()).sum();
    println!(
        "{name}: range {range:?}\n   normals {nstats:?} clusters {:?} kept {:?} spread {:.2} centre angles {:?}\n   kept-mean vs tls {:.3} deg, all-mean vs tls {:.3}",
        c.counts,
        c.kept,
        c.spread_deg,
        c.centres.iter().map(|x| format!("{:.2}", angle_between_deg(x, &c.centres[c.dominant]))).collect::<Vec<_>>(),
        angle_between_deg(&kept, &plane.plane.normal),
        angle_between_deg(&all, &plane.plane.normal),
    );
    print_kept_tls(view, &members, plane, &kept);
    (kept, plane.plane.normal)
}

/// Prints how a TLS fit of the pass-through `members` compares with the
/// plane's TLS fit and with the kept normals' mean.
fn print_kept_tls(
    view: &CloudView<'_>,
    members: &[u32],
    plane: &SegmentedPlane,
    kept: &Vector3<f64>,
) {
    let mut bm = slope_pipeline::plane_fit::Moments::new();
    for &i in members {
        if let Some(p) = view.point(i as usize) {
            bm.add(&p);
        }
    }
    if let Some(bp) = slope_pipeline::plane_fit::fit_tls(&bm) {
        println!(
            "   kept-tls vs plane-tls {:.3} deg, kept-mean vs kept-tls {:.3}",
            angle_between_deg(&bp.normal, &plane.plane.normal),
            angle_between_deg(kept, &bp.normal)
        );
    }
}
