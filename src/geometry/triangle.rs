//! The ray–triangle test.
//!
//! Watertight: a ray through a shared edge or vertex hits at least one of the
//! triangles that share it, following Woop, Benthin and Wald, "Watertight
//! Ray/Triangle Intersection" (JCGT 2013). The ray is sheared so it points
//! along +z; the edge functions are then 2D and evaluated in double precision
//! whenever single precision returns exactly zero.

use glam::{DVec3, Vec3};

/// A triangle by its three world-space vertices; the front face is the one
/// they wind counter-clockwise around. A plain record the scene cache stores as bytes.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Triangle {
    /// Vertices 0, 1, 2, counter-clockwise seen from the front.
    pub v: [Vec3; 3],
}

/// A hit: distance along the ray and the barycentric weights of vertices 1 and 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter of the hit: a distance when the ray direction is unit length.
    pub t: f32,
    /// Barycentric weight of vertex 1.
    pub b1: f32,
    /// Barycentric weight of vertex 2 (vertex 0's is `1 - b1 - b2`).
    pub b2: f32,
}

impl Triangle {
    /// The triangle with vertices `a`, `b`, `c` in that (winding) order.
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Triangle {
        Triangle { v: [a, b, c] }
    }

    /// Unnormalised geometric normal, by counter-clockwise winding.
    pub fn cross(&self) -> Vec3 {
        (self.v[1] - self.v[0]).cross(self.v[2] - self.v[0])
    }

    /// Area, in squared world units.
    pub fn area(&self) -> f32 {
        0.5 * self.cross().length()
    }

    /// Unit geometric normal; zero for a degenerate triangle.
    pub fn normal(&self) -> Vec3 {
        self.cross().normalize_or_zero()
    }

    /// The point with barycentric weights `b1` on vertex 1 and `b2` on vertex 2
    /// (single precision; see [`interpolate_precise`]).
    pub fn point(&self, b1: f32, b2: f32) -> Vec3 {
        (1.0 - b1 - b2) * self.v[0] + b1 * self.v[1] + b2 * self.v[2]
    }
}

/// What the watertight test precomputes once per ray.
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    origin: Vec3,
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
}

impl RayShear {
    /// Precomputes the shear for a ray from `origin` along `dir` (`dir` must
    /// be non-zero; it need not be unit length).
    pub fn new(origin: Vec3, dir: Vec3) -> RayShear {
        let d = dir.to_array();
        let a = d.map(f32::abs);
        let kz = if a[0] >= a[1] && a[0] >= a[2] {
            0
        } else if a[1] >= a[2] {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the winding of the projected triangle: swap when looking down −z.
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        // One division: the shear's own rounding does not affect
        // watertightness, which only needs every edge evaluated consistently.
        let sz = 1.0 / d[kz];
        RayShear {
            origin,
            kx,
            ky,
            kz,
            sx: d[kx] * sz,
            sy: d[ky] * sz,
            sz,
        }
    }

    /// The axes (`kx`, `ky`, `kz`) and shear constants (`sx`, `sy`, `sz`),
    /// for the SIMD version of this test.
    pub fn parts(&self) -> ([usize; 3], [f32; 3]) {
        ([self.kx, self.ky, self.kz], [self.sx, self.sy, self.sz])
    }

    /// The hit with `tmin < t < tmax`, if any. Hits either face.
    #[inline]
    pub fn intersect(&self, tri: &Triangle, tmin: f32, tmax: f32) -> Option<TriangleHit> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let a = tri.v[0] - self.origin;
        let b = tri.v[1] - self.origin;
        let c = tri.v[2] - self.origin;
        let ax = a[kx] - self.sx * a[kz];
        let ay = a[ky] - self.sy * a[kz];
        let bx = b[kx] - self.sx * b[kz];
        let by = b[ky] - self.sy * b[kz];
        let cx = c[kx] - self.sx * c[kz];
        let cy = c[ky] - self.sy * c[kz];

        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            // An edge passes (nearly) through the ray: decide exactly.
            let d =
                |p: f32, q: f32, r: f32, s: f32| (p as f64 * q as f64 - r as f64 * s as f64) as f32;
            u = d(cx, by, cy, bx);
            v = d(ax, cy, ay, cx);
            w = d(bx, ay, by, ax);
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let az = self.sz * a[kz];
        let bz = self.sz * b[kz];
        let cz = self.sz * c[kz];
        let t_scaled = u * az + v * bz + w * cz;
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        if !(t > tmin && t < tmax) {
            return None;
        }
        Some(TriangleHit {
            t,
            b1: v * inv_det,
            b2: w * inv_det,
        })
    }
}

/// Barycentric interpolation in double precision, for hit points that must sit
/// on the triangle as exactly as floats allow.
pub fn interpolate_precise(tri: &Triangle, b1: f32, b2: f32) -> Vec3 {
    let (b1, b2) = (b1 as f64, b2 as f64);
    let p =
        (1.0 - b1 - b2) * tri.v[0].as_dvec3() + b1 * tri.v[1].as_dvec3() + b2 * tri.v[2].as_dvec3();
    DVec3::as_vec3(p)
}
