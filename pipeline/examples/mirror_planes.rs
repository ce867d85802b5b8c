//! Planes of frame 0 as recorded and mirrored (debug aid).
#[path = "../tests/common/mod.rs"]
mod common;
use common::{Recording, View};
use slope_pipeline::{Estimator, EstimatorConfig};

fn main() {
    let dir = std::env::args().nth(1).expect("dir");
    let rec = Recording::open(std::path::Path::new(&dir)).expect("rec");
    let cfg = match std::env::var("CONFIG") {
        Ok(text) => EstimatorConfig::from_toml_str(&text).expect("CONFIG"),
        Err(_) => EstimatorConfig::default(),
    }
    .for_sensor(rec.sensor());
    let seeds: u64 = std::env::var("SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    if seeds > 0 {
        for v in View::BOTH {
            let f = rec.frame_as(0, v).expect("frame");
            let mut s: Vec<f64> = (0..seeds)
                .map(|seed| {
                    let mut c = cfg.clone();
                    c.seed = seed;
                    Estimator::new(c).estimate(&f.view()).slope_deg.abs()
                })
                .collect();
            s.sort_by(f64::total_cmp);
            println!(
                "{}: median {:.2} min {:.2} max {:.2}",
                v.name(),
                s[s.len() / 2],
                s[0],
                s[s.len() - 1]
            );
        }
        return;
    }
    for v in View::BOTH {
        let f = rec.frame_as(0, v).expect("frame");
        let mut est = Estimator::new(cfg.clone());
        let e = est.estimate(&f.view());
        let ins = est.inspection();
        println!(
            "{}: slope {:.2} ground {:?} inclined {:?}",
            v.name(),
            e.slope_deg,
            ins.ground,
            ins.inclined
        );
        for (k, p) in ins.planes.iter().enumerate() {
            let n = p.plane.normal;
            let n = if v.name() == "mirrored" {
                [-n.x, n.y, n.z]
            } else {
                [n.x, n.y, n.z]
            };
            println!(
                "  {k}: n [{:.3} {:.3} {:.3}] d {:.3} inliers {} rms {:.4}",
                n[0],
                n[1],
                n[2],
                p.plane.d,
                p.inliers.len(),
                p.rms_m
            );
        }
    }
}
