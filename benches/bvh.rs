//! BVH build and closest-hit traversal on a generated mesh (always) and the
//! Stanford bunny (when `../shared/meshes` is present).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use std::hint::black_box;
use tracer::bvh::Bvh;
use tracer::geometry::shapes;
use tracer::geometry::{Ray, Triangle};

fn triangles_of(mesh: &shapes::MeshData) -> Vec<Triangle> {
    mesh.indices
        .chunks(3)
        .map(|f| {
            Triangle::new(
                mesh.positions[f[0] as usize],
                mesh.positions[f[1] as usize],
                mesh.positions[f[2] as usize],
            )
        })
        .collect()
}

fn bunny() -> Option<Vec<Triangle>> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes/bunny.obj");
    let obj = tracer::scene::obj::load_obj(&path, None).ok()?;
    Some(
        obj.groups
            .iter()
            .flat_map(|g| triangles_of(&g.mesh))
            .collect(),
    )
}

/// Rays from points around the mesh's bounds towards random points inside it:
/// incoherent, mostly hitting.
fn rays(tris: &[Triangle], n: usize) -> Vec<Ray> {
    let bounds = tris.iter().fold(tracer::geometry::Aabb::EMPTY, |b, t| {
        b.union(tracer::geometry::Aabb::from_points(&t.v))
    });
    let (c, r) = bounds.bounding_sphere();
    let mut state = 12345u32;
    let mut next = || {
        state = tracer::sampling::sampler::hash(state);
        state as f32 / u32::MAX as f32
    };
    (0..n)
        .map(|_| {
            let o = c + r * 1.5 * tracer::sampling::warp::uniform_sphere(next(), next());
            let target = c + 0.5 * r * Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5);
            Ray::new(o, (target - o).normalize())
        })
        .collect()
}

fn bench_mesh(c: &mut Criterion, name: &str, tris: &[Triangle]) {
    let mut group = c.benchmark_group(format!("bvh/{name}"));
    group.sample_size(10);
    group.bench_function("build", |b| b.iter(|| Bvh::build(black_box(tris))));
    let bvh = Bvh::build(tris);
    let rays = rays(tris, 100_000);
    group.throughput(Throughput::Elements(rays.len() as u64));
    group.bench_function("closest_hit", |b| {
        b.iter(|| rays.iter().filter(|r| bvh.intersect(r).is_some()).count())
    });
    group.bench_function("any_hit", |b| {
        b.iter(|| rays.iter().filter(|r| bvh.occluded(r)).count())
    });
    group.finish();
}

fn benches(c: &mut Criterion) {
    let sphere = triangles_of(&shapes::sphere(Vec3::ZERO, 1.0, 7));
    bench_mesh(c, "sphere327k", &sphere);
    if let Some(bunny) = bunny() {
        bench_mesh(c, "bunny", &bunny);
    } else {
        eprintln!("../shared/meshes not found: skipping the bunny");
    }
}

criterion_group!(bvh, benches);
criterion_main!(bvh);
