//! Ablation of our changes to the paper's pipeline (pipeline README, "The
//! paper as written, and what each change buys"): the paper as written
//! (`EstimatorConfig::paper_literal`), each change switched on alone, all
//! of those our default keeps (our default), and each switched off alone
//! from our default (switched on, for the two it does not keep: 8 and 9);
//! on simulated Kinect v2 frames (analytic scenes, 5-90 degrees, walls,
//! clutter; re-rendered with new noise for every seed) and on the real
//! frames in `shared/data` as recorded and mirrored. Prints a Markdown
//! table: mean and worst |error| (degrees), frames that failed (status not
//! `ok`, left out of the mean), median milliseconds per frame.
//!
//! `cargo run --release -p slope-pipeline --example ablation`
//! (`SEEDS=n` seeds 0..n per simulated scene, default 3; `REAL_SEEDS=n`
//! per real frame, default 2; `ONLY=text` runs the variants whose name
//! contains it)

#[path = "../tests/common/mod.rs"]
mod common;

use common::{Frame, Recording, View};
use slope_pipeline::fixtures::{Scene, SceneCloud};
use slope_pipeline::literal::{
    NormalsNeighbourhood, OutlierNeighbourhood, PassThroughMode, RansacScoring,
};
use slope_pipeline::segmentation::Proposal;
use slope_pipeline::statistical_outlier::Fallback;
use slope_pipeline::{EstimateStatus, Estimator, EstimatorConfig, FrameInfo};

/// One of our changes: how to switch it on or off (the paper), and whether
/// our default keeps it (8 and 9 bought nothing here and are off).
struct Change {
    name: &'static str,
    set: fn(&mut EstimatorConfig, bool),
    kept: bool,
}

const CHANGES: [Change; 12] = [
    Change {
        name: "1 grid outlier neighbours",
        set: |c, on| {
            c.outlier.neighbourhood = if on {
                OutlierNeighbourhood::Grid
            } else {
                OutlierNeighbourhood::KdTree
            }
        },
        kept: true,
    },
    Change {
        name: "2 RANSAC on the sample grid",
        set: |c, on| {
            c.ransac.scoring = if on {
                RansacScoring::SampleGrid
            } else {
                RansacScoring::EveryPoint
            }
        },
        kept: true,
    },
    Change {
        name: "2b inlier distance max(2 cm, 0.003 z^2)",
        set: |c, on| c.ransac.distance_threshold_per_m2 = if on { 0.003 } else { 0.0 },
        kept: true,
    },
    Change {
        name: "3 window normals (>= K points)",
        set: |c, on| {
            c.normals.neighbourhood = if on {
                NormalsNeighbourhood::Window
            } else {
                NormalsNeighbourhood::KdTree
            }
        },
        kept: true,
    },
    Change {
        name: "4 surface-uniform pass-through",
        set: |c, on| {
            c.pass_through.mode = if on {
                PassThroughMode::SurfaceUniform
            } else {
                PassThroughMode::Depth
            }
        },
        kept: true,
    },
    Change {
        name: "5 patch radius scaled to noise",
        set: |c, on| {
            c.normals.min_patch_radius_m = if on { 0.1 } else { 0.0 };
            c.normals.patch_per_rms = if on { 20.0 } else { 0.0 };
        },
        kept: true,
    },
    Change {
        name: "6 k-means merge",
        set: |c, on| c.kmeans.merge_spread_ratio = if on { 2.5 } else { 0.0 },
        kept: true,
    },
    Change {
        name: "7 1000 draws",
        set: |c, on| c.cumulative.draws = if on { 1000 } else { 100 },
        kept: true,
    },
    Change {
        name: "8 interior normals only",
        set: |c, on| c.normals.interior_only = on,
        kept: false,
    },
    Change {
        name: "9 pair angles about the axis",
        set: |c, on| c.cumulative.about_axis = on,
        kept: false,
    },
    Change {
        name: "10 cell-grid plane proposal",
        set: |c, on| {
            // On the sample grid (change 2): every-point RANSAC has no
            // proposal.
            c.ransac.scoring = RansacScoring::SampleGrid;
            c.segmentation.proposal = if on {
                Proposal::Cells
            } else {
                Proposal::Sequential
            }
        },
        kept: true,
    },
    Change {
        name: "11 outlier statistic of the present neighbours",
        set: |c, on| {
            c.outlier.neighbourhood = OutlierNeighbourhood::Grid;
            c.outlier.fallback = if on {
                Fallback::PresentNeighbours
            } else {
                Fallback::ExactWindow
            }
        },
        kept: true,
    },
];

/// Index of "3 window normals" (interior-only needs windows to mean
/// anything: with k-d tree normals every point is "interior").
const WINDOWS: usize = 3;
const INTERIOR: usize = 8;

fn variants() -> Vec<(String, EstimatorConfig)> {
    let mut out = vec![(
        "paper as written".to_string(),
        EstimatorConfig::paper_literal(),
    )];
    for (k, change) in CHANGES.iter().enumerate() {
        let mut c = EstimatorConfig::paper_literal();
        (change.set)(&mut c, true);
        let mut name = format!("+ {}", change.name);
        if k == INTERIOR {
            (CHANGES[WINDOWS].set)(&mut c, true);
            name = format!("+ 3 window normals + {}", change.name);
        }
        out.push((name, c));
    }
    out.push((
        "all of ours (default)".to_string(),
        EstimatorConfig::default(),
    ));
    for change in &CHANGES {
        let mut c = EstimatorConfig::default();
        (change.set)(&mut c, !change.kept);
        let sign = if change.kept { "-" } else { "+" };
        out.push((format!("ours {sign} {}", change.name), c));
    }
    out
}

/// One frame to measure, with its truth.
struct Case {
    name: String,
    frame: Frame,
    truth_deg: f64,
    real: bool,
    seed: u64,
}

fn env_usize(key: &str, default: usize) -> usize {
    std::env::var(key)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn simulated_cases(seeds: usize) -> Vec<Case> {
    let scenes = [
        (
            "ramp 5, roll 4",
            Scene::ramp_at(5.0, 2.0, 0.5, -20.0, 4.0),
            0,
        ),
        ("ramp 12.5", Scene::ramp(12.5), 0),
        (
            "ramp 16, roll -3",
            Scene::ramp_at(16.0, 1.5, 0.6, -25.0, -3.0),
            0,
        ),
        ("ramp 30", Scene::ramp(30.0), 0),
        ("ramp 47", Scene::ramp(47.0), 0),
        ("ramp 60", Scene::ramp(60.0), 0),
        (
            "wall 90, roll 5",
            Scene::ramp_at(90.0, 2.5, 0.4, -15.0, 5.0),
            0,
        ),
        (
            "downhill 10, roll 2",
            Scene::ramp_at(-10.0, 1.5, 0.5, -30.0, 2.0),
            0,
        ),
        ("ramp 16 between walls", Scene::ramp_between_walls(16.0), 0),
        (
            "ramp 12.5 between walls, 3000 flying pixels",
            Scene::ramp_between_walls(12.5),
            3000,
        ),
    ];
    let mut cases = Vec::new();
    for seed in 0..seeds as u64 {
        for (name, scene, flying) in &scenes {
            let mut cloud = SceneCloud::kinect2(scene, 1000 + seed);
            if *flying > 0 {
                cloud.inject_flying_pixels(*flying, seed);
            }
            cases.push(Case {
                name: name.to_string(),
                truth_deg: scene.truth_slope_deg.abs(),
                frame: Frame {
                    points: cloud.points,
                    width: cloud.width,
                    height: cloud.height,
                    intrinsics: cloud.intrinsics,
                    mount: cloud.mount,
                    sensor: "synthetic".into(),
                },
                real: false,
                seed,
            });
        }
    }
    cases
}

fn real_cases(seeds: usize) -> Vec<Case> {
    let mut cases = Vec::new();
    for name in [
        "kinect2-stairs-front",
        "kinect2-stairs-top",
        "kinect1-office",
    ] {
        let Some(dir) = common::shared_data(name) else {
            continue;
        };
        let rec = Recording::open(&dir).expect("recording");
        let truth = rec.truth_slope_deg.expect("[truth] slope_deg");
        for view in View::BOTH {
            let frame = rec.frame_as(0, view).expect("frame 0");
            for seed in 0..seeds as u64 {
                cases.push(Case {
                    name: format!("{name} {}", view.name()),
                    frame: frame.clone(),
                    truth_deg: truth,
                    real: true,
                    seed,
                });
            }
        }
    }
    cases
}

#[derive(Default)]
struct Tally {
    errors: Vec<f64>,
    failed: usize,
    ms: Vec<f64>,
}

impl Tally {
    fn mean(&self) -> f64 {
        self.errors.iter().sum::<f64>() / self.errors.len() as f64
    }
    fn worst(&self) -> f64 {
        self.errors.iter().copied().fold(f64::NAN, f64::max)
    }
    fn median_ms(&self) -> f64 {
        let mut v = self.ms.clone();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    }

    /// Estimates `case` with variant `name`'s `config` (the case's seed and
    /// sensor) and counts the result: its time, and its error or failure
    /// (an error above 3 degrees, or a failure, said on stderr).
    fn add(&mut self, name: &str, case: &Case, config: &EstimatorConfig) {
        let config = EstimatorConfig {
            seed: case.seed,
            ..config.clone()
        }
        .for_sensor(&case.frame.sensor);
        let mut est = Estimator::new(config);
        let e = est.estimate_frame(
            &case.frame.view(),
            FrameInfo {
                index: 0,
                stamp_ns: 0,
            },
        );
        self.ms.push(e.timings.total_ms);
        if e.status == EstimateStatus::Ok {
            let error = (e.slope_deg.abs() - case.truth_deg).abs();
            self.errors.push(error);
            if error > 3.0 {
                eprintln!(
                    "  {name}: {} seed {}: {:.2}",
                    case.name, case.seed, e.slope_deg
                );
            }
        } else {
            self.failed += 1;
            eprintln!(
                "  {name}: {} seed {}: {}",
                case.name,
                case.seed,
                e.status.name()
            );
        }
    }
}

fn main() {
    let seeds = env_usize("SEEDS", 3);
    let real_seeds = env_usize("REAL_SEEDS", 2);
    let only = std::env::var("ONLY").unwrap_or_default();
    let mut cases = simulated_cases(seeds);
    cases.extend(real_cases(real_seeds));
    let variants: Vec<_> = variants()
        .into_iter()
        .filter(|(name, _)| name.contains(&only))
        .collect();
    eprintln!("{} variants x {} frames", variants.len(), cases.len());
    let rows: Vec<String> = variants
        .iter()
        .map(|(name, config)| run_variant(name, config, &cases))
        .collect();
    println!(
        "| variant | simulated mean | worst | failed | ms | real mean | worst | failed | ms |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for row in rows {
        println!("{row}");
    }
}

/// Runs variant `name` on every case (reporting its misses and failures on
/// stderr); returns its table row.
fn run_variant(name: &str, config: &EstimatorConfig, cases: &[Case]) -> String {
    let (mut sim, mut real) = (Tally::default(), Tally::default());
    for case in cases {
        let tally = if case.real { &mut real } else { &mut sim };
        tally.add(name, case, config);
    }
    eprintln!(
        "{name}: sim {:.3}/{:.3}, real {:.3}/{:.3}",
        sim.mean(),
        sim.worst(),
        real.mean(),
        real.worst()
    );
    format!(
        "| {name} | {:.2} | {:.2} | {} | {:.0} | {:.2} | {:.2} | {} | {:.0} |",
        sim.mean(),
        sim.worst(),
        sim.failed,
        sim.median_ms(),
        real.mean(),
        real.worst(),
        real.failed,
        real.median_ms(),
    )
}
