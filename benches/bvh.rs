//! BVH build and traversal, side by side with the `obvhs` crate (CWBVH,
//! `fast_build` preset, its closure-based `ray_traverse`/`ray_traverse_miss`)
//! on identical triangles and identical rays, one thread.
//!
//! Meshes: a displaced icosphere of 1.3 M triangles and a city of random
//! boxes (always), and the bunny, dragon and Sponza from `../shared/meshes`
//! when that folder is present. Rays: the `tracer bench` sets (primary from a
//! camera framing the mesh, incoherent in the bounds, shadow rays from
//! primary hits). Set `TRACER_BENCH_MESHES=bunny,city` to pick meshes.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3A;
use std::hint::black_box;
use std::time::Duration;
use tracer::bench::{meshes, rays};
use tracer::bvh::{BuildOptions, WideBvh};
use tracer::geometry::{Ray, Triangle};

fn shared_mesh(name: &str) -> Option<Vec<Triangle>> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/meshes")
        .join(format!("{name}.obj"));
    if !path.exists() {
        eprintln!("{} not found: skipping {name}", path.display());
        return None;
    }
    Some(meshes::obj_triangles(&path).expect("a readable mesh"))
}

fn obvhs_triangles(tris: &[Triangle]) -> Vec<obvhs::triangle::Triangle> {
    tris.iter()
        .map(|t| obvhs::triangle::Triangle {
            v0: Vec3A::from(t.v[0]),
            v1: Vec3A::from(t.v[1]),
            v2: Vec3A::from(t.v[2]),
        })
        .collect()
}

fn obvhs_ray(r: &Ray) -> obvhs::ray::Ray {
    obvhs::ray::Ray::new(Vec3A::from(r.origin), Vec3A::from(r.dir), r.tmin, r.tmax)
}

/// BVH build: ours on one thread and two, obvhs's fast build.
fn bench_build(
    group: &mut criterion::BenchmarkGroup<criterion::measurement::WallTime>,
    tris: &[Triangle],
) {
    let sequential = BuildOptions {
        parallel: false,
        ..BuildOptions::default()
    };
    group.bench_function("build/tracer_1_thread", |b| {
        b.iter(|| WideBvh::build_with(black_box(tris), &sequential))
    });
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    group.bench_function("build/tracer_2_threads", |b| {
        b.iter(|| two.install(|| WideBvh::build(black_box(tris))))
    });
    let otris = obvhs_triangles(tris);
    let params = obvhs::BvhBuildParams::fast_build();
    group.bench_function("build/obvhs_cwbvh_fast_build", |b| {
        b.iter(|| {
            obvhs::cwbvh::builder::build_cwbvh_from_tris(
                black_box(&otris),
                params,
                &mut Duration::default(),
            )
        })
    });
}

fn bench_mesh(c: &mut Criterion, name: &str, tris: &[Triangle]) {
    let mut group = c.benchmark_group(format!("bvh/{name}"));
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(5));

    bench_build(&mut group, tris);
    let otris = obvhs_triangles(tris);
    let params = obvhs::BvhBuildParams::fast_build();
    let bvh = WideBvh::build(tris);
    let cwbvh =
        obvhs::cwbvh::builder::build_cwbvh_from_tris(&otris, params, &mut Duration::default());
    // obvhs reports primitives by its own order: reorder once, as its examples do.
    let ordered: Vec<obvhs::triangle::Triangle> = cwbvh
        .primitive_indices
        .iter()
        .map(|&i| otris[i as usize])
        .collect();
    eprintln!(
        "{name}: {} triangles; tracer SAH {:.2} (binary {:.2}), {:.1} bytes/triangle",
        tris.len(),
        bvh.report().sah_cost,
        bvh.report().binary_sah_cost,
        bvh.memory_bytes() as f64 / tris.len() as f64
    );

    let bounds = bvh.bounds();
    let primary = rays::primary(&rays::framing_camera(bounds));
    let hits = rays::hit_points(&bvh, tris, &primary);
    let sets = [
        ("primary", primary.clone()),
        ("incoherent", rays::incoherent(bounds, 1 << 19)),
        ("shadow", rays::shadow(&hits, bounds)),
    ];
    for (kind, set) in &sets {
        let orays: Vec<obvhs::ray::Ray> = set.iter().map(obvhs_ray).collect();
        // Same rays, same answers (up to ties and obvhs's own epsilons).
        let ours = set.iter().filter(|r| bvh.intersect(r).is_some()).count();
        let theirs = orays
            .iter()
            .filter(|r| {
                let mut hit = obvhs::ray::RayHit::none();
                cwbvh.ray_traverse(**r, &mut hit, |r, id| ordered[id].intersect(r))
            })
            .count();
        eprintln!(
            "{name}/{kind}: {} rays, tracer {ours} hits, obvhs {theirs} hits",
            set.len()
        );
        group.throughput(Throughput::Elements(set.len() as u64));
        group.bench_function(BenchmarkId::new(format!("{kind}/closest"), "tracer"), |b| {
            b.iter(|| set.iter().filter(|r| bvh.intersect(r).is_some()).count())
        });
        group.bench_function(BenchmarkId::new(format!("{kind}/closest"), "obvhs"), |b| {
            b.iter(|| {
                orays
                    .iter()
                    .filter(|r| {
                        let mut hit = obvhs::ray::RayHit::none();
                        cwbvh.ray_traverse(**r, &mut hit, |r, id| ordered[id].intersect(r))
                    })
                    .count()
            })
        });
        group.bench_function(BenchmarkId::new(format!("{kind}/any"), "tracer"), |b| {
            b.iter(|| set.iter().filter(|r| bvh.occluded(r)).count())
        });
        group.bench_function(BenchmarkId::new(format!("{kind}/any"), "obvhs"), |b| {
            b.iter(|| {
                orays
                    .iter()
                    .filter(|r| !cwbvh.ray_traverse_miss(**r, |r, id| ordered[id].intersect(r)))
                    .count()
            })
        });
    }
    group.finish();
}

fn benches(c: &mut Criterion) {
    let only = std::env::var("TRACER_BENCH_MESHES").ok();
    let wanted = |name: &str| {
        only.as_deref()
            .is_none_or(|o| o.split(',').any(|n| n == name))
    };
    if wanted("sphere") {
        bench_mesh(c, "sphere", &meshes::displaced_sphere(8));
    }
    if wanted("city") {
        bench_mesh(c, "city", &meshes::city(160));
    }
    for name in ["bunny", "dragon", "sponza"] {
        if wanted(name) {
            if let Some(tris) = shared_mesh(name) {
                bench_mesh(c, name, &tris);
            }
        }
    }
}

criterion_group!(bvh_benches, benches);
criterion_main!(bvh_benches);
