//! Fuzzing the cloud-header checks (property tests, in the default test
//! run): any header and payload length gives Ok or an error, never a panic,
//! and Ok only for what the rules allow, written out here again as an
//! independent oracle. `SLOPE_FUZZ_CASES=N` runs N cases per property.

use proptest::prelude::*;
use proptest::test_runner::Config;
use slope_ipc_types::{CloudHeader, Intrinsics, Mount};
use slope_sensor::cloud_checks::{check_cloud, CloudCheckError};

fn config(default: u32) -> Config {
    let cases = std::env::var("SLOPE_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(default);
    Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    }
}

/// Numbers as a hostile publisher sends them: ordinary, special, extreme.
fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        -2000.0..2000.0f64,
        prop::sample::select(vec![
            0.0,
            -0.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            5e-324,
            1e-300,
            1e300,
            1e308,
            f64::MAX,
            f64::MIN,
            90.0,
            -90.0,
            180.0,
            10.0,
        ]),
        any::<f64>(),
    ]
}

fn size() -> impl Strategy<Value = u32> {
    prop_oneof![0u32..700, Just(u32::MAX), any::<u32>()]
}

fn header() -> impl Strategy<Value = CloudHeader> {
    (
        size(),
        size(),
        [number(), number(), number(), number()],
        [number(), number(), number()],
    )
        .prop_map(|(width, height, [fx, fy, cx, cy], [h, p, r])| CloudHeader {
            width,
            height,
            intrinsics: Intrinsics { fx, fy, cx, cy },
            mount: Mount {
                height_m: h,
                pitch_deg: p,
                roll_deg: r,
            },
            ..CloudHeader::default()
        })
}

/// The rules of `cloud_checks.rs`, stated again.
fn allowed(h: &CloudHeader, points: usize, max_points: usize) -> bool {
    let (w, ht) = (f64::from(h.width), f64::from(h.height));
    let n = u64::from(h.width) * u64::from(h.height);
    let k = h.intrinsics;
    let focal = |f: f64| (1.0..=1e5).contains(&f);
    let mount_ok = |v: f64, low: f64, high: f64, open_low: bool| {
        v.is_nan() || (v <= high && if open_low { v > low } else { v >= low })
    };
    n > 0
        && n <= max_points as u64
        && n == points as u64
        && focal(k.fx)
        && focal(k.fy)
        && (-w..=2.0 * w).contains(&k.cx)
        && (-ht..=2.0 * ht).contains(&k.cy)
        && mount_ok(h.mount.height_m, 0.0, 10.0, true)
        && mount_ok(h.mount.pitch_deg, -90.0, 90.0, false)
        && mount_ok(h.mount.roll_deg, -180.0, 180.0, false)
}

proptest! {
    #![proptest_config(config(2048))]

    #[test]
    fn any_header_is_judged_by_the_rules(
        header in header(),
        matching in any::<bool>(),
        points in 0usize..1_000_000,
        max_points in prop_oneof![Just(1usize << 20), 1usize..100_000, Just(usize::MAX)],
    ) {
        let points = if matching { header.point_count() } else { points };
        let verdict = check_cloud(&header, points, max_points);
        prop_assert_eq!(verdict.is_ok(), allowed(&header, points, max_points), "{:?}", verdict);
        if let Err(err) = verdict {
            // Every refusal says what is wrong in one line.
            let text = err.to_string();
            prop_assert!(!text.is_empty() && !text.contains('\n'));
            if let CloudCheckError::Intrinsics(o) | CloudCheckError::Mount(o) = &err {
                prop_assert!(text.contains(o.key));
            }
        }
    }
}
