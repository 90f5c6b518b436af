//! `tracer render`: flags, overrides, progressive passes with checkpoints,
//! interruption, and the report.

use super::cache::CacheArgs;
use super::one_of;
use super::preview;
use super::signals::{interrupt_flag, report_vanished_cache_entries, INTERRUPTED_EXIT};
use clap::Args;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use tracer::film::metadata::{program, Metadata};
use tracer::film::tonemap::Tonemap;
use tracer::film::write::{check_writable, write_image, write_image_with, ImageFormat};
use tracer::format::read_scene;
use tracer::render::{
    render_strategies, render_with, RenderOptions, RenderStats, StopReason, MAX_STRATEGY_LENGTH,
};
use tracer::scene::cache::{hex, scene_hash, CacheUse};
use tracer::scene::{build_limited, Scene};
use tracer::settings::{Crop, Display, IntegratorKind, Setting, Settings};
use tracer::{Error, Result};

/// Flags override the scene's `film` and `render` blocks.
#[derive(Args, Debug, Default)]
pub struct RenderArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Output image; the format follows the extension (.exr, .pfm, .png, .tga).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    #[arg(long, value_parser = one_of(&IntegratorKind::ALL, IntegratorKind::name))]
    pub integrator: Option<IntegratorKind>,
    /// Samples per pixel (at most 2^31 - 1).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i32::MAX as i64))]
    pub spp: Option<u32>,
    /// Stop once this many seconds have passed (within one tile's work).
    #[arg(long, value_parser = positive_seconds)]
    pub time_limit: Option<f64>,
    /// Maximum number of path segments.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub max_depth: Option<u32>,
    /// VCM's merging radius at the first sample, in scene units (default:
    /// 0.003 of the radius of the scene's bounding sphere); it shrinks as
    /// sample^-1/8.
    #[arg(long, value_name = "R", value_parser = positive_length)]
    pub vcm_radius: Option<f32>,
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
    pub checkpoint: f64,
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
    /// Refuse scenes estimated to need more than this much memory (e.g.
    /// `48G`; default: the memory available when the render starts).
    #[arg(long, value_name = "SIZE", value_parser = tracer::scene::cache::parse_size)]
    pub memory_limit: Option<u64>,
    /// Show the image in a window as it refines (needs a build with
    /// `--features preview`).
    #[arg(long)]
    pub preview: bool,
    #[command(flatten)]
    pub cache: CacheArgs,
}

/// A finite length greater than zero.
fn positive_length(s: &str) -> std::result::Result<f32, String> {
    match s.parse::<f32>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("expected a number greater than zero, found {s:?}")),
    }
}

/// Any finite positive number of seconds; one too large for the clock
/// means no limit.
fn positive_seconds(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
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

/// Reads the scene, applies the command-line overrides to its settings,
/// checks them (before any geometry is built), and builds the scene. Also
/// returns the scene's hash for the output's metadata.
pub fn prepare(args: &RenderArgs) -> Result<(Scene, Settings, String)> {
    let mut desc = read_scene(&args.scene)?;
    apply_overrides(&mut desc.settings, args);
    let settings = &desc.settings;
    settings.check().map_err(|e| {
        let flag = match e.setting {
            Setting::ImageSize => "--width/--height: ",
            Setting::Crop => "--crop: ",
            Setting::SampleRange => "--sample-offset: ",
            Setting::Adaptive => "--adaptive: ",
            Setting::VcmRadius => "--vcm-radius: ",
            Setting::Fov | Setting::Camera => "",
        };
        Error::Settings(format!("{flag}{}", e.message))
    })?;
    tracer::render::check(settings)?;
    if ImageFormat::from_path(&settings.film.output).is_none() {
        return Err(Error::Image {
            path: settings.film.output.clone(),
            message: "unknown image format: use .exr, .pfm, .png or .tga".into(),
        });
    }
    refuse_overwriting_scene(&args.scene, &settings.film.output)?;
    // Before any work: an output that cannot be written is found now, not
    // after the render.
    check_writable(&settings.film.output)?;
    if args.bdpt_strategies.is_some() && (args.crop.is_some() || args.sample_offset > 0) {
        return Err(Error::Settings(
            "--bdpt-strategies renders the whole image from sample 0: it cannot be combined with --crop or --sample-offset".into(),
        ));
    }
    let hash = scene_hash(&desc);
    let scene = build_limited(&desc, args.cache.cache().as_ref(), args.memory_limit)?;
    // Only a mesh that cannot be read leaves no hash, and then the build fails first.
    let hash = hash.map(|k| hex(&k)).ok_or_else(|| Error::Data {
        path: args.scene.clone(),
        message: "cannot hash the scene's files".into(),
    })?;
    Ok((scene, desc.settings, hash))
}

/// Refuses an output that is the scene file itself (`-o scene.png` run on
/// a scene named so): the render would replace what the user wrote.
fn refuse_overwriting_scene(scene: &Path, output: &Path) -> Result<()> {
    let same = |a: &Path, b: &Path| match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if same(scene, output) {
        return Err(Error::Settings(format!(
            "the output {} is the scene file itself: choose another output",
            output.display()
        )));
    }
    Ok(())
}

/// Flags override the scene's `film` and `render` blocks.
fn apply_overrides(s: &mut Settings, args: &RenderArgs) {
    if let Some(o) = &args.output {
        s.film.output = o.clone();
    }
    if let Some(i) = args.integrator {
        s.integrator = i;
    }
    if args.target_noise.is_some() {
        s.stop.spp = UNCAPPED_SPP;
    }
    if let Some(n) = args.spp {
        s.stop.spp = n;
    }
    if let Some(t) = args.time_limit {
        s.stop.time_limit = Some(t);
    }
    if let Some(d) = args.max_depth {
        s.max_depth = d;
    }
    if let Some(r) = args.vcm_radius {
        s.vcm_radius = Some(r);
    }
    if let Some(seed) = args.seed {
        s.seed = seed;
    }
    if let Some(w) = args.width {
        s.film.width = w;
    }
    if let Some(h) = args.height {
        s.film.height = h;
    }
    s.stop.target_noise = args.target_noise;
    s.stop.adaptive = args.adaptive;
    s.crop = args.crop;
    s.sample_offset = args.sample_offset;
}

/// The metadata of the image after `stats`; `done` is false for a checkpoint.
fn metadata(s: &Settings, hash: &str, stats: &RenderStats, done: bool) -> Metadata {
    let crop = s.crop_or_full();
    Metadata {
        program: program(),
        scene_hash: hash.to_string(),
        integrator: s.integrator.name().into(),
        vcm_radius: s.vcm_radius.filter(|_| s.integrator == IntegratorKind::Vcm),
        seed: s.seed,
        max_depth: s.max_depth,
        width: s.film.width,
        height: s.film.height,
        crop: [crop.x0, crop.y0, crop.x1, crop.y1],
        spp: stats.spp,
        max_spp: stats.max_spp,
        samples: vec![(s.sample_offset, stats.spp)],
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
    let (scene, settings, hash) = prepare(args)?;
    report_load(&scene, args, start);
    let interrupt = interrupt_flag();
    if scene.report.cache == CacheUse::Hit {
        report_vanished_cache_entries();
    }
    let options = RenderOptions {
        threads: args.threads.map(|t| t as usize),
        progress: !args.quiet,
        interrupt: Some(interrupt.clone()),
    };
    let mut window = open_window(&scene, &settings, args, &interrupt)?;
    let (image, stats) =
        render_with_checkpoints(&scene, &settings, &options, &hash, args, &mut window)?;
    let s = &settings;
    // Interrupted before every pixel had a sample: such an image is mostly
    // black, and worth less than whatever the output held before.
    if stats.stopped_by == StopReason::Interrupted && stats.spp == 0 {
        eprintln!(
            "interrupted before the first pass completed: {} was not written (a previous file there is kept)",
            s.film.output.display()
        );
        return Ok(INTERRUPTED_EXIT);
    }
    let m = metadata(s, &hash, &stats, true);
    write_image_with(
        &s.film.output,
        &image,
        s.film.tonemap,
        s.film.exposure,
        Some(&m),
    )?;
    report_render(s, &image, &stats);
    if stats.stopped_by == StopReason::Interrupted {
        return Ok(INTERRUPTED_EXIT);
    }
    if let Some(dir) = &args.bdpt_strategies {
        // As many samples as the main render took, whatever stopped it.
        match write_strategies(&scene, &settings, stats.spp, &options, dir) {
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

/// Prints what loading found and how long it took.
fn report_load(scene: &Scene, args: &RenderArgs, start: Instant) {
    for w in &scene.report.warnings {
        eprintln!("warning: {w}");
    }
    if scene.report.degenerate_triangles_dropped > 0 {
        eprintln!(
            "note: dropped {} degenerate (zero-area) triangles",
            scene.report.degenerate_triangles_dropped
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
}

/// The preview window, when `--preview` or a T-racer scene asks for one.
fn open_window(
    scene: &Scene,
    settings: &Settings,
    args: &RenderArgs,
    interrupt: &std::sync::Arc<std::sync::atomic::AtomicBool>,
) -> Result<Option<preview::Preview>> {
    let output = settings.film.output.display();
    let want = args.preview || settings.display == Some(Display::Window);
    if !want {
        return Ok(None);
    }
    if !preview::AVAILABLE {
        if args.preview {
            return Err(Error::Preview(
                "--preview needs a build with the preview window: cargo build --release --features preview".into(),
            ));
        }
        eprintln!(
            "note: this T-racer scene asks for a preview window, which this build does not have (build with --features preview); writing {output}"
        );
        return Ok(None);
    }
    match preview::Preview::open(&scene.name, settings.crop_or_full(), interrupt.clone()) {
        Ok(w) => Ok(Some(w)),
        // Asked for on the command line: an error. Asked for by a T-racer
        // scene: the image is what matters.
        Err(e) if args.preview => Err(e),
        Err(e) => {
            eprintln!("warning: {e}; writing {output} only");
            Ok(None)
        }
    }
}

/// Renders, showing each pass in the window and writing the image so far
/// at most every `--checkpoint` seconds.
fn render_with_checkpoints(
    scene: &Scene,
    s: &Settings,
    options: &RenderOptions,
    hash: &str,
    args: &RenderArgs,
    window: &mut Option<preview::Preview>,
) -> Result<(tracer::film::Image, RenderStats)> {
    // A checkpoint interval too long for the clock means only the first.
    let checkpoint = Duration::try_from_secs_f64(args.checkpoint).unwrap_or(Duration::MAX);
    let mut last_write: Option<Instant> = None;
    let mut checkpoint_error = None;
    let result = render_with(scene, s, options, |acc, stats| {
        if let Some(w) = window.as_mut() {
            w.show(&acc.image(), s.film.tonemap, s.film.exposure);
        }
        let due = last_write.is_none_or(|t| t.elapsed() >= checkpoint);
        // The final image is written after; a checkpoint after the last pass would be wasted.
        if due && stats.stopped_by == StopReason::SampleCount && stats.spp < s.stop.spp {
            let m = metadata(s, hash, stats, false);
            let image = acc.image();
            if let Err(e) = write_image_with(
                &s.film.output,
                &image,
                s.film.tonemap,
                s.film.exposure,
                Some(&m),
            ) {
                checkpoint_error.get_or_insert(e);
            }
            last_write = Some(Instant::now());
        }
    })?;
    if let Some(e) = checkpoint_error {
        eprintln!("warning: a checkpoint could not be written: {e}");
    }
    Ok(result)
}

/// Prints what the render took and why it stopped.
fn report_render(s: &Settings, image: &tracer::film::Image, stats: &RenderStats) {
    let (w, h) = (image.width, image.height);
    let noise = stats
        .noise
        .map_or(String::new(), |n| format!(", noise {n:.4}"));
    eprintln!(
        "wrote {}: {w}x{h}, {} spp, {:.2} s, {:.2} M samples/s{noise}",
        s.film.output.display(),
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
        StopReason::Interrupted => eprintln!(
            "interrupted after {:.2} s: the image holds {}..{} samples per pixel, each pixel divided by its own count",
            stats.seconds, stats.spp, stats.max_spp
        ),
        StopReason::TargetNoise => eprintln!(
            "stopped at the target noise {}",
            s.stop.target_noise.unwrap_or_default()
        ),
        StopReason::TimeLimit => eprintln!("stopped at the time limit"),
        StopReason::SampleCount => {}
    }
}

/// Renders BDPT once more with `spp` samples, keeping each strategy apart,
/// and writes `s{S}_t{T}_unweighted.exr` and `s{S}_t{T}_weighted.exr` into `dir`.
fn write_strategies(
    scene: &Scene,
    settings: &Settings,
    spp: u32,
    options: &RenderOptions,
    dir: &Path,
) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let mut s = settings.clone();
    s.integrator = IntegratorKind::Bdpt;
    s.max_depth = s.max_depth.min(MAX_STRATEGY_LENGTH);
    s.stop.spp = spp;
    s.stop.time_limit = None;
    s.stop.target_noise = None;
    s.stop.adaptive = false;
    let images = render_strategies(scene, &s, options)?;
    for i in &images {
        for (kind, image) in [("unweighted", &i.unweighted), ("weighted", &i.weighted)] {
            let path = dir.join(format!("s{}_t{}_{kind}.exr", i.s, i.t));
            write_image(&path, image, Tonemap::Clamp, 0.0)?;
        }
    }
    eprintln!(
        "wrote {} strategy images (paths up to {} segments) to {}",
        2 * images.len(),
        s.max_depth,
        dir.display()
    );
    Ok(())
}
