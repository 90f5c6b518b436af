//! The command line: `tracer render` and `tracer info`.

use crate::bench::{BenchOptions, RayKind};
use crate::film::write::{read_linear, write_image, ImageFormat};
use crate::light::Light;
use crate::render::{render, render_strategies, RenderOptions, MAX_STRATEGY_LENGTH};
use crate::scene::cache::{Cache, CacheUse};
use crate::scene::desc::{Display, IntegratorKind, Tonemap};
use crate::scene::{self, Scene};
use crate::{Error, Result};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use std::time::Instant;

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
    /// Relative MSE of a linear image (.pfm, .exr) against a reference:
    /// the mean over pixels and channels of (image − reference)² / (reference² + 0.01).
    Compare { image: PathBuf, reference: PathBuf },
}

#[derive(Subcommand, Debug)]
pub enum CacheCommand {
    /// One line per entry: key, scene, size, time since last use.
    List,
    /// Remove every entry.
    Clear,
    /// Remove least recently used entries until the rest fit in a size.
    Prune {
        /// e.g. 2G, 500M (binary multiples).
        #[arg(long, value_parser = scene::cache::parse_size)]
        max_size: u64,
    },
}

/// Where prepared geometry is cached between runs.
#[derive(Args, Debug, Default, Clone)]
pub struct CacheArgs {
    /// The scene cache folder (default: $TRACER_CACHE_DIR, else the
    /// platform's cache folder, ~/.cache/tracer on Linux).
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// Neither read nor write the scene cache.
    #[arg(long, conflicts_with = "cache_dir")]
    pub no_cache: bool,
}

impl CacheArgs {
    pub fn cache(&self) -> Option<Cache> {
        if self.no_cache {
            return None;
        }
        self.cache_dir
            .clone()
            .or_else(Cache::default_dir)
            .map(Cache::new)
    }
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

/// Flags override the scene's `film` and `render` blocks.
#[derive(Args, Debug, Default)]
pub struct RenderArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Output image; the format follows the extension (.exr, .pfm, .png, .tga).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorKind>,
    /// Samples per pixel.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Stop after the pass in progress once this many seconds have passed.
    #[arg(long, value_parser = positive_seconds)]
    pub time_limit: Option<f32>,
    /// Maximum number of path segments.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub max_depth: Option<u32>,
    /// The image is a pure function of scene, settings and seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: one per core).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..1025))]
    pub threads: Option<u32>,
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..65537))]
    pub width: Option<u32>,
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..65537))]
    pub height: Option<u32>,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
    /// Also write one EXR per BDPT strategy (s light vertices, t camera
    /// vertices), unweighted and MIS-weighted, for paths of up to 5 segments.
    #[arg(long, value_name = "DIR")]
    pub bdpt_strategies: Option<PathBuf>,
    #[command(flatten)]
    pub cache: CacheArgs,
}

fn positive_seconds(s: &str) -> std::result::Result<f32, String> {
    match s.parse::<f32>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!(
            "expected a positive number of seconds, found {s:?}"
        )),
    }
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(args) => run_render(&args),
        Command::Info { scene, cache } => run_info(&scene, &cache),
        Command::Cache { action, cache_dir } => run_cache(&action, cache_dir),
        Command::Bench(args) => run_bench(&args),
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
            Ok(())
        }
    }
}

/// Loads the scene and applies the command-line overrides.
pub fn prepare(args: &RenderArgs) -> Result<Scene> {
    let mut scene = scene::load_cached(&args.scene, args.cache.cache().as_ref())?;
    let s = &mut scene.settings;
    if let Some(o) = &args.output {
        s.output = o.clone();
    }
    if let Some(i) = args.integrator {
        s.integrator = i;
    }
    if let Some(n) = args.spp {
        s.spp = n;
    }
    if let Some(t) = args.time_limit {
        s.time_limit = Some(t);
    }
    if let Some(d) = args.max_depth {
        s.max_depth = d;
    }
    if let Some(seed) = args.seed {
        s.seed = seed;
    }
    if args.width.is_some() || args.height.is_some() {
        let (w, h) = (
            args.width.unwrap_or(s.width),
            args.height.unwrap_or(s.height),
        );
        scene.set_resolution(w, h);
    }
    if ImageFormat::from_path(&scene.settings.output).is_none() {
        return Err(Error::Image {
            path: scene.settings.output.clone(),
            message: "unknown image format: use .exr, .pfm, .png or .tga".into(),
        });
    }
    Ok(scene)
}

fn run_render(args: &RenderArgs) -> Result<()> {
    let start = Instant::now();
    let scene = prepare(args)?;
    for w in &scene.report.warnings {
        eprintln!("warning: {w}");
    }
    if scene.report.degenerate_triangles_dropped > 0 {
        eprintln!(
            "note: dropped {} degenerate (zero-area) triangles",
            scene.report.degenerate_triangles_dropped
        );
    }
    if scene.display == Some(Display::Window) {
        eprintln!(
            "note: this T-racer scene asks for a preview window, which this build does not have; writing {}",
            scene.settings.output.display()
        );
    }
    let bvh = match scene.report.cache {
        CacheUse::Hit => "geometry and BVH from the scene cache".to_string(),
        CacheUse::Stored => format!(
            "BVH built in {:.3} s and cached",
            scene.report.bvh_build_seconds
        ),
        CacheUse::Off | CacheUse::NotStored => {
            format!("BVH built in {:.3} s", scene.report.bvh_build_seconds)
        }
    };
    eprintln!(
        "loaded {} ({} triangles, {} lights) in {:.2} s, {bvh}",
        args.scene.display(),
        scene.triangles.len(),
        scene.lights.len(),
        start.elapsed().as_secs_f64(),
    );
    let options = RenderOptions {
        threads: args.threads.map(|t| t as usize),
        progress: !args.quiet,
    };
    let (image, stats) = render(&scene, &options)?;
    let s = &scene.settings;
    write_image(&s.output, &image, s.tonemap, s.exposure)?;
    eprintln!(
        "wrote {}: {}x{}, {} spp, {:.2} s, {:.2} M samples/s",
        s.output.display(),
        s.width,
        s.height,
        stats.spp,
        stats.seconds,
        stats.samples_per_second() / 1e6
    );
    if stats.discarded > 0 {
        eprintln!(
            "warning: {} of {} samples were NaN or infinite and were discarded",
            stats.discarded, stats.samples
        );
    }
    if let Some(dir) = &args.bdpt_strategies {
        write_strategies(&scene, &options, dir)?;
    }
    Ok(())
}

/// Renders BDPT once more, keeping each strategy apart, and writes
/// `s{S}_t{T}_unweighted.exr` and `s{S}_t{T}_weighted.exr` into `dir`.
fn write_strategies(scene: &Scene, options: &RenderOptions, dir: &std::path::Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let images = render_strategies(scene, options)?;
    for i in &images {
        for (kind, image) in [("unweighted", &i.unweighted), ("weighted", &i.weighted)] {
            let path = dir.join(format!("s{}_t{}_{kind}.exr", i.s, i.t));
            write_image(&path, image, Tonemap::Clamp, 0.0)?;
        }
    }
    eprintln!(
        "wrote {} strategy images (paths up to {} segments) to {}",
        2 * images.len(),
        scene.settings.max_depth.min(MAX_STRATEGY_LENGTH),
        dir.display()
    );
    Ok(())
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

fn run_cache(action: &CacheCommand, dir: Option<PathBuf>) -> Result<()> {
    let dir = dir.or_else(Cache::default_dir).ok_or_else(|| {
        Error::Unsupported("no cache folder: pass --cache-dir or set TRACER_CACHE_DIR".into())
    })?;
    let cache = Cache::new(&dir);
    let io = |e| Error::io(&dir, e);
    match action {
        CacheCommand::List => {
            let entries = cache.list().map_err(io)?;
            println!("{:<16}  {:>10}  {:>10}  scene", "key", "size", "last used");
            for e in &entries {
                let age = e.last_used.elapsed().unwrap_or_default();
                let scene = match &e.scene {
                    Ok(s) => s.clone(),
                    Err(why) => format!("(invalid: {why})"),
                };
                println!(
                    "{:<16}  {:>10}  {:>10}  {scene}",
                    &e.key[..e.key.len().min(16)],
                    human_bytes(e.bytes),
                    human_age(age)
                );
            }
            let total: u64 = entries.iter().map(|e| e.bytes).sum();
            println!(
                "{} entries, {} in {}",
                entries.len(),
                human_bytes(total),
                dir.display()
            );
        }
        CacheCommand::Clear => {
            let (n, bytes) = cache.clear().map_err(io)?;
            println!("removed {n} files ({})", human_bytes(bytes));
        }
        CacheCommand::Prune { max_size } => {
            let (n, bytes) = cache.prune(*max_size).map_err(io)?;
            println!(
                "removed {n} entries ({}), least recently used first",
                human_bytes(bytes)
            );
        }
    }
    Ok(())
}

fn human_bytes(n: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut x = n as f64;
    let mut unit = 0;
    while x >= 1024.0 && unit < UNITS.len() - 1 {
        x /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{n} B")
    } else {
        format!("{x:.1} {}", UNITS[unit])
    }
}

fn human_age(d: std::time::Duration) -> String {
    let s = d.as_secs();
    match s {
        0..60 => format!("{s} s ago"),
        60..3600 => format!("{} min ago", s / 60),
        3600..86400 => format!("{} h ago", s / 3600),
        _ => format!("{} d ago", s / 86400),
    }
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
        "bvh:        4-wide, {} nodes, {} leaves, SAH cost {:.2} (binary {:.2}), {} bytes, built in {:.3} s",
        r.nodes,
        r.leaves,
        r.sah_cost,
        r.binary_sah_cost,
        scene.bvh.memory_bytes(),
        scene.report.bvh_build_seconds
    );
    let s = &scene.settings;
    let integrator = match s.integrator {
        IntegratorKind::Pt => "pt",
        IntegratorKind::Lt => "lt",
        IntegratorKind::Bdpt => "bdpt",
    };
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
