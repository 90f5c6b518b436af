//! Drives a render: the image is cut into square tiles, and passes over all
//! tiles add samples until the sample count or the time limit is reached.
//! Tiles are scheduled over rayon, one tile per thread at a time; each tile
//! owns its pixels, so no locks are taken, and a pixel's samples are a pure
//! function of the seed, so the image is the same for any thread count.
//!
//! Light tracing and BDPT also splat into pixels other tiles own. Each tile
//! collects its splats in a list of its own, and the lists are added to the
//! image in tile order: no locks in the hot path, and the same sums in the
//! same order for any thread count. Tiles run in batches so the lists stay small.

mod progress;
mod strategies;
mod tiles;

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
use std::time::Instant;

/// Tiles per batch for the splatting integrators: bounds the splat lists held
/// at once (a few MB) while leaving enough tiles to keep every thread busy.
const SPLAT_BATCH: usize = 64;

/// Light paths draw from a sequence of their own, independent of camera paths.
const LIGHT_SEED_DOMAIN: u64 = 0x9e37_79b9_7f4a_7c15;

#[derive(Clone, Debug, Default)]
pub struct RenderOptions {
    /// Worker threads; `None` uses one per core.
    pub threads: Option<usize>,
    /// Show a progress bar on stderr (only drawn when stderr is a terminal).
    pub progress: bool,
}

#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    /// Samples taken per pixel (fewer than asked if the time limit stopped the render).
    pub spp: u32,
    pub samples: u64,
    /// Samples whose estimate was NaN or infinite, replaced by zero.
    pub discarded: u64,
    pub seconds: f64,
    pub passes: u32,
}

impl RenderStats {
    pub fn samples_per_second(&self) -> f64 {
        self.samples as f64 / self.seconds.max(1e-9)
    }
}

/// Samples per pixel in pass `k`: 1, 1, 2, 4, … up to 64, so the time limit is
/// checked often early on and rarely once the render is under way.
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
    let settings = &scene.settings;
    let pool = worker_pool(options.threads)?;
    let (width, height) = (settings.width, settings.height);
    let mut tiles = tiles::split(width, height);
    let pixels = width as u64 * height as u64;
    let progress = Progress::new(options.progress, pixels * settings.spp as u64);
    let start = Instant::now();
    let mut stats = RenderStats::default();
    let splatting = settings.integrator != IntegratorKind::Pt;
    let mut splat_sums = vec![DVec3::ZERO; if splatting { pixels as usize } else { 0 }];
    let batch = if splatting {
        SPLAT_BATCH
    } else {
        tiles.len().max(1)
    };

    while stats.spp < settings.spp {
        let first = stats.spp;
        let count = pass_size(stats.passes).min(settings.spp - first);
        for tiles in tiles.chunks_mut(batch) {
            let lists: Vec<Vec<crate::film::Splat>> = pool.install(|| {
                tiles
                    .par_iter_mut()
                    .map(|tile| {
                        let mut sink = SplatSink::default();
                        render_tile(scene, settings, tile, first, count, &mut sink);
                        tile.discarded += sink.discarded;
                        progress.advance(tile.pixel_count() as u64 * count as u64);
                        sink.splats
                    })
                    .collect()
            });
            for splat in lists.iter().flatten() {
                splat_sums[splat.pixel as usize] += splat.value.as_dvec3();
            }
        }
        stats.spp += count;
        stats.passes += 1;
        if settings
            .time_limit
            .is_some_and(|limit| start.elapsed().as_secs_f32() >= limit)
        {
            break;
        }
    }
    progress.finish();

    stats.seconds = start.elapsed().as_secs_f64();
    stats.samples = pixels * stats.spp as u64;
    stats.discarded = tiles.iter().map(|t| t.discarded).sum();
    let mut image = Image::new(width, height);
    for tile in &tiles {
        tile.resolve_into(&mut image, stats.spp);
    }
    if splatting {
        let scale = 1.0 / stats.spp.max(1) as f64;
        for (pixel, sum) in image.pixels.iter_mut().zip(&splat_sums) {
            *pixel += (*sum * scale).as_vec3();
        }
    }
    Ok((image, stats))
}

/// Adds samples `first .. first + count` to every pixel of `tile`, pushing
/// any splats the integrator makes.
fn render_tile(
    scene: &Scene,
    s: &Settings,
    tile: &mut Tile,
    first: u32,
    count: u32,
    sink: &mut SplatSink,
) {
    let light_seed = s.seed ^ LIGHT_SEED_DOMAIN;
    let mut buffers = bdpt::BdptBuffers::default();
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            let mut sum = glam::DVec3::ZERO;
            for index in first..first + count {
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
                    sum += l.as_dvec3();
                } else {
                    tile.discarded += 1;
                }
            }
            tile.add(x, y, sum);
        }
    }
}
