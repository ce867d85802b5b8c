//! How long one simulated Kinect v2 frame takes: the exact ray cast, the
//! full sensor model on top, and the shading of the colour image.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use slope_synth::{
    frame_camera, frame_rng, raycast, render_depth, shading::shade, Scene, SensorModel, World,
};

fn bench_render(c: &mut Criterion) {
    let scene = Scene::default_ramp();
    let world = World::build(&scene);
    let model = SensorModel::default();
    let camera = frame_camera(&scene, &model, 0, &mut frame_rng(7, 0));
    let geometry = raycast(&world, &camera);

    c.bench_function("raycast 512x424 default ramp", |b| {
        b.iter(|| raycast(black_box(&world), black_box(&camera)))
    });
    c.bench_function("sensor model 512x424 default ramp", |b| {
        let mut rng = frame_rng(7, 0);
        b.iter(|| render_depth(black_box(&geometry), &world, &model, &camera, &mut rng))
    });
    c.bench_function("shade 512x424", |b| b.iter(|| shade(black_box(&geometry))));
}

criterion_group!(benches, bench_render);
criterion_main!(benches);
