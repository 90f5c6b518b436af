//! Rays, and the origin offset that keeps a ray from re-hitting the surface it
//! leaves.

use glam::Vec3;

/// A ray `origin + t·dir`, restricted to an open interval of `t`.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Where the ray starts, in world space.
    pub origin: Vec3,
    /// Direction. The intersection tests accept any non-zero length; the
    /// renderer's rays are unit length, which makes `t` a world-space distance.
    pub dir: Vec3,
    /// Hits count only for `tmin < t < tmax`.
    pub tmin: f32,
    /// Far end of the interval: `f32::INFINITY` for an unbounded ray.
    pub tmax: f32,
}

impl Ray {
    /// An unbounded ray: `0 < t < ∞`.
    pub fn new(origin: Vec3, dir: Vec3) -> Ray {
        Ray {
            origin,
            dir,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    /// A segment that stops short of `tmax`, for shadow rays.
    pub fn segment(origin: Vec3, dir: Vec3, tmax: f32) -> Ray {
        Ray {
            origin,
            dir,
            tmin: 0.0,
            tmax,
        }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// Moves a surface point off its surface, to the side `toward` lies on, so a
/// ray leaving it cannot hit that surface again, and a shadow ray ending at it
/// cannot stop on that surface early.
///
/// The ray–triangle test decides which side of a plane a point is on with an
/// error of a few ULPs of the largest coordinate involved, which is the
/// largest coordinate of the triangle's vertices (`magnitude`), not of the
/// point alone. So the point moves along the geometric normal by 2^-16 of
/// that magnitude (about 128 ULPs). Offsetting each coordinate by ULPs of
/// itself (Wächter and Binder, *Ray Tracing Gems* ch. 6) is not enough: on a
/// floor at y = 0 far from the origin, y's ULPs are tiny while the test's
/// error follows x and z, and grazing shadow rays then stop on the floor.
/// The offset is relative, so it works at any scene scale with no epsilon on `t`.
pub fn offset_origin(p: Vec3, geometric_normal: Vec3, toward: Vec3, magnitude: f32) -> Vec3 {
    const RELATIVE: f32 = 1.0 / 65536.0;
    let n = if geometric_normal.dot(toward) < 0.0 {
        -geometric_normal
    } else {
        geometric_normal
    };
    let scale = magnitude.max(p.abs().max_element()).max(f32::MIN_POSITIVE);
    p + n * (scale * RELATIVE)
}

/// The largest absolute coordinate of a triangle: the scale of the rounding
/// errors of ray tests against it, for [`offset_origin`].
pub fn magnitude(v: &[Vec3; 3]) -> f32 {
    v[0].abs().max(v[1].abs()).max(v[2].abs()).max_element()
}
