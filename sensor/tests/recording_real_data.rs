//! The real Kinect recordings in `shared/data` open, decode and project.
//! Each recording that is absent is skipped, with a note (a failure in CI:
//! `slope_test_support::shared_data`).

use slope_ipc_types::CloudPoint;
use slope_sensor::recording::Recording;

struct Expected {
    name: &'static str,
    sensor: &'static str,
    width: u32,
    height: u32,
    fx: f64,
    cx: f64,
    cy: f64,
    pitch_deg: Option<f64>,
    roll_deg: Option<f64>,
}

const RECORDINGS: [Expected; 3] = [
    Expected {
        name: "kinect1-office",
        sensor: "kinect1",
        width: 640,
        height: 480,
        fx: 525.0,
        cx: 320.0,
        cy: 240.0,
        pitch_deg: None,
        roll_deg: None,
    },
    Expected {
        name: "kinect2-stairs-front",
        sensor: "kinect2",
        width: 512,
        height: 424,
        fx: 365.32,
        cx: 256.31,
        cy: 208.55,
        pitch_deg: Some(-26.96),
        roll_deg: Some(-0.12),
    },
    Expected {
        name: "kinect2-stairs-top",
        sensor: "kinect2",
        width: 512,
        height: 424,
        fx: 365.32,
        cx: 256.31,
        cy: 208.55,
        pitch_deg: Some(-76.39),
        roll_deg: Some(-16.881),
    },
];

#[test]
fn real_recordings_open_decode_and_project() {
    for expected in &RECORDINGS {
        let Some(dir) = slope_test_support::shared_data(expected.name) else {
            continue;
        };
        let rec = Recording::open(&dir).unwrap_or_else(|e| panic!("{e}"));
        let meta = rec.meta();
        assert_eq!(meta.sensor, expected.sensor);
        assert_eq!(
            (meta.depth.width, meta.depth.height),
            (expected.width, expected.height)
        );
        assert_eq!(meta.depth.unit_m, 0.001);
        let intr = rec.intrinsics();
        assert_eq!(
            (intr.fx, intr.fy, intr.cx, intr.cy),
            (expected.fx, expected.fx, expected.cx, expected.cy)
        );
        assert_eq!(meta.mount.pitch_deg, expected.pitch_deg);
        assert_eq!(meta.mount.roll_deg, expected.roll_deg);
        assert_eq!(meta.truth.slope_deg, Some(90.0));
        assert_eq!(rec.frames().len(), 1);
        let frame = &rec.frames()[0];
        assert_eq!(rec.truth_deg(frame), Some(90.0));
        assert_eq!(rec.read_color(frame).unwrap(), None);

        let depth = rec.read_depth(frame).unwrap_or_else(|e| panic!("{e}"));
        let n = (expected.width * expected.height) as usize;
        assert_eq!(depth.data.len(), n);
        let mut valid: Vec<u16> = depth.data.iter().copied().filter(|&d| d > 0).collect();
        valid.sort_unstable();
        // Indoor scenes: most pixels read, at 0.5-8 m.
        assert!(
            valid.len() > n / 2,
            "{}: {} of {n} valid",
            expected.name,
            valid.len()
        );
        let median = valid[valid.len() / 2];
        assert!(
            (500..8000).contains(&median),
            "{}: median {median} mm",
            expected.name
        );

        let projector = rec.projector();
        let mut cloud = vec![CloudPoint::INVALID; n];
        projector.project_into(&depth.data, None, &mut cloud);
        assert_eq!(cloud.iter().filter(|p| p.is_valid()).count(), valid.len());
        // Spot-check the pinhole formula at the corners and the centre.
        let (w, h) = (expected.width, expected.height);
        for (u, v) in [
            (0, 0),
            (w - 1, 0),
            (0, h - 1),
            (w - 1, h - 1),
            (w / 2, h / 2),
        ] {
            let i = (v * w + u) as usize;
            let raw = depth.data[i];
            let p = cloud[i];
            if raw == 0 {
                assert!(!p.is_valid());
                continue;
            }
            let z = f64::from(raw) * 0.001;
            let x = (f64::from(u) - intr.cx) * z / intr.fx;
            let y = (f64::from(v) - intr.cy) * z / intr.fy;
            assert!((f64::from(p.z_m) - z).abs() < 1e-6, "z {} vs {z}", p.z_m);
            assert!((f64::from(p.x_m) - x).abs() < 1e-5, "x {} vs {x}", p.x_m);
            assert!((f64::from(p.y_m) - y).abs() < 1e-5, "y {} vs {y}", p.y_m);
        }
    }
}
