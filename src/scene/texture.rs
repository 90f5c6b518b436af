//! Loads texture images: 8-bit and 16-bit images through `image`, decoded from
//! sRGB; EXR through `exr` and Radiance HDR through `image`, both linear.

use crate::color::Rgb;
use crate::material::Texture;
use std::path::Path;

/// Loads `path`; the error is a message for the caller to place at a key path.
pub fn load_texture(path: &Path) -> Result<Texture, String> {
    std::fs::metadata(path).map_err(|e| format!("cannot read texture {}: {e}", path.display()))?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if ext == "exr" {
        return load_exr(path);
    }
    let image = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| format!("cannot read texture {}: {e}", path.display()))?
        .decode()
        .map_err(|e| format!("cannot decode texture {}: {e}", path.display()))?;
    let (w, h) = (image.width() as usize, image.height() as usize);
    let linear_source = matches!(
        image,
        image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
    );
    let texels = if linear_source {
        image
            .to_rgb32f()
            .pixels()
            .map(|p| Rgb::new(p[0], p[1], p[2]))
            .collect()
    } else {
        image
            .to_rgb16()
            .pixels()
            .map(|p| Rgb::new(srgb_decode(p[0]), srgb_decode(p[1]), srgb_decode(p[2])))
            .collect()
    };
    if w == 0 || h == 0 {
        return Err(format!("texture {} is empty", path.display()));
    }
    Ok(Texture::new(w, h, texels))
}

fn srgb_decode(v: u16) -> f32 {
    let c = v as f32 / 65535.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn load_exr(path: &Path) -> Result<Texture, String> {
    let (width, height, texels) = read_exr(path)?;
    Ok(Texture::new(width, height, texels))
}

/// The first RGB(A) layer of an EXR file: width, height and linear texels,
/// top row first.
pub fn read_exr(path: &Path) -> Result<(usize, usize, Vec<Rgb>), String> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |resolution, _| {
            (
                resolution.width(),
                vec![Rgb::ZERO; resolution.width() * resolution.height()],
            )
        },
        |(width, texels), position, (r, g, b, _a): (f32, f32, f32, f32)| {
            texels[position.y() * *width + position.x()] = Rgb::new(r, g, b);
        },
    )
    .map_err(|e| format!("cannot decode {}: {e}", path.display()))?;
    let (width, texels) = image.layer_data.channel_data.pixels;
    let height = texels.len() / width.max(1);
    if width == 0 || height == 0 {
        return Err(format!("image {} is empty", path.display()));
    }
    Ok((width, height, texels))
}
