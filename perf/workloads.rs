//! The fixed workloads of the performance gate (`perf/check`).
//!
//! Each workload is deterministic: generated geometry, rays from fixed seeds,
//! renders at a fixed seed on one thread. `perf/check` runs each one under
//! `valgrind --tool=callgrind` and counts the instructions of the measured
//! part only: the setup (generating the mesh, loading the scene) runs first,
//! then the work runs between two callgrind client requests that zero the
//! counters and dump them. Instruction counts, unlike seconds, repeat on a
//! noisy shared machine.
//!
//! `TRACER_PERF_SLOWDOWN=F` (a fraction, e.g. 0.05) makes every workload
//! repeat about that fraction of its work, to show that the gate catches a
//! regression of that size.
//!
//! Usage: `perf_workloads NAME` (or `list`). Without valgrind the client
//! requests do nothing, and the program just runs the workload.

use std::hint::black_box;
use tracer::bench::{meshes, rays};
use tracer::bvh::WideBvh;
use tracer::camera::Camera;
use tracer::geometry::{Ray, Triangle};
use tracer::render::{render, worker_pool, RenderOptions};
use tracer::settings::IntegratorKind;

/// `city(129)`: 129² buildings of 12 triangles on a ground plane, 199,694 triangles.
const CITY_BLOCKS: u32 = 129;
const RAY_COUNT: usize = 200_000;
/// Renders: small images at a few samples per pixel.
const RENDER_SIZE: u32 = 64;
const RENDER_SPP: u32 = 4;

const WORKLOADS: &[&str] = &[
    "bvh-build",
    "rays-diffuse-closest",
    "rays-shadow-any",
    "render-cornell-pt",
    "render-cornell-lt",
    "render-cornell-bdpt",
    "render-caustics-pt",
    "render-caustics-lt",
    "render-caustics-bdpt",
];

fn main() {
    let name = std::env::args().nth(1).unwrap_or_default();
    let slowdown: f64 = std::env::var("TRACER_PERF_SLOWDOWN")
        .ok()
        .and_then(|s| s.parse().ok())
        .filter(|f: &f64| f.is_finite() && *f > 0.0)
        .unwrap_or(0.0);
    if name == "list" {
        for w in WORKLOADS {
            println!("{w}");
        }
        return;
    }
    // One worker, and the measured work runs on it: nested rayon calls
    // (the parallel BVH build) then run inline, in a fixed order.
    let pool = worker_pool(Some(1)).expect("one worker thread");
    match name.as_str() {
        "bvh-build" => {
            let triangles = meshes::city(CITY_BLOCKS);
            let part = prefix(&triangles, slowdown);
            pool.install(|| {
                measured(|| {
                    black_box(WideBvh::build(&triangles));
                    if !part.is_empty() {
                        black_box(WideBvh::build(part));
                    }
                })
            });
        }
        "rays-diffuse-closest" | "rays-shadow-any" => {
            let triangles = meshes::city(CITY_BLOCKS);
            let mut bvh = pool.install(|| WideBvh::build(&triangles));
            // Prefetches hide memory latency, which instruction counts do
            // not see; the city's tree (16–17 MB) sits at the size where
            // they start, and a small change in it would switch them on and
            // add a prefetch per deferred child's cache line to the count.
            bvh.set_prefetch(false);
            let set = ray_set(&name, &bvh, &triangles);
            let extra = prefix(&set, slowdown);
            let closest = name.ends_with("closest");
            pool.install(|| {
                measured(|| {
                    for rays in [&set[..], extra] {
                        if closest {
                            let hits = rays.iter().filter(|r| bvh.intersect(r).is_some());
                            black_box(hits.count());
                        } else {
                            black_box(rays.iter().filter(|r| bvh.occluded(r)).count());
                        }
                    }
                })
            });
        }
        _ if name.starts_with("render-") => render_workload(&name, slowdown),
        _ => {
            eprintln!(
                "unknown workload {name:?}; workloads: {}",
                WORKLOADS.join(", ")
            );
            std::process::exit(2);
        }
    }
}

/// The first `fraction` of `items`: the part a slowed-down run repeats.
fn prefix<T>(items: &[T], fraction: f64) -> &[T] {
    let n = ((items.len() as f64 * fraction).round() as usize).min(items.len());
    &items[..n]
}

/// Exactly [`RAY_COUNT`] rays from primary hits of a camera framing the city.
fn ray_set(name: &str, bvh: &WideBvh, triangles: &[Triangle]) -> Vec<Ray> {
    let framing = rays::framing_camera(bvh.bounds());
    let side = (RAY_COUNT as f64).sqrt().ceil() as u32 + 8;
    let camera = Camera::new(
        framing.position,
        framing.position + framing.forward(),
        glam::Vec3::Y,
        45.0,
        side,
        side,
    )
    .expect("a valid camera");
    let hits = rays::hit_points(bvh, triangles, &rays::primary(&camera));
    let set = if name.contains("shadow") {
        rays::shadow(&hits, bvh.bounds())
    } else {
        rays::diffuse(&hits)
    };
    set.into_iter().cycle().take(RAY_COUNT).collect()
}

fn render_workload(name: &str, slowdown: f64) {
    let mut parts = name.split('-').skip(1);
    let scene = match parts.next() {
        Some("cornell") => "scenes/cornell-box.json",
        Some("caustics") => "scenes/cornell-caustics.json",
        _ => unknown(name),
    };
    let integrator = match parts.next() {
        Some("pt") => IntegratorKind::Pt,
        Some("lt") => IntegratorKind::Lt,
        Some("bdpt") => IntegratorKind::Bdpt,
        _ => unknown(name),
    };
    let (scene, mut settings) = tracer::scene::load(std::path::Path::new(scene))
        .unwrap_or_else(|e| panic!("cannot load {scene}: {e}"));
    settings.integrator = integrator;
    settings.stop.spp = RENDER_SPP;
    settings.stop.time_limit = None;
    settings.seed = 1;
    let at_size = |size: u32| {
        let mut s = settings.clone();
        s.film.width = size;
        s.film.height = size;
        s
    };
    let full = at_size(RENDER_SIZE);
    let extra_size = (RENDER_SIZE as f64 * slowdown.sqrt()).round() as u32;
    let extra = (extra_size > 0).then(|| at_size(extra_size));
    let options = RenderOptions {
        threads: Some(1),
        progress: false,
        ..RenderOptions::default()
    };
    measured(|| {
        for settings in std::iter::once(&full).chain(extra.as_ref()) {
            black_box(render(&scene, settings, &options).expect("render"));
        }
    });
}

fn unknown(name: &str) -> ! {
    eprintln!("unknown workload {name:?}");
    std::process::exit(2)
}

/// Runs `work` with callgrind's counters zeroed before and dumped after, so
/// the dump holds exactly the instructions of `work`, on every thread.
fn measured(work: impl FnOnce()) {
    callgrind::zero_stats();
    work();
    callgrind::dump_stats();
}

/// Valgrind client requests, written from the protocol `valgrind.h`
/// documents: a special no-op instruction sequence that valgrind recognises,
/// with the request in a six-word block pointed to by `rax`. Outside valgrind
/// the sequence does nothing.
mod callgrind {
    /// `VG_USERREQ_TOOL_BASE('C', 'T')`: callgrind's first request, DUMP_STATS.
    const DUMP_STATS: u64 = (b'C' as u64) << 24 | (b'T' as u64) << 16;
    const ZERO_STATS: u64 = DUMP_STATS + 1;

    pub fn dump_stats() {
        request(DUMP_STATS);
    }

    pub fn zero_stats() {
        request(ZERO_STATS);
    }

    #[cfg(target_arch = "x86_64")]
    fn request(code: u64) {
        let args: [u64; 6] = [code, 0, 0, 0, 0, 0];
        let mut result: u64 = 0;
        // SAFETY: the rotations total 128 bits, so rdi is unchanged, and
        // `xchg rbx, rbx` swaps a register with itself: natively this is a
        // no-op; under valgrind it is the client request, which reads the
        // block at rax and writes its answer to rdx.
        unsafe {
            std::arch::asm!(
                "rol rdi, 3",
                "rol rdi, 13",
                "rol rdi, 61",
                "rol rdi, 51",
                "xchg rbx, rbx",
                in("rax") args.as_ptr(),
                inout("rdx") result,
                inout("rdi") 0u64 => _,
                options(nostack),
            );
        }
        std::hint::black_box(result);
    }

    #[cfg(not(target_arch = "x86_64"))]
    fn request(_code: u64) {
        eprintln!("warning: callgrind client requests are only implemented on x86_64");
    }
}
