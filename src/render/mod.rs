//! Drives a render: the image is cut into square tiles, and passes over all
//! tiles add samples until the sample count, the time limit or the target
//! noise is reached, or the render is interrupted. Each tile checks the
//! time and the interruption flag before it starts, so a render stops
//! within one tile's work, and each pixel is divided by its own sample count.
//! Tiles are scheduled over rayon, one tile per thread at a time; each tile
//! owns its pixels, so no locks are taken, and a pixel's samples are a pure
//! function of the seed, so the image is the same for any thread count.
//!
//! Light tracing and BDPT also splat into pixels other tiles own. Each tile
//! collects its splats in a list of its own, and the lists are added to the
//! image in tile order: no locks in the hot path, and the same sums in the
//! same order for any thread count. Tiles run in batches so the lists stay small.

mod accumulation;
mod progress;
mod strategies;
mod tiles;

pub use accumulation::Accumulation;
pub use strategies::{render_strategies, StrategyImages, MAX_STRATEGY_LENGTH};

pub use tiles::{Tile, TILE_SIZE};

use crate::color::{is_finite, Rgb};
use crate::film::Image;
use crate::integrator::subpath::SplatSink;
use crate::integrator::{bdpt, lt, pt};
use crate::sampling::Sampler;
use crate::scene::desc::IntegratorKind;
use crate::scene::{Scene, Settings};
use crate::{Error, Result};
use glam::DVec3;
use progress::Progress;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Tiles per batch for the splatting integrators: bounds the splat lists held
/// at once (a few MB) while leaving enough tiles to keep every thread busy.
const SPLAT_BATCH: usize = 64;

/// Light paths draw from a sequence of their own, independent of camera paths.
const LIGHT_SEED_DOMAIN: u64 = 0x9e37_79b9_7f4a_7c15;

/// A rectangle of pixels, `x0 .. x1` by `y0 .. y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crop {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Crop {
    pub fn full(width: u32, height: u32) -> Crop {
        Crop {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }
}

#[derive(Clone, Debug, Default)]
pub struct RenderOptions {
    /// Worker threads; `None` uses one per core.
    pub threads: Option<usize>,
    /// Show a progress bar on stderr (only drawn when stderr is a terminal).
    pub progress: bool,
    /// Render only these pixels; the image returned covers just them.
    pub crop: Option<Crop>,
    /// Every pixel's samples are numbered from here, so processes given
    /// disjoint ranges take disjoint samples of the same pixels.
    pub sample_offset: u32,
    /// Stop once the estimated mean relative error falls below this.
    pub target_noise: Option<f64>,
    /// Set from outside (a signal handler) to stop within a tile's time.
    pub interrupt: Option<Arc<AtomicBool>>,
    /// With `target_noise`: a tile whose own noise falls below the target
    /// takes no more samples, so the time goes where the noise is, and the
    /// render stops once every tile is below it (a stricter rule than the
    /// image's mean).
    pub adaptive: bool,
}

#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    /// Samples taken per pixel; after an interruption, the fewest any pixel got.
    pub spp: u32,
    /// The most any pixel got (above `spp` after an interruption or an
    /// adaptive render).
    pub max_spp: u32,
    pub samples: u64,
    /// Samples whose estimate was NaN or infinite, replaced by zero.
    pub discarded: u64,
    pub seconds: f64,
    pub passes: u32,
    /// The last noise estimate (mean relative error), once there is one.
    pub noise: Option<f64>,
    pub stopped_by: StopReason,
}

/// What ended a render.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StopReason {
    #[default]
    SampleCount,
    TimeLimit,
    TargetNoise,
    Interrupted,
}

impl RenderOptions {
    /// Whether these options can render `settings`: a crop inside the
    /// image, sample indices that fit in 32 bits, adaptive sampling only
    /// with a target and an integrator that has per-pixel samples.
    pub fn check(&self, settings: &Settings) -> Result<()> {
        let (width, height) = (settings.width, settings.height);
        if let Some(c) = self.crop {
            if c.x0 >= c.x1 || c.y0 >= c.y1 || c.x1 > width || c.y1 > height {
                return Err(Error::Unsupported(format!(
                    "crop {},{},{},{} is not a non-empty part of the {width}x{height} image",
                    c.x0, c.y0, c.x1, c.y1
                )));
            }
        }
        if self.sample_offset.checked_add(settings.spp).is_none() {
            return Err(Error::Unsupported(format!(
                "sample offset {} plus {} samples per pixel exceeds 2^32",
                self.sample_offset, settings.spp
            )));
        }
        if self.adaptive
            && (self.target_noise.is_none() || settings.integrator == IntegratorKind::Lt)
        {
            return Err(Error::Unsupported(
                "adaptive sampling needs a target noise, and an integrator with per-pixel samples (pt or bdpt; a light path lands anywhere)".into(),
            ));
        }
        Ok(())
    }
}

impl RenderStats {
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
        .map_err(|e| Error::Unsupported(format!("cannot start worker threads: {e}")))
}

pub fn render(scene: &Scene, options: &RenderOptions) -> Result<(Image, RenderStats)> {
    render_with(scene, options, |_, _| {})
}

/// Renders in passes until the sample count, the time limit, the target
/// noise or an interruption stops it, calling `after_pass` with what has
/// accumulated after every pass (to write checkpoints or show a preview).
pub fn render_with(
    scene: &Scene,
    options: &RenderOptions,
    mut after_pass: impl FnMut(&Accumulation, &RenderStats),
) -> Result<(Image, RenderStats)> {
    let settings = &scene.settings;
    let pool = worker_pool(options.threads)?;
    let (width, height) = (settings.width, settings.height);
    options.check(settings)?;
    let full = Crop::full(width, height);
    let crop = options.crop.unwrap_or(full);
    let splatting = settings.integrator != IntegratorKind::Pt;
    // Light paths land anywhere: a splatting integrator traces the paths of
    // every pixel, so that a crop's pixels receive all their light.
    let traced = if splatting { full } else { crop };
    let full_pixels = width as u64 * height as u64;
    let splat_len = if splatting { full_pixels as usize } else { 0 };
    let mut acc = Accumulation {
        width,
        crop,
        tiles: tiles::split(traced),
        splatting,
        splat_sums: [vec![DVec3::ZERO; splat_len], vec![DVec3::ZERO; splat_len]],
        light_paths: [0, 0],
        full_pixels,
    };
    let traced_pixels = traced.width() as u64 * traced.height() as u64;
    let total = options
        .target_noise
        .is_none()
        .then(|| traced_pixels * settings.spp as u64);
    let progress = Progress::new(options.progress, total);
    let start = Instant::now();
    let deadline = settings.time_limit.map(Duration::from_secs_f32);
    let interrupted = || {
        options
            .interrupt
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    };
    let past_deadline = || deadline.is_some_and(|d| start.elapsed() >= d);
    let batch = if splatting {
        SPLAT_BATCH
    } else {
        acc.tiles.len().max(1)
    };
    let mut stats = RenderStats::default();
    let mut taken = 0u32;

    while taken < settings.spp {
        let first_pass_done = stats.passes > 0;
        let first = options.sample_offset + taken;
        let count = pass_size(stats.passes).min(settings.spp - taken);
        for tiles in acc.tiles.chunks_mut(batch) {
            let lists: Vec<Option<[Vec<crate::film::Splat>; 2]>> = pool.install(|| {
                tiles
                    .par_iter_mut()
                    .map(|tile| {
                        // The first pass always completes under a time
                        // limit, so every pixel has a sample; an
                        // interruption may cut even that one short.
                        if interrupted() || (first_pass_done && past_deadline()) || tile.converged {
                            return None;
                        }
                        let mut sinks = [SplatSink::default(), SplatSink::default()];
                        render_tile(scene, settings, tile, first, count, &mut sinks);
                        tile.count_samples(first, count);
                        tile.discarded += sinks[0].discarded + sinks[1].discarded;
                        progress.advance(tile.pixel_count() as u64 * count as u64);
                        let [a, b] = sinks;
                        Some([a.splats, b.splats])
                    })
                    .collect()
            });
            for (tile, list) in tiles.iter().zip(&lists) {
                let Some(halves) = list else { continue };
                for (h, splats) in halves.iter().enumerate() {
                    for splat in splats {
                        acc.splat_sums[h][splat.pixel as usize] += splat.value.as_dvec3();
                    }
                }
                if splatting {
                    let n = tile.pixel_count() as u64;
                    for (paths, k) in acc.light_paths.iter_mut().zip(tiles::halves(first, count)) {
                        *paths += n * k as u64;
                    }
                }
            }
        }
        taken += count;
        stats.passes += 1;
        stats.seconds = start.elapsed().as_secs_f64();
        acc.stats(&mut stats);
        // Two half images per pass: only worth it when noise decides.
        let mut converged = false;
        if let Some(target) = options.target_noise {
            let map = acc.noise_map();
            stats.noise = map.as_ref().map(accumulation::mean_noise);
            converged = match map {
                Some(map) if options.adaptive => acc.mark_converged(&map, target),
                _ => stats.noise.is_some_and(|noise| noise < target),
            };
        }
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
    Ok((acc.image(), stats))
}

/// Adds samples `first .. first + count` to every pixel of `tile`, pushing
/// any splats the integrator makes.
fn render_tile(
    scene: &Scene,
    s: &Settings,
    tile: &mut Tile,
    first: u32,
    count: u32,
    sinks: &mut [SplatSink; 2],
) {
    let light_seed = s.seed ^ LIGHT_SEED_DOMAIN;
    let mut buffers = bdpt::BdptBuffers::default();
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            let mut sums = [DVec3::ZERO; 2];
            for index in first..first + count {
                let half = (index % 2) as usize;
                let sink = &mut sinks[half];
                let index = index as u64;
                let l: Rgb = match s.integrator {
                    IntegratorKind::Pt => {
                        let mut sampler = Sampler::new(s.seed, x, y, index);
                        let (jx, jy) = sampler.next_2d();
                        let ray = scene.camera.ray(x as f32 + jx, y as f32 + jy);
                        pt::radiance(scene, ray, &mut sampler, s.max_depth)
                    }
                    IntegratorKind::Lt => {
                        let mut sampler = Sampler::new(light_seed, x, y, index);
                        lt::sample(scene, &mut sampler, s.max_depth, sink);
                        Rgb::ZERO
                    }
                    IntegratorKind::Bdpt => {
                        let mut camera = Sampler::new(s.seed, x, y, index);
                        let mut light = Sampler::new(light_seed, x, y, index);
                        let (jx, jy) = camera.next_2d();
                        bdpt::sample(
                            scene,
                            x as f32 + jx,
                            y as f32 + jy,
                            &mut camera,
                            &mut light,
                            s.max_depth,
                            &mut buffers,
                            sink,
                        )
                    }
                };
                if is_finite(l) {
                    sums[half] += l.as_dvec3();
                } else {
                    tile.discarded += 1;
                }
            }
            tile.add(x, y, sums);
        }
    }
}
