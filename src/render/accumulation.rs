//! What a render has gathered so far, and what can be read off it at any
//! moment: the image (each pixel divided by its own sample count, splats
//! by the light paths traced), the noise estimate from the two half
//! images, and which tiles adaptive sampling may stop.

use super::pass::light_paths;
use super::strategies::StrategySums;
use super::{splat_buffers, tiles, traced_area, RenderStats, Tile};
use crate::film::{Image, Splat};
use crate::integrator::{LightPass, StrategySample};
use crate::settings::{Crop, Settings};
use glam::DVec3;

/// Samples a tile takes before adaptive sampling may judge its noise: fewer
/// give too rough an estimate from 256 pixels.
const MIN_ADAPTIVE_SPP: u32 = 16;

/// The relative error estimate of each pixel of the crop, row-major.
pub(super) struct NoiseMap {
    pixels: Vec<f64>,
    width: u32,
}

/// The image's mean relative error: what `--target-noise` compares.
pub(super) fn mean_noise(map: &NoiseMap) -> f64 {
    map.pixels.iter().sum::<f64>() / map.pixels.len().max(1) as f64
}

/// Everything a render has accumulated: the tiles' sums and, for the
/// splatting integrators, the splats' sums over the whole image, each split
/// into the two halves of even and odd sample indices.
pub struct Accumulation {
    pub(super) width: u32,
    pub(super) crop: Crop,
    pub(super) tiles: Vec<Tile>,
    pub(super) splatting: bool,
    pub(super) splat_sums: [Vec<DVec3>; 2],
    /// Light paths traced per half: one per pixel sample taken.
    pub(super) light_paths: [u64; 2],
    /// Light paths the integrator traces per pixel sample.
    pub(super) paths_per_sample: u64,
    /// Whether light paths are traced by a light pass over the whole image
    /// (and counted there) rather than by each tile's samples.
    pub(super) light_pass: bool,
    pub(super) full_pixels: u64,
    /// Each BDPT strategy's share, when kept.
    pub(super) strategies: Option<StrategySums>,
    /// Light-pass splats dropped for being NaN or infinite.
    pub(super) light_pass_discarded: u64,
}

impl Accumulation {
    /// Nothing yet, for a render of `settings` by an integrator that
    /// splats or not; `keep_strategies` keeps each strategy's share apart.
    pub(super) fn new(
        settings: &Settings,
        paths_per_sample: u64,
        light_pass: bool,
        keep_strategies: bool,
    ) -> Accumulation {
        let splatting = paths_per_sample > 0;
        let (width, height) = (settings.film.width, settings.film.height);
        let full_pixels = width as u64 * height as u64;
        Accumulation {
            width,
            crop: settings.crop_or_full(),
            // VCM's camera paths splat nothing: only its light pass, which
            // covers the whole image anyway, lights other pixels.
            tiles: tiles::split(traced_area(settings, splatting && !light_pass)),
            splatting,
            splat_sums: splat_buffers(full_pixels, splatting),
            light_paths: [0, 0],
            paths_per_sample,
            light_pass,
            full_pixels,
            strategies: keep_strategies.then(|| StrategySums::new(full_pixels as usize)),
            light_pass_discarded: 0,
        }
    }

    /// Pixels the tiles cover (all of them for a splatting integrator).
    pub(super) fn traced_pixels(&self) -> u64 {
        self.tiles.iter().map(|t| t.pixel_count() as u64).sum()
    }

    /// Adds what `tile` splatted while taking samples `first .. first + count`.
    pub(super) fn add_tile_output(
        &mut self,
        tile: &Tile,
        halves: [(Vec<Splat>, Vec<StrategySample>); 2],
        first: u32,
        count: u32,
    ) {
        for (h, (splats, _)) in halves.iter().enumerate() {
            for splat in splats {
                self.splat_sums[h][splat.pixel as usize] += splat.value.as_dvec3();
            }
        }
        if self.splatting && !self.light_pass {
            for (paths, n) in self.light_paths.iter_mut().zip(light_paths(
                tile,
                first,
                count,
                self.paths_per_sample,
            )) {
                *paths += n;
            }
        }
        if let Some(sums) = self.strategies.as_mut() {
            for (_, records) in &halves {
                sums.add(records);
            }
        }
    }

    /// Adds the splats of sample `index`'s light pass, one light path per
    /// pixel of the image.
    pub(super) fn add_light_pass(&mut self, pass: &LightPass, index: u32) {
        let half = (index % 2) as usize;
        for splat in pass.splats() {
            self.splat_sums[half][splat.pixel as usize] += splat.value.as_dvec3();
        }
        self.light_paths[half] += self.full_pixels;
        self.light_pass_discarded += pass.discarded();
    }

    /// The image over the crop, each pixel divided by the samples it got.
    pub fn image(&self) -> Image {
        self.image_of(&[0, 1])
    }

    /// The mean over pixels of |A − B| / (A + B + 0.01), A and B the two
    /// half images (channel means): the relative standard error of the
    /// full image, estimated from two independent halves. `None` until
    /// both halves have samples everywhere.
    pub fn noise(&self) -> Option<f64> {
        self.noise_map().as_ref().map(mean_noise)
    }

    /// Each crop pixel's relative error estimate; `None` until both halves
    /// have samples everywhere.
    pub(super) fn noise_map(&self) -> Option<NoiseMap> {
        if self.tiles.iter().any(|t| t.samples.contains(&0)) {
            return None;
        }
        let (a, b) = (self.image_of(&[0]), self.image_of(&[1]));
        let pixels = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .map(|(a, b)| {
                let (a, b) = (a.element_sum() as f64 / 3.0, b.element_sum() as f64 / 3.0);
                (a - b).abs() / (a + b + 0.01)
            })
            .collect();
        Some(NoiseMap {
            pixels,
            width: a.width,
        })
    }

    /// Each tile's mean noise over its pixels in the crop, in tile order
    /// (`None` for tiles outside a crop, traced only for their light paths).
    pub fn tile_noise(&self) -> Option<Vec<Option<f64>>> {
        self.noise_map().map(|map| self.tile_means(&map))
    }

    fn tile_means(&self, map: &NoiseMap) -> Vec<Option<f64>> {
        let crop = self.crop;
        self.tiles
            .iter()
            .map(|tile| {
                let (mut sum, mut n) = (0.0, 0u32);
                for y in tile.y0.max(crop.y0)..tile.y1.min(crop.y1) {
                    for x in tile.x0.max(crop.x0)..tile.x1.min(crop.x1) {
                        sum += map.pixels[((y - crop.y0) * map.width + (x - crop.x0)) as usize];
                        n += 1;
                    }
                }
                (n > 0).then(|| sum / n as f64)
            })
            .collect()
    }

    /// Marks tiles whose own noise is below `target` as converged, so
    /// adaptive sampling gives them no more samples; true once every tile
    /// in the crop is.
    pub(super) fn mark_converged(&mut self, map: &NoiseMap, target: f64) -> bool {
        let means = self.tile_means(map);
        let mut all = true;
        for (tile, noise) in self.tiles.iter_mut().zip(means) {
            let Some(noise) = noise else { continue };
            if !tile.converged && tile.spp() >= MIN_ADAPTIVE_SPP && noise < target {
                tile.converged = true;
            }
            all &= tile.converged;
        }
        all
    }

    fn image_of(&self, halves: &[usize]) -> Image {
        let crop = self.crop;
        let mut image = Image::new(crop.width(), crop.height());
        for tile in &self.tiles {
            let scale = 1.0 / tile.samples_in(halves).max(1) as f64;
            for (x, y, sum) in tile.pixels(halves) {
                if crop.contains(x, y) {
                    image.set(x - crop.x0, y - crop.y0, (sum * scale).as_vec3());
                }
            }
        }
        if self.splatting {
            // Each splat is already divided by the pixel count (one pass of
            // light paths); N paths in all estimate the image as
            // (pixel count / N) times the splats' sum.
            let paths: u64 = halves.iter().map(|&h| self.light_paths[h]).sum();
            let scale = self.full_pixels as f64 / paths.max(1) as f64;
            for y in crop.y0..crop.y1 {
                for x in crop.x0..crop.x1 {
                    let k = (y * self.width + x) as usize;
                    let sum: DVec3 = halves.iter().map(|&h| self.splat_sums[h][k]).sum();
                    let p = image.get(x - crop.x0, y - crop.y0);
                    image.set(x - crop.x0, y - crop.y0, p + (sum * scale).as_vec3());
                }
            }
        }
        image
    }

    pub(super) fn stats(&self, stats: &mut RenderStats) {
        // A splatting integrator's crop receives light from every traced
        // tile, so all of them count; the path tracer's only its own.
        let counted = self
            .tiles
            .iter()
            .filter(|t| self.splatting || self.overlaps_crop(t));
        stats.spp = counted.clone().map(Tile::spp).min().unwrap_or(0);
        stats.max_spp = counted.clone().map(Tile::spp).max().unwrap_or(0);
        stats.samples = counted
            .clone()
            .map(|t| t.spp() as u64 * t.pixel_count() as u64)
            .sum();
        stats.discarded =
            self.tiles.iter().map(|t| t.discarded).sum::<u64>() + self.light_pass_discarded;
    }

    fn overlaps_crop(&self, t: &Tile) -> bool {
        t.x0 < self.crop.x1 && t.x1 > self.crop.x0 && t.y0 < self.crop.y1 && t.y1 > self.crop.y0
    }
}
