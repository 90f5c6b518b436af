//! Square tiles: the unit of parallel work, each owning its pixels' sums.
//!
//! A tile keeps two sums per pixel, of its even- and odd-numbered samples:
//! two independent half images, whose difference estimates the noise
//! (`--target-noise`). Tiles count their own samples, so a render stopped
//! in the middle of a pass divides each pixel by the samples it received.

use crate::settings::Crop;
use glam::DVec3;

/// Small enough for many tiles per thread (load balance), large enough that
/// per-tile overhead vanishes.
pub const TILE_SIZE: u32 = 16;

/// A rectangle of pixels, `x0 .. x1` by `y0 .. y1` in image coordinates,
/// and the sums of the samples its pixels received.
pub struct Tile {
    /// Left edge (inclusive), in pixels.
    pub x0: u32,
    /// Top edge (inclusive), in pixels from the top.
    pub y0: u32,
    /// Right edge (exclusive).
    pub x1: u32,
    /// Bottom edge (exclusive).
    pub y1: u32,
    /// Per half (even, odd sample indices), the sum of each pixel's
    /// samples, row-major within the tile.
    sums: [Vec<DVec3>; 2],
    /// Samples each pixel of this tile has received, per half.
    pub samples: [u32; 2],
    /// Samples whose estimate was NaN or infinite, counted as zero.
    pub discarded: u64,
    /// Adaptive sampling judged this tile's noise low enough: no more samples.
    pub converged: bool,
}

impl Tile {
    /// Pixels in the tile.
    pub fn pixel_count(&self) -> usize {
        self.sums[0].len()
    }

    /// Samples each pixel has received, both halves together.
    pub fn spp(&self) -> u32 {
        self.samples[0] + self.samples[1]
    }

    /// Adds one pixel's sums of a run of samples, split by half.
    pub fn add(&mut self, x: u32, y: u32, halves: [DVec3; 2]) {
        let w = self.x1 - self.x0;
        let k = ((y - self.y0) * w + (x - self.x0)) as usize;
        self.sums[0][k] += halves[0];
        self.sums[1][k] += halves[1];
    }

    /// Records that samples `first .. first + count` were added to every pixel.
    pub fn count_samples(&mut self, first: u32, count: u32) {
        let [even, odd] = halves(first, count);
        self.samples[0] += even;
        self.samples[1] += odd;
    }

    /// Each pixel's sum over `halves` (both, or one), with (x, y) in image
    /// coordinates; [`Tile::samples_in`] tells how many samples the sums hold.
    pub fn pixels<'a>(
        &'a self,
        halves: &'a [usize],
    ) -> impl Iterator<Item = (u32, u32, DVec3)> + 'a {
        let w = self.x1 - self.x0;
        (0..self.pixel_count()).map(move |k| {
            let sum = halves.iter().map(|&h| self.sums[h][k]).sum();
            (self.x0 + k as u32 % w, self.y0 + k as u32 / w, sum)
        })
    }

    /// Samples each pixel holds in `halves` (0: even sample indices, 1: odd).
    pub fn samples_in(&self, halves: &[usize]) -> u32 {
        halves.iter().map(|&h| self.samples[h]).sum()
    }
}

/// How many of the sample indices `first .. first + count` are even, and
/// how many odd: the two halves they go to.
pub fn halves(first: u32, count: u32) -> [u32; 2] {
    let (first, end) = (first as u64, first as u64 + count as u64);
    let odd = (end / 2 - first / 2) as u32;
    [count - odd, odd]
}

/// Covers `area` with tiles, in scanline order. Tiles start on multiples of
/// [`TILE_SIZE`] relative to the area's corner.
pub fn split(area: Crop) -> Vec<Tile> {
    let mut tiles = Vec::new();
    for y0 in (area.y0..area.y1).step_by(TILE_SIZE as usize) {
        for x0 in (area.x0..area.x1).step_by(TILE_SIZE as usize) {
            let (x1, y1) = ((x0 + TILE_SIZE).min(area.x1), (y0 + TILE_SIZE).min(area.y1));
            let n = ((x1 - x0) * (y1 - y0)) as usize;
            tiles.push(Tile {
                x0,
                y0,
                x1,
                y1,
                sums: [vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]],
                samples: [0, 0],
                discarded: 0,
                converged: false,
            });
        }
    }
    tiles
}

#[cfg(test)]
mod tests {
    use super::halves;

    #[test]
    fn halves_count_even_and_odd_indices() {
        for first in 0..9u32 {
            for count in 0..9u32 {
                let odd = (first..first + count).filter(|i| i % 2 == 1).count() as u32;
                assert_eq!(halves(first, count), [count - odd, odd], "{first}+{count}");
            }
        }
        assert_eq!(halves(u32::MAX - 1, 1), [1, 0]);
        assert_eq!(halves(u32::MAX, 1), [0, 1]);
    }
}
