//! Image writers. The format follows the extension: `.exr` and `.pfm` are
//! written linear; `.png` and `.tga` are tone mapped to 8 bits.
//!
//! Every file is encoded in memory, written to a temporary file beside the
//! target, flushed to disk and renamed into place: an interrupted or failed
//! write never leaves a broken image, nor destroys the previous one.

use super::metadata::{pixels_hash, sidecar_path, Metadata};
use super::tonemap::to_8bit;
use super::Image;
use crate::scene::desc::Tonemap;
use crate::{Error, Result};
use std::io::{Cursor, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Exr,
    Pfm,
    Png,
    Tga,
}

impl ImageFormat {
    pub fn from_path(path: &Path) -> Option<ImageFormat> {
        let ext = path.extension()?.to_string_lossy().to_ascii_lowercase();
        Some(match ext.as_str() {
            "exr" => ImageFormat::Exr,
            "pfm" => ImageFormat::Pfm,
            "png" => ImageFormat::Png,
            "tga" => ImageFormat::Tga,
            _ => return None,
        })
    }
}

/// Writes `image` to `path` in the format its extension names.
pub fn write_image(path: &Path, image: &Image, tonemap: Tonemap, exposure: f32) -> Result<()> {
    write_image_with(path, image, tonemap, exposure, None)
}

/// Writes `image` with `metadata`: in the header of an EXR, else in a JSON
/// sidecar beside the image (written first, so an image never lacks it).
pub fn write_image_with(
    path: &Path,
    image: &Image,
    tonemap: Tonemap,
    exposure: f32,
    metadata: Option<&Metadata>,
) -> Result<()> {
    let format = ImageFormat::from_path(path).ok_or_else(|| Error::Image {
        path: path.to_path_buf(),
        message: "unknown image format: use .exr, .pfm, .png or .tga".into(),
    })?;
    let bytes =
        encode(image, format, tonemap, exposure, metadata).map_err(|message| Error::Image {
            path: path.to_path_buf(),
            message,
        })?;
    if let (Some(m), false) = (metadata, format == ImageFormat::Exr) {
        let m = Metadata {
            pixels_hash: Some(pixels_hash(image)),
            ..m.clone()
        };
        let json = serde_json::to_vec_pretty(&m).expect("metadata serialises");
        write_atomic(&sidecar_path(path), &json)?;
    }
    write_atomic(path, &bytes)
}

pub fn encode(
    image: &Image,
    format: ImageFormat,
    tonemap: Tonemap,
    exposure: f32,
    metadata: Option<&Metadata>,
) -> std::result::Result<Vec<u8>, String> {
    match format {
        ImageFormat::Exr => encode_exr(image, metadata),
        ImageFormat::Pfm => Ok(encode_pfm(image)),
        ImageFormat::Png | ImageFormat::Tga => {
            let rgb: Vec<u8> = image
                .pixels
                .iter()
                .flat_map(|&c| to_8bit(c, tonemap, exposure))
                .collect();
            let buffer =
                image::RgbImage::from_raw(image.width, image.height, rgb).expect("size matches");
            let mut out = Cursor::new(Vec::new());
            let f = if format == ImageFormat::Png {
                image::ImageFormat::Png
            } else {
                image::ImageFormat::Tga
            };
            buffer.write_to(&mut out, f).map_err(|e| e.to_string())?;
            Ok(out.into_inner())
        }
    }
}

fn encode_exr(image: &Image, metadata: Option<&Metadata>) -> std::result::Result<Vec<u8>, String> {
    use exr::prelude::*;
    let w = image.width as usize;
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let c = image.pixels[p.y() * w + p.x()];
        (c.x, c.y, c.z)
    });
    let mut attributes = LayerAttributes::default();
    if let Some(m) = metadata {
        attributes.software_name = Some(Text::from(m.program.as_str()));
        for (key, value) in m.exr_attributes() {
            attributes.other.insert(Text::from(key.as_str()), value);
        }
    }
    let layer = Layer::new(
        (w, image.height as usize),
        attributes,
        Encoding::default(),
        channels,
    );
    let exr_image = exr::prelude::Image::from_layer(layer);
    let mut out = Cursor::new(Vec::new());
    exr_image
        .write()
        .to_buffered(&mut out)
        .map_err(|e| e.to_string())?;
    Ok(out.into_inner())
}

/// Portable float map: a text header, then little-endian RGB floats, bottom row first.
fn encode_pfm(image: &Image) -> Vec<u8> {
    let mut out = format!("PF\n{} {}\n-1.0\n", image.width, image.height).into_bytes();
    out.reserve(image.pixels.len() * 12);
    for y in (0..image.height).rev() {
        for x in 0..image.width {
            for v in image.get(x, y).to_array() {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    out
}

/// Writes `bytes` to `path` through a temporary file and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let temp = folder.join(format!(
        ".{name}.{}-{}.tmp",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    in_flight()
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push(temp.clone());
    let result = (|| {
        let mut file = std::fs::File::create(&temp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&temp, path)
    })();
    in_flight()
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .retain(|t| *t != temp);
    result.map_err(|e| {
        let _ = std::fs::remove_file(&temp);
        Error::io(path, e)
    })
}

/// Temporary files being written now.
fn in_flight() -> &'static std::sync::Mutex<Vec<PathBuf>> {
    static IN_FLIGHT: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());
    &IN_FLIGHT
}

/// Removes the temporary files of writes still in progress, for a process
/// about to exit in the middle of one (a second Ctrl-C): the previous
/// image stays, and no half-written temporary file is left beside it.
pub fn remove_writes_in_flight() {
    let temps = std::mem::take(&mut *in_flight().lock().unwrap_or_else(|e| e.into_inner()));
    for t in temps {
        let _ = std::fs::remove_file(t);
    }
}

/// Reads a PFM written by [`write_image`] (or any RGB little-endian PFM).
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
    if data.len() != w as usize * h as usize * 12 {
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
        Some(ImageFormat::Exr) => {
            let (width, height, pixels) =
                crate::scene::texture::read_exr(path).map_err(|message| Error::Image {
                    path: path.to_path_buf(),
                    message,
                })?;
            Ok(Image {
                width: width as u32,
                height: height as u32,
                pixels,
            })
        }
        _ => Err(Error::Image {
            path: path.to_path_buf(),
            message: "not a linear image: use .pfm or .exr".into(),
        }),
    }
}
