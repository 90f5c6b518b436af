//! Path tracing throughput on the bundled scenes, in camera samples per second.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use tracer::render::{render, RenderOptions};

fn benches(c: &mut Criterion) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut group = c.benchmark_group("render/pt");
    group.sample_size(10);
    for name in ["cornell-box", "cornell-caustics"] {
        let mut scene = tracer::scene::load(&root.join(format!("scenes/{name}.json"))).unwrap();
        scene.set_resolution(128, 128);
        scene.settings.spp = 4;
        group.throughput(Throughput::Elements(128 * 128 * 4));
        group.bench_function(name, |b| {
            b.iter(|| render(&scene, &RenderOptions::default()).unwrap())
        });
    }
    group.finish();
}

criterion_group!(render_benches, benches);
criterion_main!(render_benches);
