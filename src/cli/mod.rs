//! The command line: `tracer render`, `info`, `bench`, `compare`, `cache`
//! and `merge`.

mod cache;
mod merge;
mod render;
mod signals;

pub use cache::{CacheArgs, CacheCommand};
pub use merge::MergeArgs;
pub use render::{prepare, RenderArgs};
pub use signals::INTERRUPTED_EXIT;

use crate::bench::{BenchOptions, RayKind};
use crate::film::write::read_linear;
use crate::light::Light;
use crate::scene;
use crate::{Error, Result};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "tracer",
    version,
    about = "A physically based offline renderer"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene (.json, or a T-racer .trs) to an image.
    Render(RenderArgs),
    /// Describe a scene: triangles, lights, materials, bounds and BVH.
    Info {
        /// The scene file.
        scene: PathBuf,
        #[command(flatten)]
        cache: CacheArgs,
    },
    /// The scene cache: list, clear or prune its entries.
    Cache {
        #[command(subcommand)]
        action: CacheCommand,
        /// The cache folder (default: $TRACER_CACHE_DIR, else the platform's
        /// cache folder, ~/.cache/tracer on Linux).
        #[arg(long, value_name = "DIR", global = true)]
        cache_dir: Option<PathBuf>,
    },
    /// Measure BVH build time and ray throughput on a mesh (.obj) or a scene.
    Bench(BenchArgs),
    /// Combine partial renders of one scene (crops, or disjoint sample
    /// ranges from --sample-offset) into one image, weighted by their samples.
    Merge(MergeArgs),
    /// Relative MSE of a linear image (.pfm, .exr) against a reference:
    /// the mean over pixels and channels of (image − reference)² / (reference² + 0.01).
    Compare { image: PathBuf, reference: PathBuf },
}

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// An OBJ mesh, or a scene file (whose camera then makes the primary rays).
    pub input: PathBuf,
    /// Ray sets to trace (repeatable).
    #[arg(long, value_enum, default_values_t = [RayKind::All])]
    pub rays: Vec<RayKind>,
    /// Trace rays from this file instead: 32-byte little-endian f32 records
    /// (origin x y z, tmin, direction x y z, tmax).
    #[arg(long, value_name = "FILE")]
    pub rays_file: Option<PathBuf>,
    /// Thread counts to measure, e.g. `1,2` (default: 1 and every core).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..1025))]
    pub threads: Vec<u32>,
    /// Timed runs per figure; the median is reported.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..1000))]
    pub runs: u32,
    /// Also write each generated ray set to DIR/<kind>.rays, for other tools.
    #[arg(long, value_name = "DIR")]
    pub save_rays: Option<PathBuf>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Runs a command; returns the process's exit status.
pub fn run(cli: Cli) -> Result<i32> {
    match cli.command {
        Command::Render(args) => render::run_render(&args),
        Command::Merge(args) => merge::run_merge(&args),
        Command::Info { scene, cache } => run_info(&scene, &cache).map(|()| 0),
        Command::Cache { action, cache_dir } => cache::run_cache(&action, cache_dir).map(|()| 0),
        Command::Bench(args) => run_bench(&args).map(|()| 0),
        Command::Compare { image, reference } => {
            let (a, b) = (read_linear(&image)?, read_linear(&reference)?);
            let error = crate::film::relative_mse(&a, &b).ok_or_else(|| Error::Image {
                path: image.clone(),
                message: format!(
                    "is {}x{}, the reference {}x{}",
                    a.width, a.height, b.width, b.height
                ),
            })?;
            println!("{error:.6e}");
            Ok(0)
        }
    }
}

fn run_bench(args: &BenchArgs) -> Result<()> {
    let mut threads: Vec<usize> = args.threads.iter().map(|&t| t as usize).collect();
    if threads.is_empty() {
        threads = vec![
            1,
            std::thread::available_parallelism().map_or(1, |n| n.get()),
        ];
    }
    threads.dedup();
    let options = BenchOptions {
        kinds: args.rays.clone(),
        rays_file: args.rays_file.clone(),
        threads,
        runs: args.runs as usize,
        save_rays: args.save_rays.clone(),
    };
    let report = crate::bench::run(&args.input, &options)?;
    if args.json {
        let json = serde_json::to_string_pretty(&report)
            .map_err(|e| Error::Unsupported(format!("cannot write JSON: {e}")))?;
        println!("{json}");
    } else {
        print!("{}", report.table());
    }
    Ok(())
}

fn run_info(path: &std::path::Path, cache: &CacheArgs) -> Result<()> {
    let scene = scene::load_cached(path, cache.cache().as_ref())?;
    let count = |f: fn(&Light) -> bool| scene.lights.iter().filter(|l| f(l)).count();
    println!("scene:      {} ({})", scene.name, path.display());
    println!("triangles:  {}", scene.triangles.len());
    if scene.report.degenerate_triangles_dropped > 0 {
        println!(
            "dropped:    {} degenerate triangles",
            scene.report.degenerate_triangles_dropped
        );
    }
    println!(
        "lights:     {} (area triangles {}, point {}, spot {}, directional {})",
        scene.lights.len(),
        count(|l| matches!(l, Light::Area(_))),
        count(|l| matches!(l, Light::Point(_))),
        count(|l| matches!(l, Light::Spot(_))),
        count(|l| matches!(l, Light::Directional(_))),
    );
    println!(
        "materials:  {} ({})",
        scene.materials.len(),
        scene.material_names.join(", ")
    );
    let b = scene.bounds;
    if b.is_empty() {
        println!("bounds:     empty");
    } else {
        println!(
            "bounds:     ({:.4}, {:.4}, {:.4}) .. ({:.4}, {:.4}, {:.4})",
            b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
        );
    }
    let r = scene.bvh.report();
    println!(
        "bvh:        4-wide, {} nodes, {} leaves, SAH cost {:.2} (binary {:.2}), {} bytes, {}",
        r.nodes,
        r.leaves,
        r.sah_cost,
        r.binary_sah_cost,
        scene.bvh.memory_bytes(),
        match scene.report.cache {
            scene::cache::CacheUse::Hit => "from the scene cache".to_string(),
            _ => format!("built in {:.3} s", scene.report.bvh_build_seconds),
        }
    );
    let s = &scene.settings;
    let integrator = s.integrator.name();
    println!(
        "render:     {}x{}, {} spp, {}, max depth {}, seed {} -> {}",
        s.width,
        s.height,
        s.spp,
        integrator,
        s.max_depth,
        s.seed,
        s.output.display()
    );
    for w in &scene.report.warnings {
        println!("warning:    {w}");
    }
    Ok(())
}
