//! Time from start to the first traced ray, with and without the scene
//! cache: for a scene referencing a generated 1.3 M-triangle OBJ (always)
//! and the Stanford dragon (when `../shared/meshes` is present).
//!
//! - `no-cache`: parse the scene and mesh, build the BVH, trace one ray;
//! - `cold`: the same with an empty cache, plus storing the entry;
//! - `warm`: key, map and check the entry, trace one ray;
//! - `load`: the entry lookup alone, in bytes per second (criterion's
//!   throughput), which is the cache's load throughput;
//! - `copy-instead`: what reading the entry into fresh memory and
//!   checksumming it would cost, the design the map was chosen over.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;
use tracer::bvh::BuildOptions;
use tracer::format::read_scene;
use tracer::geometry::shapes;
use tracer::scene::cache::{scene_key, Cache};
use tracer::scene::{build, Scene};

/// A displaced icosphere of 20 · 4^8 = 1,310,720 triangles as OBJ, with
/// vertices shared between faces as a scanned mesh has them.
fn write_generated_obj(path: &Path) {
    let mesh = shapes::sphere(glam::Vec3::ZERO, 1.0, 8);
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    for p in &mesh.positions {
        let bumps = (7.0 * p.x).sin() * (5.0 * p.y).cos() * 0.08 + (23.0 * p.z).sin() * 0.02;
        let q = *p * (1.0 + bumps);
        writeln!(out, "v {} {} {}", q.x, q.y, q.z).unwrap();
    }
    for f in mesh.indices.chunks_exact(3) {
        writeln!(out, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1).unwrap();
    }
}

fn write_scene(dir: &Path, mesh: &Path) -> PathBuf {
    let scene = format!(
        r#"{{
          "format": 1,
          "camera": {{"position": [0, 0.3, 2.5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40}},
          "film": {{"width": 64, "height": 64}},
          "objects": [
            {{"type": "mesh", "file": {mesh:?}}},
            {{"type": "quad", "emission": [4, 4, 4], "transform": {{"translate": [0, 3, 0], "rotate": [1, 0, 0, 90]}}}}
          ]
        }}"#
    );
    let path = dir.join(format!(
        "{}.json",
        mesh.file_stem().unwrap().to_string_lossy()
    ));
    std::fs::write(&path, scene).unwrap();
    path
}

/// Loads the scene and traces the camera's centre ray: the moment a render
/// could begin.
fn first_ray(path: &Path, cache: Option<&Cache>) -> Scene {
    let desc = read_scene(path).unwrap();
    let scene = build(&desc, cache).unwrap();
    let camera = desc.settings.camera().unwrap();
    let (w, h) = (camera.width() as f32, camera.height() as f32);
    let ray = camera.ray(0.5 * w, 0.5 * h);
    std::hint::black_box(scene.intersect(&ray));
    scene
}

fn benches(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let mut meshes = Vec::new();
    let generated = dir.path().join("displaced-sphere.obj");
    write_generated_obj(&generated);
    meshes.push(generated);
    let dragon = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes/dragon.obj");
    if dragon.exists() {
        meshes.push(dragon.canonicalize().unwrap());
    }

    for mesh in &meshes {
        let scene_path = write_scene(dir.path(), mesh);
        let name = scene_path
            .file_stem()
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let cache_dir = dir.path().join(format!("cache-{name}"));
        let cache = Cache::new(&cache_dir);
        let mut group = c.benchmark_group(format!("first-ray/{name}"));
        group.sample_size(10);
        group.measurement_time(Duration::from_secs(15));
        group.bench_function("no-cache", |b| b.iter(|| first_ray(&scene_path, None)));
        group.bench_function("cold", |b| {
            b.iter_batched(
                || {
                    cache.clear().unwrap();
                },
                |()| first_ray(&scene_path, Some(&cache)),
                BatchSize::PerIteration,
            )
        });
        first_ray(&scene_path, Some(&cache));
        group.bench_function("warm", |b| {
            b.iter(|| {
                let s = first_ray(&scene_path, Some(&cache));
                assert!(s.triangles.is_mapped(), "not a cache hit");
                s
            })
        });

        let key = scene_key(&read_scene(&scene_path).unwrap(), &BuildOptions::default()).unwrap();
        let bytes = std::fs::metadata(cache.entry_path(&key)).unwrap().len();
        group.throughput(Throughput::Bytes(bytes));
        group.bench_function("load", |b| {
            b.iter(|| {
                let mut warnings = Vec::new();
                let g = cache.lookup(&key, 1, &mut warnings);
                assert!(g.is_some(), "{warnings:?}");
                g
            })
        });
        // The design not taken: read the entry into freshly allocated
        // memory (then it would be cast into the arrays) and checksum it.
        let entry = cache.entry_path(&key);
        group.bench_function("copy-instead", |b| {
            b.iter(|| {
                let bytes = std::fs::read(&entry).unwrap();
                let mut h = blake3::Hasher::new();
                h.update_rayon(&bytes);
                (h.finalize(), bytes.len())
            })
        });
        group.finish();
        eprintln!("{name}: cache entry {:.1} MB", bytes as f64 / 1e6);
    }
}

criterion_group!(cache_benches, benches);
criterion_main!(cache_benches);
