//! The ray sets `tracer bench` traces: generated from the mesh itself with a
//! fixed seed, or read from a file so that other tools can trace the very
//! same rays.

use crate::bvh::WideBvh;
use crate::camera::Camera;
use crate::geometry::ray::{magnitude, offset_origin};
use crate::geometry::{Aabb, Ray, Triangle};
use crate::sampling::sampler::hash;
use crate::sampling::warp;
use crate::{Error, Result};
use glam::Vec3;
use std::path::Path;

/// Primary rays come from a 1024 × 1024 image.
pub const PRIMARY_RESOLUTION: u32 = 1024;
/// Incoherent rays: as many as primary rays.
pub const INCOHERENT_COUNT: usize = 1 << 20;
/// Bytes per ray in a rays file: origin, tmin, direction, tmax as little-endian f32.
pub const RECORD_BYTES: usize = 32;

/// A deterministic stream of uniform numbers in [0, 1).
struct Uniform(u32);

impl Uniform {
    fn next(&mut self) -> f32 {
        self.0 = hash(self.0.wrapping_add(0x9e37_79b9));
        (self.0 >> 8) as f32 / (1u32 << 24) as f32
    }
}

/// A camera framing `bounds` from the front-right and slightly above (for a
/// mesh without a scene of its own).
pub fn framing_camera(bounds: Aabb) -> Camera {
    let (center, radius) = bounds.bounding_sphere();
    let radius = radius.max(1e-6);
    let fov: f32 = 45.0;
    let distance = radius / (0.5 * fov.to_radians()).sin();
    let from = center + distance * Vec3::new(0.35, 0.3, 1.0).normalize();
    Camera::new(
        from,
        center,
        Vec3::Y,
        fov,
        PRIMARY_RESOLUTION,
        PRIMARY_RESOLUTION,
    )
    .expect("the view direction is never vertical")
}

/// One ray through the centre of every pixel.
pub fn primary(camera: &Camera) -> Vec<Ray> {
    let (w, h) = (camera.width(), camera.height());
    let mut rays = Vec::with_capacity(w as usize * h as usize);
    for y in 0..h {
        for x in 0..w {
            rays.push(camera.ray(x as f32 + 0.5, y as f32 + 0.5));
        }
    }
    rays
}

/// Where a primary ray hit, as an origin for the next ray: the point moved
/// off its surface (as the renderer moves it), and the geometric normal
/// facing the primary ray.
#[derive(Clone, Copy, Debug)]
pub struct HitPoint {
    /// The hit point, moved off the surface to the side the primary ray came from.
    pub origin: Vec3,
    /// Unit geometric normal, facing the primary ray.
    pub normal: Vec3,
}

/// Where each of the `primary` rays hit, in ray order; misses are skipped.
pub fn hit_points(bvh: &WideBvh, triangles: &[Triangle], primary: &[Ray]) -> Vec<HitPoint> {
    primary
        .iter()
        .filter_map(|ray| {
            let hit = bvh.intersect(ray)?;
            let triangle = &triangles[hit.triangle as usize];
            let n = triangle.normal();
            let n = if n.dot(ray.dir) > 0.0 { -n } else { n };
            Some(HitPoint {
                origin: offset_origin(ray.at(hit.t), n, n, magnitude(&triangle.v)),
                normal: n,
            })
        })
        .collect()
}

/// From each primary hit, a cosine-distributed direction about its normal.
pub fn diffuse(hits: &[HitPoint]) -> Vec<Ray> {
    let mut u = Uniform(1);
    hits.iter()
        .map(|h| {
            let local = warp::cosine_hemisphere(u.next(), u.next());
            let (t, b) = h.normal.any_orthonormal_pair();
            let dir = (local.x * t + local.y * b + local.z * h.normal).normalize();
            Ray::new(h.origin, dir)
        })
        .collect()
}

/// Origins uniform in the bounds, directions uniform on the sphere.
pub fn incoherent(bounds: Aabb, count: usize) -> Vec<Ray> {
    let mut u = Uniform(2);
    (0..count)
        .map(|_| {
            let o = bounds.min + bounds.extent() * Vec3::new(u.next(), u.next(), u.next());
            Ray::new(o, warp::uniform_sphere(u.next(), u.next()))
        })
        .collect()
}

/// From each primary hit towards a random point in the bounds, stopping there.
pub fn shadow(hits: &[HitPoint], bounds: Aabb) -> Vec<Ray> {
    let mut u = Uniform(3);
    hits.iter()
        .filter_map(|h| {
            let target = bounds.min + bounds.extent() * Vec3::new(u.next(), u.next(), u.next());
            let d = target - h.origin;
            let distance = d.length();
            (distance > 0.0).then(|| Ray::segment(h.origin, d / distance, distance))
        })
        .collect()
}

/// The little-endian f32s of a file of `floats`-float records named
/// `what` in the error when the size is not a whole number of them.
fn read_records(path: &Path, floats: usize, what: &str) -> Result<Vec<f32>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let record_bytes = 4 * floats;
    if bytes.len() % record_bytes != 0 {
        return Err(Error::Data {
            path: path.to_path_buf(),
            message: format!(
                "{} bytes is not a whole number of {record_bytes}-byte {what} records",
                bytes.len()
            ),
        });
    }
    Ok(bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

/// Reads rays from 32-byte little-endian records: origin x, y, z, tmin,
/// direction x, y, z, tmax.
pub fn read_file(path: &Path) -> Result<Vec<Ray>> {
    Ok(read_records(path, RECORD_BYTES / 4, "ray")?
        .chunks_exact(RECORD_BYTES / 4)
        .map(|f| Ray {
            origin: Vec3::new(f[0], f[1], f[2]),
            tmin: f[3],
            dir: Vec3::new(f[4], f[5], f[6]),
            tmax: f[7],
        })
        .collect())
}

/// Reads triangles written by [`write_triangles`].
pub fn read_triangles(path: &Path) -> Result<Vec<Triangle>> {
    Ok(read_records(path, 9, "triangle")?
        .chunks_exact(9)
        .map(|f| Triangle {
            v: [
                Vec3::new(f[0], f[1], f[2]),
                Vec3::new(f[3], f[4], f[5]),
                Vec3::new(f[6], f[7], f[8]),
            ],
        })
        .collect())
}

/// Writes the triangles as 36-byte little-endian records (three vertices,
/// x y z each, as f32), in the order the BVH numbers them.
pub fn write_triangles(path: &Path, triangles: &[Triangle]) -> Result<()> {
    let mut bytes = Vec::with_capacity(triangles.len() * 36);
    for t in triangles {
        for v in t.v {
            for c in v.to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    crate::film::write::write_atomic(path, &bytes)
}

/// Writes rays in the same format, for other tools to trace.
pub fn write_file(path: &Path, rays: &[Ray]) -> Result<()> {
    let mut bytes = Vec::with_capacity(rays.len() * RECORD_BYTES);
    for r in rays {
        for v in [
            r.origin.x, r.origin.y, r.origin.z, r.tmin, r.dir.x, r.dir.y, r.dir.z, r.tmax,
        ] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    crate::film::write::write_atomic(path, &bytes)
}
