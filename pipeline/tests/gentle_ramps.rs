//! Real floors bent into ramps of known angle (issue #44): the frames of
//! `shared/data` whose floor reaches past a hinge with ground before it
//! (`bent::QUALIFYING`), bent at 4, 5, 8, 12, 16, 25 and 40 degrees (40:
//! a wall) by `slope_synth::bend`, each run with the default config for its
//! sensor at seeds 0-2, and judged against the bend's exact truth: status
//! ok with the bent part as the road (rising, its plane within 5 degrees of
//! the ramp's and 0.1 m of the hinge line), |slope| - truth.
//!
//! The issue's bar: ok with the bent part as the road in at least 95 % of
//! frames, mean error at most 0.4 degrees. It is not met today:
//! `issue_44_bar_on_every_bent_floor` asserts it and is ignored until the
//! selection's rules meet it (`cargo test --release -p slope-pipeline --test
//! gentle_ramps -- --ignored --nocapture` prints the table and every
//! surface of each failing frame). `bar_where_met_today` asserts the bar
//! where it holds today, so that those cases stay met.
//!
//! Left out of the bar, with their reason:
//! - `kinect2-stairs-front`: its first riser stands 0.5 m ahead, nearer
//!   than any hinge with floor before it, and the floor beyond the hinge
//!   lies beside the staircase (0.8-1.6 m to the right), outside the
//!   robot's corridor: the road is rightly the riser, never the bent part.
//! - From the mean error (held to truth ± their floor's bend + 0.4
//!   instead): frames whose floor is more than [`FLAT_FLOOR_DEG`] from flat
//!   at the hinge before bending (`BentFrame::floor_bend_deg`: the CAPE
//!   tunnel 1.9, the stairs 2.7): the ramp is that far floor turned by the
//!   truth, so its angle to the near floor is uncertain by that much.
//!
//! Skipped with a note when the data is absent; CI sets
//! SLOPE_REQUIRE_SHARED_DATA, which turns the skip into a failure.

mod common;

#[path = "common/bent.rs"]
mod bent;

use std::sync::OnceLock;

const ANGLES_DEG: [f64; 7] = [4.0, 5.0, 8.0, 12.0, 16.0, 25.0, 40.0];
const SEEDS: std::ops::Range<u64> = 0..3;

/// The issue's bar.
const MIN_FOUND_SHARE: f64 = 0.95;
const MAX_MEAN_ERROR_DEG: f64 = 0.4;

/// Frames whose road can never be the bent part (module documentation).
const NOT_A_RAMP_AHEAD: [&str; 1] = ["kinect2-stairs-front"];

/// A floor more than this from flat at the hinge (before bending) leaves
/// its frame out of the mean error, degrees: the cleanest floors are
/// 0.3-1.0 from flat there (the mine tunnel 0.45, NYU 0.35, the corridor
/// 0.46, TUM 0.96, the Kinect v1 office 0.31), CAPE 1.93 and the stairs
/// 2.74.
const FLAT_FLOOR_DEG: f64 = 1.5;

/// One bent frame and the verdicts of its seeds.
struct Row {
    name: &'static str,
    hinge_m: f64,
    angle_deg: f64,
    floor_bend_deg: Option<f64>,
    verdicts: Vec<bent::Verdict>,
    /// Every surface of each seed whose road is not the bent part.
    failures: Vec<(u64, String)>,
}

impl Row {
    fn found_everywhere(&self) -> bool {
        self.verdicts.iter().all(bent::Verdict::found)
    }

    /// Its floor is flat enough at the hinge for the 0.4 degree bar.
    fn flat_floor(&self) -> bool {
        self.floor_bend_deg.is_some_and(|b| b <= FLAT_FLOOR_DEG)
    }

    fn in_bar(&self) -> bool {
        !NOT_A_RAMP_AHEAD.contains(&self.name)
    }
}

/// Every qualifying frame bent at every angle and estimated at every
/// seed, once for all tests (`None` when the data is absent).
fn table() -> Option<&'static [Row]> {
    static TABLE: OnceLock<Option<Vec<Row>>> = OnceLock::new();
    TABLE.get_or_init(measure).as_deref()
}

fn measure() -> Option<Vec<Row>> {
    let mut rows = Vec::new();
    for (name, hinge_m) in bent::QUALIFYING {
        let dir = common::shared_data(name)?;
        for angle_deg in ANGLES_DEG {
            let b = bent::bend(&dir, angle_deg, hinge_m);
            assert_eq!(b.truth_deg, angle_deg, "{name}");
            let frame = bent::project(&b);
            let ramp = bent::ramp_normal(&b);
            let mut verdicts = Vec::new();
            let mut failures = Vec::new();
            for seed in SEEDS {
                let e = bent::estimate(&frame, seed);
                let v = bent::judge(&e, &b, ramp);
                if !v.found() {
                    failures.push((seed, bent::surfaces(&e)));
                }
                verdicts.push(v);
            }
            rows.push(Row {
                name,
                hinge_m,
                angle_deg,
                floor_bend_deg: b.floor_bend_deg,
                verdicts,
                failures,
            });
        }
    }
    print_table(&rows);
    Some(rows)
}

fn print_table(rows: &[Row]) {
    println!(
        "| frame | hinge (m) | floor bend (deg) | angle (deg) | seed | status | road | bent part | \
         plane off (deg) | from hinge line (m) | road starts (m past hinge) | error (deg) | \
         ramp to ground (deg) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        for (seed, v) in SEEDS.zip(&r.verdicts) {
            println!(
                "| {} | {} | {} | {} | {seed} | {} | {} | {} | {:.2} | {:.3} | {:+.2} | {:+.2} | {:.2} |",
                r.name,
                r.hinge_m,
                r.floor_bend_deg.map_or("-".into(), |b| format!("{b:.2}")),
                r.angle_deg,
                v.status.name(),
                v.road_role.map_or("none", |role| role.name()),
                if v.road_is_bent { "yes" } else { "no" },
                v.plane_off_deg,
                v.at_hinge_m,
                v.start_from_hinge_m,
                v.error_deg,
                v.ramp_to_ground_deg,
            );
        }
    }
}

fn print_failures(rows: &[Row]) {
    for r in rows.iter().filter(|r| r.in_bar()) {
        for (seed, surfaces) in &r.failures {
            println!(
                "{} bent {} deg at {} m, seed {seed}: not the bent part as the road\n{surfaces}",
                r.name, r.angle_deg, r.hinge_m
            );
        }
    }
}

/// Every qualifying frame bends at every angle (else `bent::bend` fails),
/// and the table is printed (`-- --nocapture`).
#[test]
fn every_qualifying_floor_bends_and_is_estimated() {
    let Some(rows) = table() else {
        return;
    };
    assert_eq!(rows.len(), bent::QUALIFYING.len() * ANGLES_DEG.len());
    assert!(rows
        .iter()
        .all(|r| r.verdicts.len() == SEEDS.count() && r.floor_bend_deg.is_some()));
}

/// The bar where it holds today, so that it stays met: TUM's office floor
/// at 8 and 12 degrees (found at every seed, mean error within 0.4), the
/// corridor at 40 (a wall), and the CAPE tunnel at 8-25 within its
/// floor's own bend at the hinge plus 0.4 (a floor 1.9 degrees from flat:
/// the truth is uncertain by that much).
#[test]
fn bar_where_met_today() {
    let Some(rows) = table() else {
        return;
    };
    let cases: [(&str, &[f64]); 3] = [
        ("tum-office-desk", &[8.0, 12.0]),
        ("pcl-corridor-people", &[40.0]),
        ("cape-foot-tunnel", &[8.0, 12.0, 16.0, 25.0]),
    ];
    for (name, angles) in cases {
        for r in rows
            .iter()
            .filter(|r| r.name == name && angles.contains(&r.angle_deg))
        {
            let what = format!("{name} bent {} deg at {} m", r.angle_deg, r.hinge_m);
            assert!(
                r.found_everywhere(),
                "{what}: {:?}\n{}",
                r.verdicts,
                r.failures
                    .iter()
                    .map(|(seed, s)| format!("seed {seed}\n{s}"))
                    .collect::<String>()
            );
            let errors: Vec<f64> = r.verdicts.iter().map(|v| v.error_deg.abs()).collect();
            let mean = errors.iter().sum::<f64>() / errors.len() as f64;
            if r.flat_floor() {
                assert!(mean <= MAX_MEAN_ERROR_DEG, "{what}: errors {errors:?}");
            } else {
                let bound = r.floor_bend_deg.unwrap_or(0.0) + MAX_MEAN_ERROR_DEG;
                assert!(
                    errors.iter().all(|&e| e <= bound),
                    "{what}: errors {errors:?}, floor bend {:?}",
                    r.floor_bend_deg
                );
            }
        }
    }
}

/// The issue's bar on every bent floor but the stairs (module
/// documentation): ok with the bent part as the road in at least 95 % of
/// frames and seeds, mean |error| at most 0.4 over those found on floors
/// flat at the hinge. Not met today (the pipeline README's "Real sensors"
/// and the table this prints say where and why).
#[test]
#[ignore = "issue #44: not met today; run with --ignored --nocapture for the table and the failing frames' surfaces"]
fn issue_44_bar_on_every_bent_floor() {
    let Some(rows) = table() else {
        return;
    };
    print_failures(rows);
    let runs: Vec<(&Row, &bent::Verdict)> = rows
        .iter()
        .filter(|r| r.in_bar())
        .flat_map(|r| r.verdicts.iter().map(move |v| (r, v)))
        .collect();
    let found = runs.iter().filter(|(_, v)| v.found()).count();
    let errors: Vec<f64> = runs
        .iter()
        .filter(|(r, v)| v.found() && r.flat_floor())
        .map(|(_, v)| v.error_deg.abs())
        .collect();
    let mean = errors.iter().sum::<f64>() / errors.len().max(1) as f64;
    println!(
        "found {found} of {} (bar {:.0} %), mean |error| {mean:.2} deg over {} on flat floors (bar {MAX_MEAN_ERROR_DEG})",
        runs.len(),
        100.0 * MIN_FOUND_SHARE,
        errors.len()
    );
    assert!(
        found as f64 >= MIN_FOUND_SHARE * runs.len() as f64,
        "found {found} of {}",
        runs.len()
    );
    assert!(mean <= MAX_MEAN_ERROR_DEG, "mean |error| {mean:.2}");
}
