//! One pass: every tile not yet done takes the same run of samples, tiles
//! in parallel, and what they splat is merged in tile order. For an
//! estimator with a light pass (VCM), each sample index is an iteration of
//! its own: the light pass over the whole image first, then the tiles.

use super::progress::Progress;
use super::tiles::{self, Tile};
use super::Accumulation;
use crate::camera::Camera;
use crate::color::is_finite;
use crate::color::Rgb;
use crate::film::Splat;
use crate::integrator::{
    Integrator, LightPass, PixelSample, SampleSink, StrategySample, ThreadState,
};
use crate::scene::Scene;
use glam::DVec3;
use rayon::prelude::*;

/// Tiles per batch for the splatting integrators: bounds the splat lists held
/// at once (a few MB) while leaving enough tiles to keep every thread busy.
const SPLAT_BATCH: usize = 64;

/// Paths per call of [`Integrator::sample_pixels`] (whole pixels, so at
/// least one pixel's samples): enough that lanes seldom wait for the
/// batch's last paths, few enough that the estimates stay in cache.
const LANE_BATCH: usize = 1024;

/// What one tile hands back: its splats and strategy records, per half.
type TileOutput = [(Vec<Splat>, Vec<StrategySample>); 2];

#[derive(Clone, Copy)]
pub(super) struct Pass<'a> {
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    pub integrator: &'a Integrator,
    pub seed: u64,
    /// Samples `first .. first + count` of every pixel.
    pub first: u32,
    pub count: u32,
    pub keep_strategies: bool,
    pub progress: &'a Progress,
}

impl Pass<'_> {
    /// Runs the pass over `acc`'s tiles; a tile for which `skip` says so
    /// (checked as it starts) takes no samples.
    pub fn run(
        &self,
        pool: &rayon::ThreadPool,
        acc: &mut Accumulation,
        skip: &(impl Fn() -> bool + Sync),
    ) {
        if !self.integrator.has_light_pass() {
            self.run_tiles(pool, acc, skip, None);
            return;
        }
        let mut previous = None;
        for index in self.first..self.first + self.count {
            // An iteration not begun is not begun at all: no light paths
            // without the camera paths that need them.
            if skip() {
                return;
            }
            let light = pool.install(|| {
                self.integrator.light_pass(
                    self.scene,
                    self.camera,
                    self.seed,
                    index as u64,
                    previous.take(),
                )
            });
            // Stopped while the light pass ran: drop it, or the image would
            // hold one more iteration of light paths than of camera paths.
            if skip() {
                return;
            }
            if let Some(light) = &light {
                acc.add_light_pass(light, index);
            }
            let iteration = Pass {
                first: index,
                count: 1,
                ..*self
            };
            iteration.run_tiles(pool, acc, skip, light.as_ref());
            previous = light;
        }
    }

    /// Every tile's share of the pass, given the light pass of its one
    /// sample index for an estimator that has one.
    fn run_tiles(
        &self,
        pool: &rayon::ThreadPool,
        acc: &mut Accumulation,
        skip: &(impl Fn() -> bool + Sync),
        light: Option<&LightPass>,
    ) {
        let batch = if acc.splatting {
            SPLAT_BATCH
        } else {
            acc.tiles.len().max(1)
        };
        let mut tiles = std::mem::take(&mut acc.tiles);
        let (first, count) = (self.first, self.count);
        let merge = |acc: &mut Accumulation, done: &[Tile], outputs: Vec<Option<TileOutput>>| {
            for (tile, output) in done.iter().zip(outputs) {
                if let Some(output) = output {
                    acc.add_tile_output(tile, output, first, count);
                }
            }
        };
        pool.install(|| {
            // Each batch's splats are added, in tile order, while the next
            // batch renders: adding them is serial work (0.09 s of a 2.9 s
            // Cornell box `lt` render on two threads, timed; see
            // docs/benchmarks.md), which would otherwise leave every other
            // thread idle, a loss that grows with the thread count.
            let mut pending: Option<(&[Tile], Vec<Option<TileOutput>>)> = None;
            for chunk in tiles.chunks_mut(batch) {
                let mut render = || {
                    // A worker's memory (light vertices, lanes) is made
                    // once per run of tiles rayon hands it, not per tile.
                    chunk
                        .par_iter_mut()
                        .map_init(ThreadState::default, |state, tile| {
                            if skip() || tile.converged {
                                return None;
                            }
                            Some(self.tile(tile, light, state))
                        })
                        .collect::<Vec<_>>()
                };
                let outputs = match pending.take() {
                    Some((done, outputs)) => rayon::join(|| merge(acc, done, outputs), render).1,
                    None => render(),
                };
                pending = Some((chunk, outputs));
            }
            if let Some((done, outputs)) = pending {
                merge(acc, done, outputs);
            }
        });
        acc.tiles = tiles;
    }

    /// Adds this pass's samples to every pixel of `tile`.
    fn tile(
        &self,
        tile: &mut Tile,
        light: Option<&LightPass>,
        state: &mut ThreadState,
    ) -> TileOutput {
        let sink = || SampleSink {
            strategies: self.keep_strategies.then(Vec::new),
            ..SampleSink::default()
        };
        let mut sinks = [sink(), sink()];
        // The lanes record no strategies: a pass that keeps them takes its
        // samples one by one, the same samples.
        if self.integrator.samples_in_lanes() && !self.keep_strategies {
            self.tile_in_lanes(tile, &mut sinks, state, light);
        } else {
            for y in tile.y0..tile.y1 {
                for x in tile.x0..tile.x1 {
                    let mut sums = [DVec3::ZERO; 2];
                    let first = PixelSample::new(x, y, self.first as u64, self.seed);
                    for index in self.first..self.first + self.count {
                        let half = (index % 2) as usize;
                        let pixel = first.with_index(index as u64);
                        let l = self.integrator.sample(
                            self.scene,
                            self.camera,
                            pixel,
                            state,
                            &mut sinks[half],
                            light,
                        );
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
        tile.count_samples(self.first, self.count);
        tile.discarded += sinks[0].discarded + sinks[1].discarded;
        self.progress
            .advance(tile.pixel_count() as u64 * self.count as u64);
        sinks.map(|s| (s.splats, s.strategies.unwrap_or_default()))
    }
}

impl Pass<'_> {
    /// `tile`'s samples of this pass, taken by the integrator a batch of
    /// pixels at a time (see [`Integrator::sample_pixels`]). Out of line,
    /// so that `tile`, where the other integrators' code is inlined, keeps
    /// the shape it had before the lanes (see docs/benchmarks.md, "Paths
    /// in lanes").
    #[inline(never)]
    fn tile_in_lanes(
        &self,
        tile: &mut Tile,
        sinks: &mut [SampleSink; 2],
        state: &mut ThreadState,
        light: Option<&LightPass>,
    ) {
        let (first, count) = (self.first, self.count);
        if count == 0 {
            return;
        }
        let batch = (LANE_BATCH / count as usize).max(1);
        let pixels: Vec<(u32, u32)> = (tile.y0..tile.y1)
            .flat_map(|y| (tile.x0..tile.x1).map(move |x| (x, y)))
            .collect();
        let mut samples = Vec::with_capacity(batch);
        let mut estimates = Vec::new();
        for chunk in pixels.chunks(batch) {
            samples.clear();
            samples.extend(
                chunk
                    .iter()
                    .map(|&(x, y)| PixelSample::new(x, y, first as u64, self.seed)),
            );
            estimates.clear();
            estimates.resize(chunk.len() * count as usize, Rgb::ZERO);
            self.integrator.sample_pixels(
                self.scene,
                self.camera,
                &samples,
                count,
                &mut estimates,
                sinks,
                state,
                light,
            );
            for (&(x, y), pixel) in chunk.iter().zip(estimates.chunks(count as usize)) {
                // As the one-by-one loop in `tile` adds them: the same sums.
                let mut sums = [DVec3::ZERO; 2];
                for (index, &l) in (first..first + count).zip(pixel) {
                    if is_finite(l) {
                        sums[(index % 2) as usize] += l.as_dvec3();
                    } else {
                        tile.discarded += 1;
                    }
                }
                tile.add(x, y, sums);
            }
        }
    }
}

/// Light paths added to each half by `tile` taking samples
/// `first .. first + count`, `per_sample` of them per pixel sample.
pub(super) fn light_paths(tile: &Tile, first: u32, count: u32, per_sample: u64) -> [u64; 2] {
    let n = tile.pixel_count() as u64 * per_sample;
    tiles::halves(first, count).map(|k| n * k as u64)
}
