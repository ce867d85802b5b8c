//! The smallest slope found per sensor and distance (issue #44, item 1):
//! the real floors of `shared/data` bent into ramps of 1-6 and 8 degrees at
//! hinges 1.5, 2 and 3 m ahead and the frame's own hinge of
//! `tests/gentle_ramps.rs` (where the frame's floor reaches past the hinge
//! with ground before it), each run with the default config for its
//! sensor at seeds 0-2; a ramp counts as found when every seed says `ok`
//! with the bent part as the road (`tests/common/bent.rs`).
//!
//! `cargo run --release -p slope-pipeline --example gentle_ramps` prints the
//! table (the pipeline README's "The smallest slope found");
//! `... --example gentle_ramps -- FRAME HINGE_M ANGLE_DEG` prints every
//! surface of that bent frame at each seed instead (`CONFIG=toml` runs it
//! with that estimator config).

#[path = "../tests/common/mod.rs"]
mod common;

#[path = "../tests/common/bent.rs"]
mod bent;

use std::path::Path;

use slope_pipeline::EstimatorConfig;
use slope_synth::bend::{bend_recording, BendParams};
use slope_synth::BendError;

const SEEDS: std::ops::Range<u64> = 0..3;
const ANGLES_DEG: [f64; 7] = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0];
const HINGES_M: [f64; 3] = [1.5, 2.0, 3.0];
const FRAMES: [(&str, &str); 7] = [
    ("Kinect v2", "kv2-mine-tunnel-0"),
    ("Kinect v2", "kinect2-stairs-front"),
    ("Kinect v1", "nyu-basement"),
    ("Kinect v1", "pcl-corridor-people"),
    ("Kinect v1", "tum-office-desk"),
    ("Kinect v1", "kinect1-office"),
    ("Kinect v1", "cape-foot-tunnel"),
];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let [name, hinge, angle] = args.as_slice() {
        let hinge: f64 = hinge.parse().expect("HINGE_M");
        let angle: f64 = angle.parse().expect("ANGLE_DEG");
        print_surfaces(name, hinge, angle);
        return;
    }
    println!("| sensor | frame | hinge (m) | floor bend at the hinge (deg) | found at every seed (1-6, 8 deg tried) | smallest | its error (deg) |");
    println!("|---|---|---|---|---|---|---|");
    for (sensor, name) in FRAMES {
        let Some(dir) = common::shared_data(name) else {
            continue;
        };
        let own = bent::QUALIFYING
            .iter()
            .find(|(n, _)| *n == name)
            .map(|&(_, h)| h);
        let mut hinges = HINGES_M.to_vec();
        if let Some(h) = own.filter(|h| !HINGES_M.contains(h)) {
            hinges.push(h);
        }
        for hinge in hinges {
            let mut found = Vec::new();
            let mut floor_bend = None;
            let mut refused = None;
            for angle in ANGLES_DEG {
                let b = match bend_recording(&dir, 0, &BendParams::new(angle, hinge)) {
                    Ok(b) => b,
                    Err(BendError::FloorShort { reach_m, .. }) => {
                        refused = Some(format!("the floor reaches {reach_m:.1} m"));
                        break;
                    }
                    Err(BendError::NoGroundBeforeHinge { from_m, .. }) => {
                        refused = Some(format!("the floor is seen from {from_m:.1} m"));
                        break;
                    }
                    Err(e) => panic!("{name}: {e}"),
                };
                floor_bend = b.floor_bend_deg;
                let frame = bent::project(&b);
                let ramp = bent::ramp_normal(&b);
                let verdicts: Vec<bent::Verdict> = SEEDS
                    .map(|seed| bent::judge(&bent::estimate(&frame, seed), &b, ramp))
                    .collect();
                if verdicts.iter().all(bent::Verdict::found) {
                    let mean = verdicts.iter().map(|v| v.error_deg.abs()).sum::<f64>()
                        / verdicts.len() as f64;
                    found.push((angle, mean));
                }
            }
            if let Some(reason) = refused {
                println!("| {sensor} | {name} | {hinge} | - | not bent: {reason} | - | - |");
                continue;
            }
            let bend = floor_bend.map_or("-".into(), |b| format!("{b:.2}"));
            let list = if found.is_empty() {
                "none".to_string()
            } else {
                found
                    .iter()
                    .map(|(a, _)| format!("{a}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let (smallest, error) = found.first().map_or(("> 8".into(), "-".into()), |(a, e)| {
                (format!("{a}"), format!("{e:.2}"))
            });
            println!("| {sensor} | {name} | {hinge} | {bend} | {list} | {smallest} | {error} |");
        }
    }
}

/// Every surface of `name` bent by `angle` at `hinge`, at each seed.
fn print_surfaces(name: &str, hinge: f64, angle: f64) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data")
        .join(name);
    let b = bent::bend(&dir, angle, hinge);
    println!(
        "{name} bent {angle} deg at {hinge} m: floor bend at the hinge {:?} deg",
        b.floor_bend_deg
    );
    let frame = bent::project(&b);
    let ramp = bent::ramp_normal(&b);
    let config = match std::env::var("CONFIG") {
        Ok(text) => EstimatorConfig::from_toml_str(&text).expect("CONFIG"),
        Err(_) => EstimatorConfig::default(),
    };
    for seed in SEEDS {
        let e = bent::estimate_with(config.clone(), &frame, seed);
        let v = bent::judge(&e, &b, ramp);
        println!(
            "seed {seed}: {} {:.2} deg, road {:?}, bent part {} (plane {:.2} deg off the ramp's, {:.3} m from the hinge line), error {:+.2} (the ramp's plane {:.2} deg from this ground)",
            e.status.name(),
            e.slope_deg,
            v.road_role.map(|r| r.name()),
            v.road_is_bent,
            v.plane_off_deg,
            v.at_hinge_m,
            v.error_deg,
            v.ramp_to_ground_deg
        );
        if let (Some(g), Some(i)) = (&e.ground, &e.inclined) {
            let n = |c: [f64; 4]| nalgebra::Vector3::new(c[0], c[1], c[2]);
            println!(
                "  the estimate's inclined plane is {:.2} deg from its ground plane",
                n(g.coefficients).angle(&n(i.coefficients)).to_degrees()
            );
        }
        print!("{}", bent::surfaces(&e));
    }
}
