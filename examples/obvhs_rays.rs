//! The `obvhs` crate's figures on the files `tracer bench --save-rays`
//! writes, for `benches/peers/embree.py`, which puts them in one table with
//! tracer's and Embree's from the same run.
//!
//!     cargo run --release --example obvhs_rays -- FOLDER THREADS RUNS
//!
//! Reads FOLDER/triangles.f32 (nine f32 per triangle) and every
//! FOLDER/<set>.rays (32-byte records: origin, tmin, direction, tmax),
//! builds obvhs's CWBVH with its `fast_build` preset (median of up to three
//! builds, on THREADS threads), traces each set for the closest hit and
//! for any hit on THREADS threads (median of RUNS runs) and prints one JSON
//! object shaped like the script's Embree worker's.

use glam::Vec3A;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use rayon::prelude::*;
use serde_json::json;
use std::path::Path;
use std::time::Duration;
use tracer::bench::{median_seconds, rays};

const SETS: [&str; 4] = ["primary", "diffuse", "incoherent", "shadow"];

/// Converts tracer's ray to obvhs's.
fn obvhs_ray(r: &tracer::geometry::Ray) -> Ray {
    Ray::new(Vec3A::from(r.origin), Vec3A::from(r.dir), r.tmin, r.tmax)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 4 {
        eprintln!("usage: obvhs_rays FOLDER THREADS RUNS");
        std::process::exit(2);
    }
    let folder = Path::new(&args[1]);
    let threads: usize = args[2].parse().expect("THREADS: a number");
    let runs: usize = args[3].parse().expect("RUNS: a number");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");

    let triangles: Vec<Triangle> = rays::read_triangles(&folder.join("triangles.f32"))
        .unwrap_or_else(|e| panic!("{e}"))
        .iter()
        .map(|t| Triangle {
            v0: t.v[0].into(),
            v1: t.v[1].into(),
            v2: t.v[2].into(),
        })
        .collect();
    let mut bvh = None;
    let build_seconds = median_seconds(runs.min(3), || {
        bvh = Some(pool.install(|| {
            build_cwbvh_from_tris(
                &triangles,
                BvhBuildParams::fast_build(),
                &mut Duration::default(),
            )
        }));
    });
    let bvh = bvh.expect("built at least once");
    // obvhs reports primitives by its own order: reorder once, as its examples do.
    let ordered: Vec<Triangle> = bvh
        .primitive_indices
        .iter()
        .map(|&i| triangles[i as usize])
        .collect();
    let closest = |r: &Ray| {
        let mut hit = RayHit::none();
        bvh.ray_traverse(*r, &mut hit, |r, id| ordered[id].intersect(r));
        hit
    };
    let occluded = |r: &Ray| !bvh.ray_traverse_miss(*r, |r, id| ordered[id].intersect(r));

    let mut traces = Vec::new();
    for set in SETS {
        let path = folder.join(format!("{set}.rays"));
        if !path.exists() {
            continue;
        }
        let rays: Vec<Ray> = rays::read_file(&path)
            .unwrap_or_else(|e| panic!("{e}"))
            .iter()
            .map(obvhs_ray)
            .collect();
        let hits: Vec<RayHit> = pool.install(|| rays.par_iter().map(closest).collect());
        let hit_count = hits.iter().filter(|h| h.t < f32::INFINITY).count();
        let distance_sum: f64 = hits
            .iter()
            .filter(|h| h.t < f32::INFINITY)
            .map(|h| h.t as f64)
            .sum();
        let any_count = pool.install(|| rays.par_iter().filter(|r| occluded(r)).count());
        let closest_seconds = median_seconds(runs, || {
            pool.install(|| {
                rays.par_iter()
                    .map(closest)
                    .filter(|h| h.t < f32::INFINITY)
                    .count()
            });
        });
        let any_seconds = median_seconds(runs, || {
            pool.install(|| rays.par_iter().filter(|r| occluded(r)).count());
        });
        for (query, hits, seconds, sum) in [
            ("closest", hit_count, closest_seconds, distance_sum),
            ("any", any_count, any_seconds, 0.0),
        ] {
            traces.push(json!({
                "rays": set, "query": query, "threads": threads, "count": rays.len(),
                "mrays_per_second": rays.len() as f64 / seconds / 1e6,
                "hits": hits, "distance_sum": sum,
            }));
        }
    }
    let report = json!({"threads": threads, "build_seconds": build_seconds, "traces": traces});
    println!("{report}");
}
