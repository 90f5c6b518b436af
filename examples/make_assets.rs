//! Generates the project's own assets: the texture `assets/checker.png` and
//! the sky `assets/sky.exr`.
//!
//! The texture is a 256×256, 8×8
//! checkerboard of cream and teal with thin dark grid lines, made so that a
//! texture's orientation can be read off a render:
//!
//! - the cell at the UV origin (u = 0, v = 0: the image's bottom-left corner)
//!   is solid orange;
//! - a red arrow runs from it along +u (the bottom row, pointing right);
//! - a green arrow runs from it along +v (the left column, pointing up).
//!
//! A mirrored mapping shows the arrows in swapped order (red to green is
//! clockwise instead of counter-clockwise); a rotated one moves the orange cell.
//!
//! The sky is a 512×256 latitude–longitude image in linear RGB (half floats,
//! ZIP), the environment of `scenes/sky-materials.json`: blue at the zenith
//! brightening to a hazy horizon, a dim brownish ground below it, and a sun
//! 2.5° in radius, 35° above the horizon, with a soft glow. The sun gives
//! roughly two thirds of the light on a horizontal surface, so shadows are
//! distinct but not black. Rows run from the +y pole (top) to the −y pole;
//! column u looks along (sin 2πu, 0, −cos 2πu), so the middle column is +z.
//!
//! Re-run it with
//! `cargo run --release --example make_assets` (from anywhere in the crate);
//! it overwrites the files, byte for byte the same unless this program changes.

use image::{Rgb, RgbImage};
use std::path::Path;

const SIZE: u32 = 256;
const CELLS: u32 = 8;
const CELL: u32 = SIZE / CELLS;

const CREAM: [u8; 3] = [232, 220, 196];
const TEAL: [u8; 3] = [64, 122, 140];
const GRID: [u8; 3] = [36, 44, 52];
const ORIGIN: [u8; 3] = [236, 150, 40];
const U_AXIS: [u8; 3] = [205, 45, 45];
const V_AXIS: [u8; 3] = [50, 160, 70];

/// Whether a pixel lies on an axis arrow, given its distance in pixels from
/// the UV origin corner along the arrow's axis and across it. The arrow runs
/// down the middle of the first row (or column): a shaft from the origin cell
/// to the last cell, then a triangular head.
fn on_arrow(along: i32, across: i32) -> bool {
    let cell = CELL as i32;
    let centre = cell / 2;
    let offset = (across - centre).abs();
    let head_start = cell * (CELLS as i32 - 1);
    let tip = cell * CELLS as i32 - 6;
    if along >= cell && along < head_start {
        offset <= 3
    } else if along >= head_start && along <= tip {
        // Half-width shrinks linearly from 12 pixels to 0 at the tip.
        let half = 12 * (tip - along) / (tip - head_start);
        offset <= half
    } else {
        false
    }
}

fn texel(x: u32, y: u32) -> [u8; 3] {
    // Pixel coordinates measured from the bottom-left corner (the UV origin).
    let (px, py) = (x as i32, (SIZE - 1 - y) as i32);
    let (cx, cy) = (x / CELL, (SIZE - 1 - y) / CELL);
    let (fx, fy) = (x % CELL, (SIZE - 1 - y) % CELL);

    // Grid lines: one pixel either side of every cell boundary, two at the border.
    let edge = |f: u32| f == 0 || f == CELL - 1;
    let border = x < 2 || y < 2 || x >= SIZE - 2 || y >= SIZE - 2;
    if border || edge(fx) || edge(fy) {
        return GRID;
    }
    if cx == 0 && cy == 0 {
        return ORIGIN;
    }
    if on_arrow(px, py) {
        return U_AXIS;
    }
    if on_arrow(py, px) {
        return V_AXIS;
    }
    if (cx + cy) % 2 == 0 {
        TEAL
    } else {
        CREAM
    }
}

/// Linear radiance of the sky in the direction of pixel (`x`, `y`) of a
/// `width × height` latitude–longitude image.
fn sky(x: usize, y: usize, width: usize, height: usize) -> [f32; 3] {
    use std::f32::consts::PI;
    let theta = PI * (y as f32 + 0.5) / height as f32;
    let phi = 2.0 * PI * (x as f32 + 0.5) / width as f32;
    let d = glam::Vec3::new(
        theta.sin() * phi.sin(),
        theta.cos(),
        -theta.sin() * phi.cos(),
    );
    let elevation = PI / 2.0 - theta;
    let up = elevation.sin().max(0.0).powf(0.45);
    let zenith = glam::Vec3::new(0.18, 0.32, 0.75);
    let horizon = glam::Vec3::new(0.75, 0.82, 0.95);
    let ground = glam::Vec3::new(0.16, 0.14, 0.11);
    let air = horizon + (zenith - horizon) * up;
    // A narrow blend across the horizon, so the image has no hard seam.
    let t = ((elevation + 0.02) / 0.04).clamp(0.0, 1.0);
    let mut rgb = ground + (air - ground) * t;
    let (sun_theta, sun_phi) = (PI / 2.0 - 35f32.to_radians(), 2.0 * PI * 0.62);
    let sun = glam::Vec3::new(
        sun_theta.sin() * sun_phi.sin(),
        sun_theta.cos(),
        -sun_theta.sin() * sun_phi.cos(),
    );
    let angle = d.dot(sun).clamp(-1.0, 1.0).acos();
    if t > 0.0 {
        rgb += glam::Vec3::new(1.0, 0.85, 0.6) * (3.0 * (-angle / 0.12).exp());
    }
    if angle < 2.5f32.to_radians() {
        rgb = glam::Vec3::new(900.0, 820.0, 700.0);
    }
    rgb.to_array()
}

fn write_sky(out: &Path) {
    use exr::prelude::*;
    let (width, height) = (512, 256);
    let channels = SpecificChannels::rgb(|Vec2(x, y)| {
        let [r, g, b] = sky(x, y, width, height);
        (f16::from_f32(r), f16::from_f32(g), f16::from_f32(b))
    });
    Image::from_encoded_channels((width, height), Encoding::SMALL_LOSSLESS, channels)
        .write()
        .to_file(out)
        .expect("cannot write the sky");
    println!("wrote {}", out.display());
}

fn main() {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    std::fs::create_dir_all(&assets).expect("cannot create assets/");
    let out = assets.join("checker.png");
    let image = RgbImage::from_fn(SIZE, SIZE, |x, y| Rgb(texel(x, y)));
    image.save(&out).expect("cannot write the texture");
    println!("wrote {}", out.display());
    write_sky(&assets.join("sky.exr"));
}
