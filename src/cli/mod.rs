//! The command line: `tracer render`, `info`, `bench`, `compare`, `cache`
//! and `merge`.

/// `println!` for a command's output on stdout. A reader that goes away
/// early (`tracer bench --json | head`) makes the write fail with a broken
/// pipe; the command then exits at once with the status a shell gives a
/// process killed by SIGPIPE (141), quietly, as other Unix tools do,
/// instead of panicking.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::cli::write_out(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` for a command's output, as [`outln!`].
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::cli::write_out(format_args!($($arg)*))
    };
}

mod bench;
mod cache;
mod info;
mod merge;
mod preview;
mod render;
mod signals;

use bench::BenchArgs;
use cache::{CacheArgs, CacheCommand};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Parser, Subcommand};
use merge::MergeArgs;
use render::RenderArgs;
use std::path::PathBuf;
use tracer::film::read::read_linear;
use tracer::{Error, Result};

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

/// Runs a command; returns the process's exit status.
pub fn run(cli: Cli) -> Result<i32> {
    match cli.command {
        Command::Render(args) => render::run_render(&args),
        Command::Merge(args) => merge::run_merge(&args),
        Command::Info { scene, cache } => info::run_info(&scene, &cache).map(|()| 0),
        Command::Cache { action, cache_dir } => cache::run_cache(&action, cache_dir).map(|()| 0),
        Command::Bench(args) => bench::run_bench(&args).map(|()| 0),
        Command::Compare { image, reference } => {
            let (a, b) = (read_linear(&image)?, read_linear(&reference)?);
            let error = tracer::film::relative_mse(&a, &b).ok_or_else(|| Error::Image {
                path: image.clone(),
                message: format!(
                    "is {}x{}, the reference {}x{}",
                    a.width, a.height, b.width, b.height
                ),
            })?;
            outln!("{error:.6e}");
            Ok(0)
        }
    }
}

/// A flag whose value is one of `all`, by the names `name` gives them: the
/// library's enums stay free of the command-line parser.
fn one_of<T: Copy + Send + Sync + 'static>(
    all: &'static [T],
    name: fn(T) -> &'static str,
) -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(all.iter().map(|&v| name(v))).try_map(move |s| {
        all.iter()
            .copied()
            .find(|&v| name(v) == s)
            .ok_or_else(|| format!("unknown value {s:?}"))
    })
}

/// Writes a command's output to stdout; see [`outln!`].
pub(crate) fn write_out(text: std::fmt::Arguments) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    if let Err(e) = stdout.write_fmt(text).and_then(|()| stdout.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(BROKEN_PIPE_EXIT);
        }
        eprintln!("error: writing to stdout: {e}");
        std::process::exit(1);
    }
}

/// 128 + SIGPIPE: what a shell reports for a process a closed pipe ended.
const BROKEN_PIPE_EXIT: i32 = 141;
