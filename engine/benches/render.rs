//! Camera render-and-readback throughput at 320 × 240, colour plus depth (issue 6: at least
//! 500 frames/s on lavapipe). Criterion reports frames per second as `elem/s`.
//!
//! - `one_frame`: one view, one submission and wait per frame (a single simulation).
//! - `batch_8`: eight views in one submission (eight cameras or eight tests).
//! - `workers_2x8`: two threads, each rendering batches of eight through the shared device
//!   (what a campaign's rayon workers do).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use paracosm_engine::network::Network;
use paracosm_engine::render::{CameraPose, RenderJob, RenderObject, Renderer, SceneGeometry, View};
use paracosm_engine::CameraSpec;
use paracosm_engine::Size;

fn objects() -> Vec<RenderObject> {
    vec![
        RenderObject {
            base_m: [40.0, 0.0, 1.75],
            size: Size {
                length_m: 4.5,
                width_m: 1.9,
                height_m: 1.7,
            },
            heading_rad: 0.0,
            albedo: [0.92, 0.92, 0.92],
            class: paracosm_engine::SemanticClass::Car,
            actor: 0,
        },
        RenderObject {
            base_m: [30.0, 0.15, 5.0],
            size: Size {
                length_m: 0.5,
                width_m: 0.5,
                height_m: 1.8,
            },
            heading_rad: 0.0,
            albedo: [0.75, 0.22, 0.18],
            class: paracosm_engine::SemanticClass::Pedestrian,
            actor: 0,
        },
    ]
}

/// Frame `i` of a drive down the road.
fn job<'a>(
    scene: &'a SceneGeometry,
    objects: &'a [RenderObject],
    view: &'a mut View,
    i: usize,
) -> RenderJob<'a> {
    RenderJob {
        scene,
        view,
        pose: CameraPose {
            chassis_m: [10.0 + i as f64 * 0.1, 0.5, 1.75],
            heading_rad: 0.0,
        },
        objects,
        light: 0.5,
        fog: 0.1,
        t_s: 0.0,
        noise_seed: 0,
    }
}

fn bench(c: &mut Criterion) {
    let renderer = Renderer::shared().expect("a GPU adapter (lavapipe: mesa-vulkan-drivers)");
    eprintln!("adapter: {}", renderer.adapter());
    let network = Network::single_segment(300.0, 4, 1.0).unwrap();
    let scene = renderer.scene(&network);
    let camera = CameraSpec::default();
    let objects = objects();
    let (scene, objects) = (&scene, &objects[..]);
    let mut group = c.benchmark_group("render_320x240_rgb_depth");
    group.sample_size(20);

    let mut view = renderer.view(&camera).unwrap();
    group.throughput(Throughput::Elements(1));
    group.bench_function("one_frame", |b| {
        b.iter(|| {
            renderer
                .render_one(job(scene, objects, &mut view, 0))
                .unwrap()
        })
    });

    let mut views: Vec<_> = (0..8).map(|_| renderer.view(&camera).unwrap()).collect();
    group.throughput(Throughput::Elements(8));
    group.bench_function("batch_8", |b| {
        b.iter(|| {
            let mut jobs: Vec<_> = views
                .iter_mut()
                .enumerate()
                .map(|(i, v)| job(scene, objects, v, i))
                .collect();
            renderer.render(&mut jobs).unwrap()
        })
    });

    let mut per_worker: Vec<Vec<_>> = (0..2)
        .map(|_| (0..8).map(|_| renderer.view(&camera).unwrap()).collect())
        .collect();
    group.throughput(Throughput::Elements(16));
    group.bench_function("workers_2x8", |b| {
        b.iter(|| {
            std::thread::scope(|s| {
                for views in per_worker.iter_mut() {
                    let renderer = &renderer;
                    s.spawn(move || {
                        let mut jobs: Vec<_> = views
                            .iter_mut()
                            .enumerate()
                            .map(|(i, v)| job(scene, objects, v, i))
                            .collect();
                        renderer.render(&mut jobs).unwrap()
                    });
                }
            })
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
