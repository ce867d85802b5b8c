//! Projection of one full 512 x 424 Kinect v2 depth frame (into the loaned
//! shared-memory sample it must take at most 0.5 ms).
//!
//! Frames: `stairs`, the real Kinect v2 frame in
//! `../shared/data/kinect2-stairs-front` (depth only; skipped when `../shared`
//! is absent), and `ramp16`, the bundled simulated recording, which has
//! colour (as `slope-capture` with colour on).
//!
//! - `project_into_vec`: [`Projector::project_into`] into a `Vec`.
//! - `project_into_loaned`: the same into a loaned, uninitialised iceoryx2
//!   sample: what [`CloudPublisher::publish`] does.
//! - `point_per_pixel_loaned`: the former publisher path for comparison,
//!   `write_from_fn` with [`Projector::point`] per pixel index.
//! - `publish`: all of [`CloudPublisher::publish`]: loan, project, send,
//!   notify (no subscriber is connected, so nothing is delivered).
//!
//! Run: `cargo bench -p slope-sensor --bench projection`.

use std::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{criterion_group, criterion_main, Criterion};
use iceoryx2::prelude::*;
use slope_ipc_types::{CloudPoint, ServiceNames, DEFAULT_MAX_CLOUD_POINTS};
use slope_sensor::ipc::{create_node, CloudPublisher};
use slope_sensor::recording::Recording;
use slope_sensor::source::{FrameSource, RecordingSource, SourceFrame};

/// The recordings present, by short name, with their first frame.
fn frames() -> Vec<(&'static str, RecordingSource, SourceFrame)> {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dirs: [(&str, PathBuf); 2] = [
        (
            "stairs",
            manifest.join("../../shared/data/kinect2-stairs-front"),
        ),
        ("ramp16", manifest.join("../tests/recordings/ramp16")),
    ];
    dirs.into_iter()
        .filter(|(_, dir)| dir.is_dir())
        .map(|(name, dir)| {
            let recording = Recording::open(&dir).expect("the bench recording opens");
            let mut source = RecordingSource::new(recording, false);
            let mut frame = SourceFrame::default();
            assert!(source
                .next_frame(&mut frame)
                .expect("the first frame reads"));
            (name, source, frame)
        })
        .collect()
}

fn projection(c: &mut Criterion) {
    // Unique names: never a running stack's services.
    let prefix = format!("slope-bench-projection-{}", std::process::id());
    let node = create_node(&prefix).expect("node");
    for (name, source, frame) in frames() {
        let info = source.info().clone();
        let projector = source.recording().projector();
        let depth = &frame.depth.data;
        let color = frame.color.as_ref().map(|c| c.data.as_slice());
        let points = projector.len();
        eprintln!(
            "{name}: {} x {}, colour {}",
            info.width,
            info.height,
            color.is_some()
        );

        let mut cloud = vec![CloudPoint::default(); points];
        c.bench_function(&format!("project_into_vec/{name}"), |b| {
            b.iter(|| projector.project_into(black_box(depth), color, &mut cloud))
        });

        // A plain publisher for the raw loan: CloudPublisher keeps its port.
        let service = node
            .service_builder(&ServiceName::new(&format!("{prefix}/{name}-raw")).expect("name"))
            .publish_subscribe::<[CloudPoint]>()
            .open_or_create()
            .expect("service");
        let publisher = service
            .publisher_builder()
            .initial_max_slice_len(points)
            .create()
            .expect("publisher");
        c.bench_function(&format!("project_into_loaned/{name}"), |b| {
            b.iter(|| {
                let mut sample = publisher.loan_slice_uninit(points).expect("loan");
                projector.project_into(black_box(depth), color, sample.payload_mut());
                // Dropped unsent: the chunk goes back to the pool.
                black_box(sample)
            })
        });
        c.bench_function(&format!("point_per_pixel_loaned/{name}"), |b| {
            b.iter(|| {
                let sample = publisher.loan_slice_uninit(points).expect("loan");
                let depth = black_box(depth);
                black_box(sample.write_from_fn(|i| {
                    let rgb = color.map_or(0, |c| {
                        let [r, g, b] = c[i];
                        CloudPoint::pack_rgb(r, g, b)
                    });
                    projector.point(i, depth[i], rgb)
                }))
            })
        });

        let names = ServiceNames::new(format!("{prefix}/{name}"));
        let cloud_publisher =
            CloudPublisher::create(&node, &names, &info, DEFAULT_MAX_CLOUD_POINTS)
                .expect("cloud publisher");
        c.bench_function(&format!("publish/{name}"), |b| {
            b.iter(|| cloud_publisher.publish(black_box(&frame)).expect("publish"))
        });
    }
}

criterion_group!(benches, projection);
criterion_main!(benches);
