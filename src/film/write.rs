//! Image writers. The format follows the extension: `.exr` and `.pfm` are
//! written linear; `.png` and `.tga` are tone mapped to 8 bits.
//!
//! Every file is encoded in memory, written to a temporary file beside the
//! target, flushed to disk and renamed into place: an interrupted or failed
//! write never leaves a broken image, nor destroys the previous one.

use super::metadata::{pixels_hash, sidecar_path, Metadata};
use super::tonemap::to_8bit;
use super::tonemap::Tonemap;
use super::Image;
use crate::{Error, Result};
use std::io::{Cursor, Write};
use std::path::{Path, PathBuf};

/// An image file format, named by its extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// OpenEXR: linear 32-bit float channels, with the metadata in its header.
    Exr,
    /// Portable float map: linear 32-bit floats, metadata in a sidecar.
    Pfm,
    /// PNG: tone mapped to 8 bits, metadata in a sidecar.
    Png,
    /// TGA: tone mapped to 8 bits, metadata in a sidecar.
    Tga,
}

impl ImageFormat {
    /// The format `path`'s extension names (any case); `None` for other extensions.
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
/// sidecar beside the image. Both are written to temporary files first, so
/// a failure replaces neither.
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
    let image_file = Staged::new(path, &bytes)?;
    // The sidecar is staged before either file replaces its old version:
    // where the disk is full or the folder unwritable, both fail together
    // and neither old file is touched.
    let sidecar = match (metadata, format == ImageFormat::Exr) {
        (Some(m), false) => {
            let m = Metadata {
                pixels_hash: Some(pixels_hash(image)),
                ..m.clone()
            };
            let json = serde_json::to_vec_pretty(&m).map_err(|e| Error::Image {
                path: sidecar_path(path),
                message: format!("cannot encode metadata: {e}"),
            })?;
            Some(Staged::new(&sidecar_path(path), &json)?)
        }
        _ => None,
    };
    image_file.commit()?;
    // A sidecar left over from an earlier image describes other pixels;
    // readers compare the pixels' hash, so a failure here cannot mislead.
    match sidecar {
        Some(s) => s.commit(),
        None => Ok(()),
    }
}

/// The bytes of the image file, with `metadata` in the header of an EXR
/// (other formats' metadata goes in a sidecar, see [`write_image_with`]);
/// `tonemap` and `exposure` apply only to PNG and TGA.
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
    Staged::new(path, bytes)?.commit()
}

/// Checks that `path` can be written, by creating (and removing) a
/// temporary file beside it: a render can refuse an unwritable output
/// before it starts, not after it has finished.
pub fn check_writable(path: &Path) -> Result<()> {
    Staged::new(path, &[]).map(|_| ())
}

/// Bytes written to a temporary file beside their destination, flushed to
/// disk, waiting to be renamed into place. The temporary file has a random
/// name and is created exclusively (`O_CREAT | O_EXCL`), so a file or a
/// symbolic link planted beside the output can never be written through.
/// Dropped without [`Staged::commit`], it is removed.
struct Staged {
    /// `None` once committed.
    file: Option<tempfile::NamedTempFile>,
    target: PathBuf,
}

impl Staged {
    fn new(path: &Path, bytes: &[u8]) -> Result<Staged> {
        let folder = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        let prefix = format!(".{name}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        // As a plainly created file would be (the umask applies), not 0600.
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        let mut file = builder
            .tempfile_in(&folder)
            .map_err(|e| Error::io(path, e))?;
        in_flight()
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(file.path().to_path_buf());
        let written = file
            .write_all(bytes)
            .and_then(|()| file.as_file().sync_all());
        if let Err(e) = written {
            forget_in_flight(file.path());
            return Err(Error::io(path, e));
        }
        Ok(Staged {
            file: Some(file),
            target: path.to_path_buf(),
        })
    }

    /// Renames the file into place.
    fn commit(mut self) -> Result<()> {
        let Some(file) = self.file.take() else {
            return Ok(());
        };
        let temp = file.path().to_path_buf();
        let result = file.persist(&self.target);
        forget_in_flight(&temp);
        result
            .map(|_| ())
            .map_err(|e| Error::io(&self.target, e.error))
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(file) = &self.file {
            forget_in_flight(file.path());
        }
    }
}

fn forget_in_flight(temp: &Path) {
    in_flight()
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .retain(|t| t != temp);
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
