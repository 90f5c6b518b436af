//! Image textures: linear RGB texels looked up by UV with bilinear filtering
//! and repeat wrapping. UV (0, 0) is the bottom-left of the image, as in OBJ.

use crate::color::Rgb;
use glam::Vec2;

/// An RGB image sampled by texture coordinates.
#[derive(Clone, Debug)]
pub struct Texture {
    width: usize,
    height: usize,
    /// Linear RGB, row 0 at the top of the image.
    texels: Vec<Rgb>,
}

impl Texture {
    /// `texels` holds `width × height` linear colours, top row first.
    pub fn new(width: usize, height: usize, texels: Vec<Rgb>) -> Texture {
        assert!(width > 0 && height > 0 && texels.len() == width * height);
        Texture {
            width,
            height,
            texels,
        }
    }

    /// Width and height, in texels.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The mean texel.
    pub fn mean(&self) -> Rgb {
        let sum = self
            .texels
            .iter()
            .fold(glam::DVec3::ZERO, |acc, t| acc + t.as_dvec3());
        (sum / self.texels.len() as f64).as_vec3()
    }

    fn texel(&self, x: i64, y: i64) -> Rgb {
        let x = x.rem_euclid(self.width as i64) as usize;
        let y = y.rem_euclid(self.height as i64) as usize;
        self.texels[y * self.width + x]
    }

    /// The bilinearly filtered colour at `uv`, wrapping outside [0, 1); (0, 0)
    /// is the bottom-left corner. A non-finite `uv` gives the top-left texel.
    pub fn lookup(&self, uv: Vec2) -> Rgb {
        // Texel centres sit at half-integers.
        let x = uv.x * self.width as f32 - 0.5;
        let y = (1.0 - uv.y) * self.height as f32 - 0.5;
        if !x.is_finite() || !y.is_finite() {
            return self.texels[0];
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0) * (1.0 - fx) + self.texel(x0 + 1, y0) * fx;
        let bottom = self.texel(x0, y0 + 1) * (1.0 - fx) + self.texel(x0 + 1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bottom_left_is_uv_origin_and_wraps() {
        let t = Texture::new(2, 2, vec![Rgb::X, Rgb::Y, Rgb::Z, Rgb::ONE]);
        // Exactly at a texel centre there is no blending.
        assert_eq!(t.lookup(Vec2::new(0.25, 0.25)), Rgb::Z, "bottom-left texel");
        assert_eq!(t.lookup(Vec2::new(0.75, 0.75)), Rgb::Y, "top-right texel");
        assert_eq!(t.lookup(Vec2::new(1.25, 3.25)), Rgb::Z, "repeat wrapping");
    }
}
