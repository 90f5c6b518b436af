//! The image: linear radiance per pixel, tone mapping, and the writers.

pub mod metadata;
pub mod read;
pub mod tonemap;
pub mod write;

use crate::color::Rgb;

/// A linear RGB image, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width, in pixels.
    pub width: u32,
    /// Height, in pixels.
    pub height: u32,
    /// `width × height` pixels, row-major from the top-left.
    pub pixels: Vec<Rgb>,
}

impl Image {
    /// A black image of `width` × `height` pixels.
    pub fn new(width: u32, height: u32) -> Image {
        Image {
            width,
            height,
            pixels: vec![Rgb::ZERO; width as usize * height as usize],
        }
    }

    /// The pixel in column `x`, row `y` from the top; both must be inside the image.
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Sets the pixel in column `x`, row `y` from the top; both must be inside the image.
    pub fn set(&mut self, x: u32, y: u32, c: Rgb) {
        self.pixels[y as usize * self.width as usize + x as usize] = c;
    }

    /// Mean over all pixels, in double precision.
    pub fn mean(&self) -> Rgb {
        let sum = self
            .pixels
            .iter()
            .fold(glam::DVec3::ZERO, |acc, p| acc + p.as_dvec3());
        (sum / self.pixels.len().max(1) as f64).as_vec3()
    }
}

/// Relative mean squared error of `image` against `reference`: the mean over
/// pixels and channels of (image − reference)² / (reference² + 0.01). The
/// 0.01 keeps black pixels from dominating. `None` if the sizes differ.
pub fn relative_mse(image: &Image, reference: &Image) -> Option<f64> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return None;
    }
    let mut sum = 0.0f64;
    for (a, r) in image.pixels.iter().zip(&reference.pixels) {
        for (a, r) in a.to_array().into_iter().zip(r.to_array()) {
            let (a, r) = (a as f64, r as f64);
            sum += (a - r) * (a - r) / (r * r + 0.01);
        }
    }
    Some(sum / (3 * reference.pixels.len().max(1)) as f64)
}

/// A contribution that lands in a pixel chosen by projection (light tracing
/// and BDPT's t = 1 strategy), not in the pixel whose sample made it.
#[derive(Clone, Copy, Debug)]
pub struct Splat {
    /// Row-major pixel index.
    pub pixel: u32,
    /// One light path's contribution; the film scales the sum of splats by
    /// pixel count / light paths traced.
    pub value: Rgb,
}
