//! Square tiles: the unit of parallel work, each owning its pixels' sums.

use crate::film::Image;
use glam::DVec3;

/// Small enough for many tiles per thread (load balance), large enough that
/// per-tile overhead vanishes.
pub const TILE_SIZE: u32 = 16;

pub struct Tile {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
    /// Sum of the samples of each pixel, row-major within the tile.
    sums: Vec<DVec3>,
    pub discarded: u64,
}

impl Tile {
    pub fn pixel_count(&self) -> usize {
        self.sums.len()
    }

    pub fn add(&mut self, x: u32, y: u32, value: DVec3) {
        let w = self.x1 - self.x0;
        self.sums[((y - self.y0) * w + (x - self.x0)) as usize] += value;
    }

    /// Writes the mean of `spp` samples per pixel into `image`.
    pub fn resolve_into(&self, image: &mut Image, spp: u32) {
        let w = self.x1 - self.x0;
        let scale = 1.0 / spp.max(1) as f64;
        for (k, sum) in self.sums.iter().enumerate() {
            let (x, y) = (self.x0 + k as u32 % w, self.y0 + k as u32 / w);
            image.set(x, y, (*sum * scale).as_vec3());
        }
    }
}

/// Covers a `width` × `height` image with tiles, in scanline order.
pub fn split(width: u32, height: u32) -> Vec<Tile> {
    let mut tiles = Vec::new();
    for y0 in (0..height).step_by(TILE_SIZE as usize) {
        for x0 in (0..width).step_by(TILE_SIZE as usize) {
            let (x1, y1) = ((x0 + TILE_SIZE).min(width), (y0 + TILE_SIZE).min(height));
            tiles.push(Tile {
                x0,
                y0,
                x1,
                y1,
                sums: vec![DVec3::ZERO; ((x1 - x0) * (y1 - y0)) as usize],
                discarded: 0,
            });
        }
    }
    tiles
}
