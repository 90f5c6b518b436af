//! Drives a render: the image is cut into square tiles, and passes over all
//! tiles add samples until the sample count, the time limit or the target
//! noise is reached, or the render is interrupted. Each tile checks the
//! time and the interruption flag before it starts, so a render stops
//! within one tile's work, and each pixel is divided by its own sample count.
//! Tiles are scheduled over rayon, one tile per thread at a time; each tile
//! owns its pixels, so no locks are taken, and a pixel's samples are a pure
//! function of the seed, so the image is the same for any thread count.
//!
//! Integrators that splat (see [`Integrator::splats`]) also add light to
//! pixels other tiles own. Each tile collects its splats in a list of its
//! own, and the lists are added to the image in tile order: no locks in the
//! hot path, and the same sums in the same order for any thread count.
//! Tiles run in batches so the lists stay small.
//!
//! This is the one tile loop: the integrator supplies the per-sample part,
//! and `--bdpt-strategies` is a sink that keeps each strategy's share.

mod accumulation;
mod pass;
mod progress;
mod strategies;
mod tiles;

pub use accumulation::Accumulation;
pub use strategies::{StrategyImages, MAX_STRATEGY_LENGTH};
pub use tiles::{Tile, TILE_SIZE};

use crate::film::Image;
use crate::integrator::Integrator;
use crate::scene::Scene;
use crate::settings::{Crop, Settings};
use crate::{Error, Result};
use glam::DVec3;
use pass::Pass;
use progress::Progress;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How a render runs, as opposed to what it renders ([`Settings`]).
#[derive(Clone, Debug, Default)]
pub struct RenderOptions {
    /// Worker threads; `None` uses one per core.
    pub threads: Option<usize>,
    /// Show a progress bar on stderr (only drawn when stderr is a terminal).
    pub progress: bool,
    /// Set from outside (a signal handler) to stop within a tile's time.
    pub interrupt: Option<Arc<AtomicBool>>,
}

/// What a render took, and why it stopped.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    /// Samples taken per pixel; after an interruption, the fewest any pixel got.
    pub spp: u32,
    /// The most any pixel got (above `spp` after an interruption or an
    /// adaptive render).
    pub max_spp: u32,
    /// Pixel samples taken, over the pixels that count: the crop's tiles, or
    /// every tile for a splatting integrator.
    pub samples: u64,
    /// Samples whose estimate was NaN or infinite, replaced by zero.
    pub discarded: u64,
    /// Wall-clock time of the render, in seconds.
    pub seconds: f64,
    /// Passes run; pass `k` takes 1, 1, 2, 4, … up to 64 samples per pixel.
    pub passes: u32,
    /// The last noise estimate (mean relative error), once there is one.
    pub noise: Option<f64>,
    /// What ended the render.
    pub stopped_by: StopReason,
}

/// What ended a render.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StopReason {
    /// Every pixel got the samples asked for.
    #[default]
    SampleCount,
    /// The time limit passed (the first pass always completes regardless).
    TimeLimit,
    /// The noise estimate fell below the target (adaptively: every tile's did).
    TargetNoise,
    /// The interrupt flag was set, e.g. by Ctrl-C or SIGTERM.
    Interrupted,
}

impl RenderStats {
    /// Pixel samples per wall-clock second.
    pub fn samples_per_second(&self) -> f64 {
        self.samples as f64 / self.seconds.max(1e-9)
    }
}

/// Samples per pixel in pass `k`: 1, 1, 2, 4, … up to 64, so the stopping
/// rules are checked often early on and rarely once the render is under way.
fn pass_size(k: u32) -> u32 {
    1u32 << k.saturating_sub(1).min(6)
}

/// A rayon pool of `threads` workers (`None`: one per core).
pub fn worker_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| Error::Threads(e.to_string()))
}

/// Checks that `settings` can be rendered by their integrator, and builds it
/// with the camera.
fn prepare(settings: &Settings) -> Result<(Integrator, crate::camera::Camera)> {
    settings.check().map_err(|e| Error::Settings(e.message))?;
    let integrator = Integrator::new(settings);
    if settings.stop.adaptive && !integrator.supports_adaptive() {
        let why = if integrator.has_light_pass() {
            "its iterations trace every pixel's light path before any camera path"
        } else {
            "its paths land anywhere"
        };
        return Err(Error::Settings(format!(
            "adaptive sampling needs an integrator whose pixels can stop on their own (pt or bdpt); {}: {why}",
            settings.integrator.name()
        )));
    }
    let camera = settings.camera().ok_or_else(|| {
        Error::Settings(
            "the camera has no direction: position equals look_at, or up is parallel to the view"
                .into(),
        )
    })?;
    Ok((integrator, camera))
}

/// Checks that `settings` describe a render this scene can run, without
/// rendering: what a caller should ask before opening windows or files.
pub fn check(settings: &Settings) -> Result<()> {
    prepare(settings).map(|_| ())
}

/// Renders to the end and returns the image and what it took.
pub fn render(
    scene: &Scene,
    settings: &Settings,
    options: &RenderOptions,
) -> Result<(Image, RenderStats)> {
    render_with(scene, settings, options, |_, _| {})
}

/// Renders in passes until the sample count, the time limit, the target
/// noise or an interruption stops it, calling `after_pass` with what has
/// accumulated after every pass (to write checkpoints or show a preview).
pub fn render_with(
    scene: &Scene,
    settings: &Settings,
    options: &RenderOptions,
    after_pass: impl FnMut(&Accumulation, &RenderStats),
) -> Result<(Image, RenderStats)> {
    let (acc, stats) = run(scene, settings, options, false, after_pass)?;
    Ok((acc.image(), stats))
}

/// Renders with BDPT, its paths capped at [`MAX_STRATEGY_LENGTH`] segments,
/// keeping each connection strategy apart, and returns the images of every
/// strategy that contributed, ordered by path length, then by `s`. Every
/// strategy image divides by one sample count, so a render cut short
/// cannot be normalised: an interruption returns [`Error::Interrupted`].
pub fn render_strategies(
    scene: &Scene,
    settings: &Settings,
    options: &RenderOptions,
) -> Result<Vec<StrategyImages>> {
    let (acc, stats) = run(scene, settings, options, true, |_, _| {})?;
    if stats.stopped_by == StopReason::Interrupted {
        return Err(Error::Interrupted);
    }
    let (width, height) = (settings.film.width, settings.film.height);
    Ok(acc
        .strategies
        .map(|s| s.images(width, height, stats.spp))
        .unwrap_or_default())
}

/// The tile loop behind every render.
fn run(
    scene: &Scene,
    settings: &Settings,
    options: &RenderOptions,
    keep_strategies: bool,
    mut after_pass: impl FnMut(&Accumulation, &RenderStats),
) -> Result<(Accumulation, RenderStats)> {
    let (integrator, camera) = prepare(settings)?;
    let pool = worker_pool(options.threads)?;
    let mut acc = Accumulation::new(
        settings,
        integrator.light_paths_per_sample(),
        integrator.has_light_pass(),
        keep_strategies,
    );
    let total = settings
        .stop
        .target_noise
        .is_none()
        .then(|| acc.traced_pixels() * settings.stop.spp as u64);
    let progress = Progress::new(options.progress, total);
    let start = Instant::now();
    // A limit too large for the clock is no limit.
    let deadline = settings
        .stop
        .time_limit
        .and_then(|t| Duration::try_from_secs_f64(t).ok());
    let interrupted = || {
        options
            .interrupt
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    };
    let past_deadline = || deadline.is_some_and(|d| start.elapsed() >= d);
    let mut stats = RenderStats::default();
    let mut taken = 0u32;

    while taken < settings.stop.spp {
        let first_pass_done = stats.passes > 0;
        let pass = Pass {
            scene,
            camera: &camera,
            integrator: &integrator,
            seed: settings.seed,
            first: settings.sample_offset + taken,
            count: pass_size(stats.passes).min(settings.stop.spp - taken),
            keep_strategies,
            progress: &progress,
        };
        // The first pass always completes under a time limit, so every
        // pixel has a sample; an interruption may cut even that one short.
        let skip = || interrupted() || (first_pass_done && past_deadline());
        pass.run(&pool, &mut acc, &skip);
        taken += pass.count;
        stats.passes += 1;
        stats.seconds = start.elapsed().as_secs_f64();
        acc.stats(&mut stats);
        let converged = check_noise(&mut acc, settings, &mut stats);
        let reason = if interrupted() {
            Some(StopReason::Interrupted)
        } else if past_deadline() {
            Some(StopReason::TimeLimit)
        } else if converged {
            Some(StopReason::TargetNoise)
        } else {
            None
        };
        if let Some(reason) = reason {
            stats.stopped_by = reason;
        }
        after_pass(&acc, &stats);
        if reason.is_some() {
            break;
        }
    }
    progress.finish();
    stats.seconds = start.elapsed().as_secs_f64();
    if stats.noise.is_none() {
        stats.noise = acc.noise();
    }
    Ok((acc, stats))
}

/// Under a target noise: updates the estimate and tells whether the render
/// (or, adaptively, every tile) is below it. Two half images per pass: only
/// worth it when noise decides.
fn check_noise(acc: &mut Accumulation, settings: &Settings, stats: &mut RenderStats) -> bool {
    let Some(target) = settings.stop.target_noise else {
        return false;
    };
    let map = acc.noise_map();
    stats.noise = map.as_ref().map(accumulation::mean_noise);
    match map {
        Some(map) if settings.stop.adaptive => acc.mark_converged(&map, target),
        _ => stats.noise.is_some_and(|noise| noise < target),
    }
}

/// The crop a render's tiles cover: splatting integrators trace the paths
/// of every pixel, so that a crop's pixels receive all their light.
fn traced_area(settings: &Settings, splatting: bool) -> Crop {
    if splatting {
        Crop::full(settings.film.width, settings.film.height)
    } else {
        settings.crop_or_full()
    }
}

/// The splat sums of an image of `pixels` pixels (none without splatting).
fn splat_buffers(pixels: u64, splatting: bool) -> [Vec<DVec3>; 2] {
    let n = if splatting { pixels as usize } else { 0 };
    [vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A splatting render adds each batch of tiles' splats, and counts its
    /// light paths, exactly once, also when batches are added while later
    /// ones render: 10 x 9 tiles of 16 pixels are two batches of 64.
    #[test]
    fn every_batch_of_light_paths_is_counted_once() {
        let (scene, mut settings) =
            crate::scene::load(std::path::Path::new("scenes/cornell-box.json")).unwrap();
        settings.integrator = crate::settings::IntegratorKind::Lt;
        (settings.film.width, settings.film.height) = (160, 144);
        settings.stop.spp = 4;
        settings.stop.time_limit = None;
        for threads in [1, 2] {
            let options = RenderOptions {
                threads: Some(threads),
                progress: false,
                ..RenderOptions::default()
            };
            let (acc, _) = run(&scene, &settings, &options, false, |_, _| {}).unwrap();
            assert_eq!(
                acc.light_paths.iter().sum::<u64>(),
                160 * 144 * 4,
                "{threads} threads"
            );
        }
    }
}
