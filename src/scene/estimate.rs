//! How much memory a render will need, worked out from the description
//! before anything is built, so that a scene asking for more than the
//! machine has is refused with a message instead of aborting part way
//! (a 12 KB scene of 100 finely divided spheres asks for 2 billion
//! triangles).

use crate::files::open_regular;
use crate::format::desc::{SceneDesc, ShapeDesc};
use crate::settings::{IntegratorKind, Settings};
use crate::{Error, Result};
use std::io::{BufRead, BufReader};

/// Peak bytes per triangle while building and rendering: positions,
/// shading records, the BVH and its build's scratch. Measured with
/// `/usr/bin/time -v tracer render` on the Stanford dragon (871,308
/// triangles): 213 MB resident at the peak, 245 bytes per triangle.
pub const BYTES_PER_TRIANGLE: u64 = 256;

/// Bytes per pixel of the film: two half sums per pixel in its tile, two
/// splat sums, the image and its encoded copy.
pub const BYTES_PER_PIXEL: u64 = 160;

/// Bytes per pixel that VCM adds: an iteration keeps every light vertex of
/// one light path per pixel, 280 bytes each with the merge grid's copy.
/// The bundled Cornell box (albedo up to 0.89, depth 16) averages 5.4
/// vertices per path; eight covers brighter scenes.
pub const VCM_BYTES_PER_PIXEL: u64 = 8 * 280;

/// What a render of a scene will need.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Estimate {
    /// Triangles the objects will make (an upper bound for OBJ meshes:
    /// degenerate faces are dropped later).
    pub triangles: u64,
    /// Pixels of the full image.
    pub pixels: u64,
    /// Bytes in all.
    pub bytes: u64,
}

/// Estimates a render of `desc` with `settings`. Mesh files are scanned for
/// their faces (a fast pass over the bytes, no parsing of numbers); one
/// that cannot be read counts as empty, and building it reports the error.
pub fn estimate(desc: &SceneDesc, settings: &Settings) -> Estimate {
    let triangles = desc
        .objects
        .iter()
        .map(|o| shape_triangles(&o.shape))
        .fold(0u64, u64::saturating_add);
    with_triangles(triangles, settings)
}

fn shape_triangles(shape: &ShapeDesc) -> u64 {
    match shape {
        ShapeDesc::Quad => 2,
        ShapeDesc::Cube => 12,
        // 20 faces, each divided into four per level.
        ShapeDesc::Sphere { subdivisions, .. } => {
            20u64.saturating_mul(4u64.saturating_pow(*subdivisions))
        }
        ShapeDesc::Triangles {
            positions, indices, ..
        } => indices.as_ref().map_or(positions.len(), Vec::len) as u64 / 3,
        ShapeDesc::Mesh { file, .. } => obj_triangles(file).unwrap_or(0),
    }
}

/// Triangles an OBJ file's faces make: a face of n vertices becomes n − 2.
fn obj_triangles(path: &std::path::Path) -> std::io::Result<u64> {
    let mut reader = BufReader::with_capacity(1 << 20, open_regular(path)?);
    let mut line = Vec::new();
    let mut triangles = 0u64;
    loop {
        line.clear();
        if reader.read_until(b'\n', &mut line)? == 0 {
            return Ok(triangles);
        }
        let text = line.trim_ascii_start();
        if let Some(rest) = text.strip_prefix(b"f") {
            if rest.first().is_some_and(u8::is_ascii_whitespace) {
                let vertices = rest
                    .split(u8::is_ascii_whitespace)
                    .filter(|t| !t.is_empty())
                    .count() as u64;
                triangles += vertices.saturating_sub(2);
            }
        }
    }
}

/// Memory the system can give this process now (Linux's `MemAvailable`),
/// if known.
pub fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// Refuses a render of `desc` that would need more memory than `limit`
/// (default: what the machine has available now).
pub fn check(desc: &SceneDesc, limit: Option<u64>) -> Result<()> {
    check_estimate(estimate(desc, &desc.settings), limit)
}

/// Refuses a render whose estimate exceeds `limit` (default: what the
/// machine has available now).
pub fn check_estimate(e: Estimate, limit: Option<u64>) -> Result<()> {
    let Some(available) = limit.or_else(available_memory) else {
        return Ok(());
    };
    if e.bytes > available {
        return Err(Error::Memory {
            needed: e.bytes,
            available,
            triangles: e.triangles,
            pixels: e.pixels,
        });
    }
    Ok(())
}

/// The estimate for `triangles` already known (a scene cache hit) and the
/// film of `settings`.
pub fn with_triangles(triangles: u64, settings: &Settings) -> Estimate {
    let pixels = settings.film.width as u64 * settings.film.height as u64;
    let per_pixel = match settings.integrator {
        IntegratorKind::Vcm => BYTES_PER_PIXEL + VCM_BYTES_PER_PIXEL,
        _ => BYTES_PER_PIXEL,
    };
    Estimate {
        triangles,
        pixels,
        bytes: triangles
            .saturating_mul(BYTES_PER_TRIANGLE)
            .saturating_add(pixels.saturating_mul(per_pixel)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// VCM keeps an iteration's light vertices: its estimate grows with
    /// the image by that much more than the other integrators'.
    #[test]
    fn vcm_needs_its_light_vertices_counted() {
        let mut settings = Settings::new(
            crate::settings::CameraSettings {
                position: glam::Vec3::ZERO,
                look_at: glam::Vec3::Z,
                up: glam::Vec3::Y,
                fov: 40.0,
                aperture_radius: 0.0,
                focus_distance: None,
            },
            "out.exr".into(),
        );
        settings.film.width = 3840;
        settings.film.height = 2160;
        let bdpt = with_triangles(1000, &settings);
        settings.integrator = IntegratorKind::Vcm;
        let vcm = with_triangles(1000, &settings);
        assert_eq!(vcm.bytes - bdpt.bytes, 3840 * 2160 * VCM_BYTES_PER_PIXEL);
        assert!(vcm.bytes > 18_000_000_000, "{}", vcm.bytes);
    }
}
