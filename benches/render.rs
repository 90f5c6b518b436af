//! Rendering throughput of the three integrators on the bundled Cornell box
//! and caustic scene at 256 × 256 on two threads, in camera samples per
//! second (criterion's elements per second). Equal-time error against long
//! references comes from `benches/equal-time.sh`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::time::Duration;
use tracer::render::{render, RenderOptions};
use tracer::settings::IntegratorKind;

fn benches(c: &mut Criterion) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let options = RenderOptions {
        threads: Some(2),
        progress: false,
        ..RenderOptions::default()
    };
    for name in ["cornell-box", "cornell-caustics"] {
        let mut group = c.benchmark_group(format!("render/{name}"));
        group.sample_size(10);
        group.measurement_time(Duration::from_secs(8));
        for (integrator, label, spp) in [
            (IntegratorKind::Pt, "pt", 4),
            (IntegratorKind::Lt, "lt", 2),
            (IntegratorKind::Bdpt, "bdpt", 1),
            (IntegratorKind::Vcm, "vcm", 1),
        ] {
            let (scene, mut settings) =
                tracer::scene::load(&root.join(format!("scenes/{name}.json"))).unwrap();
            settings.film.width = 256;
            settings.film.height = 256;
            settings.integrator = integrator;
            settings.stop.spp = spp;
            group.throughput(Throughput::Elements(256 * 256 * spp as u64));
            group.bench_function(label, |b| {
                b.iter(|| render(&scene, &settings, &options).unwrap())
            });
        }
        group.finish();
    }
}

criterion_group!(render_benches, benches);
criterion_main!(render_benches);
