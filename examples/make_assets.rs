//! Generates the project's own texture, `assets/checker.png`: a 256×256, 8×8
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
//! Re-run it with
//! `cargo run --release --example make_assets` (from anywhere in the crate);
//! it overwrites the file, byte for byte the same unless this program changes.

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

fn main() {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/checker.png");
    let image = RgbImage::from_fn(SIZE, SIZE, |x, y| Rgb(texel(x, y)));
    std::fs::create_dir_all(out.parent().unwrap()).expect("cannot create assets/");
    image.save(&out).expect("cannot write the texture");
    println!("wrote {}", out.display());
}
