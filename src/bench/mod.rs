//! `tracer bench`: BVH build and ray throughput on a mesh or a scene, for
//! comparing builds, machines and other ray tracers on identical rays.

pub mod meshes;
pub mod rays;

use crate::bvh::wide::PACKET_SIZE;
use crate::bvh::{BuildOptions, WideBvh};
use crate::camera::Camera;
use crate::geometry::{Aabb, Ray, Triangle};
use crate::render::worker_pool;
use crate::{Error, Result};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Which generated ray sets to trace.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RayKind {
    /// One ray through the centre of each pixel of a 1024 × 1024 image, from
    /// the scene's camera (or one framing the mesh).
    Primary,
    /// A cosine-distributed ray from each primary hit.
    Diffuse,
    /// Origins uniform in the scene's bounds, directions uniform on the sphere.
    Incoherent,
    /// From each primary hit to a random point in the bounds (any-hit queries).
    Shadow,
    /// Every set above.
    All,
}

impl RayKind {
    /// Every kind, in the order the command line lists them.
    pub const ALL: [RayKind; 5] = [
        RayKind::Primary,
        RayKind::Diffuse,
        RayKind::Incoherent,
        RayKind::Shadow,
        RayKind::All,
    ];

    /// The name the command line uses.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Diffuse => "diffuse",
            RayKind::Incoherent => "incoherent",
            RayKind::Shadow => "shadow",
            RayKind::All => "all",
        }
    }
}

/// What `tracer bench` measures, and how often.
pub struct BenchOptions {
    /// Generated ray sets to trace; ignored when `rays_file` is given.
    pub kinds: Vec<RayKind>,
    /// Trace these rays instead of generated ones.
    pub rays_file: Option<PathBuf>,
    /// Thread counts to measure, each in a pool of its own.
    pub threads: Vec<usize>,
    /// Timed repetitions per measurement; the median is reported.
    pub runs: usize,
    /// Write each generated ray set here, in the rays-file format, and the
    /// triangles traced (`triangles.f32`), so other tools trace the same scene.
    pub save_rays: Option<PathBuf>,
    /// Spatial-split budget of the builds ([`BuildOptions::spatial_split_budget`]).
    pub spatial_split_budget: f32,
}

/// One timed BVH build.
#[derive(Debug, Serialize)]
pub struct BuildFigures {
    /// Threads in the pool it ran in (one builds sequentially).
    pub threads: usize,
    /// Median wall-clock build time, in seconds.
    pub seconds: f64,
}

/// One timed query over one ray set.
#[derive(Debug, Serialize)]
pub struct TraceFigures {
    /// The ray set: `primary`, `diffuse`, `incoherent`, `shadow`, or a rays
    /// file's name without extension.
    pub rays: String,
    /// `closest`, `packet` (closest hits, eight consecutive rays at a
    /// time), `any` or `packet-any` (any hits, eight at a time).
    pub query: &'static str,
    /// Threads in the pool it ran in.
    pub threads: usize,
    /// Rays in the set.
    pub count: usize,
    /// Millions of rays per second, from the median run.
    pub mrays_per_second: f64,
    /// Rays that hit something (closest hits) or were occluded (any hits).
    pub hits: usize,
    /// Sum of closest-hit distances (closest-hit queries only), to check
    /// two implementations against each other.
    pub distance_sum: f64,
}

/// What `tracer bench` measured: printed by [`BenchReport::table`], or
/// written as JSON.
#[derive(Debug, Serialize)]
pub struct BenchReport {
    /// The mesh or scene file, as given.
    pub input: String,
    /// Triangles built over and traced.
    pub triangles: usize,
    /// One build per thread count asked for.
    pub builds: Vec<BuildFigures>,
    /// SAH cost of the 8-wide BVH (see [`crate::bvh::wide::BuildReport`]).
    pub sah_cost: f32,
    /// SAH cost of the binary BVH before the collapse.
    pub binary_sah_cost: f32,
    /// 8-wide inner nodes.
    pub nodes: usize,
    /// Leaf blocks (up to four triangles each).
    pub leaves: usize,
    /// Triangle references in the leaf blocks: `triangles`, plus the
    /// copies that spatial splits add.
    pub references: usize,
    /// The spatial-split budget the BVH was built with (0 for none).
    pub spatial_split_budget: f32,
    /// Bytes of nodes and leaf blocks.
    pub memory_bytes: usize,
    /// `memory_bytes` / `triangles`.
    pub bytes_per_triangle: f64,
    /// Every measurement: for each ray set, each thread count and query.
    pub traces: Vec<TraceFigures>,
}

/// The triangles of an OBJ mesh, or of a scene (with its camera).
fn load(path: &Path) -> Result<(Vec<Triangle>, Option<Camera>)> {
    let is_obj = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if is_obj {
        let triangles = meshes::obj_triangles(path).map_err(|message| Error::Data {
            path: path.to_path_buf(),
            message,
        })?;
        Ok((triangles, None))
    } else {
        let (scene, mut settings) = crate::scene::load(path)?;
        settings.film.width = rays::PRIMARY_RESOLUTION;
        settings.film.height = rays::PRIMARY_RESOLUTION;
        Ok((scene.triangles.into_vec(), settings.camera()))
    }
}

/// The median of `runs` timings of `f` (at least one), in seconds.
pub fn median_seconds(runs: usize, mut f: impl FnMut()) -> f64 {
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

/// Rays per parallel work item: large enough to amortise scheduling.
const CHUNK: usize = 4096;

fn trace_closest(bvh: &WideBvh, rays: &[Ray]) -> (usize, f64) {
    rays.par_chunks(CHUNK)
        .map(|chunk| {
            chunk
                .iter()
                .fold((0usize, 0f64), |(n, sum), r| match bvh.intersect(r) {
                    Some(h) => (n + 1, sum + h.t as f64),
                    None => (n, sum),
                })
        })
        .reduce(|| (0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// Closest hits with packets of consecutive rays (for primary rays, eight
/// neighbouring pixels of a row; for the others, rays drawn independently).
fn trace_packets(bvh: &WideBvh, rays: &[Ray]) -> (usize, f64) {
    rays.par_chunks(CHUNK)
        .map(|chunk| {
            let mut result = (0usize, 0f64);
            for packet in chunk.chunks(PACKET_SIZE) {
                for hit in bvh.intersect_packet(packet).iter().flatten() {
                    result.0 += 1;
                    result.1 += hit.t as f64;
                }
            }
            result
        })
        .reduce(|| (0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// Any hits with packets of consecutive rays.
fn trace_any_packets(bvh: &WideBvh, rays: &[Ray]) -> usize {
    rays.par_chunks(CHUNK)
        .map(|chunk| {
            chunk
                .chunks(PACKET_SIZE)
                .map(|packet| bvh.occluded_packet(packet).count_ones() as usize)
                .sum::<usize>()
        })
        .sum()
}

fn trace_any(bvh: &WideBvh, rays: &[Ray]) -> usize {
    rays.par_chunks(CHUNK)
        .map(|chunk| chunk.iter().filter(|r| bvh.occluded(r)).count())
        .sum()
}

/// Loads the OBJ mesh or scene file at `path` (an OBJ by its extension),
/// builds its BVH and times builds and ray queries as `options` ask.
pub fn run(path: &Path, options: &BenchOptions) -> Result<BenchReport> {
    let (triangles, camera) = load(path)?;
    let mut builds = Vec::new();
    let mut bvh = None;
    for &threads in &options.threads {
        let pool = worker_pool(Some(threads))?;
        let build_options = BuildOptions {
            parallel: threads > 1,
            spatial_split_budget: options.spatial_split_budget,
            ..BuildOptions::default()
        };
        let seconds = median_seconds(options.runs.min(3), || {
            bvh = Some(pool.install(|| WideBvh::build_with(&triangles, &build_options)));
        });
        builds.push(BuildFigures { threads, seconds });
    }
    let bvh = match bvh {
        Some(b) => b,
        None => WideBvh::build_with(
            &triangles,
            &BuildOptions {
                spatial_split_budget: options.spatial_split_budget,
                ..BuildOptions::default()
            },
        ),
    };
    let bounds = bvh.bounds();
    let sets = ray_sets(&bvh, &triangles, camera, bounds, options)?;
    if let Some(dir) = &options.save_rays {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        for (name, rays) in &sets {
            rays::write_file(&dir.join(format!("{name}.rays")), rays)?;
        }
        rays::write_triangles(&dir.join("triangles.f32"), &triangles)?;
    }

    let mut traces = Vec::new();
    for (name, rays) in &sets {
        for &threads in &options.threads {
            let pool = worker_pool(Some(threads))?;
            let mut measure = |query: &'static str, trace: &(dyn Fn() -> (usize, f64) + Sync)| {
                let (hits, distance_sum) = pool.install(trace);
                let seconds = median_seconds(options.runs, || {
                    pool.install(trace);
                });
                traces.push(TraceFigures {
                    rays: name.clone(),
                    query,
                    threads,
                    count: rays.len(),
                    mrays_per_second: rays.len() as f64 / seconds / 1e6,
                    hits,
                    distance_sum,
                });
            };
            measure("closest", &|| trace_closest(&bvh, rays));
            measure("packet", &|| trace_packets(&bvh, rays));
            measure("any", &|| (trace_any(&bvh, rays), 0.0));
            measure("packet-any", &|| (trace_any_packets(&bvh, rays), 0.0));
        }
    }
    let report = bvh.report();
    Ok(BenchReport {
        input: path.display().to_string(),
        triangles: triangles.len(),
        builds,
        sah_cost: report.sah_cost,
        binary_sah_cost: report.binary_sah_cost,
        nodes: report.nodes,
        leaves: report.leaves,
        references: report.references,
        spatial_split_budget: options.spatial_split_budget,
        memory_bytes: bvh.memory_bytes(),
        bytes_per_triangle: bvh.memory_bytes() as f64 / triangles.len().max(1) as f64,
        traces,
    })
}

fn ray_sets(
    bvh: &WideBvh,
    triangles: &[Triangle],
    camera: Option<Camera>,
    bounds: Aabb,
    options: &BenchOptions,
) -> Result<Vec<(String, Vec<Ray>)>> {
    if let Some(file) = &options.rays_file {
        let name = file
            .file_stem()
            .map_or("file".into(), |s| s.to_string_lossy().into_owned());
        return Ok(vec![(name, rays::read_file(file)?)]);
    }
    let wants = |k: RayKind| options.kinds.contains(&k) || options.kinds.contains(&RayKind::All);
    let camera = camera.unwrap_or_else(|| rays::framing_camera(bounds));
    let primary = rays::primary(&camera);
    let hits = rays::hit_points(bvh, triangles, &primary);
    let mut sets = Vec::new();
    if wants(RayKind::Primary) {
        sets.push(("primary".to_string(), primary));
    }
    if wants(RayKind::Diffuse) {
        sets.push(("diffuse".to_string(), rays::diffuse(&hits)));
    }
    if wants(RayKind::Incoherent) {
        sets.push((
            "incoherent".to_string(),
            rays::incoherent(bounds, rays::INCOHERENT_COUNT),
        ));
    }
    if wants(RayKind::Shadow) {
        sets.push(("shadow".to_string(), rays::shadow(&hits, bounds)));
    }
    Ok(sets)
}

impl BenchReport {
    /// A human-readable table.
    pub fn table(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = writeln!(s, "{}: {} triangles", self.input, self.triangles);
        for b in &self.builds {
            let _ = writeln!(
                s,
                "build      {:>2} thread(s): {:.3} s",
                b.threads, b.seconds
            );
        }
        let _ = writeln!(
            s,
            "bvh        {}-wide: SAH cost {:.2} (binary before collapse {:.2}), {} nodes, {} leaves, {:.1} bytes/triangle",
            crate::bvh::wide::WIDTH, self.sah_cost, self.binary_sah_cost, self.nodes, self.leaves, self.bytes_per_triangle
        );
        if self.spatial_split_budget > 0.0 {
            let _ = writeln!(
                s,
                "splits     spatial, budget {}: {} references to {} triangles (+{:.1}%)",
                self.spatial_split_budget,
                self.references,
                self.triangles,
                100.0 * (self.references as f64 / self.triangles.max(1) as f64 - 1.0)
            );
        }
        let _ = writeln!(
            s,
            "{:<12} {:<10} {:>7} {:>9} {:>10} {:>9} {:>16}",
            "rays", "query", "threads", "count", "Mrays/s", "hits", "distance sum"
        );
        for t in &self.traces {
            let _ = writeln!(
                s,
                "{:<12} {:<10} {:>7} {:>9} {:>10.2} {:>9} {:>16.6e}",
                t.rays, t.query, t.threads, t.count, t.mrays_per_second, t.hits, t.distance_sum
            );
        }
        s
    }
}
