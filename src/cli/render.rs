//! `tracer render`: flags, overrides, progressive passes with checkpoints,
//! interruption, and the report.

use super::cache::CacheArgs;
use super::signals::{interrupt_flag, INTERRUPTED_EXIT};
use crate::film::metadata::{program, Metadata};
use crate::film::write::{write_image, write_image_with, ImageFormat};
use crate::preview;
use crate::render::{
    render_strategies, render_with, Crop, RenderOptions, RenderStats, StopReason,
    MAX_STRATEGY_LENGTH,
};
use crate::scene::cache::{hex, scene_hash, CacheUse};
use crate::scene::desc::{Display, IntegratorKind, Tonemap};
use crate::scene::{self, Scene};
use crate::{Error, Result};
use clap::Args;
use std::path::PathBuf;
use std::time::{Duration, Instant};

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
    /// Samples per pixel (at most 2^31 - 1).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i32::MAX as i64))]
    pub spp: Option<u32>,
    /// Stop once this many seconds have passed (within one tile's work).
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
    /// Write the image so far after a pass at most this often (the first
    /// pass is always written).
    #[arg(long, value_name = "SECONDS", value_parser = positive_seconds, default_value_t = 10.0)]
    pub checkpoint: f32,
    /// Stop once the estimated mean relative error per pixel falls below
    /// this (e.g. 0.02); the scene's spp no longer caps the render, --spp does.
    #[arg(long, value_name = "X", value_parser = positive_fraction)]
    pub target_noise: Option<f64>,
    /// With --target-noise: tiles whose own noise is below the target take
    /// no more samples (pt and bdpt).
    #[arg(long, requires = "target_noise")]
    pub adaptive: bool,
    /// Render only the pixels X0 <= x < X1, Y0 <= y < Y1.
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_crop)]
    pub crop: Option<Crop>,
    /// Number this render's samples from N on: processes with disjoint
    /// ranges take disjoint samples of the same pixels (for `tracer merge`).
    #[arg(long, value_name = "N", default_value_t = 0,
          value_parser = clap::value_parser!(u32).range(0..=i32::MAX as i64))]
    pub sample_offset: u32,
    /// Show the image in a window as it refines (needs a build with
    /// `--features preview`).
    #[arg(long)]
    pub preview: bool,
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

fn positive_fraction(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("expected a positive number, found {s:?}")),
    }
}

fn parse_crop(s: &str) -> std::result::Result<Crop, String> {
    let v: Vec<u32> = s
        .split(',')
        .map(|p| p.trim().parse::<u32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("expected four whole numbers X0,Y0,X1,Y1, found {s:?}"))?;
    match v[..] {
        [x0, y0, x1, y1] if x0 < x1 && y0 < y1 => Ok(Crop { x0, y0, x1, y1 }),
        [_, _, _, _] => Err(format!("the crop {s:?} is empty: need X0 < X1 and Y0 < Y1")),
        _ => Err(format!(
            "expected four whole numbers X0,Y0,X1,Y1, found {s:?}"
        )),
    }
}

/// The most samples per pixel a render stopped by noise may take.
const UNCAPPED_SPP: u32 = 1 << 30;

/// Loads the scene and applies the command-line overrides; also returns the
/// scene's hash for the output's metadata.
pub fn prepare(args: &RenderArgs) -> Result<(Scene, String)> {
    let desc = scene::parse_file(&args.scene)?;
    let hash = scene_hash(&desc);
    let mut scene = scene::load_desc_cached(desc, args.cache.cache().as_ref())?;
    // Only a mesh that cannot be read leaves no hash, and then the load fails first.
    let hash = hash
        .map(|k| hex(&k))
        .ok_or_else(|| Error::Unsupported(format!("cannot hash {}", args.scene.display())))?;
    let s = &mut scene.settings;
    if let Some(o) = &args.output {
        s.output = o.clone();
    }
    if let Some(i) = args.integrator {
        s.integrator = i;
    }
    if args.target_noise.is_some() {
        s.spp = UNCAPPED_SPP;
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
    if args.bdpt_strategies.is_some() && (args.crop.is_some() || args.sample_offset > 0) {
        return Err(Error::Unsupported(
            "--bdpt-strategies renders the whole image from sample 0: it cannot be combined with --crop or --sample-offset".into(),
        ));
    }
    Ok((scene, hash))
}

/// The metadata of the image after `stats`; `done` is false for a checkpoint.
fn metadata(
    scene: &Scene,
    hash: &str,
    args: &RenderArgs,
    stats: &RenderStats,
    done: bool,
) -> Metadata {
    let s = &scene.settings;
    let crop = args.crop.unwrap_or(Crop::full(s.width, s.height));
    Metadata {
        program: program(),
        scene_hash: hash.to_string(),
        integrator: s.integrator.name().into(),
        seed: s.seed,
        max_depth: s.max_depth,
        width: s.width,
        height: s.height,
        crop: [crop.x0, crop.y0, crop.x1, crop.y1],
        spp: stats.spp,
        max_spp: stats.max_spp,
        samples: vec![(args.sample_offset, stats.spp)],
        render_seconds: stats.seconds,
        passes: stats.passes,
        stopped_by: match stats.stopped_by {
            _ if !done => "in progress",
            StopReason::SampleCount => "spp",
            StopReason::TimeLimit => "time-limit",
            StopReason::TargetNoise => "target-noise",
            StopReason::Interrupted => "interrupted",
        }
        .into(),
        noise: stats.noise,
        pixels_hash: None,
    }
}

/// Renders and writes the image; returns the exit status.
pub fn run_render(args: &RenderArgs) -> Result<i32> {
    let start = Instant::now();
    let (scene, hash) = prepare(args)?;
    for w in &scene.report.warnings {
        eprintln!("warning: {w}");
    }
    if scene.report.degenerate_triangles_dropped > 0 {
        eprintln!(
            "note: dropped {} degenerate (zero-area) triangles",
            scene.report.degenerate_triangles_dropped
        );
    }
    let want_preview = args.preview || scene.display == Some(Display::Window);
    if want_preview && !preview::AVAILABLE {
        if args.preview {
            return Err(Error::Unsupported(
                "--preview needs a build with the preview window: cargo build --release --features preview".into(),
            ));
        }
        eprintln!(
            "note: this T-racer scene asks for a preview window, which this build does not have (build with --features preview); writing {}",
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
    let interrupt = interrupt_flag();
    let options = RenderOptions {
        threads: args.threads.map(|t| t as usize),
        progress: !args.quiet,
        crop: args.crop,
        sample_offset: args.sample_offset,
        target_noise: args.target_noise,
        interrupt: Some(interrupt.clone()),
        adaptive: args.adaptive,
    };
    // Before a window opens or anything is written.
    options.check(&scene.settings)?;
    let s = &scene.settings;
    let mut window = match (want_preview && preview::AVAILABLE)
        .then(|| preview::Preview::open(&scene, options.crop, interrupt.clone()))
    {
        None => None,
        Some(Ok(w)) => Some(w),
        // Asked for on the command line: an error. Asked for by a T-racer
        // scene: the image is what matters.
        Some(Err(e)) if args.preview => return Err(e),
        Some(Err(e)) => {
            eprintln!(
                "warning: {e}; writing {} only",
                scene.settings.output.display()
            );
            None
        }
    };
    let checkpoint = Duration::from_secs_f32(args.checkpoint);
    let mut last_write: Option<Instant> = None;
    let mut checkpoint_error = None;
    let (image, stats) = render_with(&scene, &options, |acc, stats| {
        if let Some(w) = window.as_mut() {
            w.show(&acc.image(), s.tonemap, s.exposure);
        }
        let due = last_write.is_none_or(|t| t.elapsed() >= checkpoint);
        // The final image is written below; a checkpoint after the last pass would be wasted.
        if due && stats.stopped_by == StopReason::SampleCount && stats.spp < s.spp {
            let m = metadata(&scene, &hash, args, stats, false);
            if let Err(e) =
                write_image_with(&s.output, &acc.image(), s.tonemap, s.exposure, Some(&m))
            {
                checkpoint_error.get_or_insert(e);
            }
            last_write = Some(Instant::now());
        }
    })?;
    if let Some(e) = checkpoint_error {
        eprintln!("warning: a checkpoint could not be written: {e}");
    }
    let m = metadata(&scene, &hash, args, &stats, true);
    write_image_with(&s.output, &image, s.tonemap, s.exposure, Some(&m))?;
    let (w, h) = (image.width, image.height);
    let noise = stats
        .noise
        .map_or(String::new(), |n| format!(", noise {n:.4}"));
    eprintln!(
        "wrote {}: {w}x{h}, {} spp, {:.2} s, {:.2} M samples/s{noise}",
        s.output.display(),
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
    match stats.stopped_by {
        StopReason::Interrupted => {
            eprintln!(
                "interrupted after {:.2} s: the image holds {}..{} samples per pixel, each pixel divided by its own count",
                stats.seconds, stats.spp, stats.max_spp
            );
            return Ok(INTERRUPTED_EXIT);
        }
        StopReason::TargetNoise => eprintln!(
            "stopped at the target noise {}",
            args.target_noise.unwrap_or_default()
        ),
        StopReason::TimeLimit => eprintln!("stopped at the time limit"),
        StopReason::SampleCount => {}
    }
    if let Some(dir) = &args.bdpt_strategies {
        // As many samples as the main render took, whatever stopped it.
        let mut scene = scene;
        scene.settings.spp = stats.spp;
        match write_strategies(&scene, &options, dir) {
            Err(Error::Interrupted) => {
                eprintln!("interrupted: the strategy images were not written");
                return Ok(INTERRUPTED_EXIT);
            }
            other => other?,
        }
    }
    if let Some(w) = window.take() {
        eprintln!("showing the result: close the window (or press Ctrl-C) to exit");
        w.wait();
    }
    Ok(0)
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
