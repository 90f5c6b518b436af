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
use std::time::{Duration, Instant};

const SETS: [&str; 4] = ["primary", "diffuse", "incoherent", "shadow"];

fn floats(path: &Path) -> Vec<f32> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

fn median_seconds(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..runs.max(1))
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
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

    let triangles: Vec<Triangle> = floats(&folder.join("triangles.f32"))
        .chunks_exact(9)
        .map(|v| Triangle {
            v0: Vec3A::new(v[0], v[1], v[2]),
            v1: Vec3A::new(v[3], v[4], v[5]),
            v2: Vec3A::new(v[6], v[7], v[8]),
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
        let rays: Vec<Ray> = floats(&path)
            .chunks_exact(8)
            .map(|r| {
                Ray::new(
                    Vec3A::new(r[0], r[1], r[2]),
                    Vec3A::new(r[4], r[5], r[6]),
                    r[3],
                    r[7],
                )
            })
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
