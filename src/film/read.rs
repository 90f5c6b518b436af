//! Image readers: linear images (EXR, PFM) with the metadata `tracer` wrote
//! beside them, for `merge` and `compare`; and textures (PNG, JPEG, TGA and
//! 16-bit images decoded from sRGB; EXR and Radiance HDR, linear).

use super::metadata::{pixels_hash, sidecar_path, Metadata};
use super::write::ImageFormat;
use super::Image;
use crate::color::Rgb;
use crate::{Error, Result};
use std::path::Path;

/// Reads a PFM written by [`super::write::write_image`] (or any RGB little-endian PFM).
pub fn read_pfm(path: &Path) -> Result<Image> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let bad = |m: &str| Error::Image {
        path: path.to_path_buf(),
        message: m.to_string(),
    };
    let mut fields = Vec::new();
    let mut start = 0;
    let mut i = 0;
    while fields.len() < 4 && i < bytes.len() {
        if bytes[i].is_ascii_whitespace() {
            if i > start {
                fields.push(String::from_utf8_lossy(&bytes[start..i]).into_owned());
            }
            start = i + 1;
        }
        i += 1;
    }
    if fields.len() < 4 || fields[0] != "PF" {
        return Err(bad("not an RGB PFM file"));
    }
    let w: u32 = fields[1].parse().map_err(|_| bad("bad width"))?;
    let h: u32 = fields[2].parse().map_err(|_| bad("bad height"))?;
    let scale: f32 = fields[3].parse().map_err(|_| bad("bad scale"))?;
    if scale >= 0.0 {
        return Err(bad("big-endian PFM is not supported"));
    }
    let data = &bytes[start..];
    // Checked: 2^31 × 2^31 × 12 wraps to 0, the length of no data at all.
    let expected = (w as usize)
        .checked_mul(h as usize)
        .and_then(|n| n.checked_mul(12));
    if expected != Some(data.len()) {
        return Err(bad("pixel data has the wrong length"));
    }
    let mut image = Image::new(w, h);
    for (k, c) in data.chunks_exact(12).enumerate() {
        let f = |o: usize| f32::from_le_bytes(c[o..o + 4].try_into().unwrap());
        let (x, y) = (k as u32 % w, h - 1 - k as u32 / w);
        image.set(x, y, glam::Vec3::new(f(0), f(4), f(8)));
    }
    Ok(image)
}

/// Reads a linear image and the metadata `tracer` wrote with it (EXR
/// attributes, or a PFM's JSON sidecar).
pub fn read_with_metadata(path: &Path) -> Result<(Image, Metadata)> {
    let bad = |message: String| Error::Image {
        path: path.to_path_buf(),
        message,
    };
    match ImageFormat::from_path(path) {
        Some(ImageFormat::Exr) => {
            use exr::prelude::*;
            check_exr_size(path).map_err(bad)?;
            let image = read()
                .no_deep_data()
                .largest_resolution_level()
                .rgb_channels(
                    |size: Vec2<usize>, _: &RgbChannels| {
                        super::Image::new(size.width() as u32, size.height() as u32)
                    },
                    |image: &mut super::Image, p: Vec2<usize>, (r, g, b): (f32, f32, f32)| {
                        image.set(p.x() as u32, p.y() as u32, glam::Vec3::new(r, g, b))
                    },
                )
                .first_valid_layer()
                .all_attributes()
                .from_file(path)
                .map_err(|e| bad(format!("cannot decode: {e}")))?;
            let layer = image.layer_data;
            let metadata = Metadata::from_exr_attributes(&layer.attributes.other).map_err(bad)?;
            Ok((layer.channel_data.pixels, metadata))
        }
        Some(ImageFormat::Pfm) => {
            let image = read_pfm(path)?;
            let side = sidecar_path(path);
            let text = std::fs::read(&side).map_err(|e| Error::io(&side, e))?;
            let metadata: Metadata = serde_json::from_slice(&text).map_err(|e| Error::Image {
                path: side.clone(),
                message: format!("not tracer metadata: {e}"),
            })?;
            if metadata
                .pixels_hash
                .as_ref()
                .is_some_and(|h| *h != pixels_hash(&image))
            {
                return Err(Error::Image {
                    path: side,
                    message: "describes another version of its image (the pixels' hash differs)"
                        .into(),
                });
            }
            Ok((image, metadata))
        }
        _ => Err(bad(
            "partial renders must be .exr (or .pfm with its .json sidecar)".into(),
        )),
    }
}

/// Reads a linear image written by `tracer` (or any tool): `.pfm` or `.exr`.
pub fn read_linear(path: &Path) -> Result<Image> {
    match ImageFormat::from_path(path) {
        Some(ImageFormat::Pfm) => read_pfm(path),
        Some(ImageFormat::Exr) => read_exr(path).map_err(|message| Error::Image {
            path: path.to_path_buf(),
            message,
        }),
        _ => Err(Error::Image {
            path: path.to_path_buf(),
            message: "not a linear image: use .pfm or .exr".into(),
        }),
    }
}

/// Loads `path`; the error is a message for the caller to place at a key path.
pub fn read_texture(path: &Path) -> std::result::Result<Image, String> {
    crate::files::open_regular(path)
        .map_err(|e| format!("cannot read texture {}: {e}", path.display()))?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if ext == "exr" {
        return read_exr(path);
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
    Ok(Image {
        width: w as u32,
        height: h as u32,
        pixels: texels,
    })
}

fn srgb_decode(v: u16) -> f32 {
    let c = v as f32 / 65535.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Refuses an EXR whose header claims more pixels than any image a render
/// makes ([`crate::settings::MAX_PIXELS`]), before decoding it: the decoder
/// allocates what the header says, and a few damaged bytes can claim
/// terabytes.
fn check_exr_size(path: &Path) -> std::result::Result<(), String> {
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| format!("cannot decode: {e}"))?;
    for header in meta.headers.iter() {
        let (w, h) = (header.layer_size.width(), header.layer_size.height());
        if (w as u64).saturating_mul(h as u64) > crate::settings::MAX_PIXELS {
            return Err(format!(
                "its header claims {w} x {h} pixels, more than the {} an image can have",
                crate::settings::MAX_PIXELS
            ));
        }
    }
    Ok(())
}

/// The first RGB(A) layer of an EXR file, linear, top row first.
fn read_exr(path: &Path) -> std::result::Result<Image, String> {
    use exr::prelude::*;
    check_exr_size(path).map_err(|e| format!("{}: {e}", path.display()))?;
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
    Ok(super::Image {
        width: width as u32,
        height: height as u32,
        pixels: texels,
    })
}
