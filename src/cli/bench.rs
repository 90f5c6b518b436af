//! `tracer bench`: BVH build time and ray throughput on a mesh or a scene.

use clap::Args;
use std::path::PathBuf;
use tracer::bench::{BenchOptions, RayKind};
use tracer::{Error, Result};

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// An OBJ mesh, or a scene file (whose camera then makes the primary rays).
    pub input: PathBuf,
    /// Ray sets to trace (repeatable).
    #[arg(long, value_parser = super::one_of(&RayKind::ALL, RayKind::name), default_value = "all")]
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
    /// Build with spatial splits, allowing this many extra triangle
    /// references as a fraction of the triangle count (0 for none).
    #[arg(long, value_name = "FRACTION", default_value_t = 0.0, value_parser = budget_fraction)]
    pub spatial_splits: f32,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run_bench(args: &BenchArgs) -> Result<()> {
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
        spatial_split_budget: args.spatial_splits,
    };
    let report = tracer::bench::run(&args.input, &options)?;
    if args.json {
        let json = serde_json::to_string_pretty(&report)
            .map_err(|e| Error::io("(standard output)", std::io::Error::other(e)))?;
        outln!("{json}");
    } else {
        out!("{}", report.table());
    }
    Ok(())
}

/// A spatial-split budget: a fraction from 0 to 16.
fn budget_fraction(text: &str) -> std::result::Result<f32, String> {
    match text.parse::<f32>() {
        Ok(f) if (0.0..=16.0).contains(&f) => Ok(f),
        _ => Err(format!("expected a number from 0 to 16, got {text:?}")),
    }
}
